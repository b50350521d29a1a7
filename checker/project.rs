//! Projection of a global type onto a participant (Def 4.8) and the merge operator of
//! Def 4.7, with Def 4.8 (3) read as the merge `⊓` (seeds README, known error 3).
//!
//! Projection is continuation-passing: [`project`] takes the local type `tail` that
//! follows `g` and pushes it into every branch of a choice. Tails are [`Arc`]-shared,
//! so a sequence of choices costs linear space, and the result is in the prefix form of
//! Def 4.6 (`dt<a>.T`, `⊕{..}`, `&{..}`, `&{..} & dt<a>.T`, `mu t.T`, `t`, `end`).
//!
//! The rules, for a role `r`:
//! - `p -> q : {[P_i] l_i(F_i).G_i}`: the sender gets `⊕{[P_i] q!l_i(F_i).T_i}`, the
//!   receiver `&{p?l_i(F_i).T_i}`, anybody else the merge `⊓_i T_i` (a single message
//!   is a choice with one branch);
//! - `dt<(p_i : a_i)>.T` is `dt<a_j>.T` for `r = p_j` and `T` otherwise;
//! - `g1 * g2` is the projection of the side that contains `r` (and `T` if none does);
//! - sequences fold from the right; `t` and `end` ignore the tail;
//! - `mu t.G` is `mu t.T'` when `r ∈ pt{G}`. Def 4.8 (4) leaves the projection
//!   undefined otherwise; we follow the usual MPST convention that `r` has left the
//!   protocol and project to `end`.
//!
//! Equality of local types ([`equal`]) ignores source locations, compares the branches
//! of a choice as a set, and is alpha-equivalence: payload fields and recursion
//! parameters (binders) correspond by position, and a value is its binding site, never
//! its name (see `Differ`). The merge reads one branch's continuation in terms of the
//! other's binders of a shared message before merging the two (`rename_local`).

use crate::diag::{Code, Diagnostic};
use crate::hir::print;
use crate::hir::*;
use fixedbitset::FixedBitSet;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

/// Projects the choreography onto every participant of the system. A participant whose
/// projection fails is missing from the map and has a diagnostic (E0601) instead.
pub fn project_all(prog: &Program) -> (BTreeMap<RoleId, LocalRc>, Vec<Diagnostic>) {
    let mut out = BTreeMap::new();
    let mut diags = Vec::new();
    let Some(chor) = &prog.choreography else {
        return (out, diags);
    };
    let tail: LocalRc = Arc::new(Local::End(Loc(chor.span)));
    // Who occurs where, computed once for all roles: projecting n roles must not walk
    // the whole type n times to find each role's side of every `*`.
    let occurs = Occurs::new(prog, &chor.body);
    for role in prog.role_ids() {
        match (Projector { prog, role, occurs: &occurs }).project(&chor.body, tail.clone()) {
            Ok(t) => {
                out.insert(role, t);
            }
            Err(d) => diags.push(d),
        }
    }
    (out, diags)
}

/// Checks every `local R = T;` item against the projection onto `R` (E0602). Roles
/// whose projection failed are skipped: their error is already reported.
pub fn check_declared(prog: &Program, projections: &BTreeMap<RoleId, LocalRc>) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    for def in &prog.locals {
        let Some(proj) = projections.get(&def.role) else {
            continue;
        };
        let Some((declared, projected)) = first_difference(&def.body, proj) else {
            continue;
        };
        let name = prog.role_name(def.role);
        diags.push(
            Diagnostic::error(
                Code::LocalMismatch,
                def.span,
                format!("the declared local type of `{name}` differs from the projection of the choreography"),
            )
            .with_label(declared.0, "the declared type says this")
            .with_label(projected.0, "where the choreography says this")
            .with_note(format!("the projection onto `{name}` is:\n{}", print_bounded(prog, proj, 20_000)))
            .with_help(format!(
                "use `mochi project FILE --role {name}` to print the projection and paste it, or change the choreography"
            )),
        );
    }
    diags
}

/// The projection of `g` onto `role`, followed by `tail` (Def 4.8).
pub fn project(prog: &Program, g: &Global, role: RoleId, tail: LocalRc) -> Result<LocalRc, Diagnostic> {
    let occurs = Occurs::new(prog, g);
    Projector { prog, role, occurs: &occurs }.project(g, tail)
}

/// The participants of every node of a global type, keyed by the node's address, and
/// for each `*` the side each participant is on.
struct Occurs {
    pt: HashMap<*const Global, FixedBitSet>,
    sides: HashMap<*const Global, HashMap<RoleId, Vec<usize>>>,
}

impl Occurs {
    fn new(prog: &Program, g: &Global) -> Occurs {
        let mut o = Occurs { pt: HashMap::new(), sides: HashMap::new() };
        o.fill(g, prog.roles.len());
        o
    }

    fn fill(&mut self, g: &Global, n: usize) -> FixedBitSet {
        let mut set = FixedBitSet::with_capacity(n);
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || match g {
            Global::Msg(m) => {
                set.insert(m.from.idx());
                set.insert(m.to.idx());
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| set.insert(r.idx())),
            Global::Seq(gs, _) | Global::Choice(gs, _) => gs.iter().for_each(|c| set.union_with(&self.fill(c, n))),
            Global::Par(gs, _) => {
                let mut side_of: HashMap<RoleId, Vec<usize>> = HashMap::new();
                for (i, c) in gs.iter().enumerate() {
                    let sub = self.fill(c, n);
                    for r in sub.ones() {
                        side_of.entry(RoleId(r as u32)).or_default().push(i);
                    }
                    set.union_with(&sub);
                }
                self.sides.insert(g as *const Global, side_of);
            }
            Global::Rec { body, .. } => set = self.fill(body, n),
            Global::Var(_) | Global::End(_) => {}
        });
        self.pt.insert(g as *const Global, set.clone());
        set
    }

    fn contains(&self, g: &Global, r: RoleId) -> bool {
        match self.pt.get(&(g as *const Global)) {
            Some(set) => set.contains(r.idx()),
            None => {
                // Not a node of the type `Occurs` was built for: compute directly.
                let mut pt = Vec::new();
                g.participants(&mut pt);
                pt.contains(&r)
            }
        }
    }
}

/// Whether two local types are equal up to locations, the renaming of value binders
/// (alpha-equivalence) and the order of choice branches.
pub fn equal(a: &LocalRc, b: &LocalRc) -> bool {
    first_difference(a, b).is_none()
}

/// The locations of the first pair of nodes where `a` and `b` differ, if any.
pub fn first_difference(a: &LocalRc, b: &LocalRc) -> Option<(Loc, Loc)> {
    Differ::new().diff(a, b)
}

