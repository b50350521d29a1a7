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
//!   it (three-valued interval truth, [`crate::space::truth`]), or
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
mod pose;
mod squares;

use crate::bounds::{self, Interval};
use crate::diag::{Assignment, Overlap};
use crate::geometry::search::bnb::{self, Bound, Closest, Feasible, Focus, Options, QBox, Scene};
use crate::geometry::placement::{chain_motion_bound, ArgBounds, FrameBound};
use crate::geometry::{self, Pose3};
use crate::hir::body::Pose;
use crate::hir::{Expr, PrimApp, Program, RoleId, Slot, Var};
use crate::obligation::{Goal, Obligation};
use crate::smt::goals::geo::{self as ask, Configs, Exists};
use crate::smt::goals::Part;
use crate::space::truth::truth;
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
    let Some(world) = crate::space::world::of(prog) else { return GeoAnswer::Unknown("no geometry was built".into()) };
    let built = match (&ob.goal, part) {
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => {
            let (a, b) = (parts[*i].0, parts[*j].0);
            // A mounted robot and its carrier are attached at the mount, like two links of
            // one robot: their mutual clearance is not a question of the protocol.
            if attached(prog, a, b) {
                return GeoAnswer::Apart;
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
                return GeoAnswer::Apart;
            }
            let first = |k: usize| firsts[k].1.first().cloned();
            let (Some(ar), Some(as_)) = (first(*r), first(*s)) else {
                return GeoAnswer::Unknown("a participant with no first motion".into());
            };
            let runs = vec![
                Run { role: firsts[*r].0, app: ar, hyps: ob.hyps.clone(), clock: 0 },
                Run { role: firsts[*s].0, app: as_, hyps: ob.hyps.clone(), clock: 0 },
            ];
            Geo::new(prog, world, ob, runs, [Who::Run(0), Who::Run(1)], Mode::Initial)
        }
        _ => return GeoAnswer::Unknown("not a collision question".into()),
    };
    let geo = match built {
        Ok(g) => g,
        Err(why) => return GeoAnswer::Unknown(why),
    };
    geo.solve(limit)
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

impl<'a> Geo<'a> {
    fn new(
        prog: &'a Program,
        world: &'a World,
        ob: &'a Obligation,
        runs: Vec<Run>,
        who: [Who; 2],
        mode: Mode,
    ) -> Result<Geo<'a>, String> {
        let initial = mode == Mode::Initial;
        let mut sides: [Vec<Placed<'a>>; 2] = [Vec::new(), Vec::new()];
        for (side, w) in sides.iter_mut().zip(who) {
            match w {
                Who::Run(k) => {
                    let r = &runs[k];
                    let kind = prog.role(r.role).kind;
                    let pieces = if mode != Mode::Footprints {
                        &world.kinds[kind.idx()]
                    } else {
                        match world.prims.get(r.app.prim.idx()).and_then(|p| p.as_ref()) {
                            Some(p) => p,
                            // A predicate footprint of a mounted participant: its body stands
                            // for it only if the predicate is the body (not known): unknown.
                            None => {
                                return Err(format!(
                                    "`{}` of `{}` has a footprint written as a predicate, which the geometric procedure cannot place; write it as `footprint: geometry;` or shapes",
                                    prog.prim(r.app.prim).name,
                                    prog.role_name(r.role)
                                ))
                            }
                        }
                    };
                    let run = (!initial).then_some(k);
                    side.extend(pieces.iter().map(|piece| Placed {
                        piece,
                        role: Some(r.role),
                        run,
                        at: None,
                        obstacle: None,
                        turned: turns_about_z(prog, piece).then(|| piece.solid.z_cylinder()),
                    }));
                }
                Who::Obstacle(o) => {
                    let obstacle = &prog.obstacles[o];
                    side.extend(world.obstacles[o].iter().map(|piece| Placed {
                        piece,
                        role: None,
                        run: None,
                        at: obstacle.pose.as_ref(),
                        obstacle: Some(o),
                        turned: None,
                    }));
                }
            }
            if side.is_empty() {
                return Err("a side with no solid (a body that failed to load, or an empty one)".into());
            }
        }
        // The context's ranges, and each run's own ranges and arguments.
        let mut shared = Vec::new();
        let mut own = Vec::new();
        let mut params = Vec::new();
        for r in &runs {
            let facts: Vec<&Expr> = r.hyps.iter().collect();
            let s = bounds::ranges_from(prog, &facts, &bounds::closed);
            if initial {
                own.push(HashMap::new());
                params.push(Vec::new());
            } else {
                let prim = prog.prim(r.app.prim);
                let lookup = |v: &Var| s.get(v).copied();
                let ps: Vec<Option<Interval>> = r.app.args.iter().map(|a| bounds::eval(prog, a, &lookup)).collect();
                let role = r.role;
                let lift = |v: &Var| -> Option<Interval> {
                    match v {
                        Var::Old(i) => s.get(&Var::Role(role, Slot::State(*i))).copied(),
                        Var::Param(i) => ps.get(*i).copied().flatten(),
                        Var::Clock => Some(Interval::new(0.0, f64::INFINITY)),
                        _ => None,
                    }
                };
                let mut facts: Vec<&Expr> = vec![&prim.guarantee];
                facts.extend(prog.kind(prim.kind).invariant.as_ref());
                own.push(bounds::ranges_from(prog, &facts, &lift));
                params.push(ps);
            }
            shared.push(s);
        }
        let mut geo = Geo {
            prog,
            ob,
            runs,
            dims: Vec::new(),
            root: QBox::new(Vec::new(), Vec::new()),
            shared,
            own,
            params,
            carrier: HashMap::new(),
            sides,
            initial,
            tight: mode == Mode::Bodies,
            contracted: std::cell::RefCell::new(None),
            contractions: Vec::new(),
            scratch: Default::default(),
            poses: Default::default(),
            at_poses: Default::default(),
            pose_stack: Default::default(),
        };
        geo.layout()?;
        if !initial {
            geo.contractions = (0..geo.runs.len()).map(|k| geo.compile_contraction(k)).collect();
        }
        Ok(geo)
    }

