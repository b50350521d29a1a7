//! Whether a placed solid lies within other placed solids, each read as the solid it is: a
//! mesh by its closed triangle mesh (the generalised winding number), not by its convex
//! hull or its convex pieces, which bulge into a concave mesh's hollows. For the simulator
//! (`crate::simulate`), which tests concrete states: these are tests that find a point
//! outside, never proofs that none is.

use super::{Pose3, Solid};
use nalgebra::{Point3, Vector3};
use parry3d::query::PointQuery;
use parry3d::shape::{Triangle, TypedShape};

/// The triangles of a mesh solid in its shape's frame (place them by `owner * pose`).
fn local_triangles(s: &Solid) -> Option<Vec<[Point3<f64>; 3]>> {
    let t = s.triangles.as_ref().filter(|_| s.is_hull)?;
    let v = |i: u32| t.vertices.get(i as usize).copied();
    let tri: Option<Vec<[Point3<f64>; 3]>> = t.indices.iter().map(|[a, b, c]| Some([v(*a)?, v(*b)?, v(*c)?])).collect();
    tri.filter(|t| !t.is_empty())
}

/// Whether the world point `p` lies in the solid `s` whose owner frame is at `owner`, or
/// within `tol` metres of it. A mesh solid is the region its triangles bound: a point
/// within `tol` of a triangle, or whose winding number about the triangles is at least
/// 1/2 in magnitude (1 inside a closed oriented mesh, 0 outside); any other solid is its
/// convex shape.
pub fn solid_contains(owner: &Pose3, s: &Solid, p: [f64; 3], tol: f64) -> bool {
    contains_with(owner, s, local_triangles(s).as_deref(), p, tol)
}

/// [`solid_contains`] with the mesh solid's triangles given (`local_triangles`, built once
/// by a caller that asks about many points).
fn contains_with(owner: &Pose3, s: &Solid, tri: Option<&[[Point3<f64>; 3]]>, p: [f64; 3], tol: f64) -> bool {
    let pose = owner * s.pose;
    let wp = Point3::new(p[0], p[1], p[2]);
    if let Some(tri) = tri {
        let local = pose.inverse_transform_point(&wp);
        if let Some(m) = s.mesh() {
            if m.distance_to_local_point(&local, false) <= tol {
                return true;
            }
        }
        return super::mesh::winding(tri, &local).abs() >= 0.5;
    }
    s.shape.distance_to_point(&pose, &wp, true) <= tol
}

/// Points of the solid `s` placed by `owner` (world frame) where it is most likely to leave
/// a region: the corners of a box or polyhedron and the support points in the 26 directions
/// of a cube's faces, edges and corners, each moved `inset` metres towards their mean; for
/// a mesh solid, the vertices of its triangles (points of the mesh itself, not of its hull).
pub fn probe_points(owner: &Pose3, s: &Solid, inset: f64) -> Vec<[f64; 3]> {
    let pose = owner * s.pose;
    if let Some(tri) = local_triangles(s) {
        return tri.iter().flatten().map(|p| pose * p).map(|p| [p.x, p.y, p.z]).collect();
    }
    let mut pts: Vec<Point3<f64>> = super::boundary_points(owner, s, 0.0).iter().map(|p| Point3::from(*p)).collect();
    match s.shape.as_typed_shape() {
        TypedShape::Cuboid(c) => {
            let h = c.half_extents;
            for i in 0..8 {
                let sgn = |b: usize| if i & b == 0 { -1.0 } else { 1.0 };
                pts.push(pose * Point3::new(sgn(1) * h.x, sgn(2) * h.y, sgn(4) * h.z));
            }
        }
        TypedShape::ConvexPolyhedron(c) => pts.extend(c.points().iter().map(|p| pose * p)),
        _ => {}
    }
    if pts.is_empty() {
        return Vec::new();
    }
    let centre = pts.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / pts.len() as f64;
    pts.iter()
        .map(|p| {
            let to_centre = centre - p.coords;
            let n = to_centre.norm();
            let q = if n > inset { p.coords + to_centre * (inset / n) } else { centre };
            [q.x, q.y, q.z]
        })
        .collect()
}

