//! The solids of a program (the geometry stage's second half): every body of a robot
//! kind, of a geometric footprint and of an obstacle, as the geometry engine's solids,
//! each with how it is placed. URDF files and meshes are read here, through the byte
//! loader the driver passes in; a URDF's movable joints are matched with the kind's state
//! variables of the same names (E0513).
//!
//! A [`Piece`] is one convex solid and the frames that place it in its owner's frame:
//! the part's `at pose(...)` (expressions over the owner's variables, evaluated by the
//! geometric procedure at each configuration) and, for a URDF link, the link's pose by
//! forward kinematics of the joint variables.

use crate::bounds;
use crate::diag::{Code, Diagnostic};
use crate::geometry::{self, Robot, Solid};
use crate::hir::body::{Body, Pose, Shape};
use crate::hir::{KindId, Program, Slot};
use crate::source::{SourceDb, Span};
use crate::syntax::ByteLoader;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A URDF link a piece belongs to: the robot, the link, and per joint variable of the
/// robot the kind's state slot that drives it.
#[derive(Clone)]
pub struct Link {
    pub robot: Arc<Robot>,
    pub link: usize,
    pub joints: Arc<Vec<Slot>>,
}

/// One solid of a body and how it is placed in its owner's frame.
#[derive(Clone)]
pub struct Piece {
    pub solid: Arc<Solid>,
    /// The part's `at pose(...)`, `None` for the owner's frame.
    pub place: Option<Pose>,
    /// For a URDF part: the link whose frame the solid is in.
    pub link: Option<Link>,
}

/// Every body of the program as solids.
#[derive(Clone, Default)]
pub struct World {
    /// Per robot kind (by `KindId`): its body (empty for a kind with none).
    pub kinds: Vec<Vec<Piece>>,
    /// Per primitive: its geometric footprint, when it has one.
    pub prims: Vec<Option<Vec<Piece>>>,
    /// Per obstacle: its body (placed by the obstacle's `at:`, not included here).
    pub obstacles: Vec<Vec<Piece>>,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = |v: &[Piece]| v.len();
        f.debug_struct("World")
            .field("kinds", &self.kinds.iter().map(|k| n(k)).collect::<Vec<_>>())
            .field("prims", &self.prims.iter().map(|p| p.as_deref().map(n)).collect::<Vec<_>>())
            .field("obstacles", &self.obstacles.iter().map(|o| n(o)).collect::<Vec<_>>())
            .finish()
    }
}

impl World {
    /// Whether some piece is a URDF link or a mesh hull: no predicate exists for the body,
    /// only solids.
    pub fn needs_solids(pieces: &[Piece]) -> bool {
        pieces.iter().any(|p| p.link.is_some() || p.solid.is_hull)
    }
}

/// The solids of `prog`, when the geometry stage has built them (`Program::world`).
pub fn of(prog: &Program) -> Option<&World> {
    prog.world.as_deref().and_then(|w| w.downcast_ref::<World>())
}

/// [`of`], shared.
pub fn shared(prog: &Program) -> Option<Arc<World>> {
    prog.world.clone().and_then(|w| w.downcast::<World>().ok())
}

/// Builds the world of `prog`, reading URDF and mesh files through `read` (URDF texts
/// are added to `db`, so diagnostics can point into them).
pub fn build(prog: &Program, db: &mut SourceDb, read: &mut ByteLoader<'_>) -> (World, Vec<Diagnostic>) {
    let mut b = Builder { prog, db, read, diags: Vec::new(), robots: HashMap::new(), meshes: HashMap::new() };
    let mut world = World::default();
    for (k, kind) in prog.kinds.iter().enumerate() {
        let pieces = match &kind.body {
            Some(body) => b.body(body, Some(KindId(k as u32))),
            None => Vec::new(),
        };
        world.kinds.push(pieces);
    }
    for prim in &prog.prims {
        world.prims.push(prim.footprint.body().map(|body| b.body(body, Some(prim.kind))));
    }
    for o in &prog.obstacles {
        world.obstacles.push(b.body(&o.body, None));
    }
    (world, b.diags)
}

/// A URDF read for one kind: the robot and its joint variables' state slots.
type LoadedUrdf = (Arc<Robot>, Arc<Vec<Slot>>);

struct Builder<'a, 'l> {
    prog: &'a Program,
    db: &'a mut SourceDb,
    read: &'a mut ByteLoader<'l>,
    diags: Vec<Diagnostic>,
    /// URDFs already read, by (path, kind): the joint slots depend on the kind.
    robots: HashMap<(String, Option<KindId>), Option<LoadedUrdf>>,
    meshes: HashMap<String, Option<Arc<Solid>>>,
}

