//! A sound branch and bound over boxes of configurations:
//! are two sets of solids, each placed by a configuration `q` (time and state variables)
//! ranging over a box, apart for every `q` that satisfies the constraints? And what is
//! their minimum distance? ARCHITECTURE.md, "Geometric decision procedure", has the
//! argument; in short:
//!
//! * a box `B` with centre `c` is **apart** when `lower(c) − motion(B) > margin`, where
//!   `lower(c)` is a certified lower bound on the distance of the two sides placed at
//!   `c` and `motion(B)` bounds how far any point of either side moves between `c` and
//!   any `q ∈ B` (`placement.rs`): a point of side 1 at `q` is within `m1` of a point of
//!   side 1 at `c`, likewise for side 2, and `m1 + m2 ≤ motion(B)`; so the distance at
//!   `q` is at least `lower(c) − motion(B) > 0`;
//! * or when the constraints are infeasible on `B` (`Feasible::No`, sound by contract);
//! * otherwise `B` is split; a box below the caller's resolution is a **contact** only if
//!   a `q` in it that satisfies the constraints (the scene's witness) has distance ≤ 0
//!   when evaluated again, and **unknown** otherwise. Exhausting the node budget or the
//!   deadline is unknown: never a pass.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d::math::{Isometry as PIso, Point as PPoint, Vector as PVec};
use parry3d::shape::SharedShape;

use crate::geometry::placement::{chain_motion_bound, pose_isometry, AffinePose, FrameBound};

mod parry_scene;
mod split;
#[cfg(test)]
mod tests;

pub use parry_scene::*;
use split::*;

/// The distance of the two sides placed at one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Closest {
    /// parry's distance (negative: penetration depth), the best estimate.
    pub distance: f64,
    /// A certified lower bound on the true distance (≤ `distance`); for contacts it may
    /// be any non-positive number. Only this value is used to prove a box apart.
    pub lower: f64,
    /// The closest points (world), one on each side.
    pub points: [[f64; 3]; 2],
    /// The two closest solids: an index into side 0 and one into side 1.
    pub solids: [usize; 2],
}

/// A box's certified lower bound ([`Scene::bound`]).
#[derive(Clone, Debug)]
pub struct Bound {
    /// No `q` of the box puts the sides closer than this.
    pub lower: f64,
    /// The sides at the box's centre.
    pub at_c: Closest,
    /// The motion bound the splitting rule compares against ([`Scene::focus_motion_bound`]
    /// with `focus`).
    pub mb: f64,
    /// The pair of solids whose bound is `lower` (`None`: every solid).
    pub focus: Option<Focus>,
}

/// The pair of solids a box's bound comes from (one of each side), and for each whether
/// it was bounded by a stand-in the scene places instead (see the scene's `bound`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Focus {
    pub solids: [usize; 2],
    pub proxy: [bool; 2],
}

/// Can the constraints hold in a box?
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feasible {
    /// No `q` in the box satisfies them (must be sound).
    No,
    /// Perhaps.
    Maybe,
    /// Every `q` in the box satisfies them (must be sound).
    All,
}