/// A short description of the first action of a local type, for messages:
/// `GRobot!ready`, `&{Cart?ok, Cart?ko} & dt<m_idle>`, `dt<a /\ b>`, `end`.
pub fn describe(prog: &Program, t: &Local) -> String {
    match t {
        Local::Motion { prims, .. } => motion_text(prog, prims),
        Local::Send { branches, .. } => {
            let items: Vec<String> = branches.iter().map(|b| format!("{}!{}", prog.role_name(b.to), b.label)).collect();
            if items.len() == 1 {
                items.join("")
            } else {
                format!("+{{{}}}", items.join(", "))
            }
        }
        Local::Recv { branches, default, .. } => {
            let items: Vec<String> =
                branches.iter().map(|b| format!("{}?{}", prog.role_name(b.from), b.label)).collect();
            let mut s = if items.len() == 1 && default.is_none() {
                items.join("")
            } else {
                format!("&{{{}}}", items.join(", "))
            };
            if let Some((prims, _)) = default {
                s.push_str(" & ");
                s.push_str(&motion_text(prog, prims));
            }
            s
        }
        Local::Rec { var, body, .. } => format!("mu {var}. {}", describe(prog, body)),
        Local::Var { var, args, .. } => {
            if args.is_empty() {
                var.clone()
            } else {
                let args: Vec<String> = args.iter().map(|a| print::expr(prog, None, a)).collect();
                format!("{var}({})", args.join(", "))
            }
        }
        Local::End(_) => "end".to_string(),
    }
}

/// Prints a local type for a diagnostic. Shared tails make a local type a DAG whose
/// printed tree can be exponentially larger, so a type that would print more than
/// `max_nodes` nodes is summarised by its first action.
pub fn print_bounded(prog: &Program, t: &LocalRc, max_nodes: usize) -> String {
    if tree_size(t, max_nodes + 1, &mut HashMap::new()) <= max_nodes {
        print::local(prog, t)
    } else {
        format!("{}. ... (too large to print here; use `mochi project`)", describe(prog, t))
    }
}

/// The number of nodes of `t` printed as a tree, saturating at `cap`.
fn tree_size(t: &LocalRc, cap: usize, memo: &mut HashMap<usize, usize>) -> usize {
    let key = Arc::as_ptr(t) as usize;
    if let Some(&n) = memo.get(&key) {
        return n;
    }
    let n = stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || {
        let mut n = 1usize;
        let mut add = |c: &LocalRc, memo: &mut HashMap<usize, usize>| {
            n = n.saturating_add(tree_size(c, cap, memo)).min(cap);
        };
        match &**t {
            Local::Motion { cont, .. } => add(cont, memo),
            Local::Send { branches, .. } => branches.iter().for_each(|b| add(&b.cont, memo)),
            Local::Recv { branches, default, .. } => {
                branches.iter().for_each(|b| add(&b.cont, memo));
                if let Some((_, c)) = default {
                    add(c, memo);
                }
            }
            Local::Rec { body, .. } => add(body, memo),
            Local::Var { .. } | Local::End(_) => {}
        }
        n
    });
    memo.insert(key, n);
    n
}

/// `dt<a>` or `dt<a /\ b>`.
pub fn motion_text(prog: &Program, prims: &[PrimApp]) -> String {
    let items: Vec<String> = prims.iter().map(|a| print::prim_app(prog, a)).collect();
    format!("dt<{}>", items.join(" /\\ "))
}

/// How many nodes a local type printed in a note may have.
pub(crate) const NOTE_NODES: usize = 400;

struct Projector<'a> {
    prog: &'a Program,
    role: RoleId,
    occurs: &'a Occurs,
}

/// Why two branch projections could not be merged: the two nodes that differ.
struct Clash {
    left: Loc,
    left_text: String,
    right: Loc,
    right_text: String,
    why: Option<String>,
}

