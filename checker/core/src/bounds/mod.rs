//! Interval arithmetic over predicates: sound enclosures of terms, and axis-aligned
//! boxes around the points a footprint may occupy. The SMT stage uses them to settle
//! the separation of `g1 * ... * gn` without a solver when each side's footprints fit
//! in a box and the boxes are pairwise disjoint (the boxes are then the partition
//! `∃ FP1, FP2` of [AGCOMP], inferred), to bound `sin`/`cos` of constants, and to
//! enclose the cosines and sines of pose angles.
//!
//! **The rule: every enclosure contains the exact real value, in every case.**
//! - *Rational values are computed exactly.* A literal is a decimal, i.e. an exact
//!   rational (`0.1` is 1/10, `1e-400` is 10^-400, neither is a double), and sums,
//!   differences, products, quotients, integer powers, `min`, `max` and `abs` of rationals
//!   are rational: [`eval`] computes them as [`BigRational`]s and encloses the result in
//!   the tightest pair of doubles around it ([`Interval::of_rational`], checked against
//!   the rational exactly). So `1 - 1e-20 - 1` is the interval just around -1e-20, never
//!   the point 0, and an interval is a single point only when that point *is* the value.
//! - *Everything else is rounded outward.* Where a variable's range, `sqrt`, `sin` or
//!   `cos` enters, the ends are doubles, and each operation rounds its lower end down and
//!   its upper end up: the round-to-nearest result is kept only when an error-free
//!   transformation shows it exact (TwoSum for `+`, a fused multiply-add for `*`, `/`
//!   and `sqrt`), otherwise it moves one ulp outward (`f64::next_down`/`next_up`), which
//!   contains the exact result because round-to-nearest is within half an ulp.
//!   `sin`/`cos` are not correctly rounded by libm: their values are widened by 2^-50
//!   (eight ulps of 1) beyond the argument's half-width (both are 1-Lipschitz).
//!
//! **Why these crates and not an interval library.** inari (IEEE 1788 interval arithmetic)
//! would give directed rounding directly, but it needs a nightly toolchain (`asm`,
//! `stdsimd`), a Haswell target CPU set at build time, and GMP/MPFR for its transcendental
//! functions; mochi builds on stable Rust for any x86-64 or ARM machine. The values the
//! checker meets are mostly rational constants, for which exact arithmetic is both simpler
//! and tighter than any rounding: num-rational's `BigRational` (num-bigint underneath) is
//! the long-standing pure-Rust choice, with no native dependency (malachite is faster on
//! huge numbers, which contracts do not have, and is a much larger dependency). Outward
//! rounding of doubles is then only needed where values are irrational or unknown, and
//! four small functions with error-free transformations do it on stable Rust.
//!
//! `None` means "unbounded or unknown".

use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, Var};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};
use std::collections::HashMap;

pub mod compiled;
pub mod truth;

/// A closed interval `[lo, hi]`, possibly with infinite ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

const ALL: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };

/// Below this magnitude a product or quotient may have lost bits to underflow, so the
/// error-free checks are not trusted and the result is widened both ways.
const TINY: f64 = 1e-280;

