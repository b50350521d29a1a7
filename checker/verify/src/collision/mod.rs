//! The checks' collision questions posed to the geometric search: those whose bodies the
//! SMT solver cannot represent (a URDF robot, a mesh, a participant mounted on a moving
//! carrier) are decided by branch and bound over boxes of configurations
//! ([`crate::geometry::search::bnb`]), with Z3 asked only for witnesses, through
//! `smt::goals::geo` ([`crate::smt::goals::geo::exists`], `witness`, `assignments`).
//!
//! A configuration `q` holds each motion's clock and the state variables the bodies are
//! placed by (a cart's `x` and heading, a robot's joints, its carrier's state). A box of
//! configurations is
//! - **infeasible** when some guarantee, invariant or the context cannot hold anywhere in
//!   it (three-valued interval truth, [`crate::bounds::truth`]), or
//! - **apart** when parry's certified distance between the two sides placed at the box's
//!   centre exceeds how far any of their points can move within the box (the pose
//!   chains' bounds, [`crate::geometry::placement`], and forward kinematics' displacement
//!   bounds, [`crate::geometry::Robot::displacement_bound`]);
//!
//! otherwise it is split. A box at the resolution where the centre's solids touch becomes
//! a counterexample only once Z3 finds a configuration in it that satisfies every
//! constraint exactly and parry confirms the contact there; anything else is unknown,
//! never apart. ARCHITECTURE.md ("Geometric decision procedure") has the argument.

mod affine;
mod contract;
mod earliest;
mod place;
mod pose;
pub(crate) mod predicate;
mod scene;
mod squares;

use crate::bounds::truth::truth;
use crate::bounds::{self, Interval};
use crate::diag::{Assignment, Overlap};
use crate::geometry::placement::{chain_motion_bound, ArgBounds, FrameBound};
use crate::geometry::search::bnb::{self, Bound, Closest, Feasible, Focus, Options, QBox, Scene};
use crate::geometry::{self, Pose3};
use crate::hir::body::Pose;
use crate::hir::{Expr, PrimApp, Program, RoleId, Slot, Var};
use crate::obligation::{Goal, Obligation};
use crate::smt::goals::geo::{self as ask, Configs, Exists};
use crate::smt::goals::Part;
use crate::space::world::{Piece, World};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// A robot's link poses at a box's centre and its links' displacement bounds over it.
type Kinematics = (Vec<Pose3>, Vec<f64>);

/// What the procedure found.
pub(crate) enum GeoAnswer {
    Apart,
    /// A configuration satisfying every constraint (a Z3 model) where the sides touch.
    Contact {
        values: Vec<Assignment>,
        overlap: Overlap,
    },
    Unknown(String),
}

/// Whether `part` of `ob` is the geometric procedure's: some body in it has no predicate
/// (a URDF or a mesh), or a participant in it rides on another.
pub(crate) fn applies(prog: &Program, ob: &Obligation, part: &Part) -> bool {
    let Some(world) = crate::space::world::of(prog) else { return false };
    // A geometric footprint turned by a variable (a heading): its predicate has the
    // cosine and sine of a state variable, which Z3 decides only partially.
    let turns = |pieces: &[Piece]| {
        pieces.iter().any(|p| {
            p.place.as_ref().is_some_and(|pose| {
                pose.args[3..].iter().any(|a| crate::hir::expr::mentions(a, &|v| !matches!(v, Var::Const(_))))
            })
        })
    };
    let run = |r: RoleId, app: &PrimApp| {
        let prim = prog.prim(app.prim);
        let pieces = world.prims.get(app.prim.idx()).and_then(|p| p.as_deref());
        (prim.footprint.predicate().is_none() && pieces.is_some())
            || pieces.is_some_and(turns)
            || prog.role(r).mounted_on.is_some()
    };
    match (&ob.goal, part) {
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => [i, j].iter().any(|k| run(parts[**k].0, &parts[**k].1)),
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => {
            run(parts[*i].0, &parts[*i].1)
                || prog.obstacles.get(*o).is_some_and(|x| crate::space::region::obstacle_region(prog, x).is_none())
        }
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            [(a, ra), (b, rb)].iter().any(|(s, r)| sides[**s].runs.get(**r).is_some_and(|x| run(x.role, &x.app)))
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => [r, s].iter().any(|k| {
            let (role, _) = &firsts[**k];
            prog.role(*role).mounted_on.is_some()
                || world.kinds.get(prog.role(*role).kind.idx()).is_some_and(|p| World::needs_solids(p))
        }),
        _ => false,
    }
}

