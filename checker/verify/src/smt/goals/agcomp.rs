//! [AGCOMP] (Sec 3.4): the parts of a joint motion `dt<p1: a1, ..., pn: an>` compose when
//! each part's precondition holds at the `dt` ("compatible from Pre"), the others'
//! guarantees discharge each part's assumption, their footprints are pairwise disjoint at
//! every time, their durations fit (a non-interruptible part's within every interruptible
//! one's, every other non-interruptible part's the same single instant: joint end,
//! ARCHITECTURE.md; or, with none, a common time), and the joint motion can end. This module plans those parts
//! and builds their queries; pairs of footprints whose boxes are apart are proved by
//! [`super::boxes`] without a query.

use super::super::encode::zero;
use super::super::encode::{Frame, Unsupported};
use super::boxes::{app_box, meeting_pairs};
use super::frames::world_point;
use super::hyps;
use super::motion::{ends, Inst};
use super::{Part, Plan, Query};
use crate::bounds::{self, Interval};
use crate::hir::expr::BinOp;
use crate::hir::{Expr, ExprKind, PrimApp, Program, RoleId, Slot, Var};
use crate::sigma::cone::{seeds_of, slice};
use std::collections::HashMap;
use z3::ast::{Bool, Real};

/// The parts of a `dt`'s [AGCOMP] obligation.
pub(super) fn plan(prog: &Program, hyps: &[Expr], parts: &[(RoleId, PrimApp)]) -> Plan {
    let mut out = Vec::new();
    // The ranges Σ gives the variables at the `dt` (they hold of every state it allows).
    let facts: Vec<&Expr> = hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &facts, &bounds::closed);
    // A lone primitive's precondition is [T-MOTION]'s to check, in its process; in a
    // protocol without processes nobody else checks it, so it is asked here. One that the
    // ranges alone decide needs no query.
    let lone = parts.len() == 1 && !prog.processes.is_empty();
    for (i, (role, app)) in parts.iter().enumerate() {
        let p = prog.prim(app.prim);
        // An argument with a partial operator must be defined (`hir::expr::definedness`),
        // whatever the precondition: asked by the same part.
        let partial = app.args.iter().any(|a| !crate::hir::expr::definedness(a).is_true());
        if partial || (!p.pre.is_true() && !lone && !pre_by_intervals(prog, *role, app, &shared)) {
            out.push(Part::Pre(i));
        }
        if !p.assume.is_true() {
            out.push(Part::Assume(i));
        }
    }
    // A part with no footprint may occupy all space and meets every other footprint.
    if parts.len() > 1 {
        if let Some(who) = without_footprint(prog, parts) {
            return Plan::Fails(format!(
                "`{}` of `{}` declares no footprint, so it may occupy all space and meets every other footprint",
                prog.prim(who.1.prim).name,
                prog.role_name(who.0)
            ));
        }
    }
    // Footprints pairwise disjoint: a pair whose boxes are apart is proved by the boxes
    // (sound enclosures of each footprint over its whole motion, from the context at the
    // `dt`); only the pairs whose boxes meet, or that cannot be bounded, become queries.
    let facts: Vec<&Expr> = hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &facts, &bounds::closed);
    let boxes: Vec<_> = parts.iter().map(|(r, app)| app_box(prog, *r, app, &shared)).collect();
    out.extend(meeting_pairs(&boxes).into_iter().map(|(i, j)| Part::Disjoint(i, j)));
    // Every part against every static obstacle, at every time: the obstacle is there
    // whatever the protocol does. Pairs whose boxes are apart need no query.
    if !prog.obstacles.is_empty() {
        if let Some(who) = without_footprint(prog, parts) {
            return Plan::Fails(format!(
                "`{}` of `{}` declares no footprint, so it may occupy all space and meets every obstacle",
                prog.prim(who.1.prim).name,
                prog.role_name(who.0)
            ));
        }
        let obstacle_boxes: Vec<_> = prog.obstacles.iter().map(|o| obstacle_box(prog, o)).collect();
        for (i, b) in boxes.iter().enumerate() {
            for (o, ob) in obstacle_boxes.iter().enumerate() {
                if !super::boxes::apart(b, ob) {
                    out.push(Part::ClearOf { i, o });
                }
            }
        }
    }
    // The first non-interruptible part ends the motion. Every other non-interruptible
    // part must end at the same time (joint end: equal singleton durations, E0401), and
    // every interruptible one be ready then (its duration contains the first's, E0405).
    let non: Vec<usize> = (0..parts.len()).filter(|&i| !prog.prim(parts[i].1.prim).interruptible).collect();
    match non.first() {
        Some(&n) => out.extend((0..parts.len()).filter(|&j| j != n).map(|j| {
            if non.contains(&j) {
                Part::CommonEnd(n, j)
            } else {
                Part::Within(n, j)
            }
        })),
        None if parts.len() > 1 => out.push(Part::Meet),
        None => {}
    }
    // One can-end question for the whole `dt`: the parts end together. Asked after the
    // durations, so that durations that cannot fit are reported as such (E0401, E0405)
    // rather than as a motion that cannot end (E0408); all parts must hold either way.
    out.push(Part::CanEnd);
    Plan::Parts(out)
}

