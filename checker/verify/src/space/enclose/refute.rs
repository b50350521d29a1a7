//! The other direction of the containment search: that the body is **not** within the
//! footprint (E0512 fails), for the same footprints that turn with the state.
//!
//! **Claim.** At every state within the ranges the contract's facts give (the invariant,
//! the precondition and the guarantee, [`Facts`]) where those facts are not false, some
//! point of the body lies outside the footprint. Every state the contract allows is such a
//! state, so at every allowed state the body sticks out: containment fails as soon as the
//! contract allows one (whether it does is asked separately, as for the mesh vertices of
//! [`super::solid`]: E0408 and the vacuity guard).
//!
//! **Search.** The box of the state variables the rewritten predicate reads (the heading)
//! is split; a piece is settled when the contract's facts are false on all of it, or when
//! one *candidate point* `q` of the shape makes the predicate false at every state of the
//! piece (three-valued interval truth, outward rounded, with `q` an exact floating-point
//! point: [`crate::bounds`]). The candidates are points of the shape in its own frame:
//! its box's corners, and points on the ellipsoid inscribed in its box (scaled by
//! `1 - 1e-6`) at 32 azimuths and 7 elevations; each is kept only if it lies in the shape's
//! box exactly (rationals) and the shape's own predicate is true at it (the same interval
//! truth at a point: a definite answer about that point). A piece the coarse candidates do
//! not settle also tries the *fine ring* (the ellipsoid's equator at 1,024 azimuths, kept by
//! the same tests): the ring's points outside the footprint at the piece's middle state are
//! tried over the whole piece. When no candidate is outside at a middle state the facts do
//! not rule out, no candidate can settle the piece holding that state (the truth is
//! inclusion monotone), and the search stops at once. A piece that is neither settled nor
//! given up is halved along its widest variable (relative to its whole range); a search that
//! runs out of pieces or of resolution settles nothing, and the question goes on to Z3.
//!
//! Sound by the three-valued truth alone: a piece is settled only by a definite `false`
//! over the whole piece (of a fact, or of the footprint at a point of the body), and the
//! variables the predicate does not read stay at their whole ranges.

use super::*;

/// Pieces examined per body part before the refutation gives up.
const REFUTE_BUDGET: usize = 8_192;
/// Pieces examined per body part looking for states at which it sticks out (a reason only).
const SOMEWHERE_BUDGET: usize = 512;

/// A point of the body outside the footprint at every state the contract's facts allow,
/// described for the diagnostic: `Some(why)` when some part of the body of `prim`'s kind
/// sticks out of its footprint at every such state.
pub fn body_outside(prog: &Program, prim: PrimId) -> Option<String> {
    outside(prog, prim, true)
}

/// Where [`body_outside`] does not hold, a piece of states on which a point of the body is
/// outside the footprint (the same interval truth), described for an unknown's reason: the
/// body sticks out at those states if the contract allows one, which this search does not
/// decide (it is no rejection: the states of the piece may all be excluded by the contract).
pub fn body_outside_somewhere(prog: &Program, prim: PrimId) -> Option<String> {
    outside(prog, prim, false)
}

