//! A participant's process, stepped on concrete values: what both runners share (protocols
//! without motion, [`super::session`], and choreographies with motion, [`super::lockstep`]).
//!
//! An [`Actor`] is a participant with the values it has and, if it has one, where its
//! process is. [`Runner::settle_process`] runs the process up to its next action (a send,
//! a receive, a motion or `end`): `mu` and jumps bind the process's parameters (their
//! refinements checked, E0712/E0713's question), `if` takes the branch its condition
//! selects, evaluated exactly with what the participant knows. A read of a value it does
//! not have is a violation ([`unknown_read`], E0305's question).

use super::report::Kind;
use super::run::Runner;
use crate::exact::{self, Tri, Value};
use crate::hir::{Expr, Process, Program, RecParam, RoleId, Slot, ValueId, ValueOrigin, Var};
use std::collections::HashMap;

/// One participant as a runner sees it: the values it has and its process, if any.
pub(super) struct Actor<'p> {
    pub(super) id: RoleId,
    /// The values it has: payloads sent and received, recursion parameters (of its local
    /// type and of its process), and its process's variables (other binding sites, so one
    /// map holds them all).
    pub(super) known: HashMap<ValueId, Value>,
    pub(super) proc: Option<Proc<'p>>,
}

impl<'p> Actor<'p> {
    /// `role` with nothing known yet, and its process from `prog` if it has one.
    pub(super) fn new(prog: &'p Program, role: RoleId) -> Actor<'p> {
        Actor {
            id: role,
            known: HashMap::new(),
            proc: prog.processes.iter().find(|d| d.role == role).map(|d| Proc { at: &d.body, loops: HashMap::new() }),
        }
    }
}

/// Where a participant's process is, and the process loops around it.
pub(super) struct Proc<'p> {
    pub(super) at: &'p Process,
    pub(super) loops: HashMap<&'p str, (&'p [RecParam], &'p Process)>,
}

/// Unfoldings of `mu`/jumps in a row without an action before a participant counts as
/// looping for ever.
pub(super) const UNFOLD_LIMIT: usize = 64;

/// What participant `role` does not know, read by `e`: `None` when it knows all. It
/// knows its own state, the values `known` says it has, and the fields `keep` (those of
/// the message it is sending).
pub(super) fn unknown_read(
    prog: &Program,
    role: RoleId,
    known: &dyn Fn(ValueId) -> bool,
    e: &Expr,
    keep: &[ValueId],
) -> Option<String> {
    let mut bad = None;
    e.visit_vars(&mut |v, _| {
        if bad.is_some() {
            return;
        }
        // As E0305 reads it: a participant's own inputs are its own (sensed), not the
        // state of their source.
        match v.clone() {
            Var::Role(r, slot) if r != role => {
                bad = Some(format!(
                    "`{}.{}`, the state of `{}`",
                    prog.role_name(r),
                    prog.slot_name(prog.role(r).kind, slot),
                    prog.role_name(r)
                ));
            }
            Var::Value(id, name) if !keep.contains(&id) && !known(id) => {
                let how = match &prog.value(id).origin {
                    ValueOrigin::Message { from, to } => {
                        format!("sent by `{}` to `{}`", prog.role_name(*from), prog.role_name(*to))
                    }
                    ValueOrigin::RecParam => "a recursion parameter whose value it could not compute".to_string(),
                    ValueOrigin::Bound { role } => format!("bound by `{}`", prog.role_name(*role)),
                    ValueOrigin::Stream { .. } => "a stream's field as declared".to_string(),
                    ValueOrigin::Observed { reader, .. } => {
                        format!("observed by `{}` from a stream", prog.role_name(*reader))
                    }
                };
                bad = Some(format!("`{name}` ({how})"));
            }
            _ => {}
        }
    });
    bad
}

impl Runner<'_, '_> {
    /// A value as `role` sees it: its own state, the values it has.
    pub(super) fn lookup_as(&self, role: &Actor, v: &Var) -> Option<Value> {
        match self.prog.source_of(v) {
            Var::Role(r, Slot::State(i)) if r == role.id => self.state.get(r.idx())?.get(i).cloned(),
            Var::Value(id, _) => role.known.get(&id).cloned(),
            _ => None,
        }
    }

    pub(super) fn eval_as(&self, role: &Actor, e: &Expr) -> Result<Value, String> {
        exact::eval(self.prog, e, &|v: &Var| self.lookup_as(role, v))
    }

    pub(super) fn holds_as(&self, role: &Actor, e: &Expr) -> Tri {
        exact::holds(self.prog, e, &|v: &Var| self.lookup_as(role, v))
    }

    /// `what` reads something `role` does not know: a finding. True when reported.
    pub(super) fn leak(&mut self, role: &Actor, e: &Expr, keep: &[ValueId], what: &str) -> bool {
        let Some(read) = unknown_read(self.prog, role.id, &|id| role.known.contains_key(&id), e, keep) else {
            return false;
        };
        let now = self.now();
        let msg = format!("`{}`: {what} reads {read}, which it does not know", self.prog.role_name(role.id));
        self.report(Kind::Violation, &now, msg);
        true
    }

