//! Well-scopedness (Sec 4.1, labelling rules (1)-(6)) on the once-unfolded type, with
//! the participant half of full separation (E0307), total motion (Def 4.4 (3), E0309),
//! `pt{G} = P` of [T-SESS] (E0313), the coupling half of full separation (E0315) and the
//! [AGCOMP] obligation of each joint motion (whose joint-end part decides E0401, several
//! non-interruptible primitives, in the SMT stage).
//!
//! The labelling is deterministic: the root gets every participant, `.` and `+` pass
//! their label down, and `g1 * ... * gn` gives each side exactly `pt{g_i}`. That choice
//! loses nothing: any valid labelling must give side i at least `pt{g_i}`, and a
//! participant given to no side has no motion there, which total motion forbids.
//!
//! Predicates are not decided here; each joint motion yields an [AGCOMP] obligation,
//! each `*` a full-separation obligation and each guarded choice a total-choice one.
//! They are made by a second walk, [`Contexts`], which threads the logical context Σ
//! ([`Sigma`]) through the type (not unfolded: loops get an invariant instead) and gives
//! each obligation the Σ of its point as hypotheses:
//!
//! - the root starts from every participant's `init` and its kind's invariant ([T-SESS]);
//! - after `p -> q : [P] l(v: S {P'})`, Σ ∧ P ∧ P' (payload fields are value variables;
//!   a field of the same name bound earlier is forgotten first);
//! - each branch of a choice starts from Σ ∧ its first message's guard, and after the
//!   choice Σ is the join of the branches that continue (what they agree on, with
//!   literal bounds weakened to cover every branch);
//! - a joint motion `dt<p: a, q: b>` applies the effect of every part
//!   ([`Sigma::apply_joint_motion`]: strongest postcondition, one level of snapshots);
//! - `g1 * g2`: each side starts from the facts of Σ over its own participants (and over
//!   values and constants only), and afterwards Σ is the conjunction of the sides' ends;
//! - `mu t(n: S {R} = e). G`: R must hold of `e` at entry (E0414) and of the arguments
//!   at each `t(a)` (E0415); the body assumes it. The rest of the loop invariant is a
//!   fixpoint: the candidate is Σ at entry; the body is walked under it (and R), and the
//!   next candidate is its join ([`Sigma::join`]: common facts, and the weaker of two
//!   literal bounds on a term) with the context at every `t` reached, until it is the
//!   candidate again. After [`WEAKEN_WALKS`] walks only facts every `t` holds literally
//!   are kept (widening), so the candidate shrinks and this ends. Only the last walk's
//!   obligations are kept. Recursion parameters are forgotten at entry and at each `t`.
//!
//! Every step only keeps or weakens what holds, so every obligation's hypotheses hold
//! whenever the choreography reaches its point.

use crate::diag::{Code, Diagnostic};
use crate::hir::expr::{and_all, defined_and, definedness, BinOp};
use crate::hir::*;
use crate::obligation::{Enabled, Goal, Obligation, RoleMotion, Rule, Side};
use crate::sigma::Sigma;
use std::collections::HashMap;

pub fn check(prog: &Program, g: &Global) -> (Vec<Obligation>, Vec<Diagnostic>) {
    let mut s = Scope { prog, diags: Vec::new(), recs: HashMap::new(), unfolding: Vec::new() };
    let used = participants(g);
    let all: Vec<RoleId> = prog.role_ids().collect();
    for r in not_in(&all, &used) {
        s.diags.push(
            Diagnostic::error(
                Code::ParticipantUnused,
                prog.role(r).span,
                format!("participant `{}` takes no part in the choreography", prog.role_name(r)),
            )
            .with_note("[T-SESS] requires pt{G} = P")
            .with_help("give it a role in the choreography or remove it from the system"),
        );
    }
    // The root scope is P; an unused participant was reported above (E0313), so scope
    // with pt{G} to avoid reporting it again at every motion.
    s.walk(g, &used, true);
    let mut c = Contexts {
        prog,
        obligations: Vec::new(),
        loops: Vec::new(),
        jumps: Vec::new(),
        runs: Vec::new(),
        in_par: 0,
        steps: 0,
        choice_firsts: Default::default(),
        enum_of: Default::default(),
        exact_entry: Default::default(),
    };
    let start = c.initial();
    c.streams();
    c.walk(g, start);
    (c.obligations, s.diags)
}

struct Scope<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
    /// Recursion variable → its body, for the one unfolding.
    recs: HashMap<&'a str, &'a Global>,
    /// Variables being unfolded (their second occurrence is a leaf).
    unfolding: Vec<&'a str>,
}

/// pt{G} in order of appearance, as [`Global::participants`] gives it, through a set:
/// a joint motion of n participants is n lookups, not n²/2 comparisons.
fn participants(g: &Global) -> Vec<RoleId> {
    fn go(g: &Global, seen: &mut std::collections::HashSet<RoleId>, out: &mut Vec<RoleId>) {
        let mut add = |r: RoleId| {
            if seen.insert(r) {
                out.push(r)
            }
        };
        match g {
            Global::Msg(m) => {
                add(m.from);
                add(m.to);
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| add(*r)),
            Global::After(a) => add(a.by),
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
                gs.iter().for_each(|g| crate::stack::deep(|| go(g, seen, out)))
            }
            Global::Rec { body, .. } => crate::stack::deep(|| go(body, seen, out)),
            Global::Var(_) | Global::End(_) => {}
        }
    }
    let mut out = Vec::new();
    let mut seen = Default::default();
    crate::stack::deep(|| go(g, &mut seen, &mut out));
    out
}

/// The participants of `rs` not in `of`, in the order of `rs`. A joint motion of n
/// participants in a scope of n compares them through a set, not pairwise.
fn not_in(rs: &[RoleId], of: &[RoleId]) -> Vec<RoleId> {
    if rs.len() * of.len() > 4096 {
        let of: std::collections::HashSet<&RoleId> = of.iter().collect();
        rs.iter().copied().filter(|r| !of.contains(r)).collect()
    } else {
        rs.iter().copied().filter(|r| !of.contains(r)).collect()
    }
}

fn names(prog: &Program, rs: &[RoleId]) -> String {
    let v: Vec<_> = rs.iter().map(|r| format!("`{}`", prog.role_name(*r))).collect();
    v.join(", ")
}

impl<'a> Scope<'a> {
    /// `original` is false inside an unfolded copy, where per-node errors were already
    /// produced for the original.
    fn walk(&mut self, g: &'a Global, scope: &[RoleId], original: bool) {
        crate::stack::deep(|| self.walk_inner(g, scope, original))
    }

    fn out_of_scope(&mut self, who: &[RoleId], scope: &[RoleId], loc: Loc, what: &str) {
        let outside = not_in(who, scope);
        if outside.is_empty() {
            return;
        }
        self.diags.push(
            Diagnostic::error(
                Code::OutOfScope,
                loc.0,
                format!(
                    "{what} involves {}, outside its scope {{{}}}",
                    names(self.prog, &outside),
                    names(self.prog, scope)
                ),
            )
            .with_note("Sec 4.1, well-scopedness: a `*` splits the participants in scope between its sides")
            .with_help("move this action out of the `*`, or move the participant into this side"),
        );
    }

    fn walk_inner(&mut self, g: &'a Global, scope: &[RoleId], original: bool) {
        match g {
            Global::Msg(m) => {
                if original {
                    self.out_of_scope(&[m.from, m.to], scope, m.loc, "this message");
                }
            }
            Global::Motion(m) => {
                if original {
                    self.motion(m, scope);
                }
            }
            Global::After(a) => {
                if original {
                    self.out_of_scope(&[a.by], scope, a.loc, "this timeout");
                }
            }
            Global::Seq(items, _) => items.iter().for_each(|i| self.walk(i, scope, original)),
            Global::Choice(branches, _) => branches.iter().for_each(|b| self.walk(b, scope, original)),
            Global::Par(sides, loc) => self.par(sides, *loc, scope, original),
            Global::Rec { var, body, .. } => {
                self.recs.insert(var, body);
                self.walk(body, scope, original);
            }
            Global::Var(v) => {
                if self.unfolding.contains(&v.var.as_str()) {
                    return;
                }
                let Some(body) = self.recs.get(v.var.as_str()).copied() else { return };
                let mut pt = Vec::new();
                body.participants(&mut pt);
                let outside = not_in(&pt, scope);
                if !outside.is_empty() {
                    self.diags.push(
                        Diagnostic::error(
                            Code::OutOfScope,
                            v.loc.0,
                            format!(
                                "unfolding `{}` here brings {} into a scope of only {{{}}}",
                                v.var,
                                names(self.prog, &outside),
                                names(self.prog, scope)
                            ),
                        )
                        .with_note("Sec 4.1: well-scopedness is checked on the once-unfolded type")
                        .with_help("recurse outside the `*`, where every participant of the loop is in scope"),
                    );
                    return;
                }
                self.unfolding.push(&v.var);
                self.walk(body, scope, false);
                self.unfolding.pop();
            }
            Global::End(_) => {}
        }
    }

    fn motion(&mut self, m: &Motion, scope: &[RoleId]) {
        let who: Vec<RoleId> = m.parts.iter().map(|(r, _)| *r).collect();
        self.out_of_scope(&who, scope, m.loc, "this joint motion");
        let missing = not_in(scope, &who);
        if !missing.is_empty() {
            self.diags.push(
                Diagnostic::error(
                    Code::IncompleteMotion,
                    m.loc.0,
                    format!("this joint motion gives no primitive to {}, in scope here", names(self.prog, &missing)),
                )
                .with_note("Def 4.4 (3), total motion: time passes for every participant in scope, so each must run a primitive")
                .with_help("add a primitive for them (an idle one if they stay put), or separate them with `*`"),
            );
        }
        // Several non-interruptible primitives are not an error here: whether their
        // durations force a common end (joint end, ARCHITECTURE.md) depends on Σ, so the
        // SMT stage decides it as a part of this motion's [AGCOMP] obligation (E0401).
    }

