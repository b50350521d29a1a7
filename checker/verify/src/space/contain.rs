//! Whether a robot's body lies within a geometric footprint that has no predicate (a
//! mesh or URDF, `hir::Footprint::Solid`): Sec 3.1's "FP contains geom(p)" (E0512),
//! decided with the solids of [`super::world`] where that is exact, and otherwise left
//! undecided (the caller reports unknown).
//!
//! Decided case: every piece of the body is the footprint's piece itself (the same mesh
//! file, read once) or lies within one piece of the footprint placed by the same pose (`at pose(...)` with equal expressions, so that whatever the state, the
//! two are in one frame and the question does not depend on the state), neither a URDF
//! link. A piece `A` lies within a convex piece `B` iff every point of a finite set whose
//! hull holds `A` (a box's corners, a mesh's vertices; a cylinder's bounding box's
//! corners) is inside `B`, or for round pieces every point of a core (a ball's centre, a
//! capsule's segment ends) is inside `B` at depth at least the radius (the points of a
//! convex `B` at depth at least `r` form a convex set, so the core's hull is in it too).
//!
//! A markedly concave mesh footprint (one `geometry::mesh::decompose` cuts into convex
//! pieces) is read by the geometric checks as the union of its pieces, so there `B` is one
//! of the pieces, never the hull: the hull also holds the mesh's hollows (a cradle's slot),
//! which the footprint does not claim.
//!
//! Soundness of the arithmetic: `B` stands for the convex hull of the mesh's vertices
//! only when every vertex of the hull parry built is one of them (parry's quickhull keeps
//! input points, so its hull is then within the true one); a hull of thickened vertices
//! (a flat mesh) is bigger than the footprint, and the question is left undecided. Each
//! point must be inside `B` by a margin of 1e-9 m, a relative 1e-12 of its distance from
//! the origin and both solids' slacks (the rounding of the mesh's numbers and of the
//! projection), on top of the depth it needs.

use super::world::Piece;
use crate::geometry::FramePoint as Point;
use crate::hir::{Footprint, PrimId, Program};
use std::collections::HashSet;

/// Whether the body of a kind lies within a footprint, decided by the solids.
#[derive(Debug, PartialEq)]
pub enum Contained {
    /// At every state, with how it was shown.
    Yes(String),
    /// At no state: a point of the body is outside the footprint whatever the state.
    No(String),
    /// Not decided, with why.
    Unknown(String),
}

/// Whether the body of `prim`'s kind lies within `prim`'s footprint at every state.
pub fn body_within_footprint(prog: &Program, prim: PrimId) -> Contained {
    let p = prog.prim(prim);
    let Some(world) = crate::space::world::of(prog) else { return Contained::Unknown("no solids were built".into()) };
    let Footprint::Solid { .. } = &p.footprint else {
        return Contained::Unknown("not a footprint with a URDF or mesh part".into());
    };
    let (body, fp) =
        match (pieces(world.kinds.get(p.kind.idx())), pieces(world.prims.get(prim.idx()).and_then(|x| x.as_ref()))) {
            (Ok(b), Ok(f)) => (b, f),
            (Err(why), _) | (_, Err(why)) => return Contained::Unknown(why),
        };
    for a in body {
        if fp.iter().any(|b| same_place(prog, a, b) && within(a, b)) {
            continue;
        }
        // Outside: every footprint part is placed as `a` is, and a point of `a` lies
        // beyond all their bounding spheres about that frame's origin.
        if let Some(q) = beyond(prog, a, fp) {
            return Contained::No(format!(
                "the footprint contains the robot's body, but the point ({:.4}, {:.4}, {:.4}) m of the body's `{}` (in the frame of its `at pose(...)`) lies outside every part of the footprint, placed by the same pose, at every state",
                q.x, q.y, q.z, a.solid.name
            ));
        }
        return Contained::Unknown(format!(
            "the body's `{}` does not lie, by the solids alone, within a part of the footprint placed by the same pose (the SMT solver has no predicate for a URDF or mesh footprint)",
            a.solid.name
        ));
    }
    Contained::Yes("each part of the body lies within a part of the footprint placed by the same pose".into())
}

