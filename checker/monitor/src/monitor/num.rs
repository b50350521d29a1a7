//! Exact rationals of fixed width for the monitor's hot path.
//!
//! A [`Q`] is `num / den` with `i128` parts, `den > 0` and the fraction reduced. Every
//! operation is checked: an intermediate that does not fit 128 bits is `None`
//! ([`Overflow`]), never a wrapped or rounded value, and the caller then evaluates the
//! predicate again over unbounded rationals (`exact::eval`, counted as a fallback). So a
//! result of this module is always the exact rational answer.
//!
//! What fits: every MAVLink integer (`uint64_t` and `int64_t` included), every decimal
//! constant of a protocol with fewer than ~38 digits, and every `float` whose exponent lies
//! in [-103, 103] (a binary32 `m * 2^e`, `|m| < 2^24`, is `m / 2^-e` or `m * 2^e`): parameter
//! values, coordinates, speeds. Subnormal and huge floats take the fallback.

/// An exact rational `num / den` (`den > 0`, reduced).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Q {
    pub num: i128,
    pub den: i128,
}

/// An intermediate that does not fit 128 bits: the caller evaluates over big rationals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overflow;

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.wrapping_abs();
    b = b.wrapping_abs();
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

// Checked operations named as the operators they are; they return `Option` (overflow),
// so they are not the `std::ops` traits.
#[allow(clippy::should_implement_trait)]
impl Q {
    pub const ZERO: Q = Q { num: 0, den: 1 };
    pub const ONE: Q = Q { num: 1, den: 1 };

    pub fn int(i: i128) -> Q {
        Q { num: i, den: 1 }
    }

