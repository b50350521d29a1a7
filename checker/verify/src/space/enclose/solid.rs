//! Body containment (E0512, Sec 3.1's "FP contains geom(p)") for a footprint that is a
//! predicate and a body with a URDF or mesh part, which has no predicate of its own: the
//! SMT encoding cannot represent it, so the parts are decided here, by the interval search
//! of the parent module, against shapes that stand for them.
//!
//! **Holds.** Each solid of such a part is replaced by a stand-in that holds it at every
//! state: a sphere about the part's frame origin (`at pose(...)`, or the owner's frame),
//! and a cylinder about that frame's z axis from the solid's lowest to its highest `z`
//! (placed by the part's pose moved along its z axis to the solid's floor: `pose(x, y,
//! z + floor, 0, 0, yaw)`, which is the same frame moved along z only when the pose's roll
//! and pitch are the constant 0; otherwise only when the floor is at or above 0 and the
//! cylinder stands on `z = 0`). For a mesh (the convex hull of its vertices, slack included) the stand-ins are read
//! off the corners of its axis-aligned box in the part's frame (a convex function's
//! maximum over a box is at a corner, so the farthest point from the origin, or from the z
//! axis, of the box is a corner; the hull lies in the box). For a URDF link, the sphere's
//! radius is [`crate::geometry::Robot::reach`]'s bound on the distance from the URDF's root
//! of any point of the link's collision geometry over every configuration within the joint
//! limits; the limits are part of the kind's invariant (E0513), so every state the
//! contract allows is within them. That holds only for limits that are a finite range
//! (`lower < upper`, the ones the invariant receives): a link below a prismatic joint whose
//! limits are not (a `<limit>` without positions, URDF's `0` and `0`) slides as far as the
//! kind's own invariant lets it, beyond the reach, and has no stand-in (unknown). Each radius, height and depth is enlarged by
//! `1e-9 + 1e-9 |value|` m against the rounding of the poses (not the floor of a solid with
//! no pose of its own and no slack, whose box is its points' least and greatest coordinates,
//! exactly). If the footprint's predicate
//! holds at every point of a stand-in at every state the contract allows (the search of
//! [`super::part_within`], sound on its own), it holds at every point of the solid.
//!
//! **Fails.** A vertex of a mesh is a point of the body (the body is the hull of the
//! vertices). When the footprint's predicate, with its point at a vertex (enclosed in a box
//! of `1e-9 + 1e-12 |v|` m around the rounded value) and the state anywhere in the ranges
//! the contract's facts give, is false by outward-rounded interval evaluation, that vertex
//! is outside the footprint at every state the contract allows: the body is not contained.
//! As with `space::contain`'s rejection, the claim is about every allowed state; whether
//! the contract allows any is asked separately (E0408 and the vacuity guard).
//!
//! **Unknown** otherwise: a stand-in too coarse for the footprint (a footprint that fits
//! the solid more tightly than the sphere or cylinder around it), a URDF link whose body
//! points outside the footprint only at some configurations, or a search out of pieces.

use super::{exact_double, normalise_bool, part_within, place, strip, Facts, Tree, BUDGET};
use crate::bounds::compiled::VarTable;
use crate::bounds::Interval;
use crate::hir::body::{BodyPart, Pose, Shape};
use crate::hir::expr::{ExprKind, Sort};
use crate::hir::{Expr, Loc, PrimId, Program, Var};
use crate::space::world::Piece;
use num_rational::BigRational;

/// What the solids of a body say about containment in a predicate footprint.
#[derive(Debug, PartialEq)]
pub enum Solids {
    /// Every URDF and mesh part lies within the footprint, with how it was shown.
    Holds(String),
    /// A point of a URDF or mesh part lies outside the footprint at every allowed state.
    Fails(String),
    /// Not decided, with why.
    Unknown(String),
}