impl Projector<'_> {
    fn project(&self, g: &Global, tail: LocalRc) -> Result<LocalRc, Diagnostic> {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.project_inner(g, tail))
    }

    fn project_inner(&self, g: &Global, tail: LocalRc) -> Result<LocalRc, Diagnostic> {
        match g {
            Global::Msg(m) => self.choice(std::slice::from_ref(g), m.loc, tail),
            Global::Choice(branches, loc) => self.choice(branches, *loc, tail),
            Global::Motion(m) => Ok(match m.parts.iter().find(|(r, _)| *r == self.role) {
                Some((_, a)) => Arc::new(Local::Motion { prims: vec![a.clone()], cont: tail, loc: a.loc }),
                None => tail,
            }),
            Global::Seq(items, _) => {
                let mut t = tail;
                for item in items.iter().rev() {
                    t = self.project(item, t)?;
                }
                Ok(t)
            }
            Global::Par(sides, loc) => {
                let mine: Vec<&Global> = match self.occurs.sides.get(&(g as *const Global)) {
                    Some(side_of) => {
                        side_of.get(&self.role).into_iter().flatten().filter_map(|&i| sides.get(i)).collect()
                    }
                    None => sides.iter().filter(|s| self.occurs_in(s)).collect(),
                };
                match mine.as_slice() {
                    [] => Ok(tail),
                    [side] => self.project(side, tail),
                    [..] => Err(Diagnostic::error(
                        Code::SeparationOverlap,
                        loc.0,
                        format!("`{}` occurs on more than one side of `*`", self.name()),
                    )
                    .with_note("projection (Def 4.8 (7)) needs the sides of `*` to have disjoint participants")
                    .with_help("move the participant's actions out of all sides but one")),
                }
            }
            Global::Rec { var, params, body, loc } => {
                if !self.occurs_in(body) {
                    // Def 4.8 (4) is undefined here; the role has left the protocol.
                    return Ok(Arc::new(Local::End(*loc)));
                }
                let body = self.project(body, tail)?;
                if matches!(&*body, Local::Var { var: v, .. } if v == var) {
                    // `mu t. t` would be unguarded: the role never acts in the loop.
                    return Ok(Arc::new(Local::End(*loc)));
                }
                Ok(Arc::new(Local::Rec { var: var.clone(), params: params.clone(), body, loc: *loc }))
            }
            Global::Var(v) => Ok(Arc::new(Local::Var { var: v.var.clone(), args: v.args.clone(), loc: v.loc })),
            Global::End(loc) => Ok(Arc::new(Local::End(*loc))),
        }
    }

    fn name(&self) -> &str {
        self.prog.role_name(self.role)
    }

    fn occurs_in(&self, g: &Global) -> bool {
        self.occurs.contains(g, self.role)
    }

    /// Projects the items of a sequence, right to left, in front of `tail`.
    fn seq(&self, items: &[&Global], tail: LocalRc) -> Result<LocalRc, Diagnostic> {
        let mut t = tail;
        for item in items.iter().rev() {
            t = self.project(item, t)?;
        }
        Ok(t)
    }

    /// Def 4.8 (1)-(3): a choice whose branches each start with a message `p -> q`.
    fn choice(&self, branches: &[Global], loc: Loc, tail: LocalRc) -> Result<LocalRc, Diagnostic> {
        let mut split: Vec<(&Msg, Vec<&Global>)> = Vec::new();
        for b in branches {
            split_branch(b, &[], &mut split).map_err(not_a_choice)?;
        }
        let Some(&(first, _)) = split.first() else {
            return Err(not_a_choice(loc));
        };
        if let Some((m, _)) = split.iter().find(|(m, _)| m.from != first.from || m.to != first.to) {
            return Err(not_a_choice(m.loc));
        }
        if self.role == first.from {
            let mut out = Vec::new();
            for (m, rest) in &split {
                out.push(SendBranch {
                    guard: m.guard.clone(),
                    to: m.to,
                    label: m.label.clone(),
                    payload: m.payload.clone(),
                    cont: self.seq(rest, tail.clone())?,
                    loc: m.loc,
                });
            }
            return Ok(Arc::new(Local::Send { branches: out, loc: first.loc }));
        }
        if self.role == first.to {
            let mut out = Vec::new();
            for (m, rest) in &split {
                out.push(RecvBranch {
                    from: m.from,
                    label: m.label.clone(),
                    payload: m.payload.clone(),
                    cont: self.seq(rest, tail.clone())?,
                    loc: m.loc,
                });
            }
            return Ok(Arc::new(Local::Recv { branches: out, default: None, loc: first.loc }));
        }
        // Def 4.8 (3) with the merge of Def 4.7.
        let mut acc: Option<(LocalRc, Vec<&str>)> = None;
        for (m, rest) in &split {
            let t = self.seq(rest, tail.clone())?;
            acc = Some(match acc {
                None => (t, vec![m.label.as_str()]),
                Some((prev, mut labels)) => match self.merge(&prev, &t) {
                    Ok(merged) => {
                        labels.push(&m.label);
                        (merged, labels)
                    }
                    Err(clash) => {
                        let left = format!("`{}`", labels.join("`/`"));
                        let right = format!("`{}`", m.label);
                        return Err(self.unmergeable(first, (&left, &prev), (&right, &t), clash));
                    }
                },
            });
        }
        Ok(acc.map(|(t, _)| t).unwrap_or(tail))
    }

    /// E0601. `left` and `right` are the labels of the branches with their projections.
    fn unmergeable(&self, choice: &Msg, left: (&str, &LocalRc), right: (&str, &LocalRc), c: Clash) -> Diagnostic {
        let r = self.name();
        let (p, q) = (self.prog.role_name(choice.from), self.prog.role_name(choice.to));
        let ((left, lt), (right, rt)) = (left, right);
        let mut d = Diagnostic::error(
            Code::Unmergeable,
            choice.loc.0,
            format!("cannot merge the projections onto `{r}` of two branches"),
        )
        .with_label(c.left.0, format!("after {left}, `{r}` does `{}`", c.left_text))
        .with_label(c.right.0, format!("after {right}, `{r}` does `{}`", c.right_text));
        if let Some(why) = c.why {
            d = d.with_note(why);
        }
        d.with_note(format!(
            "`{r}` takes no part in `{p} -> {q}`, so it cannot tell the branches apart (Def 4.8 (3), merge of Def 4.7); its projections are\nafter {left}: {}\nafter {right}: {}",
            print_bounded(self.prog, lt, NOTE_NODES),
            print_bounded(self.prog, rt, NOTE_NODES)
        ))
        .with_help(format!(
            "inform `{r}` of the choice: start each branch's part for `{r}` with a message to it (e.g. `{p} -> {r} : ...` or `{q} -> {r} : ...` with distinct labels)"
        ))
    }

    /// The merge `T1 ⊓ T2` of Def 4.7.
    fn merge(&self, a: &LocalRc, b: &LocalRc) -> Result<LocalRc, Clash> {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.merge_inner(a, b))
    }

    fn merge_inner(&self, a: &LocalRc, b: &LocalRc) -> Result<LocalRc, Clash> {
        if equal(a, b) {
            return Ok(a.clone());
        }
        match (&**a, &**b) {
            (Local::Recv { branches: b1, default: d1, loc }, Local::Recv { branches: b2, default: d2, .. }) => {
                let branches = self.union(b1, b2)?;
                let default = match (d1, d2) {
                    (None, None) => None,
                    (Some(d), None) | (None, Some(d)) => Some(d.clone()),
                    (Some((p1, c1)), Some((p2, c2))) => Some(self.merge_default(p1, c1, p2, c2)?),
                };
                Ok(Arc::new(Local::Recv { branches, default, loc: *loc }))
            }
            (Local::Motion { prims, cont, .. }, Local::Recv { branches, default, loc }) => {
                let default = match default {
                    None => (prims.clone(), cont.clone()),
                    Some((p2, c2)) => self.merge_default(prims, cont, p2, c2)?,
                };
                Ok(Arc::new(Local::Recv { branches: branches.clone(), default: Some(default), loc: *loc }))
            }
            (Local::Recv { branches, default, loc }, Local::Motion { prims, cont, .. }) => {
                let default = match default {
                    None => (prims.clone(), cont.clone()),
                    Some((p1, c1)) => self.merge_default(p1, c1, prims, cont)?,
                };
                Ok(Arc::new(Local::Recv { branches: branches.clone(), default: Some(default), loc: *loc }))
            }
            _ => Err(self.clash(a, b, None)),
        }
    }

    fn clash(&self, a: &Local, b: &Local, why: Option<String>) -> Clash {
        Clash {
            left: a.loc(),
            left_text: describe(self.prog, a),
            right: b.loc(),
            right_text: describe(self.prog, b),
            why,
        }
    }

    /// `dt<a ⊓ a'>.T'` from two default motions with the same continuation `T'`.
    fn merge_default(
        &self,
        p1: &[PrimApp],
        c1: &LocalRc,
        p2: &[PrimApp],
        c2: &LocalRc,
    ) -> Result<(Vec<PrimApp>, LocalRc), Clash> {
        if !equal(c1, c2) {
            let why = "the default motions of the two branches continue differently; Def 4.7 merges them only when the continuations are equal".to_string();
            let (l, r) = first_difference(c1, c2).unwrap_or((c1.loc(), c2.loc()));
            return Err(Clash {
                left: l,
                left_text: format!("{}. {}", motion_text(self.prog, p1), describe(self.prog, c1)),
                right: r,
                right_text: format!("{}. {}", motion_text(self.prog, p2), describe(self.prog, c2)),
                why: Some(why),
            });
        }
        Ok((self.meet(p1, p2)?, c1.clone()))
    }

    /// The motion merge `a ⊓ a'`: the list of both primitives, which the refinement
    /// obligations read as their meet. Def 3.4 (6): a primitive refining both must
    /// have the interruptibility of each, so they must agree.
    fn meet(&self, p1: &[PrimApp], p2: &[PrimApp]) -> Result<Vec<PrimApp>, Clash> {
        let mut out: Vec<PrimApp> = p1.to_vec();
        for a in p2 {
            if !out.contains(a) {
                out.push(a.clone());
            }
        }
        let first = out.first().map(|a| self.prog.prim(a.prim));
        if let Some(bad) = out.iter().find(|a| {
            let p = self.prog.prim(a.prim);
            first.is_some_and(|f| f.interruptible != p.interruptible || f.kind != p.kind)
        }) {
            let anchor = p1.first().map(|a| a.loc).unwrap_or(bad.loc);
            return Err(Clash {
                left: anchor,
                left_text: motion_text(self.prog, p1),
                right: bad.loc,
                right_text: motion_text(self.prog, p2),
                why: Some(
                    "Def 3.4 (6): a motion refining both primitives must have the interruptibility of each, and one is interruptible while the other is not"
                        .to_string(),
                ),
            });
        }
        Ok(out)
    }

    /// The union of two external choices from the same sender; shared labels merge
    /// their continuations and must carry equal payloads.
    fn union(&self, b1: &[RecvBranch], b2: &[RecvBranch]) -> Result<Vec<RecvBranch>, Clash> {
        let mut out: Vec<RecvBranch> = b1.to_vec();
        let sender = b1.first().map(|b| b.from);
        for b in b2 {
            if let Some(s) = sender.filter(|s| *s != b.from) {
                let first = b1.first().map(|x| x.loc).unwrap_or(b.loc);
                return Err(Clash {
                    left: first,
                    left_text: format!("{}?...", self.prog.role_name(s)),
                    right: b.loc,
                    right_text: format!("{}?{}", self.prog.role_name(b.from), b.label),
                    why: Some("Def 4.7 merges receptions only from the same sender".to_string()),
                });
            }
            match out.iter_mut().find(|x| x.label == b.label) {
                None => out.push(b.clone()),
                Some(x) => {
                    if payloads_differ(&x.payload, &b.payload) {
                        let same_text = fields_text(self.prog, &x.payload) == fields_text(self.prog, &b.payload);
                        let why = if same_text {
                            format!(
                                "the two branches receive `{}` with payloads that read alike, but a name in them stands for different values (a value is where it is bound, not its name)",
                                b.label
                            )
                        } else {
                            format!("the two branches receive `{}` with different payloads", b.label)
                        };
                        return Err(Clash {
                            left: x.loc,
                            left_text: recv_text(self.prog, x),
                            right: b.loc,
                            right_text: recv_text(self.prog, b),
                            why: Some(why),
                        });
                    }
                    // `b`'s continuation speaks of `b`'s binders of this message: read it
                    // in terms of `x`'s (the same message, so the same values).
                    let map: HashMap<ValueId, (ValueId, String)> = b
                        .payload
                        .iter()
                        .zip(&x.payload)
                        .filter(|(y, x)| y.value != x.value)
                        .map(|(y, x)| (y.value, (x.value, x.name.clone())))
                        .collect();
                    let cont = rename_local(&b.cont, &map, &mut HashMap::new());
                    x.cont = self.merge(&x.cont, &cont)?;
                }
            }
        }
        Ok(out)
    }
}