fn outside(prog: &Program, prim: PrimId, everywhere: bool) -> Option<String> {
    let p = prog.prim(prim);
    let fp = match &p.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => &fp.pred,
        Footprint::Everywhere | Footprint::Solid { .. } => return None,
    };
    let body = prog.kind(p.kind).body.as_ref()?;
    let facts = Facts::of(prog, prim);
    let kind = prog.kind(p.kind);
    let name = |v: &Var| match v {
        Var::Own(Slot::State(i)) if *i < kind.state.len() => format!("`{}`", kind.state[*i].0),
        Var::Old(i) if *i < kind.state.len() => format!("`old({})`", kind.state[*i].0),
        v => describe(v),
    };
    for (k, part) in body.parts.iter().enumerate() {
        if !everywhere {
            if let Some(found) = part_outside(prog, part, fp, &facts, &name, false) {
                return Some(format!(
                    "part {} of `geometry:` (its {}) sticks out of the footprint at some states within the contract's ranges: at {}, its point ({:.4}, {:.4}, {:.4}) m (in the part's own frame) is outside it; whether the contract allows such a state was not decided",
                    k + 1,
                    shape_name(&part.shape),
                    found.example,
                    found.point[0],
                    found.point[1],
                    found.point[2],
                ));
            }
            continue;
        }
        if let Some(found) = part_outside(prog, part, fp, &facts, &name, true) {
            return Some(format!(
                "the footprint contains the robot's body, but part {} of `geometry:` (its {}) sticks out of it at every state the contract allows (interval subdivision over {}, {} pieces): e.g. at {}, its point ({:.4}, {:.4}, {:.4}) m (in the part's own frame) is outside the footprint",
                k + 1,
                shape_name(&part.shape),
                found.vars.join(", "),
                found.pieces,
                found.example,
                found.point[0],
                found.point[1],
                found.point[2],
            ));
        }
    }
    None
}

fn shape_name(s: &Shape) -> &'static str {
    match s {
        Shape::Box(_) => "box",
        Shape::Sphere(_) => "sphere",
        Shape::Cylinder(..) => "cylinder",
        Shape::Capsule(..) => "capsule",
        Shape::Urdf { .. } => "URDF",
        Shape::Mesh { .. } => "mesh",
    }
}

/// A refutation for one part.
struct Outside {
    /// The variables split, by name.
    vars: Vec<String>,
    pieces: usize,
    /// One settled piece, in words, and its candidate point.
    example: String,
    point: [f64; 3],
}

/// Candidate points of the shape whose exact box is `exact` (see the module doc).
fn candidates(exact: &[(BigRational, BigRational); 3]) -> Vec<[f64; 3]> {
    ellipsoid_points(exact, 32, 3)
}

/// The fine ring: the inscribed ellipsoid's equator at [`FINE_AZIMUTHS`] azimuths (a point
/// of a round body within 0.2 mrad of any direction about its axis), tried on a piece the
/// coarse candidates do not settle, first at the piece's middle state (see [`part_outside`]).
fn fine_ring(exact: &[(BigRational, BigRational); 3]) -> Vec<[f64; 3]> {
    ellipsoid_points(exact, FINE_AZIMUTHS, 0)
}

/// Azimuths of the fine ring.
const FINE_AZIMUTHS: usize = 1024;

/// The box's corners (when `rings > 0`) and points of the ellipsoid inscribed in the box,
/// scaled by `1 - 1e-6`, at `azimuths` azimuths on each of `2 rings + 1` elevations (the
/// poles once); each kept only within the box, exactly.
fn ellipsoid_points(exact: &[(BigRational, BigRational); 3], azimuths: usize, rings: i32) -> Vec<[f64; 3]> {
    let lo = [0, 1, 2].map(|i| Interval::of_rational(&exact[i].0).hi);
    let hi = [0, 1, 2].map(|i| Interval::of_rational(&exact[i].1).lo);
    let mut out = Vec::new();
    if (0..3).any(|i| !(lo[i].is_finite() && hi[i].is_finite()) || lo[i] > hi[i]) {
        return out;
    }
    let c = [0, 1, 2].map(|i| lo[i] / 2.0 + hi[i] / 2.0);
    let h = [0, 1, 2].map(|i| (hi[i] / 2.0 - lo[i] / 2.0) * (1.0 - 1e-6));
    if rings > 0 {
        for x in [lo[0], hi[0]] {
            for y in [lo[1], hi[1]] {
                for z in [lo[2], hi[2]] {
                    out.push([x, y, z]);
                }
            }
        }
    }
    for e in -rings..=rings {
        let psi = if rings == 0 { 0.0 } else { f64::from(e) * std::f64::consts::FRAC_PI_2 / f64::from(rings) };
        for a in 0..azimuths {
            let phi = a as f64 * std::f64::consts::TAU / azimuths as f64;
            out.push([
                c[0] + h[0] * phi.cos() * psi.cos(),
                c[1] + h[1] * phi.sin() * psi.cos(),
                c[2] + h[2] * psi.sin(),
            ]);
            if rings > 0 && e.abs() == rings {
                break;
            }
        }
    }
    // Kept only within the box, exactly.
    out.retain(|q| (0..3).all(|i| BigRational::from_float(q[i]).is_some_and(|v| v >= exact[i].0 && v <= exact[i].1)));
    out
}