/// `v` (a round-to-nearest result) as an interval: itself when `exact`, otherwise one
/// ulp either way, which contains every real that rounds to `v`.
fn around(v: f64, exact: bool) -> (f64, f64) {
    if v.is_nan() {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else if exact {
        (v, v)
    } else {
        (v.next_down(), v.next_up())
    }
}

/// `a + b` rounded outward.
fn add_out(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    if !s.is_finite() {
        // Infinite operands give exact infinities; finite ones that overflow round out.
        return around(s, a.is_infinite() || b.is_infinite());
    }
    // TwoSum (Knuth): a + b == s + err exactly, for finite a, b, s.
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    around(s, err == 0.0)
}

/// `a * b` rounded outward.
fn mul_out(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 || b == 0.0 {
        return if a.is_finite() && b.is_finite() { (0.0, 0.0) } else { around(f64::NAN, false) };
    }
    let p = a * b;
    if !p.is_finite() {
        return around(p, a.is_infinite() || b.is_infinite());
    }
    // With no underflow, a * b - p is a double and the fused multiply-add computes it.
    around(p, p.abs() >= TINY && a.mul_add(b, -p) == 0.0)
}

/// `a / b` (b nonzero) rounded outward.
fn div_out(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 && b != 0.0 {
        return (0.0, 0.0);
    }
    let q = a / b;
    if !q.is_finite() || a.is_infinite() || b.is_infinite() {
        // inf / x is an exact infinity; x / inf is exactly 0; overflow rounds out.
        return around(q, a.is_infinite() || b.is_infinite());
    }
    // With no underflow, a - q * b is a double (the remainder) and is 0 iff q is exact.
    around(q, q.abs() >= TINY && a.abs() >= TINY && (-q).mul_add(b, a) == 0.0)
}

/// `sqrt(a)` (a >= 0) rounded outward.
fn sqrt_out(a: f64) -> (f64, f64) {
    let r = a.sqrt();
    if a == 0.0 || a.is_infinite() {
        return (r, r);
    }
    around(r, r >= 1e-140 && r.mul_add(r, -a) == 0.0)
}

/// `a^n` (n >= 1, a >= 0) rounded down (`up == false`) or up, by repeated squaring
/// (O(log n) products): for non-negative factors, products of lower (upper) bounds
/// rounded down (up) stay lower (upper) bounds.
fn pow_nonneg(a: f64, n: i64, up: bool) -> f64 {
    let pick = |(lo, hi): (f64, f64)| if up { hi } else { lo.max(0.0) };
    let (mut base, mut n, mut acc) = (a, n, 1.0f64);
    while n > 0 {
        if n & 1 == 1 {
            acc = pick(mul_out(acc, base));
        }
        n >>= 1;
        if n > 0 {
            base = pick(mul_out(base, base));
        }
    }
    acc
}

impl Interval {
    /// The interval holding exactly the double `v`.
    pub fn point(v: f64) -> Interval {
        Interval { lo: v, hi: v }
    }

    /// `[lo, hi]` as given: the caller vouches that the ends are sound.
    pub fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi }
    }

    /// The tightest interval of doubles around the rational `q`: a point exactly when
    /// `q` is a double. Checked against `q` exactly, whatever `to_f64` rounds to.
    pub fn of_rational(q: &BigRational) -> Interval {
        // Fast path: numerator and denominator are doubles, so `n / d` is the correctly
        // rounded quotient, exact iff the remainder `n - v d` is 0.
        const EXACT: i64 = 1 << 53;
        if let (Some(n), Some(d)) = (q.numer().to_i64(), q.denom().to_i64()) {
            if n.unsigned_abs() <= EXACT as u64 && (1..=EXACT).contains(&d) {
                let (n, d) = (n as f64, d as f64);
                let (lo, hi) = div_out(n, d);
                return Interval { lo, hi };
            }
        }
        let Some(v) = q.to_f64().filter(|v| !v.is_nan()) else { return ALL };
        let v = v.clamp(-f64::MAX, f64::MAX);
        let above = |f: f64| BigRational::from_float(f).is_some_and(|r| r > *q);
        let below = |f: f64| BigRational::from_float(f).is_some_and(|r| r < *q);
        let (mut lo, mut hi) = (v, v);
        for _ in 0..4 {
            if !above(lo) {
                break;
            }
            lo = lo.next_down();
        }
        for _ in 0..4 {
            if !below(hi) {
                break;
            }
            hi = hi.next_up();
        }
        // `to_f64` is within an ulp; should it ever be further off, give up soundly.
        if above(lo) {
            lo = f64::NEG_INFINITY;
        }
        if below(hi) {
            hi = f64::INFINITY;
        }
        Interval { lo, hi }
    }

    pub fn is_finite(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// Whether the interval is exactly the number `v`: since every enclosure contains
    /// the exact value, the value is then `v`.
    pub fn is_exactly(&self, v: f64) -> bool {
        self.lo == v && self.hi == v
    }

    pub fn hull(self, o: Interval) -> Interval {
        Interval { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    pub fn meet(self, o: Interval) -> Interval {
        Interval { lo: self.lo.max(o.lo), hi: self.hi.min(o.hi) }
    }

    pub fn disjoint(self, o: Interval) -> bool {
        self.hi < o.lo || o.hi < self.lo
    }

    fn div(self, o: Interval) -> Option<Interval> {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return None; // the divisor may be zero
        }
        let qs = [div_out(self.lo, o.lo), div_out(self.lo, o.hi), div_out(self.hi, o.lo), div_out(self.hi, o.hi)];
        Some(Interval::spanning(&qs))
    }

    /// The smallest interval holding every `(lo, hi)` pair; unbounded if one is NaN.
    fn spanning(ps: &[(f64, f64)]) -> Interval {
        if ps.iter().any(|(l, h)| l.is_nan() || h.is_nan()) {
            return ALL;
        }
        let lo = ps.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        let hi = ps.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        Interval { lo, hi }
    }

    /// `self` to the integer power `n`, rounded outward.
    pub fn pow(self, n: i64) -> Interval {
        if n == 0 {
            return Interval::point(1.0);
        }
        if n % 2 == 0 {
            // |x|^n: from the smallest to the largest magnitude.
            let (small, large) = if self.lo <= 0.0 && self.hi >= 0.0 {
                (0.0, self.lo.abs().max(self.hi.abs()))
            } else {
                (self.lo.abs().min(self.hi.abs()), self.lo.abs().max(self.hi.abs()))
            };
            return Interval { lo: pow_nonneg(small, n, false), hi: pow_nonneg(large, n, true) };
        }
        // Odd powers are increasing: x^n = sign(x) |x|^n.
        let odd = |x: f64, up: bool| {
            if x >= 0.0 {
                pow_nonneg(x, n, up)
            } else {
                -pow_nonneg(-x, n, !up)
            }
        };
        Interval { lo: odd(self.lo, false), hi: odd(self.hi, true) }
    }

    /// The square root, rounded outward; `None` when the interval reaches below 0.
    pub fn sqrt(self) -> Option<Interval> {
        if self.lo < 0.0 {
            return None;
        }
        Some(Interval { lo: sqrt_out(self.lo).0, hi: sqrt_out(self.hi).1 })
    }
}

/// Sums, negations and products enclose the exact result (outward rounding).
impl std::ops::Add for Interval {
    type Output = Interval;
    fn add(self, o: Interval) -> Interval {
        let (lo, hi) = (add_out(self.lo, o.lo).0, add_out(self.hi, o.hi).1);
        if lo.is_nan() || hi.is_nan() {
            return ALL;
        }
        Interval { lo, hi }
    }
}

impl std::ops::Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }
}