    fn par(&mut self, sides: &'a [Global], loc: Loc, scope: &[RoleId], original: bool) {
        let pts: Vec<Vec<RoleId>> = sides.iter().map(Global::participant_list).collect();
        if original {
            // Each participant's side, found in one pass (n-ary `*` of PGCD's lanes has
            // hundreds of sides, so no pairwise comparison of sides).
            let mut owner: HashMap<RoleId, usize> = HashMap::new();
            let mut reported: Vec<RoleId> = Vec::new();
            for (i, pt) in pts.iter().enumerate() {
                for r in pt {
                    match owner.get(r) {
                        Some(&j) if j != i && !reported.contains(r) => {
                            reported.push(*r);
                            self.diags.push(
                                Diagnostic::error(
                                    Code::SeparationOverlap,
                                    sides[i].loc().0,
                                    format!("{} on both sides of `*`", names(self.prog, &[*r])),
                                )
                                .with_label(sides[j].loc().0, "the other side")
                                .with_note("Sec 4.1, full separation: pt{g1} ∩ pt{g2} = ∅")
                                .with_help("keep each participant's actions on one side of the `*`"),
                            );
                        }
                        Some(_) => {}
                        None => {
                            owner.insert(*r, i);
                        }
                    }
                }
            }
            let dropped: Vec<RoleId> = scope.iter().copied().filter(|r| !owner.contains_key(r)).collect();
            if !dropped.is_empty() {
                self.diags.push(
                    Diagnostic::error(
                        Code::IncompleteMotion,
                        loc.0,
                        format!("{} in scope but on no side of this `*`", names(self.prog, &dropped)),
                    )
                    .with_note(
                        "Def 4.4 (3), total motion: while the sides run, every participant in scope must be moving",
                    )
                    .with_help("add a side `dt<P: idle>` for them"),
                );
            }
            self.coupling(sides, &owner);
        }
        for (side, pt) in sides.iter().zip(&pts) {
            let sub: Vec<RoleId> = if pt.len() * scope.len() > 4096 {
                let in_scope: std::collections::HashSet<&RoleId> = scope.iter().collect();
                pt.iter().copied().filter(|r| in_scope.contains(r)).collect()
            } else {
                pt.iter().copied().filter(|r| scope.contains(r)).collect()
            };
            self.walk(side, &sub, original);
        }
    }

    /// Full separation, coupling half (Sec 4.1): the assumption of a primitive in side i
    /// reads only inputs fed by participants of side i.
    fn coupling(&mut self, sides: &[Global], owner: &HashMap<RoleId, usize>) {
        for (i, side) in sides.iter().enumerate() {
            let mut motions = Vec::new();
            collect_motions(side, &mut motions);
            for m in motions {
                for (r, app) in &m.parts {
                    let prim = self.prog.prim(app.prim);
                    let sources = &self.prog.role(*r).input_sources;
                    let mut bad = Vec::new();
                    prim.assume.visit_vars(&mut |v, _| {
                        if let Var::Own(Slot::Input(k)) = v {
                            if let Some(Some(src)) = sources.get(*k) {
                                if owner.get(src) != Some(&i) && !bad.iter().any(|(kk, _)| kk == k) {
                                    bad.push((*k, *src));
                                }
                            }
                        }
                    });
                    for (k, src) in bad {
                        let input = &self.prog.kind_of(*r).inputs[k].0;
                        self.diags.push(
                            Diagnostic::error(
                                Code::CoupledAcrossSeparation,
                                app.loc.0,
                                format!(
                                    "the assumption of `{}` reads input `{input}` of `{}`, fed by `{}` outside this side of `*`",
                                    prim.name,
                                    self.prog.role_name(*r),
                                    self.prog.role_name(src)
                                ),
                            )
                            .with_note("Sec 4.1, full separation: assumptions depend only on state variables of the same side")
                            .with_help(format!("put `{}` and `{}` on the same side", self.prog.role_name(*r), self.prog.role_name(src))),
                        );
                    }
                }
            }
        }
    }
}

/// After this many walks of one loop body its candidate invariant is given up for
/// `true` (which is always an invariant), and so once the whole walk has taken
/// [`STEP_BUDGET`] steps: nested loops would otherwise multiply their walks.
const MAX_LOOP_WALKS: usize = 32;
/// For this many walks the candidate is joined with the jumps' contexts by
/// [`Sigma::join`], whose bounds may weaken step by step (`x <= 1`, `x <= 2`, ...);
/// after them only facts every jump holds literally are kept (the widening: a bound
/// that keeps weakening goes to ±∞), so the candidate can only shrink and the
/// fixpoint ends.
const WEAKEN_WALKS: usize = 4;
const STEP_BUDGET: usize = 1 << 20;

/// The walk that threads Σ through the type and makes the predicate obligations (see
/// the module documentation).
struct Contexts<'a> {
    prog: &'a Program,
    obligations: Vec<Obligation>,
    /// Enclosing recursions, innermost last: the variable, its parameters and its
    /// termination measure.
    loops: Vec<(&'a str, &'a [RecParam], Option<&'a Expr>)>,
    /// The contexts reached at recursion variables: (index into `loops`, Σ there).
    jumps: Vec<(usize, Sigma)>,
    /// The primitives run inside some `*`, in walk order, with the context each starts
    /// in; each side of a `*` takes the ones logged while it was walked.
    runs: Vec<RoleMotion>,
    /// How many `*` enclose the current point.
    in_par: usize,
    steps: usize,
    /// The first messages of the choices met: their progress is the choice's.
    choice_firsts: std::collections::HashSet<crate::source::Span>,
    /// The enum of each enum-typed payload value met so far (E0243's shortcut for `x == y`
    /// with `y` of the same enum).
    enum_of: HashMap<ValueId, (String, crate::dialect::Wire)>,
    /// The exact entry predicate of each enum-typed payload value that Σ assumes by a
    /// weaker fact (`lower::approximate_entries`): added to the hypotheses of total choice
    /// and progress ([`Contexts::exact`]), whose counterexamples must be values of the
    /// fields' types.
    exact_entry: HashMap<ValueId, Expr>,
}

impl<'a> Contexts<'a> {
    /// Walks `g` from context `sigma`; the context at its end, or `None` when no path
    /// goes past it (it loops back or ends).
    fn walk(&mut self, g: &'a Global, sigma: Sigma) -> Option<Sigma> {
        crate::stack::deep(|| self.walk_inner(g, sigma))
    }

    fn walk_inner(&mut self, g: &'a Global, mut sigma: Sigma) -> Option<Sigma> {
        self.steps += 1;
        match g {
            Global::Msg(m) => {
                // Progress (E0419): in every state of Σ, the guard holds and some payload
                // satisfies the refinements (the first message of a choice: the
                // choice's). A message no value fits is stuck, not unreachable: nothing
                // but the protocol itself is there to establish it (a program may have no
                // processes at all).
                if !self.choice_firsts.contains(&m.loc.0) {
                    observe(&mut sigma, &m.observed);
                    let e = enabled(self.prog, m);
                    if e.guard.is_some() || !e.refinement.is_true() {
                        self.obligations.push(Obligation {
                            rule: Rule::Progress,
                            span: m.loc.0,
                            what: format!("the message {}: some payload satisfies its refinements", e.what),
                            hyps: self.exact(sigma.facts()),
                            goal: Goal::Progress { branches: vec![e] },
                        });
                    }
                }
                // Σ assumes a costly entry predicate (MAV_CMD's fifty runs) by its hull; the
                // message's own checks read the exact one (`lower::approximate_entries`).
                let assumed = crate::lower::approximate_entries(self.prog.dialect, m);
                if let Some(a) = &assumed {
                    for (f, g) in m.payload.iter().zip(&a.payload) {
                        let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
                        if f.refinement != g.refinement {
                            let x = crate::hir::expr::value_expr(f.value, &f.name, &f.sort);
                            let (entry, _) = crate::lower::entry_predicate(self.prog.dialect, check, &x);
                            self.exact_entry.insert(f.value, entry);
                        }
                    }
                }
                let asked = self.enum_fields(m);
                if !asked.is_empty() {
                    self.enum_entries(m, assumed.as_ref().unwrap_or(m), &asked, &sigma);
                }
                sigma.assume_message(assumed.as_ref().unwrap_or(m));
                Some(sigma)
            }
            Global::Motion(m) => {
                self.motion(m, &mut sigma);
                Some(sigma)
            }
            Global::Seq(items, _) => {
                let mut cur = Some(sigma);
                for it in items {
                    // What follows a `t` or `end` is unreachable (E0314): `true` will do.
                    cur = self.walk(it, cur.unwrap_or_default());
                }
                cur
            }
            Global::Choice(branches, _) => {
                // The deciding participant's snapshot, shared by the branches' first messages.
                let mut snap: Vec<Observed> = Vec::new();
                for m in branches.iter().filter_map(super::side::first_message) {
                    for o in &m.observed {
                        if !snap.iter().any(|x| x.value == o.value) {
                            snap.push(o.clone());
                        }
                    }
                }
                observe(&mut sigma, &snap);
                self.total_choice(branches, &sigma);
                self.progress(branches, &sigma);
                let mut out: Option<Sigma> = None;
                for b in branches {
                    let mut s = sigma.clone();
                    let first = super::side::first_message(b);
                    if let Some(guard) = first.and_then(|m| m.guard.as_ref()) {
                        s.assume(&defined_and(guard.clone()));
                    }
                    if let (Some(m), true) = (first, branches.len() > 1) {
                        // A dead branch: its guard, or its guard and its payload's
                        // refinements together (no value fits), contradict Σ.
                        let mut taken = sigma.clone();
                        taken.assume_message(m);
                        if taken.facts() != sigma.facts() {
                            let what = format!(
                                "the guard and payload of branch `{}` ({} -> {})",
                                m.label,
                                self.prog.role_name(m.from),
                                self.prog.role_name(m.to)
                            );
                            self.reachable(m.loc.0, what, &taken, vec![sigma.facts().to_vec()], true);
                        }
                    }
                    if let Some(end) = self.walk(b, s) {
                        out = Some(match out {
                            None => end,
                            Some(o) => o.join(&end, self.prog),
                        });
                    }
                }
                out
            }
            Global::Par(sides, loc) => self.par(sides, *loc, sigma),
            Global::Rec { var, params, decreases, body, .. } => self.rec(var, params, decreases.as_ref(), body, sigma),
            Global::Var(v) => {
                if let Some(i) = self.loops.iter().rposition(|(n, _, _)| *n == v.var) {
                    let (_, params, measure) = self.loops[i];
                    if let (Some(e), true) = (measure, params.len() == v.args.len()) {
                        self.measure(&v.var, e, params, v, &sigma);
                    }
                    // The next iteration assumes the refinements of the arguments.
                    if params.len() == v.args.len() {
                        for p in params {
                            let Some(r) = &p.refinement else { continue };
                            self.obligations.push(Obligation {
                                rule: Rule::RecJump,
                                span: v.loc.0,
                                what: format!(
                                    "the refinement `{}` of parameter `{}` of `{}` must hold of the argument{}",
                                    print::expr(self.prog, None, r),
                                    p.name,
                                    v.var,
                                    args_text(self.prog, &v.args)
                                ),
                                hyps: sigma.facts().to_vec(),
                                goal: Goal::Valid(defined_and(crate::sigma::subst_params(r, params, &v.args))),
                            });
                        }
                    }
                    // The arguments are the parameters' new values.
                    let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
                    sigma.forget_values(&ids);
                    self.jumps.push((i, sigma));
                }
                None
            }
            Global::End(_) => None,
            // A timeout teaches nothing about values (docs/observed-and-timeouts.md): Σ
            // after it is Σ at the choice.
            Global::After(_) => Some(sigma),
        }
    }