/// A world point of the convex solid `body` (placed by `owner`) that lies in none of the
/// solids `region` (each with its owner's world pose), by more than `tol`; `None` when the
/// tests find none. Tested: the body's [`probe_points`] (1 µm inside it); and, when the
/// region is one mesh solid and the body is no mesh, every triangle of the mesh that
/// reaches more than `tol` into the body: the mesh's surface there has the region's outside
/// on one side, so a point just off the triangle, inside the body and outside the mesh, is
/// one. (A concave footprint's hollow may hold every corner of the body's top and still cut
/// through its middle: that second test finds it.)
pub fn point_outside(owner: &Pose3, body: &Solid, region: &[(Pose3, &Solid)], tol: f64) -> Option<[f64; 3]> {
    let meshes: Vec<Option<Vec<[Point3<f64>; 3]>>> = region.iter().map(|(_, s)| local_triangles(s)).collect();
    let inside =
        |p: [f64; 3]| region.iter().zip(&meshes).any(|((o, s), tri)| contains_with(o, s, tri.as_deref(), p, tol));
    if let Some(p) = probe_points(owner, body, 1e-6).into_iter().find(|p| !inside(*p)) {
        return Some(p);
    }
    let [(ro, rs)] = region else { return None };
    if body.is_hull {
        return None;
    }
    let tri = local_triangles(rs)?;
    let (bp, rp) = (owner * body.pose, ro * rs.pose);
    let bbox = body.shape.compute_aabb(&bp);
    for t in &tri {
        let w = [rp * t[0], rp * t[1], rp * t[2]];
        let (lo, hi) = (w[0].inf(&w[1]).inf(&w[2]), w[0].sup(&w[1]).sup(&w[2]));
        if (0..3).any(|k| hi[k] < bbox.mins[k] || lo[k] > bbox.maxs[k]) {
            continue;
        }
        let triangle = Triangle::new(w[0], w[1], w[2]);
        let Some(normal) = triangle.normal() else { continue };
        let Ok(Some(c)) = parry3d::query::contact(&bp, body.shape.as_ref(), &Pose3::identity(), &triangle, 0.0) else {
            continue;
        };
        if c.dist.is_nan() || c.dist >= -2.0 * tol {
            continue;
        }
        // The triangle's point deepest in the body, moved off the surface to either side.
        for e in [1e-7, 1e-6, 1e-5, 1e-4, 1e-3] {
            for side in [1.0, -1.0] {
                let q = c.point2 + normal.into_inner() * (side * e);
                let p = [q.x, q.y, q.z];
                if body.shape.distance_to_point(&bp, &q, true) <= 0.0 && !inside(p) {
                    return Some(p);
                }
            }
        }
    }
    None
}

/// A world point of the solid `s` placed by `owner`: a vertex of a mesh solid's triangles,
/// else the support point of its shape along x.
pub fn some_point(owner: &Pose3, s: &Solid) -> Option<[f64; 3]> {
    probe_points(owner, s, 0.0).into_iter().next()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::identity;

    /// The cradle of `robots/meshes/cradle.obj`: a U, 0.3 by 0.2 by 0.1 m, whose slot
    /// (x in [-0.05, 0.05]) opens at z = 0.03.
    fn cradle() -> Solid {
        let text = "v -0.15 -0.1 0\nv 0.15 -0.1 0\nv 0.15 -0.1 0.1\nv 0.05 -0.1 0.1\nv 0.05 -0.1 0.03\nv -0.05 -0.1 0.03\nv -0.05 -0.1 0.1\nv -0.15 -0.1 0.1\nv -0.15 0.1 0\nv 0.15 0.1 0\nv 0.15 0.1 0.1\nv 0.05 0.1 0.1\nv 0.05 0.1 0.03\nv -0.05 0.1 0.03\nv -0.05 0.1 0.1\nv -0.15 0.1 0.1\nf 1 2 5\nf 9 13 10\nf 1 5 6\nf 9 14 13\nf 1 6 7\nf 9 15 14\nf 1 7 8\nf 9 16 15\nf 2 3 4\nf 10 12 11\nf 2 4 5\nf 10 13 12\nf 2 1 9\nf 2 9 10\nf 3 2 10\nf 3 10 11\nf 4 3 11\nf 4 11 12\nf 5 4 12\nf 5 12 13\nf 6 5 13\nf 6 13 14\nf 7 6 14\nf 7 14 15\nf 8 7 15\nf 8 15 16\nf 1 8 16\nf 1 16 9\n";
        let data = crate::geometry::mesh::parse(text.as_bytes(), crate::geometry::mesh::Format::Obj).expect("obj");
        crate::geometry::mesh::hull_solid(&data, [1.0; 3], identity(), "cradle".into()).expect("a solid")
    }

    #[test]
    fn a_point_in_the_hollow_of_a_concave_mesh_is_outside_it() {
        let c = cradle();
        assert!(solid_contains(&identity(), &c, [0.1, 0.0, 0.05], 1e-9), "in a wall");
        assert!(solid_contains(&identity(), &c, [0.0, 0.0, 0.01], 1e-9), "in the floor");
        // In the slot: inside the hull, outside the mesh.
        assert!(!solid_contains(&identity(), &c, [0.0, 0.0, 0.06], 1e-9));
        assert!(c.shape.distance_to_point(&identity(), &Point3::new(0.0, 0.0, 0.06), true) <= 0.0);
    }

    #[test]
    fn a_box_whose_top_is_in_the_slot_leaves_the_cradle_and_one_below_it_does_not() {
        let c = cradle();
        let region = [(identity(), &c)];
        // 5 cm tall from z = 0: its top 2 cm are in the slot.
        let tall = Solid::mochi_box(0.08, 0.1, 0.05, identity(), "tall").expect("box");
        let p = point_outside(&identity(), &tall, &region, 1e-9).expect("the top is in the slot");
        assert!(p[2] > 0.03 && p[0].abs() < 0.05, "{p:?}");
        // 2 cm tall: within the floor.
        let low = Solid::mochi_box(0.08, 0.1, 0.02, identity(), "low").expect("box");
        assert_eq!(point_outside(&identity(), &low, &region, 1e-9), None);
        // A box wider than the slot whose corners all lie in the walls' tops, its middle
        // over the slot: only the triangle test finds it.
        let bridge =
            Solid::mochi_box(0.2, 0.1, 0.02, nalgebra::Isometry3::translation(0.0, 0.0, 0.07), "bridge").expect("box");
        let p = point_outside(&identity(), &bridge, &region, 1e-9).expect("the middle is over the slot");
        assert!(!solid_contains(&identity(), &c, p, 1e-9), "{p:?}");
    }
}
