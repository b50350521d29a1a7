//! A joint motion `dt<p_i: a_i>` on concrete states: its arguments, its preconditions
//! ([TRAJ-BASE]), a witness trajectory from Z3 ([TRAJ-STEP], [INTERRUPT]/[NON-INTERRUPT],
//! [M-PAR]) replayed exactly, its assumptions against the others' guarantees ([AGCOMP]),
//! and the collision checks at each sampled time ([`super::space`]).

use super::lockstep::Typed;
use super::par::Segment;
use super::report::Kind;
use super::run::{Flow, Runner};
use super::value_expr;
use crate::exact::{self, Num, Rat, Tri, Value};
use crate::hir::{Expr, Motion, PrimApp, Program, RoleId, Slot, Var};
use crate::smt::goals::witness::{Mover, Occupant};
use num_bigint::BigInt;

impl Runner<'_, '_> {
    pub(super) fn motion(&mut self, m: &Motion) -> Flow {
        if self.steps >= self.cfg.steps {
            return Flow::Stop;
        }
        self.steps += 1;
        let prog = self.prog;
        let t0 = m.parts.iter().map(|(r, _)| self.clock[r.idx()].clone()).max().unwrap_or_default();
        let names: Vec<String> = m
            .parts
            .iter()
            .map(|(r, app)| format!("{}: {}", prog.role_name(*r), crate::hir::print::prim_app(prog, app)))
            .collect();
        let who = format!("dt<{}>", names.join(", "));
        // Arguments evaluated now, preconditions checked exactly ([TRAJ-BASE]).
        let mut movers = Vec::new();
        let mut typed: Vec<Option<Typed>> = Vec::new();
        for (r, app) in &m.parts {
            let mut args = Vec::new();
            for a in &app.args {
                if self.leaks(*r, a, &[], &format!("an argument of `{}`", prog.prim(app.prim).name)) {
                    return Flow::Stop;
                }
                match self.argument(a) {
                    Ok(x) => args.push(x),
                    Err(why) => {
                        self.report(Kind::Undecided, &t0, format!("{who}: {why}"));
                        return Flow::Stop;
                    }
                }
            }
            let prim = prog.prim(app.prim);
            let start = self.state[r.idx()].clone();
            let vals: Vec<Value> = args.iter().map(|(v, _)| v.clone()).collect();
            let zero = Num::int(0);
            let now_inputs: Vec<Option<Value>> =
                (0..prog.kind_of(*r).inputs.len()).map(|i| self.lookup(&Var::Role(*r, Slot::Input(i)))).collect();
            let pre = exact::holds(prog, &prim.pre, &frame_env(&start, &start, &vals, &zero, &now_inputs));
            if pre == Tri::Unknown {
                self.report(
                    Kind::Undecided,
                    &t0,
                    format!(
                        "{who}: the precondition of `{}` ({}) cannot be decided: an enclosure of its values lies on both sides of a boundary; {}",
                        prim.name,
                        prog.role_name(*r),
                        self.show_state(*r)
                    ),
                );
                return Flow::Stop;
            }
            if pre == Tri::False {
                self.report(
                    Kind::Stuck,
                    &t0,
                    format!(
                        "{who}: the precondition of `{}` ({}) is false; {}",
                        prim.name,
                        prog.role_name(*r),
                        self.show_state(*r)
                    ),
                );
                return Flow::Stop;
            }
            let inputs = prog.role(*r).input_sources.iter().enumerate().map(|(i, src)| {
                let src = (*src)?;
                if m.parts.iter().any(|(p, _)| *p == src) {
                    return None;
                }
                self.lookup(&Var::Role(*r, Slot::Input(i)))
            });
            let inputs: Vec<Option<Value>> = inputs.collect();
            let app_closed = PrimApp { prim: app.prim, args: args.into_iter().map(|(_, e)| e).collect(), loc: app.loc };
            // A participant with a process moves with its process's primitive and
            // arguments ([`super::lockstep`]); the type's is kept to check refinement.
            let app = match self.process_moves(*r, app, &who) {
                Err(()) => return Flow::Stop,
                Ok(None) => {
                    typed.push(None);
                    app_closed
                }
                Ok(Some((papp, pvals))) => {
                    let pp = prog.prim(papp.prim);
                    let env = frame_env(&start, &start, &pvals, &zero, &now_inputs);
                    match exact::holds(prog, &pp.pre, &env) {
                        Tri::True => {}
                        Tri::False => {
                            let msg = format!(
                                "{who}: the process of `{}` moves with `{}`, whose precondition is false where its type's `{}` holds (it does not refine it, Def 3.4); {}",
                                prog.role_name(*r),
                                crate::hir::print::prim_app(prog, &papp),
                                prim.name,
                                self.show_state(*r)
                            );
                            self.report(Kind::Violation, &t0, msg);
                            return Flow::Stop;
                        }
                        Tri::Unknown => {
                            let msg = format!(
                                "{who}: the precondition of the process's `{}` ({}) cannot be decided",
                                pp.name,
                                prog.role_name(*r)
                            );
                            self.report(Kind::Undecided, &t0, msg);
                            return Flow::Stop;
                        }
                    }
                    typed.push(Some(Typed { app: app_closed, args: vals }));
                    papp
                }
            };
            movers.push(Mover { role: *r, app, start, inputs });
        }
        let mut fracs: Vec<Rat> = (1..self.cfg.samples.max(1)).map(|_| self.rng.fraction()).collect();
        fracs.sort();
        fracs.dedup();
        fracs.push(Rat::from_integer(BigInt::from(1)));
        // With a non-interruptible part, its end is aimed at the start or the end of its
        // duration now and then (where durations that do not nest show).
        let lead = movers.iter().position(|mv| !prog.prim(mv.app.prim).interruptible);
        let aimed = match (lead, self.rng.below(4)) {
            (Some(_), 0 | 1) => self.sess.trajectory_aimed(prog, &movers, &fracs, None, Some(true)),
            (Some(_), 2) => self.sess.trajectory_aimed(prog, &movers, &fracs, None, Some(false)),
            _ => Ok(None),
        };
        let traj = match aimed {
            Ok(Some(t)) => Ok(Some(t)),
            _ => self.sess.trajectory(prog, &movers, &fracs, None),
        };
        let traj = match traj {
            Ok(Some(t)) => t,
            Ok(None) => {
                self.report(
                    Kind::Stuck,
                    &t0,
                    format!(
                        "{who}: no trajectory satisfies the guarantees, assumptions and invariants and ends with the postconditions within the durations"
                    ),
                );
                return Flow::Stop;
            }
            Err(why) => {
                self.undecided(&t0, &who, why);
                return Flow::Stop;
            }
        };
        // The others must be able to end when the non-interruptible part does.
        if let Some(n) = lead {
            for (j, mv) in movers.iter().enumerate() {
                let prim = prog.prim(mv.app.prim);
                let args = self.arg_values(&mv.app);
                let zero = Num::int(0);
                let env = frame_env(&mv.start, &mv.start, &args, &zero, &[]);
                let lo = exact::eval(prog, &prim.duration.lo, &env).ok().and_then(|v| v.num().ok().cloned());
                let hi = prim
                    .duration
                    .hi
                    .as_ref()
                    .map(|h| exact::eval(prog, h, &env).ok().and_then(|v| v.num().ok().cloned()));
                let early = lo.is_some_and(|lo| traj.end.hi < lo.lo);
                let late = matches!(hi, Some(Some(hi)) if traj.end.lo > hi.hi);
                if j != n && (early || late) {
                    let t = &t0 + traj.end.mid();
                    self.report(
                        Kind::Stuck,
                        &t,
                        format!(
                            "{who}: the non-interruptible `{}` ({}) ends after {} s, outside the duration of `{}` ({})",
                            prog.prim(movers[n].app.prim).name,
                            prog.role_name(movers[n].role),
                            traj.end,
                            prim.name,
                            prog.role_name(mv.role)
                        ),
                    );
                    return Flow::Stop;
                }
            }
        }
        // A process's primitive ends within its type's duration (Def 3.4). After the
        // check above: where the type's own durations do not fit together, that is the
        // type's defect (stuck), not the process's.
        for (mv, ty) in movers.iter().zip(&typed) {
            let Some(ty) = ty else { continue };
            if self.outside_type_duration(ty, &mv.start, &traj.end) {
                let t = &t0 + traj.end.mid();
                let msg = format!(
                    "{who}: the process of `{}` moves with `{}`, which ends after {} s, outside the duration of its type's `{}` (it does not refine it, Def 3.4)",
                    prog.role_name(mv.role),
                    prog.prim(mv.app.prim).name,
                    traj.end,
                    prog.prim(ty.app.prim).name
                );
                self.report(Kind::Violation, &t, msg);
                return Flow::Stop;
            }
        }
        // Assumptions: could the others' guarantees break one at a sampled time?
        for (i, mv) in movers.iter().enumerate() {
            if prog.prim(mv.app.prim).assume.is_true() {
                continue;
            }
            for s in &traj.samples {
                let c = s.time.mid();
                match self.sess.assumption_breaks(prog, &movers, i, &s.time) {
                    Ok(None) => {}
                    Ok(Some(inputs)) => {
                        let kind = prog.kind_of(mv.role);
                        let shown: Vec<String> = kind
                            .inputs
                            .iter()
                            .zip(&inputs)
                            .map(|((n, _), v)| format!("{}.{n} = {v}", prog.role_name(mv.role)))
                            .collect();
                        let t = &t0 + &c;
                        self.report(
                            Kind::Violation,
                            &t,
                            format!(
                                "{who}: the others' guarantees allow inputs that break the assumption of `{}` ({}): {}",
                                prog.prim(mv.app.prim).name,
                                prog.role_name(mv.role),
                                shown.join(", ")
                            ),
                        );
                        return Flow::Stop;
                    }
                    Err(why) => {
                        self.undecided(
                            &(&t0 + &c),
                            &format!("{who}: the assumption of `{}`", prog.prim(mv.app.prim).name),
                            why,
                        );
                        return Flow::Stop;
                    }
                }
            }
        }
        // At time 0 every participant is at its start state ([TRAJ-BASE]).
        let zero = Num::int(0);
        let at_start: Vec<Occupant> = movers.iter().map(|mv| occupant(mv, &mv.start, &zero)).collect();
        if !self.occupied(&at_start, &t0, &who) {
            return Flow::Stop;
        }
        // Replay the witness exactly, then compare footprints at each sample.
        for s in &traj.samples {
            for (i, mv) in movers.iter().enumerate() {
                let prim = prog.prim(mv.app.prim);
                let args = self.arg_values(&mv.app);
                let inputs = self.inputs_at(&movers, i, &s.states);
                let env = frame_env(&s.states[i], &mv.start, &args, &s.time, &inputs);
                let mut checks = vec![("guarantee", &prim.guarantee), ("assumption", &prim.assume)];
                let inv = prog.kind(prim.kind).invariant.as_ref();
                checks.extend(inv.map(|e| ("invariant", e)));
                if std::ptr::eq(s, traj.samples.last().unwrap_or(s)) {
                    checks.push(("postcondition", &prim.post));
                }
                for (what, e) in checks {
                    if exact::holds(prog, e, &env) == Tri::False {
                        let t = &t0 + s.time.mid();
                        self.report(
                            Kind::Replay,
                            &t,
                            format!("{who}: Z3's witness breaks the {what} of `{}` when replayed exactly", prim.name),
                        );
                        return Flow::Stop;
                    }
                }
                let last = std::ptr::eq(s, traj.samples.last().unwrap_or(s));
                let ty = typed.get(i).and_then(Option::as_ref);
                if let Some(what) =
                    ty.and_then(|ty| self.type_contract_breaks(ty, &s.states[i], &mv.start, &s.time, &inputs, last))
                {
                    let t = &t0 + s.time.mid();
                    let ty_name = ty.map(|ty| prog.prim(ty.app.prim).name.clone()).unwrap_or_default();
                    let msg = format!(
                        "{who}: the process of `{}` moves with `{}`, whose run breaks the {what} of its type's `{ty_name}` (it does not refine it, Def 3.4); {}",
                        prog.role_name(mv.role),
                        prim.name,
                        show_values(prog, mv.role, &s.states[i])
                    );
                    self.report(Kind::Violation, &t, msg);
                    return Flow::Stop;
                }
            }
            let now: Vec<Occupant> = movers.iter().zip(&s.states).map(|(mv, st)| occupant(mv, st, &s.time)).collect();
            if !self.occupied(&now, &(&t0 + s.time.mid()), &who) {
                return Flow::Stop;
            }
        }
        let end = traj.end.mid();
        let t1 = &t0 + &end;
        let last = traj.samples.last().map(|s| s.states.clone()).unwrap_or_default();
        for (i, mv) in movers.iter().enumerate() {
            self.segments.push(Segment {
                role: mv.role,
                app: mv.app.clone(),
                start: mv.start.clone(),
                end: last.get(i).cloned().unwrap_or_else(|| mv.start.clone()),
                len: traj.end.clone(),
                from: t0.clone(),
                to: t1.clone(),
                inputs: mv.inputs.clone(),
            });
            if let Some(s) = last.get(i) {
                self.state[mv.role.idx()] = s.clone();
            }
            self.clock[mv.role.idx()] = t1.clone();
        }
        let states: Vec<String> = movers.iter().map(|mv| self.show_state(mv.role)).collect();
        self.trace.push(format!(
            "t = {} to {}: {who}; then {}",
            exact::decimal(&t0),
            exact::decimal(&t1),
            states.join("; ")
        ));
        Flow::Next
    }