/// A point of `a` farther from its frame's origin than any point of the parts `fp`, all
/// placed as `a` is.
fn beyond(prog: &Program, a: &Piece, fp: &[Piece]) -> Option<Point> {
    if !fp.iter().all(|b| same_place(prog, a, b)) {
        return None;
    }
    let reach = fp.iter().map(|b| b.solid.bounding_radius()).fold(0.0, f64::max);
    let (points, depth) = core(a)?;
    // Corners and vertices are points of the body (within its slack); a round part's
    // core is not on its surface, so only polyhedral parts (depth = slack) are used.
    if depth > a.solid.slack {
        return None;
    }
    points.into_iter().find(|q| {
        let n = q.coords.norm();
        n.is_finite() && n > reach + a.solid.slack + 1e-9 + 1e-12 * n
    })
}

fn pieces(p: Option<&Vec<Piece>>) -> Result<&Vec<Piece>, String> {
    match p {
        Some(v) if !v.is_empty() => {
            if v.iter().any(|x| x.link.is_some()) {
                Err("a URDF part, placed by its joints".into())
            } else {
                Ok(v)
            }
        }
        _ => Err("a body with no solid".into()),
    }
}

/// Both placed by the same pose: equal arguments, by value ([`crate::bounds::same_value`]).
fn same_place(prog: &Program, a: &Piece, b: &Piece) -> bool {
    match (&a.place, &b.place) {
        (None, None) => true,
        (Some(x), Some(y)) => {
            x.args.len() == y.args.len()
                && x.args.iter().zip(&y.args).all(|(u, v)| crate::bounds::same_value(prog, u, v))
        }
        _ => false,
    }
}

/// The points (in the piece's owner frame) whose hull, thickened by the depth, holds `a`.
fn core(a: &Piece) -> Option<(Vec<Point>, f64)> {
    let s = &a.solid;
    let at = |p: Point| s.pose * p;
    let shape = &s.shape;
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        let mut out = Vec::new();
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    out.push(at(Point::new(sx * h.x, sy * h.y, sz * h.z)));
                }
            }
        }
        return Some((out, s.slack));
    }
    if let Some(b) = shape.as_ball() {
        return Some((vec![at(Point::origin())], b.radius + s.slack));
    }
    if let Some(c) = shape.as_capsule() {
        return Some((vec![at(c.segment.a), at(c.segment.b)], c.radius + s.slack));
    }
    if let Some(c) = shape.as_cylinder() {
        // Parry's cylinder stands on its y axis: its bounding box's corners.
        let (r, h) = (c.radius, c.half_height);
        let mut out = Vec::new();
        for sx in [-r, r] {
            for sy in [-h, h] {
                for sz in [-r, r] {
                    out.push(at(Point::new(sx, sy, sz)));
                }
            }
        }
        return Some((out, s.slack));
    }
    if shape.as_convex_polyhedron().is_some() {
        // A mesh stands for the hull of its vertices (within its slack).
        let t = s.triangles.as_ref()?;
        return Some((t.vertices.iter().map(|p| at(*p)).collect(), s.slack));
    }
    None
}

/// Whether `b` is known to stand for no more than its mesh's hull (or is a primitive).
fn exact(b: &Piece) -> bool {
    let s = &b.solid;
    let Some(poly) = s.shape.as_convex_polyhedron() else { return s.triangles.is_none() };
    let Some(t) = s.triangles.as_ref() else { return false };
    let key = |p: &Point| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let verts: HashSet<[u64; 3]> = t.vertices.iter().map(key).collect();
    poly.points().iter().all(|p| verts.contains(&key(p)))
}