    /// Binds `params` to `args` for `role`, checking their refinements. False when the run
    /// must stop.
    pub(super) fn bind(&mut self, role: &mut Actor, params: &[RecParam], args: Vec<Value>) -> bool {
        for (p, v) in params.iter().zip(args) {
            role.known.insert(p.value, v.clone());
            if let Some(r) = &p.refinement {
                if self.leak(role, r, &[], &format!("the refinement of `{}`", p.name)) {
                    return false;
                }
                if self.holds_as(role, r) == Tri::False {
                    let now = self.now();
                    let msg = format!(
                        "`{}`: the recursion parameter `{} = {v}` breaks its refinement",
                        self.prog.role_name(role.id),
                        p.name
                    );
                    self.report(Kind::Violation, &now, msg);
                    return false;
                }
            }
        }
        true
    }

    /// Values of `exprs` as `role` evaluates them (`what` names them in findings).
    pub(super) fn values_as(&mut self, role: &Actor, exprs: &[&Expr], what: &str) -> Option<Vec<Value>> {
        let mut out = Vec::new();
        for e in exprs {
            if self.leak(role, e, &[], what) {
                return None;
            }
            match self.eval_as(role, e) {
                Ok(v) => out.push(v),
                Err(err) => {
                    let now = self.now();
                    self.report(Kind::Undecided, &now, format!("{what} of `{}`: {err}", self.prog.role_name(role.id)));
                    return None;
                }
            }
        }
        Some(out)
    }

    /// Runs `role`'s process up to its next action (a message, a motion, or its end): `mu` and jumps bind the
    /// process's parameters, `if` takes the branch its condition selects, evaluated
    /// exactly. False when the run must stop.
    pub(super) fn settle_process(&mut self, role: &mut Actor<'_>) -> bool {
        let name = self.prog.role_name(role.id);
        for _ in 0..UNFOLD_LIMIT {
            let Some(proc) = role.proc.as_ref() else { return true };
            let at = proc.at;
            match at {
                Process::Rec { var, params, body, .. } => {
                    let inits: Vec<&Expr> = params.iter().map(|p| &p.init).collect();
                    let what = format!("the initial values of the process loop `{var}`");
                    let Some(args) = self.values_as(role, &inits, &what) else { return false };
                    if !self.bind(role, params, args) {
                        return false;
                    }
                    if let Some(proc) = role.proc.as_mut() {
                        proc.loops.insert(var.as_str(), (params.as_slice(), &**body));
                        proc.at = body;
                    }
                }
                Process::Var { var, args, .. } => {
                    let Some((params, body)) = role.proc.as_ref().and_then(|p| p.loops.get(var.as_str()).copied())
                    else {
                        let now = self.now();
                        self.report(Kind::Undecided, &now, format!("`{name}`: `{var}` is not a loop of its process"));
                        return false;
                    };
                    let exprs: Vec<&Expr> = args.iter().collect();
                    let what = format!("the arguments of the process jump `{var}`");
                    let Some(vals) = self.values_as(role, &exprs, &what) else { return false };
                    if !self.bind(role, params, vals) {
                        return false;
                    }
                    if let Some(proc) = role.proc.as_mut() {
                        proc.at = body;
                    }
                }
                Process::If { cond, then, els, .. } => {
                    if self.leak(role, cond, &[], "an `if` condition of its process") {
                        return false;
                    }
                    let next: &Process = match self.holds_as(role, cond) {
                        Tri::True => then,
                        Tri::False => els,
                        Tri::Unknown => {
                            let now = self.now();
                            let msg = format!("`{name}`: an `if` condition of its process cannot be evaluated exactly");
                            self.report(Kind::Undecided, &now, msg);
                            return false;
                        }
                    };
                    if let Some(proc) = role.proc.as_mut() {
                        proc.at = next;
                    }
                }
                Process::Send { .. }
                | Process::Choose { .. }
                | Process::Recv { .. }
                | Process::Motion { .. }
                | Process::End(_) => return true,
            }
        }
        let now = self.now();
        self.report(Kind::Stuck, &now, format!("the process of `{name}` loops without an action"));
        false
    }

    /// The sends `role`'s process may take now: (receiver, label, arguments, continuation).
    pub(super) fn offers<'p>(role: &Actor<'p>) -> Vec<(RoleId, &'p str, &'p [Expr], &'p Process)> {
        fn collect<'p>(p: &'p Process, out: &mut Vec<(RoleId, &'p str, &'p [Expr], &'p Process)>) {
            match p {
                Process::Send { to, label, args, cont, .. } => out.push((*to, label, args, cont)),
                Process::Choose { branches, .. } => branches.iter().for_each(|b| collect(b, out)),
                _ => {}
            }
        }
        let mut out = Vec::new();
        if let Some(p) = &role.proc {
            collect(p.at, &mut out);
        }
        out
    }

    /// A finding: `role`'s process does not do what its local type says here.
    pub(super) fn off_type(&mut self, role: &Actor<'_>, what: String) {
        let now = self.now();
        let msg = format!("the process of `{}` {what}", self.prog.role_name(role.id));
        self.report(Kind::Violation, &now, msg);
    }
}
