//! Solids: one convex shape of parry, placed in its owner's frame (a URDF link, a robot
//! kind's body, an obstacle), with a human name for diagnostics.
//!
//! Two conventions build them (both in metres):
//! - mochi's (`checker/core/src/hir/body.rs`, LANGUAGE.md): `box(lx, ly, lz)` centred in x and y and
//!   standing on z = 0; `sphere(r)` centred; `cylinder(r, h)` and `capsule(r, h)` with their
//!   axis on z from z = 0 to z = h (a capsule's segment from z = r to z = h - r);
//! - URDF's: `<box size>` centred; `<cylinder radius length>` and `<capsule>` centred on
//!   their origin along z (a URDF capsule's `length` is that of its cylinder part);
//!   `<sphere radius>` centred.
//!
//! parry's cylinders and capsules lie along y: a z-axis one is placed by a rotation of a
//! quarter turn about x. Every solid is convex and has a support map, so every query of
//! [`super::distance`] between two solids is supported by parry.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::shape::{SharedShape, TypedShape};
use std::sync::Arc;

/// A size that describes no solid: what it is, of which shape, and the value.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeError {
    pub message: String,
}

impl std::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

fn positive(shape: &str, what: &str, v: f64) -> Result<f64, ShapeError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ShapeError { message: format!("the {what} of a {shape} is {v}: it must be a positive finite number") })
    }
}

/// The triangles of a mesh solid, kept for a caller that wants to confirm a contact of
/// convex hulls on the mesh itself ([`Solid::trimesh`]).
#[derive(Debug)]
pub struct Triangles {
    /// In the solid's own frame (already scaled).
    pub vertices: Vec<Point3<f64>>,
    pub indices: Vec<[u32; 3]>,
}

/// A convex piece of a decomposed mesh, with a sphere (centre in the solid's own frame,
/// radius) that holds it.
#[derive(Clone)]
pub struct Piece {
    pub shape: SharedShape,
    pub centre: Point3<f64>,
    pub radius: f64,
}

/// The convex pieces of a concave mesh and their slack, built on first use (`None`: the
/// mesh is not cut).
type LazyPieces = Arc<std::sync::OnceLock<Option<(Vec<Piece>, f64)>>>;

/// One convex solid placed in its owner's frame.
#[derive(Clone)]
pub struct Solid {
    /// The convex shape, in its own frame.
    pub shape: SharedShape,
    /// Its pose in the owner's frame (a link's frame, a body's frame).
    pub pose: Isometry3<f64>,
    /// For diagnostics: `"panda_link3 (collision 1)"`, `"box"`.
    pub name: String,
    /// How far a point of what this solid stands for may lie outside `shape` (metres): 0
    /// for primitives; for a mesh, the largest distance of a mesh vertex outside the hull
    /// parry computed (its quickhull drops points within a tolerance of a face). A
    /// clearance is only proved after subtracting the slacks of both sides.
    pub slack: f64,
    /// For a mesh: the triangles the hull was built from (`None` for primitives).
    pub triangles: Option<Arc<Triangles>>,
    /// Whether `shape` is a convex hull standing for a (possibly non-convex) mesh: a
    /// contact of hulls is then reported as "convex hulls touch", not as a contact.
    pub is_hull: bool,
    /// For a markedly concave closed mesh: convex pieces, in the solid's own frame, whose
    /// union holds the mesh's solid (`mesh::decompose`), each within `shape`, with how far
    /// their slack exceeds [`Solid::slack`]. Built on first use ([`Solid::pieces`]): only
    /// where hulls touch ([`super::solid_closest`]), so a mesh whose hull is never reached
    /// costs nothing.
    pieces: LazyPieces,
    radius: f64,
    aabb: Aabb,
    /// [`Solid::trimesh`], built on first use by [`Solid::mesh`] (a BVH build per call
    /// would dominate a search that confirms contacts of hulls).
    mesh: Arc<std::sync::OnceLock<Option<parry3d::shape::TriMesh>>>,
}