/// Whether the body of `prim`'s kind has a URDF or mesh part (and `prim`'s footprint is a
/// predicate): `None` when not (the question is Z3's or the other procedures'); otherwise the
/// answer for those parts, and the indices of the body's other parts (boxes, spheres,
/// cylinders, capsules), which the caller asks Z3 about.
pub fn solid_parts_in_predicate(prog: &Program, prim: PrimId) -> Option<(Solids, Vec<usize>)> {
    let p = prog.prim(prim);
    let fp = &p.footprint.predicate()?.pred;
    let body = prog.kind(p.kind).body.as_ref()?;
    let is_solid = |s: &Shape| matches!(s, Shape::Urdf { .. } | Shape::Mesh { .. });
    if !body.parts.iter().any(|part| is_solid(&part.shape)) {
        return None;
    }
    let others: Vec<usize> = (0..body.parts.len()).filter(|k| !is_solid(&body.parts[*k].shape)).collect();
    let Some(world) = crate::space::world::of(prog) else {
        return Some((Solids::Unknown("no solids were built for the body".into()), others));
    };
    let pieces: Vec<&Piece> =
        world.kinds.get(p.kind.idx()).into_iter().flatten().filter(|x| is_solid_piece(x)).collect();
    if pieces.is_empty() {
        return Some((Solids::Unknown("the body's URDF or mesh parts have no solid".into()), others));
    }
    let facts = Facts::of(prog, prim);
    let mut notes = Vec::new();
    for piece in &pieces {
        match piece_within(prog, piece, fp, &facts) {
            Ok(note) => notes.push(note),
            Err(why) => {
                if let Some(v) = vertex_outside(prog, piece, fp, &facts) {
                    return Some((
                        Solids::Fails(format!(
                            "the footprint contains the robot's body, but the vertex ({:.4}, {:.4}, {:.4}) m of the body's `{}` (in the frame of its part's `at pose(...)`) lies outside the footprint at every state the contract allows",
                            v[0], v[1], v[2], piece.solid.name
                        )),
                        others,
                    ));
                }
                return Some((
                    Solids::Unknown(format!(
                        "the body's `{}` is not shown within the footprint: {why}",
                        piece.solid.name
                    )),
                    others,
                ));
            }
        }
    }
    Some((
        Solids::Holds(format!(
            "each URDF or mesh solid of the body lies within a sphere or cylinder about its part's frame that lies within the footprint at every state its contract allows (interval branch and bound; {})",
            notes.join(", ")
        )),
        others,
    ))
}

/// A solid of a URDF or mesh part (a primitive shape's solid has neither a link nor
/// triangles nor a hull).
fn is_solid_piece(p: &Piece) -> bool {
    p.link.is_some() || p.solid.triangles.is_some() || p.solid.is_hull
}

/// Enlarged against the rounding of the poses.
fn out(v: f64) -> f64 {
    v + 1e-9 + 1e-9 * v.abs()
}

/// A cylinder about the z axis: its radius, floor and top.
type Cylinder = (f64, f64, f64);

/// The stand-ins of one solid, in its part's frame: a sphere of radius `r` about the
/// origin, and `Some((r_xy, floor, top))` a cylinder about the z axis holding it.
fn stand_ins(piece: &Piece) -> Result<(f64, Option<Cylinder>), String> {
    let infinite = || "its extent is not finite".to_string();
    if let Some(link) = &piece.link {
        if !slides_bounded(&link.robot, link.link) {
            return Err("a prismatic joint between the URDF's root and this link has no position limits (`lower` < `upper`), so the invariant does not bound how far the link slides".into());
        }
        let reach = link.robot.reach();
        let r = reach.get(link.link).ok_or_else(infinite)?.1;
        return (r.is_finite() && r >= 0.0).then(|| (out(r), None)).ok_or_else(infinite);
    }
    let b = piece.solid.local_aabb();
    let (lo, hi) = (b.mins, b.maxs);
    let mut r: f64 = 0.0;
    let mut rxy: f64 = 0.0;
    for x in [lo.x, hi.x] {
        for y in [lo.y, hi.y] {
            rxy = rxy.max(x.hypot(y));
            for z in [lo.z, hi.z] {
                r = r.max((x * x + y * y + z * z).sqrt());
            }
        }
    }
    if !(r.is_finite() && rxy.is_finite()) {
        return Err(infinite());
    }
    // The floor is padded downwards, the top upwards; a solid in its part's frame itself
    // (identity pose, no slack) has an exact box (the least and greatest coordinates of its
    // points, no arithmetic), and its floor is kept.
    let exact = piece.solid.pose == crate::geometry::identity() && piece.solid.slack == 0.0;
    let floor = if exact { lo.z } else { lo.z - 1e-9 - 1e-9 * lo.z.abs() };
    let cyl = (floor.is_finite() && hi.z.is_finite()).then(|| (out(rxy), floor, out(hi.z)));
    Ok((out(r), cyl))
}