    /// Termination (`mu t(params) decreases E`): at the jump `t(a)` (`v`), under Σ there
    /// (the path's messages and guards, the parameters' refinements, the loop invariant),
    /// `E >= 0` (E0416) and `E[a/params] < E` (E0417). E reads only the parameters, values
    /// bound before the loop and constants (lowering), none of which changes between the
    /// loop head and a jump back to it: E here is E of the iteration that jumps.
    fn measure(&mut self, var: &str, e: &Expr, params: &[RecParam], v: &RecVar, sigma: &Sigma) {
        let text = print::expr(self.prog, None, e);
        let zero = Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc: e.loc };
        let cmp = |op, a: Expr, b: Expr| Expr {
            kind: ExprKind::Binary(op, Box::new(a), Box::new(b)),
            sort: Sort::Bool,
            loc: e.loc,
        };
        self.obligations.push(Obligation {
            rule: Rule::MeasureBound,
            span: v.loc.0,
            what: format!("the measure `{text}` of `{var}` at the jump `{}`", jump_text(self.prog, v)),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Valid(defined_and(cmp(BinOp::Le, zero, e.clone()))),
        });
        let next = crate::sigma::subst_params(e, params, &v.args);
        self.obligations.push(Obligation {
            rule: Rule::MeasureDecrease,
            span: v.loc.0,
            what: format!(
                "the measure `{text}` of `{var}` must decrease at the jump `{}` (to `{}`)",
                jump_text(self.prog, v),
                print::expr(self.prog, None, &next)
            ),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Valid(defined_and(cmp(BinOp::Lt, next, e.clone()))),
        });
    }

    /// The streams' assumption, checked: every reading of a stream satisfies its fields'
    /// refinements (wire range, enum, the invariant), so some message of the stream must
    /// exist. An invariant no value of the field's type satisfies would make every step that
    /// reads the stream hold vacuously (a protocol whose first step can never be taken would
    /// verify with a warning): it is E0410 at the stream, as an `init` no state satisfies is.
    /// One query per stream: a stream's refinements read its own template values and
    /// constants only (E0211), so streams are independent of each other and of Σ.
    fn streams(&mut self) {
        for s in &self.prog.streams {
            let facts: Vec<Expr> = s.fields.iter().filter_map(|f| f.refinement.clone()).collect();
            if facts.is_empty() {
                continue;
            }
            let to: Vec<&str> = s.to.iter().map(|&r| self.prog.role_name(r)).collect();
            let what = format!(
                "the invariant of the stream `{} -> {}: {}`",
                self.prog.role_name(s.from),
                to.join(", "),
                s.label
            );
            self.reachable(s.loc.0, what, &Sigma::from_facts(&facts), Vec::new(), false);
        }
    }

    /// [T-SESS]'s assumption, checked: each participant's `init` is satisfiable and
    /// implies its kind's invariant, and all of them are jointly satisfiable. The
    /// initial context Σ (every `init` and invariant) is returned.
    fn initial(&mut self) -> Sigma {
        let prog = self.prog;
        let mut each = Vec::new();
        for r in prog.role_ids() {
            let init = crate::sigma::init(prog, r);
            let span = prog.role(r).init.as_ref().map(|e| e.loc.0).unwrap_or(prog.role(r).span);
            let name = prog.role_name(r);
            // The robot's first state satisfies `init` and, as every state of the kind,
            // the invariant: `init` need not repeat the invariant, but must allow a
            // state within it (E0411). One query when it does; when it does not, an
            // `init` no state satisfies at all is E0410 instead.
            let both = Sigma::initial(prog, [r]).into_facts();
            if crate::sigma::invariant(prog, r).is_empty() {
                if !init.is_empty() {
                    let what = format!("the initial state of `{name}`");
                    self.reachable(span, what, &Sigma::from_facts(&init), Vec::new(), false);
                }
            } else {
                self.obligations.push(Obligation {
                    rule: Rule::InitInvariant,
                    span,
                    what: format!("the `init` of `{name}`"),
                    hyps: both.clone(),
                    goal: Goal::Reachable { before: vec![init], dead_branch: false },
                });
            }
            each.push(both);
        }
        let all = Sigma::initial(prog, prog.role_ids());
        // Contexts over disjoint variables (each participant's own, an input being its
        // source's) are jointly satisfiable when each is: ask only when some share.
        let mut owner: HashMap<Var, usize> = HashMap::new();
        let mut shared = false;
        for (i, facts) in each.iter().enumerate() {
            for f in facts {
                f.visit_vars(&mut |v, _| {
                    if !matches!(v, Var::Const(_)) {
                        shared |= *owner.entry(prog.source_of(v)).or_insert(i) != i;
                    }
                });
            }
        }
        if shared && !all.is_empty() {
            let span = prog.system.as_ref().map(|(_, s)| *s).unwrap_or_default();
            let what = "the conjunction of the participants' initial states".to_string();
            self.reachable(span, what, &all, each, false);
        }
        all
    }

    /// The vacuity guard at a step: Σ after it (`sigma`) is satisfiable, or the step is
    /// where the protocol gets stuck (when every context in `before` is satisfiable).
    fn reachable(
        &mut self,
        span: crate::source::Span,
        what: String,
        sigma: &Sigma,
        before: Vec<Vec<Expr>>,
        dead_branch: bool,
    ) {
        self.obligations.push(Obligation {
            rule: Rule::Reachable,
            span,
            what,
            hyps: sigma.facts().to_vec(),
            goal: Goal::Reachable { before, dead_branch },
        });
    }

    /// [AGCOMP] under Σ, the runs for enclosing `*`s, then the motion's effect.
    fn motion(&mut self, m: &Motion, sigma: &mut Sigma) {
        // Every dt gets one: even a lone primitive must be able to end (see smt::goals).
        let who: Vec<RoleId> = m.parts.iter().map(|(r, _)| *r).collect();
        self.obligations.push(Obligation {
            rule: Rule::AgComp,
            span: m.loc.0,
            what: format!("joint motion of {}", names(self.prog, &who)),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Compatible { parts: m.parts.clone() },
        });
        if self.in_par > 0 {
            for (role, app) in &m.parts {
                self.runs.push(RoleMotion { role: *role, app: app.clone(), hyps: sigma.facts().to_vec() });
            }
        }
        sigma.apply_joint_motion(self.prog, &m.parts);
    }

    /// `facts` with the exact entry predicate of every payload value they mention whose
    /// entry predicate Σ assumes by a weaker fact (MAV_CMD's hull): total choice and
    /// progress then decide over the field's type (a counterexample is an entry, and a
    /// split at a gap of the entries is total), while the other checks keep Σ's cheaper
    /// fact. Sound: the predicate mentions the value alone and holds of every value the
    /// field carried (it is the field's type), whichever binding a fact is about.
    fn exact(&self, facts: &[Expr]) -> Vec<Expr> {
        let mut out = facts.to_vec();
        if self.exact_entry.is_empty() {
            return out;
        }
        let mut seen = std::collections::BTreeSet::new();
        for f in facts {
            f.visit_vars(&mut |v, _| {
                if let Var::Value(id, _) = v {
                    if self.exact_entry.contains_key(id) {
                        seen.insert(*id);
                    }
                }
            });
        }
        out.extend(seen.into_iter().filter_map(|id| self.exact_entry.get(&id).cloned()));
        out
    }

    /// Def 4.4 (1): under Σ, some guard holds.
    fn total_choice(&mut self, branches: &[Global], sigma: &Sigma) {
        let guards: Vec<Option<&Expr>> =
            branches.iter().map(|b| super::side::first_message(b).and_then(|m| m.guard.as_ref())).collect();
        if guards.iter().any(|g| g.is_none_or(Expr::is_true)) {
            return; // an unguarded branch: the disjunction is trivially valid
        }
        let Some(m) = branches.first().and_then(super::side::first_message) else { return };
        // A guard that cannot be evaluated does not hold: each disjunct is defined too.
        let mut disj: Option<Expr> = None;
        for g in guards.into_iter().flatten().map(|g| defined_and(g.clone())) {
            disj = Some(match disj {
                None => g,
                Some(d) => {
                    let loc = d.loc;
                    Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(d), Box::new(g)), sort: Sort::Bool, loc }
                }
            });
        }
        if let Some(goal) = disj {
            self.obligations.push(Obligation {
                rule: Rule::TotalChoice,
                span: m.loc.0,
                what: format!("the guards of the choice by `{}`", self.prog.role_name(m.from)),
                hyps: self.exact(sigma.facts()),
                goal: Goal::Valid(goal),
            });
        }
    }

    /// The fields of `m` that E0243 asks about: enum-typed, with a user refinement that does
    /// not settle the question by itself ([`pins_entry`]). Records the enum of every
    /// enum-typed field of `m` on the way.
    fn enum_fields(&mut self, m: &Msg) -> Vec<usize> {
        let mut asked = Vec::new();
        for (i, f) in m.payload.iter().enumerate() {
            let Some(mav) = &f.mav else { continue };
            let Some(check) = &mav.entry else { continue };
            self.enum_of.insert(f.value, (check.enum_name.clone(), check.wire));
            let user = match (&f.refinement, mav.implicit) {
                (Some(r), true) if mav.user => match &r.kind {
                    ExprKind::Binary(BinOp::And, _, u) => Some(&**u),
                    _ => None,
                },
                (r, false) if mav.user => r.as_ref(),
                _ => None,
            };
            if user.is_some_and(|u| !pins_entry(self.prog, &self.enum_of, f.value, check, u)) {
                asked.push(i);
            }
        }
        asked
    }

    /// Enum-typed MAVLink fields (E0243; ARCHITECTURE.md, "Enum-typed fields"). A field
    /// whose values are entries of an enum has the entry predicate in its refinement (its
    /// type), so a user refinement only narrows it. This asks, for each field of `asked`,
    /// that the narrowing leaves some entry: Σ after the message (Σ `before` it, the guard
    /// and every field's refinement as `assumed`, this one's exactly) is satisfiable, and if it is not while Σ after
    /// the message *without this field's entry predicate* is, the enum is to blame
    /// (`Goal::Reachable` with that context as the one before the step). Both contexts are
    /// cut to the field's cone of influence: the facts that share no variable with it,
    /// directly or through others, cannot make the difference (and E0243 only rejects: no
    /// proof rests on it).
    fn enum_entries(&mut self, m: &Msg, assumed: &Msg, asked: &[usize], before: &Sigma) {
        for &i in asked {
            let f = &m.payload[i];
            let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
            // The other fields as Σ will assume them; this one exactly, and without its
            // predicate.
            let mut with = assumed.clone();
            with.payload[i].refinement = f.refinement.clone();
            let mut after = before.clone();
            after.assume_message(&with);
            with.payload[i].refinement = crate::lower::refinement_without_entry(self.prog.dialect, f);
            let mut s = before.clone();
            s.assume_message(&with);
            let x =
                Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
            let (_, what) = crate::lower::entry_predicate(self.prog.dialect, check, &x);
            let written = f.mav.as_ref().map_or(f.name.as_str(), |mav| mav.written.as_str());
            self.obligations.push(Obligation {
                rule: Rule::EnumEntry,
                span: check.at.0,
                what: format!("`{written}` of {}: some value its refinement admits is {what}", m.label),
                hyps: crate::sigma::cone::cone(self.prog, after.facts(), &x),
                goal: Goal::Reachable {
                    before: vec![crate::sigma::cone::cone(self.prog, s.facts(), &x)],
                    dead_branch: false,
                },
            });
        }
    }

    /// Progress at a choice (E0419): under Σ and the guards' disjunction (whose validity
    /// is total choice's, E0316), some branch has a true guard and a payload its
    /// refinements admit. Asked only when some first message has a refinement: without
    /// one this is total choice itself.
    fn progress(&mut self, branches: &[Global], sigma: &Sigma) {
        let firsts: Vec<&Msg> = branches.iter().filter_map(super::side::first_message).collect();
        if branches.iter().any(|b| b.timeout_head().is_some()) {
            // The timeout branch is always enabled: time passes, and its waiting role takes
            // it when no other branch's message came. The choice cannot get stuck, and no
            // message branch needs to be enabled on its own.
            self.choice_firsts.extend(firsts.iter().map(|m| m.loc.0));
            return;
        }
        if firsts.len() != branches.len() {
            return; // a branch without a first message: E0303, reported by `side`
        }
        self.choice_firsts.extend(firsts.iter().map(|m| m.loc.0));
        let each: Vec<Enabled> = firsts.iter().map(|m| enabled(self.prog, m)).collect();
        if each.iter().all(|e| e.fields.is_empty() && e.refinement.is_true()) {
            return;
        }
        let mut hyps = sigma.clone();
        if let Some(any) = firsts
            .iter()
            .map(|m| m.guard.clone())
            .collect::<Option<Vec<Expr>>>()
            .and_then(|gs| gs.into_iter().reduce(or))
        {
            hyps.assume(&any);
        }
        let m = firsts[0];
        self.obligations.push(Obligation {
            rule: Rule::Progress,
            span: m.loc.0,
            what: format!("the choice by `{}`: some branch can be taken", self.prog.role_name(m.from)),
            hyps: self.exact(hyps.facts()),
            goal: Goal::Progress { branches: each },
        });
    }

    /// `g1 * ... * gn`: each side from the facts over its own participants; one
    /// separation obligation listing what each side may run.
    fn par(&mut self, sides: &'a [Global], loc: Loc, sigma: Sigma) -> Option<Sigma> {
        let pts: Vec<Vec<RoleId>> = sides.iter().map(Global::participant_list).collect();
        // Pushed now so that obligations keep the order of the type; the sides are
        // filled in once they have been walked.
        let slot = (sides.len() > 1).then(|| {
            self.obligations.push(Obligation {
                rule: Rule::FullSeparation,
                span: loc.0,
                what: format!("footprints of the {} sides of `*`", sides.len()),
                hyps: sigma.facts().to_vec(),
                goal: Goal::Separated { sides: Vec::new() },
            });
            self.obligations.len() - 1
        });
        let starts = sigma.split(&pts);
        let mut out = Some(Sigma::new());
        let mut done = Vec::with_capacity(sides.len());
        self.in_par += 1;
        for ((side, roles), start) in sides.iter().zip(pts).zip(starts) {
            let from = self.runs.len();
            let end = self.walk(side, start);
            done.push(Side { roles, runs: self.runs[from..].to_vec() });

            out = match (out, end) {
                (Some(mut o), Some(e)) => {
                    o.meet(e);
                    Some(o)
                }
                _ => None,
            };
        }
        self.in_par -= 1;
        if self.in_par == 0 {
            self.runs.clear();
        }

        if let Some(i) = slot {
            if let Some(Obligation { goal: Goal::Separated { sides }, .. }) = self.obligations.get_mut(i) {
                *sides = done;
            }
        }
        out
    }

    /// `mu t(n: S {R} = e). G`: the refinement `R` must hold of `e` at entry (and of
    /// the arguments at each jump, see `walk`), so the body assumes it; the rest of the
    /// loop invariant is the fixpoint of the module documentation.
    fn rec(
        &mut self,
        var: &'a str,
        params: &'a [RecParam],
        measure: Option<&'a Expr>,
        body: &'a Global,
        sigma: Sigma,
    ) -> Option<Sigma> {
        let inits = crate::sigma::initial_values(params);
        for p in params {
            let Some(r) = &p.refinement else { continue };
            self.obligations.push(Obligation {
                rule: Rule::RecInit,
                span: p.init.loc.0,
                what: format!(
                    "the refinement `{}` of parameter `{}` of `{var}` holds of its initial value `{}`",
                    print::expr(self.prog, None, r),
                    p.name,
                    print::expr(self.prog, None, &p.init)
                ),
                hyps: sigma.facts().to_vec(),
                goal: Goal::Valid(defined_and(crate::sigma::subst_params(r, params, &inits))),
            });
        }
        let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
        let mut candidate = sigma;
        candidate.forget_values(&ids);
        let marks = (self.obligations.len(), self.runs.len(), self.jumps.len());
        let depth = self.loops.len();
        let mut walks = 0;
        loop {
            walks += 1;
            let mut start = candidate.clone();
            for r in params.iter().filter_map(|p| p.refinement.as_ref()) {
                start.assume(r);
            }
            self.loops.push((var, params, measure));
            let out = self.walk(body, start);
            self.loops.pop();
            let reached: Vec<&Sigma> =
                self.jumps[marks.2..].iter().filter(|(i, _)| *i == depth).map(|(_, s)| s).collect();
            // The next candidate: implied by the current one and by every jump's context.
            let next = if walks <= WEAKEN_WALKS {
                reached.iter().fold(candidate.clone(), |c, s| c.join(s, self.prog))
            } else {
                let mut c = candidate.clone();
                c.retain(|f| reached.iter().all(|s| s.contains(f)));
                c
            };
            if next == candidate {
                // Stable: every jump implies the candidate. This walk's obligations
                // stand. Jumps to this loop are used up; jumps to enclosing loops stay
                // for them.
                let mut k = 0;
                self.jumps.retain(|(i, _)| {
                    k += 1;
                    k <= marks.2 || *i != depth
                });
                return out;
            }
            candidate = if walks >= MAX_LOOP_WALKS || self.steps > STEP_BUDGET { Sigma::new() } else { next };
            self.obligations.truncate(marks.0);
            self.runs.truncate(marks.1);
            self.jumps.truncate(marks.2);
        }
    }
}