    /// The dimensions (clocks, then the state variables the bodies are placed by) and the
    /// root box.
    fn layout(&mut self) -> Result<(), String> {
        let prog = self.prog;
        let clocks = self.runs.iter().map(|r| r.clock).max().map_or(0, |m| m + 1);
        let mut dims: Vec<Dim> = (0..clocks).map(Dim::Clock).collect();
        let add = |d: Dim, dims: &mut Vec<Dim>| {
            if !dims.contains(&d) {
                dims.push(d);
            }
        };
        for side in &self.sides {
            for p in side {
                let Some(role) = p.role else { continue };
                let mut placing = vec![role];
                for m in prog.carriers(role) {
                    let mount = &prog.kind_of(m.carrier).mounts[m.mount];
                    for e in &mount.pose.args {
                        e.visit_vars(&mut |v, _| {
                            if let Var::Own(slot) = v {
                                add(Dim::Now(m.carrier, *slot), &mut dims);
                            }
                        });
                    }
                    placing.push(m.carrier);
                }
                if let Some(pose) = &p.piece.place {
                    for e in &pose.args {
                        e.visit_vars(&mut |v, _| {
                            if let Var::Own(slot) = v {
                                add(Dim::Now(role, *slot), &mut dims);
                            }
                        });
                    }
                }
                if let Some(link) = &p.piece.link {
                    for slot in link.joints.iter() {
                        add(Dim::Now(role, *slot), &mut dims);
                    }
                }
            }
        }
        // Carriers that run nothing here: their state ranges over their invariant.
        for d in &dims {
            if let Dim::Now(r, _) = d {
                if !self.runs.iter().any(|x| x.role == *r) && !self.carrier.contains_key(r) {
                    let inv = prog.kind_of(*r).invariant.as_ref();
                    let facts: Vec<&Expr> = inv.into_iter().collect();
                    self.carrier.insert(*r, bounds::ranges_from(prog, &facts, &bounds::closed));
                }
            }
        }
        self.dims = dims;
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        for d in &self.dims.clone() {
            let iv = match d {
                Dim::Clock(k) => self.clock_range(*k)?,
                Dim::Now(r, slot) => self.state_range(*r, *slot),
            };
            if !iv.is_finite() || iv.lo > iv.hi {
                let what = match d {
                    Dim::Clock(_) => {
                        "the time of a motion whose guarantee reads `clock` and whose duration has no upper end"
                            .to_string()
                    }
                    Dim::Now(r, slot) => {
                        format!("`{}.{}`, which places a body", prog.role_name(*r), prog.kind_of(*r).var(*slot).0)
                    }
                };
                return Err(format!(
                    "{what} is not bounded: the geometric procedure searches a bounded box (give the kind an invariant that bounds it)"
                ));
            }
            lo.push(iv.lo);
            hi.push(iv.hi);
        }
        self.root = QBox::new(lo, hi);
        Ok(())
    }