fn recv_text(prog: &Program, b: &RecvBranch) -> String {
    let fields: Vec<String> = b.payload.iter().map(|f| format!("{}: {}", f.name, f.sort)).collect();
    if fields.is_empty() {
        format!("{}?{}", prog.role_name(b.from), b.label)
    } else {
        format!("{}?{}({})", prog.role_name(b.from), b.label, fields.join(", "))
    }
}

fn not_a_choice(loc: Loc) -> Diagnostic {
    Diagnostic::error(Code::ChoiceMismatch, loc.0, "this branch of a choice does not start with the choosing message")
        .with_note("Def 4.1: every branch of `+` starts with a message from the same sender to the same receiver")
        .with_help("start every branch with `p -> q : label` for the same `p` and `q`")
}

/// Splits a branch of a choice, followed by `rest`, into its choosing message and
/// what follows it. A nested choice at the front is distributed over the rest,
/// `(g1 + g2).g = g1.g + g2.g`, as Sec 4.1 writes choices. Fails with the location of
/// a branch that does not start with a message.
fn split_branch<'g>(b: &'g Global, rest: &[&'g Global], out: &mut Vec<(&'g Msg, Vec<&'g Global>)>) -> Result<(), Loc> {
    stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || {
        let mut items = Vec::new();
        flatten_seq(b, &mut items);
        items.extend_from_slice(rest);
        match items.split_first() {
            Some((Global::Msg(m), tail)) => {
                out.push((m, tail.to_vec()));
                Ok(())
            }
            Some((Global::Choice(inner, _), tail)) => inner.iter().try_for_each(|i| split_branch(i, tail, out)),
            _ => Err(b.loc()),
        }
    })
}

/// The items of a (possibly nested) sequence, in order.
fn flatten_seq<'g>(g: &'g Global, out: &mut Vec<&'g Global>) {
    match g {
        Global::Seq(items, _) => items.iter().for_each(|i| flatten_seq(i, out)),
        other => out.push(other),
    }
}

/// The payload as printed (to tell "different" from "reads alike, means otherwise").
fn fields_text(prog: &Program, fs: &[Field]) -> Vec<String> {
    fs.iter()
        .map(|f| {
            let r = f.refinement.as_ref().map(|r| print::expr(prog, None, r)).unwrap_or_default();
            format!("{}: {} {{{r}}}", f.name, f.sort)
        })
        .collect()
}

/// Whether two payloads of one message differ, up to the renaming of their binders.
fn payloads_differ(a: &[Field], b: &[Field]) -> bool {
    !Differ::new().bind_fields(a, b)
}