impl std::ops::Mul for Interval {
    type Output = Interval;
    fn mul(self, o: Interval) -> Interval {
        // 0 * inf is NaN in each product: the product is then unbounded (`spanning`).
        let ps = [mul_out(self.lo, o.lo), mul_out(self.lo, o.hi), mul_out(self.hi, o.lo), mul_out(self.hi, o.hi)];
        Interval::spanning(&ps)
    }
}

/// A decimal literal (`0.65`, `1e-3`, `12`, `-2.5E+4`) as an exact rational; `None` for
/// a malformed one or an exponent beyond ±100000 (the caller then rounds outward).
pub fn decimal(lit: &str) -> Option<BigRational> {
    let (mant, exp) = match lit.split_once(['e', 'E']) {
        Some((m, e)) => (m, e.parse::<i64>().ok()?),
        None => (lit, 0),
    };
    let (neg, mant) = match mant.strip_prefix('-') {
        Some(m) => (true, m),
        None => (false, mant),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let digits = format!("{int}{frac}");
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) || exp.abs() > 100_000 {
        return None;
    }
    let n: BigInt = digits.parse().ok()?;
    let scale = exp - frac.len() as i64;
    let ten = BigInt::from(10);
    let p = num_traits::pow(ten, scale.unsigned_abs() as usize);
    let q = if scale >= 0 { BigRational::from_integer(n * p) } else { BigRational::new(n, p) };
    Some(if neg { -q } else { q })
}

