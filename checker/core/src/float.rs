//! Binary floating-point formats as sets of exact rationals (binary32, binary64): rounding
//! to nearest with ties to even, membership, and exact decimals. Plain arithmetic on
//! `num-rational`: lowering (MAVLink float fields), exact evaluation and the SMT encoding
//! use it.

use crate::hir::Builtin;

/// A binary floating-point format as a set of rationals: its finite values are exactly
/// `m * 2^q` for integers `|m| <= 2^p - 1` and `qmin <= q <= qmax` (`q` the exponent of
/// the last significand bit: binary32 has `p = 24`, subnormals down to `2^-149`, and its
/// largest value `(2^24 - 1) * 2^104`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FloatFormat {
    pub p: u32,
    pub qmin: i64,
    pub qmax: i64,
}

pub const BINARY32: FloatFormat = FloatFormat { p: 24, qmin: -149, qmax: 104 };
pub const BINARY64: FloatFormat = FloatFormat { p: 53, qmin: -1074, qmax: 971 };

/// The format [`Builtin::Float32`] or [`Builtin::Float64`] stands for.
pub fn float_format(f: Builtin) -> Option<FloatFormat> {
    match f {
        Builtin::Float32 => Some(BINARY32),
        Builtin::Float64 => Some(BINARY64),
        _ => None,
    }
}

/// `2^k` as an exact rational.
pub fn pow2(k: i64) -> num_rational::BigRational {
    use num_bigint::BigInt;
    let one = BigInt::from(1);
    if k >= 0 {
        num_rational::BigRational::from_integer(one << (k as usize))
    } else {
        num_rational::BigRational::new(one.clone(), one << (k.unsigned_abs() as usize))
    }
}

/// `r` rounded to the nearest value of `f`, ties to even (IEEE 754's default, what an
/// autopilot's `(float)0.1` does), exactly. `None` when it rounds to an infinity (its
/// magnitude is at least the largest finite value plus half its ulp), which the
/// finite-float model excludes.
pub fn round_to_float(r: &num_rational::BigRational, f: FloatFormat) -> Option<num_rational::BigRational> {
    use num_traits::{One, Signed, Zero};
    if r.is_zero() {
        return Some(r.clone());
    }
    let a = r.abs();
    // e = floor(log2 a): 2^e <= a < 2^(e+1).
    let mut e = a.numer().bits() as i64 - a.denom().bits() as i64;
    if a < pow2(e) {
        e -= 1;
    }
    let q = (e - (i64::from(f.p) - 1)).max(f.qmin);
    let scaled = &a / pow2(q);
    let mut n = scaled.floor();
    let twice = (&scaled - &n) * num_rational::BigRational::from_integer(2.into());
    let odd = !(n.to_integer() % num_bigint::BigInt::from(2)).is_zero();
    if twice > num_rational::BigRational::one() || (twice.is_one() && odd) {
        n += num_rational::BigRational::one();
    }
    let v = n * pow2(q);
    let max = num_rational::BigRational::from_integer((num_bigint::BigInt::from(1) << f.p as usize) - 1) * pow2(f.qmax);
    if v > max {
        return None;
    }
    Some(if r.is_negative() { -v } else { v })
}

/// Whether `r` is a finite value of `f`.
pub fn is_float(r: &num_rational::BigRational, f: FloatFormat) -> bool {
    round_to_float(r, f).as_ref() == Some(r)
}

/// A rational whose denominator is a power of two (every float) as its exact decimal,
/// `-0.100000001490116119384765625`.
pub fn dyadic_decimal(r: &num_rational::BigRational) -> Option<String> {
    use num_traits::{One, Signed, Zero};
    let d = r.denom();
    let k = d.bits().checked_sub(1)?;
    if (num_bigint::BigInt::one() << k as usize) != *d {
        return None;
    }
    let n = r.numer().abs() * num_traits::pow(num_bigint::BigInt::from(5), k as usize);
    let mut digits = n.to_string();
    let k = k as usize;
    if k > 0 {
        if digits.len() <= k {
            digits = format!("{}{digits}", "0".repeat(k + 1 - digits.len()));
        }
        digits.insert(digits.len() - k, '.');
    } else {
        digits.push_str(".0");
    }
    let sign = if r.is_negative() && !r.is_zero() { "-" } else { "" };
    Some(format!("{sign}{digits}"))
}
