//! A ready scene: parry solids placed by chains of frames, with the certified distance
//! bound of docs/soundness-geometry.md ("parry's distance is not a certificate").

use super::*;

/// Places a solid: its chain of frames at `q` and their bounds over a box.
pub trait Placer {
    /// The frames at `q`, outermost first.
    fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>>;
    /// The frames' bounds over `[lo, hi]` relative to `centre`, outermost first.
    fn bounds(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Vec<FrameBound>;
}

/// A chain of affine poses.
impl Placer for Vec<AffinePose> {
    fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        self.iter().map(|p| pose_isometry(&p.eval(q))).collect()
    }
    fn bounds(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Vec<FrameBound> {
        self.iter().map(|p| FrameBound::pose(&p.bounds(lo, hi, centre))).collect()
    }
}

/// One solid of the search's own scene ([`ParryScene`]): a parry shape in its innermost
/// frame, placed by a [`Placer`], with a bound on the distance of its points from that
/// frame's origin (the checks' solids, read from URDFs, meshes and shapes, are
/// `geometry::Solid`).
pub struct SearchSolid {
    pub name: String,
    pub shape: SharedShape,
    pub radius: f64,
    pub place: Box<dyn Placer + Send + Sync>,
}

impl SearchSolid {
    /// `radius` is computed from the shape's bounding sphere (padded for f32).
    pub fn new(name: &str, shape: SharedShape, place: Box<dyn Placer + Send + Sync>) -> SearchSolid {
        let s = shape.compute_local_bounding_sphere();
        let radius = s.center().coords.norm() + s.radius();
        SearchSolid { name: name.to_string(), shape, radius: radius * (1.0 + 1e-5) + 1e-9, place }
    }
}

/// Constraints of a [`ParryScene`]: `feasible` and `witness` as in [`Scene`].
pub trait Constraints {
    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible;
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>>;
}

/// No constraints: every `q` of the box.
pub struct Unconstrained;
impl Constraints for Unconstrained {
    fn feasible(&self, _: &[f64], _: &[f64]) -> Feasible {
        Feasible::All
    }
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        Some(near.iter().zip(lo.iter().zip(hi)).map(|(x, (l, h))| x.clamp(*l, *h)).collect())
    }
}

/// Two sides of parry solids, each placed by its own chain. A side with no solid is apart
/// from everything: a caller must reject a body that failed to load rather than pass an
/// empty side.
pub struct ParryScene {
    pub dims: usize,
    pub sides: [Vec<SearchSolid>; 2],
    pub constraints: Box<dyn Constraints + Send + Sync>,
}

/// parry is its f64 build (`parry3d-f64`, Cargo.toml): its isometries are ours. The f32
/// padding below ([`F32_REL`]) is kept although the arithmetic is now f64: it is a
/// conservative margin, far above f64 rounding.
/// The distance of two solids placed at `p1`, `p2` when a side is a convex hull standing
/// for a mesh, measured on the mesh's triangles (not its hull) against the other solid
/// (its triangles too if it is a hull), with the closest points; `None` when parry cannot
/// tell (an unsupported pair).
///
/// What it may be used for: a value `<= 0` is a contact (a mesh's surface that meets the
/// other solid is a point of both solids); a positive value is an upper bound on the
/// solids' distance (the surfaces' closest points are points of the solids; the solids
/// may be closer only if one lies inside a closed mesh, and then their distance is 0).
/// It is never a lower bound: proofs use the hulls.
pub fn mesh_distance(
    s1: &crate::geometry::Solid,
    p1: &Isometry3<f64>,
    s2: &crate::geometry::Solid,
    p2: &Isometry3<f64>,
) -> Option<(f64, [[f64; 3]; 2])> {
    let g1: &dyn parry3d::shape::Shape = if s1.is_hull { s1.mesh()? } else { s1.shape.as_ref() };
    let g2: &dyn parry3d::shape::Shape = if s2.is_hull { s2.mesh()? } else { s2.shape.as_ref() };
    let c = parry3d::query::contact(&to_parry(p1), g1, &to_parry(p2), g2, f64::MAX).ok()??;
    let pt = |p: PPoint<f64>| [p.x, p.y, p.z];
    (!c.dist.is_nan()).then(|| (c.dist, [pt(c.point1), pt(c.point2)]))
}

fn to_parry(iso: &Isometry3<f64>) -> PIso<f64> {
    *iso
}

/// Relative error allowed for f32 geometry (module-level argument in ARCHITECTURE.md):
/// poses rounded to f32 and support points computed in f32 are off by a few units of
/// 2⁻²⁴ of the magnitudes involved (about ten roundings per point); 4e-6 is more than
/// 60 such units of the sum of the magnitudes.
pub const F32_REL: f64 = 4e-6;

/// Relative gap of parry's GJK distance: it stops when `max − min ≤ √(10 ε_f32) · max`
/// (≈ 1.1e-3, parry 0.25 `gjk::closest_points`); used only where no certificate exists.
pub const GJK_REL: f64 = 2.5e-3;