/// A snapshot of observed values is taken (LANGUAGE.md, "Observed state"): each is a new
/// value (what was known of the same binding site, an earlier round's snapshot, is
/// forgotten) of which only its refinement is known: the field's wire range and float
/// model and the stream's invariant. Nothing relates it to any other step's snapshot.
fn observe(sigma: &mut Sigma, snap: &[Observed]) {
    if snap.is_empty() {
        return;
    }
    let ids: Vec<ValueId> = snap.iter().map(|o| o.value).collect();
    sigma.forget_values(&ids);
    for r in snap.iter().filter_map(|o| o.refinement.as_ref()) {
        sigma.assume(&defined_and(r.clone()));
    }
}

fn or(a: Expr, b: Expr) -> Expr {
    let loc = a.loc;
    Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(a), Box::new(b)), sort: Sort::Bool, loc }
}

/// Whether the user's refinement `u` of the enum-typed value `x` forces it to a value the
/// enum allows wherever `u` holds, syntactically: `x == c` for a constant `c` the enum
/// allows (`lower::entry_allows`), or `x == y` for a value `y` of the same enum and wire
/// type (itself an entry by its type), either way round; a conjunction when one conjunct does; a
/// disjunction when each disjunct does. Then Σ after the message is satisfiable exactly
/// when it is without `x`'s entry predicate, and E0243 needs no query.
fn pins_entry(
    prog: &Program,
    enum_of: &HashMap<ValueId, (String, crate::dialect::Wire)>,
    x: ValueId,
    check: &EnumCheck,
    u: &Expr,
) -> bool {
    match &u.kind {
        ExprKind::Binary(BinOp::And, a, b) => {
            pins_entry(prog, enum_of, x, check, a) || pins_entry(prog, enum_of, x, check, b)
        }
        ExprKind::Binary(BinOp::Or, a, b) => {
            pins_entry(prog, enum_of, x, check, a) && pins_entry(prog, enum_of, x, check, b)
        }
        ExprKind::Binary(BinOp::Eq, a, b) => [(a, b), (b, a)].into_iter().any(|(v, e)| {
            if !matches!(&v.kind, ExprKind::Var(Var::Value(id, _)) if *id == x) {
                return false;
            }
            match &e.kind {
                ExprKind::Var(Var::Value(y, _)) => enum_of.get(y) == Some(&(check.enum_name.clone(), check.wire)),
                _ => {
                    e.sort == Sort::Int
                        && crate::hir::expr::const_int(prog, e)
                            .is_some_and(|c| crate::lower::entry_allows(prog.dialect, check, c))
                }
            }
        }),
        _ => false,
    }
}

