//! The question as a [`Scene`] of the branch and bound: distances at a configuration, the
//! pair-by-pair bound over a box, feasibility and the Z3 witness.

use super::*;

impl Scene for Geo<'_> {
    fn dims(&self) -> usize {
        self.dims.len()
    }

    fn contract(&self, b: &QBox) -> Option<QBox> {
        self.narrow(&b.lo, &b.hi).map(|(lo, hi)| QBox::new(lo, hi))
    }

    fn distance(&self, q: &[f64]) -> Closest {
        let place = |side: usize| -> Vec<Option<Pose3>> {
            self.side_frames(side, q, q, q)
                .into_iter()
                .zip(&self.sides[side])
                .map(|(frames, p)| {
                    let mut pose = geometry::identity();
                    for (f, _) in frames? {
                        pose *= f;
                    }
                    Some(pose * p.piece.solid.pose)
                })
                .collect()
        };
        let (a, b) = (place(0), place(1));
        let mut best = Closest { distance: f64::INFINITY, lower: f64::INFINITY, points: [[0.0; 3]; 2], solids: [0, 0] };
        // Pairs in order of their bounding spheres' gap (a lower bound of the pair's
        // distance): once a gap exceeds the best lower bound found, no later pair can lower
        // the minimum, and parry is not asked about it.
        let origin = |p: &Pose3, s: &geometry::Solid| geometry::apply(&(*p * s.pose.inverse()), [0.0; 3]);
        let mut pairs = Vec::new();
        for (i, pa) in a.iter().enumerate() {
            for (j, pb) in b.iter().enumerate() {
                let (Some(pa), Some(pb)) = (pa, pb) else {
                    // A pose that cannot be evaluated: no bound.
                    best.lower = f64::NEG_INFINITY;
                    best.distance = f64::NAN;
                    return best;
                };
                let (sa, sb) = (&self.sides[0][i].piece.solid, &self.sides[1][j].piece.solid);
                let (ca, cb) = (origin(pa, sa), origin(pb, sb));
                let d2: f64 = ca.iter().zip(cb).map(|(x, y)| (x - y) * (x - y)).sum();
                pairs.push((d2.sqrt() - sa.bounding_radius() - sb.bounding_radius(), i, j));
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (gap, i, j) in pairs {
            if best.lower.is_finite() && gap > best.lower {
                break;
            }
            let (Some(pa), Some(pb)) = (&a[i], &b[j]) else { continue };
            let (sa, sb) = (&self.sides[0][i].piece.solid, &self.sides[1][j].piece.solid);
            let (mut d, lower, mut points) = geometry::solid_closest(sa, pa, sb, pb);
            if sa.is_hull || sb.is_hull {
                // The estimate (a contact when <= 0) is the meshes' own, not their hulls':
                // hulls that touch are not a contact (`bnb::mesh_distance`). The certified
                // lower bound stays the hulls'.
                (d, points) = bnb::mesh_distance(sa, pa, sb, pb).unwrap_or((f64::INFINITY, points));
            }
            let lower = lower - sa.slack - sb.slack - geometry::DISTANCE_MARGIN;
            best.lower = if lower.is_nan() { f64::NEG_INFINITY } else { best.lower.min(lower) };
            if d < best.distance || best.distance.is_infinite() {
                best.distance = d;
                best.points = points;
                best.solids = [i, j];
            }
        }
        best
    }

    /// Pair by pair: the two sides' solids placed at the centre, each with the bound on
    /// how far its points move over the (contracted) box; the box's bound is the least over
    /// pairs `(i, j)` of `lower_ij(c) − m_i − m_j` (each pair's distance at any `q` is at
    /// least that: the module argument, per pair), which is at least the default
    /// `min_ij lower_ij(c) − max_i m_i − max_j m_j`. A pair whose bounding spheres' gap
    /// minus its motion already exceeds the least bound so far asks parry nothing: its
    /// true distance is at least that gap (spheres contain the solids).
    fn bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Bound {
        let none = || Bound {
            lower: f64::NEG_INFINITY,
            at_c: Closest { distance: f64::NAN, lower: f64::NEG_INFINITY, points: [[0.0; 3]; 2], solids: [0, 0] },
            mb: f64::INFINITY,
            focus: None,
        };
        let Some((lo, hi)) = self.narrow(lo, hi) else {
            // No feasible configuration: nothing to bound (the search prunes it first).
            return Bound { lower: f64::INFINITY, mb: 0.0, ..none() };
        };
        let (Some(a), Some(b)) = (self.placed(0, &lo, &hi, centre), self.placed(1, &lo, &hi, centre)) else {
            return none();
        };
        let pad = 1.0 + geometry::placement::PAD;
        let mut pairs = Vec::with_capacity(a.len() * b.len());
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                let (sa, sb) = (&self.sides[0][i].piece.solid, &self.sides[1][j].piece.solid);
                let (ca, cb) = (geometry::apply(&x.owner, [0.0; 3]), geometry::apply(&y.owner, [0.0; 3]));
                let d2: f64 = ca.iter().zip(cb).map(|(x, y)| (x - y) * (x - y)).sum();
                let gap = d2.sqrt() - sa.bounding_radius() - sb.bounding_radius() - geometry::DISTANCE_MARGIN;
                let m = (x.motion + y.motion) * pad;
                pairs.push((gap - m, gap, m, i, j));
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut out = Bound {
            lower: f64::INFINITY,
            at_c: Closest { distance: f64::INFINITY, lower: f64::INFINITY, points: [[0.0; 3]; 2], solids: [0, 0] },
            mb: 0.0,
            focus: None,
        };
        for (key, gap, m, i, j) in pairs {
            // This pair's bound is at least its key: it cannot lower the minimum. (Pairs whose
            // spheres overlap at the centre are still asked, so that a contact at the centre
            // is seen.)
            if key >= out.lower && gap > 0.0 {
                continue;
            }
            let (x, y) = (&a[i], &b[j]);
            let (sa, sb) = (&self.sides[0][i].piece.solid, &self.sides[1][j].piece.solid);
            let (d, lower, points) = geometry::solid_closest(sa, &x.pose, sb, &y.pose);
            let lower = lower - sa.slack - sb.slack - geometry::DISTANCE_MARGIN;
            let lower = if lower.is_nan() { f64::NEG_INFINITY } else { lower };
            let mut best = (lower.max(gap) - m, m, [false, false]);
            if best.0.is_nan() {
                best.0 = f64::NEG_INFINITY;
            }
            if best.0 <= 0.0 || self.tight {
                // Not proved apart directly (or a clearance, which wants the tightest bound):
                // try the stand-ins of solids whose frame turns about z (a mobile base's
                // heading). Each is a sound bound of its own: the
                // stand-in holds the solid at every heading, and moves by at most its motion
                // bound over the box; the pair's bound is the best of them.
                let sides = [(&self.sides[0][i], x), (&self.sides[1][j], y)];
                for proxy in [[false, true], [true, false], [true, true]] {
                    let mut parts = Vec::with_capacity(2);
                    for (s, (placed, at)) in sides.iter().enumerate() {
                        if proxy[s] {
                            let (Some(stand), Some(mv)) = (&placed.turned, at.turned_motion) else { break };
                            parts.push((stand, at.owner * stand.pose, mv));
                        } else {
                            parts.push((&placed.piece.solid, at.pose, at.motion));
                        }
                    }
                    let [(s0, p0, m0), (s1, p1, m1)] = parts[..] else { continue };
                    let (_, low, _) = bnb::parry_closest(&s0.shape, &p0, &s1.shape, &p1);
                    let mv = (m0 + m1) * pad;
                    let bound = low - s0.slack - s1.slack - geometry::DISTANCE_MARGIN - mv;
                    if bound > best.0 {
                        best = (bound, mv, proxy);
                    }
                }
            }
            let (pair, mv, proxy) = best;
            if pair < out.lower || out.focus.is_none() {
                out.lower = out.lower.min(pair);
                out.mb = mv;
                out.focus = Some(Focus { solids: [i, j], proxy });
            }
            out.at_c.lower = out.at_c.lower.min(lower);
            if d < out.at_c.distance || out.at_c.distance.is_infinite() || d.is_nan() {
                out.at_c.distance = d;
                out.at_c.points = points;
                out.at_c.solids = [i, j];
            }
        }
        out
    }

    fn focus_motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64], focus: Option<Focus>) -> f64 {
        let Some(Focus { solids: [i, j], proxy }) = focus else { return self.motion_bound(lo, hi, centre) };
        let Some((lo, hi)) = self.narrow(lo, hi) else { return 0.0 };
        let m = |side: usize, k: usize| {
            let at = self.placed_one(side, k, &lo, &hi, centre);
            at.and_then(|at| if proxy[side] { at.turned_motion } else { Some(at.motion) }).unwrap_or(f64::INFINITY)
        };
        (m(0, i) + m(1, j)) * (1.0 + geometry::placement::PAD)
    }

    fn motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> f64 {
        // Only the feasible configurations of the box move the bodies: bound the motion over
        // the contracted box (its centre stays the box's; the bounds measure from it).
        let Some((lo, hi)) = self.narrow(lo, hi) else { return 0.0 };
        let (lo, hi) = (&lo[..], &hi[..]);
        let side = |k: usize| {
            self.side_frames(k, lo, hi, centre)
                .into_iter()
                .zip(&self.sides[k])
                .map(|(frames, p)| match frames {
                    Some(frames) => {
                        let fb: Vec<FrameBound> = frames.into_iter().map(|(_, b)| b).collect();
                        chain_motion_bound(&fb, p.piece.solid.bounding_radius())
                    }
                    None => f64::INFINITY,
                })
                .fold(0.0, f64::max)
        };
        (side(0) + side(1)) * (1.0 + geometry::placement::PAD)
    }

    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
        let Some((lo, hi)) = self.narrow(lo, hi) else { return Feasible::No };
        let (lo, hi) = (&lo[..], &hi[..]);
        let check = |e: &Expr, run: usize, role: RoleId| {
            truth(self.prog, e, &|v: &Var| self.var_range(run, role, v, Some((lo, hi))))
        };
        for (k, r) in self.runs.iter().enumerate() {
            if self.initial {
                // The start state: the context (over `Role` variables) with the box.
                let ranges = |v: &Var| match v {
                    Var::Role(role, slot) if *role == r.role => self
                        .dims
                        .iter()
                        .position(|d| *d == Dim::Now(*role, *slot))
                        .map(|i| Interval::new(lo[i], hi[i]))
                        .or_else(|| self.shared[k].get(v).copied()),
                    other => self.shared[k].get(other).copied(),
                };
                for h in &r.hyps {
                    if truth(self.prog, h, &ranges) == Some(false) {
                        return Feasible::No;
                    }
                }
                continue;
            }
            let prim = self.prog.prim(r.app.prim);
            if check(&prim.guarantee, k, r.role) == Some(false) {
                return Feasible::No;
            }
            if let Some(inv) = &self.prog.kind(prim.kind).invariant {
                if check(inv, k, r.role) == Some(false) {
                    return Feasible::No;
                }
            }
        }
        for role in self.carrier.keys() {
            if let Some(inv) = &self.prog.kind_of(*role).invariant {
                if check(inv, usize::MAX, *role) == Some(false) {
                    return Feasible::No;
                }
            }
        }
        // "Every point satisfies them" is never claimed (the context's constraints are over
        // ranges, not the exact set): a contact is always confirmed by a witness.
        Feasible::Maybe
    }

    fn witness(&self, lo: &[f64], hi: &[f64], _near: &[f64]) -> Option<Vec<f64>> {
        ask::witness(&self.configs(), lo, hi)
    }

    /// A point on both sides at `q`, by the measure the replay uses ([`Geo::point_distance`]:
    /// each side's distance from the point, 0 inside): parry's two witness points, their
    /// midpoint, or the point of the segment between them where the larger of the two
    /// distances is least (golden-section search; each distance is convex along the segment
    /// for one convex solid). Parry's points alone are not enough: against a mesh's
    /// triangles a penetrating contact's point on the other solid can lie outside the mesh's
    /// hull by the depth, and their midpoint half of it (0.16 mm on the mounted arm). `None`
    /// when no point of the segment lies on both within [`SHARED_POINT`]: the contact is then
    /// not confirmed.
    fn contact_point(&self, q: &[f64], at: &Closest) -> Option<[f64; 3]> {
        point_on_both(at.points, &|p| self.point_distance(0, q, p).max(self.point_distance(1, q, p)))
    }

    fn solid_name(&self, side: usize, solid: usize) -> String {
        let Some(p) = self.sides.get(side).and_then(|s| s.get(solid)) else { return "?".into() };
        let owner = match (p.role, p.obstacle) {
            (Some(r), _) => self.prog.role_name(r).to_string(),
            (None, Some(o)) => format!("obstacle {}", self.prog.obstacles[o].name),
            (None, None) => "obstacle".to_string(),
        };
        let hull = if p.piece.solid.is_hull { " (hull)" } else { "" };
        format!("{}'s {}{hull}", owner, p.piece.solid.name)
    }
}

