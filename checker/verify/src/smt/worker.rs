//! The workers of [`super::discharge`]: each decides obligations from the pool, part by
//! part, through the caches, the guesses and Z3 under the time limit.

use super::describe::describe;
use super::*;

mod witness;

/// What the workers of one [`discharge`] share besides the pool.
#[derive(Default)]
pub(super) struct Caches {
    /// Answers by query text (exact, and up to renaming).
    cache: Mutex<HashMap<String, Answer>>,
    /// The vacuity guard's answers, by hypotheses.
    contexts: Mutex<HashMap<Vec<Expr>, Answer>>,
    /// Primitives some obligation has shown able to end: a `dt` whose can-end question had a
    /// witness, or a refinement whose concrete primitive was realisable.
    witnessed: Mutex<HashSet<crate::hir::PrimId>>,
    /// Queries dumped so far (numbers the dump labels).
    dumped: AtomicUsize,
    /// Set when the dump sink failed: nothing more is dumped.
    dump_failed: AtomicBool,
}

/// One worker: decides obligations from the pool until there are none.
pub(super) fn work(lease: &pool::Lease<Caches>) {
    let sh = lease.shared;
    let w = Worker {
        prog: &sh.prog,
        cfg: &sh.cfg,
        caches: &sh.extra,
        labels: &sh.labels,
        watchdog: lease.watchdog,
        timeout: sh.cfg.timeout,
    };
    while let Some(i) = lease.take() {
        let ob = &sh.obligations[i];
        let t = std::time::Instant::now();
        let (d, mut st) = match &ob.goal {
            // A primitive's contract (E0409) is witnessed by any use of it that
            // could end (the driver puts these obligations last).
            Goal::CanEnd { prim }
                if ob.rule == crate::obligation::Rule::Contract
                    && !sh.cfg.no_cache
                    && sh.extra.witnessed.lock().is_ok_and(|w| w.contains(prim)) =>
            {
                (Decision::Holds(None), Stats { folded: 1, ..Stats::default() })
            }
            _ => w.decide(i, ob),
        };
        if matches!(d, Decision::Holds(_)) && st.vacuous == 0 {
            let shown = witnesses(ob);
            if !shown.is_empty() {
                if let Ok(mut w) = sh.extra.witnessed.lock() {
                    w.extend(shown);
                }
            }
        }
        st.millis = t.elapsed().as_secs_f64() * 1000.0;
        lease.finish(i, (d, st));
    }
}

/// The primitives whose contracts an obligation that held non-vacuously has shown able to
/// end: every part of a `dt` (its joint can-end question had a witness), and the concrete
/// primitive of a refinement (its realisability question had one). Not a primitive refining
/// itself: that holds without the question.
fn witnesses(ob: &Obligation) -> Vec<crate::hir::PrimId> {
    match &ob.goal {
        Goal::Compatible { parts } => parts.iter().map(|(_, a)| a.prim).collect(),
        Goal::Refines { concrete, abstract_, .. } if abstract_.as_slice() != std::slice::from_ref(concrete) => {
            vec![concrete.prim]
        }
        _ => Vec::new(),
    }
}

/// A cached answer to one query.
#[derive(Clone)]
enum Answer {
    Unsat,
    /// `exact`: the model's values as rationals, for [`replay`]; `bound`: where each of
    /// two same-named values in the model is bound.
    Sat {
        values: Vec<Assignment>,
        overlap: Option<Overlap>,
        bound: Vec<(String, String, crate::source::Span)>,
        exact: replay::Valuation,
    },
    Unknown(Why),
}

#[derive(Clone, Copy)]
struct Worker<'a> {
    prog: &'a Program,
    cfg: &'a SmtConfig,
    caches: &'a Caches,
    labels: &'a [String],
    watchdog: &'a Watchdog,
    /// Per query: the configuration's, or less for a first quick pass
    /// ([`Worker::contains_turning`]).
    timeout: Duration,
}

