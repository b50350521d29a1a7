//! Processes in choreographies with motion: each participant's process runs in lockstep
//! with the run of the global type ([`super::run`]).
//!
//! The run walks the global type; the events that involve a participant are, in order,
//! the events of its projection (Def 4.7) along the path the run takes. A participant
//! with a `process` must perform each of them, and it decides what it can ([`Actor`],
//! stepped by [`Runner::settle_process`] as in protocols without motion):
//! - at a **choice** it makes, the branch is one its process sends; every send its
//!   process may take there must be a branch of the type whose guard is true ([T-OUT],
//!   internal choice);
//! - at a **message** it sends, the payload is its process's arguments, evaluated exactly
//!   with what it knows, and the type's refinements must hold of them ([T-OUT]); a
//!   message it receives binds its process's variables;
//! - at a **motion**, its primitive and arguments are its process's ([T-MOTION]), or the
//!   default motion of a reception ([SUB-IN3]); the motion runs with them, so collisions,
//!   assumptions and pre/postconditions are those of what the robot does. That primitive
//!   must refine the type's (Def 3.4, as docs/checks.md reads it) on the run: same kind
//!   and interruptibility, its precondition holds where the type's does, and the witness
//!   trajectory, replayed exactly, satisfies the type's guarantee, the kind's invariant and
//!   the type's postcondition, and ends within the type's duration. (A footprint larger
//!   than the type's is not compared point by point: the run places the process's
//!   footprint, so it shows where it meets another participant or an obstacle.)
//! - at `end` of the type, every process must be at `end`; a process that does something
//!   else where its type has an event (or ends before it) is a **violation**.

use super::motion::frame_env;
use super::process::Actor;
use super::report::Kind;
use super::run::Runner;
use super::{first_message, value_expr};
use crate::exact::{self, Num, Tri, Value};
use crate::hir::expr::map_vars;
use crate::hir::{Expr, Global, Loc, Msg, PrimApp, Process, RoleId, Var};
use std::collections::HashMap;

/// What a process is about to do, in a finding.
fn doing(prog: &crate::hir::Program, p: &Process) -> String {
    match p {
        Process::Send { to, label, .. } => format!("sends `{}!{label}`", prog.role_name(*to)),
        Process::Choose { .. } => "chooses among sends".to_string(),
        Process::Recv { from, .. } => format!("receives from `{}`", prog.role_name(*from)),
        Process::Motion { prim, .. } => format!("moves with `{}`", crate::hir::print::prim_app(prog, prim)),
        Process::End(_) => "has ended".to_string(),
        Process::Rec { .. } | Process::Var { .. } | Process::If { .. } => "loops".to_string(),
    }
}

/// A motion part whose participant runs a process: the type's primitive (arguments
/// closed) and its argument values, for the refinement checked on the run.
pub(super) struct Typed {
    pub(super) app: PrimApp,
    pub(super) args: Vec<Value>,
}

