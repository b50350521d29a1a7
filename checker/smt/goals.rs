//! From obligations to satisfiability queries. Each [`Goal`] splits into [`Part`]s, one
//! query each, so that a failure names exactly what failed (an assumption, two
//! footprints, a duration). A part holds iff its query is unsatisfiable.
//!
//! How a primitive run by participant `p` is read (Def 3.4, Sec 3.4):
//! - its state when it starts is `p.x` — the same variables the context Σ speaks of;
//! - its state at time `t` of the motion is `p.x(t)`, at its end `p.x(end)`;
//! - `old(x)` is the start state, parameters are the arguments, `clock` is `t`;
//! - an input `w` is the connected participant's `w(t)` when that participant is part
//!   of the same joint motion, and unconstrained otherwise;
//! - the kind's invariant holds of every state (assumed, as in typing);
//! - footprints are in the participant's frame: the world point `(x, y, z)` is moved
//!   into it by the inverse of the participant's `pose`.

use super::encode::{real_of_rational, Encoder, Frame, Term, Unsupported};
use crate::bounds::{self, Interval};
use crate::hir::{Builtin, Expr, ExprKind, PrimApp, Primitive, Program, RoleId, Slot, Var};
use crate::obligation::{Goal, Obligation, Run, Side};
use num_rational::BigRational;
use std::collections::{HashMap, HashSet};
use z3::ast::{Bool, Real};

pub mod witness;

/// One question about an obligation.
#[derive(Clone, Debug, PartialEq)]
pub enum Part {
    /// `hyps ⇒ goal`.
    Valid,
    /// [AGCOMP] "compatible from Pre": part `i`'s precondition holds at the `dt`.
    Pre(usize),
    /// The joint motion can end (a **sat** question; see [`Part::is_sat_question`]):
    /// from Σ and every part's precondition, some time `t` in every part's duration and
    /// an end state of every part at which its guarantee (at 0 and at `t`), its
    /// postcondition and its kind's invariant hold together, inputs reading their
    /// sources' end states ([M-PAR], [NON-INTERRUPT], [INTERRUPT], Def 4.11 (5), (8)).
    CanEnd,
    /// The joint motion can start: Σ and every part's precondition and invariant are
    /// consistent (a sat question, asked when it cannot end: a precondition that
    /// contradicts a satisfiable context is [AGCOMP]'s pre part's or [T-MOTION]'s to
    /// report).
    CanStart,
    /// The obligation's hypotheses alone are satisfiable (a sat question): asked when a
    /// joint motion cannot end, to tell a stuck motion from an unreachable point, and
    /// for [`Goal::Reachable`].
    Context,
    /// [`Goal::Reachable`]: the context before the step (its `k`-th) is satisfiable.
    Before(usize),
    /// [`Goal::CanEnd`]: the declared primitive admits a run that ends.
    Realisable,
    /// [`Goal::CanEnd`] under [`crate::obligation::Rule::Occupies`]: the primitive's
    /// footprint holds some point when it starts (a footprint no point satisfies would make
    /// every collision check about it hold vacuously).
    Occupies,
    /// Conjunct `k` of a `Valid` goal.
    Conjunct(usize),
    /// [AGCOMP]: the others' guarantees discharge part `i`'s assumption.
    Assume(usize),
    /// [AGCOMP]: the footprints of parts `i` and `j` are disjoint at every time.
    Disjoint(usize, usize),
    /// [AGCOMP]: the non-interruptible part `i`'s duration lies within part `j`'s.
    Within(usize, usize),
    /// [AGCOMP] with no non-interruptible part: the durations share a time.
    Meet,
    /// Separation: run `ra` of side `a` and run `rb` of side `b` never overlap.
    Apart { a: usize, ra: usize, b: usize, rb: usize },
    /// Def 3.4 (corrected direction), one item.
    Refine(RefineItem),
    /// [T-SESS]: the first motions of `r` and `s` start with disjoint footprints.
    InitiallyApart { r: usize, s: usize },
    /// A written partition: the regions of sides `a` and `b` are disjoint.
    RegionsApart(usize, usize),
    /// A written partition: run `ra` of side `a` stays in the side's region.
    InRegion { a: usize, ra: usize },
}

impl Part {
    /// Parts that must be satisfiable (a model is the witness) rather than unsat.
    pub fn is_sat_question(&self) -> bool {
        matches!(
            self,
            Part::CanEnd
                | Part::CanStart
                | Part::Context
                | Part::Before(_)
                | Part::Realisable
                | Part::Occupies
                | Part::Refine(RefineItem::Realisable)
        )
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefineItem {
    Pre,
    Assume,
    Guarantee,
    Post,
    Footprint,
    Duration,
    /// The concrete primitive admits a run that ends from a start the abstract one
    /// allows (a sat question): otherwise the other items hold vacuously.
    Realisable,
}

impl RefineItem {
    pub fn text(self) -> &'static str {
        match self {
            RefineItem::Pre => "the abstract precondition implies the concrete one",
            RefineItem::Assume => "the abstract assumption implies the concrete one",
            RefineItem::Guarantee => "the concrete guarantee implies the abstract one",
            RefineItem::Post => "the concrete postcondition implies the abstract one",
            RefineItem::Footprint => "the concrete footprint lies within the abstract one",
            RefineItem::Duration => "the durations nest (Def 3.4, corrected)",
            RefineItem::Realisable => {
                "the concrete primitive can end (some time in its duration, an end state meeting its guarantee, postcondition and invariant) from a start the abstract precondition allows; otherwise every other item holds vacuously"
            }
        }
    }
}

/// A query: the part holds iff `assertions` (with the encoder's side conditions) are
/// unsatisfiable. `point` and `times` name the variables of an overlap, if any.
pub struct Query<'p> {
    pub enc: Encoder<'p>,
    pub assertions: Vec<Bool>,
    pub point: Option<[Real; 3]>,
    pub times: Vec<Real>,
}

/// What an obligation splits into; an `Err` settles it without a solver.
pub enum Plan {
    Parts(Vec<Part>),
    /// Decided without a query (for example separation by boxes), with a note.
    Holds(Option<String>),
    /// Fails without a query, with the reason.
    Fails(String),
    Unknown(Unsupported),
}

