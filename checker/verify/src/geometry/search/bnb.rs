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
    /// The contact point (world): the midpoint of the two closest points.
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

#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
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

/// Dimension `k` of `b` is at its resolution: no wider than it, or too narrow for f64 to
/// hold a midpoint strictly inside (so splitting would not shrink it).
fn widths_ok(b: &QBox, res: &[f64], k: usize) -> bool {
    let (l, h) = (b.lo[k], b.hi[k]);
    let mid = l + 0.5 * (h - l);
    h - l <= res.get(k).copied().unwrap_or(0.0) || mid <= l || mid >= h
}

fn at_resolution(b: &QBox, res: &[f64]) -> bool {
    (0..b.lo.len()).all(|k| widths_ok(b, res, k))
}

/// The dimension to split (one that is above its resolution; `None` if none is).
fn choose_split(
    scene: &dyn Scene,
    b: &QBox,
    c: &[f64],
    mb: f64,
    focus: Option<Focus>,
    opts: &Options,
) -> Option<usize> {
    let res = &opts.resolution;
    let open: Vec<usize> = (0..b.lo.len()).filter(|&k| !widths_ok(b, res, k)).collect();
    if open.is_empty() {
        return None;
    }
    let widest = || {
        open.iter().copied().max_by(|&i, &j| {
            let s = |k: usize| (b.hi[k] - b.lo[k]) / res[k].max(f64::MIN_POSITIVE);
            s(i).total_cmp(&s(j))
        })
    };
    if opts.split == SplitRule::WidestScaled || !mb.is_finite() {
        return widest();
    }
    let mut best: Option<(usize, f64)> = None;
    let (mut lo, mut hi) = (b.lo.clone(), b.hi.clone());
    for &k in &open {
        lo[k] = c[k];
        hi[k] = c[k];
        let gain = mb - scene.focus_motion_bound(&lo, &hi, c, focus);
        lo[k] = b.lo[k];
        hi[k] = b.hi[k];
        if gain > 1e-12 * mb && best.is_none_or(|(_, g)| gain > g) {
            best = Some((k, gain));
        }
    }
    best.map(|(k, _)| k).or_else(widest)
}

/// `b` narrowed by the scene's contraction, intersected with `b` (a contraction may only
/// shrink a box); `None` when no `q` of `b` satisfies the constraints. A malformed answer
/// (NaN, wrong length) keeps `b`: never lose a configuration.
fn narrowed(scene: &dyn Scene, b: QBox) -> Option<QBox> {
    let n = scene.contract(&b)?;
    if n.lo.len() != b.lo.len() || n.hi.len() != b.hi.len() {
        return Some(b);
    }
    let mut out = b.clone();
    for k in 0..b.lo.len() {
        let (l, h) = (n.lo[k], n.hi[k]);
        if l.is_nan() || h.is_nan() {
            continue;
        }
        out.lo[k] = out.lo[k].max(l);
        out.hi[k] = out.hi[k].min(h);
        if out.lo[k] > out.hi[k] {
            return None;
        }
    }
    Some(out)
}

fn count_split(stats: &mut Stats, k: usize) {
    if stats.splits.len() <= k {
        stats.splits.resize(k + 1, 0);
    }
    stats.splits[k] += 1;
}

fn midpoint(p: &[[f64; 3]; 2]) -> [f64; 3] {
    [0.5 * (p[0][0] + p[1][0]), 0.5 * (p[0][1] + p[1][1]), 0.5 * (p[0][2] + p[1][2])]
}

/// Try to confirm a contact in `b`: a `q` that satisfies the constraints (the centre if
/// every point of the box does, else the scene's witness) whose distance, evaluated
/// again, is ≤ 0.
fn confirm(
    scene: &dyn Scene,
    b: &QBox,
    c: &[f64],
    at_c: &Closest,
    feas: Feasible,
    stats: &mut Stats,
) -> Option<(Vec<f64>, Closest)> {
    if feas == Feasible::All && at_c.distance <= 0.0 {
        return Some((c.to_vec(), at_c.clone()));
    }
    stats.witness_calls += 1;
    let q = scene.witness(&b.lo, &b.hi, c)?;
    if !b.contains(&q) {
        return None;
    }
    stats.distance_calls += 1;
    let d = scene.distance(&q);
    (d.distance <= 0.0).then_some((q, d))
}

/// How many configurations [`probe`] samples per box, and how many candidate contacts
/// per search it may ask the scene to confirm (each a solver call).
const PROBES_PER_BOX: usize = 1;
const PROBE_WITNESSES: usize = 64;
const MIN_WITNESSES: usize = 1024;
/// Probing starts once a search has evaluated this many boxes: most proofs end sooner
/// and pay nothing for it.
const PROBE_AFTER: usize = 3_000;

/// Looks for a contact inside `b` away from its centre: a few configurations drawn from
/// the box (a fixed pseudo-random sequence, so runs repeat), each evaluated where the
/// constraints may hold; one whose solids touch is confirmed like any contact, by the
/// scene's witness in a box around it (half a resolution wide in every dimension) whose
/// distance, evaluated again, is ≤ 0. The centre alone misses contacts that need several
/// coordinates at once (a heading and a position), which splitting by the motion bound
/// does not steer towards. Only ever finds contacts: it proves nothing apart, and a
/// probe that is not confirmed changes nothing.
fn probe(scene: &dyn Scene, b: &QBox, opts: &Options, stats: &mut Stats) -> Option<(Vec<f64>, Closest)> {
    if stats.witness_calls >= PROBE_WITNESSES || stats.nodes < PROBE_AFTER {
        return None;
    }
    for _ in 0..PROBES_PER_BOX {
        stats.probes += 1;
        let q = draw(b, stats.probes);
        if scene.feasible(&q, &q) == Feasible::No {
            continue;
        }
        stats.distance_calls += 1;
        if scene.distance(&q).distance > 0.0 {
            continue;
        }
        if let Some((w, d)) = witness_near(scene, b, &q, opts, stats) {
            if d.distance <= 0.0 {
                return Some((w, d));
            }
        }
        if stats.witness_calls >= PROBE_WITNESSES {
            return None;
        }
    }
    None
}