/// Decides `part` of `ob` geometrically, within `limit`.
pub(crate) fn decide(prog: &Program, ob: &Obligation, part: &Part, limit: Duration) -> GeoAnswer {
    match question(prog, ob, part) {
        Ok(Some(geo)) => geo.solve(limit),
        // A mounted robot and its carrier are attached at the mount, like two links of
        // one robot: their mutual clearance is not a question of the protocol.
        Ok(None) => GeoAnswer::Apart,
        Err(why) => GeoAnswer::Unknown(why),
    }
}

/// The scene of `part` of `ob`: `None` when its two participants are attached (a mounted
/// robot and its carrier).
fn question<'a>(prog: &'a Program, ob: &'a Obligation, part: &Part) -> Result<Option<Geo<'a>>, String> {
    let Some(world) = crate::space::world::of(prog) else { return Err("no geometry was built".into()) };
    let built = match (&ob.goal, part) {
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => {
            let (a, b) = (parts[*i].0, parts[*j].0);
            if attached(prog, a, b) {
                return Ok(None);
            }
            let mut runs = vec![run(&parts[*i], &ob.hyps, 0), run(&parts[*j], &ob.hyps, 0)];
            runs.extend(carrier_runs(prog, parts, &[a, b], &ob.hyps));
            Geo::new(prog, world, ob, runs, [Who::Run(0), Who::Run(1)], Mode::Footprints)
        }
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => {
            let mut runs = vec![run(&parts[*i], &ob.hyps, 0)];
            runs.extend(carrier_runs(prog, parts, &[parts[*i].0], &ob.hyps));
            Geo::new(prog, world, ob, runs, [Who::Run(0), Who::Obstacle(*o)], Mode::Footprints)
        }
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let (x, y) = (&sides[*a].runs[*ra], &sides[*b].runs[*rb]);
            let runs = vec![
                Run { role: x.role, app: x.app.clone(), hyps: x.hyps.clone(), clock: 0 },
                Run { role: y.role, app: y.app.clone(), hyps: y.hyps.clone(), clock: 1 },
            ];
            Geo::new(prog, world, ob, runs, [Who::Run(0), Who::Run(1)], Mode::Footprints)
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => {
            // [T-SESS] between a mounted robot and its carrier: attached, as above.
            if attached(prog, firsts[*r].0, firsts[*s].0) {
                return Ok(None);
            }
            let first = |k: usize| firsts[k].1.first().cloned();
            let (Some(ar), Some(as_)) = (first(*r), first(*s)) else {
                return Err("a participant with no first motion".into());
            };
            let runs = vec![
                Run { role: firsts[*r].0, app: ar, hyps: ob.hyps.clone(), clock: 0 },
                Run { role: firsts[*s].0, app: as_, hyps: ob.hyps.clone(), clock: 0 },
            ];
            Geo::new(prog, world, ob, runs, [Who::Run(0), Who::Run(1)], Mode::Initial)
        }
        _ => return Err("not a collision question".into()),
    };
    built.map(Some)
}

/// A counterexample of the geometric procedure placed again ([`replay_contact`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactReplay {
    /// The two sides' distance at the configuration, by parry, on a mesh's own triangles
    /// where its hull is touched (as the search confirms a contact): at most 0 when they
    /// touch.
    pub distance: f64,
    /// How far the point shown lies from each side (0 inside one of its solids; a mesh is
    /// measured by its convex hull, which holds it).
    pub point_to: [f64; 2],
    /// A guarantee, an invariant or (at the start) the context is false at the
    /// configuration, by outward-rounded interval truth at that one point.
    pub infeasible: bool,
}