pub fn plan(prog: &Program, ob: &Obligation) -> Plan {
    match &ob.goal {
        Goal::Valid(e) => {
            // One part per conjunct, so that a failure names the conjunct that fails.
            let n = e.conjuncts().len();
            Plan::Parts(if n > 1 { (0..n).map(Part::Conjunct).collect() } else { vec![Part::Valid] })
        }
        Goal::Compatible { parts } => {
            let mut out = Vec::new();
            // A lone primitive's precondition is [T-MOTION]'s to check, in its process.
            let lone = parts.len() == 1;
            for (i, (_, app)) in parts.iter().enumerate() {
                let p = prog.prim(app.prim);
                if !p.pre.is_true() && !lone {
                    out.push(Part::Pre(i));
                }
                if !p.assume.is_true() {
                    out.push(Part::Assume(i));
                }
            }
            for i in 0..parts.len() {
                for j in i + 1..parts.len() {
                    let (a, b) = (prog.prim(parts[i].1.prim), prog.prim(parts[j].1.prim));
                    if a.footprint.is_none() || b.footprint.is_none() {
                        let who = if a.footprint.is_none() { &parts[i] } else { &parts[j] };
                        return Plan::Fails(format!(
                            "`{}` of `{}` declares no footprint, so it may occupy all space and meets every other footprint",
                            prog.prim(who.1.prim).name,
                            prog.role_name(who.0)
                        ));
                    }
                    out.push(Part::Disjoint(i, j));
                }
            }
            // One can-end question for the whole `dt`: the parts end together.
            out.push(Part::CanEnd);
            let non: Vec<usize> = (0..parts.len()).filter(|&i| !prog.prim(parts[i].1.prim).interruptible).collect();
            match non.first() {
                Some(&n) => out.extend((0..parts.len()).filter(|&j| j != n).map(|j| Part::Within(n, j))),
                None if parts.len() > 1 => out.push(Part::Meet),
                None => {}
            }
            Plan::Parts(out)
        }
        Goal::Separated { sides } => match prog.partition(ob.span) {
            Some(p) if p.regions.len() == sides.len() => {
                let mut parts = Vec::new();
                for a in 0..sides.len() {
                    for b in a + 1..sides.len() {
                        parts.push(Part::RegionsApart(a, b));
                    }
                    parts.extend((0..sides[a].runs.len()).map(|ra| Part::InRegion { a, ra }));
                }
                Plan::Parts(parts)
            }
            Some(_) => Plan::Fails("the partition does not have one region per side".into()),
            None => separation_plan(prog, sides),
        },
        Goal::Refines { concrete, abstract_, .. } => {
            if abstract_.len() == 1 && abstract_[0] == *concrete {
                return Plan::Holds(None); // a primitive refines itself
            }
            let c = prog.prim(concrete.prim);
            if let Some(s) = abstract_.iter().map(|a| prog.prim(a.prim)).find(|s| s.interruptible != c.interruptible) {
                return Plan::Fails(format!(
                    "`{}` is {} but `{}` is {} (Def 3.4: refinement keeps interruptibility)",
                    c.name,
                    interruptibility(c),
                    s.name,
                    interruptibility(s)
                ));
            }
            use RefineItem::*;
            Plan::Parts(
                [Realisable, Pre, Assume, Guarantee, Post, Footprint, Duration].into_iter().map(Part::Refine).collect(),
            )
        }
        Goal::InitiallyDisjoint { firsts } => {
            // Boxes first, as for separation: only participants whose boxes meet need Z3.
            let boxes: Vec<Option<[Interval; 3]>> = firsts
                .iter()
                .map(|(role, apps)| {
                    let side = Side {
                        roles: vec![*role],
                        runs: apps
                            .iter()
                            .map(|a| Run {
                                role: *role,
                                app: a.clone(),
                                hyps: slice(prog, &ob.hyps, seeds_of(prog, &[(*role, a.clone())])),
                            })
                            .collect(),
                    };
                    side_box(prog, &side)
                })
                .collect();
            let mut out = Vec::new();
            for r in 0..firsts.len() {
                for s in r + 1..firsts.len() {
                    if let (Some(x), Some(y)) = (&boxes[r], &boxes[s]) {
                        if (0..3).any(|k| x[k].disjoint(y[k])) {
                            continue;
                        }
                    }
                    out.push(Part::InitiallyApart { r, s });
                }
            }
            if out.is_empty() {
                return Plan::Holds(None);
            }
            Plan::Parts(out)
        }
        Goal::CanEnd { .. } if ob.rule == crate::obligation::Rule::Occupies => Plan::Parts(vec![Part::Occupies]),
        Goal::CanEnd { .. } => Plan::Parts(vec![Part::Realisable]),
        Goal::Reachable { .. } => Plan::Parts(vec![Part::Context]),
    }
}

fn interruptibility(p: &Primitive) -> &'static str {
    if p.interruptible {
        "interruptible"
    } else {
        "non-interruptible"
    }
}

/// Builds the query of one part.
pub fn build<'p>(prog: &'p Program, ob: &Obligation, part: &Part) -> Result<Query<'p>, Unsupported> {
    let mut q = Query { enc: Encoder::new(prog), assertions: Vec::new(), point: None, times: Vec::new() };
    match (&ob.goal, part) {
        (Goal::Valid(goal), Part::Valid) => {
            let seeds = vars_of(prog, [goal]);
            hyps(&mut q, &slice(prog, &ob.hyps, seeds))?;
            let g = q.enc.boolean(goal)?;
            q.assertions.push(g.not());
        }
        (Goal::Valid(goal), Part::Conjunct(k)) => {
            let c = goal.conjuncts()[*k];
            hyps(&mut q, &slice(prog, &ob.hyps, vars_of(prog, [c])))?;
            let g = q.enc.boolean(c)?;
            q.assertions.push(g.not());
        }
        // Σ alone, whatever the goal (the vacuity guard; a stuck motion).
        (_, Part::Context) => hyps(&mut q, &context_of(prog, ob))?,
        (Goal::Compatible { parts }, _) => compat(&mut q, &ob.hyps, parts, part)?,
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let (x, y) = (&sides[*a].runs[*ra], &sides[*b].runs[*rb]);
            let p = world_point(&mut q);
            let mut times = Vec::new();
            for (run, tag) in [(x, "t1"), (y, "t2")] {
                hyps(&mut q, &slice(prog, &run.hyps, seeds_of(prog, &[(run.role, run.app.clone())])))?;
                let t = q.enc.named_real(if tag == "t1" { "time 1" } else { "time 2" });
                let inst = Inst::new(&mut q.enc, run.role, &run.app, t.clone(), tag)?;
                inst.started(&mut q)?;
                inst.running(&mut q)?;
                inst.occupies(&mut q, &p)?;
                times.push(t);
            }
            q.point = Some(p);
            q.times = times;
        }
        (Goal::Separated { .. }, Part::RegionsApart(a, b)) => {
            let p = world_point(&mut q);
            let regions = &prog.partition(ob.span).ok_or_else(|| Unsupported("a partition".into()))?.regions;
            let frame = Frame { point: Some(p.clone()), ..Frame::default() };
            for i in [*a, *b] {
                let r = q.enc.in_frame(&frame, |enc| enc.boolean(&regions[i]))?;
                q.assertions.push(r);
            }
            q.point = Some(p);
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => {
            let run = &sides[*a].runs[*ra];
            let regions = &prog.partition(ob.span).ok_or_else(|| Unsupported("a partition".into()))?.regions;
            hyps(&mut q, &slice(prog, &run.hyps, seeds_of(prog, &[(run.role, run.app.clone())])))?;
            let p = world_point(&mut q);
            let t = q.enc.named_real("time");
            let inst = Inst::new(&mut q.enc, run.role, &run.app, t.clone(), "t")?;
            inst.started(&mut q)?;
            inst.running(&mut q)?;
            inst.occupies(&mut q, &p)?;
            let frame = Frame { point: Some(p.clone()), ..Frame::default() };
            let r = q.enc.in_frame(&frame, |enc| enc.boolean(&regions[*a]))?;
            q.assertions.push(r.not());
            q.point = Some(p);
            q.times = vec![t];
        }
        (Goal::Refines { role, concrete, abstract_ }, Part::Refine(item)) => {
            refine(&mut q, *role, concrete, abstract_, *item)?
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => {
            let mut involved = Vec::new();
            for (role, apps) in [&firsts[*r], &firsts[*s]] {
                involved.extend(apps.iter().map(|a| (*role, a.clone())));
            }
            hyps(&mut q, &slice(prog, &ob.hyps, seeds_of(prog, &involved)))?;
            let p = world_point(&mut q);
            let zero = zero();
            let mut any = Vec::new();
            for (role, apps) in [&firsts[*r], &firsts[*s]] {
                // Whichever first motion the participant takes, it starts inside it.
                let mut inside = Vec::new();
                for app in apps {
                    let inst = Inst::new(&mut q.enc, *role, app, zero.clone(), "0")?;
                    let fp = inst.footprint(&mut q.enc, &p)?;
                    let start_is_now = inst.at_start();
                    inside.push(Bool::and(&[fp, start_is_now]));
                }
                // Each first footprint contains the robot at time 0, so the robot lies in
                // their intersection (not merely their union).
                any.push(Bool::and(&inside));
            }
            q.assertions.extend(any);
            q.point = Some(p);
        }
        (Goal::Reachable { before, .. }, Part::Before(k)) => {
            hyps(&mut q, before.get(*k).map(Vec::as_slice).unwrap_or_default())?
        }
        (Goal::CanEnd { prim }, Part::Realisable) => {
            // Some arguments, start state and time: every parameter is free.
            let prog = q.enc.prog();
            let p = prog.prim(*prim);
            // Read in the frame of some participant of the kind (the driver asks only
            // about kinds that have one): its name shows in the counterexample.
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let Some(role) = role else { return Err(Unsupported("a primitive of a kind no participant has".into())) };
            let app = PrimApp { prim: *prim, args: Vec::new(), loc: Default::default() };
            let t = q.enc.named_real("time");
            let mut inst = Inst::new(&mut q.enc, role, &app, t.clone(), "t")?;
            inst.frame.params = p.params.iter().map(|(n, sort)| q.enc.named(n, sort)).collect::<Result<_, _>>()?;
            ends(&mut q, std::slice::from_ref(&inst), &t)?;
        }
        (Goal::CanEnd { prim }, Part::Occupies) => {
            // Some arguments, state and point (in the robot's own frame: a pose only moves
            // it) satisfy the footprint's predicate at time 0. Deliberately weak and cheap:
            // it catches footprints no point satisfies (`false`, contradictory bounds).
            let prog = q.enc.prog();
            let p = prog.prim(*prim);
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let Some(role) = role else { return Err(Unsupported("a primitive of a kind no participant has".into())) };
            let Some(fp) = p.footprint.clone() else { return Ok(q) };
            let app = PrimApp { prim: *prim, args: Vec::new(), loc: Default::default() };
            let mut inst = Inst::new(&mut q.enc, role, &app, zero(), "t")?;
            inst.frame.params = p.params.iter().map(|(n, sort)| q.enc.named(n, sort)).collect::<Result<_, _>>()?;
            let local = [q.enc.named_real("point.x"), q.enc.named_real("point.y"), q.enc.named_real("point.z")];
            let frame = Frame { point: Some(local.clone()), ..inst.frame.clone() };
            let holds = inst.pred(&mut q.enc, &fp.pred, &frame)?;
            q.assertions.push(holds);
        }
        _ => return Err(Unsupported("an obligation split into a part of another kind".into())),
    }
    Ok(q)
}