/// A configuration of `b` that satisfies the constraints (the scene's witness, asked near a
/// probe drawn from the box), with the distance there: an attained upper bound for
/// [`min_distance`]. At most `MIN_WITNESSES` witnesses per search (a clearance has its own
/// time budget, and each witness may lower the attained bound).
fn probe_min(scene: &dyn Scene, b: &QBox, opts: &Options, stats: &mut Stats) -> Option<(Vec<f64>, Closest)> {
    if stats.witness_calls >= MIN_WITNESSES {
        return None;
    }
    stats.probes += 1;
    // The box's centre first (the box popped is the one with the least bound: its centre is
    // where the least distance is likeliest), then drawn configurations.
    let q = if stats.probes % 2 == 1 { b.centre() } else { draw(b, stats.probes) };
    if scene.feasible(&q, &q) == Feasible::No {
        return None;
    }
    witness_near(scene, b, &q, opts, stats).filter(|(_, d)| !d.distance.is_nan())
}

/// The scene's witness (a configuration that satisfies the constraints) in the part of `b`
/// within half a resolution of `q` in every dimension, with the two sides' distance there.
fn witness_near(
    scene: &dyn Scene,
    b: &QBox,
    q: &[f64],
    opts: &Options,
    stats: &mut Stats,
) -> Option<(Vec<f64>, Closest)> {
    let n = q.len();
    let lo: Vec<f64> = (0..n).map(|k| (q[k] - 0.5 * opts.resolution[k]).max(b.lo[k])).collect();
    let hi: Vec<f64> = (0..n).map(|k| (q[k] + 0.5 * opts.resolution[k]).min(b.hi[k])).collect();
    stats.witness_calls += 1;
    let w = scene.witness(&lo, &hi, q).filter(|w| b.contains(w))?;
    stats.distance_calls += 1;
    let d = scene.distance(&w);
    Some((w, d))
}

