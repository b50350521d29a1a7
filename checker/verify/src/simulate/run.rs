//! The run loop: a participant state per role, a clock per role, and the global type
//! walked as Def 4.11 consumes it (messages, choices, recursion; motions and `*` are in
//! [`super::motion`] and [`super::par`]).

use super::par::Segment;
use super::report::{Finding, Kind};
use super::{first_message, own_to_role, value_expr, var_expr, Rng, SimConfig};
use crate::exact::{self, Rat, Tri, Value};
use crate::hir::expr::map_vars;
use crate::hir::{Expr, Global, Loc, Msg, Program, RoleId, Slot, ValueId, Var};
use crate::smt::goals::witness::Session;
use crate::smt::Why;
use mochi_core::splitmix::SplitMix64;
use num_bigint::BigInt;
use num_traits::Zero;
use std::collections::{HashMap, HashSet};

/// What walking a global type ended with.
pub(super) enum Flow {
    /// Fell off the end: the continuation runs next.
    Next,
    /// Reached `t(args)`.
    Jump(String, Vec<Value>),
    /// The run is over (`end`, the budget, or a finding).
    Stop,
}

pub(super) struct Runner<'a, 'p> {
    pub(super) prog: &'p Program,
    pub(super) sess: &'a Session<'a>,
    pub(super) cfg: &'a SimConfig,
    pub(super) run: usize,
    pub(super) rng: Rng,
    /// Per participant, one value per state variable.
    pub(super) state: Vec<Vec<Value>>,
    /// When each participant is next free.
    pub(super) clock: Vec<Rat>,
    pub(super) values: HashMap<ValueId, Value>,
    pub(super) segments: Vec<Segment>,
    pub(super) steps: usize,
    pub(super) trace: Vec<String>,
    /// The messages of a protocol run without motion, as sent (for `SimReport::messages`).
    pub(super) messages: Vec<super::report::SimMessage>,
    pub(super) findings: Vec<Finding>,
    pub(super) over: bool,
    /// Per participant, the values it has (the global walk's knowledge: payloads sent or
    /// received, recursion parameters whose values it could compute).
    pub(super) known: Vec<HashSet<ValueId>>,
    /// At a jump, per argument, which participants know its value.
    pub(super) jump_known: Vec<Vec<bool>>,
    /// In a choreography with motion, per participant, its process as it runs in lockstep
    /// with the global type ([`super::lockstep`]); empty in protocols without motion.
    pub(super) actors: Vec<super::process::Actor<'p>>,
    /// The walk reached the type's `end` (outside `*`): every process must have ended.
    ended: bool,
    /// How many sides of `*` the walk is in.
    pub(super) par_depth: usize,
}

impl<'a, 'p> Runner<'a, 'p> {
    pub(super) fn new(prog: &'p Program, sess: &'a Session<'a>, cfg: &'a SimConfig, run: usize) -> Runner<'a, 'p> {
        Runner {
            prog,
            sess,
            cfg,
            run,
            rng: Rng(SplitMix64(cfg.seed.wrapping_mul(0x2545_F491_4F6C_DD1D).wrapping_add(run as u64))),
            state: Vec::new(),
            clock: vec![Rat::zero(); prog.roles.len()],
            values: HashMap::new(),
            segments: Vec::new(),
            steps: 0,
            trace: Vec::new(),
            messages: Vec::new(),
            findings: Vec::new(),
            over: false,
            known: vec![HashSet::new(); prog.roles.len()],
            jump_known: Vec::new(),
            actors: Vec::new(),
            ended: false,
            par_depth: 0,
        }
    }

    /// Half the time, a variable to move off Z3's first model and by how much (up or
    /// down by up to 1, 0.1 or 0.01).
    pub(super) fn nudge(&mut self, n: usize) -> Option<(usize, Rat)> {
        if n == 0 || self.rng.below(2) == 0 {
            return None;
        }
        let k = self.rng.below(n);
        let scale = [1, 10, 100][self.rng.below(3)];
        let d = self.rng.fraction() / Rat::from_integer(BigInt::from(scale));
        Some((k, if self.rng.below(2) == 0 { d } else { -d }))
    }

    pub(super) fn report(&mut self, kind: Kind, time: &Rat, message: String) {
        self.findings.push(Finding {
            kind,
            run: self.run,
            step: self.steps,
            time: exact::decimal(time),
            message,
            trace: self.trace.clone(),
        });
        self.over = true;
    }

    pub(super) fn undecided(&mut self, time: &Rat, what: &str, why: Why) {
        self.report(Kind::Undecided, time, format!("{what}: {why}"));
    }

    pub(super) fn now(&self) -> Rat {
        self.clock.iter().max().cloned().unwrap_or_default()
    }