/// The first pass's limit per query for body containment with a footprint that turns with
/// the state ([`Worker::contains_turning`]).
const QUICK: Duration = Duration::from_secs(1);

/// An undecided body containment with a footprint that turns with the state, its reason made
/// precise where the interval search finds states at which a point of the body is outside
/// the footprint (`space::enclose::body_outside_somewhere`): still unknown (whether the
/// contract allows such a state is not decided), never a rejection.
fn sticks_out(prog: &Program, prim: crate::hir::PrimId, d: Decision) -> Decision {
    match d {
        Decision::Unknown { part, why } => match crate::space::enclose::body_outside_somewhere(prog, prim) {
            Some(found) => Decision::Unknown { part, why: Why::Interval(format!("{found} ({why})")) },
            None => Decision::Unknown { part, why },
        },
        d => d,
    }
}

impl Worker<'_> {
    /// Decides one obligation: every part must hold. A failing part wins over an
    /// unknown one (it is a definite answer).
    fn decide(&self, index: usize, ob: &Obligation) -> (Decision, Stats) {
        if let Goal::Contains { prim } = ob.goal {
            if crate::space::enclose::turns(self.prog, prim) && !ob.trivially_holds() {
                return self.contains_turning(index, ob, prim);
            }
        }
        self.decide_parts(index, ob)
    }

    /// Body containment (E0512) with a footprint that turns with the state (its `cos`/`sin`,
    /// or the body's): first the interval search of `space::enclose` with a small budget
    /// (a footprint affine in the body's point, such as a square turned with the heading
    /// around a disc, is decided in a few hundred pieces, milliseconds); then Z3 for at most
    /// [`QUICK`] per query (most other such questions are linear once the heading is fixed,
    /// and answered in milliseconds); then, if the first search only ran out of pieces, the
    /// search with its full budget (about a second); then Z3 again with the full limit.
    /// Between the first search and Z3, the refutation of `space::enclose::body_outside`
    /// (a point of the body outside the footprint at every allowed state).
    /// Every answer is one of the procedures', each sound on its own.
    fn contains_turning(&self, index: usize, ob: &Obligation, prim: crate::hir::PrimId) -> (Decision, Stats) {
        use crate::space::enclose::{body_in_predicate, BUDGET, QUICK_BUDGET};
        let first = body_in_predicate(self.prog, prim, QUICK_BUDGET);
        let mut stats = Stats::default();
        let retry = match first {
            Ok(note) => {
                stats.geometric += 1;
                return (Decision::Holds(Some(note)), stats);
            }
            Err(u) => u.ran_out,
        };
        // The other direction, by the same interval truth: a point of the body outside the
        // footprint at every state the contract allows.
        if let Some(why) = crate::space::enclose::body_outside(self.prog, prim) {
            stats.geometric += 1;
            let failure = Failure { part: why, which: None, values: Vec::new(), overlap: None, bound: Vec::new() };
            return (Decision::Fails(failure), stats);
        }
        let quick = Worker { timeout: self.timeout.min(QUICK), ..*self };
        let (d, more) = quick.decide_parts(index, ob);
        stats.add(&more);
        if !matches!(d, Decision::Unknown { .. }) {
            return (d, stats);
        }
        if retry {
            if let Ok(note) = body_in_predicate(self.prog, prim, BUDGET) {
                stats.geometric += 1;
                return (Decision::Holds(Some(note)), stats);
            }
        }
        if quick.timeout == self.timeout {
            return (sticks_out(self.prog, prim, d), stats);
        }
        let (d, more) = self.decide_parts(index, ob);
        stats.add(&more);
        (sticks_out(self.prog, prim, d), stats)
    }

    fn decide_parts(&self, index: usize, ob: &Obligation) -> (Decision, Stats) {
        let mut stats = Stats::default();
        if ob.trivially_holds() {
            stats.folded += 1;
            return (Decision::Holds(None), stats);
        }
        let parts = match goals::plan(self.prog, ob) {
            Plan::Holds(note) => {
                stats.folded += 1;
                return (Decision::Holds(note), stats);
            }
            Plan::Fails(why) => {
                return (
                    Decision::Fails(Failure {
                        part: why,
                        which: None,
                        values: Vec::new(),
                        overlap: None,
                        bound: Vec::new(),
                    }),
                    stats,
                );
            }
            Plan::Unknown(Unsupported(what)) => {
                return (Decision::Unknown { part: String::new(), why: Why::Unsupported(what) }, stats);
            }
            Plan::Undecided(why) => return (Decision::Unknown { part: String::new(), why }, stats),
            Plan::Parts(parts) => parts,
        };
        let mut unknown = None;
        // E0243's example: a model of the context without the field's entry predicate.
        let mut admitted: Option<Vec<Assignment>> = None;
        // Set when a part held only because Σ is unsatisfiable; `sat` when a part's
        // witness showed Σ satisfiable (a sat question asked with all of Σ).
        let mut vacuous = false;
        let mut sat = false;
        for (k, part) in parts.iter().enumerate() {
            let answer = self.ask(ob, index, k, part, &mut stats);
            if part.is_sat_question() {
                // Satisfiable means it holds (a witness exists); unsat fails, unless the
                // point itself cannot be reached (an earlier step is to blame).
                let fails = match (answer, part) {
                    (Answer::Sat { .. }, _) => {
                        sat |= matches!(part, Part::CanEnd | Part::CanStart | Part::Context);
                        continue;
                    }
                    (Answer::Unknown(why), _) => {
                        unknown.get_or_insert((describe(self.prog, ob, part), why));
                        continue;
                    }
                    // A joint motion that cannot end: stuck if it can start. If it cannot,
                    // a precondition contradicts the context (the pre part's or
                    // [T-MOTION]'s to report), or Σ itself is unsatisfiable.
                    (Answer::Unsat, Part::CanEnd) => {
                        let mut fails = false;
                        for next in [Part::CanStart, Part::Context] {
                            match self.ask(ob, index, k, &next, &mut stats) {
                                Answer::Sat { .. } => {
                                    fails = next == Part::CanStart;
                                    break;
                                }
                                Answer::Unsat => vacuous = next == Part::Context,
                                Answer::Unknown(why) => {
                                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                                    break;
                                }
                            }
                        }
                        fails
                    }
                    // Σ after a step is unsatisfiable: the step is to blame when every
                    // context before it is satisfiable.
                    (Answer::Unsat, Part::Context) => {
                        let Goal::Reachable { before, .. } = &ob.goal else { continue };
                        let mut blame = true;
                        for b in 0..before.len() {
                            match self.ask(ob, index, k, &Part::Before(b), &mut stats) {
                                // An enum-typed field (E0243): the context without its entry
                                // predicate has a model, whose value of the field is one the
                                // refinement admits and the enum does not: the example shown
                                // (in the failure's text: it falsifies no goal of its own, so
                                // it is not a counterexample).
                                Answer::Sat { values, .. } if ob.rule == crate::obligation::Rule::EnumEntry => {
                                    admitted = Some(values);
                                }
                                Answer::Sat { .. } => {}
                                // An `init` that no state satisfies, invariant or not.
                                Answer::Unsat if ob.rule == crate::obligation::Rule::InitInvariant => {
                                    let which = Some(Part::Before(b));
                                    let part = format!("some state satisfies {}", ob.what);
                                    return (
                                        Decision::Fails(Failure {
                                            part,
                                            which,
                                            values: Vec::new(),
                                            overlap: None,
                                            bound: Vec::new(),
                                        }),
                                        stats,
                                    );
                                }
                                Answer::Unsat => blame = false,
                                Answer::Unknown(why) => {
                                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                                    blame = false;
                                }
                            }
                        }
                        if !blame {
                            vacuous = true;
                        }
                        blame
                    }
                    (Answer::Unsat, _) => true,
                };
                if fails {
                    let which = Some(part.clone());
                    let mut part = describe(self.prog, ob, part);
                    if let Some(values) = admitted.take().filter(|v| !v.is_empty()) {
                        let shown: Vec<String> = values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                        part =
                            format!("{part}; the refinement admits, for example, {}, and no entry", shown.join(", "));
                    }
                    return (
                        Decision::Fails(Failure { part, which, values: Vec::new(), overlap: None, bound: Vec::new() }),
                        stats,
                    );
                }
                continue;
            }
            match answer {
                Answer::Unsat => {}
                Answer::Sat { mut values, mut overlap, mut bound, exact } => {
                    // A counterexample is shown only if, evaluated exactly, it falsifies
                    // the part's own goal; one that does not is unknown, never a failure
                    // (the geometric procedure's contact is parry's, replayed there).
                    let geometric = crate::collision::applies(self.prog, ob, part);
                    let mut replayed =
                        if geometric { replay::Replay::Falsifies } else { replay::replay(self.prog, ob, part, &exact) };
                    // A hypothesis `float32(v)` is weakened to `true` in the encoding, so a
                    // model may give a MAVLink float a value no float has: ask again with
                    // each float value pinned to its value rounded to the field's format,
                    // and keep that model if it replays.
                    if !geometric && !matches!(replayed, replay::Replay::Falsifies) {
                        if let Some(Answer::Sat { values: v, overlap: o, bound: b, exact: e }) =
                            self.float_witness(ob, part, &exact, &mut stats)
                        {
                            if matches!(replay::replay(self.prog, ob, part, &e), replay::Replay::Falsifies) {
                                (values, overlap, bound, replayed) = (v, o, b, replay::Replay::Falsifies);
                            }
                        }
                    }
                    let why = match replayed {
                        replay::Replay::Falsifies => None,
                        // A float hypothesis (weakened to `true` in the encoding) the
                        // model breaks, and no model with the floats rounded to their
                        // format completes a counterexample (`float_witness`).
                        replay::Replay::Refuted(why) if why.contains("`float32(") || why.contains("`float64(") => Some(format!("its model gives a MAVLink float a value its format does not hold ({why}), and no model with the floats rounded to their format falsifies the goal: the encoding weakens `float32(v)` in hypotheses, so the question stays open")),
                        replay::Replay::Refuted(why) => Some(format!("its model does not falsify the goal in exact arithmetic ({why}); the encoding's enclosure of a pose turned by an angle that is not an exact multiple of `pi / 2` admits such models, otherwise please report this as a bug in mochi")),
                        replay::Replay::Undecided(why) => Some(format!("its model is not confirmed as a counterexample in exact arithmetic ({why}): the encoding's enclosures (of a pose's rotation, `sin`, `cos`, `sqrt`) may admit it where the real functions do not")),
                    };
                    if let Some(why) = why {
                        unknown.get_or_insert((describe(self.prog, ob, part), Why::Incomplete(why, Hard::default())));
                        continue;
                    }
                    // A joint motion's footprints: look for an earlier meeting, and
                    // prove a time before which they do not meet.
                    // (Not after the interval search: its questions are the ones Z3's
                    // nonlinear arithmetic does not decide.)
                    let interval = crate::collision::predicate::applies(self.prog, ob, part);
                    if !geometric && !interval && matches!(ob.goal, Goal::Compatible { .. }) {
                        if let Some(found) = overlap.as_ref().and_then(|o| o.times.first().copied()) {
                            let (not_before, better) = self.earliest(ob, part, found, &mut stats);
                            if let Some(Answer::Sat { values: v, overlap: o, bound: b, .. }) = better {
                                (values, overlap, bound) = (v, o, b);
                            }
                            if let Some(o) = overlap.as_mut() {
                                o.not_before = not_before;
                                let undecided = not_before.is_none() && o.times.first().is_some_and(|t| *t > 0.0);
                                o.earliest_open = undecided.then(|| "whether they meet at the motion's start was not decided (by Z3 within the time limit, with a model that replays exactly)".into());
                            }
                        }
                    }
                    let which = Some(part.clone());
                    // Say which engine found it: Z3's model, or the geometric procedure's
                    // contact (parry, at a configuration a Z3 model of the contracts gave).
                    let engine = if geometric {
                        " [found by the geometric procedure: parry's contact at a state and time Z3 showed the contracts allow]"
                    } else if interval {
                        " [found by the interval search: a point of the obstacle inside the footprint at a state and time it found, completed by Z3 and replayed exactly]"
                    } else {
                        ""
                    };
                    let part = format!("{}{engine}", describe(self.prog, ob, part));
                    return (Decision::Fails(Failure { part, which, values, overlap, bound }), stats);
                }
                Answer::Unknown(why) => {
                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                }
            }
        }
        if let Some((part, why)) = unknown {
            return (Decision::Unknown { part, why }, stats);
        }
        // The vacuity guard: an obligation proved from hypotheses proved nothing if the
        // hypotheses are unsatisfiable. One query per distinct context (cached by its
        // text, up to renaming); the obligations that ask about Σ itself need none.
        // Separation's queries use the contexts of its runs' `dt`s (whose can-end witness
        // shows them satisfiable), [T-SESS]'s the initial states (checked on their own).
        let covered = matches!(
            ob.goal,
            Goal::Reachable { .. }
                | Goal::CanEnd { .. }
                | Goal::Occupies { .. }
                | Goal::Separated { .. }
                | Goal::InitiallyDisjoint { .. }
        );
        if !vacuous && !sat && !covered && !ob.hyps.is_empty() {
            // Obligations with the same hypotheses share the answer.
            let context = goals::context_of(self.prog, ob);
            let known = if self.cfg.no_cache {
                None
            } else {
                self.caches.contexts.lock().ok().and_then(|c| c.get(&context).cloned())
            };
            let answer = match known {
                Some(a) => {
                    stats.cached += 1;
                    a
                }
                None => {
                    let a = self.ask(ob, index, parts.len(), &Part::Context, &mut stats);
                    if !self.cfg.no_cache && !matches!(a, Answer::Unknown(Why::Timeout(..))) {
                        if let Ok(mut c) = self.caches.contexts.lock() {
                            c.insert(context, a.clone());
                        }
                    }
                    a
                }
            };
            match answer {
                Answer::Unsat => vacuous = true,
                Answer::Sat { .. } => {}
                // Undecided: the obligation's proof stands; only the count is unsure.
                Answer::Unknown(_) => stats.unsure += 1,
            }
        }
        if vacuous {
            stats.vacuous += 1;
        }
        (Decision::Holds(None), stats)
    }

    /// Bisects the time of a joint motion's footprint meeting found at `found` s: each
    /// step asks the part's query with `time <= mid`. Unsat proves the footprints do not
    /// meet at or before `mid` (the encoding encloses, so its unsat is sound); a model
    /// that replays exactly is an earlier meeting and replaces the counterexample. Returns
    /// the proved bound (if any) and the earliest replayed model found (if any). A few
    /// steps only, each with the query's limit; an undecided step ends the search.
    fn earliest(&self, ob: &Obligation, part: &Part, found: f64, stats: &mut Stats) -> (Option<f64>, Option<Answer>) {
        const STEPS: usize = 6;
        let Ok(q) = goals::build(self.prog, ob, part) else { return (None, None) };
        let Some(time) = q.times.first().cloned() else { return (None, None) };
        let solver = solver_for(&q);
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            solver.assert(a);
        }
        let (mut lo, mut hi) = (None::<f64>, found);
        let mut best = None;
        for step in 0..STEPS {
            // First whether they meet at the motion's start, then halves.
            let mid = if step == 0 { 0.0 } else { (lo.unwrap_or(0.0) + hi) / 2.0 };
            if !mid.is_finite() || mid >= hi {
                break;
            }
            let Some(bound) = encode::real_of_f64(mid) else { break };
            solver.push();
            solver.assert(time.le(&bound));
            stats.queries += 1;
            let seq = self.watchdog.arm(self.timeout);
            let result = solver.check();
            let timed_out = self.watchdog.disarm(seq);
            let model = if matches!(result, z3::SatResult::Sat) { solver.get_model() } else { None };
            solver.pop(1);
            match (result, model) {
                (z3::SatResult::Unsat, _) if !timed_out => lo = Some(mid),
                (z3::SatResult::Sat, Some(m)) if !q.enc.spurious_trig(&m) => {
                    let exact = replay::valuation(&q.enc, &m);
                    if !matches!(replay::replay(self.prog, ob, part, &exact), replay::Replay::Falsifies) {
                        break;
                    }
                    let at = encode::Encoder::value_of(&m, &time).unwrap_or(f64::NAN);
                    if at.is_nan() || at > mid {
                        break;
                    }
                    hi = at;
                    let overlap = q.point.as_ref().map(|p| {
                        Overlap::at(
                            [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                            q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
                        )
                    });
                    best = Some(Answer::Sat {
                        values: q.enc.assignments(&m),
                        overlap,
                        bound: q.enc.shared_names(),
                        exact,
                    });
                }
                _ => break,
            }
        }
        (lo, best)
    }

    /// Builds and solves one part's query.
    fn ask(&self, ob: &Obligation, index: usize, k: usize, part: &Part, stats: &mut Stats) -> Answer {
        // A context is often shown satisfiable without Z3, by a point that satisfies it.
        let context = match (part, &ob.goal) {
            (Part::Context, _) => Some(goals::context_of(self.prog, ob)),
            (Part::Before(b), Goal::Reachable { before, .. }) => before.get(*b).cloned(),
            _ => None,
        };
        // (Not for the context before an enum-typed field's entry predicate, E0243: asked
        // only when the field fails, and its model is the example the report shows.)
        let example = ob.rule == crate::obligation::Rule::EnumEntry && matches!(part, Part::Before(_));
        if !example && context.is_some_and(|c| goals::witnessed(self.prog, &c)) {
            return Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() };
        }
        // Bodies the solver cannot represent (URDF links, meshes, a participant riding on
        // another): the geometric procedure, Z3 asked only for witnesses.
        if crate::collision::applies(self.prog, ob, part) {
            stats.geometric += 1;
            return match crate::collision::decide(self.prog, ob, part, self.timeout) {
                crate::collision::GeoAnswer::Apart => Answer::Unsat,
                crate::collision::GeoAnswer::Contact { values, overlap } => {
                    Answer::Sat { values, overlap: Some(overlap), bound: Vec::new(), exact: Default::default() }
                }
                crate::collision::GeoAnswer::Unknown(why) => Answer::Unknown(Why::Search(why)),
            };
        }
        // A footprint predicate turned by the state against an obstacle: the interval
        // search over the obstacle's points and the state, Z3 asked only to complete a
        // candidate into a counterexample (`collision::predicate`).
        let mut pinned = 0;
        let time_of = |a: &Answer| match a {
            Answer::Sat { overlap: Some(o), .. } => o.times.first().copied(),
            _ => None,
        };
        let mut pin = |pins: &crate::collision::predicate::Pins| {
            pinned += 1;
            self.pinned_witness(ob, part, pins)
        };
        let found = crate::collision::predicate::decide(self.prog, ob, part, self.timeout, &mut pin, &time_of);
        if let Some(found) = found {
            stats.geometric += 1;
            stats.queries += pinned;
            return match found {
                crate::collision::predicate::Found::Apart => Answer::Unsat,
                crate::collision::predicate::Found::Contact((mut a, early)) => {
                    if let Answer::Sat { overlap: Some(o), .. } = &mut a {
                        (o.not_before, o.earliest_open) = (early.not_before, early.open);
                    }
                    a
                }
                crate::collision::predicate::Found::Undecided(why) => Answer::Unknown(Why::Interval(format!(
                    "the footprint against obstacle `{}`: {why}",
                    match part {
                        Part::ClearOf { o, .. } => self.prog.obstacles.get(*o).map_or("?", |x| x.name.as_str()),
                        _ => "?",
                    }
                ))),
            };
        }
        // A payload float chosen by the progress check: first with integer witnesses
        // only, a stronger question Z3 decides quickly; its unsat proves the part, and
        // anything else leaves the exact question to ask.
        let chooses = matches!(ob.goal, Goal::Progress { .. }) && !self.prog.wire_floats.is_empty();
        if let Some(Ok(q)) = chooses.then(|| goals::build_integer_witnesses(self.prog, ob, part)).flatten() {
            stats.queries += 1;
            if matches!(self.solve(q, index, k, false, false, stats), Answer::Unsat) {
                return Answer::Unsat;
            }
        }
        stats.queries += 1;
        match goals::build(self.prog, ob, part) {
            Err(Unsupported(what)) => Answer::Unknown(Why::Unsupported(what)),
            Ok(q) => self.solve(q, index, k, !part.is_sat_question() && *part != Part::Context, !example, stats),
        }
    }

    /// Solves `q`. Without `model`, a satisfiable answer found under other names serves
    /// (sat questions need the verdict, not the witness), and with `guess` too a point
    /// guessed from the query's definitions (`guess.rs`), whose values are not reported.
    fn solve(&self, q: Query, index: usize, k: usize, model: bool, guess: bool, stats: &mut Stats) -> Answer {
        let label = self.labels.get(index).cloned().unwrap_or_else(|| format!("obligation-{index}"));
        let solver_of = |q: &Query| {
            let solver = solver_for(q);
            for a in q.assertions.iter().chain(q.enc.side_conditions()) {
                solver.assert(a);
            }
            solver
        };
        // `--dump`: every query's text, answered from the cache or not.
        let mut solver = None;
        if let Some(dump) = &self.cfg.dump {
            if !self.caches.dump_failed.load(Ordering::Relaxed) {
                let s = solver.insert(solver_of(&q));
                let n = self.caches.dumped.fetch_add(1, Ordering::Relaxed);
                let name = format!("{n:05}-{label}-{k}");
                if let Err(e) = dump(&name, &format!("; mochi: {label}, part {k}\n{s}(check-sat)\n")) {
                    // The first failure is reported (with this obligation); later ones
                    // would only repeat it.
                    if !self.caches.dump_failed.swap(true, Ordering::Relaxed) {
                        stats.dump_error = Some(format!("{name}: {e}"));
                    }
                }
            }
        }
        // The exact key first (any answer); then the key up to renaming of the free
        // constants, which only answers without a model carry over (the model's names
        // differ). Both are read off the terms: a query answered here builds no solver.
        let keys = (!self.cfg.no_cache).then(|| key::of(&q, q.enc.logic()));
        let cached = |key: &String| self.caches.cache.lock().ok().and_then(|c| c.get(key).cloned());
        if let Some(keys) = &keys {
            if let Some(a) = cached(&keys.exact) {
                stats.cached += 1;
                // The same query may come from other values of the same names: where this
                // query's values are bound is this query's.
                return match a {
                    Answer::Sat { values, overlap, exact, .. } => {
                        Answer::Sat { values, overlap, bound: q.enc.shared_names(), exact }
                    }
                    other => other,
                };
            }
            if let Some(a) = keys.canonical.as_ref().and_then(cached) {
                if !model || !matches!(a, Answer::Sat { .. }) {
                    stats.cached += 1;
                    return a;
                }
            }
        }
        // A sat question whose definitions give a point that satisfies it: a model.
        if !model && guess && !self.cfg.no_cache && guess::satisfied(&q) {
            stats.witnessed += 1;
            return Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() };
        }
        let solver = solver.unwrap_or_else(|| solver_of(&q));
        let seq = self.watchdog.arm(self.timeout);
        #[cfg(test)]
        pool::maybe_hang(&label);
        let mut result = solver.check();
        let mut timed_out = self.watchdog.disarm(seq);
        // A sat question needs a genuine witness, and a model of a query that encloses
        // `sin`, `cos` or `pi` may give them values the real functions do not take
        // (`x == sin(1) && x == 0.8414709848078965` has such a model and no real
        // solution). The witness is confirmed in exact arithmetic ([`confirm`]); failing
        // that, one is looked for with every trigonometric argument 0, where the
        // enclosures are exact, and confirmed the same way. Neither: unknown.
        // (Counterexamples are replayed in exact arithmetic instead, [`replay`].)
        let mut unconfirmed = None;
        if !model && matches!(result, z3::SatResult::Sat) && q.enc.encloses() {
            let first = match solver.get_model() {
                Some(m) => confirm::confirm(&q, &m),
                None => Err("the solver gave no model".into()),
            };
            if let Err(why) = first {
                let mut second = Err(why);
                if q.enc.has_trig() {
                    for pin in q.enc.trig_at_zero() {
                        solver.assert(&pin);
                    }
                    let seq = self.watchdog.arm(self.timeout);
                    let r = solver.check();
                    timed_out |= self.watchdog.disarm(seq);
                    if matches!(r, z3::SatResult::Sat) {
                        if let Some(m) = solver.get_model() {
                            second = confirm::confirm(&q, &m);
                        }
                    }
                }
                if let Err(why) = second {
                    result = z3::SatResult::Unknown;
                    unconfirmed = Some(why);
                }
            }
        }
        let answer = match result {
            z3::SatResult::Unsat => Answer::Unsat,
            z3::SatResult::Sat => match solver.get_model() {
                // (A sat question's witness was confirmed above, whatever values the
                // model gives the enclosed functions.)
                Some(m) if model && q.enc.spurious_trig(&m) => Answer::Unknown(Why::Incomplete(
                    "its counterexample gives sin/cos values the real functions do not take (the encoding encloses them)"
                        .into(),
                    Hard::of(&q),
                )),
                Some(m) => {
                    let overlap = q.point.as_ref().map(|p| Overlap::at(
                        [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                        q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
                    ));
                    Answer::Sat {
                        values: q.enc.assignments(&m),
                        overlap,
                        bound: q.enc.shared_names(),
                        exact: replay::valuation(&q.enc, &m),
                    }
                }
                None => Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() },
            },
            z3::SatResult::Unknown if timed_out => Answer::Unknown(Why::Timeout(self.timeout, Hard::of(&q))),
            z3::SatResult::Unknown if unconfirmed.is_some() => Answer::Unknown(Why::Incomplete(
                format!(
                    "its witness holds only of the encoding's enclosure of `sin`, `cos` or `pi`, not of the real functions' values ({})",
                    unconfirmed.unwrap_or_default()
                ),
                Hard::of(&q),
            )),
            z3::SatResult::Unknown => Answer::Unknown(Why::Incomplete(
                solver.get_reason_unknown().unwrap_or_else(|| "unknown".into()),
                Hard::of(&q),
            )),
        };
        // A timeout depends on the machine's load: do not cache it.
        if let Some(keys) = keys.filter(|_| !matches!(answer, Answer::Unknown(Why::Timeout(..)))) {
            if let Ok(mut c) = self.caches.cache.lock() {
                if let Some(canonical) = keys.canonical {
                    c.insert(canonical, answer.clone());
                }
                c.insert(keys.exact, answer.clone());
            }
        }
        answer
    }
}

/// A solver for `q`. Z3's default solver spends ~5 ms per check choosing a strategy;
/// naming the logic skips that (nlsat: complete for nonlinear real arithmetic). Queries
/// with integer variables keep the default solver. The encoder says which (it declared
/// the variables), not the query's text.
pub(crate) fn solver_for(q: &Query) -> z3::Solver {
    match q.enc.logic() {
        Logic::Nra => z3::Solver::new_for_logic("QF_NRA").unwrap_or_default(),
        Logic::WithIntegers => z3::Solver::new(),
    }
}