    /// `num / den` reduced; `None` for a zero denominator or on overflow (`i128::MIN`).
    pub fn new(num: i128, den: i128) -> Option<Q> {
        if den == 0 || num == i128::MIN || den == i128::MIN {
            return None;
        }
        if den == 1 {
            return Some(Q { num, den });
        }
        let g = gcd(num, den).max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = -n;
            d = -d;
        }
        Some(Q { num: n, den: d })
    }

    pub fn is_integer(self) -> bool {
        self.den == 1
    }

    pub fn add(self, o: Q) -> Option<Q> {
        if self.den == 1 && o.den == 1 {
            return Some(Q::int(self.num.checked_add(o.num)?)).filter(|q| q.num != i128::MIN);
        }
        let g = gcd(self.den, o.den);
        let (a, b) = (self.den / g, o.den / g);
        let n = self.num.checked_mul(b)?.checked_add(o.num.checked_mul(a)?)?;
        Q::new(n, self.den.checked_mul(b)?)
    }

    pub fn neg(self) -> Option<Q> {
        Some(Q { num: self.num.checked_neg()?, den: self.den })
    }

    pub fn sub(self, o: Q) -> Option<Q> {
        self.add(o.neg()?)
    }

    pub fn mul(self, o: Q) -> Option<Q> {
        if self.den == 1 && o.den == 1 {
            return Some(Q::int(self.num.checked_mul(o.num)?)).filter(|q| q.num != i128::MIN);
        }
        // Cross-reduce first so that the products stay as small as they can.
        let g1 = gcd(self.num, o.den).max(1);
        let g2 = gcd(o.num, self.den).max(1);
        let n = (self.num / g1).checked_mul(o.num / g2)?;
        let d = (self.den / g2).checked_mul(o.den / g1)?;
        Q::new(n, d)
    }

    /// `self / o`; `Err(None)` never: a zero divisor is the caller's question (undefined).
    pub fn div(self, o: Q) -> Option<Q> {
        self.mul(Q::new(o.den, o.num)?)
    }

    /// `self ^ k` for an integer `k` (`self != 0` when `k < 0`, checked by the caller).
    pub fn pow(self, k: i64) -> Option<Q> {
        let mut base = if k < 0 { Q::new(self.den, self.num)? } else { self };
        let mut e = k.unsigned_abs();
        let mut acc = Q::ONE;
        while e > 0 {
            if e & 1 == 1 {
                acc = acc.mul(base)?;
            }
            e >>= 1;
            if e > 0 {
                base = base.mul(base)?;
            }
        }
        Some(acc)
    }

    /// The comparison of two rationals, exactly (`None` on overflow of a cross product).
    pub fn cmp(self, o: Q) -> Option<std::cmp::Ordering> {
        if self.den == o.den {
            return Some(self.num.cmp(&o.num));
        }
        Some(self.num.checked_mul(o.den)?.cmp(&o.num.checked_mul(self.den)?))
    }

    pub fn abs(self) -> Option<Q> {
        if self.num < 0 {
            self.neg()
        } else {
            Some(self)
        }
    }

    /// The exact value of a finite binary32 or binary64 float (`None` for NaN, infinities,
    /// and values whose exponent takes them outside 128 bits).
    pub fn from_f64(x: f64) -> Option<Q> {
        if !x.is_finite() {
            return None;
        }
        if x == 0.0 {
            return Some(Q::ZERO);
        }
        let bits = x.to_bits();
        let sign = if bits >> 63 == 1 { -1i128 } else { 1 };
        let exp = ((bits >> 52) & 0x7ff) as i32;
        let frac = (bits & ((1u64 << 52) - 1)) as i128;
        let (mut m, mut e) = if exp == 0 { (frac, -1074) } else { (frac | (1i128 << 52), exp - 1075) };
        let tz = m.trailing_zeros() as i32;
        m >>= tz;
        e += tz;
        if e >= 0 {
            if e > 126 || m.leading_zeros() as i32 <= e + 1 {
                return None;
            }
            Some(Q { num: sign * (m << e), den: 1 })
        } else {
            if -e > 126 {
                return None;
            }
            Some(Q { num: sign * m, den: 1i128 << (-e) })
        }
    }

    /// `floor(self)` as an integer.
    pub fn floor(self) -> i128 {
        self.num.div_euclid(self.den)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_is_exact_and_reduced() {
        let tenth = Q::new(1, 10).unwrap();
        assert_eq!(tenth.add(Q::new(2, 10).unwrap()), Q::new(3, 10));
        assert_eq!(Q::new(6, -4), Some(Q { num: -3, den: 2 }));
        assert_eq!(Q::int(3).pow(-2), Q::new(1, 9));
        assert_eq!(Q::int(2).div(Q::int(4)), Q::new(1, 2));
        assert_eq!(Q::int(0).div(Q::ZERO), None);
    }

    #[test]
    fn overflow_is_reported_not_wrapped() {
        let big = Q::int(i128::MAX / 2 + 1);
        assert_eq!(big.add(big), None);
        assert_eq!(big.mul(Q::int(2)), None);
        assert_eq!(Q::int(2).pow(200), None);
        assert_eq!(Q::new(i128::MIN, 1), None);
    }

    #[test]
    fn floats_are_their_binary_rationals() {
        // 0.1f32 is 13421773 / 2^27, not 1/10.
        let x = Q::from_f64(f64::from(0.1f32)).unwrap();
        assert_eq!(x, Q { num: 13421773, den: 1 << 27 });
        assert_ne!(x, Q::new(1, 10).unwrap());
        assert_eq!(Q::from_f64(-2.5), Q::new(-5, 2));
        assert_eq!(Q::from_f64(f64::NAN), None);
        assert_eq!(Q::from_f64(f64::INFINITY), None);
        // f32::MAX = (2^24 - 1) * 2^104 does not fit; the smallest subnormal neither.
        assert_eq!(Q::from_f64(f64::from(f32::MAX)), None);
        assert_eq!(Q::from_f64(f64::from(f32::from_bits(1))), None);
        assert_eq!(Q::from_f64(f64::from(2f32.powi(100))), Some(Q::int(1i128 << 100)));
        assert_eq!(Q::int(7).floor(), 7);
        assert_eq!(Q::new(-7, 2).unwrap().floor(), -4);
    }
}