pub(super) fn compat(q: &mut Query, hs: &[Expr], parts: &[(RoleId, PrimApp)], part: &Part) -> Result<(), Unsupported> {
    let prog = q.enc.prog();
    // The parts the question is about: a pair's footprints (with the parts whose state
    // their inputs read, transitively: an input is its source's state while both move),
    // one part's precondition, one part's assumption (with the parts its inputs read), two
    // parts' durations; every part for the joint questions (can end, can start, a common
    // time). Leaving the others out drops
    // hypotheses only, which can turn "holds" into "fails" but never the reverse, and
    // keeps a query's size independent of the number of parts (a wide `dt`'s pairs would
    // otherwise cost n² in all, or n³ without the boxes).
    let about: Vec<usize> = match part {
        Part::Disjoint(i, j) => with_sources(prog, parts, &[*i, *j]),
        Part::Pre(i) => vec![*i],
        // An assumption reads the part's own state and inputs: the partners whose
        // guarantees can discharge it are the ones its inputs read (transitively).
        Part::Assume(i) => with_sources(prog, parts, &[*i]),
        Part::Within(n, j) | Part::CommonEnd(n, j) => with_sources(prog, parts, &[*n, *j]),
        Part::ClearOf { i, .. } => with_sources(prog, parts, &[*i]),
        _ => (0..parts.len()).collect(),
    };
    let mut at = vec![None; parts.len()];
    for (k, &p) in about.iter().enumerate() {
        at[p] = Some(k);
    }
    let at = |p: usize| at.get(p).copied().flatten().ok_or_else(|| Unsupported("an [AGCOMP] part out of range".into()));
    let sub: Vec<(RoleId, PrimApp)> = about.iter().map(|&p| parts[p].clone()).collect();
    if matches!(part, Part::CanEnd | Part::CanStart) {
        hyps(q, hs)?;
    } else {
        hyps(q, &slice(prog, hs, seeds_of(prog, &sub)))?;
    }
    let t = q.enc.named_real("time");
    let mut insts = Vec::new();
    for (r, app) in &sub {
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
            let inst = &insts[at(*i)?];
            if let Some(inv) = q.enc.prog().kind(inst.prim.kind).invariant.clone() {
                let b = inst.pred(&mut q.enc, &inv, &inst.start_frame())?;
                q.assertions.push(b);
            }
            let pre = inst.pred(&mut q.enc, &inst.prim.pre, &inst.start_frame())?;
            q.assertions.push(Bool::and(&[inst.args_defined.clone(), pre]).not());
        }
        Part::Assume(i) => {
            let i = at(*i)?;
            for (j, inst) in insts.iter().enumerate() {
                inst.started(q)?;
                if j == i {
                    // Its own guarantee is not assumed: that would be circular.
                    q.assertions.push(t.ge(zero()));
                } else {
                    inst.running(q)?;
                }
            }
            let a = insts[i].pred(&mut q.enc, &insts[i].prim.assume, &insts[i].frame)?;
            q.assertions.push(a.not());
        }
        Part::Disjoint(i, j) => {
            for inst in &insts {
                inst.started(q)?;
                inst.running(q)?;
            }
            let p = world_point(q);
            insts[at(*i)?].occupies(q, &p)?;
            insts[at(*j)?].occupies(q, &p)?;
            q.point = Some(p);
            q.times = vec![t];
        }
        Part::ClearOf { i, o } => {
            for inst in &insts {
                inst.started(q)?;
                inst.running(q)?;
            }
            let obstacle = prog.obstacles.get(*o).ok_or_else(|| Unsupported("an obstacle out of range".into()))?;
            let region = crate::space::region::obstacle_region(prog, obstacle).ok_or_else(|| {
                Unsupported(format!(
                    "obstacle `{}` has a URDF or mesh part, which the SMT solver cannot represent",
                    obstacle.name
                ))
            })?;
            let p = world_point(q);
            insts[at(*i)?].occupies(q, &p)?;
            let frame = Frame { point: Some(p.clone()), ..Frame::default() };
            let inside = q.enc.in_frame(&frame, |enc| enc.boolean(&region))?;
            q.assertions.push(inside);
            q.point = Some(p);
            q.times = vec![t];
        }
        Part::Within(n, j) => {
            for inst in &insts {
                inst.started(q)?;
            }
            let (nlo, nhi) = insts[at(*n)?].duration(&mut q.enc)?;
            let (jlo, jhi) = insts[at(*j)?].duration(&mut q.enc)?;
            let inside = match (nhi, jhi) {
                (_, None) => jlo.le(&nlo),
                (Some(nhi), Some(jhi)) => Bool::and(&[jlo.le(&nlo), nhi.le(&jhi)]),
                // An unbounded non-interruptible duration never fits a bounded one.
                (None, Some(_)) => Bool::from_bool(false),
            };
            q.assertions.push(inside.not());
        }
        Part::CommonEnd(n, j) => {
            for inst in &insts {
                inst.started(q)?;
            }
            let (nlo, nhi) = insts[at(*n)?].duration(&mut q.enc)?;
            let (jlo, jhi) = insts[at(*j)?].duration(&mut q.enc)?;
            let same = match (nhi, jhi) {
                // Both end exactly at `nlo`: each duration is that one instant.
                (Some(nhi), Some(jhi)) => Bool::and(&[nlo.eq(&nhi), jlo.eq(&jhi), nlo.eq(&jlo)]),
                // An unbounded duration is never a single instant.
                _ => Bool::from_bool(false),
            };
            q.assertions.push(same.not());
        }
        Part::Meet => {
            for inst in &insts {
                inst.started(q)?;
            }
            let mut ds = Vec::new();
            for inst in &insts {
                ds.push(inst.duration(&mut q.enc)?);
            }
            // They share a time iff no part ends before another starts (every lo_i <= every
            // hi_j). Asked as: the latest start `m` (no lower end exceeds it, and it is one
            // of them) lies after some upper end, in a query linear in the parts (the
            // n² comparisons of every pair made a wide `dt`'s query quadratic). Equivalent:
            // lo_i > hi_j gives m = max lo >= lo_i > hi_j; conversely m = lo_k > hi_j.
            let his: Vec<&Real> = ds.iter().filter_map(|(_, hi)| hi.as_ref()).collect();
            if his.is_empty() || ds.is_empty() {
                // Every part may run for ever: any late enough time is common.
                q.assertions.push(Bool::from_bool(false));
            } else {
                let m = q.enc.named_real("latest start");
                let mut one_of = Vec::new();
                for (lo, _) in &ds {
                    q.assertions.push(m.ge(lo));
                    one_of.push(m.eq(lo));
                }
                q.assertions.push(Bool::or(&one_of));
                let after: Vec<Bool> = his.iter().map(|hi| m.gt(*hi)).collect();
                q.assertions.push(Bool::or(&after));
            }
        }
        _ => return Err(Unsupported("an [AGCOMP] obligation split into a part of another kind".into())),
    }
    Ok(())
}