impl Builder<'_, '_> {
    fn body(&mut self, body: &Body, kind: Option<KindId>) -> Vec<Piece> {
        let mut out = Vec::new();
        for part in &body.parts {
            let size = |e: &crate::hir::Expr| bounds::eval(self.prog, e, &bounds::closed).map_or(f64::NAN, |i| i.hi);
            let id = geometry::identity();
            // Sizes are rounded up (the solid encloses the body it stands for); the
            // geometry stage checked they are positive constants (E0511).
            let solid = match &part.shape {
                Shape::Box([x, y, z]) => Solid::mochi_box(size(x), size(y), size(z), id, "box"),
                Shape::Sphere(r) => Solid::sphere(size(r), id, "sphere"),
                Shape::Cylinder(r, h) => Solid::mochi_cylinder(size(r), size(h), id, "cylinder"),
                Shape::Capsule(r, h) => Solid::mochi_capsule(size(r), size(h), id, "capsule"),
                Shape::Mesh { path, span } => {
                    if let Some(s) = self.mesh(path, *span) {
                        out.push(Piece { solid: s, place: part.place.clone(), link: None });
                    }
                    continue;
                }
                Shape::Urdf { path, span } => {
                    if let Some((robot, joints)) = self.urdf(path, *span, kind) {
                        for (l, link) in robot.links.iter().enumerate() {
                            for s in &link.solids {
                                out.push(Piece {
                                    solid: Arc::new(s.clone()),
                                    place: part.place.clone(),
                                    link: Some(Link { robot: robot.clone(), link: l, joints: joints.clone() }),
                                });
                            }
                        }
                    }
                    continue;
                }
            };
            match solid {
                Ok(s) => out.push(Piece { solid: Arc::new(s), place: part.place.clone(), link: None }),
                Err(e) => self.diags.push(
                    Diagnostic::error(Code::ShapeInvalid, part.span, format!("this shape cannot be built: {e}"))
                        .with_help("give the shape positive, finite sizes"),
                ),
            }
        }
        out
    }

    fn mesh(&mut self, path: &str, span: Span) -> Option<Arc<Solid>> {
        if let Some(m) = self.meshes.get(path) {
            return m.clone();
        }
        let made = (|| {
            let format = geometry::mesh::format_of(path).map_err(|e| (Code::MeshUnreadable, e.to_string()))?;
            let bytes = (self.read)(Path::new(path)).map_err(|e| (Code::GeometryFileMissing, e.to_string()))?;
            let data = geometry::mesh::parse(&bytes, format).map_err(|e| (Code::MeshUnreadable, e.to_string()))?;
            let name = Path::new(path).file_name().map_or(path.to_string(), |n| n.to_string_lossy().into_owned());
            geometry::mesh::hull_solid(&data, [1.0; 3], geometry::identity(), name)
                .ok_or((Code::MeshUnreadable, "no convex hull can be built of its vertices".to_string()))
        })();
        let solid = match made {
            Ok(s) => Some(Arc::new(s)),
            Err((code, why)) => {
                self.diags.push(
                    Diagnostic::error(code, span, format!("the mesh `{path}` cannot be used: {why}"))
                        .with_help("check the path (relative to this file) and that the file is an STL or OBJ mesh"),
                );
                None
            }
        };
        self.meshes.insert(path.to_string(), solid.clone());
        solid
    }

    fn urdf(&mut self, path: &str, span: Span, kind: Option<KindId>) -> Option<LoadedUrdf> {
        let key = (path.to_string(), kind);
        if let Some(r) = self.robots.get(&key) {
            return r.clone();
        }
        let loaded = match geometry::load_robot(self.db, Path::new(path), span, self.read) {
            Ok(r) => Some(r),
            Err(ds) => {
                self.diags.extend(ds);
                None
            }
        };
        let made = loaded.and_then(|robot| {
            let joints = self.joint_slots(&robot, span, kind)?;
            Some((Arc::new(robot), Arc::new(joints)))
        });
        self.robots.insert(key, made.clone());
        made
    }

    /// Per joint variable of `robot`, the kind's real state variable of the same name;
    /// an obstacle's URDF (no kind) has none and stands at its joints' zero.
    fn joint_slots(&mut self, robot: &Robot, span: Span, kind: Option<KindId>) -> Option<Vec<Slot>> {
        let names = robot.joint_names();
        // An obstacle reads constants only: every joint stands at 0 (LANGUAGE.md).
        let Some(k) = kind else { return Some(Vec::new()) };
        let kind = self.prog.kind(k);
        let mut slots = Vec::new();
        let mut missing = Vec::new();
        for n in &names {
            match kind.state.iter().position(|(s, sort)| s == n && sort.is_numeric()) {
                Some(i) => slots.push(Slot::State(i)),
                None => missing.push(n.to_string()),
            }
        }
        if missing.is_empty() {
            return Some(slots);
        }
        self.diags.push(
            Diagnostic::error(
                Code::JointWithoutState,
                span,
                format!(
                    "the URDF's movable joint{} {} {} no state variable of robot `{}`",
                    if missing.len() > 1 { "s" } else { "" },
                    missing.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", "),
                    if missing.len() > 1 { "have" } else { "has" },
                    kind.name
                ),
            )
            .with_help(format!(
                "declare one real state variable per movable joint, named as in the URDF: `state {}: real;`",
                missing.join(": real, ")
            )),
        );
        None
    }
}