impl<'p> Runner<'_, 'p> {
    /// An actor for every participant (with its process, if it has one).
    pub(super) fn start_processes(&mut self) {
        let prog = self.prog;
        self.actors = prog.role_ids().map(|r| Actor::new(prog, r)).collect();
    }

    /// Whether `r` runs a process.
    pub(super) fn has_process(&self, r: RoleId) -> bool {
        self.actors.get(r.idx()).is_some_and(|a| a.proc.is_some())
    }

    /// `r`'s actor, taken out to be stepped (put back with [`Self::put_actor`]), settled at
    /// its next action. `None` when it has no process, or when the run must stop.
    fn settled(&mut self, r: RoleId) -> Option<Actor<'p>> {
        if !self.has_process(r) {
            return None;
        }
        let blank = Actor { id: r, known: HashMap::new(), proc: None };
        let mut a = std::mem::replace(&mut self.actors[r.idx()], blank);
        let ok = self.settle_process(&mut a);
        if ok {
            Some(a)
        } else {
            self.put_actor(a);
            None
        }
    }

    fn put_actor(&mut self, a: Actor<'p>) {
        let i = a.id.idx();
        if let Some(slot) = self.actors.get_mut(i) {
            *slot = a;
        }
    }

    /// The process is not where its type is: a violation.
    fn astray(&mut self, a: Actor<'p>, expected: &str) {
        let at = a.proc.as_ref().map(|p| doing(self.prog, p.at)).unwrap_or_default();
        self.off_type(&a, format!("{at} where its type {expected}"));
        self.put_actor(a);
    }

    /// At a choice of the global type: the branches the chooser's process may take among
    /// `enabled` (indices into `branches`, whose guards hold). Every send the process may
    /// take here must start a branch whose guard holds. `None` when the run must stop.
    pub(super) fn process_picks(&mut self, branches: &[Global], enabled: Vec<usize>) -> Option<Vec<usize>> {
        let Some(chooser) = branches.iter().find_map(first_message).map(|m| m.from) else { return Some(enabled) };
        if !self.has_process(chooser) {
            return Some(enabled);
        }
        let a = self.settled(chooser)?;
        let offers = Self::offers(&a);
        let prog = self.prog;
        if offers.is_empty() {
            let labels: Vec<String> = branches
                .iter()
                .filter_map(first_message)
                .map(|m| format!("`{}!{}`", prog.role_name(m.to), m.label))
                .collect();
            self.astray(a, &format!("chooses among {}", labels.join(", ")));
            return None;
        }
        let mut picks = Vec::new();
        for (to, label, _, _) in &offers {
            let Some(k) = branches
                .iter()
                .position(|b| first_message(b).is_some_and(|m| m.from == chooser && m.to == *to && m.label == *label))
            else {
                let msg = format!("sends `{}!{label}`, which its type does not offer here", prog.role_name(*to));
                self.off_type(&a, msg);
                self.put_actor(a);
                return None;
            };
            if !enabled.contains(&k) {
                let msg = format!("may send `{}!{label}` although its guard is false", prog.role_name(*to));
                self.off_type(&a, msg);
                self.put_actor(a);
                return None;
            }
            picks.push(k);
        }
        self.put_actor(a);
        Some(picks)
    }

    /// The payload of `m` as the sender's process sends it: its arguments evaluated
    /// exactly with what it knows. `Ok(None)` when the sender runs no process (the payload
    /// is drawn); `Err` when the run must stop.
    pub(super) fn process_sends(&mut self, m: &Msg, who: &str) -> Result<Option<Vec<Value>>, ()> {
        if !self.has_process(m.from) {
            return Ok(None);
        }
        let Some(mut a) = self.settled(m.from) else { return Err(()) };
        let sent = Self::offers(&a).into_iter().find(|(to, label, _, _)| *to == m.to && *label == m.label);
        let Some((_, _, args, cont)) = sent else {
            self.astray(a, &format!("sends `{who}`"));
            return Err(());
        };
        if args.len() != m.payload.len() {
            let msg = format!("sends {} value(s) in `{who}`, whose type carries {}", args.len(), m.payload.len());
            self.off_type(&a, msg);
            self.put_actor(a);
            return Err(());
        }
        let exprs: Vec<&Expr> = args.iter().collect();
        let vals = self.values_as(&a, &exprs, &format!("the values its process sends in `{who}`"));
        if let Some(p) = a.proc.as_mut() {
            p.at = cont;
        }
        self.put_actor(a);
        vals.map(Some).ok_or(())
    }

    /// The receiver's process takes `m`'s payload `vals`. False when the run must stop.
    pub(super) fn process_receives(&mut self, m: &Msg, who: &str, vals: &[Value]) -> bool {
        if !self.has_process(m.to) {
            return true;
        }
        let Some(mut a) = self.settled(m.to) else { return false };
        let arm = match a.proc.as_ref().map(|p| p.at) {
            Some(Process::Recv { from, branches, .. }) if *from == m.from => {
                branches.iter().find(|arm| arm.label == m.label)
            }
            _ => None,
        };
        let Some(arm) = arm else {
            self.astray(a, &format!("receives `{who}`"));
            return false;
        };
        if arm.binders.len() != vals.len() {
            let msg = format!("binds {} value(s) of `{who}`, which carries {}", arm.binders.len(), vals.len());
            self.off_type(&a, msg);
            self.put_actor(a);
            return false;
        }
        for (id, v) in arm.binders.iter().zip(vals) {
            a.known.insert(*id, v.clone());
        }
        if let Some(p) = a.proc.as_mut() {
            p.at = &arm.cont;
        }
        self.put_actor(a);
        true
    }

    /// The primitive `r`'s process moves with where its type runs `ty` (in `who`): the
    /// process's primitive with its arguments (values and closed expressions), checked to
    /// be of `ty`'s kind and interruptibility. `Ok(None)` when `r` runs no process; `Err`
    /// when the run must stop. The process moves on past the motion.
    pub(super) fn process_moves(
        &mut self,
        r: RoleId,
        ty: &PrimApp,
        who: &str,
    ) -> Result<Option<(PrimApp, Vec<Value>)>, ()> {
        if !self.has_process(r) {
            return Ok(None);
        }
        let prog = self.prog;
        let Some(mut a) = self.settled(r) else { return Err(()) };
        let step = match a.proc.as_ref().map(|p| p.at) {
            Some(Process::Motion { prim, cont, .. }) => Some((prim, &**cont)),
            // [SUB-IN3]: a reception with a default motion, where the type only moves.
            Some(Process::Recv { default: Some((prim, cont)), .. }) => Some((prim, &**cont)),
            _ => None,
        };
        let Some((app, cont)) = step else {
            self.astray(a, &format!("moves with `{}` in {who}", crate::hir::print::prim_app(prog, ty)));
            return Err(());
        };
        let (p, t) = (prog.prim(app.prim), prog.prim(ty.prim));
        let mismatch = if p.kind != t.kind {
            Some("a primitive of another kind")
        } else if p.interruptible != t.interruptible {
            Some(if t.interruptible {
                "a non-interruptible primitive where its type's is interruptible"
            } else {
                "an interruptible primitive where its type's is not"
            })
        } else {
            None
        };
        if let Some(why) = mismatch {
            let msg = format!(
                "moves with `{}`, {why} (`{}`, in {who}): it does not refine its type (Def 3.4)",
                crate::hir::print::prim_app(prog, app),
                t.name
            );
            self.off_type(&a, msg);
            self.put_actor(a);
            return Err(());
        }
        let mut vals = Vec::new();
        let mut exprs = Vec::new();
        for e in &app.args {
            if self.leak(&a, e, &[], &format!("an argument of its process's `{}`", p.name)) {
                self.put_actor(a);
                return Err(());
            }
            match self.process_argument(&a, e) {
                Ok((v, x)) => {
                    vals.push(v);
                    exprs.push(x);
                }
                Err(why) => {
                    let now = self.now();
                    let msg = format!("{who}: the process of `{}`: {why}", prog.role_name(r));
                    self.report(Kind::Undecided, &now, msg);
                    self.put_actor(a);
                    return Err(());
                }
            }
        }
        if let Some(pr) = a.proc.as_mut() {
            pr.at = cont;
        }
        self.put_actor(a);
        Ok(Some((PrimApp { prim: app.prim, args: exprs, loc: app.loc }, vals)))
    }

    /// An argument of a process's primitive, as [`Runner::argument`] makes one of the
    /// type's, with what the participant knows.
    fn process_argument(&self, a: &Actor, e: &Expr) -> Result<(Value, Expr), String> {
        let v = self.eval_as(a, e).map_err(|err| format!("an argument of its primitive cannot be evaluated: {err}"))?;
        if let Some(x) = value_expr(&v, &e.sort, e.loc) {
            return Ok((v, x));
        }
        let closed = map_vars(e, &mut |x, sort| match x {
            Var::Role(..) | Var::Value(..) => {
                self.lookup_as(a, x).and_then(|val| value_expr(&val, sort, Loc::default()))
            }
            _ => None,
        });
        let mut open = false;
        closed.visit_vars(&mut |x, _| open |= matches!(x, Var::Role(..) | Var::Value(..)));
        if open {
            return Err(format!("an argument reads a value known only as an enclosure ({v})"));
        }
        Ok((v, closed))
    }

    /// The type's primitive at a sample of the process's witness: its guarantee and the
    /// kind's invariant (and its postcondition at the end) must hold of the state the
    /// process's motion reached, its precondition-free part of Def 3.4. `None` when they
    /// hold (or cannot be decided, which is reported), else the violated part.
    pub(super) fn type_contract_breaks(
        &self,
        ty: &Typed,
        now: &[Value],
        start: &[Value],
        clock: &Num,
        inputs: &[Option<Value>],
        last: bool,
    ) -> Option<&'static str> {
        let prog = self.prog;
        let prim = prog.prim(ty.app.prim);
        let env = frame_env(now, start, &ty.args, clock, inputs);
        let mut parts = vec![("guarantee", &prim.guarantee)];
        if last {
            parts.push(("postcondition", &prim.post));
        }
        parts.into_iter().find(|(_, e)| exact::holds(prog, e, &env) == Tri::False).map(|(what, _)| what)
    }

    /// Whether the type's duration, with its arguments at `start`, excludes `end` for
    /// certain.
    pub(super) fn outside_type_duration(&self, ty: &Typed, start: &[Value], end: &Num) -> bool {
        let prog = self.prog;
        let prim = prog.prim(ty.app.prim);
        let zero = Num::int(0);
        let env = frame_env(start, start, &ty.args, &zero, &[]);
        let num = |e: &Expr| exact::eval(prog, e, &env).ok().and_then(|v| v.num().ok().cloned());
        let early = num(&prim.duration.lo).is_some_and(|lo| end.hi < lo.lo);
        let late = prim.duration.hi.as_ref().and_then(num).is_some_and(|hi| end.lo > hi.hi);
        early || late
    }

    /// The type has ended: every process must be at its `end` too.
    pub(super) fn processes_end(&mut self) {
        let prog = self.prog;
        for r in prog.role_ids() {
            let Some(a) = self.settled(r) else {
                if self.over {
                    return;
                }
                continue;
            };
            if matches!(a.proc.as_ref().map(|p| p.at), Some(Process::End(_))) {
                self.put_actor(a);
                continue;
            }
            self.astray(a, "has ended");
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::lower::tests::lower_src;
    use crate::simulate::{simulate, Kind, SimConfig, SimReport};

    /// Two robots 10 m apart: `P` tells `Q` how far it goes, then moves that far while `Q`
    /// waits.
    const SCENE: &str = "
        robot K { state x: real; }
        motion K.go(d: real) { interruptible: false; pre: d > 0; guarantee: old(x) <= x && x <= old(x) + d;
            post: x == old(x) + d; footprint(px, py, pz): px^2 + py^2 + pz^2 <= 1; duration: [1, 2]; }
        motion K.far(d: real) { interruptible: false; pre: d > 0; guarantee: old(x) <= x && x <= old(x) + 2 * d;
            post: x == old(x) + 2 * d; footprint(px, py, pz): px^2 + py^2 + pz^2 <= 1; duration: [1, 2]; }
        motion K.wait { interruptible: true; guarantee: x == old(x); footprint(px, py, pz): px^2 + py^2 + pz^2 <= 1; }
        system S { participant P: K { init: x == 0; at: pose(0, 0, 0); } participant Q: K { init: x == 0; at: pose(0, 10, 0); } }
        choreography G = mu t. P -> Q : step(d: real { d > 0 && d <= 1 }). dt<P: go(d), Q: wait>. t;
        process Q = mu k. P?step(e).dt<wait>.k;
    ";

    fn run(src: &str) -> SimReport {
        let (prog, d) = lower_src(src);
        assert!(d.iter().all(|d| !d.is_error()), "{d:?}");
        simulate(&prog, &SimConfig { runs: 2, steps: 8, ..SimConfig::default() })
    }

    fn violation(r: &SimReport, text: &str) {
        assert!(
            r.findings.iter().any(|f| f.kind == Kind::Violation && f.message.contains(text)),
            "expected a violation about `{text}`: {:?}",
            r.findings
        );
    }

    #[test]
    fn a_process_that_follows_its_type_runs_clean_and_moves_as_it_says() {
        let r = run(&format!("{SCENE} process P = mu k. Q!step(1 / 2).dt<go(1 / 2)>.k;"));
        assert!(r.findings.is_empty(), "{:?}", r.findings);
        assert!(r.steps >= 16, "{}", r.steps);
    }

    #[test]
    fn a_payload_that_breaks_the_refinement_is_a_violation() {
        let r = run(&format!("{SCENE} process P = mu k. Q!step(2).dt<go(2)>.k;"));
        violation(&r, "breaks the refinement of `d`");
    }

    #[test]
    fn a_primitive_whose_run_leaves_the_types_contract_is_a_violation() {
        // Another primitive that goes twice as far: its end breaks the type's postcondition.
        // Its run leaves the type's guarantee (`x <= old(x) + d`) or, at the end, its
        // postcondition.
        let r = run(&format!("{SCENE} process P = mu k. Q!step(1 / 2).dt<far(1 / 2)>.k;"));
        violation(&r, "of its type's `go` (it does not refine it, Def 3.4)");
        // The type's primitive with another argument than the one sent.
        let r = run(&format!("{SCENE} process P = mu k. Q!step(1 / 2).dt<go(1)>.k;"));
        violation(&r, "of its type's `go` (it does not refine it, Def 3.4)");
        // An interruptible primitive where the type's is not.
        let r = run(&format!("{SCENE} process P = mu k. Q!step(1 / 2).dt<wait>.k;"));
        violation(&r, "an interruptible primitive where its type's is not");
    }

    #[test]
    fn a_process_that_ends_early_or_goes_on_is_a_violation() {
        let r = run(&format!("{SCENE} process P = Q!step(1 / 2).dt<go(1 / 2)>.end;"));
        violation(&r, "has ended where its type sends");
        let once = SCENE.replace(
            "mu t. P -> Q : step(d: real { d > 0 && d <= 1 }). dt<P: go(d), Q: wait>. t;",
            "P -> Q : step(d: real { d > 0 && d <= 1 }). dt<P: go(d), Q: wait>. end;",
        );
        let once = once.replace("process Q = mu k. P?step(e).dt<wait>.k;", "process Q = P?step(e).dt<wait>.end;");
        let r = run(&format!("{once} process P = Q!step(1 / 2).dt<go(1 / 2)>.end;"));
        assert!(r.findings.is_empty(), "{:?}", r.findings);
        let r = run(&format!("{once} process P = Q!step(1 / 2).dt<go(1 / 2)>.dt<go(1 / 2)>.end;"));
        violation(&r, "moves with `go(1 / 2)` where its type has ended");
    }

    #[test]
    fn the_process_decides_the_branch_of_a_choice() {
        let choice = SCENE.replace(
            "mu t. P -> Q : step(d: real { d > 0 && d <= 1 }). dt<P: go(d), Q: wait>. t;",
            "mu t. (P -> Q : step(d: real { d > 0 && d <= 1 }). dt<P: go(d), Q: wait>. t + P -> Q : stop. end);",
        );
        let choice = choice.replace(
            "process Q = mu k. P?step(e).dt<wait>.k;",
            "process Q = mu k. (P?step(e).dt<wait>.k + P?stop.end);",
        );
        // Always `step`: the runs never stop early.
        let r = run(&format!("{choice} process P = mu k. Q!step(1 / 2).dt<go(1 / 2)>.k;"));
        assert!(r.findings.is_empty(), "{:?}", r.findings);
        assert!(r.steps >= 16, "{}", r.steps);
        let r = run(&format!("{choice} process P = mu k. Q!halt.end;"));
        violation(&r, "sends `Q!halt`, which its type does not offer here");
    }
}