/// How far from a side the point of a contact may lie and still count as on it (m): parry
/// computes in f64, and the point shown is one the search found on both sides at 1e-9 m
/// ([`Scene::contact_point`]).
pub const POINT_TOLERANCE: f64 = 1e-6;

/// How far from each side the point a contact is shown at may lie, by the search's own
/// measure ([`Scene::contact_point`]): a thousandth of the replay's tolerance.
const SHARED_POINT: f64 = 1e-9;

impl ContactReplay {
    /// The claim of a contact: the configuration is one the contracts allow, the two sides
    /// touch there, and the point shown lies on both.
    pub fn falsifies(&self) -> bool {
        !self.infeasible && self.distance <= 0.0 && self.point_to.iter().all(|d| *d <= POINT_TOLERANCE)
    }
}

/// Replays a counterexample of the geometric procedure to `part` of `ob`: each body or
/// footprint of the question placed at the configuration the counterexample shows (`value`
/// gives a value by the name the report shows: `Cart.x(t)`, `Cart.x` at the start, `Cart.x(t1)`
/// for a side of `*`, `time`, `time 1`), and the claim evaluated: the sides' distance there,
/// the point's distance from each, and whether the configuration is allowed. An `Err` when the
/// question has no scene (not a geometric question, attached participants) or a value the
/// configuration needs is missing.
pub fn replay_contact(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    value: &dyn Fn(&str) -> Option<f64>,
    point: [f64; 3],
) -> Result<ContactReplay, String> {
    let _consts = bounds::ConstCache::new();
    let geo = question(prog, ob, part)?.ok_or("the two participants are attached: no contact to replay")?;
    let q: Vec<f64> = geo
        .dims
        .iter()
        .map(|d| {
            geo.dim_value(*d, value).ok_or_else(|| format!("the counterexample gives no value of {}", geo.dim_name(*d)))
        })
        .collect::<Result<_, _>>()?;
    let infeasible = matches!(geo.feasible(&q, &q), Feasible::No);
    let at = geo.distance(&q);
    let point_to = [0, 1].map(|side| geo.point_distance(side, &q, point));
    Ok(ContactReplay { distance: at.distance, point_to, infeasible })
}

/// Whether one of `a`, `b` rides (directly or through other carriers) on the other.
fn attached(prog: &Program, a: RoleId, b: RoleId) -> bool {
    prog.carriers(a).iter().any(|m| m.carrier == b) || prog.carriers(b).iter().any(|m| m.carrier == a)
}

/// The parts of the same joint motion that carry one of `roles`: their guarantees say
/// where the carriers are while it runs (on the same clock).
fn carrier_runs(prog: &Program, parts: &[(RoleId, PrimApp)], roles: &[RoleId], hyps: &[Expr]) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for r in roles {
        for m in prog.carriers(*r) {
            if roles.contains(&m.carrier) || out.iter().any(|x| x.role == m.carrier) {
                continue;
            }
            if let Some(p) = parts.iter().find(|(role, _)| *role == m.carrier) {
                out.push(run(p, hyps, 0));
            }
        }
    }
    out
}

fn run(p: &(RoleId, PrimApp), hyps: &[Expr], clock: usize) -> Run {
    Run { role: p.0, app: p.1.clone(), hyps: hyps.to_vec(), clock }
}

/// A participant in the question: running `app` from the context `hyps` on clock `clock`,
/// or (at the start, [T-SESS]) standing in a state `hyps` allows.
pub(crate) struct Run {
    pub role: RoleId,
    pub app: PrimApp,
    pub hyps: Vec<Expr>,
    pub clock: usize,
}

/// What is placed: the primitives' footprints while they run, the robots' bodies at the
/// start ([T-SESS]), or the robots' bodies while they run (the clearance report).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Footprints,
    Initial,
    Bodies,
}

#[derive(Clone, Copy)]
enum Who {
    Run(usize),
    Obstacle(usize),
}

