//! Sound bounds on how far a placed point can move while the configuration `q` ranges
//! over a box: the motion term of the branch and bound
//! (`checker/verify/src/geometry/search/bnb.rs`, ARCHITECTURE.md "Geometric decision procedure").
//!
//! A frame places its children by `x ↦ R x + t`, a rigid motion. A part's world place is
//! a chain of frames, outermost first: a participant's `at:` pose, a carrier's mount
//! frame, the part's own `pose(...)`, then the joints of a URDF tree. Each frame's
//! arguments are functions of `q`; the caller encloses them over a box (interval
//! evaluation, outward rounded) and evaluates them at the box's centre `c`.
//!
//! **One frame.** For a point `y` in the frame's own coordinates,
//! `|T(q) y − T(c) y| = |(R(q) − R(c)) y + t(q) − t(c)| ≤ ‖R(q) − R(c)‖ |y| + |t(q) − t(c)|`.
//! With `R = Rz(yaw) Ry(pitch) Rx(roll)`:
//! `‖R_a R_b R_c − R_a' R_b' R_c'‖ ≤ ‖R_a − R_a'‖ + ‖R_b − R_b'‖ + ‖R_c − R_c'‖`
//! (telescoping, each factor of norm 1), and an elementary rotation is 1-Lipschitz in
//! its angle in operator norm (`‖R(a) − R(a')‖ = 2 |sin((a − a')/2)| ≤ |a − a'|`); also
//! `‖R − R'‖ ≤ 2` for any two rotations. The same holds for a rotation about any fixed
//! unit axis (a URDF revolute joint).
//!
//! **A chain.** With frames `T_1 … T_n` (outermost first) and a point `p` of the part,
//! `T_1(q)…T_n(q) p − T_1(c)…T_n(c) p = Σ_k T_1(c)…T_{k−1}(c) [T_k(q) y_k] − T_1(c)…T_{k−1}(c) [T_k(c) y_k]`
//! with `y_k = T_{k+1}(q)…T_n(q) p` (telescoping; the prefix at `c` is a rigid motion, so
//! it preserves the distance between the two points it maps). Hence the displacement
//! is at most `Σ_k (|Δt_k| + ‖ΔR_k‖ |y_k|)`, and `|y_k| ≤ |p| + Σ_{j>k} max_q |t_j(q)|`
//! because rotations preserve norms: a bound independent of the configuration within
//! the box. `|p| ≤ radius`, the part's bounding radius about its own frame's origin.
//!
//! **Rounding.** The bounds are sums, products and square roots of non-negative f64
//! numbers, each operation with relative error at most 2⁻⁵³; a chain of `n` frames takes
//! fewer than `8 n` operations, so the result is padded by the relative factor
//! `1 + PAD` (`PAD = 1e-9` covers chains of any length below ten million frames).
//! The interval enclosures themselves must be outward rounded by the caller. A bound
//! that is not finite (an unbounded or NaN argument) is `+∞`: never a pass.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

/// Relative padding of every motion bound for f64 rounding (module doc).
pub const PAD: f64 = 1e-9;

/// The enclosure of a frame's six pose arguments `[x, y, z, roll, pitch, yaw]` over a
/// box of `q`, and their values at the box's centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArgBounds {
    pub centre: [f64; 6],
    pub lo: [f64; 6],
    pub hi: [f64; 6],
}

impl ArgBounds {
    /// A frame that does not depend on `q`.
    pub fn fixed(args: [f64; 6]) -> ArgBounds {
        ArgBounds { centre: args, lo: args, hi: args }
    }

    /// `max |arg_i(q) − arg_i(c)|` over the box. Sound even if the centre value lies (by
    /// rounding) slightly outside `[lo, hi]`.
    fn dev(&self, i: usize) -> f64 {
        amax(self.hi[i] - self.centre[i], self.centre[i] - self.lo[i])
    }
}

/// `max(|a|, |b|)`, NaN-propagating as +∞ (f64::max would silently drop a NaN).
fn amax(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::INFINITY
    } else {
        a.abs().max(b.abs())
    }
}

/// NaN becomes +∞ (f64::max would silently drop it).
fn nan_inf(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x
    }
}