/// A part whose primitive declares no footprint at all (neither a predicate nor a body):
/// it may occupy all space.
fn without_footprint<'p>(prog: &Program, parts: &'p [(RoleId, PrimApp)]) -> Option<&'p (RoleId, PrimApp)> {
    parts.iter().find(|(_, app)| !prog.prim(app.prim).footprint.is_declared())
}

/// A world box around a static obstacle (its region's point box: constants only), or
/// `None` when it cannot be bounded (a URDF or mesh part: every footprint is then asked).
fn obstacle_box(prog: &Program, o: &crate::hir::body::Obstacle) -> Option<[Interval; 3]> {
    let region = crate::space::region::obstacle_region(prog, o)?;
    let point = |v: &Var| match v {
        Var::Point(k) => Some(*k),
        _ => None,
    };
    let b = bounds::point_box(prog, &region, &point, &bounds::closed);
    b.iter().all(Interval::is_finite).then_some(b)
}

/// Whether the precondition of `app`, run by `role`, holds at every state in the ranges
/// `shared` (which Σ gives at the `dt`), by intervals alone: every conjunct a comparison
/// `a op b` whose sides' enclosures ([`bounds::eval`], rounded outwards) are apart the
/// right way. Sound: every state Σ allows lies in the ranges, so Σ ∧ ¬Pre is unsat, the
/// pre part's question. `false` means only "not shown" (the query decides): an equality,
/// a variable with no range, or an empty range (a contradictory Σ, which the vacuity guard
/// reports) never counts.
fn pre_by_intervals(prog: &Program, role: RoleId, app: &PrimApp, shared: &HashMap<Var, Interval>) -> bool {
    let lookup = |v: &Var| shared.get(v).copied();
    let ranges = |v: &Var| -> Option<Interval> {
        let r = match v {
            // In the start frame the participant's own state is Σ's.
            Var::Own(slot @ Slot::State(_)) => lookup(&Var::Role(role, *slot)),
            Var::Old(i) => lookup(&Var::Role(role, Slot::State(*i))),
            Var::Param(i) => app.args.get(*i).and_then(|a| bounds::eval(prog, a, &lookup)),
            _ => None,
        }?;
        (r.lo <= r.hi).then_some(r)
    };
    let certainly = |c: &Expr| {
        let ExprKind::Binary(op, a, b) = &c.kind else { return false };
        let (Some(x), Some(y)) = (bounds::eval(prog, a, &ranges), bounds::eval(prog, b, &ranges)) else {
            return false;
        };
        // Non-empty, NaN-free enclosures only.
        if !(x.lo <= x.hi && y.lo <= y.hi) {
            return false;
        }
        match op {
            BinOp::Le => x.hi <= y.lo,
            BinOp::Lt => x.hi < y.lo,
            BinOp::Ge => x.lo >= y.hi,
            BinOp::Gt => x.lo > y.hi,
            BinOp::Ne => x.hi < y.lo || y.hi < x.lo,
            _ => false,
        }
    };
    prog.prim(app.prim).pre.conjuncts().into_iter().all(certainly)
}