/// The `seed`-th configuration of a fixed pseudo-random sequence (xorshift64*) in `b`.
fn draw(b: &QBox, seed: usize) -> Vec<f64> {
    let mut s = (seed as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..b.lo.len())
        .map(|k| {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            let u = (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
            (b.lo[k] + u * (b.hi[k] - b.lo[k])).clamp(b.lo[k], b.hi[k])
        })
        .collect()
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
            if let Some((q, at)) = confirm(scene, b, &n.c, &n.at_c, n.feas, stats) {
                out.end = Some(PassEnd::Contact { q, at, box_time: time.map_or(f64::NEG_INFINITY, |t| b.lo[t]) });
                return out;
            }
        }
        if time_ok {
            if let Some((q, at)) = probe(scene, b, opts, stats) {
                out.end = Some(PassEnd::Contact { q, at, box_time: time.map_or(f64::NEG_INFINITY, |t| b.lo[t]) });
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
pub fn decide(scene: &dyn Scene, root: &QBox, opts: &Options) -> Decision {
    let start = Instant::now();
    let mut stats = Stats::default();
    let finish = |outcome: Outcome, mut stats: Stats| {
        stats.elapsed = start.elapsed();
        Decision { outcome, stats }
    };
    if !root.well_formed(scene.dims()) || opts.resolution.len() != scene.dims() {
        return finish(Outcome::Unknown { why: UnknownWhy::BadBox, qbox: root.clone(), unresolved: 1 }, stats);
    }
    let time = opts.time_dim.filter(|&t| t < scene.dims());
    let first = pass(scene, root, opts, false, opts.max_nodes, &mut stats);
    let contact = |q: Vec<f64>, at: Closest, clear_before: Option<f64>| {
        Outcome::Contact(Contact {
            point: midpoint(&at.points),
            points: at.points,
            distance: at.distance,
            names: [scene.solid_name(0, at.solids[0]), scene.solid_name(1, at.solids[1])],
            q,
            clear_before,
        })
    };
    match first.end {
        Some(PassEnd::Contact { q, at, .. }) => {
            let Some(t) = time else {
                return finish(contact(q, at, None), stats);
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
            let (q, at, clear) = match second.end {
                Some(PassEnd::Contact { q: q2, at: at2, box_time }) => (q2, at2, box_time.min(second.unknown_time)),
                Some(PassEnd::Budget { frontier, .. }) => (q, at, frontier.min(second.unknown_time)),
                // Every feasible q with time below q[t] was decided: none touches, except
                // perhaps in boxes left unknown.
                None => {
                    let t1 = q[t];
                    (q, at, t1.min(second.unknown_time))
                }
            };
            finish(contact(q, at, Some(clear.max(root.lo[t]))), stats)
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

// ---------------------------------------------------------------------------------
// A ready scene: parry solids placed by chains of frames.

/// Places a solid: its chain of frames at `q` and their bounds over a box.
pub trait Placer {
    /// The frames at `q`, outermost first.
    fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>>;
    /// The frames' bounds over `[lo, hi]` relative to `centre`, outermost first.
    fn bounds(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Vec<FrameBound>;
}

/// A chain of affine poses.
impl Placer for Vec<AffinePose> {
    fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        self.iter().map(|p| pose_isometry(&p.eval(q))).collect()
    }
    fn bounds(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> Vec<FrameBound> {
        self.iter().map(|p| FrameBound::pose(&p.bounds(lo, hi, centre))).collect()
    }
}

/// One solid: a parry shape in its innermost frame, with a bound on the distance of its
/// points from that frame's origin.
pub struct Solid {
    pub name: String,
    pub shape: SharedShape,
    pub radius: f64,
    pub place: Box<dyn Placer + Send + Sync>,
}

impl Solid {
    /// `radius` is computed from the shape's bounding sphere (padded for f32).
    pub fn new(name: &str, shape: SharedShape, place: Box<dyn Placer + Send + Sync>) -> Solid {
        let s = shape.compute_local_bounding_sphere();
        let radius = s.center().coords.norm() + s.radius();
        Solid { name: name.to_string(), shape, radius: radius * (1.0 + 1e-5) + 1e-9, place }
    }
}

/// Constraints of a [`ParryScene`]: `feasible` and `witness` as in [`Scene`].
pub trait Constraints {
    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible;
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>>;
}

/// No constraints: every `q` of the box.
pub struct Unconstrained;
impl Constraints for Unconstrained {
    fn feasible(&self, _: &[f64], _: &[f64]) -> Feasible {
        Feasible::All
    }
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        Some(near.iter().zip(lo.iter().zip(hi)).map(|(x, (l, h))| x.clamp(*l, *h)).collect())
    }
}

/// Two sides of parry solids, each placed by its own chain. A side with no solid is apart
/// from everything: a caller must reject a body that failed to load rather than pass an
/// empty side.
pub struct ParryScene {
    pub dims: usize,
    pub sides: [Vec<Solid>; 2],
    pub constraints: Box<dyn Constraints + Send + Sync>,
}

/// parry is its f64 build (`parry3d-f64`, Cargo.toml): its isometries are ours. The f32
/// padding below ([`F32_REL`]) is kept although the arithmetic is now f64: it is a
/// conservative margin, far above f64 rounding.
/// The distance of two solids placed at `p1`, `p2` when a side is a convex hull standing
/// for a mesh, measured on the mesh's triangles (not its hull) against the other solid
/// (its triangles too if it is a hull), with the closest points; `None` when parry cannot
/// tell (an unsupported pair).
///
/// What it may be used for: a value `<= 0` is a contact (a mesh's surface that meets the
/// other solid is a point of both solids); a positive value is an upper bound on the
/// solids' distance (the surfaces' closest points are points of the solids; the solids
/// may be closer only if one lies inside a closed mesh, and then their distance is 0).
/// It is never a lower bound: proofs use the hulls.
pub fn mesh_distance(
    s1: &crate::geometry::Solid,
    p1: &Isometry3<f64>,
    s2: &crate::geometry::Solid,
    p2: &Isometry3<f64>,
) -> Option<(f64, [[f64; 3]; 2])> {
    let g1: &dyn parry3d::shape::Shape = if s1.is_hull { s1.mesh()? } else { s1.shape.as_ref() };
    let g2: &dyn parry3d::shape::Shape = if s2.is_hull { s2.mesh()? } else { s2.shape.as_ref() };
    let c = parry3d::query::contact(&to_parry(p1), g1, &to_parry(p2), g2, f64::MAX).ok()??;
    let pt = |p: PPoint<f64>| [p.x, p.y, p.z];
    (!c.dist.is_nan()).then(|| (c.dist, [pt(c.point1), pt(c.point2)]))
}

fn to_parry(iso: &Isometry3<f64>) -> PIso<f64> {
    *iso
}

/// Relative error allowed for f32 geometry (module-level argument in ARCHITECTURE.md):
/// poses rounded to f32 and support points computed in f32 are off by a few units of
/// 2⁻²⁴ of the magnitudes involved (about ten roundings per point); 4e-6 is more than
/// 60 such units of the sum of the magnitudes.
pub const F32_REL: f64 = 4e-6;

/// Relative gap of parry's GJK distance: it stops when `max − min ≤ √(10 ε_f32) · max`
/// (≈ 1.1e-3, parry 0.25 `gjk::closest_points`); used only where no certificate exists.
pub const GJK_REL: f64 = 2.5e-3;

/// The distance of two posed parry shapes with a certified lower bound. For two convex
/// shapes with support maps the lower bound is a separating-plane certificate: along the
/// unit direction `n` between parry's closest points, every point `a` of shape 1 has
/// `n·a ≤ h1(n)` and every `b` of shape 2 has `n·b ≥ −h2(−n)` (support functions), so
/// `|a − b| ≥ −h2(−n) − h1(n)`, computed in f64 from f32 support points and padded for
/// f32 rounding. Otherwise (meshes, compounds) parry's distance shrunk by GJK's relative
/// gap and the same padding. Contacts (distance ≤ 0) get lower = distance − pad.
pub fn parry_closest(
    s1: &SharedShape,
    p1: &Isometry3<f64>,
    s2: &SharedShape,
    p2: &Isometry3<f64>,
) -> (f64, f64, [[f64; 3]; 2]) {
    let (i1, i2) = (to_parry(p1), to_parry(p2));
    let r1 = s1.compute_local_bounding_sphere();
    let r2 = s2.compute_local_bounding_sphere();
    let scale = p1.translation.vector.norm()
        + p2.translation.vector.norm()
        + (r1.center().coords.norm() + r1.radius() + r2.center().coords.norm() + r2.radius());
    let pad = F32_REL * scale + 1e-9;
    let c = parry3d::query::contact(&i1, s1.as_ref(), &i2, s2.as_ref(), f64::MAX);
    let unknown = (f64::NAN, f64::NEG_INFINITY, [[0.0; 3]; 2]);
    let Ok(Some(c)) = c else {
        // Unsupported pair or nothing found: no information (never a pass, never a
        // contact).
        return unknown;
    };
    let pt = |p: PPoint<f64>| [p.x, p.y, p.z];
    let points = [pt(c.point1), pt(c.point2)];
    let dist = c.dist;
    if dist.is_nan() {
        return unknown;
    }
    if dist <= 0.0 {
        return (dist, dist - pad, points);
    }
    let cert = match (s1.as_support_map(), s2.as_support_map()) {
        (Some(m1), Some(m2)) => {
            let n = Vector3::new(points[1][0] - points[0][0], points[1][1] - points[0][1], points[1][2] - points[0][2]);
            let n = if n.norm() > 0.0 { n / n.norm() } else { c.normal1.into_inner() };
            let nf = PVec::new(n.x, n.y, n.z);
            let a = m1.support_point(&i1, &nf);
            let b = m2.support_point(&i2, &-nf);
            let a = Point3::new(a.x, a.y, a.z);
            let b = Point3::new(b.x, b.y, b.z);
            // The certificate uses the f64 direction `n`; the f32 direction `nf` only picks
            // the support points, whose rounding is within the pad (ARCHITECTURE.md).
            n.dot(&b.coords) - n.dot(&a.coords)
        }
        _ => dist * (1.0 - GJK_REL),
    };
    (dist, cert.min(dist) - pad, points)
}

impl ParryScene {
    pub fn new(dims: usize, sides: [Vec<Solid>; 2]) -> ParryScene {
        ParryScene { dims, sides, constraints: Box::new(Unconstrained) }
    }
}

impl Scene for ParryScene {
    fn dims(&self) -> usize {
        self.dims
    }

    fn distance(&self, q: &[f64]) -> Closest {
        let place = |s: &Solid| crate::geometry::placement::compose(&s.place.frames(q));
        let a: Vec<Isometry3<f64>> = self.sides[0].iter().map(place).collect();
        let b: Vec<Isometry3<f64>> = self.sides[1].iter().map(place).collect();
        let mut best = Closest { distance: f64::INFINITY, lower: f64::INFINITY, points: [[0.0; 3]; 2], solids: [0, 0] };
        for (i, (s1, p1)) in self.sides[0].iter().zip(&a).enumerate() {
            for (j, (s2, p2)) in self.sides[1].iter().zip(&b).enumerate() {
                let (d, lower, points) = parry_closest(&s1.shape, p1, &s2.shape, p2);
                // A NaN lower bound is no bound (f64::min would drop it).
                best.lower = if lower.is_nan() { f64::NEG_INFINITY } else { best.lower.min(lower) };
                if d < best.distance || (best.distance.is_nan() && !d.is_nan()) || (i, j) == (0, 0) {
                    best.distance = d;
                    best.points = points;
                    best.solids = [i, j];
                }
            }
        }
        best
    }

    fn motion_bound(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> f64 {
        let side = |s: &Vec<Solid>| {
            s.iter().map(|x| chain_motion_bound(&x.place.bounds(lo, hi, centre), x.radius)).fold(0.0, f64::max)
        };
        // Each side's points move by at most the largest of its solids' bounds.
        (side(&self.sides[0]) + side(&self.sides[1])) * (1.0 + crate::geometry::placement::PAD)
    }

    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
        self.constraints.feasible(lo, hi)
    }

    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        self.constraints.witness(lo, hi, near)
    }

    fn solid_name(&self, side: usize, solid: usize) -> String {
        self.sides
            .get(side)
            .and_then(|s| s.get(solid))
            .map_or_else(|| format!("side {side} solid {solid}"), |s| s.name.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::SharedShape;

    const T: usize = 0;

    /// A solid placed by one affine pose.
    fn solid(name: &str, shape: SharedShape, pose: AffinePose) -> Solid {
        Solid::new(name, shape, Box::new(vec![pose]))
    }

    fn ball(r: f64) -> SharedShape {
        SharedShape::ball(r)
    }

    /// Ball A (r 0.5) moves along x from -5 to 5 over t ∈ [0, 10]; ball B (r 0.5) rests at
    /// (0, y, 0). Their least distance is `y - 1`, at t = 5.
    fn passing_balls(y: f64) -> ParryScene {
        let a = solid("A", ball(0.5), AffinePose::fixed([-5.0, 0.0, 0.0, 0.0, 0.0, 0.0]).with(0, T, 1.0));
        let b = solid("B", ball(0.5), AffinePose::fixed([0.0, y, 0.0, 0.0, 0.0, 0.0]));
        ParryScene::new(1, [vec![a], vec![b]])
    }

    fn opts(res: &[f64]) -> Options {
        let mut o = Options::new(res.to_vec());
        o.time_dim = Some(T);
        o
    }

    fn root1() -> QBox {
        QBox::new(vec![0.0], vec![10.0])
    }

    fn report(name: &str, d: &Decision) {
        eprintln!(
            "{name}: {} nodes, {} distance calls, {} witness calls, {:?}",
            d.stats.nodes, d.stats.distance_calls, d.stats.witness_calls, d.stats.elapsed
        );
    }

    /// The passing balls with the constraint `t >= 6` (after the balls have passed), told to
    /// the search only through `contract` (`feasible` says Maybe everywhere), possibly
    /// answering with a box larger than asked (`widen`: a contraction may only shrink).
    struct AfterSix {
        inner: ParryScene,
        widen: bool,
    }
    impl Scene for AfterSix {
        fn dims(&self) -> usize {
            1
        }
        fn distance(&self, q: &[f64]) -> Closest {
            self.inner.distance(q)
        }
        fn motion_bound(&self, lo: &[f64], hi: &[f64], c: &[f64]) -> f64 {
            self.inner.motion_bound(lo, hi, c)
        }
        fn feasible(&self, _: &[f64], _: &[f64]) -> Feasible {
            Feasible::Maybe
        }
        fn contract(&self, b: &QBox) -> Option<QBox> {
            if self.widen {
                return Some(QBox::new(vec![b.lo[0] - 100.0], vec![b.hi[0] + 100.0]));
            }
            let lo = b.lo[0].max(6.0);
            (lo <= b.hi[0]).then(|| QBox::new(vec![lo], b.hi.clone()))
        }
        fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
            let lo = [lo[0].max(6.0)];
            (lo[0] <= hi[0]).then(|| Unconstrained.witness(&lo, hi, near)).flatten()
        }
        fn solid_name(&self, side: usize, solid: usize) -> String {
            self.inner.solid_name(side, solid)
        }
    }

    /// A box is evaluated after contraction: its centre and motion bound are the narrowed
    /// box's. Balls touching at t = 5 (y = 0.9) are apart for t >= 6, which the search proves
    /// in a few boxes only through the contraction; a contraction answering a larger box is
    /// intersected with the box, so the touching balls are still found (never lost).
    #[test]
    fn a_contracted_box_is_evaluated_and_a_contraction_only_shrinks() {
        let s = AfterSix { inner: passing_balls(0.9), widen: false };
        let d = decide(&s, &root1(), &opts(&[1e-4]));
        report("after six", &d);
        assert!(matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
        assert!(d.stats.nodes <= 3, "{:?}", d.stats);
        let w = AfterSix { inner: passing_balls(0.9), widen: true };
        let d = decide(&w, &root1(), &opts(&[1e-4]));
        // The widened answer is cut back to the box; the witness still only looks at t >= 6,
        // so no contact is confirmed there, but nothing is proved apart either.
        assert!(!matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
    }

    #[test]
    fn grazing_balls_1e_3_apart_are_proved_apart() {
        let s = passing_balls(1.001);
        let d = decide(&s, &root1(), &opts(&[1e-4]));
        report("grazing 1e-3", &d);
        match d.outcome {
            Outcome::Apart { min_lower_bound, .. } => {
                assert!(min_lower_bound > 0.0 && min_lower_bound <= 1e-3 + 1e-6, "{min_lower_bound}");
            }
            o => panic!("expected apart, got {o:?}"),
        }
    }

    #[test]
    fn penetrating_balls_1e_3_deep_contact_at_the_first_time_and_place() {
        let s = passing_balls(0.999);
        let d = decide(&s, &root1(), &opts(&[1e-4]));
        report("penetrating 1e-3", &d);
        let Outcome::Contact(c) = d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
        // First touch: (t - 5)^2 + 0.999^2 = 1.
        let first = 5.0 - (1.0f64 - 0.999 * 0.999).sqrt();
        let before = c.clear_before.unwrap();
        assert!(before <= first + 1e-5, "clear before {before} > first contact {first}");
        // Boxes in the band where the distance is below the pads stay unknown: the
        // guaranteed window [clear_before, q] is a little wider than the resolution.
        assert!(c.q[0] >= first - 1e-5 && c.q[0] - before <= 2e-3, "{c:?}");
        assert!(c.distance <= 0.0);
        assert_eq!(c.names, ["A".to_string(), "B".to_string()]);
        // Near the first touch the contact point lies on the segment between the centres,
        // at half the way: ((t - 5) / 2, 0.4995, 0).
        assert!((c.point[0] - (c.q[0] - 5.0) / 2.0).abs() < 1e-3, "{:?}", c.point);
        assert!((c.point[1] - 0.4995).abs() < 1e-3, "{:?}", c.point);
    }

    #[test]
    fn the_first_of_two_contacts_is_reported() {
        // A passes B2 (at x = -2) before B1 (at x = 2).
        let a = solid("A", ball(0.5), AffinePose::fixed([-5.0, 0.0, 0.0, 0.0, 0.0, 0.0]).with(0, T, 1.0));
        let b1 = solid("B1", ball(0.5), AffinePose::fixed([2.0, 0.5, 0.0, 0.0, 0.0, 0.0]));
        let b2 = solid("B2", ball(0.5), AffinePose::fixed([-2.0, 0.5, 0.0, 0.0, 0.0, 0.0]));
        let s = ParryScene::new(1, [vec![a], vec![b1, b2]]);
        let d = decide(&s, &root1(), &opts(&[1e-3]));
        let Outcome::Contact(c) = d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
        assert_eq!(c.names[1], "B2");
        let first = 3.0 - 0.75f64.sqrt();
        assert!(c.clear_before.unwrap() <= first && c.q[0] - first < 2e-3, "{c:?}");
    }

    /// A bar (4 x 0.1 x 0.1, centred on the origin) turning about z by yaw = t, t ∈ [0, π],
    /// and a box of side 0.4 turned by 30° with its centre at (c, c, 0).
    fn turning_bar(c: f64) -> ParryScene {
        let bar = solid("bar", SharedShape::cuboid(2.0, 0.05, 0.05), AffinePose::fixed([0.0; 6]).with(5, T, 1.0));
        let obstacle = solid(
            "box",
            SharedShape::cuboid(0.2, 0.2, 0.2),
            AffinePose::fixed([c, c, 0.0, 0.0, 0.0, 30f64.to_radians()]),
        );
        ParryScene::new(1, [vec![bar], vec![obstacle]])
    }

    #[test]
    fn turning_bar_sweeping_past_a_turned_box() {
        let root = QBox::new(vec![0.0], vec![std::f64::consts::PI]);
        // The box's nearest point is about 2.12 - 0.27 = 1.85 < 2 from the axis: contact.
        let d = decide(&turning_bar(1.5), &root, &opts(&[1e-4]));
        report("turning bar, contact", &d);
        let Outcome::Contact(c) = &d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
        assert!(c.q[0] > 0.5 && c.q[0] < std::f64::consts::FRAC_PI_4, "{c:?}");
        assert_eq!(c.names, ["bar".to_string(), "box".to_string()]);
        // Far enough: the box's nearest point is about 2.4 - 0.27 > 2.0006.
        let d = decide(&turning_bar(1.7), &root, &opts(&[1e-4]));
        report("turning bar, apart", &d);
        assert!(matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
        assert!(d.stats.nodes < 5_000, "{:?}", d.stats);
    }

    /// `t ≤ limit`.
    struct Before(f64);
    impl Constraints for Before {
        fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
            if lo[T] > self.0 {
                Feasible::No
            } else if hi[T] <= self.0 {
                Feasible::All
            } else {
                Feasible::Maybe
            }
        }
        fn witness(&self, lo: &[f64], _hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
            (lo[T] <= self.0).then(|| vec![near[T].min(self.0)])
        }
    }

    #[test]
    fn an_infeasible_collision_is_apart() {
        let mut s = passing_balls(0.5);
        s.constraints = Box::new(Before(4.0));
        let d = decide(&s, &root1(), &opts(&[1e-4]));
        report("infeasible collision", &d);
        match d.outcome {
            Outcome::Apart { infeasible, .. } => assert!(infeasible > 0),
            o => panic!("expected apart, got {o:?}"),
        }
        // Without the constraint it collides (the test can fail).
        let s = passing_balls(0.5);
        assert!(matches!(decide(&s, &root1(), &opts(&[1e-4])).outcome, Outcome::Contact(_)));
    }

    #[test]
    fn everywhere_infeasible_is_apart_but_vacuous() {
        let mut s = passing_balls(0.0);
        s.constraints = Box::new(Before(-1.0));
        let d = decide(&s, &root1(), &opts(&[1e-4]));
        assert!(d.outcome.is_vacuous(), "{:?}", d.outcome);
        let mut s = passing_balls(0.0);
        s.constraints = Box::new(Before(4.0));
        assert!(!decide(&s, &root1(), &opts(&[1e-4])).outcome.is_vacuous());
    }

    #[test]
    fn closer_than_the_resolution_is_unknown() {
        // 1e-7 apart: beyond what a coarse resolution can prove, and not a contact.
        let s = passing_balls(1.0 + 1e-7);
        let d = decide(&s, &root1(), &opts(&[0.05]));
        match d.outcome {
            Outcome::Unknown { why: UnknownWhy::Resolution, qbox, .. } => {
                assert!(qbox.lo[0] >= 4.0 && qbox.hi[0] <= 6.0, "{qbox:?}")
            }
            o => panic!("expected unknown, got {o:?}"),
        }
    }

    #[test]
    fn budgets_exhausted_are_unknown() {
        let s = passing_balls(1.001);
        let mut o = opts(&[1e-4]);
        o.max_nodes = 5;
        let d = decide(&s, &root1(), &o);
        assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::Nodes(5), .. }), "{:?}", d.outcome);
        let mut o = opts(&[1e-4]);
        o.deadline = Some(Instant::now());
        let d = decide(&s, &root1(), &o);
        assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::Deadline, .. }), "{:?}", d.outcome);
    }

    #[test]
    fn malformed_boxes_are_unknown() {
        let s = passing_balls(2.0);
        for b in [
            QBox::new(vec![0.0, 1.0], vec![1.0, 2.0]),
            QBox::new(vec![1.0], vec![0.0]),
            QBox::new(vec![0.0], vec![f64::INFINITY]),
            QBox::new(vec![f64::NAN], vec![1.0]),
        ] {
            let d = decide(&s, &b, &opts(&[1e-3]));
            assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::BadBox, .. }));
        }
    }

    #[test]
    fn certified_lower_bound_is_below_the_true_distance() {
        // Two unit cubes 0.25 apart, one turned: the exact distance is known.
        let s1 = SharedShape::cuboid(0.5, 0.5, 0.5);
        let p1 = pose_isometry(&[0.0; 6]);
        let p2 = pose_isometry(&[1.25, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let (d, lower, _) = parry_closest(&s1, &p1, &s1, &p2);
        assert!((d - 0.25).abs() < 1e-5 && lower <= 0.25 && lower > 0.2499, "{d} {lower}");
        // A sphere against a cube corner: sqrt(3) * 2 - 0.5*sqrt(3) - 1.
        let b = SharedShape::ball(1.0);
        let p2 = pose_isometry(&[2.0, 2.0, 2.0, 0.0, 0.0, 0.0]);
        let truth = 2.0 * 3f64.sqrt() - 0.5 * 3f64.sqrt() - 1.0;
        let (d, lower, _) = parry_closest(&s1, &p1, &b, &p2);
        assert!((d - truth).abs() < 1e-4 && lower <= truth && lower > truth - 1e-4, "{d} {lower}");
    }

    /// Property: for random turned boxes against balls (whose exact distance is the
    /// distance from the ball's centre to the box, in the box's frame, minus the radius),
    /// the certified lower bound never exceeds the truth and is close to it.
    #[test]
    fn certified_lower_bound_on_random_box_ball_pairs() {
        use crate::geometry::placement::tests::Rng;
        let mut rng = Rng::new(17);
        let mut worst: f64 = 0.0;
        for _ in 0..2000 {
            // Lengths representable in f32, so parry's shapes are exactly these.
            let mut f = |a: f64, b: f64| rng.range(a, b);
            let h = [f(0.05, 1.0), f(0.05, 1.0), f(0.05, 1.0)];
            let cube = SharedShape::cuboid(h[0], h[1], h[2]);
            let args = [
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
            ];
            let p1 = pose_isometry(&args);
            let r = rng.range(0.05, 1.0);
            let centre = Point3::new(
                args[0] + rng.range(-3.0, 3.0),
                args[1] + rng.range(-3.0, 3.0),
                args[2] + rng.range(-3.0, 3.0),
            );
            let p2 = Isometry3::translation(centre.x, centre.y, centre.z);
            let local = p1.inverse_transform_point(&centre);
            let out = Vector3::new(
                (local.x.abs() - h[0]).max(0.0),
                (local.y.abs() - h[1]).max(0.0),
                (local.z.abs() - h[2]).max(0.0),
            );
            let truth = out.norm() - r;
            if truth <= 1e-3 {
                continue;
            }
            let (d, lower, _) = parry_closest(&cube, &p1, &SharedShape::ball(r), &p2);
            assert!(lower <= truth, "lower {lower} above the truth {truth} (parry {d})");
            worst = worst.max(truth - lower);
        }
        assert!(worst < 1e-3, "certificate too loose: {worst}");
    }

    #[test]
    fn clearance_of_passing_balls() {
        let s = passing_balls(2.0);
        let c = min_distance(&s, &root1(), 1e-4, &opts(&[1e-6]));
        eprintln!("clearance: {c:?}");
        assert!(c.complete, "{c:?}");
        assert!(c.lower <= 1.0 && c.upper >= 1.0 - 1e-5 && c.upper - c.lower <= 1e-4, "{c:?}");
        let q = c.at_q.unwrap();
        assert!((q[0] - 5.0).abs() < 0.05, "{q:?}");
        assert_eq!(c.names.unwrap(), ["A".to_string(), "B".to_string()]);
        // With the constraint t ≤ 4 the least distance is at t = 4: sqrt(1 + 4) - 1.
        let mut s = passing_balls(2.0);
        s.constraints = Box::new(Before(4.0));
        let c = min_distance(&s, &root1(), 1e-4, &opts(&[1e-6]));
        let truth = 5f64.sqrt() - 1.0;
        assert!(c.lower <= truth && c.upper >= truth - 1e-5 && c.upper - c.lower <= 1e-4, "{c:?}");
        assert!(c.at_q.unwrap()[0] <= 4.0);
    }

    /// Property: random scenes of two to four solids in two dimensions (time and an
    /// angle): apart means dense sampling finds no contact (and no distance below the
    /// claimed lower bound); contact means the returned `q` is in the box and touches.
    #[test]
    fn random_scenes_agree_with_sampling() {
        use crate::geometry::placement::tests::Rng;
        let mut rng = Rng::new(3);
        let (mut apart, mut contact, mut unknown) = (0, 0, 0);
        for case in 0..60 {
            let shape = |rng: &mut Rng| match (rng.next() * 3.0) as usize {
                0 => SharedShape::ball(rng.range(0.1, 0.6)),
                1 => SharedShape::cuboid(rng.range(0.05, 0.6), rng.range(0.05, 0.6), rng.range(0.05, 0.6)),
                _ => SharedShape::capsule_z(rng.range(0.05, 0.5), rng.range(0.05, 0.3)),
            };
            let pose = |rng: &mut Rng| {
                let mut p = AffinePose::fixed([
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-0.5, 0.5),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ]);
                for j in 0..6 {
                    for i in 0..2 {
                        if rng.next() < 0.3 {
                            p = p.with(j, i, rng.range(-1.0, 1.0));
                        }
                    }
                }
                p
            };
            let side = |rng: &mut Rng, tag: &str| -> Vec<Solid> {
                (0..1 + (rng.next() * 2.0) as usize)
                    .map(|k| {
                        let chain: Vec<AffinePose> = (0..1 + (rng.next() * 2.0) as usize).map(|_| pose(rng)).collect();
                        Solid::new(&format!("{tag}{k}"), shape(rng), Box::new(chain))
                    })
                    .collect()
            };
            let s = ParryScene::new(2, [side(&mut rng, "a"), side(&mut rng, "b")]);
            let root = QBox::new(vec![0.0, -1.0], vec![2.0, 1.0]);
            let mut o = Options::new(vec![1e-3, 1e-3]);
            o.time_dim = if case % 2 == 0 { Some(0) } else { None };
            o.split = if case % 3 == 0 { SplitRule::WidestScaled } else { SplitRule::Sensitivity };
            let d = decide(&s, &root, &o);
            match &d.outcome {
                Outcome::Apart { min_lower_bound, .. } => {
                    apart += 1;
                    for i in 0..=40 {
                        for j in 0..=40 {
                            let q = [2.0 * i as f64 / 40.0, -1.0 + 2.0 * j as f64 / 40.0];
                            let x = s.distance(&q).distance;
                            assert!(x > 0.0, "case {case}: apart, but distance {x} at {q:?}");
                            assert!(x >= min_lower_bound - 1e-4, "case {case}: {x} < {min_lower_bound}");
                        }
                    }
                }
                Outcome::Contact(c) => {
                    contact += 1;
                    assert!(root.contains(&c.q) && s.distance(&c.q).distance <= 0.0, "case {case}: {c:?}");
                }
                Outcome::Unknown { .. } => unknown += 1,
            }
        }
        eprintln!("random scenes: {apart} apart, {contact} contact, {unknown} unknown");
        assert!(apart > 5 && contact > 5, "{apart} apart, {contact} contact");
    }

    /// An arm on a cart, in four dimensions `(t, θ1, θ2, θ3)`: the cart drives along x
    /// (x = -3 + t) while turning (yaw = 0.5 t), the arm's three revolute joints range
    /// over [-0.5, 0.5] each (shoulder yaw θ1, elbow pitch θ2, wrist pitch θ3), and a
    /// pillar stands at (0, y, 0). Sampling cross-checks the verdict.
    fn mounted_arm(pillar_y: f64) -> ParryScene {
        let cart = || AffinePose::fixed([-3.0, 0.0, 0.1, 0.0, 0.0, 0.0]).with(0, 0, 1.0).with(5, 0, 0.5);
        let j1 = || AffinePose::fixed([0.0, 0.0, 0.2, 0.0, 0.0, 0.0]).with(5, 1, 1.0);
        let j2 = || AffinePose::fixed([0.0, 0.0, 0.1, 0.0, 0.0, 0.0]).with(4, 2, 1.0);
        let j3 = || AffinePose::fixed([0.0, 0.0, 0.4, 0.0, 0.0, 0.0]).with(4, 3, 1.0);
        // A link: a capsule from its joint's origin up its z axis, `len` long.
        let link = |len: f64| AffinePose::fixed([0.0, 0.0, len / 2.0, 0.0, 0.0, 0.0]);
        let side0 = vec![
            Solid::new("cart", SharedShape::cuboid(0.3, 0.2, 0.1), Box::new(vec![cart()])),
            Solid::new("base", SharedShape::ball(0.08), Box::new(vec![cart(), j1()])),
            Solid::new("upper", SharedShape::capsule_z(0.2, 0.05), Box::new(vec![cart(), j1(), j2(), link(0.4)])),
            Solid::new("fore", SharedShape::capsule_z(0.2, 0.04), Box::new(vec![cart(), j1(), j2(), j3(), link(0.4)])),
        ];
        let pillar = Solid::new(
            "pillar",
            // parry's cylinder stands on y; roll 90° stands it on z.
            SharedShape::cylinder(1.0, 0.15),
            Box::new(vec![AffinePose::fixed([0.0, pillar_y, 1.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0])]),
        );
        ParryScene::new(4, [side0, vec![pillar]])
    }

    fn arm_root() -> QBox {
        QBox::new(vec![0.0, -0.5, -0.5, -0.5], vec![6.0, 0.5, 0.5, 0.5])
    }

    fn sampled_min(s: &ParryScene, n: usize) -> f64 {
        let r = arm_root();
        let mut m = f64::INFINITY;
        let mut rng = crate::geometry::placement::tests::Rng::new(5);
        for _ in 0..n {
            let q: Vec<f64> = r.lo.iter().zip(&r.hi).map(|(l, h)| rng.range(*l, *h)).collect();
            m = m.min(s.distance(&q).distance);
        }
        m
    }

    #[test]
    fn mounted_arm_past_a_pillar() {
        let mut o = Options::new(vec![1e-3; 4]);
        o.time_dim = Some(0);
        let apart = mounted_arm(0.9);
        let d = decide(&apart, &arm_root(), &o);
        report("mounted arm, apart", &d);
        let Outcome::Apart { min_lower_bound, .. } = d.outcome else { panic!("expected apart, got {:?}", d.outcome) };
        let sampled = sampled_min(&apart, 3000);
        assert!(min_lower_bound > 0.0 && sampled >= min_lower_bound, "{sampled} {min_lower_bound}");
        let touching = mounted_arm(0.6);
        // Coarser in the joints: the first-contact pass resolves the grazing band box by box.
        o.resolution = vec![1e-3, 1e-2, 1e-2, 1e-2];
        let d = decide(&touching, &arm_root(), &o);
        report("mounted arm, contact", &d);
        let Outcome::Contact(c) = &d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
        eprintln!("  at {:?}, clear before {:?}", c.q, c.clear_before);
        assert!(touching.distance(&c.q).distance <= 0.0 && c.names[1] == "pillar", "{c:?}");
        let mut any = o.clone();
        any.time_dim = None;
        let d = decide(&touching, &arm_root(), &any);
        report("mounted arm, any contact", &d);
        assert!(matches!(d.outcome, Outcome::Contact(_)), "{:?}", d.outcome);
        let o = Options::new(vec![1e-3; 4]);
        let c = min_distance(&apart, &arm_root(), 2e-2, &o);
        eprintln!(
            "mounted arm clearance: [{}, {}] at {:?} ({:?}), {} nodes, {:?}",
            c.lower, c.upper, c.at_q, c.names, c.stats.nodes, c.stats.elapsed
        );
        assert!(c.lower <= sampled && c.lower > 0.0, "{c:?}");
    }
}
