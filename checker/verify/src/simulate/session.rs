//! Protocols without motion (MAVLink sessions among them) run as each participant's
//! projection ([`crate::project`], Def 4.7), every participant with only what it knows:
//! its own state, the payloads it sent or received, and the recursion parameters it bound
//! itself (their initial values and jump arguments evaluated by it).
//!
//! A step is a message: a participant at a send picks at random a branch whose guard is
//! true (evaluated with its knowledge), the receiver must be waiting for that label from
//! it, and the payload is a Z3 model of the refinements with everything the sender knows
//! pinned (replayed exactly). Findings:
//! - a guard, refinement, initial value or jump argument that reads a value the
//!   participant does not have: a **violation** (a knowledge leak, E0305's question);
//! - no admissible payload, every guard false, or no participant able to send while some
//!   have not ended: **stuck**;
//! - a recursion parameter whose value breaks its refinement: a **violation**.
//!
//! A participant with a `process` runs it in lockstep with its projection, as process
//! typing (Table 1) relates them: the process decides which label is sent and with which
//! values (its arguments evaluated exactly with what it knows), `if` conditions are
//! evaluated exactly, and a receive binds the process's variables to the payload. The
//! projection says what must hold of it: a send whose guard is false or whose values
//! break the type's refinement ([T-OUT]), a label the type does not offer or a receive the
//! process lacks (E0702-E0704), and a process that goes on after its type ended (or
//! stops before) are **violations**. So a process typed `verified` that sends what its
//! protocol forbids is found here, independently of the typing rules.

use super::process::{Actor, UNFOLD_LIMIT};
use super::report::Kind;
use super::run::Runner;
use super::var_expr;
use crate::exact::{self, Tri, Value};
use crate::hir::expr::map_vars;
use crate::hir::local::{Local, LocalArc, RecvBranch, SendBranch};
use crate::hir::{Expr, Global, Loc, Process, RecParam, ValueId, Var};
use std::collections::HashMap;

/// Whether the global type has no motion and no `*`: it runs as projections.
pub(super) fn applies(g: &Global) -> bool {
    fn motion_free(g: &Global) -> bool {
        match g {
            Global::Motion(_) | Global::Par(..) => false,
            Global::Seq(items, _) | Global::Choice(items, _) => items.iter().all(motion_free),
            Global::Rec { body, .. } => motion_free(body),
            Global::Msg(_) | Global::Var(_) | Global::End(_) | Global::After(_) => true,
        }
    }
    motion_free(g)
}

/// One participant running its local type (and its process, if it has one).
struct Role<'p> {
    me: Actor<'p>,
    at: LocalArc,
    /// Its loops by name: parameters and body.
    loops: HashMap<String, (Vec<RecParam>, LocalArc)>,
}

impl<'p> std::ops::Deref for Role<'p> {
    type Target = Actor<'p>;
    fn deref(&self) -> &Actor<'p> {
        &self.me
    }
}

impl std::ops::DerefMut for Role<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.me
    }
}

impl Runner<'_, '_> {
    /// Unfolds `mu` and jumps until `role` is at a send, a receive or the end. False when
    /// the run must stop.
    fn settle(&mut self, role: &mut Role) -> bool {
        for _ in 0..UNFOLD_LIMIT {
            let at = role.at.clone();
            match &*at {
                Local::Rec { var, params, body, .. } => {
                    let inits: Vec<&Expr> = params.iter().map(|p| &p.init).collect();
                    let Some(args) = self.values_as(role, &inits, &format!("the initial values of `{var}`")) else {
                        return false;
                    };
                    role.loops.insert(var.clone(), (params.clone(), body.clone()));
                    if !self.bind(role, params, args) {
                        return false;
                    }
                    role.at = body.clone();
                }
                Local::Var { var, args, .. } => {
                    let Some((params, body)) = role.loops.get(var).cloned() else {
                        let now = self.now();
                        self.report(Kind::Undecided, &now, format!("`{var}` is not a loop of this participant"));
                        return false;
                    };
                    let exprs: Vec<&Expr> = args.iter().collect();
                    let Some(vals) = self.values_as(role, &exprs, &format!("the arguments of `{var}`")) else {
                        return false;
                    };
                    if !self.bind(role, &params, vals) {
                        return false;
                    }
                    role.at = body;
                }
                Local::Motion { .. } => {
                    let now = self.now();
                    self.report(Kind::Undecided, &now, "a motion in a protocol run as projections".into());
                    return false;
                }
                Local::Send { .. } | Local::Recv { .. } | Local::End(_) => return true,
            }
        }
        let now = self.now();
        let msg = format!("`{}` loops without a message", self.prog.role_name(role.id));
        self.report(Kind::Stuck, &now, msg);
        false
    }