    pub(super) fn go(&mut self, g: &Global) {
        if !self.init() {
            return;
        }
        self.start_processes();
        let _ = self.walk(g);
        if self.ended && !self.over {
            self.processes_end();
        }
    }

    /// Initial states: a model of each participant's `init` and invariant.
    pub(super) fn init(&mut self) -> bool {
        let prog = self.prog;
        for r in prog.role_ids() {
            let kind = prog.kind_of(r);
            let mut facts = Vec::new();
            facts.extend(prog.role(r).init.clone());
            facts.extend(kind.invariant.as_ref().map(|inv| own_to_role(inv, r)));
            let want: Vec<Expr> = (0..kind.state.len())
                .map(|i| var_expr(Var::Role(r, Slot::State(i)), kind.state[i].1.clone()))
                .collect();
            let nudge = self.nudge(want.len());
            match self.sess.values_nudged(prog, &facts, &want, nudge) {
                Ok(Some(vs)) => {
                    self.state.push(vs);
                    // Replayed exactly, as every model is.
                    if facts.iter().any(|f| self.holds(f) == Tri::False) {
                        self.report(
                            Kind::Replay,
                            &Rat::zero(),
                            format!(
                                "Z3's initial state of `{}` breaks its init or invariant exactly",
                                prog.role_name(r)
                            ),
                        );
                        return false;
                    }
                }
                Ok(None) => {
                    self.report(
                        Kind::Stuck,
                        &Rat::zero(),
                        format!(
                            "`{}` has no initial state: its init contradicts its kind's invariant",
                            prog.role_name(r)
                        ),
                    );
                    return false;
                }
                Err(why) => {
                    self.undecided(&Rat::zero(), &format!("the initial state of `{}`", prog.role_name(r)), why);
                    return false;
                }
            }
        }
        let states: Vec<String> = prog.role_ids().map(|r| self.show_state(r)).collect();
        let states: Vec<String> = states.into_iter().filter(|s| !s.is_empty()).collect();
        self.trace.push(format!("t = 0: start; {}", states.join("; ")));
        true
    }

    pub(super) fn show_state(&self, r: RoleId) -> String {
        let kind = self.prog.kind_of(r);
        let vals: Vec<String> = kind
            .state
            .iter()
            .zip(&self.state[r.idx()])
            .map(|((n, _), v)| format!("{}.{n} = {v}", self.prog.role_name(r)))
            .collect();
        vals.join(", ")
    }

    /// The value of a variable of the shared vocabulary.
    pub(super) fn lookup(&self, v: &Var) -> Option<Value> {
        match self.prog.source_of(v) {
            Var::Role(r, Slot::State(i)) => self.state.get(r.idx())?.get(i).cloned(),
            Var::Value(id, _) => self.values.get(&id).cloned(),
            _ => None,
        }
    }

    pub(super) fn eval(&self, e: &Expr) -> Result<Value, String> {
        exact::eval(self.prog, e, &|v: &Var| self.lookup(v))
    }

    pub(super) fn holds(&self, e: &Expr) -> Tri {
        exact::holds(self.prog, e, &|v: &Var| self.lookup(v))
    }

    /// `role` reads `e` (sending, or moving): a read of something it does not have is a
    /// violation. True when reported.
    pub(super) fn leaks(&mut self, role: RoleId, e: &Expr, keep: &[ValueId], what: &str) -> bool {
        let known = &self.known[role.idx()];
        let Some(read) = super::process::unknown_read(self.prog, role, &|id| known.contains(&id), e, keep) else {
            return false;
        };
        let now = self.now();
        let msg = format!("`{}`: {what} reads {read}, which it does not know", self.prog.role_name(role));
        self.report(Kind::Violation, &now, msg);
        true
    }

    /// Which participants know the value of `e` (they know everything it reads).
    fn knowers(&self, e: &Expr) -> Vec<bool> {
        self.prog
            .role_ids()
            .map(|r| {
                let known = &self.known[r.idx()];
                super::process::unknown_read(self.prog, r, &|id| known.contains(&id), e, &[]).is_none()
            })
            .collect()
    }

    /// A recursion parameter bound: the participants in `who` know it, the others not.
    fn learn(&mut self, id: ValueId, who: &[bool]) {
        for (k, set) in self.known.iter_mut().enumerate() {
            if who.get(k).copied().unwrap_or(false) {
                set.insert(id);
            } else {
                set.remove(&id);
            }
        }
    }