/// What the chain bound needs of one frame, over a box: `dt ≥ max |t(q) − t(c)|`,
/// `drot ≥ max ‖R(q) − R(c)‖`, `reach ≥ max |t(q)|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameBound {
    pub dt: f64,
    pub drot: f64,
    pub reach: f64,
}

impl FrameBound {
    /// A `pose(x, y, z, roll, pitch, yaw)` frame (rotation `Rz(yaw) Ry(pitch) Rx(roll)`).
    pub fn pose(a: &ArgBounds) -> FrameBound {
        let dt = (sq(a.dev(0)) + sq(a.dev(1)) + sq(a.dev(2))).sqrt();
        let drot = (a.dev(3).min(2.0) + a.dev(4).min(2.0) + a.dev(5).min(2.0)).min(2.0);
        let mag = |i: usize| amax(amax(a.lo[i], a.hi[i]), a.centre[i]);
        let reach = (sq(mag(0)) + sq(mag(1)) + sq(mag(2))).sqrt();
        FrameBound { dt: nan_inf(dt), drot: nan_inf(drot), reach: nan_inf(reach) }
    }

    /// A fixed frame (a URDF joint's origin): it moves nothing relative to its parent.
    pub fn fixed(args: [f64; 6]) -> FrameBound {
        FrameBound::pose(&ArgBounds::fixed(args))
    }

    /// A rotation about a fixed unit axis by an angle in `[lo, hi]`, centre value `c`
    /// (a URDF revolute or continuous joint).
    pub fn revolute(lo: f64, hi: f64, c: f64) -> FrameBound {
        let d = amax(hi - c, c - lo);
        FrameBound { dt: 0.0, drot: d.min(2.0), reach: 0.0 }
    }

    /// A translation along a fixed unit axis by an amount in `[lo, hi]`, centre value `c`
    /// (a URDF prismatic joint).
    pub fn prismatic(lo: f64, hi: f64, c: f64) -> FrameBound {
        FrameBound { dt: amax(hi - c, c - lo), drot: 0.0, reach: amax(amax(lo, hi), c) }
    }
}

fn sq(x: f64) -> f64 {
    x * x
}

/// Upper bound on `|T_1(q)…T_n(q) p − T_1(c)…T_n(c) p|` for every `q` in the box and
/// every point `p` with `|p| ≤ radius` in the innermost frame's coordinates; `frames`
/// outermost first (module doc for the argument). An empty chain moves nothing.
pub fn chain_motion_bound(frames: &[FrameBound], radius: f64) -> f64 {
    let mut reach = nan_inf(radius.abs());
    let mut total = 0.0;
    for f in frames.iter().rev() {
        total += f.dt + f.drot * reach;
        reach += f.reach;
    }
    let b = total * (1.0 + PAD);
    if b.is_nan() {
        f64::INFINITY
    } else {
        b
    }
}

/// Upper bound on `|T_1(q)…T_n(q) 0|`, the distance of the innermost frame's origin from
/// the world origin, for every `q` in the box (rotations preserve norms).
pub fn chain_reach(frames: &[FrameBound]) -> f64 {
    nan_inf(frames.iter().map(|f| f.reach).sum::<f64>() * (1.0 + PAD))
}

/// The rigid motion of `pose(x, y, z, roll, pitch, yaw)`: `Rz(yaw) Ry(pitch) Rx(roll)`,
/// then the translation (nalgebra's `from_euler_angles` is exactly that order).
pub fn pose_isometry(a: &[f64; 6]) -> Isometry3<f64> {
    let r = Rotation3::from_euler_angles(a[3], a[4], a[5]);
    Isometry3::from_parts(Translation3::new(a[0], a[1], a[2]), UnitQuaternion::from_rotation_matrix(&r))
}

/// A rotation by `angle` about the unit `axis`.
pub fn axis_isometry(axis: [f64; 3], angle: f64) -> Isometry3<f64> {
    let axis = Unit::new_normalize(Vector3::new(axis[0], axis[1], axis[2]));
    Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&axis, angle))
}

/// The composition of frames, outermost first.
pub fn compose(frames: &[Isometry3<f64>]) -> Isometry3<f64> {
    frames.iter().fold(Isometry3::identity(), |acc, f| acc * f)
}