/// The parts end together at time `t` ([M-PAR]: one elapsed time for all): every part
/// started (precondition, invariant), `t` lies in every part's duration (Def 4.11 (5):
/// `t <= ⌈D⌉`; (8)(a), (b) and [NON-INTERRUPT]/[INTERRUPT]: `t ∈ D`), the guarantee
/// held at time 0 of the start state and at `t` of the end state (the two ends of
/// [TRAJ-STEP]'s `[0, t]`), and the postcondition and invariant hold of the end state.
/// The state at `t` is each instance's frame, so `connect` already makes an input its
/// source's end state when the source is a part.
fn ends(q: &mut Query, insts: &[Inst], t: &Real) -> Result<(), Unsupported> {
    q.assertions.push(t.ge(zero()));
    for inst in insts {
        inst.started(q)?;
        let (lo, hi) = inst.duration(&mut q.enc)?;
        q.assertions.push(t.ge(&lo));
        if let Some(hi) = hi {
            q.assertions.push(t.le(&hi));
        }
        let at_zero = Frame { clock: Some(zero()), ..inst.start_frame() };
        let g0 = inst.pred(&mut q.enc, &inst.prim.guarantee, &at_zero)?;
        let gt = inst.pred(&mut q.enc, &inst.prim.guarantee, &inst.frame)?;
        let post = inst.pred(&mut q.enc, &inst.prim.post, &inst.frame)?;
        q.assertions.extend([g0, gt, post]);
        if let Some(inv) = q.enc.prog().kind(inst.prim.kind).invariant.clone() {
            let b = inst.pred(&mut q.enc, &inv, &inst.frame)?;
            q.assertions.push(b);
        }
    }
    Ok(())
}

/// The hypotheses a proof of `ob` rests on, for the vacuity guard: for a validity goal
/// the slice its parts use (each conjunct's cone of influence lies within the goal's),
/// otherwise all of them. The proof is vacuous iff these are unsatisfiable.
pub fn context_of(prog: &Program, ob: &Obligation) -> Vec<Expr> {
    match &ob.goal {
        Goal::Valid(goal) => slice(prog, &ob.hyps, vars_of(prog, [goal])),
        _ => ob.hyps.clone(),
    }
}

/// A cheap, sufficient test that `facts` are satisfiable, without Z3: a candidate point
/// in exact rational arithmetic. Equalities `v == e` define `v` as `e`'s exact value, in
/// order, once `e`'s variables have values; every other variable takes a simple value read
/// off the ranges the facts give it (a point range's value, a finite range's midpoint, a
/// bound plus or minus one, else 0; integers rounded); then every fact is evaluated
/// exactly at that point. `false` means only "not shown": facts over inputs (their
/// sources' variables under another name), booleans, points, `sqrt`, `sin`, `cos`, or
/// numbers beyond 128-bit rationals are left to Z3.
pub fn witnessed(prog: &Program, facts: &[Expr]) -> bool {
    // Only real and integer state, snapshot and value variables.
    let mut simple = true;
    let mut ints = HashSet::new();
    for f in facts {
        f.visit_vars(&mut |v, _| {
            let sort = match v {
                Var::Const(_) => return,
                Var::Role(r, slot @ Slot::State(_)) | Var::Snap(r, slot @ Slot::State(_)) => {
                    prog.kind_of(*r).var(*slot).1.clone()
                }
                Var::Value(id, _) => prog.value(*id).sort.clone(),
                _ => {
                    simple = false;
                    return;
                }
            };
            match sort {
                crate::hir::Sort::Int => {
                    ints.insert(v.clone());
                }
                crate::hir::Sort::Real => {}
                _ => simple = false,
            }
        });
    }
    if !simple {
        return false;
    }
    let mut at: HashMap<Var, Rat> = HashMap::new();
    let mut defining = vec![false; facts.len()];
    loop {
        let mut grew = false;
        for (i, f) in facts.iter().enumerate() {
            if defining[i] {
                continue;
            }
            let ExprKind::Binary(crate::hir::expr::BinOp::Eq, a, b) = &f.kind else { continue };
            for (lhs, rhs) in [(a, b), (b, a)] {
                let ExprKind::Var(v) = &lhs.kind else { continue };
                if matches!(v, Var::Const(_)) || at.contains_key(v) {
                    continue;
                }
                let Some(x) = Rat::eval(prog, rhs, &at) else { continue };
                if ints.contains(v) && x.1 != 1 {
                    continue;
                }
                at.insert(v.clone(), x);
                defining[i] = true;
                grew = true;
                break;
            }
        }
        if !grew {
            break;
        }
    }
    let rest: Vec<&Expr> = facts.iter().zip(&defining).filter(|(_, d)| !**d).map(|(f, _)| f).collect();
    // Ranges only guide the choice of values (every fact is then checked exactly).
    let known = |v: &Var| at.get(v).map(|r| Interval::new(r.0 as f64 / r.1 as f64, r.0 as f64 / r.1 as f64));
    let ranges = bounds::ranges_from(prog, &rest, &known);
    let mut free = Vec::new();
    for f in &rest {
        f.visit_vars(&mut |v, _| {
            if !matches!(v, Var::Const(_)) && !at.contains_key(v) {
                free.push(v.clone());
            }
        });
    }
    for v in free {
        let i = ranges.get(&v).copied().unwrap_or(Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY });
        let x = if i.lo == i.hi {
            i.lo
        } else if i.lo.is_finite() && i.hi.is_finite() {
            i.lo / 2.0 + i.hi / 2.0
        } else if i.lo.is_finite() {
            i.lo.floor() + 1.0
        } else if i.hi.is_finite() {
            i.hi.ceil() - 1.0
        } else {
            0.0
        };
        let x = if ints.contains(&v) { x.round() } else { x };
        let Some(x) = Rat::of_f64(x) else { return false };
        at.entry(v).or_insert(x);
    }
    rest.iter().all(|f| Rat::truth(prog, f, &at) == Some(true))
}

/// An exact rational `(numerator, denominator)`, denominator positive, in lowest terms.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rat(i128, i128);

impl Rat {
    fn new(n: i128, d: i128) -> Option<Rat> {
        if d == 0 {
            return None;
        }
        let g = gcd(n.unsigned_abs(), d.unsigned_abs()).max(1) as i128;
        let (n, d) = (n / g, d / g);
        Some(if d < 0 { Rat(n.checked_neg()?, d.checked_neg()?) } else { Rat(n, d) })
    }

    /// The exact value of a double (dyadic), when it fits.
    fn of_f64(x: f64) -> Option<Rat> {
        if !x.is_finite() {
            return None;
        }
        let mut d: i128 = 1;
        let mut y = x;
        while y.fract() != 0.0 {
            y *= 2.0;
            d = d.checked_mul(2)?;
        }
        if y.abs() >= 1e30 {
            return None;
        }
        Rat::new(y as i128, d)
    }

    /// The exact value of a decimal literal such as `0.65` or `1e-3`.
    fn of_decimal(s: &str) -> Option<Rat> {
        let (mant, exp) = match s.find(['e', 'E']) {
            Some(i) => (&s[..i], s[i + 1..].parse::<i32>().ok()?),
            None => (s, 0),
        };
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let digits: i128 = format!("{int}{frac}").parse().ok()?;
        let scale = exp.checked_sub(i32::try_from(frac.len()).ok()?)?;
        let pow = 10i128.checked_pow(scale.unsigned_abs())?;
        if scale >= 0 {
            Rat::new(digits.checked_mul(pow)?, 1)
        } else {
            Rat::new(digits, pow)
        }
    }

