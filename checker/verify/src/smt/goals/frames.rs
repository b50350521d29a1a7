//! Frames: footprints are written in the participant's own frame, placed in the world by
//! its `pose(x, y, z, roll, pitch, yaw)` (Sec 3.5: each robot has its own coordinates).
//! A world point is moved into the frame by the inverse pose, with cosines and sines of
//! the angles enclosed soundly (an exact quarter turn exactly), so that an unsat answer
//! holds for the true rotation.

use super::super::encode::{real_of_rational, Encoder, Unsupported};
use super::Query;
use crate::bounds::{self, Interval};
use crate::hir::{Builtin, Expr, Program, RoleId};
use num_rational::BigRational;
use z3::ast::{Bool, Real};

pub(super) fn world_point(q: &mut Query) -> [Real; 3] {
    [q.enc.named_real("point.x"), q.enc.named_real("point.y"), q.enc.named_real("point.z")]
}

/// The world point moved into `role`'s frame: `R^T (p - o)` for `pose(o, roll, pitch,
/// yaw)`, `R = Rz(yaw) Ry(pitch) Rx(roll)`. Offsets and angles that are exactly zero
/// (exact rational arithmetic, [`bounds::exact`]) are skipped.
///
/// **No rounding can turn an overlap into a pass.** A pose's angles are constants, but
/// their cosines and sines are irrational (but for angle 0). Each is enclosed
/// ([`bounds::trig`]: `c ∈ [c_lo, c_hi]`, `s ∈ [s_lo, s_hi]`, a few ulps wide), and the
/// query ranges over *every* rotation in the enclosure, so an unsat answer holds for the
/// true one. To keep the query linear (an exact `c * x` with a variable `c` made
/// Handover's separation queries time out), the rotation by `(c, s)` of `(x, y)` is
/// written around a rational centre `(c0, s0)` of the enclosure (0 or ±1 when the
/// enclosure holds it, the simplest coefficients for the solver):
///
/// `x' = c0 x + s0 y + e1`, `y' = c0 y - s0 x + e2`,
/// `|e1|, |e2| <= u`, `u = d (|x| + |y|)` (`abs` as `ite`),
///
/// with `d = max(dc, ds)`, `dc = max(c_hi - c0, c0 - c_lo)` and `ds` likewise (computed
/// exactly). The true rotation `c x + s y = c0 x + s0 y + (c - c0) x + (s - s0) y`
/// satisfies these (take the slacks to be the error terms: `|(c - c0) x + (s - s0) y|
/// <= dc |x| + ds |y| <= u`), so the set of local points queried contains the true one;
/// chained rotations compose the same way, each on the exactly rotated coordinates of
/// the one before. A counterexample may then be one of the neighbouring rotations: a
/// false alarm only for footprints within `2 d |p - o|` (about 1e-15 of the distance
/// from the pose's origin) of each other, never a false proof.
///
/// Measured alternatives (sorting.chor): a constant slack `(dc + ds) R` from a bound
/// `R` on the footprint's size, and fresh rotated coordinates within the slack, both
/// made two separation queries time out (nlsat), so this form stays; one shared bound
/// `u` for both slacks was faster than two (Handover).
pub(super) fn to_local(enc: &mut Encoder, role: RoleId, p: &[Real; 3]) -> Result<[Real; 3], Unsupported> {
    let prog = enc.prog();
    // A mounted participant's frame moves with its carrier's state: its `pose` alone does
    // not place it, so no query may read its footprint as if it did (the geometric
    // procedure places it through the carrier).
    if prog.role(role).mounted_on.is_some() {
        return Err(Unsupported(format!(
            "`{}` rides on another participant, so its footprint moves with the carrier's state",
            prog.role_name(role)
        )));
    }
    let pose = prog.role(role).pose.clone();
    let mut v = p.clone();
    for (k, c) in v.iter_mut().enumerate() {
        if let Some(o) = pose.get(k) {
            if !is_zero(prog, o) {
                *c = Real::sub(&[c.clone(), enc.real(o)?]);
            }
        }
    }
    // Undo yaw (about z), then pitch (about y), then roll (about x).
    for (idx, axes) in [(5usize, (0usize, 1usize)), (4, (2, 0)), (3, (1, 2))] {
        let Some(angle) = pose.get(idx) else { continue };
        if let Some((c, s)) = bounds::quarter_turn(prog, angle) {
            // An exact multiple of π/2 (`pi / 2`, `-pi`, ...): cos and sin are exactly 0
            // or ±1, so the rotation is exact, with no slack (0 is no rotation at all).
            if (c, s) != (1, 0) {
                let (x, y) = (v[axes.0].clone(), v[axes.1].clone());
                let turn = |k: i64, r: &Real| match k {
                    0 => None,
                    1 => Some(r.clone()),
                    _ => Some(r.unary_minus()),
                };
                // x' = c x + s y, y' = c y - s x.
                let sum = |p: Option<Real>, q: Option<Real>| match (p, q) {
                    (Some(p), Some(q)) => Real::add(&[p, q]),
                    (Some(p), None) | (None, Some(p)) => p,
                    (None, None) => Real::from_rational_str("0", "1").expect("literal"),
                };
                v[axes.0] = sum(turn(c, &x), turn(s, &y));
                v[axes.1] = sum(turn(c, &y), turn(-s, &x));
            }
            continue;
        }
        let iv = bounds::eval(prog, angle, &bounds::closed)
            .filter(|i| i.is_finite())
            .ok_or_else(|| Unsupported("a pose angle that is not a constant".into()))?;
        if iv.is_exactly(0.0) {
            continue;
        }
        let (x, y) = (v[axes.0].clone(), v[axes.1].clone());
        let bad = || Unsupported("a pose angle whose cosine or sine cannot be enclosed".into());
        let (c0, dc) = centre(bounds::trig(Builtin::Cos, Some(iv))).ok_or_else(bad)?;
        let (s0, ds) = centre(bounds::trig(Builtin::Sin, Some(iv))).ok_or_else(bad)?;
        let r = |q: &BigRational| real_of_rational(q).ok_or_else(bad);
        let d = r(&std::cmp::max(dc, ds))?;
        let (c0, s0) = (r(&c0)?, r(&s0)?);
        let zero = Real::from_rational_str("0", "1").expect("literal");
        let abs = |r: &Real| r.ge(&zero).ite(r, &r.unary_minus());
        let bound = Real::mul(&[d, Real::add(&[abs(&x), abs(&y)])]);
        let u = Real::fresh_const("rot_bound");
        enc.require(u.eq(&bound));
        // Rotation by -angle in the (x, y) plane of these axes, with its slack.
        let mut slack = || {
            let e = Real::fresh_const("rot_slack");
            enc.require(Bool::and(&[e.le(&u), e.ge(u.unary_minus())]));
            e
        };
        let (e1, e2) = (slack(), slack());
        v[axes.0] = Real::add(&[Real::mul(&[c0.clone(), x.clone()]), Real::mul(&[s0.clone(), y.clone()]), e1]);
        v[axes.1] = Real::add(&[Real::mul(&[c0, y]), Real::mul(&[s0, x]).unary_minus(), e2]);
    }
    Ok(v)
}