    /// The participants of a joint motion at one time: every pair's footprints apart,
    /// each footprint clear of the obstacles, each body within its footprint, and the real
    /// bodies apart from the obstacles, from each other and (outside `*`) from the bodies
    /// of the participants that wait ([`super::bodies`]). False when the run must stop.
    pub(super) fn occupied(&mut self, now: &[Occupant], t: &Rat, who: &str) -> bool {
        let moving: Vec<&Occupant> = now.iter().collect();
        for i in 0..now.len() {
            for j in i + 1..now.len() {
                if !self.collide(&now[i], &now[j], t, who, &moving) {
                    return false;
                }
            }
        }
        now.iter().all(|o| self.clear_of_obstacles(o, t, who, &moving) && self.body_in_footprint(o, t, who, &moving))
            && self.bodies_apart(&moving, t, who, self.par_depth == 0)
    }

    /// An argument of a primitive now: its value (exact, or an enclosure such as that of
    /// `pi / 2`) and a closed expression for the witness queries: the exact value as a
    /// literal, or else the argument with every known variable replaced by its exact value
    /// (so Z3 reads `pi`, `sin`, `sqrt` as the checks' encoding does). `Err` when a value
    /// it reads is itself only an enclosure, or cannot be evaluated.
    pub(super) fn argument(&self, a: &Expr) -> Result<(Value, Expr), String> {
        let v =
            self.eval(a).map_err(|e| format!("the argument `{}` cannot be evaluated: {e}", show_expr(self.prog, a)))?;
        if let Some(e) = value_expr(&v, &a.sort, a.loc) {
            return Ok((v, e));
        }
        let closed = self.close(a, &[]);
        let mut open = false;
        closed.visit_vars(&mut |x, _| open |= matches!(x, Var::Role(..) | Var::Value(..)));
        if open {
            return Err(format!(
                "the argument `{}` reads a value known only as an enclosure ({v}), which a witness query cannot pin",
                show_expr(self.prog, a)
            ));
        }
        Ok((v, closed))
    }