/// Two sides of solids placed by a configuration `q` (see the module doc). Implemented
/// by a caller that evaluates mochi expressions over intervals and asks Z3 for witnesses,
/// or by [`ParryScene`] for solids placed by chains of frames.
pub trait Scene {
    fn dims(&self) -> usize;
    /// The two sides placed at `q`: parry's distance, a certified lower bound, the closest
    /// points and solids.
    fn distance(&self, q: &[f64]) -> Closest;
    /// Upper bound on how far any point of either side can move, relative to its place
    /// at `centre`, for `q` anywhere in `[lo, hi]` (the sum of both sides' bounds).
    fn motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> f64;
    /// A certified lower bound on the distance of the two sides over every `q` of the
    /// box `[lo, hi]` (centre `centre`), with the sides' distance at the centre. The
    /// default is `distance(centre).lower − motion_bound(..)`; a scene may bound pair by
    /// pair instead (`min` over pairs of solids of `lower_ij(c) − m_i − m_j`, which is at
    /// least the default), and name the pair that attains it (its `focus`).
    fn bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Bound {
        let at_c = self.distance(centre);
        let mb = self.motion_bound(lo, hi, centre);
        Bound { lower: at_c.lower - mb, at_c, mb, focus: None }
    }
    /// [`Scene::motion_bound`] restricted to the solids of `focus` (one of each side), an
    /// upper bound on how far their points move; default: every solid.
    fn focus_motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64], focus: Option<Focus>) -> f64 {
        let _ = focus;
        self.motion_bound(lo, hi, centre)
    }
    /// Can some `q` in the box satisfy the constraints?
    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible;
    /// A sub-box of `b` that holds every `q` of `b` satisfying the constraints (`None`:
    /// none does). Must be sound in that sense; the search then evaluates the narrowed box
    /// (its centre, its motion bound) instead of `b`. Default: `b` itself.
    fn contract(&self, b: &QBox) -> Option<QBox> {
        Some(b.clone())
    }
    /// A `q` in the box that satisfies the constraints exactly, if one can be found (an
    /// SMT solver may be asked), preferably near `near`. Used only to confirm a contact
    /// and to attain a clearance's upper bound.
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>>;
    /// The point a contact at `q` is shown at (`at`: the sides there, distance ≤ 0): one
    /// that lies on both sides. `None` when the scene finds none, and then the contact is
    /// not confirmed (the search goes on). Default: the midpoint of the two closest points.
    fn contact_point(&self, q: &[f64], at: &Closest) -> Option<[f64; 3]> {
        let _ = q;
        Some(midpoint(&at.points))
    }
    /// The name of solid `solid` of side `side` (0 or 1), for reports.
    fn solid_name(&self, side: usize, solid: usize) -> String;
}

/// A box of configurations `[lo, hi]` (closed, per dimension).
#[derive(Clone, Debug, PartialEq)]
pub struct QBox {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

impl QBox {
    pub fn new(lo: Vec<f64>, hi: Vec<f64>) -> QBox {
        QBox { lo, hi }
    }

    /// The midpoint (within the box even after rounding).
    pub fn centre(&self) -> Vec<f64> {
        self.lo.iter().zip(&self.hi).map(|(l, h)| (l + 0.5 * (h - l)).clamp(*l, h.max(*l))).collect()
    }

    pub fn contains(&self, q: &[f64]) -> bool {
        q.len() == self.lo.len() && q.iter().zip(self.lo.iter().zip(&self.hi)).all(|(x, (l, h))| l <= x && x <= h)
    }

    fn well_formed(&self, dims: usize) -> bool {
        self.lo.len() == dims
            && self.hi.len() == dims
            && self.lo.iter().zip(&self.hi).all(|(l, h)| l.is_finite() && h.is_finite() && l <= h)
    }

    fn split(&self, k: usize) -> (QBox, QBox) {
        let mid = self.lo[k] + 0.5 * (self.hi[k] - self.lo[k]);
        let mut a = self.clone();
        let mut b = self.clone();
        a.hi[k] = mid;
        b.lo[k] = mid;
        (a, b)
    }
}

/// How to choose the dimension to split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitRule {
    /// The dimension whose collapse to its centre lowers the motion bound most (one
    /// extra `motion_bound` call per dimension); the widest in units of its resolution
    /// when no dimension lowers it (e.g. the rest of the box is at rest: then only the
    /// constraints can prune, and every dimension is narrowed in turn).
    Sensitivity,
    /// The widest in units of its resolution (cheap: no extra calls).
    WidestScaled,
}