/// When `m` can be sent: its guard, and some payload satisfying the conjunction of its
/// fields' refinements. A field defined by an equality `f == e` (e of f's sort, reading no
/// field of `m`) is replaced by `e` in the other conjuncts (∃f. f == e ∧ P(f) is P(e)), so
/// that `seq == i` needs no quantifier; the fields still read are left to an existential.
///
/// Both are asked to be defined as well ([`definedness`]): a guard that cannot be evaluated
/// lets no branch be taken, and a payload whose refinement cannot be evaluated is not
/// admitted. The condition is added before a field is replaced by its definition, so that
/// `speed == sqrt(e)` leaves `e >= 0` behind (the encoding alone would let `sqrt` of a
/// negative be any value, and some `speed` would equal it).
fn enabled(prog: &Program, m: &Msg) -> Enabled {
    let written = and_all(m.payload.iter().filter_map(|f| f.refinement.clone()), m.loc);
    let mut conj: Vec<Expr> = Vec::new();
    crate::hir::expr::conjuncts(&definedness(&written), &mut conj);
    crate::hir::expr::conjuncts(&written, &mut conj);
    let ids: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
    let field = |e: &Expr| match &e.kind {
        ExprKind::Var(Var::Value(id, _)) if ids.contains(id) => Some(*id),
        _ => None,
    };
    let reads_field = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Value(id, _) if ids.contains(id)));
    loop {
        let def = conj.iter().enumerate().find_map(|(k, c)| {
            let ExprKind::Binary(BinOp::Eq, a, b) = &c.kind else { return None };
            [(a, b), (b, a)].into_iter().find_map(|(x, e)| {
                let id = field(x)?;
                (!reads_field(e)
                    && (x.sort == e.sort || x.sort == Sort::Real && e.sort == Sort::Int)
                    && crate::lower::float_definition_decided(prog, id, e))
                .then(|| (k, id, (**e).clone()))
            })
        });
        let Some((k, id, e)) = def else { break };
        conj.remove(k);
        let map = HashMap::from([(id, e)]);
        conj = conj.iter().map(|c| crate::hir::expr::subst_values(c, &map)).collect();
    }
    let rest = crate::hir::expr::and_all(conj, m.loc);
    let fields = m
        .payload
        .iter()
        .filter(|f| crate::hir::expr::mentions(&rest, &|v| matches!(v, Var::Value(id, _) if *id == f.value)))
        .map(|f| (f.value, f.name.clone(), f.sort.clone()))
        .collect();
    Enabled {
        what: format!("{} -> {}: {}", prog.role_name(m.from), prog.role_name(m.to), m.label),
        guard: m.guard.clone().map(defined_and),
        fields,
        refinement: rest,
    }
}

/// `t(a, b)`: a jump as written.
fn jump_text(prog: &Program, v: &RecVar) -> String {
    if v.args.is_empty() {
        return v.var.clone();
    }
    let a: Vec<String> = v.args.iter().map(|a| print::expr(prog, None, a)).collect();
    format!("{}({})", v.var, a.join(", "))
}

/// "s `a, b`": the arguments of a jump as written, for messages.
fn args_text(prog: &Program, args: &[Expr]) -> String {
    let v: Vec<String> = args.iter().map(|a| print::expr(prog, None, a)).collect();
    format!("s `{}`", v.join(", "))
}

fn collect_motions<'g>(g: &'g Global, out: &mut Vec<&'g Motion>) {
    match g {
        Global::Motion(m) => out.push(m),
        Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
            gs.iter().for_each(|g| collect_motions(g, out))
        }
        Global::Rec { body, .. } => collect_motions(body, out),
        Global::Msg(_) | Global::Var(_) | Global::End(_) | Global::After(_) => {}
    }
}

#[cfg(test)]
mod tests {
    use crate::diag::Code;
    use crate::lower::tests::lower_src;
    use crate::obligation::Rule;

    const SYS: &str = "
        robot R { state x: real; }
        robot W { input x: real; }
        motion R.go { interruptible: false; }
        motion R.wait { interruptible: true; }
        motion W.watch { interruptible: true; assume: x >= 0; }
        system S { participant P: R; participant Q: R; participant V: R; }
    ";

    fn run(chor: &str) -> (Vec<Code>, Vec<Rule>) {
        let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let c = p.choreography.as_ref().expect("choreography");
        let (o, d) = super::check(&p, &c.body);
        (d.into_iter().map(|d| d.code).collect(), o.into_iter().map(|o| o.rule).collect())
    }

    #[test]
    fn figure_2_shape_is_well_scoped() {
        let (d, o) = run("mu t. P -> Q : a. P -> V : c. ((dt<P: go, Q: wait>. P -> Q : b. (dt<P: go> * dt<Q: wait>)) * dt<V: wait>). t");
        assert_eq!(d, vec![]);
        // Every dt needs [AGCOMP] (a lone one only that it can end: 4 of them); two `*` need separation.
        assert_eq!(o.iter().filter(|r| **r == Rule::AgComp).count(), 4);
        assert_eq!(o.iter().filter(|r| **r == Rule::FullSeparation).count(), 2);
    }

    #[test]
    fn scoping_errors_have_their_codes() {
        assert_eq!(
            run("(dt<P: go> * dt<P: wait, Q: wait> * dt<V: wait>). dt<V: wait, P: wait, Q: wait>. end").0,
            vec![Code::SeparationOverlap]
        );
        // V is unused: reported once (E0313), not again at every motion it misses.
        assert_eq!(run("dt<P: go, Q: wait>. end").0, vec![Code::ParticipantUnused]);
        assert_eq!(
            run("(dt<P: go> * dt<Q: wait>). dt<P: wait, Q: wait, V: wait>. end").0,
            vec![Code::IncompleteMotion]
        );
        // Two non-interruptible primitives: joint end is the SMT stage's to decide (E0401).
        assert_eq!(run("dt<P: go, Q: go, V: wait>. end").0, vec![]);
        assert_eq!(
            run("mu t. (P -> Q : a. dt<P: go, Q: wait>. t) * dt<V: wait>")
                .0
                .last()
                .copied()
                .into_iter()
                .collect::<Vec<_>>(),
            vec![Code::OutOfScope],
            "(besides E0314) the unfolded `t` needs V inside the left side"
        );
    }

    #[test]
    fn an_input_fed_from_the_other_side_couples_them() {
        let src = "robot R { state x: real; } robot W { input x: real; }
            motion R.go { interruptible: false; } motion W.watch { interruptible: true; assume: x >= 0; }
            system S { participant P: R; participant O: W; }
            choreography G = dt<P: go> * dt<O: watch>. end;";
        let (p, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let (_, d) = super::check(&p, &p.choreography.as_ref().unwrap().body);
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), vec![Code::CoupledAcrossSeparation]);
    }

    #[test]
    fn guarded_choices_need_total_choice() {
        let (_, o) = run("P -> Q : [x > 0] a. dt<P: wait, Q: wait, V: wait>. end + P -> Q : [x <= 0] b. dt<P: wait, Q: wait, V: wait>. end");
        assert!(o.contains(&Rule::TotalChoice));
        let (_, o) = run(
            "P -> Q : [x > 0] a. dt<P: wait, Q: wait, V: wait>. end + P -> Q : b. dt<P: wait, Q: wait, V: wait>. end",
        );
        assert!(!o.contains(&Rule::TotalChoice), "an unguarded branch makes it trivial");
    }
}

#[cfg(test)]
mod scale_tests {
    use crate::lower::tests::lower_src;