/// The distance of two posed parry shapes with a certified lower bound. For two convex
/// shapes with support maps the lower bound is a separating-plane certificate: along the
/// unit direction `n` between parry's closest points, every point `a` of shape 1 has
/// `n·a ≤ h1(n)` and every `b` of shape 2 has `n·b ≥ −h2(−n)` (support functions), so
/// `|a − b| ≥ −h2(−n) − h1(n)`, computed in f64 from f32 support points and padded for
/// f32 rounding. Otherwise (meshes, compounds) parry's distance shrunk by GJK's relative
/// gap and the same padding. Contacts (distance ≤ 0) get lower = distance − pad.
pub fn parry_closest(
    s1: &SharedShape,
    p1: &Isometry3<f64>,
    s2: &SharedShape,
    p2: &Isometry3<f64>,
) -> (f64, f64, [[f64; 3]; 2]) {
    let (i1, i2) = (to_parry(p1), to_parry(p2));
    let r1 = s1.compute_local_bounding_sphere();
    let r2 = s2.compute_local_bounding_sphere();
    let scale = p1.translation.vector.norm()
        + p2.translation.vector.norm()
        + (r1.center().coords.norm() + r1.radius() + r2.center().coords.norm() + r2.radius());
    let pad = F32_REL * scale + 1e-9;
    let c = parry3d::query::contact(&i1, s1.as_ref(), &i2, s2.as_ref(), f64::MAX);
    let unknown = (f64::NAN, f64::NEG_INFINITY, [[0.0; 3]; 2]);
    let Ok(Some(c)) = c else {
        // Unsupported pair or nothing found: no information (never a pass, never a
        // contact).
        return unknown;
    };
    let pt = |p: PPoint<f64>| [p.x, p.y, p.z];
    let points = [pt(c.point1), pt(c.point2)];
    let dist = c.dist;
    if dist.is_nan() {
        return unknown;
    }
    if dist <= 0.0 {
        return (dist, dist - pad, points);
    }
    let cert = match (s1.as_support_map(), s2.as_support_map()) {
        (Some(m1), Some(m2)) => {
            let n = Vector3::new(points[1][0] - points[0][0], points[1][1] - points[0][1], points[1][2] - points[0][2]);
            let n = if n.norm() > 0.0 { n / n.norm() } else { c.normal1.into_inner() };
            let nf = PVec::new(n.x, n.y, n.z);
            let a = m1.support_point(&i1, &nf);
            let b = m2.support_point(&i2, &-nf);
            let a = Point3::new(a.x, a.y, a.z);
            let b = Point3::new(b.x, b.y, b.z);
            // The certificate uses the f64 direction `n`; the f32 direction `nf` only picks
            // the support points, whose rounding is within the pad (ARCHITECTURE.md).
            n.dot(&b.coords) - n.dot(&a.coords)
        }
        _ => dist * (1.0 - GJK_REL),
    };
    (dist, cert.min(dist) - pad, points)
}

impl ParryScene {
    pub fn new(dims: usize, sides: [Vec<SearchSolid>; 2]) -> ParryScene {
        ParryScene { dims, sides, constraints: Box::new(Unconstrained) }
    }
}

impl Scene for ParryScene {
    fn dims(&self) -> usize {
        self.dims
    }

    fn distance(&self, q: &[f64]) -> Closest {
        let place = |s: &SearchSolid| crate::geometry::placement::compose(&s.place.frames(q));
        let a: Vec<Isometry3<f64>> = self.sides[0].iter().map(place).collect();
        let b: Vec<Isometry3<f64>> = self.sides[1].iter().map(place).collect();
        let mut best = Closest { distance: f64::INFINITY, lower: f64::INFINITY, points: [[0.0; 3]; 2], solids: [0, 0] };
        for (i, (s1, p1)) in self.sides[0].iter().zip(&a).enumerate() {
            for (j, (s2, p2)) in self.sides[1].iter().zip(&b).enumerate() {
                let (d, lower, points) = parry_closest(&s1.shape, p1, &s2.shape, p2);
                // A NaN lower bound is no bound (f64::min would drop it).
                best.lower = if lower.is_nan() { f64::NEG_INFINITY } else { best.lower.min(lower) };
                if d < best.distance || (best.distance.is_nan() && !d.is_nan()) || (i, j) == (0, 0) {
                    best.distance = d;
                    best.points = points;
                    best.solids = [i, j];
                }
            }
        }
        best
    }

    fn motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> f64 {
        let side = |s: &Vec<SearchSolid>| {
            s.iter().map(|x| chain_motion_bound(&x.place.bounds(lo, hi, centre), x.radius)).fold(0.0, f64::max)
        };
        // Each side's points move by at most the largest of its solids' bounds.
        (side(&self.sides[0]) + side(&self.sides[1])) * (1.0 + crate::geometry::placement::PAD)
    }

    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
        self.constraints.feasible(lo, hi)
    }

    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        self.constraints.witness(lo, hi, near)
    }

    fn solid_name(&self, side: usize, solid: usize) -> String {
        self.sides
            .get(side)
            .and_then(|s| s.get(solid))
            .map_or_else(|| format!("side {side} solid {solid}"), |s| s.name.clone())
    }
}