/// `seeds` and the parts whose state their inputs read, transitively, in order.
fn with_sources(prog: &Program, parts: &[(RoleId, PrimApp)], seeds: &[usize]) -> Vec<usize> {
    let mut keep = vec![false; parts.len()];
    let mut todo: Vec<usize> = seeds.iter().copied().filter(|&p| p < parts.len()).collect();
    while let Some(p) = todo.pop() {
        if std::mem::replace(&mut keep[p], true) {
            continue;
        }
        for src in prog.role(parts[p].0).input_sources.iter().flatten() {
            todo.extend(parts.iter().position(|(r, _)| r == src));
        }
    }
    (0..parts.len()).filter(|&p| keep[p]).collect()
}

/// Inputs read the state of the participant they are connected to, when it moves in
/// the same joint motion.
pub(super) fn connect(q: &mut Query, insts: &mut [Inst]) {
    let prog = q.enc.prog();
    let mut eqs = Vec::new();
    // The first instance of each participant (an index, not a search per input: a wide
    // `dt` of participants with inputs would cost n² otherwise).
    let mut first: HashMap<RoleId, usize> = HashMap::new();
    for (k, inst) in insts.iter().enumerate() {
        first.entry(inst.role).or_insert(k);
    }
    for a in insts.iter() {
        for (i, src) in prog.role(a.role).input_sources.iter().enumerate() {
            let Some(src) = src else { continue };
            let Some(b) = first.get(src).map(|&k| &insts[k]) else { continue };
            let name = &prog.kind_of(a.role).inputs[i].0;
            let Some((slot, _)) = prog.kind_of(*src).slot(name) else { continue };
            if let (Some(x), Some(y)) = (a.frame.own.get(&Slot::Input(i)), b.frame.own.get(&slot)) {
                eqs.extend(x.equals(y));
            }
        }
    }
    q.assertions.extend(eqs);
}