/// A pose whose six arguments are affine in `q`: `arg_j(q) = b_j + Σ_i a_ji q_i`. Its
/// interval enclosure over a box is exact up to rounding (padded by one part in 10⁹ of
/// the magnitudes involved). Used by tests and by callers whose poses are affine.
#[derive(Clone, Debug, PartialEq)]
pub struct AffinePose {
    pub constant: [f64; 6],
    /// `coeff[j][i]`: the coefficient of `q_i` in argument `j`.
    pub coeff: [Vec<f64>; 6],
}

impl AffinePose {
    pub fn fixed(constant: [f64; 6]) -> AffinePose {
        AffinePose { constant, coeff: Default::default() }
    }

    /// Adds `k q_i` to argument `j` (builder).
    pub fn with(mut self, j: usize, i: usize, k: f64) -> AffinePose {
        if self.coeff[j].len() <= i {
            self.coeff[j].resize(i + 1, 0.0);
        }
        self.coeff[j][i] += k;
        self
    }

    pub fn eval(&self, q: &[f64]) -> [f64; 6] {
        let mut out = self.constant;
        for (j, o) in out.iter_mut().enumerate() {
            for (i, k) in self.coeff[j].iter().enumerate() {
                *o += k * q.get(i).copied().unwrap_or(0.0);
            }
        }
        out
    }

    pub fn bounds(&self, lo: &[f64], hi: &[f64], centre: &[f64]) -> ArgBounds {
        let mut l = self.constant;
        let mut h = self.constant;
        for j in 0..6 {
            let mut mag = self.constant[j].abs();
            for (i, &k) in self.coeff[j].iter().enumerate() {
                let (a, b) = (k * lo.get(i).copied().unwrap_or(0.0), k * hi.get(i).copied().unwrap_or(0.0));
                l[j] += a.min(b);
                h[j] += a.max(b);
                mag += a.abs().max(b.abs());
            }
            let pad = mag * PAD;
            l[j] -= pad;
            h[j] += pad;
        }
        ArgBounds { centre: self.eval(centre), lo: l, hi: h }
    }
}

