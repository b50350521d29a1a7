//! Boxes: a sound enclosure, in world coordinates, of the points a run's footprint can
//! cover over its whole motion, by interval arithmetic ([`crate::bounds`], rounded
//! outwards) on the ranges its context, precondition, guarantee and invariant give the
//! variables, moved into the world by the participant's pose. Two footprints whose boxes
//! are disjoint never meet, so separation (Sec 4.1: the sides of `*` need a partition,
//! here inferred), [T-SESS]'s first footprints and [AGCOMP]'s pairwise footprint
//! disjointness ask Z3 only about the pairs whose boxes meet (or cannot be bounded).

use super::super::encode::Unsupported;
use super::{Part, Plan};
use crate::bounds::{self, Interval};
use crate::hir::{Builtin, Expr, Footprint, PrimApp, Program, RoleId, Slot, Var};
use crate::obligation::{Obligation, RoleMotion, Side};
use std::collections::HashMap;

/// [T-SESS]: the first motions of every two participants start with disjoint footprints;
/// boxes first, as for separation: only participants whose boxes meet need Z3.
pub(super) fn initially_disjoint(prog: &Program, ob: &Obligation, firsts: &[(RoleId, Vec<PrimApp>)]) -> Plan {
    // Boxes first, as for separation: only participants whose boxes meet need Z3. The
    // ranges are read once from all of Σ (the initial states), not from a slice per
    // participant (n slices of n facts each); they hold of every state Σ allows.
    let facts: Vec<&Expr> = ob.hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &facts, &bounds::closed);
    let boxes: Vec<Option<[Interval; 3]>> = firsts
        .iter()
        .map(|(role, apps)| hull_all(&apps.iter().map(|a| app_box(prog, *role, a, &shared)).collect::<Vec<_>>()))
        .collect();
    let out: Vec<Part> = meeting_pairs(&boxes).into_iter().map(|(r, s)| Part::InitiallyApart { r, s }).collect();
    if out.is_empty() {
        return Plan::Holds(None);
    }
    Plan::Parts(out)
}