    pub(super) fn walk(&mut self, g: &Global) -> Flow {
        if self.over {
            return Flow::Stop;
        }
        match g {
            Global::End(_) => {
                self.ended = self.par_depth == 0;
                Flow::Stop
            }
            // `simulate` refuses a program with a timeout before running it.
            Global::After(_) => {
                let now = self.now();
                self.report(Kind::Undecided, &now, "not supported yet: a timeout branch".to_string());
                Flow::Stop
            }
            Global::Var(v) => {
                self.jump_known = v.args.iter().map(|a| self.knowers(a)).collect();
                let args: Result<Vec<Value>, String> = v.args.iter().map(|a| self.eval(a)).collect();
                match args {
                    Ok(args) => Flow::Jump(v.var.clone(), args),
                    Err(e) => {
                        let now = self.now();
                        self.report(Kind::Undecided, &now, format!("the arguments of `{}`: {e}", v.var));
                        Flow::Stop
                    }
                }
            }
            Global::Seq(items, _) => {
                for it in items {
                    match self.walk(it) {
                        Flow::Next => {}
                        other => return other,
                    }
                }
                Flow::Next
            }
            Global::Rec { var, params, body, .. } => {
                let mut args = Vec::new();
                self.jump_known = params.iter().map(|p| self.knowers(&p.init)).collect();
                for p in params {
                    match self.eval(&p.init) {
                        Ok(v) => args.push(v),
                        Err(e) => {
                            let now = self.now();
                            self.report(Kind::Undecided, &now, format!("the initial value of `{}`: {e}", p.name));
                            return Flow::Stop;
                        }
                    }
                }
                loop {
                    let who = std::mem::take(&mut self.jump_known);
                    for (k, (p, v)) in params.iter().zip(&args).enumerate() {
                        self.values.insert(p.value, v.clone());
                        self.learn(p.value, who.get(k).map(Vec::as_slice).unwrap_or_default());
                        if let Some(r) = &p.refinement {
                            if self.holds(r) == Tri::False {
                                let now = self.now();
                                self.report(
                                    Kind::Violation,
                                    &now,
                                    format!("the recursion parameter `{} = {v}` breaks its refinement", p.name),
                                );
                                return Flow::Stop;
                            }
                        }
                    }
                    let before = self.steps;
                    match self.walk(body) {
                        Flow::Jump(v, new) if v == *var => {
                            if self.steps >= self.cfg.steps {
                                return Flow::Stop;
                            }
                            if self.steps == before {
                                let now = self.now();
                                self.report(
                                    Kind::Stuck,
                                    &now,
                                    format!("the recursion `{var}` loops without a message or a motion"),
                                );
                                return Flow::Stop;
                            }
                            args = new;
                        }
                        other => return other,
                    }
                }
            }
            Global::Choice(branches, _) => {
                let mut enabled = Vec::new();
                let mut undecided = false;
                for (k, b) in branches.iter().enumerate() {
                    let guard = first_message(b).and_then(|m| m.guard.as_ref());
                    match guard.map_or(Tri::True, |e| self.holds(e)) {
                        Tri::True => enabled.push(k),
                        Tri::Unknown => undecided = true,
                        Tri::False => {}
                    }
                }
                if enabled.is_empty() {
                    let now = self.now();
                    if undecided {
                        self.report(Kind::Undecided, &now, "the guards of a choice cannot be evaluated exactly".into());
                    } else {
                        self.report(
                            Kind::Stuck,
                            &now,
                            "no branch of the choice is enabled: every guard is false".into(),
                        );
                    }
                    return Flow::Stop;
                }
                // The chooser's process decides among the branches it may take.
                let Some(picks) = self.process_picks(branches, enabled) else { return Flow::Stop };
                let k = self.rng.below(picks.len());
                self.walk(&branches[picks[k]])
            }
            Global::Msg(m) => self.message(m),
            Global::Motion(m) => self.motion(m),
            Global::Par(sides, _) => self.par(sides),
        }
    }