/// A dimension of the configuration space.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Dim {
    Clock(usize),
    Now(RoleId, Slot),
}

/// One solid of a side, with who places it.
struct Placed<'a> {
    piece: &'a Piece,
    /// The participant whose frame it is in (`None`: an obstacle).
    role: Option<RoleId>,
    /// The run whose variables its pose reads (a geometric footprint's pose may read
    /// `old(x)`, parameters and `clock`).
    run: Option<usize>,
    /// An obstacle's `at:`.
    at: Option<&'a Pose>,
    /// The obstacle, by index.
    obstacle: Option<usize>,
    /// The solid's stand-in when its own frame only turns about z (`pose(x, y, z, 0, 0,
    /// yaw)` with no link after it): [`geometry::Solid::z_cylinder`], which every heading
    /// leaves in place ([`Geo::bound`]).
    turned: Option<geometry::Solid>,
}

/// Whether a piece's own frame turns about z only: its pose's roll and pitch are exactly 0
/// (constants) and no URDF link comes after it.
fn turns_about_z(prog: &Program, piece: &Piece) -> bool {
    let Some(pose) = &piece.place else { return false };
    piece.link.is_none()
        && pose.args[3..5].iter().all(|e| {
            !crate::hir::expr::mentions(e, &|v| !matches!(v, Var::Const(_)))
                && bounds::eval(prog, e, &bounds::closed).is_some_and(|iv| iv.is_exactly(0.0))
        })
}

/// A solid placed at a box's centre: its world pose, its owner frame's, and how far its
/// points move over the box; for a solid with a stand-in, how far the stand-in's points
/// move (its frame's turn about z left out: the stand-in does not change under it).
struct At {
    pose: Pose3,
    owner: Pose3,
    motion: f64,
    turned_motion: Option<f64>,
}

struct Geo<'a> {
    prog: &'a Program,
    ob: &'a Obligation,
    runs: Vec<Run>,
    dims: Vec<Dim>,
    root: QBox,
    /// The context's ranges of the start state and values, per run.
    shared: Vec<HashMap<Var, Interval>>,
    /// Per run: the ranges its guarantee and invariant give its own variables.
    own: Vec<HashMap<Var, Interval>>,
    /// Per run: its arguments' ranges.
    params: Vec<Vec<Option<Interval>>>,
    /// Per participant placed only as a carrier: its invariant's ranges.
    carrier: HashMap<RoleId, HashMap<Var, Interval>>,
    sides: [Vec<Placed<'a>>; 2],
    /// [T-SESS]: the state is the start state.
    initial: bool,
    /// The clearance report (`Mode::Bodies`): every box's bound is made as tight as the
    /// stand-ins allow, not only the bounds that fail to prove a box apart.
    tight: bool,
    /// The last box contracted and its result: the search asks `feasible` and then
    /// `motion_bound` of the same box.
    contracted: std::cell::RefCell<Option<Contracted>>,
    /// Per run, its contraction compiled (empty at the start state, [T-SESS]).
    contractions: Vec<contract::RunContraction>,
    scratch: std::cell::RefCell<bounds::compiled::Scratch>,
    /// Pose frames compiled on first use, by (the pose, whose frame, which run).
    poses: std::cell::RefCell<PoseCache>,
    /// Each participant's `at:` frame (constant), on first use.
    at_poses: std::cell::RefCell<rustc_hash::FxHashMap<RoleId, Option<(Pose3, FrameBound)>>>,
    pose_stack: std::cell::RefCell<Vec<Option<Interval>>>,
}

type PoseCache = rustc_hash::FxHashMap<(*const Pose, Option<RoleId>, usize), pose::CompiledPose>;

/// A box `(lo, hi)` and its contraction (`None`: empty).
type Contracted = ((Vec<f64>, Vec<f64>), Option<(Vec<f64>, Vec<f64>)>);

