//! The geometry engine: real shapes, meshes, URDF robots and their kinematics, and exact
//! distances between placed solids. The only module that names parry3d,
//! nalgebra, urdf-rs, stl_io, tobj and roxmltree (`tests/tidy.rs` checks it), as `smt/`
//! is for z3. It reads files only through the byte loader it is given
//! ([`crate::syntax::ByteLoader`]; the file system's is [`crate::fsload::read_bytes`]).
//!
//! - [`shape`]: a [`Solid`] is one convex parry shape placed in its owner's frame;
//! - [`mesh`]: STL and OBJ meshes, as the convex hulls of their vertices;
//! - [`urdf`]: URDF files to kinematic trees, with diagnostics pointing into the URDF;
//! - [`kinematics`]: forward kinematics and sound displacement bounds;
//! - [`within`]: whether a placed solid lies within others, a mesh read as its triangles;
//! - [`placement`]: bounds on how far a point placed by a chain of poses moves over a box;
//! - [`search`]: the geometric search: the branch and bound over boxes of configurations
//!   (clearance, first contact, [`search::bnb`]); the checks' collision questions posed to
//!   it are `crate::collision`, a layer above (it reads the HIR's bodies through `space`).
//!
//! Everything is f64: parry is its f64 build (`parry3d-f64`, imported under the name
//! `parry3d`), so no f32 rounding enters a clearance proof.

pub mod kinematics;
pub mod mesh;
pub mod placement;
pub mod search;
pub mod shape;
pub mod urdf;
pub mod within;

pub use kinematics::Robot;
pub use shape::Solid;
pub use urdf::load_robot;

use nalgebra::{Isometry3, Point3};

/// A rigid pose (rotation, then translation), for code outside the engine, which may not
/// name nalgebra (`tests/tidy.rs`).
pub type Pose3 = Isometry3<f64>;

/// A point in a frame, in the engine's own type (the checks outside this module name no
/// geometry crate: tests/tidy.rs).
pub type FramePoint = Point3<f64>;

/// The identity pose.
pub fn identity() -> Pose3 {
    Isometry3::identity()
}

/// `pose(x, y, z, roll, pitch, yaw)`: `Rz(yaw) Ry(pitch) Rx(roll)`, then the translation.
pub fn pose6(a: [f64; 6]) -> Pose3 {
    placement::pose_isometry(&a)
}

/// The length of a pose's translation.
pub fn reach(p: &Pose3) -> f64 {
    p.translation.vector.norm()
}

/// A pose applied to a point.
pub fn apply(p: &Pose3, x: [f64; 3]) -> [f64; 3] {
    let v = p * Point3::new(x[0], x[1], x[2]);
    [v.x, v.y, v.z]
}

/// What a caller subtracts from a distance [`distance`] reports before it counts as a
/// proved clearance, beyond the solids' slacks (metres): 1 µm. parry's f64 GJK stops when
/// its distance estimate is within a relative ~1e-10 of the true distance (its tolerance
/// is a few hundred f64 epsilons), and the poses carry rounding of a few ulps of the scene's
/// size; for scenes within a kilometre of the origin both are far below 1 µm.
pub const DISTANCE_MARGIN: f64 = 1e-6;

/// How two sets of solids relate at their closest pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Relation {
    /// Apart: [`Closest::distance`] > 0.
    Apart,
    /// Touching or penetrating, between exact shapes (primitives): a real contact.
    Contact,
    /// Touching or penetrating, with a convex hull of a mesh on one side: the hulls touch,
    /// the meshes may not ([`Solid::trimesh`] can confirm).
    HullsTouch,
}

/// The closest pair between two sets of placed solids.
#[derive(Clone, Debug)]
pub struct Closest {
    /// parry's distance between the closest pair; when they overlap, minus the
    /// penetration depth (≤ 0).
    pub distance: f64,
    /// The closest point of the first set's solid, and of the second's (world frame);
    /// when they overlap, the deepest points of the contact.
    pub point_a: Point3<f64>,
    pub point_b: Point3<f64>,
    pub name_a: String,
    pub name_b: String,
    pub relation: Relation,
    /// The two solids' slacks, summed (see [`Solid::slack`]).
    pub slack: f64,
}

impl Closest {
    /// A clearance that is proved: `distance − slack − DISTANCE_MARGIN`. Positive means the
    /// two sets are certainly disjoint.
    pub fn certified_clearance(&self) -> f64 {
        self.distance - self.slack - DISTANCE_MARGIN
    }
}