impl std::fmt::Debug for Solid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solid")
            .field("name", &self.name)
            .field("shape", &self.shape.shape_type())
            .field("pose", &self.pose)
            .field("slack", &self.slack)
            .finish()
    }
}

/// A quarter turn about x: parry's y axis onto z.
fn y_to_z() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2)
}

impl Solid {
    /// A solid from a convex shape placed at `pose` in its owner's frame.
    pub fn new(shape: SharedShape, pose: Isometry3<f64>, name: impl Into<String>) -> Solid {
        Solid::with_slack(shape, pose, name.into(), 0.0, None)
    }

    pub(crate) fn with_slack(
        shape: SharedShape,
        pose: Isometry3<f64>,
        name: String,
        slack: f64,
        triangles: Option<Arc<Triangles>>,
    ) -> Solid {
        let aabb = shape.compute_aabb(&pose).loosened(slack);
        let radius = far_radius(&shape, &pose) + slack;
        let is_hull = triangles.is_some();
        Solid {
            shape,
            pose,
            name,
            slack,
            triangles,
            is_hull,
            pieces: Arc::default(),
            radius,
            aabb,
            mesh: Arc::default(),
        }
    }

    /// The convex pieces of a markedly concave closed mesh, with how far their slack exceeds
    /// [`Solid::slack`] (a bound over the pieces subtracts it too); `None` for a primitive
    /// or a mesh its hull stands for alone (`mesh::decompose`). Built once, on first use.
    pub fn pieces(&self) -> Option<(&[Piece], f64)> {
        let made = self.pieces.get_or_init(|| {
            if !self.is_hull {
                return None;
            }
            let (shapes, slack) = super::mesh::pieces_of(self.triangles.as_ref()?)?;
            let pieces = shapes
                .into_iter()
                .map(|shape| {
                    let s = shape.compute_local_bounding_sphere();
                    Piece { centre: *s.center(), radius: s.radius() * (1.0 + 1e-9) + 1e-12, shape }
                })
                .collect();
            Some((pieces, (slack - self.slack).max(0.0)))
        });
        made.as_ref().map(|(p, e)| (p.as_slice(), *e))
    }

    /// The same solid placed by `place ∘ pose` in a new owner frame (`place` maps the old
    /// owner frame into the new one).
    pub fn placed(&self, place: &Isometry3<f64>) -> Solid {
        let mut s = Solid::with_slack(
            self.shape.clone(),
            place * self.pose,
            self.name.clone(),
            self.slack,
            self.triangles.clone(),
        );
        s.pieces = self.pieces.clone();
        s
    }

    /// mochi's `box(lx, ly, lz)`: centred in x and y, standing on z = 0 of `place`.
    pub fn mochi_box(lx: f64, ly: f64, lz: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let (lx, ly, lz) =
            (positive("box", "x length", lx)?, positive("box", "y length", ly)?, positive("box", "z length", lz)?);
        let pose = place * Translation3::new(0.0, 0.0, lz / 2.0);
        Ok(Solid::new(SharedShape::cuboid(lx / 2.0, ly / 2.0, lz / 2.0), pose, name))
    }

    /// mochi's and URDF's `sphere(r)`, centred on `place`'s origin.
    pub fn sphere(r: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let r = positive("sphere", "radius", r)?;
        Ok(Solid::new(SharedShape::ball(r), place, name))
    }

    /// mochi's `cylinder(r, h)`: axis z from z = 0 to z = h of `place`.
    pub fn mochi_cylinder(r: f64, h: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let (r, h) = (positive("cylinder", "radius", r)?, positive("cylinder", "height", h)?);
        let pose = place * Translation3::new(0.0, 0.0, h / 2.0) * y_to_z();
        Ok(Solid::new(SharedShape::cylinder(h / 2.0, r), pose, name))
    }