/// Separation: first by boxes (a sound enclosure of each run's footprint in the world;
/// disjoint boxes are the partition of [AGCOMP], inferred), then by queries for the
/// pairs of runs whose boxes meet.
pub(super) fn separation_plan(prog: &Program, sides: &[Side]) -> Plan {
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
    let mut parts = Vec::new();
    // Sides whose boxes meet, by the interval index (no n² loop over the sides of a wide `*`).
    for (a, b) in meeting_pairs(&boxes) {
        for ra in 0..sides[a].runs.len() {
            for rb in 0..sides[b].runs.len() {
                if !apart(&run_boxes[a][ra], &run_boxes[b][rb]) {
                    parts.push(Part::Apart { a, ra, b, rb });
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
pub(super) fn side_box(prog: &Program, side: &Side) -> Option<[Interval; 3]> {
    hull_all(&side.runs.iter().map(|r| run_box(prog, r)).collect::<Vec<_>>())
}

/// The hull of boxes, if each is bounded (`None` for none).
pub(super) fn hull_all(boxes: &[Option<[Interval; 3]>]) -> Option<[Interval; 3]> {
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
pub fn run_box(prog: &Program, run: &RoleMotion) -> Option<[Interval; 3]> {
    // Ranges of the shared vocabulary (start state, values) from the context.
    let start: Vec<&Expr> = run.hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &start, &bounds::closed);
    app_box(prog, run.role, &run.app, &shared)
}

/// A world box around the footprint of `app` run by `role`, at every time of the motion,
/// from the ranges `shared` the context gives the start state and the values (which must
/// hold of every state the context allows), and the ranges the primitive's guarantee and
/// its kind's invariant give the state while it runs. `None` when some coordinate cannot
/// be bounded (no footprint, or one that reads an unbounded variable).
pub(super) fn app_box(
    prog: &Program,
    role: RoleId,
    app: &PrimApp,
    shared: &HashMap<Var, Interval>,
) -> Option<[Interval; 3]> {
    let prim = prog.prim(app.prim);
    let fp = match &prim.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => fp,
        // No box: all space is unbounded, and a body with a URDF or mesh part has no
        // predicate to bound here. `None` is compared with every other box (conservative:
        // a missing box can only ask more questions).
        Footprint::Everywhere | Footprint::Solid { .. } => return None,
    };
    let inv = prog.kind(prim.kind).invariant.as_ref();
    let shared_lookup = |v: &Var| shared.get(v).copied();
    // In the primitive's frame: old(x) and the start are the participant's `Role` vars.
    let args = &app.args;
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
pub(super) fn to_world(prog: &Program, role: RoleId, b: [Interval; 3]) -> Option<[Interval; 3]> {
    // A mounted participant's frame moves with its carrier: its pose alone places nothing.
    if prog.role(role).mounted_on.is_some() {
        return None;
    }
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

/// Whether two boxes are apart: both bounded and disjoint along some axis. Sound as a
/// proof that two footprints never meet because each box encloses its footprint at every
/// time (outward rounding, [`crate::bounds`]) and closed intervals that are disjoint share
/// no point.
pub(super) fn apart(x: &Option<[Interval; 3]>, y: &Option<[Interval; 3]>) -> bool {
    match (x, y) {
        (Some(x), Some(y)) => (0..3).any(|k| x[k].disjoint(y[k])),
        _ => false,
    }
}

/// The interval index: every pair `(i, j)`, `i < j`, of `boxes` that are not [`apart`], in
/// lexicographic order — exactly the pairs a loop over all pairs would keep, without
/// comparing all pairs. Boxes that are bounded and non-empty on every axis are sorted by
/// their lower end along the axis that spreads them most and swept: a box is compared only
/// with the boxes still open when it starts, then on the other two axes. The others
/// (unbounded: `None`; an empty or NaN interval, which only a contradictory context gives)
/// are compared with every box, by [`apart`] itself.
pub(super) fn meeting_pairs(boxes: &[Option<[Interval; 3]>]) -> Vec<(usize, usize)> {
    let indexed = |b: &Option<[Interval; 3]>| b.is_some_and(|b| b.iter().all(|i| i.is_finite() && i.lo <= i.hi));
    let (mut swept, others): (Vec<usize>, Vec<usize>) = (0..boxes.len()).partition(|&i| indexed(&boxes[i]));
    let at = |i: usize| boxes[i].unwrap_or([Interval::point(0.0); 3]);
    let mut pairs = Vec::new();
    for &u in &others {
        for v in 0..boxes.len() {
            // A pair of two unindexed boxes is found from its first.
            if v != u && (v > u || indexed(&boxes[v])) && !apart(&boxes[u], &boxes[v]) {
                pairs.push((u.min(v), u.max(v)));
            }
        }
    }
    // The axis along which the boxes are most spread out: the largest ratio of the extent
    // of all boxes to the sum of their widths (parallel lanes: across the lanes).
    let spread = |k: usize| {
        let lo = swept.iter().map(|&i| at(i)[k].lo).fold(f64::INFINITY, f64::min);
        let hi = swept.iter().map(|&i| at(i)[k].hi).fold(f64::NEG_INFINITY, f64::max);
        let widths: f64 = swept.iter().map(|&i| at(i)[k].hi - at(i)[k].lo).sum();
        (hi - lo) / (widths + f64::MIN_POSITIVE)
    };
    let axis = (0..3).max_by(|&a, &b| spread(a).total_cmp(&spread(b))).unwrap_or(0);
    swept.sort_by(|&i, &j| at(i)[axis].lo.total_cmp(&at(j)[axis].lo).then(i.cmp(&j)));
    let mut open: Vec<usize> = Vec::new();
    for &i in &swept {
        let b = at(i);
        // Boxes that ended before this one starts end before every later one starts too
        // (indexed ends are numbers, never NaN).
        open.retain(|&j| at(j)[axis].hi >= b[axis].lo);
        for &j in &open {
            // Overlapping along the axis (j started no later and has not ended): the other
            // two axes decide.
            if !apart(&boxes[i], &boxes[j]) {
                pairs.push((i.min(j), i.max(j)));
            }
        }
        open.push(i);
    }
    pairs.sort_unstable();
    pairs
}

#[cfg(test)]
mod tests {
    use super::{apart, meeting_pairs};
    use crate::bounds::Interval;

    /// The pairs a loop over all pairs keeps.
    fn brute(boxes: &[Option<[Interval; 3]>]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if !apart(&boxes[i], &boxes[j]) {
                    out.push((i, j));
                }
            }
        }
        out
    }

    #[test]
    fn the_interval_index_keeps_exactly_the_pairs_of_the_pairwise_loop() {
        // A small deterministic generator: boxes on a coarse grid (so that ends coincide
        // and boxes touch), some unbounded, empty, infinite or NaN.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |m: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % m
        };
        for round in 0..300 {
            let n = next(40) as usize;
            let boxes: Vec<Option<[Interval; 3]>> = (0..n)
                .map(|_| {
                    if next(10) == 0 {
                        return None;
                    }
                    let mut b = [Interval::point(0.0); 3];
                    for c in &mut b {
                        let lo = next(20) as f64 / 2.0;
                        *c = Interval { lo, hi: lo + next(6) as f64 / 2.0 };
                        match next(40) {
                            0 => c.hi = f64::INFINITY,
                            1 => c.lo = f64::NEG_INFINITY,
                            2 => c.hi = c.lo - 1.0, // empty
                            3 => c.lo = f64::NAN,
                            _ => {}
                        }
                    }
                    Some(b)
                })
                .collect();
            assert_eq!(meeting_pairs(&boxes), brute(&boxes), "round {round}: {boxes:?}");
        }
    }

    /// [T-SESS] for `n` bots in a row `gap` apart (cubes of side 0.2): its plan.
    fn initial_plan(n: usize, gap: &str) -> Result<Vec<super::Part>, String> {
        use crate::obligation::{Goal, Obligation, Rule};
        let mut src = String::from(
            "robot Bot { state x: real; }
             motion Bot.hold { interruptible: true; duration: [0, inf]; guarantee: x == old(x);
               footprint(px, py, pz): x - 0.1 <= px <= x + 0.1 && -0.1 <= py <= 0.1 && -0.1 <= pz <= 0.1; }
             system S {",
        );
        for i in 0..n {
            src.push_str(&format!(" participant B{i}: Bot {{ init: x == {gap} * {i}; }}"));
        }
        let sides: Vec<String> = (0..n).map(|i| format!("dt<B{i}: hold>")).collect();
        src.push_str(&format!(" }} choreography G = {};", sides.join(" * ")));
        let (prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let ob = Obligation {
            rule: Rule::TSess,
            span: Default::default(),
            what: "initial states".into(),
            hyps: prog.roles.iter().filter_map(|r| r.init.clone()).collect(),
            goal: Goal::InitiallyDisjoint { firsts: prog.first_motions() },
        };
        super::super::tests::parts(&prog, &ob)
    }

    #[test]
    fn initial_footprints_whose_boxes_are_apart_need_no_query() {
        assert_eq!(initial_plan(30, "1"), Err("holds (None)".into()));
        // 0.15 apart: each bot meets its neighbours only.
        let near = initial_plan(4, "0.15").expect("parts");
        let pairs: Vec<(usize, usize)> = near
            .iter()
            .map(|p| match p {
                super::Part::InitiallyApart { r, s } => (*r, *s),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(pairs, vec![(0, 1), (1, 2), (2, 3)]);
    }

    #[test]
    fn lanes_are_swept_across_and_touching_boxes_meet() {
        let lane =
            |k: f64, len: f64| Some([Interval::new(0.0, len), Interval::new(k, k + 0.5), Interval::new(0.0, 0.1)]);
        // Long lanes half a unit wide, one unit apart: no pair; then lane 3 widened to
        // touch lane 4, and one box with no bound, which meets everything.
        let mut boxes: Vec<_> = (0..50).map(|k| lane(k as f64, 100.0)).collect();
        assert_eq!(meeting_pairs(&boxes), vec![]);
        boxes[3] = Some([Interval::new(0.0, 100.0), Interval::new(3.0, 4.0), Interval::new(0.0, 0.1)]);
        assert_eq!(meeting_pairs(&boxes), vec![(3, 4)]);
        boxes.push(None);
        let mut expected: Vec<(usize, usize)> = (0..50).map(|k| (k, 50)).collect();
        expected.push((3, 4));
        expected.sort_unstable();
        assert_eq!(meeting_pairs(&boxes), expected);
    }
}