    /// `[0, T]`: T the least upper end of the durations of the runs on clock `k` (they run
    /// together for one elapsed time); `[0, 0]` when none of their guarantees, invariants
    /// or bodies reads `clock` (every time is then alike) and no duration bounds it.
    fn clock_range(&self, k: usize) -> Result<Interval, String> {
        if self.initial {
            return Ok(Interval::point(0.0));
        }
        let mut hi = f64::INFINITY;
        let mut reads = false;
        for (i, r) in self.runs.iter().enumerate().filter(|(_, r)| r.clock == k) {
            let prim = self.prog.prim(r.app.prim);
            if let Some(h) = &prim.duration.hi {
                let v = bounds::eval(self.prog, h, &|v: &Var| self.var_range(i, r.role, v, None));
                if let Some(v) = v {
                    hi = hi.min(v.hi);
                }
            }
            let clocky = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Clock));
            reads |= clocky(&prim.guarantee)
                || self.prog.kind(prim.kind).invariant.as_ref().is_some_and(clocky)
                || crate::space::world::of(self.prog)
                    .and_then(|w| w.prims.get(r.app.prim.idx()).cloned().flatten())
                    .is_some_and(|ps| {
                        ps.iter().any(|p| p.place.as_ref().is_some_and(|pose| pose.args.iter().any(clocky)))
                    });
        }
        if hi.is_finite() {
            Ok(Interval::new(0.0, hi.max(0.0)))
        } else if reads {
            Ok(Interval::new(0.0, f64::INFINITY))
        } else {
            Ok(Interval::point(0.0))
        }
    }

    fn state_range(&self, r: RoleId, slot: Slot) -> Interval {
        let all = Interval::new(f64::NEG_INFINITY, f64::INFINITY);
        if let Some((k, run)) = self.runs.iter().enumerate().find(|(_, x)| x.role == r) {
            if self.initial {
                return self.shared[k].get(&Var::Role(r, slot)).copied().unwrap_or(all);
            }
            let _ = run;
            let a = self.own[k].get(&Var::Own(slot)).copied();
            return a.unwrap_or(all);
        }
        if self.initial {
            // At the start a carrier is where the context (its `init`) puts it.
            if let Some(iv) = self.shared.first().and_then(|s| s.get(&Var::Role(r, slot)).copied()) {
                return iv;
            }
        }
        self.carrier.get(&r).and_then(|m| m.get(&Var::Own(slot)).copied()).unwrap_or(all)
    }

    /// The range of variable `v` of participant `role`, read in run `run`'s frame (or as a
    /// carrier), with the dimensions taken from `q` (a box) when given.
    fn var_range(&self, run: usize, role: RoleId, v: &Var, q: Option<(&[f64], &[f64])>) -> Option<Interval> {
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let from_q = |i: usize| q.map(|(lo, hi)| Interval::new(lo[i], hi[i]));
        match v {
            Var::Own(slot) => {
                if let Some(i) = dim(Dim::Now(role, *slot)) {
                    if let Some(iv) = from_q(i) {
                        return Some(iv);
                    }
                }
                Some(self.state_range(role, *slot)).filter(|i| i.is_finite())
            }
            Var::Old(i) => self.shared.get(run)?.get(&Var::Role(role, Slot::State(*i))).copied(),
            Var::Param(i) => self.params.get(run)?.get(*i).copied().flatten(),
            Var::Clock => {
                let k = self.runs.get(run)?.clock;
                dim(Dim::Clock(k)).and_then(from_q).or(Some(Interval::new(0.0, f64::INFINITY)))
            }
            Var::Point(_) => None,
            other => self.shared.get(run)?.get(other).copied(),
        }
    }

    /// One pose frame `pose(...)` whose arguments read `role`'s variables (in run `run`'s
    /// frame), over the box `[lo, hi]` with centre `c`: the frame at `c` and its bound.
    fn pose_frame(
        &self,
        role: Option<RoleId>,
        run: usize,
        pose: &Pose,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Option<(Pose3, FrameBound)> {
        let key = (pose as *const Pose, role, run);
        if !self.poses.borrow().contains_key(&key) {
            let compiled = pose::CompiledPose::new(self.prog, pose, &|v: &Var| self.leaf(run, role, v));
            self.poses.borrow_mut().insert(key, compiled);
        }
        let poses = self.poses.borrow();
        poses.get(&key)?.frame(lo, hi, c, &mut self.pose_stack.borrow_mut())
    }

    /// The frames placing `role`'s own frame in the world (outermost first): each
    /// carrier's `at:` and mount, then its own `at:`.
    fn role_chain(&self, role: RoleId, lo: &[f64], hi: &[f64], c: &[f64]) -> Option<Vec<(Pose3, FrameBound)>> {
        let mut out = Vec::new();
        let mounts = self.prog.carriers(role);
        for m in mounts.iter().rev() {
            out.push(self.at_pose(m.carrier)?);
            let mount = &self.prog.kind_of(m.carrier).mounts[m.mount];
            let run = self.runs.iter().position(|x| x.role == m.carrier).unwrap_or(usize::MAX);
            out.push(self.pose_frame(Some(m.carrier), run, &mount.pose, lo, hi, c)?);
        }
        out.push(self.at_pose(role)?);
        Some(out)
    }

    /// The frames placing every solid of side `side` (outermost first; the solid's own
    /// pose in its owner frame is not included), over the box `[lo, hi]` with centre `c`.
    /// Chains of participants and forward kinematics are computed once per call.
    fn side_frames(&self, side: usize, lo: &[f64], hi: &[f64], c: &[f64]) -> Vec<Option<Vec<(Pose3, FrameBound)>>> {
        self.frames_of(side, None, lo, hi, c)
    }

    /// [`Geo::side_frames`], computed only for solid `only` when given (the others are
    /// `None`).
    fn frames_of(
        &self,
        side: usize,
        only: Option<usize>,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Vec<Option<Vec<(Pose3, FrameBound)>>> {
        let mut chains: HashMap<Option<RoleId>, Option<Vec<(Pose3, FrameBound)>>> = HashMap::new();
        let mut fk: HashMap<(RoleId, usize), Option<Kinematics>> = HashMap::new();
        let mut out = Vec::new();
        for (idx, p) in self.sides[side].iter().enumerate() {
            if only.is_some_and(|k| k != idx) {
                out.push(None);
                continue;
            }
            let chain = chains
                .entry(p.role)
                .or_insert_with(|| match p.role {
                    Some(r) => self.role_chain(r, lo, hi, c),
                    None => match p.at {
                        Some(at) => self.pose_frame(None, 0, at, lo, hi, c).map(|f| vec![f]),
                        None => Some(Vec::new()),
                    },
                })
                .clone();
            let Some(mut frames) = chain else {
                out.push(None);
                continue;
            };
            if let Some(place) = &p.piece.place {
                match self.pose_frame(p.role, p.run.unwrap_or(usize::MAX), place, lo, hi, c) {
                    Some(f) => frames.push(f),
                    None => {
                        out.push(None);
                        continue;
                    }
                }
            }
            if let Some(link) = &p.piece.link {
                let key = (p.role.unwrap_or(RoleId(u32::MAX)), std::sync::Arc::as_ptr(&link.robot) as usize);
                let got = fk
                    .entry(key)
                    .or_insert_with(|| {
                        let nvars = link.robot.joint_names().len();
                        let mut qc = vec![0.0; nvars];
                        let mut half = vec![0.0; nvars];
                        for (k, s) in link.joints.iter().enumerate() {
                            let i = p.role.and_then(|r| self.dims.iter().position(|d| *d == Dim::Now(r, *s)))?;
                            qc[k] = c[i];
                            half[k] = (hi[i] - c[i]).max(c[i] - lo[i]);
                        }
                        Some((link.robot.link_poses(&qc), link.robot.displacement_bound(&qc, &half)))
                    })
                    .clone();
                let Some((poses, disp)) = got else {
                    out.push(None);
                    continue;
                };
                let (lp, d) = (poses[link.link], disp[link.link]);
                frames.push((lp, FrameBound { dt: d, drot: 0.0, reach: geometry::reach(&lp) + d }));
            }
            out.push(Some(frames));
        }
        out
    }

    /// Each solid of side `side` placed at `c` with the bounds on how far its points move
    /// over `[lo, hi]`; `None` if some solid cannot be placed (no bound).
    fn placed(&self, side: usize, lo: &[f64], hi: &[f64], c: &[f64]) -> Option<Vec<At>> {
        self.side_frames(side, lo, hi, c)
            .into_iter()
            .zip(&self.sides[side])
            .map(|(frames, p)| Self::place_one(frames?, p))
            .collect()
    }

    /// Solid `k` of side `side` alone, as [`Geo::placed`] places it.
    fn placed_one(&self, side: usize, k: usize, lo: &[f64], hi: &[f64], c: &[f64]) -> Option<At> {
        let frames = self.frames_of(side, Some(k), lo, hi, c).into_iter().nth(k)??;
        Self::place_one(frames, self.sides[side].get(k)?)
    }

    fn place_one(frames: Vec<(Pose3, FrameBound)>, p: &Placed) -> Option<At> {
        let mut pose = geometry::identity();
        let mut fb = Vec::with_capacity(frames.len());
        for (f, b) in frames {
            pose *= f;
            fb.push(b);
        }
        let motion = chain_motion_bound(&fb, p.piece.solid.bounding_radius());
        // The stand-in's frame is the solid's own (`turns_about_z`: the last frame, with
        // roll and pitch fixed at 0), whose turn about z leaves it in place: only the other
        // frames' motion and that frame's translation move it.
        let turned_motion = p.turned.as_ref().map(|s| {
            if let Some(last) = fb.last_mut() {
                last.drot = 0.0;
            }
            chain_motion_bound(&fb, s.bounding_radius())
        });
        Some(At { pose: pose * p.piece.solid.pose, owner: pose, motion, turned_motion })
    }

    fn at_pose(&self, role: RoleId) -> Option<(Pose3, FrameBound)> {
        if let Some(got) = self.at_poses.borrow().get(&role) {
            return *got;
        }
        let got = self.at_pose_uncached(role);
        self.at_poses.borrow_mut().insert(role, got);
        got
    }

    fn at_pose_uncached(&self, role: RoleId) -> Option<(Pose3, FrameBound)> {
        let pose = &self.prog.role(role).pose;
        let mut a = [0.0; 6];
        let mut ab = ArgBounds::fixed([0.0; 6]);
        for (k, e) in pose.iter().enumerate().take(6) {
            let iv = bounds::eval(self.prog, e, &bounds::closed)?;
            a[k] = iv.lo / 2.0 + iv.hi / 2.0;
            ab.lo[k] = iv.lo;
            ab.hi[k] = iv.hi;
        }
        ab.centre = a;
        // The enclosure's width (a few ulps of an irrational angle) is the bound's.
        Some((geometry::pose6(a), FrameBound::pose(&ab)))
    }

    fn solve(&self, limit: Duration) -> GeoAnswer {
        // One program on this thread for the whole search: its constants are evaluated once.
        let _consts = bounds::ConstCache::new();
        let n = self.dims.len();
        let res: Vec<f64> = (0..n).map(|i| ((self.root.hi[i] - self.root.lo[i]) * 1e-4).max(1e-6)).collect();
        let mut opts = Options::new(res);
        opts.deadline = Some(Instant::now() + limit);
        opts.max_nodes = 400_000;
        opts.time_dim = self.dims.iter().position(|d| *d == Dim::Clock(0));
        let d = bnb::decide(self, &self.root, &opts);
        if d.outcome.is_vacuous() {
            return self.all_cut_away(d.stats.nodes);
        }
        match d.outcome {
            bnb::Outcome::Apart { .. } => GeoAnswer::Apart,
            bnb::Outcome::Contact(c) => {
                // A contact is confirmed on the meshes themselves (`Geo::distance`), never on
                // convex hulls alone.
                let times: Vec<f64> = self
                    .dims
                    .iter()
                    .enumerate()
                    .filter_map(|(i, d)| matches!(d, Dim::Clock(_)).then_some(c.q[i]))
                    .collect();
                let values = self.assignments(&c.q).unwrap_or_default();
                GeoAnswer::Contact {
                    values,
                    overlap: Overlap {
                        point: c.point,
                        times: if self.initial { Vec::new() } else { times },
                        not_before: None,
                    },
                }
            }
            bnb::Outcome::Unknown { why, qbox, unresolved } => {
                let at: Vec<String> = self
                    .dims
                    .iter()
                    .enumerate()
                    .map(|(i, d)| format!("{} in [{:.4}, {:.4}]", self.dim_name(*d), qbox.lo[i], qbox.hi[i]))
                    .collect();
                let splits: Vec<String> = self
                    .dims
                    .iter()
                    .enumerate()
                    .filter_map(|(i, dim)| {
                        let n = d.stats.splits.get(i).copied().unwrap_or(0);
                        (n > 0).then(|| format!("{} {n}", self.dim_name(*dim)))
                    })
                    .collect();
                GeoAnswer::Unknown(format!(
                    "the geometric search did not decide ({}; {} box(es) searched in {:.1} s, {} left, split along {}; e.g. {})",
                    match why {
                        bnb::UnknownWhy::Resolution =>
                            "boxes at the resolution limit touch or are too close to call".to_string(),
                        bnb::UnknownWhy::Nodes(n) => format!("{n} boxes searched"),
                        bnb::UnknownWhy::Deadline => "time limit reached".to_string(),
                        bnb::UnknownWhy::BadBox => "the search box is malformed".to_string(),
                    },
                    d.stats.nodes,
                    d.stats.elapsed.as_secs_f64(),
                    unresolved,
                    if splits.is_empty() { "nothing".to_string() } else { splits.join(", ") },
                    at.join(", ")
                ))
            }
        }
    }

    /// The box narrowed to where the runs' guarantees and invariants can hold: bounds
    /// read off conjuncts `x <= e`, `e <= x`, `x == e` ([`bounds::ranges_from`], outward
    /// rounded) with the box's ranges for everything else. Sound: every configuration of
    /// the box that satisfies the constraints lies in the narrowed box. `None` when it is
    /// empty (no configuration of the box satisfies them).
    fn narrow(&self, lo: &[f64], hi: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        if let Some(((l, h), got)) = self.contracted.borrow().as_ref() {
            if l == lo && h == hi {
                return got.clone();
            }
        }
        let got = self.contract_uncached(lo, hi);
        *self.contracted.borrow_mut() = Some(((lo.to_vec(), hi.to_vec()), got.clone()));
        got
    }

    fn contract_uncached(&self, lo: &[f64], hi: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let (mut lo, mut hi) = (lo.to_vec(), hi.to_vec());
        let mut work = self.scratch.borrow_mut();
        // Each run over the box as the runs before it left it.
        for c in &self.contractions {
            if !c.narrow(&mut lo, &mut hi, &mut work) {
                return None;
            }
        }
        Some((lo, hi))
    }

    /// Run `k`'s contraction, compiled: its guarantee and invariant, with the ranges of
    /// everything that is not a dimension fixed for the question ([`Geo::var_range`]).
    fn compile_contraction(&self, k: usize) -> contract::RunContraction {
        let r = &self.runs[k];
        let prim = self.prog.prim(r.app.prim);
        let mut facts: Vec<&Expr> = vec![&prim.guarantee];
        facts.extend(self.prog.kind(prim.kind).invariant.as_ref());
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let dim_of = |v: &Var| match v {
            Var::Own(slot) => dim(Dim::Now(r.role, *slot)),
            _ => None,
        };
        contract::RunContraction::new(self.prog, &facts, &dim_of, &|v: &Var| self.leaf(k, Some(r.role), v))
    }

    /// Where the range of variable `v` of participant `role`, read in run `run`'s frame,
    /// comes from in a box: [`Geo::var_range`] with the dimensions left to the box.
    /// `role` `None`: an obstacle's pose, which reads no variable.
    fn leaf(&self, run: usize, role: Option<RoleId>, v: &Var) -> contract::Leaf {
        let Some(role) = role else { return contract::Leaf::Fixed(None) };
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let i = match v {
            Var::Own(slot) => dim(Dim::Now(role, *slot)),
            Var::Clock => self.runs.get(run).and_then(|r| dim(Dim::Clock(r.clock))),
            _ => None,
        };
        match i {
            Some(i) => contract::Leaf::Dim(i),
            None => contract::Leaf::Fixed(self.var_range(run, role, v, None)),
        }
    }

    fn dim_name(&self, d: Dim) -> String {
        match d {
            Dim::Clock(k) if self.runs.iter().any(|r| r.clock == 1) => format!("time {}", k + 1),
            Dim::Clock(_) => "time".to_string(),
            Dim::Now(r, slot) => format!("{}.{}", self.prog.role_name(r), self.prog.kind_of(r).var(slot).0),
        }
    }

    /// The question's configurations, as the SMT stage is asked about them.
    fn configs(&self) -> Configs<'_> {
        Configs { prog: self.prog, hyps: &self.ob.hyps, runs: &self.runs, dims: &self.dims, initial: self.initial }
    }

    /// The search cut every box of the root away as infeasible: by the contraction, no
    /// configuration satisfies the constraints, so the sides never meet. That contradicts
    /// any configuration Z3 finds satisfying them exactly (the motion can run, the
    /// can-end question's witness): an enclosure then cut away a feasible configuration,
    /// and the search decides nothing (unknown, with the witness). Apart only when Z3
    /// confirms that no configuration of the root satisfies the constraints; unknown when
    /// it cannot tell.
    fn all_cut_away(&self, nodes: usize) -> GeoAnswer {
        let what = format!("every box of the geometric search ({nodes}) was cut away as infeasible");
        match ask::exists(&self.configs(), &self.root.lo, &self.root.hi) {
            Exists::No => GeoAnswer::Apart,
            Exists::Yes(values) => {
                let at: Vec<String> = values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                GeoAnswer::Unknown(format!(
                    "{what}, yet Z3 finds a configuration that satisfies every constraint ({}): the interval contraction contradicts this witness, so the search proves nothing",
                    if at.is_empty() { "no values shown".to_string() } else { at.join(", ") }
                ))
            }
            Exists::Unknown(reason) => GeoAnswer::Unknown(format!(
                "{what}, and Z3 could not confirm that no configuration satisfies the constraints ({reason})"
            )),
            Exists::NotPosed => {
                GeoAnswer::Unknown(format!("{what}, and the constraints could not be put to Z3 to confirm it"))
            }
        }
    }

    /// The counterexample's values at the configuration `q` (a model of the constraints
    /// with the dimensions pinned near `q`).
    fn assignments(&self, q: &[f64]) -> Option<Vec<Assignment>> {
        ask::assignments(&self.configs(), q)
    }
}

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
mod tests {
    use crate::diag::Code;
    use crate::driver::{Config, Verdict};