/// Budgets and tolerances of one query.
#[derive(Clone, Debug)]
pub struct Options {
    /// Per dimension: a box no wider than this in every dimension is not split.
    pub resolution: Vec<f64>,
    /// A box is apart when its lower bound exceeds this (≥ 0; the caller's safety
    /// distance; 0 = any positive distance).
    pub margin: f64,
    pub max_nodes: usize,
    pub deadline: Option<Instant>,
    /// The time dimension: boxes are searched earliest first, and a contact is reported
    /// only from a box no wider in time than its resolution (see [`Contact`]).
    pub time_dim: Option<usize>,
    pub split: SplitRule,
}

impl Options {
    /// Defaults: the given resolution, margin 0, 200,000 nodes, no deadline, no time.
    pub fn new(resolution: Vec<f64>) -> Options {
        Options {
            resolution,
            margin: 0.0,
            max_nodes: 200_000,
            deadline: None,
            time_dim: None,
            split: SplitRule::Sensitivity,
        }
    }
}

/// A configuration where the two sides touch.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// The configuration (satisfies the constraints: the scene's witness).
    pub q: Vec<f64>,
    /// The contact point (world): a point on both sides ([`Scene::contact_point`]).
    pub point: [f64; 3],
    pub points: [[f64; 3]; 2],
    /// parry's distance at `q` (≤ 0: minus the penetration depth).
    pub distance: f64,
    pub names: [String; 2],
    /// With a time dimension: every `q` that satisfies the constraints with time below
    /// this value was proved apart. So the first contact happens in
    /// `[clear_before, q[time]]`; when no box was left unknown before it, the gap is at
    /// most the time resolution. `None` without a time dimension.
    pub clear_before: Option<f64>,
}

/// Why a query is undecided.
#[derive(Clone, Debug, PartialEq)]
pub enum UnknownWhy {
    /// A box at the resolution could be neither proved apart nor shown to touch.
    Resolution,
    /// The node budget ran out.
    Nodes(usize),
    /// The deadline passed.
    Deadline,
    /// The root box is malformed (wrong length, not finite, empty).
    BadBox,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// No `q` of the box that satisfies the constraints puts the sides in contact.
    Apart {
        /// Boxes proved apart by distance, and boxes pruned as infeasible.
        boxes: usize,
        infeasible: usize,
        /// The least `lower(c) − motion(B)` over the boxes proved by distance: a lower
        /// bound on the distance over the feasible configurations (`+∞` if none).
        min_lower_bound: f64,
    },
    Contact(Contact),
    Unknown {
        why: UnknownWhy,
        /// The first box left undecided.
        qbox: QBox,
        /// How many boxes were left undecided.
        unresolved: usize,
    },
}

impl Outcome {
    /// Apart only because no configuration of the box satisfies the constraints (every
    /// box was pruned as infeasible): like an obligation whose context is false, it proves
    /// nothing, and the caller should say so (ARCHITECTURE.md, "The vacuity guard").
    pub fn is_vacuous(&self) -> bool {
        matches!(self, Outcome::Apart { boxes: 0, infeasible, .. } if *infeasible > 0)
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    pub nodes: usize,
    /// Per dimension: how many boxes were split along it.
    pub splits: Vec<usize>,
    pub distance_calls: usize,
    pub witness_calls: usize,
    /// Configurations sampled in boxes to look for a contact ([`probe`]).
    pub probes: usize,
    pub elapsed: Duration,
}

/// What [`decide`] found about a box of configurations, with the search's statistics (an
/// obligation's answer is `smt::Decision`; this is the search's own).
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub outcome: Outcome,
    pub stats: Stats,
}

/// An entry of a search queue; ordered for a max-heap so that the least key (compared
/// lexicographically) pops first.
struct Queued<T> {
    key: (f64, f64),
    seq: u64,
    item: T,
}