/// A term's value: an enclosure, and the exact rational when the term is a rational
/// constant (then `iv` is the tightest enclosure of it).
#[derive(Clone)]
struct Val {
    iv: Interval,
    exact: Option<BigRational>,
}

/// Rationals beyond this many bits (numerator or denominator) are only enclosed, so
/// that `10^1000^1000` cannot exhaust memory.
const MAX_BITS: u64 = 1 << 14;

impl Val {
    fn interval(iv: Interval) -> Val {
        Val { iv, exact: None }
    }

    fn rational(q: BigRational) -> Val {
        let iv = Interval::of_rational(&q);
        let small = q.numer().bits() <= MAX_BITS && q.denom().bits() <= MAX_BITS;
        Val { iv, exact: small.then_some(q) }
    }

    /// `f` on the exact values when both are known, else `g` on the enclosures.
    fn lift2(
        self,
        o: Val,
        f: impl FnOnce(&BigRational, &BigRational) -> Option<BigRational>,
        g: impl FnOnce(Interval, Interval) -> Option<Interval>,
    ) -> Option<Val> {
        if let (Some(a), Some(b)) = (&self.exact, &o.exact) {
            if let Some(q) = f(a, b) {
                return Some(Val::rational(q));
            }
        }
        g(self.iv, o.iv).map(Val::interval)
    }
}

/// Where variables range; `None` is unbounded.
pub trait Ranges {
    fn range(&self, v: &Var) -> Option<Interval>;
}

impl<F: Fn(&Var) -> Option<Interval>> Ranges for F {
    fn range(&self, v: &Var) -> Option<Interval> {
        self(v)
    }
}

/// Constants only: every other variable is unbounded.
pub fn closed(_: &Var) -> Option<Interval> {
    None
}