    /// The branches of a send of `role` whose guards hold (evaluated with its knowledge).
    /// `None` when the run must stop.
    fn enabled(&mut self, role: &Role, branches: &[SendBranch]) -> Option<Vec<usize>> {
        let mut out = Vec::new();
        for (k, b) in branches.iter().enumerate() {
            let Some(g) = &b.guard else {
                out.push(k);
                continue;
            };
            if self.leak(role, g, &[], &format!("the guard of `{}`", b.label)) {
                return None;
            }
            match self.holds_as(role, g) {
                Tri::True => out.push(k),
                Tri::False => {}
                Tri::Unknown => {
                    let now = self.now();
                    let msg = format!(
                        "`{}`: the guard of `{}` cannot be evaluated exactly",
                        self.prog.role_name(role.id),
                        b.label
                    );
                    self.report(Kind::Undecided, &now, msg);
                    return None;
                }
            }
        }
        Some(out)
    }

    /// Fresh readings of the streams `role` reads at its send (LANGUAGE.md, "Observed
    /// state"): a value for every snapshot its branches' guards and refinements read, drawn
    /// within the snapshot's refinement (the field's wire range, the stream's invariant)
    /// and nothing else, new at every step. Drawn adversarially: first one where every
    /// guard is false; then one where a random branch's guard holds (two times in three),
    /// or one where a random comparison of a payload refinement that reads only the
    /// readings (and what `role` knows) is false, or true; then any reading (Z3's models
    /// sit on boundaries). A strategy no reading satisfies falls back to the next. False
    /// when the run must stop.
    fn observe(&mut self, role: &mut Role) -> bool {
        let at = role.at.clone();
        let Local::Send { branches, .. } = &*at else { return true };
        let mut snaps: Vec<&crate::hir::Observed> = Vec::new();
        for o in branches.iter().flat_map(|b| &b.observed) {
            if !snaps.iter().any(|s| s.value == o.value) {
                snaps.push(o);
            }
        }
        if snaps.is_empty() {
            return true;
        }
        let ids: Vec<ValueId> = snaps.iter().map(|o| o.value).collect();
        for id in &ids {
            role.known.remove(id);
        }
        let pin = |e: &Expr| {
            map_vars(e, &mut |v, sort| match v {
                Var::Value(id, _) if ids.contains(id) => None,
                Var::Role(..) | Var::Value(..) => {
                    self.lookup_as(role, v).and_then(|val| super::value_expr(&val, sort, Loc::default()))
                }
                _ => None,
            })
        };
        let base: Vec<Expr> =
            snaps.iter().filter_map(|o| o.refinement.as_ref()).map(|r| crate::hir::expr::defined_and(pin(r))).collect();
        let guards: Vec<Expr> = branches.iter().filter_map(|b| b.guard.as_ref()).map(&pin).collect();
        let mut atoms = Vec::new();
        for b in branches {
            let fields: Vec<ValueId> = b.payload.iter().map(|f| f.value).collect();
            for r in b.payload.iter().filter_map(|f| f.refinement.as_ref()) {
                comparisons(r, &mut |c| {
                    let (mut reads, mut payload) = (false, false);
                    c.visit_vars(&mut |v, _| {
                        if let Var::Value(id, _) = v {
                            reads |= ids.contains(id);
                            payload |= fields.contains(id);
                        }
                    });
                    if reads && !payload {
                        atoms.push(pin(c));
                    }
                });
            }
        }
        // First a reading where every guard is false (a stuck choice: the checks prove
        // there is none), then one of the others; a strategy no reading satisfies falls
        // back to the next, the last being any reading.
        let all_false: Vec<Expr> = guards.iter().cloned().map(crate::hir::expr::not).collect();
        let other = match self.rng.below(3) {
            0 if !atoms.is_empty() => {
                let a = atoms[self.rng.below(atoms.len())].clone();
                vec![if self.rng.below(2) == 0 { crate::hir::expr::not(a) } else { a }]
            }
            _ if !guards.is_empty() => vec![guards[self.rng.below(guards.len())].clone()],
            _ => Vec::new(),
        };
        let mut tries: Vec<Vec<Expr>> = Vec::new();
        if !all_false.is_empty() {
            tries.push(all_false);
        }
        tries.push(other);
        tries.push(Vec::new());
        let want: Vec<Expr> =
            snaps.iter().map(|o| var_expr(Var::Value(o.value, o.name.clone()), o.sort.clone())).collect();
        let now = self.now();
        let who = self.prog.role_name(role.id).to_string();
        for extra in tries {
            let facts: Vec<Expr> = base.iter().chain(&extra).cloned().collect();
            match self.sess.values(self.prog, &facts, &want) {
                Ok(Some(vs)) => {
                    for (id, v) in ids.iter().zip(vs) {
                        let (v, rounded) = super::on_wire(self.prog, *id, v);
                        if rounded {
                            let msg = format!("`{who}`'s reading: Z3's value rounded to the wire's float (the simulator draws real readings)");
                            self.report(Kind::Undecided, &now, msg);
                            return false;
                        }
                        role.known.insert(*id, v);
                    }
                    return true;
                }
                Ok(None) if !extra.is_empty() => continue,
                Ok(None) => {
                    let msg = format!("`{who}`: no reading of its streams satisfies their declarations");
                    self.report(Kind::Stuck, &now, msg);
                    return false;
                }
                Err(why) => {
                    self.undecided(&now, &format!("`{who}`'s reading of its streams"), why);
                    return false;
                }
            }
        }
        true
    }