/// A rational centre `m` of the enclosure `iv` and the exact radius around it,
/// `max(hi - m, m - lo)`; `m` is 0, 1 or -1 when `iv` holds it, else the double nearest
/// the midpoint.
pub(super) fn centre(iv: Interval) -> Option<(BigRational, BigRational)> {
    let m = [0.0, 1.0, -1.0].into_iter().find(|m| iv.lo <= *m && *m <= iv.hi).unwrap_or(iv.lo / 2.0 + iv.hi / 2.0);
    let q = BigRational::from_float;
    let (lo, hi, mid) = (q(iv.lo)?, q(iv.hi)?, q(m)?);
    let r = std::cmp::max(&hi - &mid, &mid - &lo);
    Some((mid, r))
}

pub(super) fn is_zero(prog: &Program, e: &Expr) -> bool {
    bounds::eval(prog, e, &bounds::closed).is_some_and(|i| i.is_exactly(0.0))
}

#[cfg(test)]
mod tests {
    use super::super::super::Decision;

    /// [T-SESS] on two bodies: A's footprint the corner `0 <= x <= 1, 0 <= y <= 0.1,
    /// x + y <= cut` at the origin; B's the bar `1 <= x <= 2, |y| <= 0.1` turned by
    /// `yaw` at `(0.5, -0.9)`. A quarter turn puts B's near corner exactly at
    /// `(0.4, 0.1)`: the bodies touch when `cut` is 0.5, and are apart when it is less.
    fn corner_and_bar(yaw: &str, cut: &str) -> Decision {
        let src = format!(
            "robot BotA {{ state s: real; }} robot BotB {{ state s: real; }}
             motion BotA.hold {{ interruptible: true; footprint(x, y, z): 0 <= x <= 1 && 0 <= y <= 0.1 && x + y <= {cut} && -0.1 <= z <= 0.1; }}
             motion BotB.hold {{ interruptible: true; footprint(x, y, z): 1 <= x <= 2 && -0.1 <= y <= 0.1 && -0.1 <= z <= 0.1; }}
             system S {{ participant A: BotA {{ init: s == 0; }} participant B: BotB {{ init: s == 0; at: pose(0.5, -0.9, 0, 0, 0, {yaw}); }} }}
             choreography G = dt<A: hold> * dt<B: hold>;"
        );
        crate::smt::tests::initial_states(&src)
    }

    #[test]
    fn a_quarter_turn_of_pi_rotates_exactly() {
        // Touching at one rotated corner: an overlap, found (and replayed) exactly.
        let Decision::Fails(f) = corner_and_bar("pi / 2", "0.5") else { panic!("the corner touches the bar") };
        let o = f.overlap.expect("a point");
        assert!((o.point[0] - 0.4).abs() < 1e-9 && (o.point[1] - 0.1).abs() < 1e-9, "{o:?}");
        // A gap of 1e-20 is proved: no slack, no rounding (the slack of an enclosed
        // rotation is about 1e-15 here).
        assert_eq!(corner_and_bar("pi / 2", "0.49999999999999999999"), Decision::Holds(None));
        assert_eq!(corner_and_bar("-3 * pi / 2", "0.49999999999999999999"), Decision::Holds(None));
        assert_eq!(corner_and_bar("pi - pi / 2", "0.49999999999999999999"), Decision::Holds(None));
    }

    #[test]
    fn a_decimal_quarter_turn_is_not_exact() {
        // 1.5707963267948966 is not π/2: its rotation is enclosed with a slack, so a gap
        // of 1e-20 cannot be proved (it is not a quarter turn's gap to begin with).
        assert!(!matches!(corner_and_bar("1.5707963267948966", "0.49999999999999999999"), Decision::Holds(_)));
        // 1.5708 turns B's corner about 4e-6 past the exact one, into A: a genuine
        // overlap that treating 1.5708 as a quarter turn would miss.
        assert!(matches!(corner_and_bar("1.5708", "0.499999999999"), Decision::Fails(_)));
    }
}