/// Where `p` (in the innermost frame) lands in the world.
pub fn place_point(frames: &[Isometry3<f64>], p: [f64; 3]) -> [f64; 3] {
    let w = compose(frames) * Point3::new(p[0], p[1], p[2]);
    [w.x, w.y, w.z]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), so failures reproduce.
    pub(crate) struct Rng(u64);
    impl Rng {
        pub(crate) fn new(seed: u64) -> Rng {
            Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }
        pub(crate) fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
    }

    fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    #[test]
    fn euler_order_is_rz_ry_rx() {
        let (r, p, y) = (0.3, -0.7, 1.1);
        let iso = pose_isometry(&[0.0, 0.0, 0.0, r, p, y]);
        let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), y);
        let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), p);
        let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), r);
        let m = rz * ry * rx;
        let v = Vector3::new(0.2, -1.3, 0.9);
        assert!((iso.rotation * v - m * v).norm() < 1e-12);
    }

    #[test]
    fn fixed_frame_moves_nothing() {
        let f = FrameBound::fixed([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]);
        assert_eq!(f.dt, 0.0);
        assert_eq!(f.drot, 0.0);
        assert_eq!(chain_motion_bound(&[f], 10.0), 0.0);
    }

    #[test]
    fn nan_bounds_are_infinite() {
        let mut a = ArgBounds::fixed([0.0; 6]);
        a.hi[0] = f64::NAN;
        let f = FrameBound::pose(&a);
        assert!(chain_motion_bound(&[f], 1.0).is_infinite());
        // An unknown angle still turns by at most ‖R − R'‖ ≤ 2.
        let mut a = ArgBounds::fixed([0.0; 6]);
        a.hi[5] = f64::NAN;
        assert_eq!(FrameBound::pose(&a).drot, 2.0);
    }

    /// A random affine pose over `dims` variables with moderate coefficients.
    fn random_pose(rng: &mut Rng, dims: usize) -> AffinePose {
        let mut p = AffinePose::fixed([
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
        ]);
        for j in 0..6 {
            for i in 0..dims {
                if rng.next() < 0.4 {
                    p = p.with(j, i, rng.range(-2.0, 2.0));
                }
            }
        }
        p
    }

    /// Property: for random chains of affine poses (one to four frames, nested), random
    /// boxes and random points within the radius, the actual displacement from the
    /// centre's placement never exceeds the chain bound.
    #[test]
    fn chain_bound_covers_random_displacements() {
        let mut rng = Rng::new(7);
        let mut worst: f64 = 0.0;
        for _case in 0..400 {
            let dims = 1 + (rng.next() * 4.0) as usize;
            let n = 1 + (rng.next() * 4.0) as usize;
            let chain: Vec<AffinePose> = (0..n).map(|_| random_pose(&mut rng, dims)).collect();
            let width = [0.001, 0.05, 0.5, 3.0][(rng.next() * 4.0) as usize];
            let lo: Vec<f64> = (0..dims).map(|_| rng.range(-2.0, 2.0)).collect();
            let hi: Vec<f64> = lo.iter().map(|l| l + rng.range(0.0, width)).collect();
            let c: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| 0.5 * (l + h)).collect();
            let radius = rng.range(0.0, 2.0);
            let fb: Vec<FrameBound> = chain.iter().map(|p| FrameBound::pose(&p.bounds(&lo, &hi, &c))).collect();
            let bound = chain_motion_bound(&fb, radius);
            let at_c: Vec<Isometry3<f64>> = chain.iter().map(|p| pose_isometry(&p.eval(&c))).collect();
            for _ in 0..30 {
                // A point on the sphere of the radius (the worst case for rotation).
                let (u, v) = (rng.range(-1.0, 1.0), rng.range(0.0, std::f64::consts::TAU));
                let s = (1.0 - u * u).sqrt();
                let p = [radius * s * v.cos(), radius * s * v.sin(), radius * u];
                let q: Vec<f64> = lo
                    .iter()
                    .zip(&hi)
                    .map(|(l, h)| {
                        if rng.next() < 0.3 {
                            if rng.next() < 0.5 {
                                *l
                            } else {
                                *h
                            }
                        } else {
                            rng.range(*l, *h)
                        }
                    })
                    .collect();
                let at_q: Vec<Isometry3<f64>> = chain.iter().map(|pp| pose_isometry(&pp.eval(&q))).collect();
                let d = dist(place_point(&at_q, p), place_point(&at_c, p));
                assert!(d <= bound, "displacement {d} exceeds bound {bound}");
                if bound > 0.0 {
                    worst = worst.max(d / bound);
                }
            }
        }
        // The bound is not absurdly loose either (some sample comes within 2x of it).
        assert!(worst > 0.5, "tightest ratio only {worst}");
    }

    /// Property: revolute and prismatic joints below pose frames (a URDF arm on a cart).
    #[test]
    fn joint_bounds_cover_random_displacements() {
        let mut rng = Rng::new(11);
        for _ in 0..300 {
            let cart = random_pose(&mut rng, 2);
            let origin = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(0.0, 1.0), 0.2, -0.4, 0.9];
            let axis = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
            let (lo, hi) = (vec![rng.range(-1.0, 1.0), rng.range(-3.0, 3.0), rng.range(0.0, 0.5)], vec![0.0; 3]);
            let hi: Vec<f64> = lo.iter().zip(hi).map(|(l, _)| l + rng.range(0.0, 0.7)).collect();
            let c: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| 0.5 * (l + h)).collect();
            let radius = rng.range(0.0, 1.5);
            let fb = [
                FrameBound::pose(&cart.bounds(&lo[..2], &hi[..2], &c[..2])),
                FrameBound::fixed(origin),
                FrameBound::revolute(lo[1], hi[1], c[1]),
                FrameBound::prismatic(lo[2], hi[2], c[2]),
            ];
            let bound = chain_motion_bound(&fb, radius);
            let frames = |q: &[f64]| {
                vec![
                    pose_isometry(&cart.eval(&q[..2])),
                    pose_isometry(&origin),
                    axis_isometry(axis, q[1]),
                    Isometry3::translation(0.0, 0.0, q[2]),
                ]
            };
            let at_c = frames(&c);
            for _ in 0..20 {
                let p = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
                let n = dist(p, [0.0; 3]);
                let p = [p[0] * radius / n, p[1] * radius / n, p[2] * radius / n];
                let q: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| rng.range(*l, *h)).collect();
                let d = dist(place_point(&frames(&q), p), place_point(&at_c, p));
                assert!(d <= bound, "displacement {d} exceeds bound {bound}");
            }
        }
    }
}