    /// A joint motion of n participants in a scope of n, and n participants to check
    /// against pt{G}: the scope checks compare them through sets, not pairwise.
    #[test]
    #[ignore = "a timing ratio, for a quiet machine: `cargo test -- --ignored`; the pipeline benchmark measures the wide dt"]
    fn a_wide_dt_is_scoped_in_time_linear_in_its_parts() {
        let time = |n: usize| {
            let mut src = String::from("robot R { state x: real; } motion R.hold { interruptible: true; } system S {");
            for i in 0..n {
                src.push_str(&format!(" participant P{i}: R;"));
            }
            let parts: Vec<String> = (0..n).map(|i| format!("P{i}: hold")).collect();
            src.push_str(&format!(" }} choreography G = dt<{}>. end;", parts.join(", ")));
            let (p, d) = lower_src(&src);
            assert!(d.is_empty(), "{d:?}");
            let g = &p.choreography.as_ref().expect("choreography").body;
            let mut best = std::time::Duration::MAX;
            for _ in 0..3 {
                let t = std::time::Instant::now();
                let (o, d) = super::check(&p, g);
                best = best.min(t.elapsed());
                assert!(d.is_empty(), "{d:?}");
                assert_eq!(o.len(), 1, "one [AGCOMP] obligation");
            }
            best
        };
        // The pairwise comparisons were x40 and more at eight times the parts.
        crate::testing::assert_near_linear("parts", 1000, 8000, time);
    }
}

#[cfg(test)]
mod context_tests {
    //! The hypotheses of the obligations: Σ threaded through the type.
    use crate::hir::{print, Program};
    use crate::lower::tests::lower_src;
    use crate::obligation::{Goal, Obligation, Rule};

    /// Three robots on a line; `go` moves to a target, `hold` stays (`x == old(x)`).
    const SYS: &str = "
        robot R { state x: real; invariant: 0 <= x <= 10; }
        motion R.go(to: real) { interruptible: false; post: x == to; }
        motion R.hold { interruptible: true; post: x == old(x); }
        system S {
          participant P: R { init: x == 0; }
          participant Q: R { init: x == 5; }
          participant V: R { init: x == 9; }
        }
    ";

    fn obligations(chor: &str) -> (Program, Vec<Obligation>) {
        let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let body = p.choreography.as_ref().map(|c| c.body.clone()).expect("choreography");
        let (o, d) = super::check(&p, &body);
        assert!(d.is_empty(), "{d:?}");
        (p, o)
    }

    fn show(prog: &Program, hyps: &[crate::hir::Expr]) -> Vec<String> {
        hyps.iter().map(|h| print::expr(prog, None, h)).collect()
    }

    /// The hypotheses of each obligation of `rule`, printed and sorted.
    fn hyps(prog: &Program, obs: &[Obligation], rule: Rule) -> Vec<Vec<String>> {
        obs.iter().filter(|o| o.rule == rule).map(|o| sorted(show(prog, &o.hyps))).collect()
    }

    fn sorted<S: ToString>(v: impl IntoIterator<Item = S>) -> Vec<String> {
        let mut v: Vec<String> = v.into_iter().map(|s| s.to_string()).collect();
        v.sort();
        v
    }

    const INIT: [&str; 9] =
        ["P.x == 0", "0 <= P.x", "P.x <= 10", "Q.x == 5", "0 <= Q.x", "Q.x <= 10", "V.x == 9", "0 <= V.x", "V.x <= 10"];

    #[test]
    fn agcomp_hypotheses_follow_messages_and_motions() {
        let (p, o) = obligations(
            "P -> Q : a(n: real {n > x && n <= 10}). dt<P: go(n), Q: hold, V: hold>.
             Q -> P : b. dt<P: hold, Q: go(1), V: hold>. end",
        );
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h.len(), 2);
        // [T-SESS]'s initial state and the refinement of `a`.
        assert_eq!(h[0], sorted(INIT.iter().chain(&["P.x < n", "n <= 10"])));
        // After the motion P is at n (and `P.x < n` before it says `0 < n`); Q and V held.
        let after = ["P.x == n", "0 <= P.x", "P.x <= 10", "0 < n", "n <= 10"];
        assert_eq!(h[1], sorted(INIT[3..].iter().chain(&after)));
    }

    #[test]
    fn choices_assume_their_guards() {
        let (p, o) = obligations(
            "P -> Q : [x >= 1] l. dt<P: go(2), Q: hold, V: hold>. end
           + P -> Q : [x < 1] r. dt<P: go(3), Q: hold, V: hold>. end",
        );
        assert_eq!(hyps(&p, &o, Rule::TotalChoice), vec![sorted(INIT)]);
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h, vec![sorted(INIT.iter().chain(&["1 <= P.x"])), sorted(INIT.iter().chain(&["P.x < 1"]))]);
    }

    #[test]
    fn loops_get_a_syntactic_invariant_and_one_obligation_per_motion() {
        // P moves one further each round: `P.x == 0` is not invariant; Q and V hold.
        let (p, o) = obligations("mu t. P -> Q : a. dt<P: go(x + 1), Q: hold, V: hold>. Q -> P : b. t");
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h, vec![sorted(&INIT[1..])]);
        // A jump from an inner loop to the outer one weakens the outer invariant too.
        let (p, o) = obligations(
            "mu t. P -> Q : a. dt<P: hold, Q: hold, V: hold>.
               mu s. ( Q -> P : b. dt<P: hold, Q: hold, V: hold>. s
                     + Q -> P : c. dt<P: hold, Q: go(3), V: hold>. t )",
        );
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h.len(), 3, "one obligation per joint motion: {h:?}");
        // Q is at 5 or 3: the interval join keeps `3 <= Q.x <= 5` of `Q.x == 5`.
        let without_q = sorted(INIT.iter().filter(|f| **f != "Q.x == 5").chain(&["3 <= Q.x", "Q.x <= 5"]));
        assert_eq!(h[0], without_q);
        assert_eq!(h[1], without_q, "the inner loop's invariant");
        assert_eq!(h[2], without_q);
    }

    #[test]
    fn recursion_parameters_are_new_values_at_each_round() {
        let (p, o) = obligations(
            "mu t(k: int = 0). P -> Q : a(n: int {n == k && k >= 0}). dt<P: go(n), Q: hold, V: hold>. Q -> P : b. t(k + 1)",
        );
        let h = hyps(&p, &o, Rule::AgComp);
        // `n == k` holds at the motion; nothing about `k` survives the jump back (the
        // parameter is unrefined: its `0 <= k` is not checked, so not assumed either).
        assert_eq!(h, vec![sorted(INIT[1..].iter().chain(&["n == k", "0 <= k"]))]);
    }

    #[test]
    fn separation_lists_the_runs_of_each_side_with_their_contexts() {
        let (p, o) = obligations(
            "mu t. P -> Q : a. ((dt<P: go(2), Q: hold>. Q -> P : b. (dt<P: hold> * dt<Q: hold>)) * dt<V: hold>). t",
        );
        let seps: Vec<&Obligation> = o.iter().filter(|o| o.rule == Rule::FullSeparation).collect();
        assert_eq!(seps.len(), 2);
        assert_eq!(o.iter().filter(|o| o.rule == Rule::AgComp).count(), 4);
        let runs = |ob: &Obligation| -> Vec<Vec<(String, Vec<String>)>> {
            let Goal::Separated { sides } = &ob.goal else { panic!("separation") };
            sides
                .iter()
                .map(|s| {
                    s.runs
                        .iter()
                        .map(|r| {
                            let who = format!("{}: {}", p.role_name(r.role), print::prim_app(&p, &r.app));
                            (who, sorted(show(&p, &r.hyps)))
                        })
                        .collect()
                })
                .collect()
        };
        // P is at 2 after a round, so `P.x == 0` is not part of the loop's invariant;
        // the interval join of 0 and 2 keeps `P.x <= 2`.
        let pq = sorted(["0 <= P.x", "P.x <= 10", "P.x <= 2", "Q.x == 5", "0 <= Q.x", "Q.x <= 10"]);
        let outer = runs(seps[0]);
        // The P/Q side sees nothing of V, and its runs include the nested `*`'s.
        assert_eq!(
            outer[0],
            vec![
                ("P: go(2)".to_string(), pq.clone()),
                ("Q: hold".to_string(), pq),
                ("P: hold".to_string(), sorted(["P.x == 2", "0 <= P.x", "P.x <= 10"])),
                ("Q: hold".to_string(), sorted(["Q.x == 5", "0 <= Q.x", "Q.x <= 10"])),
            ]
        );
        assert_eq!(outer[1], vec![("V: hold".to_string(), sorted(&INIT[6..]))]);
        let inner = runs(seps[1]);
        assert_eq!(inner.len(), 2);
        assert_eq!(inner[0], vec![outer[0][2].clone()]);
        assert_eq!(inner[1], vec![outer[0][3].clone()]);
        // The obligation's own hypotheses: Σ at the `*`.
        assert_eq!(
            sorted(show(&p, &seps[0].hyps)),
            sorted(INIT.iter().filter(|f| **f != "P.x == 0").chain(&["P.x <= 2"]))
        );
    }

    /// Robots without an invariant, so that only the loop invariant bounds them.
    const FREE: &str = "
        robot F { state x: real; }
        motion F.go(to: real) { interruptible: false; post: x == to; }
        motion F.hold { interruptible: true; post: x == old(x); }
        system S { participant P: F { init: x >= 0; } participant Q: F { init: x == 0; } }
    ";

    fn free_obligations(chor: &str) -> (Program, Vec<Obligation>) {
        let (p, d) = lower_src(&format!("{FREE} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let body = p.choreography.as_ref().map(|c| c.body.clone()).expect("choreography");
        let (o, d) = super::check(&p, &body);
        assert!(d.is_empty(), "{d:?}");
        (p, o)
    }

    #[test]
    fn a_weaker_bound_every_jump_keeps_survives() {
        // `P.x >= 0` at entry; one branch leaves P at 1, the other at 2. Neither jump
        // holds `0 <= P.x` literally, but both imply it: the invariant keeps it (it
        // was dropped before the interval join, a false alarm for any motion needing it).
        let (p, o) = free_obligations(
            "mu t. P -> Q : a. dt<P: hold, Q: hold>.
               ( P -> Q : l. dt<P: go(1), Q: hold>. t
               + P -> Q : r. dt<P: go(2), Q: hold>. t )",
        );
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h.len(), 3);
        assert_eq!(h[0], sorted(["0 <= P.x", "Q.x == 0"]));
        // The choice's join weakens too: after it, P is between 1 and 2.
        let (p, o) = free_obligations(
            "mu t. P -> Q : a. dt<P: hold, Q: hold>.
               ( P -> Q : l. dt<P: go(1), Q: hold>. Q -> P : m. dt<P: hold, Q: hold>. t
               + P -> Q : r. dt<P: go(2), Q: hold>. Q -> P : m. dt<P: hold, Q: hold>. t )",
        );
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h[0], sorted(["0 <= P.x", "Q.x == 0"]));
    }

    #[test]
    fn bounds_that_keep_weakening_are_widened_away() {
        // Q steps down by one each round: -1, -2, ... The join would weaken the lower
        // bound forever; after WEAKEN_WALKS walks only literal facts are kept.
        let (p, o) = free_obligations("mu t. P -> Q : a. dt<P: hold, Q: go(x - 1)>. Q -> P : b. t");
        let h = hyps(&p, &o, Rule::AgComp);
        assert_eq!(h, vec![sorted(["0 <= P.x"])]);
        let (_, o) = free_obligations("mu t. P -> Q : a. dt<P: hold, Q: go(x - 1)>. Q -> P : b. t");
        let motions = o.iter().filter(|ob| ob.rule == Rule::AgComp).count();
        assert_eq!(motions, 1, "one obligation per motion, from the last walk only");
    }

    #[test]
    fn recursion_parameters_are_checked_at_entry_and_jumps_and_assumed() {
        let (p, o) = free_obligations(
            "mu t(n: int {n >= 0} = 2). ( P -> Q : [n > 0] more. dt<P: hold, Q: hold>. t(n - 1)
                                        + P -> Q : [n == 0] stop. dt<P: hold, Q: hold>. end )",
        );
        let goals = |rule: Rule| -> Vec<String> {
            o.iter()
                .filter(|ob| ob.rule == rule)
                .map(|ob| match &ob.goal {
                    Goal::Valid(e) => print::expr(&p, None, e),
                    _ => panic!("a predicate"),
                })
                .collect()
        };
        assert_eq!(goals(Rule::RecInit), vec!["2 >= 0"]);
        assert_eq!(goals(Rule::RecJump), vec!["n - 1 >= 0"]);
        // The body assumes the refinement: total choice and the jump see `0 <= n`.
        assert!(hyps(&p, &o, Rule::TotalChoice)[0].contains(&"0 <= n".to_string()));
        assert_eq!(hyps(&p, &o, Rule::RecJump), vec![sorted(["0 <= P.x", "Q.x == 0", "0 <= n", "0 < n"])]);
    }
}

