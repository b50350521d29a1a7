//! `mochi simulate`: an independent check of verdicts by running the choreography.
//!
//! The simulator walks the global type as Def 4.11 consumes it, on concrete states
//! (exact rationals, [`crate::exact`]):
//!
//! - **messages** happen in tree order, each as soon as its sender and receiver are
//!   free (a schedule consistent with happens-before); the guard is evaluated exactly and
//!   the payload is a model of the refinements (Z3, through [`crate::smt`]), replayed
//!   exactly;
//! - **choices** pick at random among the branches whose first guard holds;
//! - **recursion** is unrolled until the step budget is spent;
//! - **sides of `*`** run from the same time; each participant keeps its own clock, so
//!   their motions overlap in time as they would;
//! - **a joint motion** `dt<p_i: a_i>` checks each precondition exactly ([TRAJ-BASE]),
//!   then asks Z3 for a witness trajectory: an end time in every duration, states at a
//!   few random times satisfying every guarantee, assumption (inputs connected) and
//!   invariant, and every postcondition at the end ([TRAJ-STEP], [NON-INTERRUPT],
//!   [INTERRUPT], [M-PAR]). None means the motion cannot run to its end: stuck. The
//!   witness is replayed exactly.
//! - **footprints** are compared pairwise at the sampled times: the participants of a
//!   joint motion at each sample, and after a `*` every pair of motions of different
//!   sides at times where both run. A common point (Z3, at the concrete states, replayed
//!   exactly) is a collision.
//!
//! This is testing, not proof: it samples a few trajectories at a few times. A finding
//! in a choreography mochi verified is a bug in mochi (or in the contracts' reading);
//! no finding proves nothing. Participants that have finished a motion and wait for
//! their next event are not placed (they have no footprint then).

use crate::exact::{self, Num, Rat, Tri, Value};
use crate::hir::expr::map_vars;
use crate::hir::{
    Builtin, Expr, ExprKind, Global, Loc, Motion, Msg, PrimApp, Program, RoleId, Slot, Sort, ValueId, Var,
};
use crate::smt::goals::witness::{self, Mover, Occupant, Session};
use crate::smt::Why;
use num_bigint::BigInt;
use num_traits::{ToPrimitive, Zero};
use serde::Serialize;
use std::collections::HashMap;
use std::time::Duration;

/// How to simulate.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub runs: usize,
    pub seed: u64,
    /// Messages and motions per run (recursion is unrolled until they are spent).
    pub steps: usize,
    /// Times sampled in each motion (the end included).
    pub samples: usize,
    /// Per Z3 query.
    pub timeout: Duration,
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig { runs: 10, seed: 0, steps: 40, samples: 3, timeout: Duration::from_secs(10) }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Two footprints share a point.
    Collision,
    /// No step is possible and the protocol has not ended.
    Stuck,
    /// A guard, refinement or precondition is false where the type says it holds.
    Violation,
    /// A model that does not satisfy its own constraints when replayed exactly: a bug.
    Replay,
    /// Something the simulator could not decide (a timeout, an unsupported construct);
    /// the run stops there. Not a failure of the choreography.
    Undecided,
}

/// One thing found, in the user's terms.
#[derive(Clone, Debug, Serialize)]
pub struct Finding {
    pub kind: Kind,
    pub run: usize,
    pub step: usize,
    /// Global time (seconds since the start), as a decimal.
    pub time: String,
    pub message: String,
    /// The events of the run up to the finding, one per line.
    pub trace: Vec<String>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct SimReport {
    pub runs: usize,
    /// Messages and motions simulated, over all runs.
    pub steps: usize,
    pub queries: usize,
    pub findings: Vec<Finding>,
}

impl SimReport {
    /// Collisions, stuck states, violations and replay failures (not undecided runs).
    pub fn failures(&self) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(|f| f.kind != Kind::Undecided)
    }
}

/// Simulates `prog`'s choreography `cfg.runs` times.
pub fn simulate(prog: &Program, cfg: &SimConfig) -> SimReport {
    let mut report = SimReport { runs: cfg.runs, ..SimReport::default() };
    let Some(chor) = &prog.choreography else { return report };
    witness::session(cfg.timeout, |sess| {
        for run in 0..cfg.runs {
            let mut r = Runner::new(prog, sess, cfg, run);
            r.go(&chor.body);
            report.steps += r.steps;
            report.findings.extend(r.findings);
        }
        report.queries = sess.queries.get();
    });
    report
}