    /// The payload of `b` sent by `from`: a model of its refinements with everything the
    /// sender knows pinned. `None` when the run must stop.
    fn payload(&mut self, from: &Role, b: &SendBranch, who: &str) -> Option<Vec<Value>> {
        let prog = self.prog;
        let fields: Vec<ValueId> = b.payload.iter().map(|f| f.value).collect();
        let mut facts = Vec::new();
        for f in &b.payload {
            let Some(r) = &f.refinement else { continue };
            if self.leak(from, r, &fields, &format!("the refinement of `{}` in `{who}`", f.name)) {
                return None;
            }
            // A value on the wire satisfies the refinement only where it can be evaluated:
            // `s == 100 / n` has no solution at `n = 0` (Z3 alone would give the quotient
            // some value, and the run would go on past a stuck state).
            facts.push(crate::hir::expr::defined_and(map_vars(r, &mut |v, sort| match v {
                Var::Value(id, _) if fields.contains(id) => None,
                Var::Role(..) | Var::Value(..) => {
                    self.lookup_as(from, v).and_then(|val| super::value_expr(&val, sort, Loc::default()))
                }
                _ => None,
            })));
        }
        let want: Vec<Expr> =
            b.payload.iter().map(|f| var_expr(Var::Value(f.value, f.name.clone()), f.sort.clone())).collect();
        let nudge = self.nudge(want.len());
        let now = self.now();
        match self.sess.values_nudged(prog, &facts, &want, nudge) {
            Ok(Some(vs)) => Some(vs),
            Ok(None) => {
                self.report(Kind::Stuck, &now, format!("`{who}`: no payload satisfies its refinements"));
                None
            }
            Err(why) => {
                self.undecided(&now, &format!("`{who}`'s payload"), why);
                None
            }
        }
    }