/// Refined sessions: termination, progress and recursion parameters, decided
/// end to end (the global walk's obligations through the SMT stage), on global types with
/// no processes. The nested-loop cases are those nuscr got wrong (nuscr/nuscr#155: a
/// recursion variable missing from the progress check's environment; #158: several
/// variables under one label): shadowed parameter names, a jump to an outer loop from an
/// inner one, parameters read after an inner loop.
#[cfg(test)]
mod refined_tests {
    use crate::lower::tests::lower_src;
    use crate::obligation::Rule;
    use crate::smt::{discharge, Decision, SmtConfig};

    const SYS: &str = "robot R { state x: real; } system S { participant P: R; participant Q: R; }";

    /// The rules whose obligations fail, in order, and the first failure's counterexample
    /// as `name = value` pairs. Panics on an undecided obligation: each case is decidable.
    fn failing(chor: &str) -> (Vec<Rule>, Vec<String>) {
        let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let body = &p.choreography.as_ref().expect("choreography").body;
        let side = super::super::side::check(&p, body);
        assert!(side.is_empty(), "{side:?}");
        let (obs, d) = super::check(&p, body);
        assert!(d.is_empty(), "{d:?}");
        let labels: Vec<String> = obs.iter().map(|o| o.rule.slug().to_string()).collect();
        let results = discharge(&p, &obs, &labels, &SmtConfig::default());
        let mut rules = Vec::new();
        let mut values = Vec::new();
        for (ob, (dec, _)) in obs.iter().zip(results) {
            match dec {
                Decision::Holds(_) => {}
                Decision::Fails(f) => {
                    // A dead branch is a warning, not a failure of the protocol.
                    if matches!(ob.goal, crate::obligation::Goal::Reachable { dead_branch: true, .. }) {
                        continue;
                    }
                    if rules.is_empty() {
                        values = f.values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                    }
                    rules.push(ob.rule);
                }
                Decision::Unknown { why, .. } => panic!("undecided: {} ({why})", ob.what),
            }
        }
        (rules, values)
    }

    const UPLOAD: &str = "P -> Q: count(c: int {1 <= c && c <= 5}).
        mu t(i: int {0 <= i && i <= c} = 0) decreases c - i.
          ( Q -> P: [i < c] req(seq: int {seq == i}). P -> Q: item(s: int {s == i}). JUMP
          + Q -> P: [ACK] ack. end )";

    fn upload(jump: &str, ack: &str) -> String {
        UPLOAD.replace("JUMP", jump).replace("ACK", ack)
    }

    #[test]
    fn the_upload_terminates_and_a_counter_never_incremented_does_not() {
        assert_eq!(failing(&upload("t(i + 1)", "i == c")).0, vec![]);
        let (rules, values) = failing(&upload("t(i)", "i == c"));
        assert_eq!(rules, vec![Rule::MeasureDecrease]);
        assert!(values.iter().any(|v| v.starts_with("i = ")), "{values:?}");
        // A measure that may go negative: no refinement bounds i by c.
        let unbounded = "P -> Q: count(c: int {1 <= c && c <= 5}).
            mu t(i: int = 0) decreases c - i.
              ( Q -> P: req. t(i + 1) + Q -> P: ack. end )";
        assert_eq!(failing(unbounded).0, vec![Rule::MeasureBound]);
    }

    /// The acknowledgement's guard `i > c` is never true where the loop must end (i == c):
    /// the choice is not total there (stuck), with i == c in the counterexample.
    #[test]
    fn an_acknowledgement_that_is_never_taken_leaves_the_upload_stuck() {
        let (rules, values) = failing(&upload("t(i + 1)", "i > c"));
        assert_eq!(rules, vec![Rule::TotalChoice]);
        let get = |n: &str| values.iter().find_map(|v| v.strip_prefix(&format!("{n} = ")).map(str::to_string));
        assert_eq!(get("i"), get("c"), "stuck at i == c: {values:?}");
    }

    /// Progress with payloads: a refinement no value satisfies is stuck (a lone message),
    /// or leaves a choice with no branch to take once the guards alone are total.
    #[test]
    fn a_payload_no_value_satisfies_is_stuck() {
        assert_eq!(failing("P -> Q: m(x: int {x > 0 && x < 0}). end").0, vec![Rule::Progress]);
        // Against an earlier received value: for c == 2 no r has c < r < 3.
        let (rules, values) =
            failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r > c && r < 3}). end");
        assert_eq!(rules, vec![Rule::Progress]);
        assert!(values.iter().any(|v| v.starts_with("c = ") && v != "c = 1"), "{values:?}");
        // Satisfiable for every c: no failure (and no quantifier: r == c + 1 defines r).
        assert_eq!(failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r == c + 1}). end").0, vec![]);
        assert_eq!(failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r > c}). end").0, vec![]);
        // Guards total, but the branch for c >= 3 admits no payload.
        let choice = "P -> Q: cnt(c: int {1 <= c && c <= 5}).
            ( Q -> P: [c < 3] ok(r: int {r == c}). end + Q -> P: [c >= 3] big(r: int {r > c && r < 3}). end )";
        assert_eq!(failing(choice).0, vec![Rule::Progress]);
        let fine = choice.replace("r > c && r < 3", "r > c && r < 9");
        assert_eq!(failing(&fine).0, vec![]);
    }

    /// nuscr#155's protocol: the parameter `n` must be in the progress check's
    /// environment. At n == 0 no v has v == n && v > 0: stuck.
    #[test]
    fn nuscr_155_the_recursion_parameter_is_in_the_progress_check() {
        let g = "P -> Q: init(x: int {x >= 0}).
            mu t(n: int {n >= 0 && n <= x} = 0).
              ( Q -> P: [n < x] step(v: int {v == n && v > 0}). t(n + 1)
              + Q -> P: [n == x] stop. end )";
        let (rules, values) = failing(g);
        assert_eq!(rules, vec![Rule::Progress]);
        assert!(values.contains(&"n = 0".to_string()), "{values:?}");
        assert_eq!(failing(&g.replace("v > 0", "v >= 0")).0, vec![]);
    }

    /// nuscr#158: several parameters under one label, substituted simultaneously.
    #[test]
    fn several_parameters_are_substituted_together() {
        let g = "mu t(a: int {a >= 0} = 0, b: int {b >= a} = 0) decreases 10 - b.
              ( P -> Q: [b < 10] more. t(ARGS) + P -> Q: [b >= 10] stop. end )";
        assert_eq!(failing(&g.replace("ARGS", "a + 1, b + 1")).0, vec![]);
        assert_eq!(failing(&g.replace("ARGS", "a + 1, b")).0, vec![Rule::MeasureDecrease, Rule::RecJump]);
        // b's refinement reads the new a (a + 1 <= b + 1), not the old one.
        assert_eq!(failing(&g.replace("ARGS", "b + 1, b + 1")).0, vec![]);
    }

    const NESTED: &str = "P -> Q: cnt(c: int {2 <= c && c <= 4}).
        mu t(n: int {0 <= n && n <= c} = 0) decreases c - n.
          ( P -> Q: [n < c] outer.
            (mu s(INNER: int {0 <= INNER && INNER <= 3} = 0) decreases 3 - INNER.
              ( P -> Q: [INNER < 3] inner. s(INNER + 1)
              + P -> Q: [INNER == 3] done(v: int {READ}). t(OUTER) ))
          + P -> Q: [n == c] stop. end )";

    fn nested(inner: &str, read: &str, outer: &str) -> String {
        NESTED.replace("INNER", inner).replace("READ", read).replace("OUTER", outer)
    }

    /// A jump from the inner loop to the outer one with the outer's parameter: `n < c` of
    /// the outer iteration still holds inside the inner loop, so `t(n + 1)` keeps
    /// `n <= c` and the outer measure drops; `t(n)` does not make progress.
    #[test]
    fn a_jump_to_the_outer_loop_from_the_inner_one_uses_the_outer_parameters() {
        assert_eq!(failing(&nested("m", "v == n", "n + 1")).0, vec![]);
        assert_eq!(failing(&nested("m", "v == n", "n")).0, vec![Rule::MeasureDecrease]);
        // `n + 2` may pass c (n == c - 1): the outer refinement fails at the inner jump.
        assert_eq!(failing(&nested("m", "v == n", "n + 2")).0, vec![Rule::RecJump]);
    }

    /// The inner loop's parameter shadows the outer's name: inside it, `n` is the inner
    /// one (3 at `done`). `t(n - 3)` is then `t(0)`, which keeps `0 <= n <= c`; read as
    /// the outer `n` (names confused) it would be negative and break it. (The outer loop's
    /// `decreases c - n` is dropped here: restarting at 0 does not terminate.)
    #[test]
    fn a_shadowed_parameter_name_means_the_inner_parameter() {
        let g = nested("n", "v == n && v == 3", "n - 3").replace(" decreases c - n", "");
        assert_eq!(failing(&g).0, vec![]);
        // `t(n + 1)` with the inner n == 3 gives the outer 4 > c for c < 4.
        let g = nested("n", "v == n", "n + 1").replace(" decreases c - n", "");
        let (rules, values) = failing(&g);
        assert_eq!(rules, vec![Rule::RecJump]);
        assert!(values.iter().any(|v| v.starts_with("c = ") && v != "c = 4"), "{values:?}");
    }

    /// A parameter of the outer loop read after the inner loop's iterations (in its exit
    /// message): what held of it before the inner loop still holds.
    #[test]
    fn an_outer_parameter_read_after_the_inner_loop_keeps_its_facts() {
        assert_eq!(failing(&nested("m", "v == n && v < c", "n + 1")).0, vec![]);
        let (rules, _) = failing(&nested("m", "v == n && v >= c", "n + 1"));
        assert_eq!(rules, vec![Rule::Progress]);
    }
}