impl<T> PartialEq for Queued<T> {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl<T> Eq for Queued<T> {}
impl<T> PartialOrd for Queued<T> {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl<T> Ord for Queued<T> {
    fn cmp(&self, o: &Self) -> Ordering {
        // Least key first; among equal keys, the most recent first (depth first).
        o.key.0.total_cmp(&self.key.0).then_with(|| o.key.1.total_cmp(&self.key.1)).then_with(|| self.seq.cmp(&o.seq))
    }
}

/// How long the search for the earliest contact may take once a contact is found: as long
/// as finding it took, within these bounds.
const REFINE_MIN: Duration = Duration::from_millis(250);
const REFINE_MAX: Duration = Duration::from_secs(2);

/// A box evaluated at its centre.
struct Node {
    qbox: QBox,
    c: Vec<f64>,
    at_c: Closest,
    mb: f64,
    focus: Option<Focus>,
    feas: Feasible,
}

/// What one search pass leaves.
struct Pass {
    proved: usize,
    infeasible: usize,
    min_lb: f64,
    unknown: Option<QBox>,
    unresolved: usize,
    /// The least time lower bound of the boxes left unknown.
    unknown_time: f64,
    /// How the pass ended: `None` = the queue ran empty.
    end: Option<PassEnd>,
}

enum PassEnd {
    Contact {
        q: Vec<f64>,
        at: Closest,
        point: [f64; 3],
        /// The time lower bound of the box the contact was found in.
        box_time: f64,
    },
    Budget {
        why: UnknownWhy,
        qbox: QBox,
        /// The least time lower bound of the boxes not yet decided.
        frontier: f64,
        left: usize,
    },
}

/// Whether [`probe`] samples boxes yet: once the search has evaluated
/// [`split::PROBE_AFTER`] boxes (most proofs end sooner and pay nothing for it), or has
/// spent a tenth of its time to the deadline (where each box is slow, a robot of many
/// meshes in an unoptimised build, the box count is never reached before the deadline, and
/// a contact that needs several coordinates at once is never met at a box's centre).
fn probing(stats: &Stats, opts: &Options, started: Instant) -> bool {
    stats.nodes >= split::PROBE_AFTER
        || opts.deadline.is_some_and(|d| {
            let now = Instant::now();
            d > started && (now - started) * 10 >= d - started
        })
}

/// One branch-and-bound pass over `root`. `earliest`: boxes in order of their time lower
/// bound, and contacts only from boxes no wider in time than its resolution; otherwise
/// best first on the lower bound `lower(c) − motion(B)` (the most colliding box first, so
/// a contact is found quickly). Nodes are counted in `stats` against `max_nodes`.
fn pass(scene: &dyn Scene, root: &QBox, opts: &Options, earliest: bool, max_nodes: usize, stats: &mut Stats) -> Pass {
    let time = opts.time_dim.filter(|&t| t < scene.dims());
    let order_time = if earliest { time } else { None };
    let margin = opts.margin.max(0.0);
    let mut out = Pass {
        proved: 0,
        infeasible: 0,
        min_lb: f64::INFINITY,
        unknown: None,
        unresolved: 0,
        unknown_time: f64::INFINITY,
        end: None,
    };
    let mut heap: BinaryHeap<Queued<Node>> = BinaryHeap::new();
    let mut seq = 0u64;
    let mut pending = vec![root.clone()];
    let started = Instant::now();
    loop {
        // Evaluate the new boxes: infeasible and proved ones are done, the others queue.
        for b in pending.drain(..) {
            let budget = if stats.nodes >= max_nodes {
                Some(UnknownWhy::Nodes(opts.max_nodes))
            } else if opts.deadline.is_some_and(|d| Instant::now() >= d) {
                Some(UnknownWhy::Deadline)
            } else {
                None
            };
            if let Some(why) = budget {
                let t = |b: &QBox| time.map_or(f64::NEG_INFINITY, |t| b.lo[t]);
                let frontier = heap.iter().map(|n| t(&n.item.qbox)).fold(t(&b), f64::min);
                out.end = Some(PassEnd::Budget { why, left: heap.len() + 1, frontier, qbox: b });
                return out;
            }
            stats.nodes += 1;
            let Some(b) = narrowed(scene, b) else {
                out.infeasible += 1;
                continue;
            };
            let feas = scene.feasible(&b.lo, &b.hi);
            if feas == Feasible::No {
                out.infeasible += 1;
                continue;
            }
            let c = b.centre();
            stats.distance_calls += 1;
            let Bound { lower: lb, at_c, mb, focus } = scene.bound(&b.lo, &b.hi, &c);
            if lb > margin {
                out.proved += 1;
                out.min_lb = out.min_lb.min(lb);
                continue;
            }
            let lb = if lb.is_nan() { f64::NEG_INFINITY } else { lb };
            seq += 1;
            heap.push(Queued {
                key: (order_time.map_or(0.0, |t| b.lo[t]), lb),
                seq,
                item: Node { qbox: b, c, at_c, mb, focus, feas },
            });
        }
        let Some(Queued { item: n, .. }) = heap.pop() else {
            return out;
        };
        let b = &n.qbox;
        let res_box = at_resolution(b, &opts.resolution);
        let time_ok = !earliest || time.is_none_or(|t| widths_ok(b, &opts.resolution, t));
        // A touching centre that itself breaks the constraints (cheap to tell) asks no
        // witness: the box is split, and its feasible parts are asked in their turn.
        let centre_possible = || scene.feasible(&n.c, &n.c) != Feasible::No;
        if (n.at_c.distance <= 0.0 && time_ok && centre_possible()) || res_box {
            if let Some((q, at, point)) = located(scene, confirm(scene, b, &n.c, &n.at_c, n.feas, stats)) {
                out.end =
                    Some(PassEnd::Contact { q, at, point, box_time: time.map_or(f64::NEG_INFINITY, |t| b.lo[t]) });
                return out;
            }
        }
        if time_ok {
            if let Some((q, at, point)) = probe(scene, b, opts, probing(stats, opts, started), stats) {
                out.end =
                    Some(PassEnd::Contact { q, at, point, box_time: time.map_or(f64::NEG_INFINITY, |t| b.lo[t]) });
                return out;
            }
        }
        match choose_split(scene, b, &n.c, n.mb, n.focus, opts) {
            Some(k) => {
                count_split(stats, k);
                let (x, y) = b.split(k);
                pending.push(x);
                pending.push(y);
            }
            None => {
                out.unresolved += 1;
                if let Some(t) = time {
                    out.unknown_time = out.unknown_time.min(b.lo[t]);
                }
                if out.unknown.is_none() {
                    out.unknown = Some(n.qbox);
                }
            }
        }
    }
}

/// Decide whether the two sides of `scene` are apart for every `q` in `root` that
/// satisfies the constraints (module doc).
///
/// Search order: best first on the box's lower bound, so that a contact, if any, is
/// found early. With a time dimension, a contact found at time `t1` is then refined: a
/// second pass over the part of the box with time ≤ `t1` searches earliest first (boxes
/// in order of their time lower bound) with the nodes left; [`Contact::clear_before`]
/// says how far that pass proved the feasible configurations apart.
pub fn decide(scene: &dyn Scene, root: &QBox, opts: &Options) -> Verdict {
    let start = Instant::now();
    let mut stats = Stats::default();
    let finish = |outcome: Outcome, mut stats: Stats| {
        stats.elapsed = start.elapsed();
        Verdict { outcome, stats }
    };
    if !root.well_formed(scene.dims()) || opts.resolution.len() != scene.dims() {
        return finish(Outcome::Unknown { why: UnknownWhy::BadBox, qbox: root.clone(), unresolved: 1 }, stats);
    }
    let time = opts.time_dim.filter(|&t| t < scene.dims());
    let first = pass(scene, root, opts, false, opts.max_nodes, &mut stats);
    let contact = |q: Vec<f64>, at: Closest, point: [f64; 3], clear_before: Option<f64>| {
        Outcome::Contact(Contact {
            point,
            points: at.points,
            distance: at.distance,
            names: [scene.solid_name(0, at.solids[0]), scene.solid_name(1, at.solids[1])],
            q,
            clear_before,
        })
    };
    match first.end {
        Some(PassEnd::Contact { q, at, point, .. }) => {
            let Some(t) = time else {
                return finish(contact(q, at, point, None), stats);
            };
            // Refine: the earliest contact with time ≤ q[t], with the nodes left.
            let mut early = root.clone();
            early.hi[t] = q[t].max(early.lo[t]);
            // As long as finding the contact took (at least REFINE_MIN, at most REFINE_MAX,
            // within the time left): the contact stands whatever the refinement finds, which
            // only moves it earlier and says how far before it all is clear.
            let mut o2 = opts.clone();
            let now = Instant::now();
            let refine = start.elapsed().clamp(REFINE_MIN, REFINE_MAX);
            o2.deadline = Some(match opts.deadline {
                Some(d) => d.min(now + refine.min(d.saturating_duration_since(now))),
                None => now + refine,
            });
            let second = pass(scene, &early, &o2, true, opts.max_nodes, &mut stats);
            let (q, at, point, clear) = match second.end {
                Some(PassEnd::Contact { q: q2, at: at2, point: p2, box_time }) => {
                    (q2, at2, p2, box_time.min(second.unknown_time))
                }
                Some(PassEnd::Budget { frontier, .. }) => (q, at, point, frontier.min(second.unknown_time)),
                // Every feasible q with time below q[t] was decided: none touches, except
                // perhaps in boxes left unknown.
                None => {
                    let t1 = q[t];
                    (q, at, point, t1.min(second.unknown_time))
                }
            };
            finish(contact(q, at, point, Some(clear.max(root.lo[t]))), stats)
        }
        Some(PassEnd::Budget { why, qbox, left, .. }) => {
            finish(Outcome::Unknown { why, qbox, unresolved: first.unresolved + left }, stats)
        }
        None => match first.unknown {
            Some(qbox) => {
                finish(Outcome::Unknown { why: UnknownWhy::Resolution, qbox, unresolved: first.unresolved }, stats)
            }
            None => finish(
                Outcome::Apart { boxes: first.proved, infeasible: first.infeasible, min_lower_bound: first.min_lb },
                stats,
            ),
        },
    }
}

/// The minimum distance over the feasible configurations of a box (`--clearance`).
#[derive(Clone, Debug, PartialEq)]
pub struct Clearance {
    /// Certified: no feasible `q` of the box has distance below it (`+∞`: none is
    /// feasible).
    pub lower: f64,
    /// parry's distance at `at_q` (a feasible configuration), `+∞` if none was found.
    pub upper: f64,
    pub at_q: Option<Vec<f64>>,
    pub points: Option<[[f64; 3]; 2]>,
    pub names: Option<[String; 2]>,
    /// `upper − lower ≤ tolerance` was reached (else a budget ran out, or boxes at the
    /// resolution keep the bounds apart).
    pub complete: bool,
    pub stats: Stats,
}

/// Best-first search on the lower bound `lower(c) − motion(B)` until
/// `upper − lower ≤ tolerance`; infeasible boxes are pruned. The upper bound is attained
/// at a configuration that satisfies the constraints: a box's centre when the box is
/// `Feasible::All` (or the centre alone is), else the scene's witness for boxes at the
/// resolution.
pub fn min_distance(scene: &dyn Scene, root: &QBox, tolerance: f64, opts: &Options) -> Clearance {
    let start = Instant::now();
    let mut stats = Stats::default();
    let mut out = Clearance {
        lower: f64::NEG_INFINITY,
        upper: f64::INFINITY,
        at_q: None,
        points: None,
        names: None,
        complete: false,
        stats: Stats::default(),
    };
    if !root.well_formed(scene.dims()) || opts.resolution.len() != scene.dims() {
        out.stats.elapsed = start.elapsed();
        return out;
    }
    let mut best: Option<(Vec<f64>, Closest)> = None;
    let offer = |q: Vec<f64>, d: Closest, best: &mut Option<(Vec<f64>, Closest)>| {
        if best.as_ref().is_none_or(|(_, b)| d.distance < b.distance) {
            *best = Some((q, d));
        }
    };
    let mut heap = BinaryHeap::new();
    let mut seq = 0u64;
    let mut frozen = f64::INFINITY;
    // Evaluates a box: None when infeasible, else its lower bound (and offers its centre).
    let eval = |b: QBox, stats: &mut Stats, best: &mut Option<(Vec<f64>, Closest)>| {
        let b = narrowed(scene, b)?;
        let feas = scene.feasible(&b.lo, &b.hi);
        if feas == Feasible::No {
            return None;
        }
        let c = b.centre();
        stats.distance_calls += 1;
        let Bound { lower: lb, at_c: d, mb, focus } = scene.bound(&b.lo, &b.hi, &c);
        if feas == Feasible::All || scene.feasible(&c, &c) == Feasible::All {
            offer(c, d, best);
        }
        Some((if lb.is_nan() { f64::NEG_INFINITY } else { lb }, (b, mb, focus)))
    };
    if let Some((lb, b)) = eval(root.clone(), &mut stats, &mut best) {
        heap.push(Queued { key: (lb, 0.0), seq, item: b });
    }
    let upper_of = |best: &Option<(Vec<f64>, Closest)>| best.as_ref().map_or(f64::INFINITY, |(_, d)| d.distance);
    loop {
        let lower = heap.peek().map_or(f64::INFINITY, |q| q.key.0).min(frozen);
        let upper = upper_of(&best);
        if heap.is_empty() || upper - lower <= tolerance {
            out.lower = lower.min(upper);
            out.complete = heap.is_empty() && frozen == f64::INFINITY || upper - lower <= tolerance;
            break;
        }
        let over = stats.nodes >= opts.max_nodes || opts.deadline.is_some_and(|d| Instant::now() >= d);
        if over {
            out.lower = lower;
            break;
        }
        stats.nodes += 1;
        let Some(Queued { item: (b, mb, focus), key: (lb, _), .. }) = heap.pop() else {
            break;
        };
        let c = b.centre();
        // The split that lowers the motion charged to the pair the bound came from (as in
        // `pass`); the upper bound is sought by probes too (`probe`).
        if let Some((q, d)) = probe_min(scene, &b, opts, &mut stats) {
            if best.as_ref().is_none_or(|(_, x)| d.distance < x.distance) {
                best = Some((q, d));
            }
        }
        match choose_split(scene, &b, &c, mb, focus, opts) {
            Some(k) => {
                let (x, y) = b.split(k);
                count_split(&mut stats, k);
                for child in [x, y] {
                    if let Some((lb, child)) = eval(child, &mut stats, &mut best) {
                        seq += 1;
                        heap.push(Queued { key: (lb, 0.0), seq, item: child });
                    }
                }
            }
            None => {
                frozen = frozen.min(lb);
                stats.witness_calls += 1;
                if let Some(q) = scene.witness(&b.lo, &b.hi, &c).filter(|q| b.contains(q)) {
                    stats.distance_calls += 1;
                    let d = scene.distance(&q);
                    if best.as_ref().is_none_or(|(_, x)| d.distance < x.distance) {
                        best = Some((q, d));
                    }
                }
            }
        }
    }
    out.upper = upper_of(&best);
    if let Some((q, d)) = best {
        out.names = Some([scene.solid_name(0, d.solids[0]), scene.solid_name(1, d.solids[1])]);
        out.points = Some(d.points);
        out.at_q = Some(q);
    }
    stats.elapsed = start.elapsed();
    out.stats = stats;
    out
}