/// Resolves the file `root` already in `db` (its imports read through `load`, as
/// `driver::check_loaded` does) and simulates it. `Err` holds the errors that stopped it
/// before a program existed. (`fsload::simulate_file` reads a file from disk.)
pub fn simulate_loaded(
    db: &mut crate::source::SourceDb,
    root: crate::source::FileId,
    cfg: &SimConfig,
    load: &mut crate::syntax::Loader<'_>,
) -> Result<SimReport, Vec<crate::diag::Diagnostic>> {
    let (parsed, mut diags) = crate::syntax::parse_with_imports(db, root, load);
    if diags.iter().any(|d| d.is_error()) {
        return Err(diags);
    }
    let (prog, more) = crate::lower::lower(&parsed);
    diags.extend(more);
    if diags.iter().any(|d| d.is_error()) {
        return Err(diags);
    }
    Ok(simulate(&prog, cfg))
}

/// A small deterministic generator (SplitMix64): runs are reproducible from the seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    /// A rational in (0, 1) with denominator 1000.
    fn fraction(&mut self) -> Rat {
        Rat::new(BigInt::from(1 + self.next() % 999), BigInt::from(1000))
    }
}

/// What walking a global type ended with.
enum Flow {
    /// Fell off the end: the continuation runs next.
    Next,
    /// Reached `t(args)`.
    Jump(String, Vec<Value>),
    /// The run is over (`end`, the budget, or a finding).
    Stop,
}

/// A motion run by one participant, for comparing sides of `*`.
#[derive(Clone)]
struct Segment {
    role: RoleId,
    app: PrimApp,
    start: Vec<Value>,
    /// Global start and end time.
    /// The state at the end.
    end: Vec<Value>,
    /// The duration as the witness chose it (an enclosure when irrational); `to - from`
    /// is its midpoint.
    len: Num,
    from: Rat,
    to: Rat,
    inputs: Vec<Option<Value>>,
}

struct Runner<'a, 'p> {
    prog: &'p Program,
    sess: &'a Session<'a>,
    cfg: &'a SimConfig,
    run: usize,
    rng: Rng,
    /// Per participant, one value per state variable.
    state: Vec<Vec<Value>>,
    /// When each participant is next free.
    clock: Vec<Rat>,
    values: HashMap<ValueId, Value>,
    segments: Vec<Segment>,
    steps: usize,
    trace: Vec<String>,
    findings: Vec<Finding>,
    over: bool,
}

impl<'a, 'p> Runner<'a, 'p> {
    fn new(prog: &'p Program, sess: &'a Session<'a>, cfg: &'a SimConfig, run: usize) -> Runner<'a, 'p> {
        Runner {
            prog,
            sess,
            cfg,
            run,
            rng: Rng(cfg.seed.wrapping_mul(0x2545_F491_4F6C_DD1D).wrapping_add(run as u64)),
            state: Vec::new(),
            clock: vec![Rat::zero(); prog.roles.len()],
            values: HashMap::new(),
            segments: Vec::new(),
            steps: 0,
            trace: Vec::new(),
            findings: Vec::new(),
            over: false,
        }
    }

    /// Half the time, a variable to move off Z3's first model and by how much (up or
    /// down by up to 1, 0.1 or 0.01).
    fn nudge(&mut self, n: usize) -> Option<(usize, Rat)> {
        if n == 0 || self.rng.below(2) == 0 {
            return None;
        }
        let k = self.rng.below(n);
        let scale = [1, 10, 100][self.rng.below(3)];
        let d = self.rng.fraction() / Rat::from_integer(BigInt::from(scale));
        Some((k, if self.rng.below(2) == 0 { d } else { -d }))
    }

