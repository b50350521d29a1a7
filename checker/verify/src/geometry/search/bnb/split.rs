//! Choosing the dimension to split, narrowing a box by the scene's contraction, and the
//! probes that look for a contact at drawn configurations (docs/soundness-geometry.md,
//! "Probes").

use super::*;

/// Dimension `k` of `b` is at its resolution: no wider than it, or too narrow for f64 to
/// hold a midpoint strictly inside (so splitting would not shrink it).
pub(super) fn widths_ok(b: &QBox, res: &[f64], k: usize) -> bool {
    let (l, h) = (b.lo[k], b.hi[k]);
    let mid = l + 0.5 * (h - l);
    h - l <= res.get(k).copied().unwrap_or(0.0) || mid <= l || mid >= h
}

pub(super) fn at_resolution(b: &QBox, res: &[f64]) -> bool {
    (0..b.lo.len()).all(|k| widths_ok(b, res, k))
}

/// The dimension to split (one that is above its resolution; `None` if none is).
pub(super) fn choose_split(
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
pub(super) fn narrowed(scene: &dyn Scene, b: QBox) -> Option<QBox> {
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

pub(super) fn count_split(stats: &mut Stats, k: usize) {
    if stats.splits.len() <= k {
        stats.splits.resize(k + 1, 0);
    }
    stats.splits[k] += 1;
}

pub(super) fn midpoint(p: &[[f64; 3]; 2]) -> [f64; 3] {
    [0.5 * (p[0][0] + p[1][0]), 0.5 * (p[0][1] + p[1][1]), 0.5 * (p[0][2] + p[1][2])]
}

/// Try to confirm a contact in `b`: a `q` that satisfies the constraints (the centre if
/// every point of the box does, else the scene's witness) whose distance, evaluated
/// again, is ≤ 0.
pub(super) fn confirm(
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

/// A confirmed contact with the point it is shown at ([`Scene::contact_point`]): a contact
/// whose sides share no point the scene can find is not confirmed.
pub(super) fn located(scene: &dyn Scene, found: Option<(Vec<f64>, Closest)>) -> Option<(Vec<f64>, Closest, [f64; 3])> {
    let (q, at) = found?;
    let point = scene.contact_point(&q, &at)?;
    Some((q, at, point))
}

/// How many configurations [`probe`] samples per box, and how many candidate contacts
/// per search it may ask the scene to confirm (each a solver call).
pub(super) const PROBES_PER_BOX: usize = 1;
pub(super) const PROBE_WITNESSES: usize = 64;
pub(super) const MIN_WITNESSES: usize = 1024;
/// Probing starts once a search has evaluated this many boxes (or spent a tenth of its
/// time, `bnb::probing`): most proofs end sooner and pay nothing for it.
pub(super) const PROBE_AFTER: usize = 3_000;

/// Looks for a contact inside `b` away from its centre: a few configurations drawn from
/// the box (a fixed pseudo-random sequence, so runs repeat), each evaluated where the
/// constraints may hold; one whose solids touch is confirmed like any contact, by the
/// scene's witness in a box around it (half a resolution wide in every dimension) whose
/// distance, evaluated again, is ≤ 0. The centre alone misses contacts that need several
/// coordinates at once (a heading and a position), which splitting by the motion bound
/// does not steer towards. Only ever finds contacts: it proves nothing apart, and a
/// probe that is not confirmed changes nothing.
pub(super) fn probe(
    scene: &dyn Scene,
    b: &QBox,
    opts: &Options,
    probing: bool,
    stats: &mut Stats,
) -> Option<(Vec<f64>, Closest, [f64; 3])> {
    if stats.witness_calls >= PROBE_WITNESSES || !probing {
        return None;
    }
    for _ in 0..PROBES_PER_BOX {
        stats.probes += 1;
        let Some(q) = draw_contracted(scene, b, stats.probes) else { continue };
        if scene.feasible(&q, &q) == Feasible::No {
            continue;
        }
        stats.distance_calls += 1;
        if scene.distance(&q).distance > 0.0 {
            continue;
        }
        if let Some((w, d)) = witness_near(scene, b, &q, opts, stats) {
            if d.distance <= 0.0 {
                if let Some(found) = located(scene, Some((w, d))) {
                    return Some(found);
                }
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
pub(super) fn probe_min(scene: &dyn Scene, b: &QBox, opts: &Options, stats: &mut Stats) -> Option<(Vec<f64>, Closest)> {
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
pub(super) fn witness_near(
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

/// A configuration of `b` drawn one dimension at a time, the box contracted to the
/// constraints ([`Scene::contract`]) after each value is fixed: a thin band (a joint that
/// follows the clock within a tracking error, a position on an annulus) is drawn inside
/// rather than hit by chance. `None` when a contraction leaves nothing (the values drawn so
/// far satisfy no constraint). Only a candidate: it is confirmed as any probe.
pub(super) fn draw_contracted(scene: &dyn Scene, b: &QBox, seed: usize) -> Option<Vec<f64>> {
    let q = draw(b, seed);
    let mut cur = b.clone();
    for (k, &x) in q.iter().enumerate() {
        let v = if cur.lo[k] <= x && x <= cur.hi[k] {
            x
        } else {
            // The draw's uniform share of the contracted range.
            let u = (x - b.lo[k]) / (b.hi[k] - b.lo[k]);
            let u = if u.is_finite() { u } else { 0.5 };
            (cur.lo[k] + u * (cur.hi[k] - cur.lo[k])).clamp(cur.lo[k], cur.hi[k])
        };
        cur.lo[k] = v;
        cur.hi[k] = v;
        // Intersected with the box, a malformed answer ignored ([`narrowed`]).
        cur = narrowed(scene, cur)?;
        if !cur.lo.iter().zip(&cur.hi).all(|(l, h)| l <= h) {
            return None;
        }
    }
    Some(cur.lo)
}

/// The `seed`-th configuration of a fixed pseudo-random sequence (xorshift64*) in `b`.
pub(super) fn draw(b: &QBox, seed: usize) -> Vec<f64> {
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