    /// Runs every participant's projection of the choreography.
    pub(super) fn sessions(&mut self) {
        if !self.init() {
            return;
        }
        let prog = self.prog;
        let (locals, diags) = crate::project::project_all(prog);
        if let Some(d) = diags.iter().find(|d| d.is_error()) {
            let msg = format!("the projections cannot be computed: {}", d.message);
            self.report(Kind::Undecided, &Default::default(), msg);
            return;
        }
        let mut roles: Vec<Role> = locals
            .iter()
            .map(|(r, t)| Role { me: Actor::new(prog, *r), at: t.clone(), loops: HashMap::new() })
            .collect();
        loop {
            for role in &mut roles {
                if !self.settle(role) || !self.settle_process(role) {
                    return;
                }
            }
            if roles.iter().all(|r| matches!(&*r.at, Local::End(_))) {
                for role in &roles {
                    if role.proc.as_ref().is_some_and(|p| !matches!(p.at, Process::End(_))) {
                        self.off_type(role, "goes on after its local type has ended".into());
                        return;
                    }
                }
                return;
            }
            if self.steps >= self.cfg.steps {
                return;
            }
            for role in &mut roles {
                if !self.observe(role) {
                    return;
                }
            }
            // Every send whose guard holds and whose receiver waits for it.
            let mut ready: Vec<(usize, usize, usize)> = Vec::new();
            let mut blocked = Vec::new();
            for (s, role) in roles.iter().enumerate() {
                let Local::Send { branches, .. } = &*role.at else { continue };
                let Some(mut enabled) = self.enabled(role, branches) else { return };
                if role.proc.is_some() {
                    // The process decides: each send it may take must be one the type
                    // offers here, with its guard true ([T-OUT], internal choice).
                    let offers = Self::offers(role);
                    if offers.is_empty() {
                        let at = crate::hir::print::describe(prog, &role.at);
                        self.off_type(role, format!("does not send where its local type is at {at}"));
                        return;
                    }
                    for (to, label, _, _) in &offers {
                        let Some(k) = branches.iter().position(|b| b.to == *to && b.label == *label) else {
                            let msg = format!(
                                "sends `{}!{label}`, which its local type does not offer here",
                                prog.role_name(*to)
                            );
                            self.off_type(role, msg);
                            return;
                        };
                        if !enabled.contains(&k) {
                            let msg = format!("may send `{}!{label}` although its guard is false", prog.role_name(*to));
                            self.off_type(role, msg);
                            return;
                        }
                    }
                    enabled.retain(|k| {
                        offers.iter().any(|(to, label, _, _)| branches[*k].to == *to && branches[*k].label == *label)
                    });
                }
                if enabled.is_empty() {
                    let now = self.now();
                    let msg = format!("`{}`: every guard of its choice is false", prog.role_name(role.id));
                    self.report(Kind::Stuck, &now, msg);
                    return;
                }
                for k in enabled {
                    let b = &branches[k];
                    let waits = roles.iter().position(|q| {
                        q.id == b.to
                            && matches!(&*q.at, Local::Recv { branches, .. }
                                if branches.iter().any(|rb| rb.from == role.id && rb.label == b.label))
                    });
                    match waits {
                        Some(q) => ready.push((s, k, q)),
                        None => blocked.push(format!(
                            "`{}` -> `{}`: {}",
                            prog.role_name(role.id),
                            prog.role_name(b.to),
                            b.label
                        )),
                    }
                }
            }
            if ready.is_empty() {
                let now = self.now();
                let waiting: Vec<String> = roles
                    .iter()
                    .filter(|r| !matches!(&*r.at, Local::End(_)))
                    .map(|r| format!("`{}` at {}", prog.role_name(r.id), crate::hir::print::describe(prog, &r.at)))
                    .collect();
                let msg = format!(
                    "no participant can send: {}; sends not awaited: {}",
                    waiting.join("; "),
                    if blocked.is_empty() { "none".to_string() } else { blocked.join(", ") }
                );
                self.report(Kind::Stuck, &now, msg);
                return;
            }
            let (s, k, q) = ready[self.rng.below(ready.len())];
            let Local::Send { branches, .. } = &*roles[s].at.clone() else { return };
            let b = &branches[k];
            let who = format!("{} -> {} : {}", prog.role_name(roles[s].id), prog.role_name(b.to), b.label);
            self.steps += 1;
            let sent = Self::offers(&roles[s]).into_iter().find(|(to, label, _, _)| *to == b.to && *label == b.label);
            let vals = match sent {
                Some((_, _, args, _)) if args.len() != b.payload.len() => {
                    let msg =
                        format!("sends {} value(s) in `{who}`, whose type carries {}", args.len(), b.payload.len());
                    self.off_type(&roles[s], msg);
                    return;
                }
                // The process's values, as it evaluates its arguments.
                Some((_, _, args, _)) => {
                    let exprs: Vec<&Expr> = args.iter().collect();
                    let what = format!("the values its process sends in `{who}`");
                    match self.values_as(&roles[s], &exprs, &what) {
                        Some(vs) => vs,
                        None => return,
                    }
                }
                None => match self.payload(&roles[s], b, &who) {
                    Some(vs) => vs,
                    None => return,
                },
            };
            let mut shown = Vec::new();
            let mut rounded = false;
            let vals: Vec<Value> = b
                .payload
                .iter()
                .zip(vals)
                .map(|(f, v)| {
                    let (v, moved) = super::on_wire(prog, f.value, v);
                    rounded |= moved;
                    v
                })
                .collect();
            for (f, v) in b.payload.iter().zip(&vals) {
                shown.push(format!("{} = {v}", f.name));
                roles[s].known.insert(f.value, v.clone());
            }
            // Replayed exactly, with what the sender knows.
            for f in &b.payload {
                if let Some(r) = &f.refinement {
                    let holds = self.holds_as(&roles[s], r);
                    if holds == Tri::False && rounded && sent.is_none() {
                        let now = self.now();
                        let msg = format!("`{who}`'s payload: Z3's value rounded to the wire's float leaves the refinement of `{}` (the simulator draws real payloads)", f.name);
                        self.report(Kind::Undecided, &now, msg);
                        return;
                    }
                    if holds != Tri::True && sent.is_some() {
                        // A process's values: the type's refinement must hold of them, and
                        // be decided ([T-OUT]).
                        let shown = shown.join(", ");
                        if holds == Tri::False {
                            let msg = format!("sends `{who}({shown})`, which breaks the refinement of `{}`", f.name);
                            self.off_type(&roles[s], msg);
                        } else {
                            let now = self.now();
                            let msg =
                                format!("`{who}({shown})`: the refinement of `{}` cannot be evaluated exactly", f.name);
                            self.report(Kind::Undecided, &now, msg);
                        }
                        return;
                    }
                    if holds == Tri::False {
                        let now = self.now();
                        let msg =
                            format!("`{who}`: Z3's payload does not satisfy the refinement of `{}` exactly", f.name);
                        self.report(Kind::Replay, &now, msg);
                        return;
                    }
                }
            }
            self.messages.push(super::report::SimMessage {
                from: roles[s].id,
                to: b.to,
                label: b.label.clone(),
                fields: b
                    .payload
                    .iter()
                    .zip(&vals)
                    .map(|(f, v)| (f.value, f.mav.as_ref().map(|m| m.field.clone()), f.refinement.clone(), v.clone()))
                    .collect(),
                known: roles[s].known.iter().map(|(k, v)| (*k, v.clone())).collect(),
            });
            let Local::Recv { branches: rbs, .. } = &*roles[q].at.clone() else { return };
            let Some(rb) = rbs.iter().find(|rb| rb.from == roles[s].id && rb.label == b.label) else { return };
            receive(&mut roles[q], rb, &vals);
            if let Some((_, _, _, cont)) = sent {
                if let Some(p) = roles[s].proc.as_mut() {
                    p.at = cont;
                }
            }
            if let Some(p) = roles[q].proc.as_ref() {
                let arm = match p.at {
                    Process::Recv { from, branches, .. } if *from == roles[s].id => {
                        branches.iter().find(|a| a.label == b.label)
                    }
                    _ => None,
                };
                let Some(arm) = arm else {
                    let msg = format!("does not receive `{who}`, which its local type receives here");
                    self.off_type(&roles[q], msg);
                    return;
                };
                if arm.binders.len() != vals.len() {
                    let msg = format!("binds {} value(s) of `{who}`, which carries {}", arm.binders.len(), vals.len());
                    self.off_type(&roles[q], msg);
                    return;
                }
                for (id, v) in arm.binders.iter().zip(&vals) {
                    roles[q].known.insert(*id, v.clone());
                }
                if let Some(p) = roles[q].proc.as_mut() {
                    p.at = &arm.cont;
                }
            }
            roles[s].at = b.cont.clone();
            let now = self.now();
            self.trace.push(format!("t = {}: {who}({})", exact::decimal(&now), shown.join(", ")));
        }
    }
}