    fn report(&mut self, kind: Kind, time: &Rat, message: String) {
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

    fn undecided(&mut self, time: &Rat, what: &str, why: Why) {
        self.report(Kind::Undecided, time, format!("{what}: {why}"));
    }

    fn now(&self) -> Rat {
        self.clock.iter().max().cloned().unwrap_or_default()
    }

    fn go(&mut self, g: &Global) {
        if !self.init() {
            return;
        }
        let _ = self.walk(g);
    }

    /// Initial states: a model of each participant's `init` and invariant.
    fn init(&mut self) -> bool {
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
        self.trace.push(format!("t = 0: start; {}", states.join("; ")));
        true
    }

    fn show_state(&self, r: RoleId) -> String {
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
    fn lookup(&self, v: &Var) -> Option<Value> {
        match self.prog.source_of(v) {
            Var::Role(r, Slot::State(i)) => self.state.get(r.idx())?.get(i).cloned(),
            Var::Value(id, _) => self.values.get(&id).cloned(),
            _ => None,
        }
    }

    fn eval(&self, e: &Expr) -> Result<Value, String> {
        exact::eval(self.prog, e, &|v: &Var| self.lookup(v))
    }

    fn holds(&self, e: &Expr) -> Tri {
        exact::holds(self.prog, e, &|v: &Var| self.lookup(v))
    }

    fn walk(&mut self, g: &Global) -> Flow {
        if self.over {
            return Flow::Stop;
        }
        match g {
            Global::End(_) => Flow::Stop,
            Global::Var(v) => {
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
                    for (p, v) in params.iter().zip(&args) {
                        self.values.insert(p.value, v.clone());
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
                for b in branches {
                    let guard = first_message(b).and_then(|m| m.guard.as_ref());
                    match guard.map_or(Tri::True, |e| self.holds(e)) {
                        Tri::True => enabled.push(b),
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
                let k = self.rng.below(enabled.len());
                self.walk(enabled[k])
            }
            Global::Msg(m) => self.message(m),
            Global::Motion(m) => self.motion(m),
            Global::Par(sides, _) => self.par(sides),
        }
    }

    fn message(&mut self, m: &Msg) -> Flow {
        if self.steps >= self.cfg.steps {
            return Flow::Stop;
        }
        self.steps += 1;
        let prog = self.prog;
        let t = self.clock[m.from.idx()].clone().max(self.clock[m.to.idx()].clone());
        self.clock[m.from.idx()] = t.clone();
        self.clock[m.to.idx()] = t.clone();
        let who = format!("{} -> {} : {}", prog.role_name(m.from), prog.role_name(m.to), m.label);
        if let Some(g) = &m.guard {
            match self.holds(g) {
                Tri::True => {}
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
        if !m.payload.is_empty() {
            // The refinements, with everything but this message's fields made concrete.
            let fields: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
            let facts: Vec<Expr> =
                m.payload.iter().filter_map(|f| f.refinement.as_ref()).map(|e| self.close(e, &fields)).collect();
            let want: Vec<Expr> =
                m.payload.iter().map(|f| var_expr(Var::Value(f.value, f.name.clone()), f.sort.clone())).collect();
            let nudge = self.nudge(want.len());
            match self.sess.values_nudged(prog, &facts, &want, nudge) {
                Ok(Some(vs)) => {
                    for (f, v) in m.payload.iter().zip(vs) {
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
        self.trace.push(format!("t = {}: {who}({})", exact::decimal(&t), shown.join(", ")));
        Flow::Next
    }

    /// `e` with every participant variable and known value replaced by its value,
    /// except the value variables `keep`.
    fn close(&self, e: &Expr, keep: &[ValueId]) -> Expr {
        map_vars(e, &mut |v, sort| match v {
            Var::Value(id, _) if keep.contains(id) => None,
            Var::Role(..) | Var::Value(..) => self.lookup(v).and_then(|val| value_expr(&val, sort, Loc::default())),
            _ => None,
        })
    }

    fn motion(&mut self, m: &Motion) -> Flow {
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
        for (r, app) in &m.parts {
            let mut args = Vec::new();
            for a in &app.args {
                match self.eval(a).ok().and_then(|v| value_expr(&v, &a.sort, a.loc).map(|e| (v, e))) {
                    Some(x) => args.push(x),
                    None => {
                        self.report(Kind::Undecided, &t0, format!("{who}: an argument cannot be evaluated exactly"));
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
            let app = PrimApp { prim: app.prim, args: args.into_iter().map(|(_, e)| e).collect(), loc: app.loc };
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
        for i in 0..movers.len() {
            for j in i + 1..movers.len() {
                let zero = Num::int(0);
                let a = occupant(&movers[i], &movers[i].start, &zero);
                let b = occupant(&movers[j], &movers[j].start, &zero);
                if !self.collide(&a, &b, &t0, &who) {
                    return Flow::Stop;
                }
            }
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
            }
            for i in 0..movers.len() {
                for j in i + 1..movers.len() {
                    let a = occupant(&movers[i], &s.states[i], &s.time);
                    let b = occupant(&movers[j], &s.states[j], &s.time);
                    let t = &t0 + s.time.mid();
                    if !self.collide(&a, &b, &t, &who) {
                        return Flow::Stop;
                    }
                }
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

    fn arg_values(&self, app: &PrimApp) -> Vec<Value> {
        app.args.iter().filter_map(|a| exact::eval(self.prog, a, &|_: &Var| None).ok()).collect()
    }

    /// Input values of mover `i` at a sample: the source's sampled state when it moves
    /// in the same motion, else the fixed value.
    fn inputs_at(&self, movers: &[Mover], i: usize, states: &[Vec<Value>]) -> Vec<Option<Value>> {
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

    /// Compares two footprints; false when the run must stop (a finding was made).
    fn collide(&mut self, a: &Occupant, b: &Occupant, t: &Rat, context: &str) -> bool {
        let prog = self.prog;
        let (pa, pb) = (prog.prim(a.app.prim), prog.prim(b.app.prim));
        if pa.footprint.predicate().is_none() || pb.footprint.predicate().is_none() {
            let who = if pa.footprint.predicate().is_none() { a } else { b };
            self.report(
                Kind::Collision,
                t,
                format!(
                    "{context}: `{}` ({}) declares no footprint, so it fills all space",
                    prog.prim(who.app.prim).name,
                    prog.role_name(who.role)
                ),
            );
            return false;
        }
        match self.sess.overlap(prog, a, b) {
            Ok(None) => true,
            Ok(Some(p)) => {
                // Replay: the point must lie in both footprints, exactly (pose rotations
                // by enclosures, so a rotated point may be undecided, never wrongly false).
                let inside = [a, b].map(|o| self.in_footprint(o, &p));
                let point = format!("({}, {}, {})", p[0], p[1], p[2]);
                if inside.contains(&Tri::False) {
                    self.report(
                        Kind::Replay,
                        t,
                        format!("{context}: Z3's common point {point} of two footprints is not in both when replayed exactly"),
                    );
                } else {
                    self.report(
                        Kind::Collision,
                        t,
                        format!(
                            "{context}: the footprints of `{}` ({}: {}) and `{}` ({}: {}) share the point {point} at time {}",
                            pa.name,
                            prog.role_name(a.role),
                            show_values(prog, a.role, &a.now),
                            pb.name,
                            prog.role_name(b.role),
                            show_values(prog, b.role, &b.now),
                            exact::decimal(t)
                        ),
                    );
                }
                false
            }
            Err(why) => {
                self.undecided(t, &format!("{context}: comparing footprints"), why);
                false
            }
        }
    }

    /// Whether the world point `p` is in `o`'s footprint, evaluated exactly.
    fn in_footprint(&self, o: &Occupant, p: &[Num; 3]) -> Tri {
        let prog = self.prog;
        let Some(fp) = prog.prim(o.app.prim).footprint.predicate() else { return Tri::True };
        let Some(local) = crate::smt::replay::to_local(prog, o.role, p) else { return Tri::Unknown };
        let args = self.arg_values(&o.app);
        let env = frame_env(&o.now, &o.start, &args, &o.clock, &[]);
        let env = |v: &Var| match v {
            Var::Point(k) => local.get(*k).cloned().map(Value::Num),
            other => env(other),
        };
        exact::holds(prog, &fp.pred, &env)
    }

    /// `g1 * ... * gn`: each side from the same moment, then every pair of motions of
    /// different sides compared at times where both run.
    fn par(&mut self, sides: &[Global]) -> Flow {
        let mut ranges = Vec::new();
        let mut order: Vec<usize> = (0..sides.len()).collect();
        // Visit the sides in a random order (they do not interact).
        for i in (1..order.len()).rev() {
            let j = self.rng.below(i + 1);
            order.swap(i, j);
        }
        let mut stop = false;
        for &k in &order {
            let from = self.segments.len();
            match self.walk(&sides[k]) {
                Flow::Next => {}
                _ => stop = true,
            }
            ranges.push(from..self.segments.len());
            if self.over {
                return Flow::Stop;
            }
        }
        // An interruptible motion lasts until its participant's next event ([INTERRUPT]):
        // a side that finishes early keeps moving until the `*` ends.
        let end = ranges.iter().flat_map(|r| self.segments[r.clone()].iter().map(|s| s.to.clone())).max();
        if let Some(end) = end {
            for i in ranges.iter().flat_map(|r| r.clone()) {
                if !self.extend(i, &end) {
                    return Flow::Stop;
                }
            }
        }
        for a in 0..ranges.len() {
            for b in a + 1..ranges.len() {
                for i in ranges[a].clone() {
                    for j in ranges[b].clone() {
                        if !self.compare_segments(i, j) {
                            return Flow::Stop;
                        }
                    }
                }
            }
        }
        if stop {
            return Flow::Stop;
        }
        // The continuation goes on with each participant's own clock: a message waits
        // only for its sender and receiver.
        Flow::Next
    }

    /// Extends segment `i` to `end` when its motion is interruptible and is its
    /// participant's latest: a new witness ending then, if the contract allows one
    /// (otherwise it ends as first chosen). False when the run must stop.
    fn extend(&mut self, i: usize, end: &Rat) -> bool {
        let s = self.segments[i].clone();
        if !self.prog.prim(s.app.prim).interruptible || s.to >= *end || self.clock[s.role.idx()] != s.to {
            return true;
        }
        let len = end - &s.from;
        let mover = Mover { role: s.role, app: s.app.clone(), start: s.start.clone(), inputs: s.inputs.clone() };
        let one = [Rat::from_integer(BigInt::from(1))];
        match self.sess.trajectory(self.prog, std::slice::from_ref(&mover), &one, Some(&Num::exact(len.clone()))) {
            Ok(Some(tr)) => {
                if let Some(state) = tr.samples.first().and_then(|x| x.states.first()) {
                    self.state[s.role.idx()] = state.clone();
                    self.clock[s.role.idx()] = end.clone();
                    let seg = &mut self.segments[i];
                    seg.end = state.clone();
                    seg.to = end.clone();
                    seg.len = Num::exact(len);
                    let line = format!(
                        "t = {}: `{}` ({}) kept running until then (interruptible); {}",
                        exact::decimal(end),
                        self.prog.prim(s.app.prim).name,
                        self.prog.role_name(s.role),
                        self.show_state(s.role)
                    );
                    self.trace.push(line);
                }
                true
            }
            // Not a stuck state: the participant's next message need not wait for the
            // other sides (happens-before orders it after its own side only), so running
            // this long is one possible execution, not a forced one.
            Ok(None) => true,
            Err(why) => {
                self.undecided(end, "extending an interruptible motion", why);
                false
            }
        }
    }

    /// Two motions of different sides of `*`: at a few times where both run, a state of
    /// each (a witness from its contract at that time) and their footprints compared.
    fn compare_segments(&mut self, i: usize, j: usize) -> bool {
        let (x, y) = (self.segments[i].clone(), self.segments[j].clone());
        let lo = x.from.clone().max(y.from.clone());
        let hi = x.to.clone().min(y.to.clone());
        if lo > hi {
            return true;
        }
        let mut times = vec![lo.clone(), hi.clone()];
        let f = self.rng.fraction();
        times.push(&lo + (&hi - &lo) * f);
        times.dedup();
        for t in times {
            let mut occ = Vec::new();
            for s in [&x, &y] {
                match self.state_at(s, &t) {
                    Some(o) => occ.push(o),
                    None => return false,
                }
            }
            let context = format!(
                "`{}` ({}) and `{}` ({}) on different sides of `*`",
                self.prog.prim(x.app.prim).name,
                self.prog.role_name(x.role),
                self.prog.prim(y.app.prim).name,
                self.prog.role_name(y.role)
            );
            if !self.collide(&occ[0], &occ[1], &t, &context) {
                return false;
            }
        }
        true
    }

    /// A state of a segment's motion at global time `t` (a witness of its contract).
    fn state_at(&mut self, s: &Segment, t: &Rat) -> Option<Occupant> {
        let len = &s.to - &s.from;
        let clock = t - &s.from;
        let mover = Mover { role: s.role, app: s.app.clone(), start: s.start.clone(), inputs: s.inputs.clone() };
        if clock.is_zero() {
            return Some(occupant(&mover, &s.start, &Num::int(0)));
        }
        if clock >= len {
            return Some(occupant(&mover, &s.end, &s.len));
        }
        let fracs = vec![&clock / &len, Rat::from_integer(BigInt::from(1))];
        match self.sess.trajectory(self.prog, std::slice::from_ref(&mover), &fracs, Some(&s.len)) {
            Ok(Some(tr)) => {
                let sample = tr.samples.first()?;
                Some(occupant(&mover, &sample.states.first()?.clone(), &sample.time))
            }
            Ok(None) => {
                self.report(
                    Kind::Stuck,
                    t,
                    format!(
                        "`{}` ({}) has no state at this time of its motion",
                        self.prog.prim(s.app.prim).name,
                        self.prog.role_name(s.role)
                    ),
                );
                None
            }
            Err(why) => {
                self.undecided(t, "a state within a side of `*`", why);
                None
            }
        }
    }
}

fn occupant(m: &Mover, now: &[Value], clock: &Num) -> Occupant {
    Occupant { role: m.role, app: m.app.clone(), start: m.start.clone(), now: now.to_vec(), clock: clock.clone() }
}

fn show_values(prog: &Program, r: RoleId, vals: &[Value]) -> String {
    let kind = prog.kind_of(r);
    let v: Vec<String> = kind.state.iter().zip(vals).map(|((n, _), v)| format!("{n} = {v}")).collect();
    v.join(", ")
}

/// The environment of a primitive's contract: own state now (and inputs), `old`, the
/// arguments and the clock.
fn frame_env<'v>(
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

/// The first message of a branch of a choice.
fn first_message(g: &Global) -> Option<&Msg> {
    match g {
        Global::Msg(m) => Some(m),
        Global::Seq(items, _) => items.first().and_then(first_message),
        _ => None,
    }
}

fn var_expr(v: Var, sort: Sort) -> Expr {
    Expr { kind: ExprKind::Var(v), sort, loc: Loc::default() }
}

/// `Var::Own(slot)` as participant `r`'s variable (for the kind's invariant at `init`).
fn own_to_role(e: &Expr, r: RoleId) -> Expr {
    map_vars(e, &mut |v, sort| match v {
        Var::Own(slot) => {
            Some(Expr { kind: ExprKind::Var(Var::Role(r, *slot)), sort: sort.clone(), loc: Loc::default() })
        }
        _ => None,
    })
}

/// A value as a closed expression of `sort`; `None` for an enclosure (not exact).
fn value_expr(v: &Value, sort: &Sort, loc: Loc) -> Option<Expr> {
    let num = |n: &Num| n.value().map(|r| exact::literal(r, loc));
    Some(match v {
        Value::Bool(Tri::True) => Expr::bool(true, loc),
        Value::Bool(Tri::False) => Expr::bool(false, loc),
        Value::Bool(Tri::Unknown) => return None,
        Value::Num(n) => {
            let r = n.value()?;
            if *sort == Sort::Int && r.is_integer() {
                Expr { kind: ExprKind::Int(r.numer().to_i64()?), sort: Sort::Int, loc }
            } else {
                num(n)?
            }
        }
        Value::Vec3(c) => {
            let f = if *sort == Sort::Vector { Builtin::Vector } else { Builtin::Point };
            let args = vec![num(&c[0])?, num(&c[1])?, num(&c[2])?];
            Expr {
                kind: ExprKind::Call(f, args),
                sort: if *sort == Sort::Vector { Sort::Vector } else { Sort::Point },
                loc,
            }
        }
    })
}