    /// The Panda (its URDF) standing still at its home pose beside a pillar `gap` metres
    /// from its platform's edge: decided by the geometric procedure (a URDF body has no
    /// predicate), apart for a clear gap, and a contact (E0510, at a witness Z3 found) for
    /// a pillar through the platform.
    fn panda_and_pillar(x: &str) -> (Verdict, Vec<Code>) {
        let src = format!(
            "import \"../motion-primitives/panda.mochi\";
             system Cell {{
               participant P: Panda {{ init: panda_joint1 == 0 && panda_joint2 == -0.785398 && panda_joint3 == 0
                 && panda_joint4 == -2.356195 && panda_joint5 == 0 && panda_joint6 == 1.570796
                 && panda_joint7 == 0.785398 && panda_finger_joint1 == 0.02; }}
               obstacle Pillar {{ geometry: cylinder(0.05, 1.5); at: pose({x}, 0, 0); }}
             }}
             choreography Cell = dt<P: idle>. end;
             process P = dt<idle>.end;"
        );
        let mut db = crate::source::SourceDb::new();
        let r = crate::fsload::check_source(
            &mut db,
            &crate::testing::repo("choreographies/geo-test.chor").display().to_string(),
            &src,
            &Config::default(),
        );
        let codes = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code).collect();
        let geometric = r
            .checks
            .iter()
            .any(|c| matches!(c.detail, crate::driver::Detail::Obligations { geometric, .. } if geometric > 0));
        assert!(geometric, "decided by the geometric procedure: {:?}", r.checks);
        (r.verdict, codes)
    }

    /// A bar 1 m long spinning in place at any heading beside a pillar whose face is `face`
    /// metres from the bar's centre. Its stand-in (the vertical cylinder of radius 0.5025
    /// through the bar's box corners, `Solid::z_cylinder`) proves the far pillar clear with
    /// no split of the heading; for the near one the stand-in touches, and the contact,
    /// which only some headings make, must still be found: the stand-in never decides a
    /// pair it does not prove apart.
    fn spinning_bar(face: &str) -> (Verdict, Vec<Code>) {
        let src = format!(
            "robot Bar {{ state x: real, y: real, th: real;
               geometry: box(1.0, 0.1, 0.2) at pose(x, y, 0, 0, 0, th);
               invariant: -5 <= x <= 5 && -5 <= y <= 5 && -pi <= th <= pi; }}
             motion Bar.spin {{ interruptible: false; pre: true; guarantee: x == old(x) && y == old(y);
               post: x == old(x) && y == old(y); footprint: geometry; duration: [1, 1]; }}
             system S {{
               participant B: Bar {{ init: x == 0 && y == 0 && th == pi / 2; }}
               obstacle Pillar {{ geometry: cylinder(0.1, 1); at: pose({face} + 0.1, 0, 0); }}
             }}
             choreography S = dt<B: spin>. end;
             process B = dt<spin>.end;"
        );
        let mut db = crate::source::SourceDb::new();
        let r = crate::fsload::check_source(
            &mut db,
            &crate::testing::repo("choreographies/geo-test.chor").display().to_string(),
            &src,
            &Config::patient(),
        );
        let codes = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code).collect();
        (r.verdict, codes)
    }

    #[test]
    fn a_stand_in_proves_a_spinning_bar_clear_and_never_hides_its_contact() {
        assert_eq!(spinning_bar("0.6"), (Verdict::Verified, vec![]));
        // 0.45 from the centre: the bar's end (0.5) reaches it at headings near 0 and pi.
        assert_eq!(spinning_bar("0.45"), (Verdict::Rejected, vec![Code::ObstacleHit]));
    }

    #[test]
    fn a_urdf_robot_is_kept_clear_of_an_obstacle_or_shown_to_touch_it() {
        // The platform is 0.60 x 0.70 (x from -0.30 to 0.30); the arm at home stays above it.
        assert_eq!(panda_and_pillar("1.5"), (Verdict::Verified, vec![]));
        let (v, codes) = panda_and_pillar("0.2");
        assert_eq!(v, Verdict::Rejected);
        assert_eq!(codes, vec![Code::ObstacleHit]);
    }
}