/// The least distance between two participants (or a participant and an obstacle) over
/// the joint motions where they move together, from `--clearance`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PairClearance {
    pub a: String,
    pub b: String,
    /// Certified: their bodies are never closer (m).
    pub lower: f64,
    /// Attained at `time` of the motion at `span`, with the two closest points (m).
    pub upper: f64,
    pub time: Option<f64>,
    pub points: Option<[[f64; 3]; 2]>,
    #[serde(skip)]
    pub span: crate::source::Span,
    /// Why the bounds stay apart, when they do (a budget, boxes at the resolution).
    pub note: Option<String>,
}

/// For each pair of participants that move together in a joint motion with bodies (and
/// each participant against each obstacle), the least distance between their bodies over
/// every such motion, at every time and state the contracts allow: a certified lower
/// bound and a configuration attaining an upper bound within `tolerance` (m).
pub fn clearances(prog: &Program, obligations: &[Obligation], tolerance: f64, limit: Duration) -> Vec<PairClearance> {
    let Some(world) = crate::space::world::of(prog) else { return Vec::new() };
    let _consts = bounds::ConstCache::new();
    let mut best: Vec<PairClearance> = Vec::new();
    for ob in obligations {
        let Goal::Compatible { parts } = &ob.goal else { continue };
        let mut questions: Vec<(Vec<Run>, [Who; 2], String, String)> = Vec::new();
        let has_body = |r: RoleId| !world.kinds[prog.role(r).kind.idx()].is_empty();
        for i in 0..parts.len() {
            let a = parts[i].0;
            if !has_body(a) {
                continue;
            }
            for j in i + 1..parts.len() {
                let b = parts[j].0;
                if !has_body(b) || attached(prog, a, b) {
                    continue;
                }
                let mut runs = vec![run(&parts[i], &ob.hyps, 0), run(&parts[j], &ob.hyps, 0)];
                runs.extend(carrier_runs(prog, parts, &[a, b], &ob.hyps));
                questions.push((runs, [Who::Run(0), Who::Run(1)], prog.role_name(a).into(), prog.role_name(b).into()));
            }
            for (o, obstacle) in prog.obstacles.iter().enumerate() {
                let mut runs = vec![run(&parts[i], &ob.hyps, 0)];
                runs.extend(carrier_runs(prog, parts, &[a], &ob.hyps));
                questions.push((
                    runs,
                    [Who::Run(0), Who::Obstacle(o)],
                    prog.role_name(a).into(),
                    obstacle.name.clone(),
                ));
            }
        }
        for (runs, who, a, b) in questions {
            let found = match Geo::new(prog, world, ob, runs, who, Mode::Bodies) {
                Ok(geo) => {
                    let n = geo.dims.len();
                    let res: Vec<f64> = (0..n).map(|i| ((geo.root.hi[i] - geo.root.lo[i]) * 1e-4).max(1e-6)).collect();
                    let mut opts = Options::new(res);
                    opts.deadline = Some(Instant::now() + limit);
                    opts.max_nodes = 400_000;
                    let c = bnb::min_distance(&geo, &geo.root, tolerance, &opts);
                    let time =
                        c.at_q.as_ref().and_then(|q| geo.dims.iter().position(|d| *d == Dim::Clock(0)).map(|i| q[i]));
                    PairClearance {
                        a: a.clone(),
                        b: b.clone(),
                        lower: c.lower,
                        upper: c.upper,
                        time,
                        points: c.points,
                        span: ob.span,
                        note: (!c.complete).then(|| "the bounds did not meet within the budget".to_string()),
                    }
                }
                Err(why) => PairClearance {
                    a: a.clone(),
                    b: b.clone(),
                    lower: f64::NEG_INFINITY,
                    upper: f64::INFINITY,
                    time: None,
                    points: None,
                    span: ob.span,
                    note: Some(why),
                },
            };
            match best.iter_mut().find(|p| p.a == found.a && p.b == found.b) {
                Some(p) if found.lower < p.lower || (found.lower == p.lower && found.upper < p.upper) => *p = found,
                Some(_) => {}
                None => best.push(found),
            }
        }
    }
    best
}

#[cfg(test)]
mod tests;