fn within(a: &Piece, b: &Piece) -> bool {
    // The same solid (one mesh file, cached once by the world builder): within itself.
    if std::sync::Arc::ptr_eq(&a.solid, &b.solid) {
        return true;
    }
    let Some((points, depth)) = core(a) else { return false };
    if !exact(b) || points.is_empty() {
        return false;
    }
    // A markedly concave mesh is read by the geometric checks as the union of its convex
    // pieces (`geometry::solid_closest`), not as its hull: a body in the hull may lie in the
    // mesh's hollow, where an obstacle the footprint clears can stand. Within one piece is
    // within that union.
    let containers: Vec<_> = match b.solid.pieces() {
        Some((pieces, _)) => pieces.iter().map(|piece| &piece.shape).collect(),
        None => vec![&b.solid.shape],
    };
    containers.iter().any(|shape| {
        points.iter().all(|q| {
            let local = b.solid.pose.inverse_transform_point(q);
            let proj = shape.project_local_point(&local, false);
            let margin = 1e-9 + 1e-12 * q.coords.norm() + b.solid.slack;
            let d = (proj.point - local).norm();
            proj.is_inside && d.is_finite() && d >= depth + margin
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Solid;
    use std::sync::Arc;

    fn piece(s: Solid) -> Piece {
        Piece { solid: Arc::new(s), place: None, link: None }
    }

    #[test]
    fn a_piece_is_within_another_only_with_a_margin() {
        let id = crate::geometry::identity();
        let outer = piece(Solid::mochi_box(1.0, 1.0, 1.0, id, "outer").unwrap());
        let at = |z: f64| nalgebra::Isometry3::translation(0.0, 0.0, z);
        // Standing on the same floor: its corners touch the outer box's, not within.
        let low = piece(Solid::mochi_box(0.5, 0.5, 0.5, id, "low").unwrap());
        assert!(!within(&low, &outer));
        let inner = piece(Solid::mochi_box(0.5, 0.5, 0.5, at(0.25), "inner").unwrap());
        assert!(within(&inner, &outer));
        assert!(!within(&outer, &inner));
        // A box is not within an equal one built apart: its corners are on the boundary, not
        // inside by a margin. The same solid is within itself.
        let twin = piece(Solid::mochi_box(1.0, 1.0, 1.0, id, "twin").unwrap());
        assert!(!within(&outer, &twin));
        assert!(within(&outer, &outer));
        let ball = |r: f64, z: f64| piece(Solid::sphere(r, at(z), "ball").unwrap());
        assert!(within(&ball(0.49, 0.5), &outer));
        assert!(!within(&ball(0.51, 0.5), &outer));
        // The inner box's corners are sqrt(3) / 4 = 0.433 from its centre.
        assert!(within(&inner, &ball(0.44, 0.5)));
        assert!(!within(&inner, &ball(0.43, 0.5)));
    }

    /// The cradle (robots/meshes/cradle.obj, a U 0.3 m by 0.2 m by 0.1 m whose slot, 0.1 m
    /// wide, has its floor at z = 0.03) lowered by 1 cm: a box standing on z = 0 in the
    /// middle, 5 cm tall, is inside the cradle's hull with room to spare, but its top 3 cm
    /// are in the slot, which the decomposed mesh does not claim (an obstacle can stand
    /// there clear of the footprint): not within. A smaller box in a wall is within.
    #[test]
    fn a_body_in_the_hollow_of_a_concave_mesh_is_not_within_it() {
        use crate::geometry::mesh::{hull_solid, parse, Format};
        let text = std::fs::read_to_string(crate::testing::repo("robots/meshes/cradle.obj")).expect("cradle");
        let mut d = parse(text.as_bytes(), Format::Obj).expect("obj");
        for v in &mut d.vertices {
            v.z -= 0.01;
        }
        let id = crate::geometry::identity();
        let cradle = piece(hull_solid(&d, [1.0; 3], id, "cradle".into()).expect("hull"));
        assert!(cradle.solid.pieces().is_some(), "the cradle is decomposed");
        let in_slot = piece(Solid::mochi_box(0.08, 0.1, 0.05, id, "in slot").unwrap());
        assert!(!within(&in_slot, &cradle));
        // Within one piece of the wall (the pieces are a grid of a few centimetres).
        let at = nalgebra::Isometry3::translation(0.11, -0.025, 0.0);
        let in_wall = piece(Solid::mochi_box(0.04, 0.03, 0.05, at, "in wall").unwrap());
        assert!(within(&in_wall, &cradle));
    }
}