    pub(super) fn arg_values(&self, app: &PrimApp) -> Vec<Value> {
        app.args.iter().filter_map(|a| exact::eval(self.prog, a, &|_: &Var| None).ok()).collect()
    }

    /// Input values of mover `i` at a sample: the source's sampled state when it moves
    /// in the same motion, else the fixed value.
    pub(super) fn inputs_at(&self, movers: &[Mover], i: usize, states: &[Vec<Value>]) -> Vec<Option<Value>> {
        let prog = self.prog;
        let r = movers[i].role;
        let kind = prog.kind_of(r);
        (0..kind.inputs.len())
            .map(|k| {
                if let Some(Some(v)) = movers[i].inputs.get(k) {
                    return Some(v.clone());
                }
                let src = prog.role(r).input_sources.get(k).copied().flatten()?;
                let j = movers.iter().position(|m| m.role == src)?;
                let (slot, _) = prog.kind_of(src).slot(&kind.inputs[k].0)?;
                let Slot::State(s) = slot else { return None };
                states.get(j)?.get(s).cloned()
            })
            .collect()
    }
}

pub(super) fn occupant(m: &Mover, now: &[Value], clock: &Num) -> Occupant {
    Occupant { role: m.role, app: m.app.clone(), start: m.start.clone(), now: now.to_vec(), clock: clock.clone() }
}

pub(super) fn show_values(prog: &Program, r: RoleId, vals: &[Value]) -> String {
    let kind = prog.kind_of(r);
    let v: Vec<String> = kind.state.iter().zip(vals).map(|((n, _), v)| format!("{n} = {v}")).collect();
    v.join(", ")
}

/// The environment of a primitive's contract: own state now (and inputs), `old`, the
/// arguments and the clock.
pub(super) fn frame_env<'v>(
    now: &'v [Value],
    start: &'v [Value],
    args: &'v [Value],
    clock: &'v Num,
    inputs: &'v [Option<Value>],
) -> impl Fn(&Var) -> Option<Value> + 'v {
    move |v: &Var| match v {
        Var::Own(Slot::State(i)) => now.get(*i).cloned(),
        Var::Own(Slot::Input(i)) => inputs.get(*i).cloned().flatten(),
        Var::Old(i) => start.get(*i).cloned(),
        Var::Param(i) => args.get(*i).cloned(),
        Var::Clock => Some(Value::Num(clock.clone())),
        _ => None,
    }
}

fn show_expr(prog: &Program, e: &Expr) -> String {
    crate::hir::print::expr(prog, None, e)
}