/// Structural comparison of two local types up to the renaming of their value binders
/// (alpha-equivalence). A value is its binding site ([`ValueId`]); two types describe
/// the same protocol when they are equal once each binder of `b` (a payload field, a
/// recursion parameter) is renamed to the binder of `a` at the same position. The
/// renaming is scoped: it holds in the binder's message (its refinements may read the
/// fields) and in the continuation. Values free in both types (bound before them) must
/// be the same binding site; binders must also have the same names, so that the types
/// print the same. Pairs of nodes already found equal (or being compared) under the
/// same renaming are remembered, so shared tails are compared once.
/// A pair of nodes and the non-identity part of the renaming they were compared under.
type Compared = (usize, usize, Vec<(ValueId, ValueId)>);

struct Differ {
    same: HashSet<Compared>,
    /// The binders in scope, outermost first: (binder of `a`, binder of `b`).
    ren: Vec<(ValueId, ValueId)>,
}

impl Differ {
    fn new() -> Differ {
        Differ { same: HashSet::new(), ren: Vec::new() }
    }

    /// Whether the renaming in scope is the identity (then equal ids mean equal values
    /// and identical nodes are equal).
    fn renamed(&self) -> Vec<(ValueId, ValueId)> {
        self.ren.iter().filter(|(x, y)| x != y).copied().collect()
    }

    /// `x` (in `a`) and `y` (in `b`) are the same value: bound by corresponding binders,
    /// or both free and the same binding site.
    fn value_eq(&self, x: ValueId, y: ValueId) -> bool {
        let by_b = self.ren.iter().rposition(|p| p.1 == y);
        let by_a = self.ren.iter().rposition(|p| p.0 == x);
        match (by_b, by_a) {
            (Some(i), Some(j)) => self.ren[i].0 == x && self.ren[j].1 == y,
            (None, None) => x == y,
            _ => false,
        }
    }

    fn expr(&self, a: &Expr, b: &Expr) -> bool {
        if self.ren.iter().all(|(x, y)| x == y) {
            return a == b;
        }
        self.expr_renamed(a, b)
    }

    fn expr_renamed(&self, a: &Expr, b: &Expr) -> bool {
        if a.sort != b.sort {
            return false;
        }
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || match (&a.kind, &b.kind) {
            (ExprKind::Var(Var::Value(x, n)), ExprKind::Var(Var::Value(y, m))) => n == m && self.value_eq(*x, *y),
            (ExprKind::Var(Var::Value(..)), _) | (_, ExprKind::Var(Var::Value(..))) => false,
            (ExprKind::Unary(o, x), ExprKind::Unary(p, y)) => o == p && self.expr_renamed(x, y),
            (ExprKind::Component(x, i), ExprKind::Component(y, j)) => i == j && self.expr_renamed(x, y),
            (ExprKind::Binary(o, x1, x2), ExprKind::Binary(p, y1, y2)) => {
                o == p && self.expr_renamed(x1, y1) && self.expr_renamed(x2, y2)
            }
            (ExprKind::If(x1, x2, x3), ExprKind::If(y1, y2, y3)) => {
                self.expr_renamed(x1, y1) && self.expr_renamed(x2, y2) && self.expr_renamed(x3, y3)
            }
            (ExprKind::Call(f, xs), ExprKind::Call(g, ys)) => f == g && self.exprs(xs, ys),
            (ExprKind::Tuple(xs), ExprKind::Tuple(ys)) => self.exprs(xs, ys),
            (
                ExprKind::Unary(..)
                | ExprKind::Component(..)
                | ExprKind::Binary(..)
                | ExprKind::If(..)
                | ExprKind::Call(..)
                | ExprKind::Tuple(..),
                _,
            ) => false,
            // Literals and other variables: no value inside.
            _ => a.kind == b.kind,
        })
    }

    fn exprs(&self, a: &[Expr], b: &[Expr]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| self.expr_renamed(x, y))
    }

    fn opt_expr(&self, a: &Option<Expr>, b: &Option<Expr>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(x), Some(y)) => self.expr(x, y),
            _ => false,
        }
    }

    fn app(&self, a: &PrimApp, b: &PrimApp) -> bool {
        a.prim == b.prim && a.args.len() == b.args.len() && a.args.iter().zip(&b.args).all(|(x, y)| self.expr(x, y))
    }

    /// The motion merge compares as a set.
    fn prims(&self, a: &[PrimApp], b: &[PrimApp]) -> bool {
        a.len() == b.len()
            && a.iter().all(|x| b.iter().any(|y| self.app(x, y)))
            && b.iter().all(|y| a.iter().any(|x| self.app(x, y)))
    }

    /// Brings the fields' binders into scope, pairwise, and compares the fields (their
    /// refinements may read the message's fields). The caller truncates `ren`.
    fn bind_fields(&mut self, a: &[Field], b: &[Field]) -> bool {
        if a.len() != b.len() {
            return false;
        }
        self.ren.extend(a.iter().zip(b).map(|(x, y)| (x.value, y.value)));
        a.iter()
            .zip(b)
            .all(|(x, y)| x.name == y.name && x.sort == y.sort && self.opt_expr(&x.refinement, &y.refinement))
    }

    /// As [`Differ::bind_fields`] for recursion parameters; their initial values are
    /// read outside the binders.
    fn bind_params(&mut self, a: &[RecParam], b: &[RecParam]) -> bool {
        if a.len() != b.len() || !a.iter().zip(b).all(|(x, y)| self.expr(&x.init, &y.init)) {
            return false;
        }
        self.ren.extend(a.iter().zip(b).map(|(x, y)| (x.value, y.value)));
        a.iter()
            .zip(b)
            .all(|(x, y)| x.name == y.name && x.sort == y.sort && self.opt_expr(&x.refinement, &y.refinement))
    }

    fn diff(&mut self, a: &LocalRc, b: &LocalRc) -> Option<(Loc, Loc)> {
        let renamed = self.renamed();
        if renamed.is_empty() && Arc::ptr_eq(a, b) {
            return None;
        }
        if !self.same.insert((Arc::as_ptr(a) as usize, Arc::as_ptr(b) as usize, renamed)) {
            return None;
        }
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.diff_inner(a, b))
    }

    fn diff_inner(&mut self, a: &LocalRc, b: &LocalRc) -> Option<(Loc, Loc)> {
        let here = Some((a.loc(), b.loc()));
        let mark = self.ren.len();
        match (&**a, &**b) {
            (Local::Motion { prims: p1, cont: c1, .. }, Local::Motion { prims: p2, cont: c2, .. }) => {
                if !self.prims(p1, p2) {
                    return here;
                }
                self.diff(c1, c2)
            }
            (Local::Send { branches: b1, .. }, Local::Send { branches: b2, .. }) => {
                if b1.len() != b2.len() {
                    return here;
                }
                for x in b1 {
                    let Some(y) = b2.iter().find(|y| y.to == x.to && y.label == x.label) else {
                        return Some((x.loc, b.loc()));
                    };
                    // The guard reads the values before the message.
                    if !self.opt_expr(&x.guard, &y.guard) || !self.bind_fields(&x.payload, &y.payload) {
                        self.ren.truncate(mark);
                        return Some((x.loc, y.loc));
                    }
                    let d = self.diff(&x.cont, &y.cont);
                    self.ren.truncate(mark);
                    if d.is_some() {
                        return d;
                    }
                }
                None
            }
            (Local::Recv { branches: b1, default: d1, .. }, Local::Recv { branches: b2, default: d2, .. }) => {
                if b1.len() != b2.len() {
                    return here;
                }
                for x in b1 {
                    let Some(y) = b2.iter().find(|y| y.from == x.from && y.label == x.label) else {
                        return Some((x.loc, b.loc()));
                    };
                    if !self.bind_fields(&x.payload, &y.payload) {
                        self.ren.truncate(mark);
                        return Some((x.loc, y.loc));
                    }
                    let d = self.diff(&x.cont, &y.cont);
                    self.ren.truncate(mark);
                    if d.is_some() {
                        return d;
                    }
                }
                match (d1, d2) {
                    (None, None) => None,
                    (Some((p1, c1)), Some((p2, c2))) => {
                        if !self.prims(p1, p2) {
                            let l1 = p1.first().map(|p| p.loc).unwrap_or(a.loc());
                            let l2 = p2.first().map(|p| p.loc).unwrap_or(b.loc());
                            return Some((l1, l2));
                        }
                        self.diff(c1, c2)
                    }
                    _ => here,
                }
            }
            (Local::Rec { var: v1, params: p1, body: c1, .. }, Local::Rec { var: v2, params: p2, body: c2, .. }) => {
                if v1 != v2 || !self.bind_params(p1, p2) {
                    self.ren.truncate(mark);
                    return here;
                }
                let d = self.diff(c1, c2);
                self.ren.truncate(mark);
                d
            }
            (Local::Var { var: v1, args: a1, .. }, Local::Var { var: v2, args: a2, .. }) => {
                if v1 != v2 || a1.len() != a2.len() || !a1.iter().zip(a2).all(|(x, y)| self.expr(x, y)) {
                    return here;
                }
                None
            }
            (Local::End(_), Local::End(_)) => None,
            _ => here,
        }
    }
}