/// The comparisons `e` is built of through `&&`, `||`, `=>`, `!` and `if` conditions.
fn comparisons(e: &Expr, f: &mut dyn FnMut(&Expr)) {
    use crate::hir::expr::{BinOp, UnOp};
    use crate::hir::ExprKind;
    match &e.kind {
        ExprKind::Binary(BinOp::And | BinOp::Or | BinOp::Implies, a, b) => {
            comparisons(a, f);
            comparisons(b, f);
        }
        ExprKind::Unary(UnOp::Not, a) => comparisons(a, f),
        ExprKind::Binary(BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge, ..) => f(e),
        _ => {}
    }
}

/// The receiver takes the payload: its fields are its values now (the receiver's local
/// type names them by its own value ids).
fn receive(role: &mut Role, rb: &RecvBranch, vals: &[Value]) {
    for (f, v) in rb.payload.iter().zip(vals) {
        role.known.insert(f.value, v.clone());
    }
    role.at = rb.cont.clone();
}

#[cfg(test)]
mod tests {
    use super::super::process::unknown_read;
    use super::*;
    use crate::hir::{Program, RoleId};
    use crate::lower::tests::lower_src;

    const SYSTEM: &str = "system S { participant A; participant B; participant C; }\n";

    fn chor(src: &str) -> (Program, Global) {
        let (prog, diags) = lower_src(&format!("{SYSTEM}{src}"));
        assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
        let g = prog.choreography.as_ref().expect("a choreography").body.clone();
        (prog, g)
    }