/// An enclosure of the numeric term `e`, or `None` when it cannot be bounded.
pub fn eval(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<Interval> {
    value(prog, e, ranges).map(|v| v.iv)
}

/// The exact value of `e` when it is a rational constant (literals and constants under
/// `+ - * /`, integer powers, `min`, `max`, `abs`, `sqrt` of a rational square).
pub fn exact(prog: &Program, e: &Expr) -> Option<BigRational> {
    value(prog, e, &closed).and_then(|v| v.exact)
}

/// Whether `a` and `b` denote the same value however they are written: the same
/// expression, or two constants with the same exact value (`0.5` and `(5 / 10)`). A check
/// that compares poses or sizes by their text would treat equal values written apart as
/// different (the metamorphic tests rewrite constants to find such checks).
pub fn same_value(prog: &Program, a: &Expr, b: &Expr) -> bool {
    a == b || matches!((exact(prog, a), exact(prog, b)), (Some(x), Some(y)) if x == y)
}

thread_local! {
    /// Values of constants (by index) while a [`ConstCache`] is alive on this thread: the
    /// geometric procedure evaluates the same predicates over millions of boxes, and a
    /// constant's exact value (decimal parsing, rational arithmetic) dominated its time.
    static CONSTS: std::cell::RefCell<Option<HashMap<u32, Option<Val>>>> = const { std::cell::RefCell::new(None) };
}

/// While alive, constants' values are computed once per thread ([`eval`] of one program
/// only: create it for one program and drop it before evaluating another's expressions).
pub struct ConstCache(());

impl ConstCache {
    pub fn new() -> ConstCache {
        CONSTS.with(|c| *c.borrow_mut() = Some(HashMap::new()));
        ConstCache(())
    }
}

impl Default for ConstCache {
    fn default() -> ConstCache {
        ConstCache::new()
    }
}

impl Drop for ConstCache {
    fn drop(&mut self) {
        CONSTS.with(|c| *c.borrow_mut() = None);
    }
}

fn const_value(prog: &Program, c: crate::hir::ConstId, ranges: &dyn Ranges) -> Option<Val> {
    let cached = CONSTS.with(|m| m.borrow().as_ref().map(|m| m.get(&(c.idx() as u32)).cloned()));
    match cached {
        Some(Some(v)) => v,
        Some(None) => {
            let v = value(prog, &prog.consts[c.idx()].value, ranges);
            CONSTS.with(|m| {
                if let Some(m) = m.borrow_mut().as_mut() {
                    m.insert(c.idx() as u32, v.clone());
                }
            });
            v
        }
        None => value(prog, &prog.consts[c.idx()].value, ranges),
    }
}

fn value(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<Val> {
    crate::stack::deep(|| value_inner(prog, e, ranges))
}

fn value_inner(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<Val> {
    let v = match &e.kind {
        ExprKind::Int(i) => Val::rational(BigRational::from_integer(BigInt::from(*i))),
        ExprKind::Real(r) => match decimal(r) {
            Some(q) => Val::rational(q),
            // Beyond the exponents `decimal` takes: Rust's parse rounds to nearest.
            None => {
                let (lo, hi) = around(r.parse().ok()?, false);
                Val::interval(Interval { lo, hi })
            }
        },
        ExprKind::Var(Var::Const(c)) => const_value(prog, *c, ranges)?,
        ExprKind::Var(v) => Val::interval(ranges.range(v)?),
        ExprKind::Unary(UnOp::Neg, a) => {
            let x = value(prog, a, ranges)?;
            Val { iv: -x.iv, exact: x.exact.map(|q| -q) }
        }
        ExprKind::Binary(op, a, b) => {
            let x = value(prog, a, ranges)?;
            if *op == BinOp::Pow {
                let ExprKind::Int(n) = b.kind else { return None };
                if n < 0 {
                    return None;
                }
                if let Some(q) = &x.exact {
                    let bits = q.numer().bits().max(q.denom().bits());
                    if bits.saturating_mul(n as u64) <= MAX_BITS {
                        return Some(Val::rational(num_traits::pow(q.clone(), n as usize)));
                    }
                }
                return Some(Val::interval(x.iv.pow(n)));
            }
            let y = value(prog, b, ranges)?;
            match op {
                BinOp::Add => x.lift2(y, |a, b| Some(a + b), |a, b| Some(a + b))?,
                BinOp::Sub => x.lift2(y, |a, b| Some(a - b), |a, b| Some(a + -b))?,
                BinOp::Mul => x.lift2(y, |a, b| Some(a * b), |a, b| Some(a * b))?,
                BinOp::Div => x.lift2(y, |a, b| (!b.is_zero()).then(|| a / b), |a, b| a.div(b))?,
                _ => return None,
            }
        }
        ExprKind::If(_, a, b) => {
            let (x, y) = (value(prog, a, ranges)?, value(prog, b, ranges)?);
            match (&x.exact, &y.exact) {
                (Some(p), Some(q)) if p == q => x,
                _ => Val::interval(x.iv.hull(y.iv)),
            }
        }
        ExprKind::Call(f, args) => {
            let arg = |i: usize| args.get(i).and_then(|a| value(prog, a, ranges));
            match f {
                Builtin::Min => arg(0)?.lift2(
                    arg(1)?,
                    |a, b| Some(a.min(b).clone()),
                    |x, y| Some(Interval { lo: x.lo.min(y.lo), hi: x.hi.min(y.hi) }),
                )?,
                Builtin::Max => arg(0)?.lift2(
                    arg(1)?,
                    |a, b| Some(a.max(b).clone()),
                    |x, y| Some(Interval { lo: x.lo.max(y.lo), hi: x.hi.max(y.hi) }),
                )?,
                Builtin::Abs => {
                    let x = arg(0)?;
                    if let Some(q) = &x.exact {
                        return Some(Val::rational(q.abs()));
                    }
                    let x = x.iv;
                    Val::interval(if x.lo >= 0.0 {
                        x
                    } else if x.hi <= 0.0 {
                        -x
                    } else {
                        Interval { lo: 0.0, hi: x.hi.max(-x.lo) }
                    })
                }
                Builtin::Sqrt => {
                    let x = arg(0)?;
                    if let Some(q) = x.exact.as_ref().and_then(rational_sqrt) {
                        return Some(Val::rational(q));
                    }
                    Val::interval(x.iv.sqrt()?)
                }
                Builtin::Sin | Builtin::Cos => match args.first().and_then(|a| quarter_turn(prog, a)) {
                    // An exact quarter turn: sine and cosine are 0 or ±1, exactly.
                    Some((c, s)) => {
                        Val::rational(BigRational::from_integer(BigInt::from(if *f == Builtin::Sin { s } else { c })))
                    }
                    None => Val::interval(trig(*f, arg(0).map(|v| v.iv))),
                },
                // π is irrational: the tightest double interval around it, never exact.
                Builtin::Pi => Val::interval(PI),
                _ => return None,
            }
        }
        _ => return None,
    };
    Some(v)
}

/// The tightest interval of doubles around π: `f64::consts::PI` is the double just
/// below π (π = 3.14159265358979323846..., the double 3.141592653589793115997...), its
/// successor 3.141592653589793560087... is just above.
pub const PI: Interval = Interval { lo: std::f64::consts::PI, hi: 3.1415926535897936 };

/// The rational `q` with `e == q·π` exactly, when `e` is a constant expression that is
/// visibly such a multiple: `pi`, constants, unary minus, sums and differences of
/// multiples, products and quotients of a multiple by an exact rational
/// ([`exact`]; a nonzero divisor), and an exact 0 (`0·π`). Anything else (a decimal
/// such as 1.5708, a variable, `sqrt(pi)`) is `None`: never a guess from digits.
pub fn pi_multiple(prog: &Program, e: &Expr) -> Option<BigRational> {
    crate::stack::deep(|| pi_multiple_inner(prog, e))
}

fn pi_multiple_inner(prog: &Program, e: &Expr) -> Option<BigRational> {
    match &e.kind {
        ExprKind::Call(Builtin::Pi, _) => Some(BigRational::one()),
        ExprKind::Var(Var::Const(c)) => pi_multiple(prog, &prog.consts.get(c.idx())?.value),
        ExprKind::Unary(UnOp::Neg, a) => pi_multiple(prog, a).map(|q| -q),
        ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), a, b) => {
            let (x, y) = (pi_multiple(prog, a)?, pi_multiple(prog, b)?);
            Some(if *op == BinOp::Add { x + y } else { x - y })
        }
        ExprKind::Binary(BinOp::Mul, a, b) => {
            let times = |m: &Expr, r: &Expr| Some(pi_multiple(prog, m)? * exact(prog, r)?);
            times(a, b).or_else(|| times(b, a))
        }
        ExprKind::Binary(BinOp::Div, a, b) => {
            let d = exact(prog, b).filter(|d| !d.is_zero())?;
            Some(pi_multiple(prog, a)? / d)
        }
        _ => exact(prog, e).filter(|q| q.is_zero()),
    }
}

/// `(cos e, sin e)` when the constant angle `e` is an exact multiple of π/2
/// ([`pi_multiple`] `q` with `2q` an integer): each is 0, 1 or -1, exactly.
pub fn quarter_turn(prog: &Program, e: &Expr) -> Option<(i64, i64)> {
    let q = pi_multiple(prog, e)?;
    let n = q * BigRational::from_integer(BigInt::from(2));
    if !n.is_integer() {
        return None;
    }
    let k = (n.to_integer() % BigInt::from(4) + BigInt::from(4)) % BigInt::from(4);
    Some(match k.to_u8()? {
        0 => (1, 0),
        1 => (0, 1),
        2 => (-1, 0),
        _ => (0, -1),
    })
}

/// `sqrt(q)` when it is rational (numerator and denominator perfect squares).
fn rational_sqrt(q: &BigRational) -> Option<BigRational> {
    if q.is_negative() {
        return None;
    }
    let (n, d) = (q.numer().sqrt(), q.denom().sqrt());
    (&n * &n == *q.numer() && &d * &d == *q.denom()).then(|| BigRational::new(n, d))
}

/// An enclosure of `sin` or `cos` over `arg`, capped to [-1, 1]; [-1, 1] when the
/// argument is unbounded. Both functions are 1-Lipschitz, so over `[mid - h, mid + h]`
/// they stay within `h` of their value at `mid`; libm's value at `mid` is within an ulp
/// or two (not correctly rounded), so 2^-50 (eight ulps of 1) more is added.
pub fn trig(f: Builtin, arg: Option<Interval>) -> Interval {
    let unit = Interval { lo: -1.0, hi: 1.0 };
    let Some(x) = arg.filter(Interval::is_finite) else { return unit };
    if x.is_exactly(0.0) {
        // The one argument where both are rational: exact, so `sin(0) == 0` holds.
        let v = if f == Builtin::Sin { 0.0 } else { 1.0 };
        return Interval { lo: v, hi: v };
    }
    let mid = (x.lo + (x.hi - x.lo) / 2.0).clamp(x.lo, x.hi);
    let half = add_out(x.hi, -mid).1.max(add_out(mid, -x.lo).1);
    let v = if f == Builtin::Sin { mid.sin() } else { mid.cos() };
    let err = add_out(half, 2f64.powi(-50)).1;
    Interval { lo: add_out(v, -err).0, hi: add_out(v, err).1 }.meet(unit)
}

/// A box around the points `(x, y, z)` satisfying `pred`, where `point(v)` says which
/// coordinate (0, 1, 2) a variable is, if any. Each coordinate may stay unbounded.
pub fn point_box(
    prog: &Program,
    pred: &Expr,
    point: &dyn Fn(&Var) -> Option<usize>,
    ranges: &dyn Ranges,
) -> [Interval; 3] {
    crate::stack::deep(|| point_box_inner(prog, pred, point, ranges))
}

fn point_box_inner(
    prog: &Program,
    pred: &Expr,
    point: &dyn Fn(&Var) -> Option<usize>,
    ranges: &dyn Ranges,
) -> [Interval; 3] {
    let coord = |e: &Expr| match &e.kind {
        ExprKind::Var(v) => point(v),
        _ => None,
    };
    let mut out = [ALL; 3];
    match &pred.kind {
        ExprKind::Binary(BinOp::And, a, b) => {
            let (x, y) = (point_box(prog, a, point, ranges), point_box(prog, b, point, ranges));
            for k in 0..3 {
                out[k] = x[k].meet(y[k]);
            }
        }
        ExprKind::Binary(BinOp::Or, a, b) => {
            let (x, y) = (point_box(prog, a, point, ranges), point_box(prog, b, point, ranges));
            for k in 0..3 {
                out[k] = x[k].hull(y[k]);
            }
        }
        ExprKind::Binary(op @ (BinOp::Le | BinOp::Lt | BinOp::Ge | BinOp::Gt | BinOp::Eq), a, b) => {
            // `p <= e`, `e <= p`, `p == e` and their mirrors.
            let (lhs, rhs) = match op {
                BinOp::Ge | BinOp::Gt => (b, a),
                _ => (a, b),
            };
            if let Some(k) = coord(lhs) {
                if let Some(r) = eval(prog, rhs, ranges) {
                    out[k].hi = r.hi;
                    if *op == BinOp::Eq {
                        out[k].lo = r.lo;
                    }
                }
            } else if let Some(k) = coord(rhs) {
                if let Some(l) = eval(prog, lhs, ranges) {
                    out[k].lo = l.lo;
                    if *op == BinOp::Eq {
                        out[k].hi = l.hi;
                    }
                }
            } else if matches!(op, BinOp::Le | BinOp::Lt) {
                // A sum of even powers of coordinates below a bound: `px^2 + py^2 <= r^2`.
                if let (Some(squares), Some(r)) = (even_powers(lhs, &coord), eval(prog, rhs, ranges)) {
                    for (k, n) in squares {
                        let m = root_up(r.hi.max(0.0), n);
                        out[k] = out[k].meet(Interval { lo: -m, hi: m });
                    }
                }
            }
        }
        _ => {}
    }
    out
}

/// An upper bound of the `n`-th root of `r >= 0`: `powf`'s guess, raised until its
/// `n`-th power (rounded down) reaches `r`.
fn root_up(r: f64, n: i64) -> f64 {
    if r == 0.0 || r.is_infinite() {
        return r;
    }
    let mut m = if n == 2 { sqrt_out(r).1 } else { r.powf(1.0 / n as f64) };
    for _ in 0..64 {
        if pow_nonneg(m, n, false) >= r {
            return m;
        }
        m = m * (1.0 + 1e-15) + f64::MIN_POSITIVE;
    }
    f64::INFINITY
}

/// `e` as a sum of terms `p_k ^ n` with even `n`, each coordinate at most once.
fn even_powers(e: &Expr, coord: &dyn Fn(&Expr) -> Option<usize>) -> Option<Vec<(usize, i64)>> {
    match &e.kind {
        ExprKind::Binary(BinOp::Add, a, b) => {
            let mut v = even_powers(a, coord)?;
            v.extend(even_powers(b, coord)?);
            Some(v)
        }
        ExprKind::Binary(BinOp::Pow, a, n) => match (coord(a), &n.kind) {
            (Some(k), ExprKind::Int(n)) if *n > 0 && n % 2 == 0 => Some(vec![(k, *n)]),
            _ => None,
        },
        ExprKind::Binary(BinOp::Mul, a, b) if a == b => coord(a).map(|k| vec![(k, 2)]),
        _ => None,
    }
}

/// A conjunct read as a bound `lhs op rhs` with `op` one of `<=`, `<`, `==` (`>=` and `>`
/// flipped); `None` for any other conjunct.
pub(crate) fn as_bound(c: &Expr) -> Option<(&Expr, &Expr, BinOp)> {
    let ExprKind::Binary(op, a, b) = &c.kind else { return None };
    let (lhs, rhs, op) = match op {
        BinOp::Ge => (&**b, &**a, BinOp::Le),
        BinOp::Gt => (&**b, &**a, BinOp::Lt),
        op => (&**a, &**b, *op),
    };
    matches!(op, BinOp::Le | BinOp::Lt | BinOp::Eq).then_some((lhs, rhs, op))
}

/// A variable [`ranges_from`] reads a bound of (a state, value, start or snapshot variable).
pub(crate) fn bounded_var(e: &Expr) -> Option<&Var> {
    match &e.kind {
        ExprKind::Var(v @ (Var::Role(..) | Var::Value(..) | Var::Own(_) | Var::Old(_) | Var::Snap(..))) => Some(v),
        _ => None,
    }
}

/// Ranges of variables read off conjuncts of the form `v op e`, `e op v` or `v == e`
/// where `e` can be bounded from what is already known (two passes, so that
/// `x == y` after `y == 1` is found).
pub fn ranges_from(prog: &Program, facts: &[&Expr], start: &dyn Ranges) -> HashMap<Var, Interval> {
    let mut known: HashMap<Var, Interval> = HashMap::new();
    let cs: Vec<&Expr> = facts.iter().flat_map(|f| f.conjuncts()).collect();
    let is_var = |e: &Expr| bounded_var(e).cloned();
    for _ in 0..2 {
        for c in &cs {
            let Some((lhs, rhs, op)) = as_bound(c) else { continue };
            let found = {
                let lookup = |v: &Var| match (known.get(v).copied(), start.range(v)) {
                    (Some(a), Some(b)) => Some(a.meet(b)),
                    (a, b) => a.or(b),
                };
                let from_left = is_var(lhs).and_then(|v| {
                    let r = eval(prog, rhs, &lookup)?;
                    let lo = if op == BinOp::Eq { r.lo } else { f64::NEG_INFINITY };
                    Some((v, Interval { lo, hi: r.hi }))
                });
                from_left.or_else(|| {
                    let v = is_var(rhs)?;
                    let l = eval(prog, lhs, &lookup)?;
                    let hi = if op == BinOp::Eq { l.hi } else { f64::INFINITY };
                    Some((v, Interval { lo: l.lo, hi }))
                })
            };
            if let Some((v, iv)) = found {
                known.entry(v).and_modify(|old| *old = old.meet(iv)).or_insert(iv);
            }
        }
    }
    known
}

#[cfg(test)]
mod tests;