    /// mochi's `capsule(r, h)`: overall height `h >= 2 r`, axis z from z = 0 to z = h.
    pub fn mochi_capsule(r: f64, h: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let (r, h) = (positive("capsule", "radius", r)?, positive("capsule", "height", h)?);
        if h < 2.0 * r {
            return Err(ShapeError {
                message: format!("a capsule's overall height {h} is less than twice its radius {r}"),
            });
        }
        let shape = SharedShape::capsule(Point3::new(0.0, 0.0, r), Point3::new(0.0, 0.0, h - r), r);
        Ok(Solid::new(shape, place, name))
    }

    /// URDF's `<box size="lx ly lz">`: centred on `place`'s origin.
    pub fn urdf_box(size: [f64; 3], place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let [lx, ly, lz] = size;
        let (lx, ly, lz) =
            (positive("box", "x size", lx)?, positive("box", "y size", ly)?, positive("box", "z size", lz)?);
        Ok(Solid::new(SharedShape::cuboid(lx / 2.0, ly / 2.0, lz / 2.0), place, name))
    }

    /// URDF's `<cylinder radius length>`: centred on `place`'s origin, along its z.
    pub fn urdf_cylinder(radius: f64, length: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let (r, l) = (positive("cylinder", "radius", radius)?, positive("cylinder", "length", length)?);
        Ok(Solid::new(SharedShape::cylinder(l / 2.0, r), place * y_to_z(), name))
    }

    /// URDF's `<capsule radius length>`: a cylinder of that length centred along z, with
    /// hemispherical caps beyond its ends.
    pub fn urdf_capsule(radius: f64, length: f64, place: Isometry3<f64>, name: &str) -> Result<Solid, ShapeError> {
        let (r, l) = (positive("capsule", "radius", radius)?, positive("capsule", "length", length)?);
        let shape = SharedShape::capsule(Point3::new(0.0, 0.0, -l / 2.0), Point3::new(0.0, 0.0, l / 2.0), r);
        Ok(Solid::new(shape, place, name))
    }

    /// An upper bound on the distance from the owner frame's origin of any point this
    /// solid stands for (its slack included).
    pub fn bounding_radius(&self) -> f64 {
        self.radius
    }

    /// A solid that holds this one turned by any angle about the owner frame's z axis:
    /// the cylinder about that axis through the corners of [`Solid::local_aabb`] (slack
    /// included). The geometric search places it instead of the solid when only that
    /// turn varies (a mobile base's heading), so the heading needs no splitting.
    ///
    /// Sound: a point `p` of the solid lies in its box, so its distance from the z axis is
    /// at most the largest corner's (a convex function of `p` is largest at a vertex) and
    /// its height is in the box's z range; a turn about z keeps both. The radius and the
    /// half height are padded by 1e-9 m (and a relative 1e-12) against the rounding of the
    /// square root and of the cylinder's quarter turn (parry's cylinders stand on y).
    pub fn z_cylinder(&self) -> Solid {
        let (lo, hi) = (self.aabb.mins, self.aabb.maxs);
        let pad = |x: f64| x * (1.0 + 1e-12) + 1e-9;
        let mut r2: f64 = 0.0;
        for x in [lo.x, hi.x] {
            for y in [lo.y, hi.y] {
                r2 = r2.max(x * x + y * y);
            }
        }
        let radius = pad(r2.sqrt());
        let half = pad((hi.z - lo.z) / 2.0);
        let zc = lo.z / 2.0 + hi.z / 2.0;
        let pose = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, zc),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
        );
        Solid::new(SharedShape::cylinder(half, radius), pose, format!("{} (turned about z)", self.name))
    }

    /// The axis-aligned box, in the owner's frame, of the solid (slack included).
    pub fn local_aabb(&self) -> Aabb {
        self.aabb
    }

    /// [`Solid::trimesh`], built once per solid.
    pub fn mesh(&self) -> Option<&parry3d::shape::TriMesh> {
        self.mesh.get_or_init(|| self.trimesh()).as_ref()
    }

    /// The triangle mesh of a mesh solid, in the solid's own frame (place it by
    /// [`Solid::pose`]), to confirm a contact of convex hulls exactly; `None` for a
    /// primitive (whose shape is exact already) or a mesh parry cannot index.
    pub fn trimesh(&self) -> Option<parry3d::shape::TriMesh> {
        let t = self.triangles.as_ref()?;
        if t.indices.is_empty() {
            return None;
        }
        parry3d::shape::TriMesh::new(t.vertices.clone(), t.indices.clone()).ok()
    }
}