    fn add(self, o: Rat) -> Option<Rat> {
        Rat::new(self.0.checked_mul(o.1)?.checked_add(o.0.checked_mul(self.1)?)?, self.1.checked_mul(o.1)?)
    }

    fn mul(self, o: Rat) -> Option<Rat> {
        Rat::new(self.0.checked_mul(o.0)?, self.1.checked_mul(o.1)?)
    }

    fn neg(self) -> Option<Rat> {
        Some(Rat(self.0.checked_neg()?, self.1))
    }

    fn cmp(self, o: Rat) -> Option<std::cmp::Ordering> {
        Some(self.0.checked_mul(o.1)?.cmp(&o.0.checked_mul(self.1)?))
    }

    /// The exact value of a numeric term at `at`, when it has one.
    fn eval(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<Rat> {
        use crate::hir::expr::{BinOp, UnOp};
        match &e.kind {
            ExprKind::Int(i) => Rat::new(*i as i128, 1),
            ExprKind::Real(r) => Rat::of_decimal(r),
            ExprKind::Var(Var::Const(c)) => Rat::eval(prog, &prog.consts[c.idx()].value, at),
            ExprKind::Var(v) => at.get(v).copied(),
            ExprKind::Unary(UnOp::Neg, a) => Rat::eval(prog, a, at)?.neg(),
            ExprKind::Binary(op, a, b) => {
                let x = Rat::eval(prog, a, at)?;
                if *op == BinOp::Pow {
                    let ExprKind::Int(n) = b.kind else { return None };
                    let mut r = Rat(1, 1);
                    for _ in 0..u32::try_from(n).ok().filter(|n| *n <= 64)? {
                        r = r.mul(x)?;
                    }
                    return Some(r);
                }
                let y = Rat::eval(prog, b, at)?;
                match op {
                    BinOp::Add => x.add(y),
                    BinOp::Sub => x.add(y.neg()?),
                    BinOp::Mul => x.mul(y),
                    BinOp::Div => x.mul(Rat::new(y.1, y.0)?),
                    _ => None,
                }
            }
            ExprKind::If(c, a, b) => match Rat::truth(prog, c, at)? {
                true => Rat::eval(prog, a, at),
                false => Rat::eval(prog, b, at),
            },
            ExprKind::Call(f, args) => {
                let x = Rat::eval(prog, args.first()?, at)?;
                let y = || Rat::eval(prog, args.get(1)?, at);
                match f {
                    Builtin::Min => Some(if x.cmp(y()?)?.is_le() { x } else { y()? }),
                    Builtin::Max => Some(if x.cmp(y()?)?.is_ge() { x } else { y()? }),
                    Builtin::Abs => Some(if x.0 < 0 { x.neg()? } else { x }),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// Rational bounds `(lo, hi)` on a numeric term at `at` that mentions `pi` (enclosed
    /// in `[3.141592653589793, 3.141592653589794]`): sums, differences, negation,
    /// products and quotients by a nonzero rational. `None` otherwise.
    fn enclose(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<(Rat, Rat)> {
        use crate::hir::expr::{BinOp, UnOp};
        if let Some(x) = Rat::eval(prog, e, at) {
            return Some((x, x));
        }
        match &e.kind {
            ExprKind::Call(Builtin::Pi, _) => Some((
                Rat::new(3_141_592_653_589_793, 10i128.pow(15))?,
                Rat::new(3_141_592_653_589_794, 10i128.pow(15))?,
            )),
            ExprKind::Var(Var::Const(c)) => Rat::enclose(prog, &prog.consts[c.idx()].value, at),
            ExprKind::Unary(UnOp::Neg, a) => {
                let (lo, hi) = Rat::enclose(prog, a, at)?;
                Some((hi.neg()?, lo.neg()?))
            }
            ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div), a, b) => {
                let (alo, ahi) = Rat::enclose(prog, a, at)?;
                let (blo, bhi) = Rat::enclose(prog, b, at)?;
                let ends = match op {
                    BinOp::Add => return Some((alo.add(blo)?, ahi.add(bhi)?)),
                    BinOp::Sub => return Some((alo.add(bhi.neg()?)?, ahi.add(blo.neg()?)?)),
                    BinOp::Mul => [alo.mul(blo)?, alo.mul(bhi)?, ahi.mul(blo)?, ahi.mul(bhi)?],
                    _ => {
                        // Only by a nonzero rational (a point).
                        if blo != bhi || blo.0 == 0 {
                            return None;
                        }
                        let inv = Rat::new(blo.1, blo.0)?;
                        [alo.mul(inv)?, ahi.mul(inv)?, alo.mul(inv)?, ahi.mul(inv)?]
                    }
                };
                let mut lo = ends[0];
                let mut hi = ends[0];
                for x in &ends[1..] {
                    if x.cmp(lo)?.is_lt() {
                        lo = *x;
                    }
                    if x.cmp(hi)?.is_gt() {
                        hi = *x;
                    }
                }
                Some((lo, hi))
            }
            _ => None,
        }
    }

    /// The exact truth of a predicate at `at`, when it can be computed.
    fn truth(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<bool> {
        use crate::hir::expr::{BinOp, UnOp};
        match &e.kind {
            ExprKind::Bool(b) => Some(*b),
            ExprKind::Unary(UnOp::Not, a) => Some(!Rat::truth(prog, a, at)?),
            ExprKind::Binary(BinOp::And, a, b) => Some(Rat::truth(prog, a, at)? && Rat::truth(prog, b, at)?),
            ExprKind::Binary(BinOp::Or, a, b) => Some(Rat::truth(prog, a, at)? || Rat::truth(prog, b, at)?),
            ExprKind::Binary(BinOp::Implies, a, b) => Some(!Rat::truth(prog, a, at)? || Rat::truth(prog, b, at)?),
            ExprKind::Binary(op, a, b) => {
                let (Some(x), Some(y)) = (Rat::eval(prog, a, at), Rat::eval(prog, b, at)) else {
                    // A side that is no rational (it mentions `pi`): decided only when the
                    // enclosures of the two sides are apart.
                    let ((alo, ahi), (blo, bhi)) = (Rat::enclose(prog, a, at)?, Rat::enclose(prog, b, at)?);
                    let below = ahi.cmp(blo)?.is_lt();
                    let above = alo.cmp(bhi)?.is_gt();
                    let (le, ge) = (ahi.cmp(blo)?.is_le(), alo.cmp(bhi)?.is_ge());
                    return match op {
                        BinOp::Lt | BinOp::Le if below => Some(true),
                        BinOp::Le if le => Some(true),
                        BinOp::Lt | BinOp::Le if ge && (above || *op == BinOp::Lt) => Some(false),
                        BinOp::Gt | BinOp::Ge if above => Some(true),
                        BinOp::Ge if ge => Some(true),
                        BinOp::Gt | BinOp::Ge if le && (below || *op == BinOp::Gt) => Some(false),
                        BinOp::Eq | BinOp::Ne if below || above => Some(*op == BinOp::Ne),
                        _ => None,
                    };
                };
                let o = x.cmp(y)?;
                match op {
                    BinOp::Eq => Some(o.is_eq()),
                    BinOp::Ne => Some(o.is_ne()),
                    BinOp::Lt => Some(o.is_lt()),
                    BinOp::Le => Some(o.is_le()),
                    BinOp::Gt => Some(o.is_gt()),
                    BinOp::Ge => Some(o.is_ge()),
                    _ => None,
                }
            }
            _ => None,
        }
    }
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

fn zero() -> Real {
    z3::ast::Int::from_i64(0).to_real()
}

/// The variables of some expressions (constants excepted).
/// Inputs count as their source's state variable, which they are.
fn vars_of<'e>(prog: &Program, es: impl IntoIterator<Item = &'e Expr>) -> HashSet<Var> {
    let mut out = HashSet::new();
    for e in es {
        e.visit_vars(&mut |v, _| {
            if !matches!(v, Var::Const(_)) {
                out.insert(prog.source_of(v));
            }
        });
    }
    out
}

/// What the hypotheses of a motion query may be about: the participants' variables
/// (now and at their latest snapshot), their input sources', and the arguments'.
fn seeds_of(prog: &Program, parts: &[(RoleId, PrimApp)]) -> HashSet<Var> {
    let mut out = vars_of(prog, parts.iter().flat_map(|(_, a)| a.args.iter()));
    for (r, _) in parts {
        let mut roles = vec![*r];
        roles.extend(prog.role(*r).input_sources.iter().flatten().copied());
        for role in roles {
            let kind = prog.kind_of(role);
            for i in 0..kind.state.len() {
                out.insert(Var::Role(role, Slot::State(i)));
                out.insert(Var::Snap(role, Slot::State(i)));
            }
            for i in 0..kind.inputs.len() {
                out.insert(prog.source_of(&Var::Role(role, Slot::Input(i))));
            }
        }
    }
    out
}

/// The hypotheses connected to `seeds` through shared variables (the cone of
/// influence). Dropping the others keeps queries small and lets identical questions
/// about different participants share a cache entry. It is sound: fewer hypotheses
/// can only turn "holds" into "fails" — and only when the dropped ones contradict each
/// other, i.e. the point is unreachable, which is reported rather than hidden.
fn slice(prog: &Program, hs: &[Expr], mut seeds: HashSet<Var>) -> Vec<Expr> {
    let vars: Vec<HashSet<Var>> = hs.iter().map(|h| vars_of(prog, [h])).collect();
    let mut keep = vec![false; hs.len()];
    loop {
        let mut grew = false;
        for (i, vs) in vars.iter().enumerate() {
            if !keep[i] && (vs.is_empty() || vs.iter().any(|v| seeds.contains(v))) {
                keep[i] = true;
                grew = true;
                seeds.extend(vs.iter().cloned());
            }
        }
        if !grew {
            break;
        }
    }
    hs.iter().zip(keep).filter(|(_, k)| *k).map(|(h, _)| h.clone()).collect()
}

fn hyps(q: &mut Query, hs: &[Expr]) -> Result<(), Unsupported> {
    for h in hs {
        let b = q.enc.boolean(h)?;
        q.assertions.push(b);
    }
    Ok(())
}

fn world_point(q: &mut Query) -> [Real; 3] {
    [q.enc.named_real("point.x"), q.enc.named_real("point.y"), q.enc.named_real("point.z")]
}

/// A participant running a primitive, encoded.
#[derive(Clone)]
struct Inst<'a> {
    role: RoleId,
    prim: &'a Primitive,
    frame: Frame,
    /// The state at the start (`role.x`), for the frame of durations and `Pre`.
    start: std::collections::BTreeMap<Slot, Term>,
}

impl<'a> Inst<'a> {
    fn new(
        enc: &mut Encoder<'a>,
        role: RoleId,
        app: &PrimApp,
        clock: Real,
        tag: &str,
    ) -> Result<Inst<'a>, Unsupported> {
        let prog = enc.prog();
        let prim = prog.prim(app.prim);
        let kind = prog.kind_of(role);
        let mut frame = Frame::default();
        let mut start = std::collections::BTreeMap::new();
        for i in 0..kind.state.len() {
            let slot = Slot::State(i);
            let s = enc.role_var(role, slot)?;
            frame.old.push(s.clone());
            start.insert(slot, s);
            let (n, sort) = kind.var(slot).clone();
            let now = enc.named(&format!("{}.{n}({tag})", prog.role_name(role)), &sort)?;
            frame.own.insert(slot, now);
        }
        for i in 0..kind.inputs.len() {
            let slot = Slot::Input(i);
            let (n, sort) = kind.var(slot).clone();
            // At time t: connected later by `connect` when the source moves in the same motion.
            let now = enc.named(&format!("{}.{n}({tag})", prog.role_name(role)), &sort)?;
            frame.own.insert(slot, now.clone());
            // At the start the input *is* its source's state (the variable Σ speaks
            // of), not a fresh value: a precondition the source's state proves holds.
            let s = enc.role_var(role, slot)?;
            start.insert(slot, s);
        }
        frame.params = app.args.iter().map(|a| enc.any(a)).collect::<Result<_, _>>()?;
        frame.clock = Some(clock);
        Ok(Inst { role, prim, frame, start })
    }

    fn start_frame(&self) -> Frame {
        Frame { own: self.start.clone(), ..self.frame.clone() }
    }

    fn pred(&self, enc: &mut Encoder, e: &Expr, frame: &Frame) -> Result<Bool, Unsupported> {
        enc.in_frame(frame, |enc| enc.boolean(e))
    }

    /// `now` equals the start state (for time 0).
    fn at_start(&self) -> Bool {
        let eqs: Vec<Bool> =
            self.frame.own.iter().filter_map(|(slot, now)| now.equals(self.start.get(slot)?)).collect();
        Bool::and(&eqs)
    }

    /// The motion started: its precondition and the invariant held at the start.
    fn started(&self, q: &mut Query) -> Result<(), Unsupported> {
        let sf = self.start_frame();
        let pre = self.pred(&mut q.enc, &self.prim.pre, &sf)?;
        q.assertions.push(pre);
        if let Some(inv) = &q.enc.prog().kind(self.prim.kind).invariant.clone() {
            let b = self.pred(&mut q.enc, inv, &sf)?;
            q.assertions.push(b);
        }
        Ok(())
    }

    /// The motion is running at its clock: `0 <= t <= hi`, its guarantee and the
    /// invariant hold of the state now.
    fn running(&self, q: &mut Query) -> Result<(), Unsupported> {
        let t = self.frame.clock.clone().unwrap_or_else(zero);
        q.assertions.push(t.ge(zero()));
        if let Some(hi) = &self.prim.duration.hi {
            let hi = q.enc.in_frame(&self.start_frame(), |enc| enc.real(hi))?;
            q.assertions.push(t.le(&hi));
        }
        let g = self.pred(&mut q.enc, &self.prim.guarantee, &self.frame)?;
        q.assertions.push(g);
        if let Some(inv) = &q.enc.prog().kind(self.prim.kind).invariant.clone() {
            let b = self.pred(&mut q.enc, inv, &self.frame)?;
            q.assertions.push(b);
        }
        Ok(())
    }

    /// The world point `p` is in the footprint now.
    fn occupies(&self, q: &mut Query, p: &[Real; 3]) -> Result<(), Unsupported> {
        let fp = self.footprint(&mut q.enc, p)?;
        q.assertions.push(fp);
        Ok(())
    }

    fn footprint(&self, enc: &mut Encoder, p: &[Real; 3]) -> Result<Bool, Unsupported> {
        let Some(fp) = &self.prim.footprint else { return Ok(Bool::from_bool(true)) };
        let local = to_local(enc, self.role, p)?;
        let frame = Frame { point: Some(local), ..self.frame.clone() };
        self.pred(enc, &fp.pred, &frame)
    }

    /// `(lo, hi)` of the duration, in the start frame; `hi = None` for infinity.
    fn duration(&self, enc: &mut Encoder) -> Result<(Real, Option<Real>), Unsupported> {
        let sf = self.start_frame();
        let lo = enc.in_frame(&sf, |enc| enc.real(&self.prim.duration.lo))?;
        let hi = match &self.prim.duration.hi {
            Some(h) => Some(enc.in_frame(&sf, |enc| enc.real(h))?),
            None => None,
        };
        Ok((lo, hi))
    }
}

/// The world point moved into `role`'s frame: `R^T (p - o)` for `pose(o, roll, pitch,
/// yaw)`, `R = Rz(yaw) Ry(pitch) Rx(roll)`. Offsets and angles that are exactly zero
/// (exact rational arithmetic, [`bounds::exact`]) are skipped.
///
/// **No rounding can turn an overlap into a pass.** A pose's angles are constants, but
/// their cosines and sines are irrational (but for angle 0). Each is enclosed
/// ([`bounds::trig`]: `c ∈ [c_lo, c_hi]`, `s ∈ [s_lo, s_hi]`, a few ulps wide), and the
/// query ranges over *every* rotation in the enclosure, so an unsat answer holds for the
/// true one. To keep the query linear (an exact `c * x` with a variable `c` made
/// Handover's separation queries time out), the rotation by `(c, s)` of `(x, y)` is
/// written around a rational centre `(c0, s0)` of the enclosure (0 or ±1 when the
/// enclosure holds it, the simplest coefficients for the solver):
///
/// `x' = c0 x + s0 y + e1`, `y' = c0 y - s0 x + e2`,
/// `|e1|, |e2| <= u`, `u = d (|x| + |y|)` (`abs` as `ite`),
///
/// with `d = max(dc, ds)`, `dc = max(c_hi - c0, c0 - c_lo)` and `ds` likewise (computed
/// exactly). The true rotation `c x + s y = c0 x + s0 y + (c - c0) x + (s - s0) y`
/// satisfies these (take the slacks to be the error terms: `|(c - c0) x + (s - s0) y|
/// <= dc |x| + ds |y| <= u`), so the set of local points queried contains the true one;
/// chained rotations compose the same way, each on the exactly rotated coordinates of
/// the one before. A counterexample may then be one of the neighbouring rotations: a
/// false alarm only for footprints within `2 d |p - o|` (about 1e-15 of the distance
/// from the pose's origin) of each other, never a false proof.
///
/// Measured alternatives (sorting.chor): a constant slack `(dc + ds) R` from a bound
/// `R` on the footprint's size, and fresh rotated coordinates within the slack, both
/// made two separation queries time out (nlsat), so this form stays; one shared bound
/// `u` for both slacks was faster than two (Handover).
fn to_local(enc: &mut Encoder, role: RoleId, p: &[Real; 3]) -> Result<[Real; 3], Unsupported> {
    let prog = enc.prog();
    let pose = prog.role(role).pose.clone();
    let mut v = p.clone();
    for (k, c) in v.iter_mut().enumerate() {
        if let Some(o) = pose.get(k) {
            if !is_zero(prog, o) {
                *c = Real::sub(&[c.clone(), enc.real(o)?]);
            }
        }
    }
    // Undo yaw (about z), then pitch (about y), then roll (about x).
    for (idx, axes) in [(5usize, (0usize, 1usize)), (4, (2, 0)), (3, (1, 2))] {
        let Some(angle) = pose.get(idx) else { continue };
        if let Some((c, s)) = bounds::quarter_turn(prog, angle) {
            // An exact multiple of π/2 (`pi / 2`, `-pi`, ...): cos and sin are exactly 0
            // or ±1, so the rotation is exact, with no slack (0 is no rotation at all).
            if (c, s) != (1, 0) {
                let (x, y) = (v[axes.0].clone(), v[axes.1].clone());
                let turn = |k: i64, r: &Real| match k {
                    0 => None,
                    1 => Some(r.clone()),
                    _ => Some(r.unary_minus()),
                };
                // x' = c x + s y, y' = c y - s x.
                let sum = |p: Option<Real>, q: Option<Real>| match (p, q) {
                    (Some(p), Some(q)) => Real::add(&[p, q]),
                    (Some(p), None) | (None, Some(p)) => p,
                    (None, None) => Real::from_rational_str("0", "1").expect("literal"),
                };
                v[axes.0] = sum(turn(c, &x), turn(s, &y));
                v[axes.1] = sum(turn(c, &y), turn(-s, &x));
            }
            continue;
        }
        let iv = bounds::eval(prog, angle, &bounds::closed)
            .filter(|i| i.is_finite())
            .ok_or_else(|| Unsupported("a pose angle that is not a constant".into()))?;
        if iv.is_exactly(0.0) {
            continue;
        }
        let (x, y) = (v[axes.0].clone(), v[axes.1].clone());
        let bad = || Unsupported("a pose angle whose cosine or sine cannot be enclosed".into());
        let (c0, dc) = centre(bounds::trig(Builtin::Cos, Some(iv))).ok_or_else(bad)?;
        let (s0, ds) = centre(bounds::trig(Builtin::Sin, Some(iv))).ok_or_else(bad)?;
        let r = |q: &BigRational| real_of_rational(q).ok_or_else(bad);
        let d = r(&std::cmp::max(dc, ds))?;
        let (c0, s0) = (r(&c0)?, r(&s0)?);
        let zero = Real::from_rational_str("0", "1").expect("literal");
        let abs = |r: &Real| r.ge(&zero).ite(r, &r.unary_minus());
        let bound = Real::mul(&[d, Real::add(&[abs(&x), abs(&y)])]);
        let u = Real::fresh_const("rot_bound");
        enc.require(u.eq(&bound));
        // Rotation by -angle in the (x, y) plane of these axes, with its slack.
        let mut slack = || {
            let e = Real::fresh_const("rot_slack");
            enc.require(Bool::and(&[e.le(&u), e.ge(u.unary_minus())]));
            e
        };
        let (e1, e2) = (slack(), slack());
        v[axes.0] = Real::add(&[Real::mul(&[c0.clone(), x.clone()]), Real::mul(&[s0.clone(), y.clone()]), e1]);
        v[axes.1] = Real::add(&[Real::mul(&[c0, y]), Real::mul(&[s0, x]).unary_minus(), e2]);
    }
    Ok(v)
}

/// A rational centre `m` of the enclosure `iv` and the exact radius around it,
/// `max(hi - m, m - lo)`; `m` is 0, 1 or -1 when `iv` holds it, else the double nearest
/// the midpoint.
fn centre(iv: Interval) -> Option<(BigRational, BigRational)> {
    let m = [0.0, 1.0, -1.0].into_iter().find(|m| iv.lo <= *m && *m <= iv.hi).unwrap_or(iv.lo / 2.0 + iv.hi / 2.0);
    let q = BigRational::from_float;
    let (lo, hi, mid) = (q(iv.lo)?, q(iv.hi)?, q(m)?);
    let r = std::cmp::max(&hi - &mid, &mid - &lo);
    Some((mid, r))
}

fn is_zero(prog: &Program, e: &Expr) -> bool {
    bounds::eval(prog, e, &bounds::closed).is_some_and(|i| i.is_exactly(0.0))
}

fn compat(q: &mut Query, hs: &[Expr], parts: &[(RoleId, PrimApp)], part: &Part) -> Result<(), Unsupported> {
    if matches!(part, Part::CanEnd | Part::CanStart) {
        hyps(q, hs)?;
    } else {
        hyps(q, &slice(q.enc.prog(), hs, seeds_of(q.enc.prog(), parts)))?;
    }
    let t = q.enc.named_real("time");
    let mut insts = Vec::new();
    for (r, app) in parts {
        insts.push(Inst::new(&mut q.enc, *r, app, t.clone(), "t")?);
    }
    connect(q, &mut insts);
    match part {
        // No hypotheses sliced away: a contradiction anywhere in Σ must show.
        Part::CanEnd => ends(q, &insts, &t)?,
        Part::CanStart => {
            for inst in &insts {
                inst.started(q)?;
            }
        }
        Part::Pre(i) => {
            let inst = &insts[*i];
            if let Some(inv) = q.enc.prog().kind(inst.prim.kind).invariant.clone() {
                let b = inst.pred(&mut q.enc, &inv, &inst.start_frame())?;
                q.assertions.push(b);
            }
            let pre = inst.pred(&mut q.enc, &inst.prim.pre, &inst.start_frame())?;
            q.assertions.push(pre.not());
        }
        Part::Assume(i) => {
            for (j, inst) in insts.iter().enumerate() {
                inst.started(q)?;
                if j == *i {
                    // Its own guarantee is not assumed: that would be circular.
                    q.assertions.push(t.ge(zero()));
                } else {
                    inst.running(q)?;
                }
            }
            let a = insts[*i].pred(&mut q.enc, &insts[*i].prim.assume, &insts[*i].frame)?;
            q.assertions.push(a.not());
        }
        Part::Disjoint(i, j) => {
            for inst in &insts {
                inst.started(q)?;
                inst.running(q)?;
            }
            let p = world_point(q);
            insts[*i].occupies(q, &p)?;
            insts[*j].occupies(q, &p)?;
            q.point = Some(p);
            q.times = vec![t];
        }
        Part::Within(n, j) => {
            for inst in &insts {
                inst.started(q)?;
            }
            let (nlo, nhi) = insts[*n].duration(&mut q.enc)?;
            let (jlo, jhi) = insts[*j].duration(&mut q.enc)?;
            let inside = match (nhi, jhi) {
                (_, None) => jlo.le(&nlo),
                (Some(nhi), Some(jhi)) => Bool::and(&[jlo.le(&nlo), nhi.le(&jhi)]),
                // An unbounded non-interruptible duration never fits a bounded one.
                (None, Some(_)) => Bool::from_bool(false),
            };
            q.assertions.push(inside.not());
        }
        Part::Meet => {
            for inst in &insts {
                inst.started(q)?;
            }
            let mut ds = Vec::new();
            for inst in &insts {
                ds.push(inst.duration(&mut q.enc)?);
            }
            let mut ok = Vec::new();
            for (lo, _) in &ds {
                for (_, hi) in &ds {
                    if let Some(hi) = hi {
                        ok.push(lo.le(hi));
                    }
                }
            }
            q.assertions.push(Bool::and(&ok).not());
        }
        _ => return Err(Unsupported("an [AGCOMP] obligation split into a part of another kind".into())),
    }
    Ok(())
}

/// Inputs read the state of the participant they are connected to, when it moves in
/// the same joint motion.
fn connect(q: &mut Query, insts: &mut [Inst]) {
    let prog = q.enc.prog();
    let mut eqs = Vec::new();
    for a in insts.iter() {
        for (i, src) in prog.role(a.role).input_sources.iter().enumerate() {
            let Some(src) = src else { continue };
            let Some(b) = insts.iter().find(|b| b.role == *src) else { continue };
            let name = &prog.kind_of(a.role).inputs[i].0;
            let Some((slot, _)) = prog.kind_of(*src).slot(name) else { continue };
            if let (Some(x), Some(y)) = (a.frame.own.get(&Slot::Input(i)), b.frame.own.get(&slot)) {
                eqs.extend(x.equals(y));
            }
        }
    }
    q.assertions.extend(eqs);
}

fn refine(q: &mut Query, role: RoleId, c: &PrimApp, ss: &[PrimApp], item: RefineItem) -> Result<(), Unsupported> {
    let t = q.enc.named_real("time");
    let ci = Inst::new(&mut q.enc, role, c, t.clone(), "t")?;
    let mut sis = Vec::new();
    for s in ss {
        let mut si = Inst::new(&mut q.enc, role, s, t.clone(), "t")?;
        // The same participant: the abstract primitive reads the same state.
        si.frame.own = ci.frame.own.clone();
        sis.push(si);
    }
    let sf = ci.start_frame();
    // Pre_S of the meet is the disjunction of the abstract preconditions.
    let mut pres = Vec::new();
    for si in &sis {
        pres.push(si.pred(&mut q.enc, &si.prim.pre, &sf)?);
    }
    let pre_s = Bool::or(&pres);
    let all =
        |q: &mut Query, f: &dyn Fn(&Primitive) -> &Expr, frame: &Frame, conj: bool| -> Result<Bool, Unsupported> {
            let mut bs = Vec::new();
            for si in &sis {
                let fr = Frame { params: si.frame.params.clone(), ..frame.clone() };
                bs.push(si.pred(&mut q.enc, f(si.prim), &fr)?);
            }
            Ok(if conj { Bool::and(&bs) } else { Bool::or(&bs) })
        };
    if let Some(inv) = q.enc.prog().kind(ci.prim.kind).invariant.clone() {
        let b = ci.pred(&mut q.enc, &inv, &sf)?;
        q.assertions.push(b);
    }
    match item {
        RefineItem::Realisable => {
            q.assertions.push(pre_s);
            ends(q, std::slice::from_ref(&ci), &t)?;
        }
        RefineItem::Pre => {
            let pc = ci.pred(&mut q.enc, &ci.prim.pre, &sf)?;
            q.assertions.extend([pre_s, pc.not()]);
        }
        RefineItem::Assume => {
            let a_s = all(q, &|p| &p.assume, &ci.frame, false)?;
            let a_c = ci.pred(&mut q.enc, &ci.prim.assume, &ci.frame)?;
            q.assertions.extend([pre_s, t.ge(zero()), a_s, a_c.not()]);
        }
        RefineItem::Guarantee | RefineItem::Footprint => {
            q.assertions.push(pre_s);
            ci.running(q)?;
            if item == RefineItem::Guarantee {
                let g_s = all(q, &|p| &p.guarantee, &ci.frame, true)?;
                q.assertions.push(g_s.not());
            } else {
                let p = world_point(q);
                let fc = ci.footprint(&mut q.enc, &p)?;
                let mut fs = Vec::new();
                for si in &sis {
                    let si_now = Inst { frame: Frame { own: ci.frame.own.clone(), ..si.frame.clone() }, ..si.clone() };
                    fs.push(si_now.footprint(&mut q.enc, &p)?);
                }
                q.assertions.extend([fc, Bool::and(&fs).not()]);
                q.point = Some(p);
                q.times = vec![t];
            }
        }
        RefineItem::Post => {
            let end = end_frame(&mut q.enc, &ci)?;
            let pc = ci.pred(&mut q.enc, &ci.prim.post, &end)?;
            let p_s = all(q, &|p| &p.post, &end, true)?;
            if let Some(inv) = q.enc.prog().kind(ci.prim.kind).invariant.clone() {
                let b = ci.pred(&mut q.enc, &inv, &end)?;
                q.assertions.push(b);
            }
            q.assertions.extend([pre_s, pc, p_s.not()]);
        }
        RefineItem::Duration => {
            q.assertions.push(pre_s);
            let (clo, chi) = ci.duration(&mut q.enc)?;
            // The meet's duration is the intersection of the abstract ones.
            let mut nested = Vec::new();
            for si in &sis {
                let si_start = Inst { frame: Frame { own: ci.start.clone(), ..si.frame.clone() }, ..si.clone() };
                let (slo, shi) = si_start.duration(&mut q.enc)?;
                let (outer_lo, outer_hi, inner_lo, inner_hi) = if ci.prim.interruptible {
                    (clo.clone(), chi.clone(), slo, shi) // D_s ⊆ D_c
                } else {
                    (slo, shi, clo.clone(), chi.clone()) // D_c ⊆ D_s
                };
                let hi_ok = match (inner_hi, outer_hi) {
                    (_, None) => Bool::from_bool(true),
                    (Some(i), Some(o)) => i.le(&o),
                    (None, Some(_)) => Bool::from_bool(false),
                };
                nested.push(Bool::and(&[outer_lo.le(&inner_lo), hi_ok]));
            }
            q.assertions.push(Bool::and(&nested).not());
        }
    }
    Ok(())
}

/// The frame at the end of the motion: own variables are fresh `role.x(end)`.
fn end_frame(enc: &mut Encoder, inst: &Inst) -> Result<Frame, Unsupported> {
    let prog = enc.prog();
    let kind = prog.kind_of(inst.role);
    let mut own = inst.frame.own.clone();
    for i in 0..kind.state.len() {
        let (n, sort) = kind.var(Slot::State(i)).clone();
        own.insert(Slot::State(i), enc.named(&format!("{}.{n}(end)", prog.role_name(inst.role)), &sort)?);
    }
    Ok(Frame { own, clock: None, ..inst.frame.clone() })
}

/// Separation: first by boxes (a sound enclosure of each run's footprint in the world;
/// disjoint boxes are the partition of [AGCOMP], inferred), then by queries for the
/// pairs of runs whose boxes meet.
fn separation_plan(prog: &Program, sides: &[Side]) -> Plan {
    // Every side of `*` moves (Def 4.4 (3)); a side listing no run means the context
    // stage recorded nothing, and "nothing to compare" must not read as "separated".
    if let Some(i) = sides.iter().position(|s| s.runs.is_empty()) {
        return Plan::Unknown(Unsupported(format!("a side of `*` (side {}) whose motions were not recorded", i + 1)));
    }
    // Per run too: two runs whose boxes are disjoint need no query even when their
    // sides' boxes meet (the boxes are sound enclosures, rotations included).
    let run_boxes: Vec<Vec<Option<[Interval; 3]>>> =
        sides.iter().map(|s| s.runs.iter().map(|r| run_box(prog, r)).collect()).collect();
    let boxes: Vec<Option<[Interval; 3]>> = run_boxes.iter().map(|rs| hull_all(rs)).collect();
    let apart = |x: &Option<[Interval; 3]>, y: &Option<[Interval; 3]>| match (x, y) {
        (Some(x), Some(y)) => (0..3).any(|k| x[k].disjoint(y[k])),
        _ => false,
    };
    let mut parts = Vec::new();
    for a in 0..sides.len() {
        for b in a + 1..sides.len() {
            if apart(&boxes[a], &boxes[b]) {
                continue;
            }
            for ra in 0..sides[a].runs.len() {
                for rb in 0..sides[b].runs.len() {
                    if !apart(&run_boxes[a][ra], &run_boxes[b][rb]) {
                        parts.push(Part::Apart { a, ra, b, rb });
                    }
                }
            }
        }
    }
    if parts.is_empty() {
        let described: Vec<String> = boxes
            .iter()
            .zip(sides)
            .filter_map(|(b, s)| {
                let b = b.as_ref()?;
                let who: Vec<&str> = s.roles.iter().map(|r| prog.role_name(*r)).collect();
                Some(format!(
                    "{} within x ∈ [{:.3}, {:.3}], y ∈ [{:.3}, {:.3}], z ∈ [{:.3}, {:.3}]",
                    who.join(", "),
                    b[0].lo,
                    b[0].hi,
                    b[1].lo,
                    b[1].hi,
                    b[2].lo,
                    b[2].hi
                ))
            })
            .collect();
        return Plan::Holds((!described.is_empty()).then(|| format!("partition inferred: {}", described.join("; "))));
    }
    Plan::Parts(parts)
}

/// The world box of each side's footprints, where they can be bounded (for reports: the
/// driver lists an inferred partition's boxes in JSON).
pub fn side_boxes(prog: &Program, sides: &[Side]) -> Vec<Option<[Interval; 3]>> {
    sides.iter().map(|s| side_box(prog, s)).collect()
}

/// A world box around every footprint of a side, if each can be bounded.
fn side_box(prog: &Program, side: &Side) -> Option<[Interval; 3]> {
    hull_all(&side.runs.iter().map(|r| run_box(prog, r)).collect::<Vec<_>>())
}

/// The hull of boxes, if each is bounded (`None` for none).
fn hull_all(boxes: &[Option<[Interval; 3]>]) -> Option<[Interval; 3]> {
    let mut acc: Option<[Interval; 3]> = None;
    for b in boxes {
        let b = (*b)?;
        acc = Some(match acc {
            None => b,
            Some(a) => [a[0].hull(b[0]), a[1].hull(b[1]), a[2].hull(b[2])],
        });
    }
    acc
}

/// A world box around one run's footprint, from the ranges its context, precondition,
/// guarantee and invariant give the variables.
pub fn run_box(prog: &Program, run: &Run) -> Option<[Interval; 3]> {
    let prim = prog.prim(run.app.prim);
    let fp = prim.footprint.as_ref()?;
    // Ranges of the shared vocabulary (start state, values) from the context.
    let inv = prog.kind(prim.kind).invariant.as_ref();
    let start: Vec<&Expr> = run.hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &start, &bounds::closed);
    let shared_lookup = |v: &Var| shared.get(v).copied();
    // In the primitive's frame: old(x) and the start are the participant's `Role` vars.
    let role = run.role;
    let args = &run.app.args;
    let lift = |v: &Var| -> Option<Interval> {
        match v {
            Var::Old(i) => shared_lookup(&Var::Role(role, Slot::State(*i))),
            Var::Param(i) => args.get(*i).and_then(|a| bounds::eval(prog, a, &shared_lookup)),
            Var::Clock => Some(Interval { lo: 0.0, hi: f64::INFINITY }),
            _ => None,
        }
    };
    let mut facts: Vec<&Expr> = vec![&prim.guarantee];
    facts.extend(inv);
    let own = bounds::ranges_from(prog, &facts, &lift);
    // Old(x) gets its range from the start facts and from the invariant over Own.
    let all = |v: &Var| -> Option<Interval> {
        let o = own.get(v).copied();
        let l = lift(v);
        match (o, l) {
            (Some(a), Some(b)) => Some(a.meet(b)),
            (a, b) => a.or(b),
        }
    };
    let point = |v: &Var| match v {
        Var::Point(k) => Some(*k),
        _ => None,
    };
    let local = bounds::point_box(prog, &fp.pred, &point, &all);
    if !local.iter().all(Interval::is_finite) {
        return None;
    }
    to_world(prog, role, local)
}

/// Moves a box from `role`'s frame into the world (interval arithmetic on the pose).
fn to_world(prog: &Program, role: RoleId, b: [Interval; 3]) -> Option<[Interval; 3]> {
    let pose = &prog.role(role).pose;
    let num = |i: usize| -> Option<Interval> {
        match pose.get(i) {
            Some(e) => bounds::eval(prog, e, &bounds::closed),
            None => Some(Interval::point(0.0)),
        }
    };
    let mut v = b;
    // Apply roll (x), pitch (y), yaw (z): world = o + Rz Ry Rx local.
    for (idx, (a, c)) in [(3usize, (1usize, 2usize)), (4, (2, 0)), (5, (0, 1))] {
        let angle = num(idx)?;
        if angle.is_exactly(0.0) {
            continue;
        }
        // An exact quarter turn rotates the box exactly (0 and ±1 are exact doubles).
        let (cs, sn) = match pose.get(idx).and_then(|e| bounds::quarter_turn(prog, e)) {
            Some((cs, sn)) => (Interval::point(cs as f64), Interval::point(sn as f64)),
            None => (bounds::trig(Builtin::Cos, Some(angle)), bounds::trig(Builtin::Sin, Some(angle))),
        };
        let (x, y) = (v[a], v[c]);
        v[a] = cs * x + -(sn * y);
        v[c] = sn * x + cs * y;
    }
    for (k, c) in v.iter_mut().enumerate() {
        *c = *c + num(k)?;
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::super::Decision;

    /// [T-SESS] on two bodies: A's footprint the corner `0 <= x <= 1, 0 <= y <= 0.1,
    /// x + y <= cut` at the origin; B's the bar `1 <= x <= 2, |y| <= 0.1` turned by
    /// `yaw` at `(0.5, -0.9)`. A quarter turn puts B's near corner exactly at
    /// `(0.4, 0.1)`: the bodies touch when `cut` is 0.5, and are apart when it is less.
    fn corner_and_bar(yaw: &str, cut: &str) -> Decision {
        let src = format!(
            "robot BotA {{ state s: real; }} robot BotB {{ state s: real; }}
             motion BotA.hold {{ interruptible: true; footprint(x, y, z): 0 <= x <= 1 && 0 <= y <= 0.1 && x + y <= {cut} && -0.1 <= z <= 0.1; }}
             motion BotB.hold {{ interruptible: true; footprint(x, y, z): 1 <= x <= 2 && -0.1 <= y <= 0.1 && -0.1 <= z <= 0.1; }}
             system S {{ participant A: BotA {{ init: s == 0; }} participant B: BotB {{ init: s == 0; at: pose(0.5, -0.9, 0, 0, 0, {yaw}); }} }}
             choreography G = dt<A: hold> * dt<B: hold>;"
        );
        crate::smt::tests::initial_states(&src)
    }

    #[test]
    fn a_quarter_turn_of_pi_rotates_exactly() {
        // Touching at one rotated corner: an overlap, found (and replayed) exactly.
        let Decision::Fails(f) = corner_and_bar("pi / 2", "0.5") else { panic!("the corner touches the bar") };
        let o = f.overlap.expect("a point");
        assert!((o.point[0] - 0.4).abs() < 1e-9 && (o.point[1] - 0.1).abs() < 1e-9, "{o:?}");
        // A gap of 1e-20 is proved: no slack, no rounding (the slack of an enclosed
        // rotation is about 1e-15 here).
        assert_eq!(corner_and_bar("pi / 2", "0.49999999999999999999"), Decision::Holds(None));
        assert_eq!(corner_and_bar("-3 * pi / 2", "0.49999999999999999999"), Decision::Holds(None));
        assert_eq!(corner_and_bar("pi - pi / 2", "0.49999999999999999999"), Decision::Holds(None));
    }

    #[test]
    fn witnesses_compare_with_pi_through_its_enclosure() {
        let facts = |p: &str| {
            let src = format!(
                "robot R {{ state x: real, c: real; }} system S {{ participant A: R; participant B: R; }}
                 choreography G = A -> B : [{p}] go. end;"
            );
            let (prog, g) = crate::lower::tests::first_guard(&src);
            let fs: Vec<crate::hir::Expr> = g.conjuncts().into_iter().cloned().collect();
            (prog, fs)
        };
        let shown = |p: &str| {
            let (prog, fs) = facts(p);
            super::witnessed(&prog, &fs)
        };
        assert!(shown("x == 0 && -pi <= c && c <= pi"));
        assert!(shown("x == 3.1415926535897 && x < pi && 2 * x - pi > 0"));
        // Never a witness that depends on π's digits, and never one for an empty set.
        assert!(!shown("x == 3.14159265358979323846 && x < pi"));
        assert!(!shown("x == 3.2 && x < pi"));
        assert!(!shown("c > pi && c < 3.14"));
    }

    #[test]
    fn a_decimal_quarter_turn_is_not_exact() {
        // 1.5707963267948966 is not π/2: its rotation is enclosed with a slack, so a gap
        // of 1e-20 cannot be proved (it is not a quarter turn's gap to begin with).
        assert!(!matches!(corner_and_bar("1.5707963267948966", "0.49999999999999999999"), Decision::Holds(_)));
        // 1.5708 turns B's corner about 4e-6 past the exact one, into A: a genuine
        // overlap that treating 1.5708 as a quarter turn would miss.
        assert!(matches!(corner_and_bar("1.5708", "0.499999999999"), Decision::Fails(_)));
    }
}