/// A point within [`SHARED_POINT`] of both sides, by `off` (the larger of its distances from
/// the two sides), on the segment between parry's witness points `[a, b]`: their midpoint
/// when it is one (for two convex solids that overlap, a point inside both); else the middle
/// of the part of the segment where `off` is within the tolerance, found from any point of
/// it (`a`, `b`, or golden-section search for the least `off`: for one convex solid a side,
/// each distance is convex along the segment, and so is their maximum, whose sublevel set
/// is then an interval) by bisection towards each end. The middle rather than an end, so
/// that the point is inside both where they overlap, not on one's surface (an exact replay
/// of a point on a surface may find it an ulp outside). `None` when no point of the segment
/// is within the tolerance of both.
pub(super) fn point_on_both([a, b]: [[f64; 3]; 2], off: &dyn Fn([f64; 3]) -> f64) -> Option<[f64; 3]> {
    let at_t = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
    let ok = |t: f64| off(at_t(t)) <= SHARED_POINT;
    if ok(0.5) {
        return Some(at_t(0.5));
    }
    let t0 = if ok(0.0) {
        0.0
    } else if ok(1.0) {
        1.0
    } else {
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut lo, mut hi) = (0.0, 1.0);
        let mut best = (f64::INFINITY, 0.5);
        for _ in 0..80 {
            let (x, y) = (hi - g * (hi - lo), lo + g * (hi - lo));
            let (fx, fy) = (off(at_t(x)), off(at_t(y)));
            for (f, t) in [(fx, x), (fy, y)] {
                if f < best.0 {
                    best = (f, t);
                }
            }
            if fx <= fy {
                hi = y;
            } else {
                lo = x;
            }
        }
        if best.0.is_nan() || best.0 > SHARED_POINT {
            return None;
        }
        best.1
    };
    // The ends of the interval where `off` is within the tolerance, by bisection from `t0`.
    let end = |towards: f64| {
        let (mut inside, mut outside) = (t0, towards);
        if ok(outside) {
            return outside;
        }
        for _ in 0..60 {
            let m = 0.5 * (inside + outside);
            if ok(m) {
                inside = m;
            } else {
                outside = m;
            }
        }
        inside
    };
    let t = 0.5 * (end(0.0) + end(1.0));
    Some(at_t(if ok(t) { t } else { t0 }))
}