    pub(super) fn message(&mut self, m: &Msg) -> Flow {
        if self.steps >= self.cfg.steps {
            return Flow::Stop;
        }
        self.steps += 1;
        let prog = self.prog;
        let t = self.clock[m.from.idx()].clone().max(self.clock[m.to.idx()].clone());
        self.clock[m.from.idx()] = t.clone();
        self.clock[m.to.idx()] = t.clone();
        let who = format!("{} -> {} : {}", prog.role_name(m.from), prog.role_name(m.to), m.label);
        let fields: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
        if let Some(g) = &m.guard {
            if self.leaks(m.from, g, &[], &format!("the guard of `{who}`")) {
                return Flow::Stop;
            }
        }
        for f in &m.payload {
            if let Some(r) = &f.refinement {
                if self.leaks(m.from, r, &fields, &format!("the refinement of `{}` in `{who}`", f.name)) {
                    return Flow::Stop;
                }
            }
        }
        for id in &fields {
            self.known[m.from.idx()].insert(*id);
            self.known[m.to.idx()].insert(*id);
        }
        if let Some(g) = &m.guard {
            match self.holds(g) {
                Tri::True => {}
                Tri::False if self.has_process(m.from) => {
                    let msg = format!(
                        "the process of `{}` sends `{who}` although its guard is false",
                        prog.role_name(m.from)
                    );
                    self.report(Kind::Violation, &t, msg);
                    return Flow::Stop;
                }
                Tri::False => {
                    self.report(Kind::Stuck, &t, format!("`{who}`: its guard is false, and it is the only way on"));
                    return Flow::Stop;
                }
                Tri::Unknown => {
                    self.report(Kind::Undecided, &t, format!("`{who}`: its guard cannot be evaluated exactly"));
                    return Flow::Stop;
                }
            }
        }
        let mut shown = Vec::new();
        let mut rounded = false;
        let sent = match self.process_sends(m, &who) {
            Ok(sent) => sent,
            Err(()) => return Flow::Stop,
        };
        if let Some(vals) = sent {
            // The process's values, as the wire carries them; the type's refinements must
            // hold of them ([T-OUT]), decided.
            for (f, v) in m.payload.iter().zip(vals) {
                let (v, _) = super::on_wire(prog, f.value, v);
                shown.push(format!("{} = {v}", f.name));
                self.values.insert(f.value, v);
            }
            for f in &m.payload {
                let Some(r) = &f.refinement else { continue };
                let holds = self.holds(r);
                if holds == Tri::True {
                    continue;
                }
                let shown = shown.join(", ");
                if holds == Tri::False {
                    let msg = format!(
                        "the process of `{}` sends `{who}({shown})`, which breaks the refinement of `{}`",
                        prog.role_name(m.from),
                        f.name
                    );
                    self.report(Kind::Violation, &t, msg);
                } else {
                    let msg = format!("`{who}({shown})`: the refinement of `{}` cannot be evaluated exactly", f.name);
                    self.report(Kind::Undecided, &t, msg);
                }
                return Flow::Stop;
            }
        } else if !m.payload.is_empty() {
            // The refinements, with everything but this message's fields made concrete.
            let facts: Vec<Expr> =
                m.payload.iter().filter_map(|f| f.refinement.as_ref()).map(|e| self.close(e, &fields)).collect();
            let want: Vec<Expr> =
                m.payload.iter().map(|f| var_expr(Var::Value(f.value, f.name.clone()), f.sort.clone())).collect();
            let nudge = self.nudge(want.len());
            match self.sess.values_nudged(prog, &facts, &want, nudge) {
                Ok(Some(vs)) => {
                    for (f, v) in m.payload.iter().zip(vs) {
                        let (v, moved) = super::on_wire(prog, f.value, v);
                        rounded |= moved;
                        shown.push(format!("{} = {v}", f.name));
                        self.values.insert(f.value, v);
                    }
                }
                Ok(None) => {
                    self.report(Kind::Stuck, &t, format!("`{who}`: no payload satisfies its refinements"));
                    return Flow::Stop;
                }
                Err(why) => {
                    self.undecided(&t, &format!("`{who}`'s payload"), why);
                    return Flow::Stop;
                }
            }
            for f in &m.payload {
                if let Some(r) = &f.refinement {
                    if self.holds(r) == Tri::False && rounded {
                        let msg = format!("`{who}`'s payload: Z3's value rounded to the wire's float leaves the refinement of `{}` (the simulator draws real payloads)", f.name);
                        self.report(Kind::Undecided, &t, msg);
                        return Flow::Stop;
                    }
                    if self.holds(r) == Tri::False {
                        self.report(
                            Kind::Replay,
                            &t,
                            format!("`{who}`: Z3's payload does not satisfy the refinement of `{}` exactly", f.name),
                        );
                        return Flow::Stop;
                    }
                }
            }
        }
        let vals: Vec<Value> = m.payload.iter().filter_map(|f| self.values.get(&f.value).cloned()).collect();
        if !self.process_receives(m, &who, &vals) {
            return Flow::Stop;
        }
        self.trace.push(format!("t = {}: {who}({})", exact::decimal(&t), shown.join(", ")));
        Flow::Next
    }

    /// `e` with every participant variable and known value replaced by its value,
    /// except the value variables `keep`.
    pub(super) fn close(&self, e: &Expr, keep: &[ValueId]) -> Expr {
        map_vars(e, &mut |v, sort| match v {
            Var::Value(id, _) if keep.contains(id) => None,
            Var::Role(..) | Var::Value(..) => self.lookup(v).and_then(|val| value_expr(&val, sort, Loc::default())),
            _ => None,
        })
    }
}