/// `t` with the value variables `map` renamed (occurrences only; binders inside `t` keep
/// their identity). Used by the merge to read one branch's continuation in terms of
/// the other branch's binders of the same message. Shared tails stay shared.
fn rename_local(t: &LocalRc, map: &HashMap<ValueId, (ValueId, String)>, memo: &mut HashMap<usize, LocalRc>) -> LocalRc {
    if map.is_empty() {
        return t.clone();
    }
    if let Some(r) = memo.get(&(Arc::as_ptr(t) as usize)) {
        return r.clone();
    }
    let e = |x: &Expr| {
        crate::subtype::map_vars(x, &mut |v, sort| match v {
            Var::Value(id, _) => map.get(id).map(|(to, name)| Expr {
                kind: ExprKind::Var(Var::Value(*to, name.clone())),
                sort: sort.clone(),
                loc: Loc::default(),
            }),
            _ => None,
        })
    };
    let app = |a: &PrimApp| PrimApp { prim: a.prim, args: a.args.iter().map(e).collect(), loc: a.loc };
    // A binder of a renamed value (were its site met again inside `t`) is renamed too,
    // so that binders and occurrences stay consistent.
    let to = |v: ValueId| map.get(&v).map(|(to, _)| *to).unwrap_or(v);
    let fields = |fs: &[Field]| -> Vec<Field> {
        fs.iter().map(|f| Field { value: to(f.value), refinement: f.refinement.as_ref().map(e), ..f.clone() }).collect()
    };
    let out = stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || match &**t {
        Local::Motion { prims, cont, loc } => {
            Local::Motion { prims: prims.iter().map(app).collect(), cont: rename_local(cont, map, memo), loc: *loc }
        }
        Local::Send { branches, loc } => Local::Send {
            branches: branches
                .iter()
                .map(|b| SendBranch {
                    guard: b.guard.as_ref().map(e),
                    payload: fields(&b.payload),
                    cont: rename_local(&b.cont, map, memo),
                    ..b.clone()
                })
                .collect(),
            loc: *loc,
        },
        Local::Recv { branches, default, loc } => Local::Recv {
            branches: branches
                .iter()
                .map(|b| RecvBranch {
                    payload: fields(&b.payload),
                    cont: rename_local(&b.cont, map, memo),
                    ..b.clone()
                })
                .collect(),
            default: default.as_ref().map(|(ps, c)| (ps.iter().map(app).collect(), rename_local(c, map, memo))),
            loc: *loc,
        },
        Local::Rec { var, params, body, loc } => Local::Rec {
            var: var.clone(),
            params: params
                .iter()
                .map(|p| RecParam {
                    value: to(p.value),
                    refinement: p.refinement.as_ref().map(e),
                    init: e(&p.init),
                    ..p.clone()
                })
                .collect(),
            body: rename_local(body, map, memo),
            loc: *loc,
        },
        Local::Var { var, args, loc } => Local::Var { var: var.clone(), args: args.iter().map(e).collect(), loc: *loc },
        Local::End(loc) => Local::End(*loc),
    });
    let out = Arc::new(out);
    memo.insert(Arc::as_ptr(t) as usize, out.clone());
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::diag::Code;
    use crate::lower::tests::lower_src;

    /// The cart-and-arms example (Fig 2 as corrected in wf-rules.md): the cart tells
    /// both arms which one it serves, moves there, and comes back.
    pub(crate) const CART_ARMS: &str = "
        robot Cart { state x: real; }
        robot Arm { state h: real; }
        motion Cart.m_move(p: real) { interruptible: false; post: x == p; }
        motion Cart.m_idle { interruptible: true; }
        motion Arm.work { interruptible: true; }
        motion Arm.pick { interruptible: false; }
        system CartAndArms {
          participant Cart: Cart { init: x == 0; }
          participant G: Arm;
          participant R: Arm;
        }
        choreography Fig2 = mu t. (
            Cart -> G : arrive. Cart -> R : free.
            ((dt<Cart: m_move(1.0), G: work>. Cart -> G : ready. dt<Cart: m_idle, G: pick>. G -> Cart : ok.
              (dt<Cart: m_move(0.0)> * dt<G: work>)) * dt<R: work>). t
          + Cart -> G : free. Cart -> R : arrive.
            ((dt<Cart: m_move(2.0), R: work>. Cart -> R : ready. dt<Cart: m_idle, R: pick>. R -> Cart : ok.
              (dt<Cart: m_move(0.0)> * dt<R: work>)) * dt<G: work>). t
        );
    ";

    fn projections(src: &str) -> (Program, BTreeMap<RoleId, LocalRc>, Vec<Diagnostic>) {
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let (map, diags) = project_all(&prog);
        (prog, map, diags)
    }

    fn printed(prog: &Program, map: &BTreeMap<RoleId, LocalRc>, role: &str) -> String {
        let r = prog.role_by_name(role).expect("role exists");
        print::local(prog, map.get(&r).expect("projection exists"))
    }

    #[test]
    fn example_4_9_cart_and_arms() {
        let (prog, map, diags) = projections(CART_ARMS);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(
            printed(&prog, &map, "Cart"),
            "mu t. +{
  G!arrive.R!free.dt<m_move(1.0)>.G!ready.dt<m_idle>.G?ok.dt<m_move(0.0)>.t,
  G!free.R!arrive.dt<m_move(2.0)>.R!ready.dt<m_idle>.R?ok.dt<m_move(0.0)>.t
}"
        );
        assert_eq!(
            printed(&prog, &map, "G"),
            "mu t. &{
  Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.t,
  Cart?free.dt<work>.t
}"
        );
        // R does not take part in the choosing message: its branches are merged.
        assert_eq!(
            printed(&prog, &map, "R"),
            "mu t. &{
  Cart?free.dt<work>.t,
  Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.t
}"
        );
    }

    const ABC: &str = "
        robot K { state x: real; }
        motion K.m { interruptible: true; }
        motion K.n { interruptible: true; }
        motion K.w { interruptible: true; }
        motion K.stop { interruptible: false; }
        system S { participant A: K; participant B: K; participant C: K; }
    ";

    #[test]
    fn tails_are_shared_not_copied() {
        let src = format!("{ABC} choreography G = (A -> B : x. B -> A : y + A -> B : z). dt<A: m>. end;");
        let (prog, map, _) = projections(&src);
        let Some(a) = map.get(&RoleId(0)) else { panic!() };
        assert_eq!(print::local(&prog, a), "+{\n  B!x.B?y.dt<m>.end,\n  B!z.dt<m>.end\n}");
        let Local::Send { branches, .. } = &**a else { panic!() };
        let Local::Recv { branches: inner, .. } = &*branches[0].cont else { panic!() };
        assert!(Arc::ptr_eq(&inner[0].cont, &branches[1].cont));
    }

    #[test]
    fn a_motion_merges_with_receptions_into_a_default() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. dt<A: m, B: n, C: w>. A -> C : stop. end
              + A -> B : l2. A -> C : go. end;"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "C"), "&{\n  A?go.end\n} & dt<w>.A?stop.end");
    }

    #[test]
    fn two_defaults_merge_into_the_meet_of_their_motions() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. dt<A: m, B: n, C: w>. A -> C : stop. end
              + A -> B : l2. A -> C : go. end
              + A -> B : l3. dt<A: m, B: n, C: n>. A -> C : stop. end;"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "C"), "&{\n  A?go.end\n} & dt<w /\\ n>.A?stop.end");
    }

    #[test]
    fn motions_of_different_interruptibility_do_not_merge() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. A -> C : go. end
              + A -> B : l2. dt<A: m, B: n, C: w>. A -> C : done. end
              + A -> B : l3. dt<A: m, B: n, C: stop>. A -> C : done. end;"
        );
        let (_, _, diags) = projections(&src);
        assert_eq!(diags.len(), 1, "{diags:?}");
        assert_eq!(diags[0].code, Code::Unmergeable);
        assert!(diags[0].notes[0].contains("interruptibility"), "{:?}", diags[0].notes);
    }

    #[test]
    fn unmergeable_branches_are_e0601_with_both_labels() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. C -> A : x. end
              + A -> B : l2. C -> A : y. end;"
        );
        let (prog, map, diags) = projections(&src);
        assert_eq!(diags.len(), 1, "{diags:?}");
        let d = &diags[0];
        assert_eq!(d.code, Code::Unmergeable);
        assert!(d.message.contains("onto `C`"), "{}", d.message);
        assert_eq!(d.labels.len(), 2);
        let text = &src;
        let snippet = |s: crate::source::Span| &text[s.range()];
        assert_eq!(snippet(d.span), "A -> B : l1");
        assert_eq!(snippet(d.labels[0].span), "C -> A : x");
        assert_eq!(snippet(d.labels[1].span), "C -> A : y");
        assert!(d.labels[0].message.contains("A!x"), "{:?}", d.labels);
        assert!(d.help.as_deref().unwrap_or("").contains("inform `C`"));
        // The other participants still have projections.
        assert!(map.contains_key(&RoleId(0)) && map.contains_key(&RoleId(1)));
        assert!(!map.contains_key(&RoleId(2)));
        let _ = prog;
    }

    #[test]
    fn shared_labels_merge_their_continuations() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. A -> C : go. dt<C: m>. C -> A : a. end
              + A -> B : l2. A -> C : go. A -> C : more. end;"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "C"), "A?go.&{\n  A?more.end\n} & dt<m>.A!a.end");
    }

    /// Def 4.7 compares the branches' projections up to the renaming of their binders:
    /// each branch's `go(v)` is its own binding site, and the projections onto `C` are
    /// alpha-equal, so they merge.
    #[test]
    fn alpha_equal_branches_merge() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. A -> C : go(v: real {{v >= 0}}). C -> A : ok(u: real {{u == v}}). end
              + A -> B : l2. A -> C : go(v: real {{v >= 0}}). C -> A : ok(u: real {{u == v}}). end;"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "C"), "A?go(v: real { v >= 0 }).A!ok(u: real { u == v }).end");
    }

    /// Merging a shared label reads the second branch's continuation in terms of the
    /// first branch's binders: the merged `A?b` speaks of the merged `go`'s `v`.
    #[test]
    fn merged_continuations_refer_to_the_merged_binder() {
        let src = format!(
            "{ABC} choreography G =
                A -> B : l1. A -> C : go(v: real). A -> C : a(u: real {{u == v}}). end
              + A -> B : l2. A -> C : go(v: real). A -> C : b(u: real {{u == v}}). end;"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        let c = map.get(&prog.role_by_name("C").expect("C")).expect("projection");
        let Local::Recv { branches, .. } = &**c else { panic!("a receive: {c:?}") };
        let v = branches[0].payload[0].value;
        let Local::Recv { branches: inner, .. } = &*branches[0].cont else { panic!("a receive") };
        assert_eq!(inner.len(), 2);
        for b in inner {
            let mut seen = Vec::new();
            b.payload[0].refinement.as_ref().expect("refinement").visit_vars(&mut |x, _| {
                if let Var::Value(id, name) = x {
                    if name == "v" {
                        seen.push(*id);
                    }
                }
            });
            assert_eq!(seen, vec![v], "`{}` must read the merged `go`'s `v`", b.label);
            // `u == v`, the renamed `v` keeping its sort.
            let Some(ExprKind::Binary(_, _, rhs)) = b.payload[0].refinement.as_ref().map(|r| &r.kind) else {
                panic!("an equation")
            };
            assert_eq!((&rhs.kind, &rhs.sort), (&ExprKind::Var(Var::Value(v, "v".into())), &Sort::Real));
        }
    }

    /// Two projections that print the same but speak of different values are not
    /// equal: in the second branch `v` is A's new `l2` field, not the `v` A received
    /// before the choice. Merged by name (as before), `C` would have assumed in both
    /// branches that `w` is the first `v`.
    #[test]
    fn same_text_about_different_values_does_not_merge() {
        let src = format!(
            "{ABC} choreography G = B -> A : pre(v: real).
                ( A -> B : l1. A -> C : go(w: real {{w == v}}). end
                + A -> B : l2(v: real). A -> C : go(w: real {{w == v}}). end );"
        );
        let (prog, map, diags) = projections(&src);
        assert_eq!(diags.iter().map(|d| d.code).collect::<Vec<_>>(), vec![Code::Unmergeable], "{diags:?}");
        assert!(!map.contains_key(&prog.role_by_name("C").expect("C")));
    }

    #[test]
    fn a_role_outside_a_recursion_gets_end() {
        let src = format!("{ABC} choreography G = A -> C : hi. mu t. A -> B : ping. B -> A : pong. t;");
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "C"), "A?hi.end");
        assert_eq!(printed(&prog, &map, "B"), "mu t. A?ping.A!pong.t");
    }

    #[test]
    fn separation_projects_the_side_of_the_role() {
        let src = format!("{ABC} choreography G = (dt<A: m> * dt<B: n>). A -> B : x. (dt<A: m> * dt<C: w>). end;");
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "A"), "dt<m>.B!x.dt<m>.end");
        assert_eq!(printed(&prog, &map, "B"), "dt<n>.A?x.end");
        assert_eq!(printed(&prog, &map, "C"), "dt<w>.end");
    }

    #[test]
    fn guards_and_refined_payloads_are_kept() {
        let src = format!("{ABC} choreography G = A -> B : [x > 0] go(v: real {{ v > A.x }}). end;");
        let (prog, map, _) = projections(&src);
        assert_eq!(printed(&prog, &map, "A"), "[A.x > 0] B!go(v: real { v > A.x }).end");
        assert_eq!(printed(&prog, &map, "B"), "A?go(v: real { v > A.x }).end");
    }

    #[test]
    fn declared_local_types_must_equal_the_projection() {
        let src = format!(
            "{ABC} choreography G = A -> B : l1(v: real). B -> C : x. end + A -> B : l2. B -> C : y. end;
             local B = &{{ A?l2.C!y.end, A?l1(v: real).C!x.end }};
             local C = &{{ B?x.end }};"
        );
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        let d = check_declared(&prog, &map);
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].code, Code::LocalMismatch);
        assert!(d[0].message.contains("`C`"));
        assert!(d[0].notes[0].contains("B?y.end"), "{:?}", d[0].notes);
        assert!(d[0].help.as_deref().unwrap_or("").contains("mochi project"));
    }

    #[test]
    fn ill_formed_choreographies_get_diagnostics_not_panics() {
        let src = format!("{ABC} choreography G = dt<A: m> + A -> B : x;");
        let (_, _, diags) = projections(&src);
        assert!(diags.iter().all(|d| d.code == Code::ChoiceMismatch) && !diags.is_empty(), "{diags:?}");
        let src = format!("{ABC} choreography G = A -> B : x + A -> C : y;");
        let (_, _, diags) = projections(&src);
        assert!(diags.iter().all(|d| d.code == Code::ChoiceMismatch) && !diags.is_empty(), "{diags:?}");
        let src = format!("{ABC} choreography G = A -> B : x * A -> C : y;");
        let (_, map, diags) = projections(&src);
        assert_eq!(diags.len(), 1, "{diags:?}");
        assert_eq!(diags[0].code, Code::SeparationOverlap);
        assert_eq!(map.len(), 2);
    }

    #[test]
    fn nested_choices_are_distributed() {
        let src =
            format!("{ABC} choreography G = (A -> B : x + A -> B : y). B -> C : z. end + A -> B : w. B -> C : v. end;");
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(printed(&prog, &map, "A"), "+{\n  B!x.end,\n  B!y.end,\n  B!w.end\n}");
        assert_eq!(printed(&prog, &map, "B"), "&{\n  A?x.C!z.end,\n  A?y.C!z.end,\n  A?w.C!v.end\n}");
        assert_eq!(printed(&prog, &map, "C"), "&{\n  B?z.end,\n  B?v.end\n}");
    }

    #[test]
    fn large_shared_types_are_summarised_in_notes() {
        // Each choice doubles the printed size of A's projection, not its size in memory.
        let choices: Vec<String> = (0..40).map(|i| format!("(A -> B : a{i} + A -> B : b{i})")).collect();
        let src = format!("{ABC} choreography G = {}. end;", choices.join(". "));
        let (prog, map, diags) = projections(&src);
        assert!(diags.is_empty(), "{diags:?}");
        let a = map.get(&RoleId(0)).expect("A is projected");
        let text = print_bounded(&prog, a, NOTE_NODES);
        assert!(text.starts_with("+{B!a0, B!b0}. ..."), "{text}");
        let small = map.get(&RoleId(2)).expect("C is projected");
        assert_eq!(print_bounded(&prog, small, NOTE_NODES), "end");
    }

    #[test]
    fn deep_sequences_and_choices_do_not_overflow() {
        let mut g = String::from("end");
        for i in 0..150 {
            g = format!("(A -> B : a{i}. {g} + A -> B : b{i}. end)");
        }
        let seq: Vec<String> = (0..3000).map(|i| format!("A -> B : s{i}")).collect();
        let src = format!("{ABC} choreography G = {}. {g};", seq.join(". "));
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let (map, diags) = project_all(&prog);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(map.len(), 3);
        let b = map.get(&RoleId(1)).cloned().expect("B is projected");
        let Some(chor) = &prog.choreography else { panic!() };
        let again = project(&prog, &chor.body, RoleId(1), Arc::new(Local::End(Loc::default()))).expect("projects");
        assert!(!Arc::ptr_eq(&b, &again) && equal(&b, &again));
    }
}