#[cfg(test)]
mod tests {
    use super::super::super::{discharge, Decision, SmtConfig};
    use super::super::tests::{first_dt, parts};
    use super::super::Part;

    /// `n` bots in one `dt`, bot `i` at `x == gap * i` with the footprint of a cube of
    /// side 0.2 around its position, held still (`hold`), or for the bots listed in `free`
    /// roaming anywhere (`roam`: the footprint follows `x`, which nothing bounds).
    fn bots(n: usize, gap: &str, free: &[usize]) -> String {
        let mut s = String::from(
            "robot Bot { state x: real; }
             motion Bot.hold { interruptible: true; guarantee: x == old(x); duration: [0, inf];
               footprint(px, py, pz): old(x) - 0.1 <= px <= old(x) + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }
             motion Bot.roam { interruptible: true; duration: [0, inf];
               footprint(px, py, pz): x - 0.1 <= px <= x + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }
             system S {",
        );
        for i in 0..n {
            s.push_str(&format!(" participant B{i}: Bot {{ init: x == {gap} * {i}; }}"));
        }
        s.push_str(" } choreography G = dt<");
        let ps: Vec<String> =
            (0..n).map(|i| format!("B{i}: {}", if free.contains(&i) { "roam" } else { "hold" })).collect();
        s.push_str(&ps.join(", "));
        s.push_str(">. end;");
        s
    }

    fn disjoint_parts(src: &str) -> Vec<(usize, usize)> {
        let (prog, ob) = first_dt(src);
        let ps = parts(&prog, &ob).expect("parts");
        ps.into_iter()
            .filter_map(|p| match p {
                Part::Disjoint(i, j) => Some((i, j)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn footprints_whose_boxes_are_apart_need_no_query() {
        // Failed before the interval index: every one of the 190 pairs was a query.
        assert_eq!(disjoint_parts(&bots(20, "1", &[])), vec![]);
        let (prog, ob) = first_dt(&bots(20, "1", &[]));
        let (d, stats) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0);
        assert_eq!(d, Decision::Holds(None));
        assert!(stats.queries < 20, "{stats:?}");
    }

    #[test]
    fn footprints_whose_boxes_meet_are_queried_and_an_overlap_is_found() {
        // 0.15 apart: neighbours' cubes overlap, and their boxes meet; bots two apart
        // (0.3) have disjoint boxes.
        assert_eq!(disjoint_parts(&bots(4, "0.15", &[])), vec![(0, 1), (1, 2), (2, 3)]);
        let (prog, ob) = first_dt(&bots(4, "0.15", &[]));
        let Decision::Fails(f) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 else {
            panic!("neighbours overlap")
        };
        assert_eq!(f.which, Some(Part::Disjoint(0, 1)));
        // Touching boxes (0.2 apart: the cubes share a face) are a query, and a common
        // point is found: closed sets that touch are not disjoint.
        assert_eq!(disjoint_parts(&bots(3, "0.2", &[])), vec![(0, 1), (1, 2)]);
        let (prog, ob) = first_dt(&bots(3, "0.2", &[]));
        assert!(matches!(discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0, Decision::Fails(_)));
    }

    /// `n` bots a metre apart in one `dt`, bot `i` running `timed(lo_i, hi_i)`: an
    /// interruptible primitive whose duration is its arguments.
    fn timed(durations: &[(u32, u32)]) -> String {
        let mut s = String::from(
            "robot Bot { state x: real; }
             motion Bot.timed(a: real, b: real) { interruptible: true; guarantee: x == old(x); duration: [a, b];
               footprint(px, py, pz): old(x) - 0.1 <= px <= old(x) + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }
             system S {",
        );
        for i in 0..durations.len() {
            s.push_str(&format!(" participant B{i}: Bot {{ init: x == {i}; }}"));
        }
        let ps: Vec<String> =
            durations.iter().enumerate().map(|(i, (a, b))| format!("B{i}: timed({a}, {b})")).collect();
        s.push_str(&format!(" }} choreography G = dt<{}>. end;", ps.join(", ")));
        s
    }

    #[test]
    fn the_durations_share_a_time_in_a_query_linear_in_the_parts() {
        let meet = |ds: &[(u32, u32)]| {
            let (prog, ob) = first_dt(&timed(ds));
            let q = super::super::build(&prog, &ob, &Part::Meet).expect("a query");
            let size: usize = q.assertions.iter().map(|a| a.to_string().len()).sum();
            let d = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0;
            (size, d)
        };
        // [0, 5], [1, 6], [2, 7], ...: all contain [n - 1, 5] while n <= 6.
        let ds = |n: u32| (0..n).map(|i| (i, i + 5)).collect::<Vec<_>>();
        let (small, d) = meet(&ds(5));
        assert_eq!(d, Decision::Holds(None));
        // Failed before: one comparison per pair of parts, a query 4 times as large.
        let (large, _) = meet(&(0..40).map(|_| (0, 5)).collect::<Vec<_>>());
        let (larger, _) = meet(&(0..80).map(|_| (0, 5)).collect::<Vec<_>>());
        assert!(larger < 3 * large, "{large} -> {larger}");
        assert!(small < large);
        // [0, 5] and [6, 7] share no time: the durations part's query has a model (and the
        // obligation fails; its can-end part, asked first, already says so).
        let apart = [(0, 5), (2, 5), (6, 7)];
        assert!(matches!(meet(&apart).1, Decision::Fails(_)));
        let (prog, ob) = first_dt(&timed(&apart));
        let q = super::super::build(&prog, &ob, &Part::Meet).expect("a query");
        let solver = z3::Solver::new();
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            solver.assert(a);
        }
        assert_eq!(solver.check(), z3::SatResult::Sat);
        // Touching ends share the time 5.
        assert_eq!(meet(&[(0, 5), (5, 7)]).1, Decision::Holds(None));
    }

    /// A tail whose assumption reads its input `p`, connected to the leader's state `p`,
    /// with `n` bystanders (no input, no `p`) in the same `dt`.
    fn leader_and_tail(lead_guarantee: &str, n: usize) -> String {
        let cube = |at: &str| {
            format!("footprint(px, py, pz): {at} - 0.1 <= px <= {at} + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1;")
        };
        let mut s = format!(
            "robot Lead {{ state p: real; }} robot Tail {{ state x: real; input p: real; }} robot Bot {{ state x: real; }}
             motion Lead.go {{ interruptible: true; guarantee: {lead_guarantee}; duration: [0, inf]; {} }}
             motion Tail.follow {{ interruptible: true; assume: p >= 0; guarantee: x == old(x); duration: [0, inf]; {} }}
             motion Bot.hold {{ interruptible: true; guarantee: x == old(x); duration: [0, inf]; {} }}
             system S {{ participant L: Lead {{ init: p == 0; }} participant T: Tail {{ init: x == 2; }}",
            cube("-2"),
            cube("old(x)"),
            cube("old(x)")
        );
        for k in 0..n {
            s.push_str(&format!(" participant B{k}: Bot {{ init: x == {}; }}", 4 + 2 * k));
        }
        let bys: String = (0..n).map(|k| format!(", B{k}: hold")).collect();
        s.push_str(&format!(" }} choreography G = dt<L: go, T: follow{bys}>. end;"));
        s
    }

    #[test]
    fn an_assumption_is_discharged_by_the_partner_its_input_reads() {
        let (prog, ob) = first_dt(&leader_and_tail("0 <= p && p <= 1", 6));
        assert!(parts(&prog, &ob).expect("parts").contains(&Part::Assume(1)));
        assert_eq!(discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0, Decision::Holds(None));
        // A leader that may go below 0 does not discharge it, bystanders or not.
        let (prog, ob) = first_dt(&leader_and_tail("-1 <= p && p <= 1", 6));
        let Decision::Fails(f) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 else {
            panic!("the assumption is not discharged")
        };
        assert_eq!(f.which, Some(Part::Assume(1)));
    }

    #[test]
    fn preconditions_the_ranges_decide_need_no_query() {
        // `hold` needs x >= 0 (B_i starts at x == gap * i): a metre apart from 0, the
        // ranges of Σ decide every precondition. Failed before: one query per part.
        let src = |gap: &str| {
            bots(12, gap, &[])
                .replace("interruptible: true; guarantee", "interruptible: true; pre: x >= 0 && x != -1; guarantee")
        };
        let pres = |gap: &str| {
            let (prog, ob) = first_dt(&src(gap));
            let ps = parts(&prog, &ob).expect("parts");
            ps.into_iter().filter(|p| matches!(p, Part::Pre(_))).count()
        };
        assert_eq!(pres("1"), 0);
        // Starting at 0, -1, -2, ...: B0 is decided (0 >= 0), the others are queries, and
        // B1's fails.
        assert_eq!(pres("-1"), 11);
        let (prog, ob) = first_dt(&src("-1"));
        let Decision::Fails(f) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 else {
            panic!("B1 starts below 0")
        };
        assert_eq!(f.which, Some(Part::Pre(1)));
    }

    #[test]
    fn a_footprint_without_a_box_is_compared_with_every_other() {
        // `roam` leaves `x` unbounded while it runs: no box, so every pair with B2 is a
        // query (and fails: B2 may roam into anyone).
        assert_eq!(disjoint_parts(&bots(5, "1", &[2])), vec![(0, 2), (1, 2), (2, 3), (2, 4)]);
        let (prog, ob) = first_dt(&bots(5, "1", &[2]));
        assert!(matches!(discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0, Decision::Fails(_)));
    }

    /// A cart sliding from 0 to `xf` (its footprint the swept box, 0.5 long) and a
    /// 0.2-wide obstacle box standing at x = 2 (placed by its `at:` pose). The obstacle
    /// is built by hand: it is checked against every part of every joint motion.
    fn cart_and_wall(xf: &str) -> Decision {
        use crate::hir::body::{Body, BodyPart, Obstacle, Pose, Shape};
        use crate::hir::{Expr, ExprKind, Loc, Sort};
        let src = format!(
            "robot Cart {{ state x: real; }}
             motion Cart.go(xf: real) {{ interruptible: false; guarantee: old(x) <= x <= xf; post: x == xf; duration: [1, 1];
               footprint(px, py, pz): old(x) - 0.25 <= px <= xf + 0.25 && -0.2 <= py <= 0.2 && 0 <= pz <= 0.1; }}
             system S {{ participant C: Cart {{ init: x == 0; }} }}
             choreography G = dt<C: go({xf})>. end;"
        );
        let (mut prog, ob) = first_dt(&src);
        let lit = |v: &str| Expr { kind: ExprKind::Real(v.into()), sort: Sort::Real, loc: Loc::default() };
        prog.obstacles.push(Obstacle {
            name: "Wall".into(),
            body: Body {
                parts: vec![BodyPart {
                    shape: Shape::Box([lit("0.2"), lit("2"), lit("1")]),
                    place: None,
                    span: Default::default(),
                }],
                span: Default::default(),
            },
            pose: Some(Pose { args: ["2", "0", "0", "0", "0", "0"].map(lit), span: Default::default() }),
            span: Default::default(),
        });
        discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0
    }

    #[test]
    fn a_motion_is_checked_against_every_obstacle() {
        assert_eq!(cart_and_wall("1"), Decision::Holds(None));
        // The wall's near face is at x = 1.9; the swept box's front is at xf + 0.25, so
        // xf = 1.7 reaches 1.95, into the wall.
        let Decision::Fails(f) = cart_and_wall("1.7") else { panic!("the cart reaches into the wall") };
        assert_eq!(f.which, Some(Part::ClearOf { i: 0, o: 0 }));
        let o = f.overlap.expect("a point");
        assert!((1.9..=1.95).contains(&o.point[0]), "{o:?}");
        // Touching is meeting: closed sets.
        assert!(matches!(cart_and_wall("1.65"), Decision::Fails(_)));
        assert_eq!(cart_and_wall("1.6499"), Decision::Holds(None));
    }
}

/// Joint end (ARCHITECTURE.md): several non-interruptible parts compose exactly when
/// their durations are one and the same instant under Σ and the preconditions.
#[cfg(test)]
mod joint_end_tests {
    use super::super::super::{discharge, Decision, SmtConfig};
    use super::super::tests::{first_dt, parts};
    use super::super::Part;

    /// Two bots, each running its own non-interruptible `step` with the given duration
    /// (over its start state `x` and parameter `d`), from the given `init`s, the first
    /// with argument `arg`; and a third holding (interruptible, ready at any time).
    fn two(da: &str, db: &str, ia: &str, ib: &str, arg: &str) -> String {
        format!(
            "robot Bot {{ state x: real; }}
             motion Bot.a(d: real) {{ interruptible: false; guarantee: x == old(x); duration: {da};
               footprint(px, py, pz): old(x) - 0.1 <= px <= old(x) + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }}
             motion Bot.b {{ interruptible: false; guarantee: x == old(x); duration: {db};
               footprint(px, py, pz): old(x) - 0.1 <= px <= old(x) + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }}
             motion Bot.hold {{ interruptible: true; guarantee: x == old(x); duration: [0, inf];
               footprint(px, py, pz): old(x) - 0.1 <= px <= old(x) + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }}
             system S {{ participant A: Bot {{ init: {ia}; }} participant B: Bot {{ init: {ib}; }}
               participant C: Bot {{ init: x == 5; }} }}
             choreography G = dt<A: a({arg}), B: b, C: hold>. end;"
        )
    }

    /// `None` when the `dt` composes, else the part that failed.
    fn failing(src: &str) -> Option<Part> {
        let (prog, ob) = first_dt(src);
        match discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 {
            Decision::Holds { .. } => None,
            Decision::Fails(f) => Some(f.which.expect("a failed part")),
            other => panic!("undecided: {other:?}"),
        }
    }

    #[test]
    fn two_non_interruptible_parts_are_asked_to_end_together() {
        let (prog, ob) = first_dt(&two("[1, 1]", "[1, 1]", "x == 0", "x == 1", "0"));
        let ps = parts(&prog, &ob).expect("parts");
        assert!(ps.contains(&Part::CommonEnd(0, 1)), "{ps:?}");
        assert!(ps.contains(&Part::Within(0, 2)), "{ps:?}");
    }

    #[test]
    fn equal_singletons_end_together() {
        assert_eq!(failing(&two("[5, 5]", "[5, 5]", "x == 0", "x == 1", "0")), None);
        // Exact reals: 0.1 + 0.2 is 3/10.
        assert_eq!(failing(&two("[0.1 + 0.2, 0.1 + 0.2]", "[0.3, 0.3]", "x == 0", "x == 1", "0")), None);
        // Equal under Σ: the parameter and both start states are known.
        assert_eq!(failing(&two("[d + x, d + x]", "[x, x]", "x == 0", "x == 1", "1")), None);
    }

    #[test]
    fn durations_that_may_differ_do_not_end_together() {
        let end = Some(Part::CommonEnd(0, 1));
        // 0.30000000000000004 is the double nearest 0.1 + 0.2, not 3/10.
        assert_eq!(
            failing(&two(
                "[0.1 + 0.2, 0.1 + 0.2]",
                "[0.30000000000000004, 0.30000000000000004]",
                "x == 0",
                "x == 1",
                "0"
            )),
            end
        );
        // Nested, overlapping, not singletons: who ends first is unknown.
        assert_eq!(failing(&two("[1, 1]", "[0, 2]", "x == 0", "x == 1", "0")), end);
        assert_eq!(failing(&two("[1, 2]", "[1, 2]", "x == 0", "x == 1", "0")), end);
        assert_eq!(failing(&two("[1, inf]", "[1, inf]", "x == 0", "x == 1", "0")), end);
        // Read in each participant's own start state: B's x is only known to be in [1, 2].
        assert_eq!(failing(&two("[x + 1, x + 1]", "[x, x]", "x == 0", "1 <= x <= 2", "0")), end);
        // A singleton only at a start state Σ does not fix (x == 0).
        assert_eq!(failing(&two("[1, 1 + x]", "[1, 1]", "0 <= x <= 1", "x == 3", "0")), end);
        // A singleton only for an argument nothing fixes (d == 1).
        assert_eq!(failing(&two("[1, d]", "[1, 1]", "0 <= x <= 1", "x == 3", "A.x + 1")), end);
    }
}