#[cfg(test)]
mod mount_tests {
    use crate::diag::Code;
    use crate::driver::{Config, Verdict};

    /// A sled slides from x = 0 to 1 (a 0.5 m box at `pose(x, 0, 0)`) carrying a rider, a
    /// 0.1 m ball on its deck `mount deck: pose(x + off, 0, 0.1)`. A pillar (radius 0.1)
    /// stands at x = 1.5. The rider reaches x = 1 + off + 0.1, the pillar's face is 1.4:
    /// clear for off = 0.1, touching for off = 0.4. The rider's own `at:` is the identity,
    /// so an encoding that placed it by `at:` alone (ignoring the carrier) would see it at
    /// the origin and pass both.
    fn ride(off: &str, footprint: &str) -> (Verdict, Vec<Code>) {
        let src = format!(
            "robot Sled {{ state x: real; geometry: box(0.5, 0.4, 0.1) at pose(x, 0, 0);
               mount deck: pose(x + {off}, 0, 0.1); invariant: -5 <= x <= 5; }}
             robot Rider {{ state s: real; geometry: sphere(0.1) at pose(0, 0, 0.1); invariant: 0 <= s <= 1; }}
             motion Sled.slide(xf: real) {{ interruptible: false; pre: x < xf; guarantee: old(x) <= x <= xf;
               post: x == xf; footprint: geometry; duration: [2, 2]; }}
             motion Rider.sit {{ interruptible: true; guarantee: s == old(s); post: s == old(s);
               {footprint}; duration: [0, inf]; }}
             system S {{
               participant C: Sled {{ init: x == 0; }}
               participant R: Rider {{ init: s == 0; on: C.deck; }}
               obstacle Pillar {{ geometry: cylinder(0.1, 2); at: pose(1.5, 0, 0); }}
             }}
             choreography S = dt<C: slide(1), R: sit>. end;
             process C = dt<slide(1)>.end;
             process R = dt<sit>.end;"
        );
        let mut db = crate::source::SourceDb::new();
        let r = crate::fsload::check_source(&mut db, "mount-test.chor", &src, &Config::default());
        (r.verdict, r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code).collect())
    }

    #[test]
    fn a_mounted_body_is_placed_through_its_carrier() {
        assert_eq!(ride("0.1", "footprint: geometry"), (Verdict::Verified, vec![]));
        assert_eq!(ride("0.4", "footprint: geometry"), (Verdict::Rejected, vec![Code::ObstacleHit]));
    }

    /// A predicate footprint of a mounted participant cannot be placed through the carrier
    /// by the geometric procedure: never verified (it was verified when the Z3 encoding
    /// placed the rider by its `at:` alone).
    #[test]
    fn a_mounted_predicate_footprint_is_never_passed() {
        let fp = "footprint(px, py, pz): px^2 + py^2 + (pz - 0.1)^2 <= 0.01";
        let (v, _) = ride("0.4", fp);
        assert_ne!(v, Verdict::Verified);
        let (v, _) = ride("0.1", fp);
        assert_ne!(v, Verdict::Verified);
    }
}