    #[test]
    fn only_motion_free_protocols_run_as_projections() {
        let (prog, g) = chor("choreography P = A -> B: go(n: int {n == 1}). end;");
        assert!(applies(&g));
        let _ = prog;
        let par = Global::Par(vec![g.clone(), g.clone()], Loc::default());
        assert!(!applies(&Global::Seq(vec![g, par], Loc::default())));
    }

    #[test]
    fn a_value_another_participant_received_is_unknown() {
        let (prog, _) = chor("choreography P = A -> B: go(n: int {n == 1}). B -> C: back(m: int {m == n}). end;");
        let n = (0..prog.values.len()).map(|i| ValueId(i as u32)).find(|id| prog.value(*id).name == "n").expect("n");
        let role = |r: u32, known: &[ValueId]| Actor {
            id: RoleId(r),
            known: known.iter().map(|id| (*id, Value::Num(exact::Num::int(1)))).collect(),
            proc: None,
        };
        let read = var_expr(Var::Value(n, "n".into()), crate::hir::Sort::Int);
        // C never received `n`: a leak; B did.
        let r2 = role(2, &[]);
        let c = unknown_read(&prog, r2.id, &|id| r2.known.contains_key(&id), &read, &[]);
        assert!(c.is_some_and(|m| m.contains("sent by `A` to `B`")));
        let r1 = role(1, &[n]);
        assert!(unknown_read(&prog, r1.id, &|id| r1.known.contains_key(&id), &read, &[]).is_none());
        // A field being sent is the sender's own.
        assert!(unknown_read(&prog, r2.id, &|id| r2.known.contains_key(&id), &read, &[n]).is_none());
    }

    /// Processes run in lockstep with their projections: one that echoes a stale value
    /// is a violation, one that echoes the current value runs clean, and a loop whose
    /// `if` picks the branch exactly follows the type's guards.
    #[test]
    fn processes_run_against_their_projections() {
        let g = "choreography P = mu t. A -> B: batt(b: int). B -> C: now(n: int {n == b}).
                   C -> A: echo(e: int {e == n}). t;";
        let run = |procs: &str| {
            let (prog, _) = chor(&format!("{g} {procs}"));
            let cfg = crate::simulate::SimConfig { runs: 2, steps: 12, ..Default::default() };
            crate::simulate::simulate(&prog, &cfg)
        };
        let a = "process A = mu t(k: int = 0). B!batt(k). C?echo(e). t(k + 1);";
        let b = "process B = mu t. A?batt(b). C!now(b). t;";
        let good = run(&format!("{a} {b} process C = B?now(n). A!echo(n). mu t. B?now(m). A!echo(m). t;"));
        assert!(good.findings.is_empty(), "{:?}", good.findings);
        assert!(good.steps >= 20, "{}", good.steps);
        let stale = run(&format!("{a} {b} process C = B?now(n). A!echo(n). mu t. B?now(m). A!echo(n). t;"));
        assert!(
            stale
                .findings
                .iter()
                .any(|f| f.kind == Kind::Violation && f.message.contains("breaks the refinement of `e`")),
            "{:?}",
            stale.findings
        );
        let wrong_label = run(&format!("{a} {b} process C = B?now(n). A!other(n). end;"));
        assert!(
            wrong_label.findings.iter().any(|f| f.message.contains("does not offer")),
            "{:?}",
            wrong_label.findings
        );
    }
}