/// The largest distance from the origin of a point of `shape` placed at `pose`: exact for
/// balls, cuboids and polyhedra (the maximum of a convex function over a polytope is at a
/// vertex), exact for capsules (the axis segment's farther end plus the radius: the
/// distance to the origin is convex along the segment) and cylinders (the farthest point
/// is on a rim circle), and an AABB corner bound for anything else.
fn far_radius(shape: &SharedShape, pose: &Isometry3<f64>) -> f64 {
    let far = |pts: &mut dyn Iterator<Item = Point3<f64>>| pts.map(|p| (pose * p).coords.norm()).fold(0.0, f64::max);
    match shape.as_typed_shape() {
        TypedShape::Ball(b) => pose.translation.vector.norm() + b.radius,
        TypedShape::Cuboid(c) => {
            let h = c.half_extents;
            let mut corners = (0..8).map(|i| {
                Point3::new(
                    if i & 1 == 0 { -h.x } else { h.x },
                    if i & 2 == 0 { -h.y } else { h.y },
                    if i & 4 == 0 { -h.z } else { h.z },
                )
            });
            far(&mut corners)
        }
        TypedShape::Capsule(c) => far(&mut [c.segment.a, c.segment.b].into_iter()) + c.radius,
        TypedShape::Cylinder(c) => {
            // The farthest point lies on a rim circle (centre k, unit normal n, radius r):
            // exactly sqrt(|k∥|² + (|k⊥| + r)²), k split along and across n.
            let n = pose.rotation * nalgebra::Vector3::y();
            [-c.half_height, c.half_height]
                .map(|y| {
                    let k = (pose * Point3::new(0.0, y, 0.0)).coords;
                    let along = k.dot(&n);
                    let across = (k - n * along).norm();
                    (along * along + (across + c.radius).powi(2)).sqrt()
                })
                .into_iter()
                .fold(0.0, f64::max)
        }
        TypedShape::ConvexPolyhedron(p) => far(&mut p.points().iter().copied()),
        _ => {
            let a = shape.compute_aabb(pose);
            let m = a.mins.coords.abs().sup(&a.maxs.coords.abs());
            m.norm()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id() -> Isometry3<f64> {
        Isometry3::identity()
    }

    #[test]
    fn mochi_conventions_stand_on_the_floor_and_urdf_ones_are_centred() {
        let b = Solid::mochi_box(2.0, 1.0, 0.5, id(), "box").unwrap();
        let a = b.local_aabb();
        assert!((a.mins.z - 0.0).abs() < 1e-12 && (a.maxs.z - 0.5).abs() < 1e-12, "{a:?}");
        assert!((a.mins.x + 1.0).abs() < 1e-12 && (a.maxs.y - 0.5).abs() < 1e-12, "{a:?}");
        let c = Solid::mochi_cylinder(0.1, 0.4, id(), "cyl").unwrap();
        let a = c.local_aabb();
        assert!(a.mins.z.abs() < 1e-12 && (a.maxs.z - 0.4).abs() < 1e-12 && (a.maxs.x - 0.1).abs() < 1e-12, "{a:?}");
        let c = Solid::mochi_capsule(0.1, 0.4, id(), "cap").unwrap();
        let a = c.local_aabb();
        assert!(a.mins.z.abs() < 1e-12 && (a.maxs.z - 0.4).abs() < 1e-12, "{a:?}");
        let c = Solid::urdf_cylinder(0.1, 0.4, id(), "ucyl").unwrap();
        let a = c.local_aabb();
        assert!((a.mins.z + 0.2).abs() < 1e-12 && (a.maxs.z - 0.2).abs() < 1e-12, "{a:?}");
        let c = Solid::urdf_capsule(0.1, 0.4, id(), "ucap").unwrap();
        let a = c.local_aabb();
        assert!((a.mins.z + 0.3).abs() < 1e-12 && (a.maxs.z - 0.3).abs() < 1e-12, "{a:?}");
        let b = Solid::urdf_box([2.0, 1.0, 0.5], id(), "ubox").unwrap();
        assert!((b.local_aabb().mins.z + 0.25).abs() < 1e-12);
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert!(Solid::mochi_box(0.0, 1.0, 1.0, id(), "b").is_err());
        assert!(Solid::sphere(-1.0, id(), "s").is_err());
        assert!(Solid::mochi_cylinder(f64::NAN, 1.0, id(), "c").is_err());
        assert!(Solid::urdf_cylinder(1.0, f64::INFINITY, id(), "c").is_err());
        assert!(Solid::mochi_capsule(0.3, 0.5, id(), "c").is_err());
        let e = Solid::mochi_box(1.0, -2.0, 1.0, id(), "b").unwrap_err();
        assert!(e.message.contains("y length") && e.message.contains("-2"), "{e}");
    }

    /// The z cylinder holds the solid at every turn about z: sampled surface points of a
    /// box off the axis, turned by many angles, are inside it (parry's point test).
    #[test]
    fn z_cylinder_holds_every_turn() {
        let place = Isometry3::new(Vector3::new(0.3, -0.2, 0.1), Vector3::new(0.0, 0.0, 0.4));
        let s = Solid::mochi_box(0.14, 0.18, 0.2, place, "rover").unwrap();
        let c = s.z_cylinder();
        for k in 0..64 {
            let turn = Isometry3::rotation(Vector3::new(0.0, 0.0, k as f64 * 0.1));
            for x in [-0.07, 0.07] {
                for y in [-0.09, 0.09] {
                    for z in [0.0, 0.2] {
                        // The box's corner in its own frame, placed and turned.
                        let p = turn * s.pose * Point3::new(x, y, z - 0.1);
                        let inside = c.shape.contains_point(&c.pose, &p);
                        assert!(inside, "corner {p:?} at turn {k} outside the cylinder");
                    }
                }
            }
        }
        // Not absurdly large: by the triangle inequality every corner of the turned box's
        // axis-aligned box is within |(0.3, -0.2)| + 0.149 = 0.51 of the axis, so a point
        // 0.52 from it (at mid height) is outside.
        let out = Point3::new(0.52, 0.0, 0.2);
        assert!(!c.shape.contains_point(&c.pose, &out), "the cylinder is too wide");
    }

    /// The bounding radius bounds every point: checked on sampled surface points of each
    /// kind of shape, placed off the origin and turned.
    #[test]
    fn bounding_radius_bounds_every_point() {
        let place = Isometry3::new(Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.4, 0.7, -1.1));
        let solids = [
            Solid::mochi_box(0.2, 0.4, 0.6, place, "b").unwrap(),
            Solid::sphere(0.3, place, "s").unwrap(),
            Solid::mochi_cylinder(0.1, 0.5, place, "c").unwrap(),
            Solid::mochi_capsule(0.1, 0.5, place, "k").unwrap(),
            Solid::urdf_cylinder(0.2, 0.3, place, "uc").unwrap(),
        ];
        for s in &solids {
            let r = s.bounding_radius();
            // Support points in many directions are points of the solid, the farthest ones.
            let mut best: f64 = 0.0;
            for i in 0..40 {
                for j in 0..20 {
                    let (th, ph) = (i as f64 * 0.157, j as f64 * 0.157);
                    let dir = Vector3::new(ph.sin() * th.cos(), ph.sin() * th.sin(), ph.cos());
                    let local_dir = s.pose.inverse_transform_vector(&dir);
                    let p = s.pose * s.shape.as_support_map().unwrap().local_support_point(&local_dir);
                    best = best.max(p.coords.norm());
                }
            }
            assert!(best <= r + 1e-12, "{}: a point at {best} beyond the radius {r}", s.name);
            assert!(best >= r * 0.9, "{}: the radius {r} is loose (farthest sampled point {best})", s.name);
        }
    }
}