/// The closest pair between the solids `a` and the solids `b`, each given with the world
/// pose of its owner frame (the solid's [`Solid::pose`] places it in that frame). `None`
/// if either side is empty. Pairs whose bounding spheres are farther apart than the best
/// distance found so far are skipped (the sphere distance is a lower bound).
///
/// Every solid mochi builds is convex with a support map, a pair parry always supports;
/// a pair it does not support (impossible by construction) is reported as a contact, the
/// conservative answer for a clearance proof.
pub fn distance(a: &[(Isometry3<f64>, &Solid)], b: &[(Isometry3<f64>, &Solid)]) -> Option<Closest> {
    let mut best: Option<Closest> = None;
    // Bounding spheres: world centre of each owner frame and each solid's radius about it.
    for (pa, sa) in a {
        let ca = pa.translation.vector;
        for (pb, sb) in b {
            let cb = pb.translation.vector;
            let lower = (ca - cb).norm() - sa.bounding_radius() - sb.bounding_radius();
            if let Some(c) = &best {
                if lower > c.distance {
                    continue;
                }
            }
            let c = pair(pa, sa, pb, sb);
            if best.as_ref().is_none_or(|x| c.distance < x.distance) {
                best = Some(c);
            }
        }
    }
    best
}

/// Points on the boundary of `s` placed by its owner frame `owner` (world frame): its
/// support points in the 26 directions of a cube's faces, edges and corners, each moved
/// `inset` metres towards their mean (a point of the convex solid), so a body that fills
/// its footprint exactly is not read as leaving it by a rounding. Empty for a shape
/// without a support map.
pub fn boundary_points(owner: &Pose3, s: &Solid, inset: f64) -> Vec<[f64; 3]> {
    let pose = owner * s.pose;
    let Some(map) = s.shape.as_support_map() else { return Vec::new() };
    let mut pts = Vec::new();
    for dx in [-1.0f64, 0.0, 1.0] {
        for dy in [-1.0f64, 0.0, 1.0] {
            for dz in [-1.0f64, 0.0, 1.0] {
                if dx == 0.0 && dy == 0.0 && dz == 0.0 {
                    continue;
                }
                let d = nalgebra::Vector3::new(dx, dy, dz).normalize();
                pts.push(map.support_point(&pose, &d).coords);
            }
        }
    }
    let centre = pts.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + p) / pts.len() as f64;
    pts.iter()
        .map(|p| {
            let to_centre = centre - p;
            let n = to_centre.norm();
            let q = if n > inset { p + to_centre * (inset / n) } else { centre };
            [q.x, q.y, q.z]
        })
        .collect()
}

/// parry's distance from the world point `p` to solid `s` whose owner frame is at world pose
/// `owner` (0 inside; the solid's slack is not subtracted).
pub fn distance_to_point(owner: &Pose3, s: &Solid, p: [f64; 3]) -> f64 {
    s.shape.distance_to_point(&(owner * s.pose), &Point3::new(p[0], p[1], p[2]), true)
}

/// Whether the world point `p` lies in one of the solids `a` (each with its owner frame's
/// world pose), or within `tol` metres of one.
pub fn contains(a: &[(Pose3, &Solid)], p: [f64; 3], tol: f64) -> bool {
    let pt = Point3::new(p[0], p[1], p[2]);
    a.iter().any(|(owner, s)| s.shape.distance_to_point(&(owner * s.pose), &pt, true) <= tol)
}