/// Whether every prismatic joint between the URDF's root and `link` is driven by a joint
/// variable whose URDF limits are a finite range `lower < upper`: exactly the limits
/// `space::world::add_joint_limits` adds to the kind's invariant. [`Robot::reach`] bounds a
/// prismatic joint's travel by its variable's limits whatever they are, so where the
/// invariant does not hold the variable to them (URDF's default `0` and `0` of a `<limit>`
/// without positions, a `lower` above `upper`) the link slides beyond that reach and the
/// sphere is no stand-in. Rotations preserve lengths: revolute and continuous joints need
/// no limits.
///
/// [`Robot::reach`]: crate::geometry::Robot::reach
fn slides_bounded(robot: &crate::geometry::Robot, link: usize) -> bool {
    use crate::geometry::kinematics::JointKind;
    let bounded = |j: usize| {
        // The variable that drives `j`: its mimics followed to a joint that mimics none.
        let mut k = j;
        for _ in 0..=robot.joints.len() {
            match robot.joints.get(k).and_then(|x| x.mimic) {
                Some(m) => k = m.master,
                None => break,
            }
        }
        robot.joints.get(k).is_some_and(|v| {
            v.mimic.is_none()
                && v.kind.is_movable()
                && v.limits.is_some_and(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
        })
    };
    let mut at = link;
    for _ in 0..=robot.links.len() {
        let Some(j) = robot.parent_joint(at) else { return true };
        let Some(joint) = robot.joints.get(j) else { return false };
        if joint.kind == JointKind::Prismatic && !bounded(j) {
            return false;
        }
        at = joint.parent;
    }
    false
}

fn literal(v: f64) -> Option<Expr> {
    exact_double(v, Loc::default())
}

/// The search of [`part_within`] against each stand-in of the solid; the first that shows
/// containment answers.
fn piece_within(prog: &Program, piece: &Piece, fp: &Expr, facts: &Facts) -> Result<String, String> {
    let (r, cyl) = stand_ins(piece)?;
    let mut shapes = Vec::new();
    if let Some((rxy, floor, top)) = cyl {
        let place = lowered(prog, piece.place.as_ref(), floor);
        if let (Some(a), Some(b), Some(place)) = (literal(rxy), literal(top - floor.min(0.0)), place) {
            let what = format!("a cylinder of radius {rxy:.4} m from z = {:.4} to {top:.4} m", floor.min(0.0));
            shapes.push((Shape::Cylinder(a, b), place, what));
        }
    }
    if let Some(a) = literal(r) {
        shapes.push((Shape::Sphere(a), piece.place.clone(), format!("a sphere of radius {r:.4} m")));
    }
    let mut why = Vec::new();
    for (shape, place, what) in shapes {
        let part = BodyPart { shape, place, span: Default::default() };
        match part_within(prog, &part, fp, facts, BUDGET) {
            Ok(n) => return Ok(format!("`{}` within {what}, {n} pieces", piece.solid.name)),
            Err(u) => why.push(format!("{what} around it: {}", u.why)),
        }
    }
    Err(if why.is_empty() { "no stand-in".into() } else { why.join("; ") })
}

/// The part's pose moved along its own z axis to `floor` when the floor is below 0 (the
/// frame a cylinder standing on `z = floor` is placed by): `Some(None)`, `Some(place)` when
/// nothing moves, `None` when the pose's roll or pitch is not the constant 0 (its z axis is
/// then not the owner's, and the move is not a change of its z argument alone).
fn lowered(prog: &Program, place: Option<&Pose>, floor: f64) -> Option<Option<Pose>> {
    if floor >= 0.0 {
        return Some(place.cloned());
    }
    let dz = literal(floor)?;
    let zero = || literal(0.0);
    match place {
        None => Some(Some(Pose { args: [zero()?, zero()?, dz, zero()?, zero()?, zero()?], span: Default::default() })),
        Some(pose) => {
            let flat =
                |e: &Expr| crate::bounds::exact(prog, e).is_some_and(|q| q == BigRational::from_integer(0.into()));
            if !(flat(&pose.args[3]) && flat(&pose.args[4])) {
                return None;
            }
            let mut moved = pose.clone();
            moved.args[2] = super::bin(crate::hir::expr::BinOp::Add, pose.args[2].clone(), dz);
            Some(Some(moved))
        }
    }
}

/// Vertices examined per solid for a point outside the footprint.
const VERTICES: usize = 4096;

/// A vertex of a mesh solid (in its part's frame) that is outside the footprint at every
/// state the contract's ranges allow, by interval evaluation.
fn vertex_outside(prog: &Program, piece: &Piece, fp: &Expr, facts: &Facts) -> Option<[f64; 3]> {
    if piece.link.is_some() {
        return None;
    }
    let t = piece.solid.triangles.as_ref()?;
    let q: [Expr; 3] =
        [0, 1, 2].map(|k| Expr { kind: ExprKind::Var(Var::Point(k)), sort: Sort::Real, loc: Loc::default() });
    let placed = match &piece.place {
        Some(pose) => place(prog, pose, &q),
        None => q.clone(),
    };
    let goal = crate::hir::expr::map_vars(fp, &mut |v, _| match v {
        Var::Point(i) => placed.get(*i).cloned(),
        _ => None,
    });
    let goal = strip(&super::split_abs(&strip(&goal)));
    for v in t.vertices.iter().take(VERTICES) {
        let at = piece.solid.pose * v;
        let c = [at.x, at.y, at.z];
        if c.iter().any(|x| !x.is_finite()) {
            continue;
        }
        let pad = |x: f64| 1e-9 + 1e-12 * x.abs();
        let iv: Vec<Interval> = c.iter().map(|x| Interval::new(x - pad(*x), x + pad(*x))).collect();
        let extent = [0, 1, 2].map(|i| {
            let (l, h) = (BigRational::from_float(iv[i].lo), BigRational::from_float(iv[i].hi));
            l.zip(h)
        });
        let [Some(e0), Some(e1), Some(e2)] = extent else { continue };
        let g = normalise_bool(prog, &goal, &[e0, e1, e2]);
        let mut table = VarTable::new();
        let tree = Tree::new(prog, &g, &mut table);
        let now: Vec<Tree> = facts.now.iter().map(|f| Tree::new(prog, &strip(f), &mut table)).collect();
        let env: Vec<Option<Interval>> = table
            .vars()
            .iter()
            .map(|v| match v {
                Var::Point(i) => iv.get(*i).copied(),
                v => facts.ranges.get(v).copied().filter(|r| r.lo <= r.hi),
            })
            .collect();
        let mut work = Vec::new();
        // Some state of the ranges may satisfy the contract's facts (none is false on all
        // of them), and at every state of the ranges the vertex is outside.
        if now.iter().all(|f| f.truth(&env, &mut work) != Some(false)) && tree.truth(&env, &mut work) == Some(false) {
            return Some(c);
        }
    }
    None
}
