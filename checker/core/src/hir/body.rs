//! Bodies: the space a robot, a geometric footprint or an obstacle occupies, as a
//! function of state (Sec 3.1's `geom(p)`). A body is a list of parts; each part is a
//! shape placed in its owner's frame by a pose whose arguments may read the owner's
//! state (a cart's box at `pose(x, 0, 0)`, a turret at `pose(0, 0, 0.1, 0, 0, th)`).
//! A URDF part stands for the robot's whole kinematic tree: the geometry stage loads the
//! file and places its links by forward kinematics, the joint variables being the kind's
//! state variables of the same names.
//!
//! Conventions (LANGUAGE.md, Robots): lengths in metres, angles in radians;
//! `box(lx, ly, lz)` is centred on its frame's origin in x and y and stands on z = 0;
//! `sphere(r)` is centred on the origin; `cylinder(r, h)` and `capsule(r, h)` have their
//! axis on z, from z = 0 to z = h (a capsule's segment runs from z = r to z = h - r).

use super::{Expr, RoleId};
use crate::source::Span;

/// `pose(x, y, z, roll, pitch, yaw)`: the rotation is `Rz(yaw) Ry(pitch) Rx(roll)` (as a
/// participant's `at:`), applied before the translation. Omitted arguments are 0.
#[derive(Clone, Debug)]
pub struct Pose {
    /// `[x, y, z, roll, pitch, yaw]`, each a real expression.
    pub args: [Expr; 6],
    pub span: Span,
}

/// One shape of a body.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Full lengths along x, y, z.
    Box([Expr; 3]),
    Sphere(Expr),
    /// Radius, height.
    Cylinder(Expr, Expr),
    /// Radius, overall height (`h >= 2 r`).
    Capsule(Expr, Expr),
    /// A URDF file (path relative to the file that names it, resolved by the loader) and
    /// the span of the string, for diagnostics about the file.
    Urdf {
        path: String,
        span: Span,
    },
    /// A mesh file (STL, OBJ), as the convex hull of its vertices.
    Mesh {
        path: String,
        span: Span,
    },
}

/// A shape placed in its owner's frame.
#[derive(Clone, Debug)]
pub struct BodyPart {
    pub shape: Shape,
    /// `None`: the owner's frame itself.
    pub place: Option<Pose>,
    pub span: Span,
}

/// A body: the union of its parts.
#[derive(Clone, Debug)]
pub struct Body {
    pub parts: Vec<BodyPart>,
    pub span: Span,
}

/// A mount point a robot kind offers (`mount deck: pose(x, 0, 0.1, 0, 0, th);`): a frame
/// placed by the carrier's state, on which another participant can ride.
#[derive(Clone, Debug)]
pub struct Mount {
    pub name: String,
    pub pose: Pose,
    pub span: Span,
}

/// Where a mounted participant rides: its carrier and the carrier kind's mount index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MountedOn {
    pub carrier: RoleId,
    pub mount: usize,
}

/// A static obstacle of a system: a body placed in the world, with no state, no
/// process and no messages. Its expressions read constants only.
#[derive(Clone, Debug)]
pub struct Obstacle {
    pub name: String,
    pub body: Body,
    /// `at: pose(...)`, `None` for the world frame.
    pub pose: Option<Pose>,
    pub span: Span,
}

impl super::Program {
    /// The carriers `r` rides on, innermost first: `[(carrier, mount), (its carrier, mount),
    /// ...]`, empty for a participant placed in the world. Finite: lowering rejects mount
    /// cycles (E0216) and leaves no participant of a cycle mounted, and the walk is bounded
    /// by the number of participants besides.
    pub fn carriers(&self, r: RoleId) -> Vec<MountedOn> {
        let mut out = Vec::new();
        let mut at = r;
        while let Some(m) = self.role(at).mounted_on {
            if out.len() >= self.roles.len() {
                break;
            }
            out.push(m);
            at = m.carrier;
        }
        out
    }

    /// The obstacle called `name`.
    pub fn obstacle_by_name(&self, name: &str) -> Option<&Obstacle> {
        self.obstacles.iter().find(|o| o.name == name)
    }
}