/// [`search::bnb::parry_closest`] of two solids placed at `pa` and `pb` (the world poses of their
/// shapes: owner pose times [`Solid::pose`]): parry's distance, a certified lower bound and
/// the closest points. When a side is a decomposed concave mesh ([`Solid::pieces`]) and the
/// shapes' lower bound is not positive (the hulls touch), the lower bound is raised to the least over pairs of pieces (a side without pieces counts
/// as one piece, its shape): the pieces' union holds each solid, so two solids' distance is
/// at least the least distance of their pieces. The estimate is raised likewise (it is then
/// the pieces', not the hulls'). The caller subtracts the solids' slacks, as before; the
/// pieces' slack beyond those is subtracted here.
pub fn solid_closest(sa: &Solid, pa: &Isometry3<f64>, sb: &Solid, pb: &Isometry3<f64>) -> (f64, f64, [[f64; 3]; 2]) {
    let (d, lower, points) = search::bnb::parry_closest(&sa.shape, pa, &sb.shape, pb);
    // Only where the hulls touch: a box whose hulls are apart at its centre needs no more,
    // and a proof that never met touching hulls costs what it did before.
    // (`lower <= 0` fails for NaN too: then the hulls' answer stands.)
    let hulls_touch = matches!(lower.partial_cmp(&0.0), Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal));
    if !hulls_touch || !(sa.is_hull || sb.is_hull) {
        return (d, lower, points);
    }
    let (pa_, pb_) = (sa.pieces(), sb.pieces());
    if pa_.is_none() && pb_.is_none() {
        return (d, lower, points);
    }
    let whole = |s: &Solid| {
        let b = s.shape.compute_local_bounding_sphere();
        vec![shape::Piece { shape: s.shape.clone(), centre: *b.center(), radius: b.radius() * (1.0 + 1e-9) + 1e-12 }]
    };
    let (wa, wb) = (whole(sa), whole(sb));
    let (ka, ea): (&[shape::Piece], f64) = pa_.unwrap_or((&wa, 0.0));
    let (kb, eb): (&[shape::Piece], f64) = pb_.unwrap_or((&wb, 0.0));
    let extra = ea + eb;
    let mut best = (f64::INFINITY, f64::INFINITY, points);
    let mut pairs = Vec::with_capacity(ka.len() * kb.len());
    for (i, x) in ka.iter().enumerate() {
        let cx = pa * x.centre;
        for (j, y) in kb.iter().enumerate() {
            let gap = (cx - pb * y.centre).norm() - x.radius - y.radius;
            pairs.push((gap, i, j));
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    for (gap, i, j) in pairs {
        // Spheres hold the pieces: a pair whose spheres are farther apart than the least
        // bound so far cannot lower it. (Shrunk by a relative 1e-9 against rounding.)
        if gap - 1e-9 * gap.abs() > best.1 {
            break;
        }
        let (dd, low, pts) = search::bnb::parry_closest(&ka[i].shape, pa, &kb[j].shape, pb);
        if low.is_nan() || dd.is_nan() {
            return (d, lower, points);
        }
        if low < best.1 {
            best.1 = low;
        }
        if dd < best.0 {
            best.0 = dd;
            best.2 = pts;
        }
    }
    let low = best.1 - extra;
    if low > lower {
        (d.max(best.0), low, best.2)
    } else {
        (d, lower, points)
    }
}

fn pair(pa: &Isometry3<f64>, sa: &Solid, pb: &Isometry3<f64>, sb: &Solid) -> Closest {
    use parry3d::query::{self, ClosestPoints};
    let (wa, wb) = (pa * sa.pose, pb * sb.pose);
    let touching = if sa.is_hull || sb.is_hull { Relation::HullsTouch } else { Relation::Contact };
    let mk = |distance: f64, point_a, point_b, relation| Closest {
        distance,
        point_a,
        point_b,
        name_a: sa.name.clone(),
        name_b: sb.name.clone(),
        relation,
        slack: sa.slack + sb.slack,
    };
    if sa.is_hull || sb.is_hull {
        // The pieces of a concave mesh may part what the hulls do not: apart when their
        // certified lower bound (less the slacks and the margin) is positive.
        let (d, lower, p) = solid_closest(sa, &wa, sb, &wb);
        if lower - sa.slack - sb.slack - DISTANCE_MARGIN > 0.0 {
            let pt = |x: [f64; 3]| Point3::new(x[0], x[1], x[2]);
            return mk(d, pt(p[0]), pt(p[1]), Relation::Apart);
        }
    }
    match query::closest_points(&wa, sa.shape.as_ref(), &wb, sb.shape.as_ref(), f64::MAX) {
        Ok(ClosestPoints::WithinMargin(p1, p2)) => {
            let d = (p2 - p1).norm();
            mk(d, p1, p2, if d > 0.0 { Relation::Apart } else { touching })
        }
        Ok(ClosestPoints::Intersecting) | Ok(ClosestPoints::Disjoint) | Err(_) => {
            match query::contact(&wa, sa.shape.as_ref(), &wb, sb.shape.as_ref(), 0.0) {
                Ok(Some(c)) => mk(c.dist.min(0.0), c.point1, c.point2, touching),
                // Intersecting by one query, no contact by the other (a tangency at the
                // tolerance): a contact at the first solid's origin, conservatively.
                _ => {
                    let p = Point3::from(wa.translation.vector);
                    mk(0.0, p, p, touching)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn distance_between_primitives_and_contact() {
        let id = Isometry3::identity();
        let a = Solid::mochi_box(1.0, 1.0, 1.0, id, "box").unwrap();
        let b = Solid::sphere(0.5, id, "ball").unwrap();
        // The ball's centre at x = 2, z = 0.5: 1.5 from the box's face, 1.0 from its surface.
        let far = Isometry3::translation(2.0, 0.0, 0.5);
        let c = distance(&[(id, &a)], &[(far, &b)]).unwrap();
        assert!((c.distance - 1.0).abs() < 1e-9, "{c:?}");
        assert_eq!(c.relation, Relation::Apart);
        assert!((c.point_a - Point3::new(0.5, 0.0, 0.5)).norm() < 1e-9, "{c:?}");
        assert!((c.point_b - Point3::new(1.5, 0.0, 0.5)).norm() < 1e-9, "{c:?}");
        assert_eq!((c.name_a.as_str(), c.name_b.as_str()), ("box", "ball"));
        assert!(c.certified_clearance() < c.distance && c.certified_clearance() > 0.99);
        // Overlapping by 0.25.
        let near = Isometry3::translation(0.75, 0.0, 0.5);
        let c = distance(&[(id, &a)], &[(near, &b)]).unwrap();
        assert!((c.distance + 0.25).abs() < 1e-9, "{c:?}");
        assert_eq!(c.relation, Relation::Contact);
        assert!(distance(&[], &[(near, &b)]).is_none());
    }

    #[test]
    fn boundary_points_lie_in_the_solid_and_containment_sees_them() {
        let id = Isometry3::identity();
        let a = Solid::mochi_box(1.0, 2.0, 1.0, id, "box").unwrap();
        let pts = boundary_points(&id, &a, 1e-6);
        assert_eq!(pts.len(), 26);
        assert!(pts.iter().all(|p| contains(&[(id, &a)], *p, 0.0)), "{pts:?}");
        // A corner of the box: (0.5, 1, 1) less the inset (mochi boxes stand on z = 0).
        assert!(pts
            .iter()
            .any(|p| (p[0] - 0.5).abs() < 1e-5 && (p[1] - 1.0).abs() < 1e-5 && (p[2] - 1.0).abs() < 1e-5));
        // A smaller box does not contain the corners of this one.
        let small = Solid::mochi_box(1.0, 1.0, 1.0, id, "small").unwrap();
        assert!(pts.iter().any(|p| !contains(&[(id, &small)], *p, 1e-9)));
    }

    /// The minimum over pairs, with the sphere pruning: the second solid of `b` is closest.
    #[test]
    fn minimum_over_pairs() {
        let id = Isometry3::identity();
        let s = Solid::sphere(0.1, id, "s").unwrap();
        let c1 = Solid::mochi_cylinder(0.1, 1.0, Isometry3::translation(3.0, 0.0, 0.0), "far").unwrap();
        let c2 = Solid::mochi_cylinder(0.1, 1.0, Isometry3::translation(1.0, 0.0, 0.0), "near").unwrap();
        let rot = Isometry3::rotation(Vector3::new(0.0, 0.0, 0.3));
        let c = distance(&[(id, &s)], &[(rot, &c1), (rot, &c2)]).unwrap();
        assert_eq!(c.name_b, "near");
        assert!((c.distance - 0.8).abs() < 1e-9, "{c:?}");
    }

    /// The cradle's pieces part a pin a few millimetres clear of the slot's walls (it lies
    /// inside the cradle's hull). With cells halved 6 times the piece at each wall's foot
    /// filled the corner with a slope reaching past the pin, and these were unknown; a
    /// pin 1 mm into a wall is never proved apart.
    #[test]
    fn the_cradles_pieces_part_a_pin_2_mm_from_the_slots_walls() {
        let text = std::fs::read_to_string(crate::testing::repo("robots/meshes/cradle.obj")).unwrap();
        let d = mesh::parse(text.as_bytes(), mesh::Format::Obj).unwrap();
        let cradle = mesh::hull_solid(&d, [1.0; 3], Isometry3::identity(), "cradle".into()).unwrap();
        for (clear, above) in [(0.005, 0.01), (0.002, 0.01), (0.002, 0.005)] {
            let part =
                Solid::mochi_box(0.1 - 2.0 * clear, 0.1, 0.05, Isometry3::translation(0.0, 0.0, 0.03 + above), "pin")
                    .unwrap();
            let (_, lower, _) = solid_closest(&cradle, &cradle.pose, &part, &part.pose);
            let lower = lower - cradle.slack - part.slack;
            assert!(lower > 0.0 && lower <= clear.min(above) + 1e-9, "{clear} {above}: {lower}");
        }
        let into = Solid::mochi_box(0.102, 0.1, 0.05, Isometry3::translation(0.0, 0.0, 0.04), "pin").unwrap();
        let (_, lower, _) = solid_closest(&cradle, &cradle.pose, &into, &into.pose);
        assert!(lower <= 0.0, "{lower}");
    }
}
