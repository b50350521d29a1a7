//! Numbers between Z3 and exact arithmetic: numerals read back as exact rationals, and
//! exact rationals and doubles written as Z3 reals.

use super::*;

pub fn as_real(t: Term) -> Result<Real, Unsupported> {
    match t {
        Term::R(r) => Ok(r),
        Term::I(i) => Ok(i.to_real()),
        Term::B(_) => Err(Unsupported("a boolean used as a number".into())),
        Term::V(_) => Err(Unsupported("a point or vector used as a number".into())),
    }
}

pub fn zero() -> Real {
    Int::from_i64(0).to_real()
}

pub fn one() -> Real {
    Int::from_i64(1).to_real()
}

/// A decimal literal (`0.65`, `1e-3`, `12`) as an exact Z3 rational.
pub fn rational(lit: &str) -> Option<Real> {
    // One reader of decimals for the whole checker: the interval stage's.
    real_of_rational(&bounds::decimal(lit)?)
}

/// An f64 as the exact rational it is (not its shortest round-trip decimal, which may
/// lie on either side of it: an enclosure's end must not move inward).
pub fn real_of_f64(v: f64) -> Option<Real> {
    real_of_rational(&BigRational::from_float(v)?)
}

/// An exact rational as a Z3 real.
pub fn real_of_rational(q: &BigRational) -> Option<Real> {
    Real::from_rational_str(&q.numer().to_string(), &q.denom().to_string())
}

/// The exact value of a Z3 numeral (`3.0`, `(/ 1.0 3.0)`, `(- (/ 7.0 2.0))`), of any
/// size; `None` for anything that is not a rational numeral.
pub fn rational_value(r: &Real) -> Option<BigRational> {
    if let Some((n, d)) = r.as_rational().filter(|&(_, d)| d != 0) {
        return Some(BigRational::new(n.into(), d.into()));
    }
    let text = r.to_string().replace(['(', ')'], " ");
    let mut toks: Vec<&str> = text.split_whitespace().collect();
    let mut neg = false;
    while let Some(i) = toks.iter().position(|t| *t == "-") {
        toks.remove(i);
        neg = !neg;
    }
    let q = match toks.as_slice() {
        [n] => bounds::decimal(n)?,
        ["/", n, d] => {
            let d = bounds::decimal(d)?;
            if d.is_zero() {
                return None;
            }
            bounds::decimal(n)? / d
        }
        _ => return None,
    };
    Some(if neg { -q } else { q })
}

/// Z3 prints rationals as `(/ 13.0 20.0)`; users read `0.65` (rounded to 1e-6 m or s,
/// far below any tolerance of the robots modelled).
pub(super) fn decimal(r: &Real) -> String {
    // The exact value: a decimal of at most 30 places (Z3's models are mostly short
    // rationals), else a fraction. Never a value rounded to a few places that reads as exact:
    // `th == pi / 2` holds of a model's value in π's enclosure, halved, as far as exact
    // arithmetic can tell, and not of 1.570796.
    if let Some(q) = rational_value(r) {
        if let Some(text) = exact_decimal(&q, 30) {
            return text;
        }
        // A fraction that is no short decimal (a dyadic one from Z3's arithmetic, n / 2^68):
        // exactly, while it stays readable.
        let (n, d) = (q.numer().to_string(), q.denom().to_string());
        if n.len() <= 30 && d.len() <= 30 {
            return format!("{n}/{d}");
        }
    }
    // Otherwise (an algebraic number, a huge fraction) the nearest double, marked as such.
    let v = match r.approx(17).parse::<f64>() {
        Ok(v) => v,
        Err(_) => return r.to_string(),
    };
    if v != 0.0 && v.abs() < 1e-4 {
        format!("≈{v:e}")
    } else {
        format!("≈{v}")
    }
}

/// `q` written exactly in decimal, if it has at most `places` decimal places: `0.65`,
/// `-7`, `1e-9` (scientific below 1e-4, as Rust prints small doubles).
pub(super) fn exact_decimal(q: &BigRational, places: u32) -> Option<String> {
    let ten = num_bigint::BigInt::from(10u8);
    let mut scaled = q.clone();
    let mut k = 0u32;
    while !scaled.is_integer() {
        if k == places {
            return None;
        }
        scaled *= BigRational::from_integer(ten.clone());
        k += 1;
    }
    let n = scaled.to_integer();
    let (neg, digits) = (n.sign() == num_bigint::Sign::Minus, n.magnitude().to_string());
    let sign = if neg { "-" } else { "" };
    if k == 0 {
        return Some(format!("{sign}{digits}"));
    }
    let small = !n.is_zero() && (digits.len() as i64 - k as i64) < -3;
    let text = if small {
        // d.ddd e-x: the exponent of the leading digit.
        let exp = digits.len() as i64 - 1 - k as i64;
        let mant = digits.trim_end_matches('0');
        match mant.len() {
            1 => format!("{mant}e{exp}"),
            _ => format!("{}.{}e{exp}", &mant[..1], &mant[1..]),
        }
    } else if digits.len() as u32 > k {
        let (int, frac) = digits.split_at(digits.len() - k as usize);
        format!("{int}.{}", frac.trim_end_matches('0'))
    } else {
        format!("0.{}{}", "0".repeat((k as usize) - digits.len()), digits.trim_end_matches('0'))
    };
    Some(format!("{sign}{}", text.trim_end_matches('.')))
}

/// An integer of a Z3 model as the user writes it: Z3 prints a negative one as `(- 1)`.
pub(super) fn int_text(z3: &str) -> String {
    match z3.strip_prefix("(- ").and_then(|r| r.strip_suffix(')')) {
        Some(n) if n.bytes().all(|b| b.is_ascii_digit()) => format!("-{n}"),
        _ => z3.to_string(),
    }
}