fn part_outside(
    prog: &Program,
    part: &BodyPart,
    fp: &Expr,
    facts: &Facts,
    name: &dyn Fn(&Var) -> String,
    everywhere: bool,
) -> Option<Outside> {
    let super::PartGoal { shape, exact, goal } = super::part_goal(prog, part, fp).ok()?;
    let mut table = VarTable::new();
    let goal = Tree::new(prog, &goal, &mut table);
    // The goal's variables are numbered first.
    let goal_vars = table.len();
    let shape = Tree::new(prog, &strip(&shape), &mut table);
    let now: Vec<Tree> = facts.now.iter().map(|f| Tree::new(prog, &strip(f), &mut table)).collect();
    let vars = table.vars().to_vec();
    let point_dim = |i: usize| vars.iter().position(|v| *v == Var::Point(i));
    // The points of the shape among the candidates: the shape's predicate true at them.
    let mut env: Vec<Option<Interval>> = vec![None; table.len()];
    let mut work = Vec::new();
    let mut in_shape = |pts: Vec<[f64; 3]>| -> Vec<[f64; 3]> {
        pts.into_iter()
            .filter(|c| {
                for (i, x) in c.iter().enumerate() {
                    if let Some(d) = point_dim(i) {
                        env[d] = Some(Interval::point(*x));
                    }
                }
                shape.truth(&env, &mut work) == Some(true)
            })
            .collect()
    };
    let mut points: Vec<[f64; 3]> = in_shape(candidates(&exact));
    if points.is_empty() {
        return None;
    }
    let fine: Vec<[f64; 3]> = in_shape(fine_ring(&exact));
    // The state variables the goal reads are split; every other variable at its range.
    let reads: Vec<usize> = (0..goal_vars).filter(|&k| !matches!(vars[k], Var::Point(_))).collect();
    let read_vars: Vec<Var> = reads.iter().map(|&k| vars[k].clone()).collect();
    let mut lo = Vec::with_capacity(reads.len());
    let mut hi = Vec::with_capacity(reads.len());
    for &k in &reads {
        let iv = facts.ranges.get(&vars[k]).copied()?;
        if !(iv.lo.is_finite() && iv.hi.is_finite()) || iv.lo > iv.hi {
            return None;
        }
        lo.push(iv.lo);
        hi.push(iv.hi);
    }
    for (k, v) in vars.iter().enumerate() {
        if !matches!(v, Var::Point(_)) && !reads.contains(&k) {
            env[k] = facts.ranges.get(v).copied().filter(|r| r.lo <= r.hi);
        }
    }
    let names: Vec<String> = reads.iter().map(|&k| name(&vars[k])).collect();
    let widths: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| (h - l).max(f64::MIN_POSITIVE)).collect();
    let n = reads.len();
    let mut stack = vec![(lo, hi)];
    let mut pieces = 0usize;
    let mut last = 0usize;
    let mut example: Option<(String, [f64; 3])> = None;
    while let Some((lo, hi)) = stack.pop() {
        pieces += 1;
        if pieces > if everywhere { REFUTE_BUDGET } else { SOMEWHERE_BUDGET } {
            return None;
        }
        for (j, &k) in reads.iter().enumerate() {
            env[k] = Some(Interval::new(lo[j], hi[j]));
        }
        if now.iter().any(|f| f.truth(&env, &mut work) == Some(false)) {
            continue;
        }
        let order = std::iter::once(last).chain((0..points.len()).filter(|i| *i != last));
        let mut settled = false;
        for i in order {
            for (a, x) in points[i].iter().enumerate() {
                if let Some(d) = point_dim(a) {
                    env[d] = Some(Interval::point(*x));
                }
            }
            if goal.truth(&env, &mut work) == Some(false) {
                last = i;
                settled = true;
                if example.is_none() || !everywhere {
                    let at: Vec<String> =
                        (0..n).map(|j| format!("{} in [{:.4}, {:.4}]", names[j], lo[j], hi[j])).collect();
                    let at = if at.is_empty() { "every state".to_string() } else { at.join(", ") };
                    example = Some((at, points[i]));
                }
                break;
            }
        }
        if settled && !everywhere {
            break;
        }
        if settled {
            continue;
        }
        // The fine ring, through the piece's middle state: the points outside the footprint
        // there are tried on the whole piece (and kept as candidates once one settles a
        // piece). None outside at a middle state the facts do not rule out: the body may lie
        // within the footprint there, and the refutation gives up (the question goes on).
        let mid: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| l + 0.5 * (h - l)).collect();
        let set = |env: &mut Vec<Option<Interval>>, at: &dyn Fn(usize) -> Interval| {
            for (j, &k) in reads.iter().enumerate() {
                env[k] = Some(at(j));
            }
        };
        set(&mut env, &|j| Interval::point(mid[j]));
        let mid_ruled_out = now.iter().any(|f| f.truth(&env, &mut work) == Some(false));
        let mut outside_mid = Vec::new();
        for (i, p) in points.iter().chain(&fine).enumerate() {
            for (a, x) in p.iter().enumerate() {
                if let Some(d) = point_dim(a) {
                    env[d] = Some(Interval::point(*x));
                }
            }
            if goal.truth(&env, &mut work) == Some(false) {
                outside_mid.push(i);
            }
        }
        if outside_mid.is_empty() && !mid_ruled_out {
            if everywhere {
                return None;
            }
            // Looking for some piece: one narrow enough whose middle has the body inside is
            // left (only a reason is sought, and its neighbours are tried).
            if (0..n).all(|d| (hi[d] - lo[d]) * 16.0 <= widths[d]) {
                continue;
            }
        }
        set(&mut env, &|j| Interval::new(lo[j], hi[j]));
        let found = outside_mid.into_iter().find(|&i| {
            let p = if i < points.len() { points[i] } else { fine[i - points.len()] };
            for (a, x) in p.iter().enumerate() {
                if let Some(d) = point_dim(a) {
                    env[d] = Some(Interval::point(*x));
                }
            }
            goal.truth(&env, &mut work) == Some(false)
        });
        if let Some(i) = found {
            last = i.min(points.len());
            if i >= points.len() {
                points.push(fine[i - points.len()]);
            }
            if example.is_none() || !everywhere {
                let at: Vec<String> = (0..n).map(|j| format!("{} in [{:.4}, {:.4}]", names[j], lo[j], hi[j])).collect();
                let at = if at.is_empty() { "every state".to_string() } else { at.join(", ") };
                example = Some((at, points[last]));
            }
            if !everywhere {
                break;
            }
            continue;
        }
        let d = (0..n)
            .filter(|d| hi[*d] > lo[*d])
            .max_by(|a, b| ((hi[*a] - lo[*a]) / widths[*a]).total_cmp(&((hi[*b] - lo[*b]) / widths[*b])))?;
        bisect(&mut stack, lo, hi, d, &read_vars).ok()?;
    }
    let (example, point) = example?;
    Some(Outside { vars: names, pieces, example, point })
}