/// The position limits of a kind's URDF joints (`<limit lower upper>` of each revolute
/// and prismatic joint driven by a state variable), added to the kind's invariant as
/// `lower <= J && J <= upper` (Sec 3.1: every state of the robot satisfies its invariant;
/// the robot description says the joint stays within these). Each bound is the double the
/// URDF's decimal was read as, moved one ulp outward, so the range holds the decimal
/// written. A joint whose limits are not a range (`lower >= upper`: the URDF default of
/// 0 and 0 when `<limit>` gives no position, or infinite values) is left unbounded. A
/// contract that drives a joint past its limit then contradicts the invariant: its
/// motion cannot end (E0408, E0409), or its start is outside it (E0411).
///
/// The velocity limits (`<limit velocity>` of each movable joint driven by a state
/// variable, positive and finite) become the kind's [`crate::hir::RobotKind::speed`]: no
/// motion moves the joint farther from where it started than `velocity * clock` (the
/// bound one ulp outward). A contract whose postcondition needs more than that within its
/// duration cannot end (E0408 where it runs, E0409 at the declaration).
pub fn add_joint_limits(prog: &mut Program) {
    let Some(world) = shared(prog) else { return };
    for (k, pieces) in world.kinds.iter().enumerate() {
        let mut limits: Vec<(Slot, f64, f64)> = Vec::new();
        let mut speeds: Vec<(Slot, f64)> = Vec::new();
        for p in pieces {
            let Some(link) = &p.link else { continue };
            for ((slot, (lo, hi)), v) in
                link.joints.iter().zip(link.robot.joint_limits()).zip(link.robot.joint_velocities())
            {
                if let Some(v) = v {
                    if !speeds.iter().any(|(s, _)| s == slot) {
                        speeds.push((*slot, v.next_up()));
                    }
                }
                if !(lo.is_finite() && hi.is_finite() && lo < hi) || limits.iter().any(|(s, ..)| s == slot) {
                    continue;
                }
                limits.push((*slot, lo.next_down(), hi.next_up()));
            }
        }
        let Some(kind) = prog.kinds.get_mut(k) else { continue };
        if limits.is_empty() && speeds.is_empty() {
            continue;
        }
        // The facts point at the `urdf("...")` they come from.
        let urdf = kind.body.as_ref().and_then(|b| {
            b.parts.iter().find_map(|p| match &p.shape {
                Shape::Urdf { span, .. } => Some(*span),
                _ => None,
            })
        });
        let loc = crate::hir::Loc(urdf.unwrap_or(kind.span));
        use crate::hir::expr::BinOp;
        use crate::hir::{Expr, ExprKind, Sort, Var};
        let bin = |op: BinOp, a: Expr, b: Expr, sort: Sort| Expr {
            kind: ExprKind::Binary(op, Box::new(a), Box::new(b)),
            sort,
            loc,
        };
        let cmp = |a: Expr, b: Expr| bin(BinOp::Le, a, b, Sort::Bool);
        let mut facts = Vec::new();
        for (slot, lo, hi) in limits {
            let Some(sort) = kind.state.get(match slot {
                Slot::State(i) => i,
                _ => continue,
            }) else {
                continue;
            };
            let var = Expr { kind: ExprKind::Var(Var::Own(slot)), sort: sort.1.clone(), loc };
            let (Some(lo), Some(hi)) = (super::literal::exact_double(lo, loc), super::literal::exact_double(hi, loc))
            else {
                continue;
            };
            facts.push(cmp(lo, var.clone()));
            facts.push(cmp(var, hi));
        }
        if !facts.is_empty() {
            let mut all: Vec<Expr> = kind.invariant.take().into_iter().collect();
            all.extend(facts);
            let at = all.first().map_or(loc, |e| e.loc);
            kind.invariant = Some(crate::hir::expr::and_all(all, at));
        }
        // |J - old(J)| <= v * clock, as two linear facts.
        let mut speed = Vec::new();
        for (slot, v) in speeds {
            let Slot::State(i) = slot else { continue };
            let Some((_, sort)) = kind.state.get(i) else { continue };
            if !sort.is_numeric() {
                continue;
            }
            let Some(v) = super::literal::exact_double(v, loc) else { continue };
            let var = Expr { kind: ExprKind::Var(Var::Own(slot)), sort: sort.clone(), loc };
            let old = Expr { kind: ExprKind::Var(Var::Old(i)), sort: sort.clone(), loc };
            let clock = Expr { kind: ExprKind::Var(Var::Clock), sort: Sort::Real, loc };
            let reach = bin(BinOp::Mul, v, clock, Sort::Real);
            speed.push(cmp(bin(BinOp::Sub, var.clone(), old.clone(), sort.clone()), reach.clone()));
            speed.push(cmp(bin(BinOp::Sub, old, var, sort.clone()), reach));
        }
        if !speed.is_empty() {
            kind.speed = Some(crate::hir::expr::and_all(speed, loc));
        }
    }
}