/// Observed state (LANGUAGE.md, "Observed state"): each message reads a fresh snapshot of
/// what its sender observes, one per choice, constrained only by the stream's refinements.
/// Each case that must fail here holds when the same value is sent once and read at every
/// step (a stable value): that is the unsoundness the snapshots remove.
#[cfg(test)]
mod observed_tests {
    use crate::lower::tests::lower_src;
    use crate::obligation::Rule;
    use crate::smt::{discharge, Decision, SmtConfig};

    /// The rules whose obligations fail (dead branches aside), or the lowering errors.
    fn failing(src: &str) -> Vec<Rule> {
        let (p, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let body = &p.choreography.as_ref().expect("choreography").body;
        let side = super::super::side::check(&p, body);
        assert!(side.is_empty(), "{side:?}");
        let (obs, d) = super::check(&p, body);
        assert!(d.is_empty(), "{d:?}");
        let labels: Vec<String> = obs.iter().map(|o| o.rule.slug().to_string()).collect();
        let mut rules = Vec::new();
        for (ob, (dec, _)) in obs.iter().zip(discharge(&p, &obs, &labels, &SmtConfig::default())) {
            match dec {
                Decision::Holds(_) => {}
                Decision::Fails(_)
                    if matches!(ob.goal, crate::obligation::Goal::Reachable { dead_branch: true, .. }) => {}
                Decision::Fails(_) => rules.push(ob.rule),
                Decision::Unknown { why, .. } => panic!("undecided: {} ({why})", ob.what),
            }
        }
        rules
    }

    /// `Q` streams `h` in [0, 100] to `P`.
    fn observed(chor: &str) -> String {
        format!(
            "system S {{ participant P; participant Q; stream Q -> P: tick(h: int {{0 <= h && h <= 100}}); }}
             choreography G = {chor};"
        )
    }

    /// `Q` sends `h` once, at the start: every later step reads that one value.
    fn stable(chor: &str) -> String {
        format!(
            "system S {{ participant P; participant Q; }}
             choreography G = Q -> P: tick(h: int {{0 <= h && h <= 100}}). {chor};"
        )
    }

    const LATER_CHOICE: &str = "( P -> Q: [h > 50] a.
          ( P -> Q: [h > 10] b. end + P -> Q: [h < 0] c. end )
        + P -> Q: [h <= 50] d. end )";

    #[test]
    fn a_later_choice_reads_a_fresh_value() {
        assert_eq!(failing(&stable(LATER_CHOICE)), vec![]);
        assert_eq!(failing(&observed(LATER_CHOICE)), vec![Rule::TotalChoice]);
    }

    #[test]
    fn the_branches_of_one_choice_read_one_snapshot() {
        // Per-message readings would leave a gap between the two guards.
        assert_eq!(failing(&observed("( P -> Q: [h > 10] a. end + P -> Q: [h <= 10] b. end )")), vec![]);
    }

    #[test]
    fn a_reading_satisfies_the_streams_refinement() {
        // Total only because every value of the stream is in [0, 100].
        assert_eq!(failing(&observed("( P -> Q: [h >= 0] a. end + P -> Q: [h > 100] b. end )")), vec![]);
        assert_eq!(
            failing(&observed("( P -> Q: [h >= 1] a. end + P -> Q: [h > 100] b. end )")),
            vec![Rule::TotalChoice]
        );
    }

    #[test]
    fn a_guard_and_refinement_of_one_message_read_one_snapshot() {
        // The payload fits the guard's reading: `x == h` with `h > 10` gives `x > 10`.
        let g = "( P -> Q: [h > 10] a(x: int {x == h && x > 10}). end + P -> Q: [h <= 10] b. end )";
        assert_eq!(failing(&observed(g)), vec![]);
    }

    #[test]
    fn progress_at_a_later_step_reads_a_fresh_value() {
        // Q answers below P's reading at `a`: sent in `a`, a value Q holds, so it exists.
        // Q answers below its own reading when it answers (Q streams `h`, so it reads its
        // own current value): a fresh value, which may be 41 or less: stuck.
        let sent = "( P -> Q: [h > 50] a(x: int {x == h}). Q -> P: b(y: int {y > 40 && y < x}). end
                    + P -> Q: [h <= 50] c. end )";
        assert_eq!(failing(&observed(sent)), vec![]);
        let reread = "( P -> Q: [h > 50] a. Q -> P: b(y: int {y > 40 && y < h}). end
                      + P -> Q: [h <= 50] c. end )";
        assert_eq!(failing(&stable(reread)), vec![]);
        assert_eq!(failing(&observed(reread)), vec![Rule::Progress]);
    }

    #[test]
    fn a_loop_reads_a_fresh_value_each_round() {
        let g = "mu t. ( P -> Q: [h > 50] a. ( P -> Q: [h > 10] b. t + P -> Q: [h <= 10] c. end )
                       + P -> Q: [h <= 50] d. end )";
        assert_eq!(failing(&observed(g)), vec![]);
        let g = "mu t. ( P -> Q: [h > 50] a. ( P -> Q: [h > 10] b. t + P -> Q: [h < 0] c. end )
                       + P -> Q: [h <= 50] d. end )";
        assert_eq!(failing(&stable(g)), vec![]);
        assert_eq!(failing(&observed(g)), vec![Rule::TotalChoice]);
    }

    /// A timeout branch counts as unguarded for total choice and makes the choice always
    /// able to progress; Σ is unchanged by it.
    #[test]
    fn a_timeout_branch_is_always_enabled() {
        let partial = "( P -> Q: [h > 50] a. end + P -> Q: [h < 10] b. end )";
        assert_eq!(failing(&stable(partial)), vec![Rule::TotalChoice]);
        let waited = "( P -> Q: [h > 50] a. end + P -> Q: [h < 10] b. end + after 100 ms by Q. end )";
        assert_eq!(failing(&stable(waited)), vec![]);
        let stuck = "P -> Q: a(y: int {y > h && y < h}). end";
        assert_eq!(failing(&stable(stuck)), vec![Rule::Progress]);
        let left = "( P -> Q: a(y: int {y > h && y < h}). end + after 100 ms by Q. end )";
        assert_eq!(failing(&stable(left)), vec![]);
        // What follows the timeout knows what held before the choice (`h <= 100`), no more.
        let after = "( P -> Q: a. end + after 100 ms by Q. Q -> P: b(y: int {y == h && y <= 100}). end )";
        assert_eq!(failing(&stable(after)), vec![]);
        let more = "( P -> Q: a. end + after 100 ms by Q. Q -> P: b(y: int {y == h && y > 100}). end )";
        assert_eq!(failing(&stable(more)), vec![Rule::Progress]);
    }

    /// A loop re-entered through a timeout branch decreases its measure there too.
    #[test]
    fn a_jump_through_a_timeout_decreases_the_measure() {
        let g = |jump: &str| {
            format!(
                "mu t(n: int {{0 <= n}} = 3) decreases n.
                   ( P -> Q: [n > 0] ask. ( Q -> P: ok. end + after 10 ms by P. {jump} )
                   + P -> Q: [n == 0] stop. end )"
            )
        };
        assert_eq!(failing(&stable(&g("t(n - 1)"))), vec![]);
        assert_eq!(failing(&stable(&g("t(n)"))), vec![Rule::MeasureDecrease]);
    }
}
