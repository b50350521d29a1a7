//! Exact evaluation of [`Expr`] over rationals, independent of Z3.
//!
//! Used to replay the SMT stage's counterexamples before they are shown and by the
//! simulator (`mochi_verify::simulate`) to run a choreography on concrete states.
//!
//! - Numbers are closed rational intervals `[lo, hi]` (`num-rational` over `num-bigint`);
//!   every `+ - * / ^`, `min`, `max`, `abs` of exact values is exact (`lo == hi`).
//! - `sqrt` of a perfect square is exact; otherwise, and for `sin`/`cos`, the result is an
//!   enclosure: a double-precision value widened outward and checked (for `sqrt`, by
//!   squaring the bounds exactly; for `sin`/`cos`, by a margin far above `libm`'s error).
//! - `pi` is a rational enclosure 20 decimals wide ([`pi`]); `sin`/`cos` of an exact
//!   multiple of π/2 ([`crate::bounds::quarter_turn`]) are exact.
//! - Comparisons and connectives are three-valued ([`Tri`]): `Unknown` when an enclosure
//!   straddles the answer. Never `True` or `False` unless that is the exact answer.
//! - Division by an interval that contains 0, `sqrt` of a possibly negative number, an
//!   unbound variable or a tuple is an [`Err`] (the caller treats it as unknown): Z3 gives
//!   those no fixed value either. Connectives skip only what their left side decides, as
//!   `hir::expr::definedness` reads them: an error on a side that is evaluated is the
//!   whole expression's.

use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Loc, Program, Sort, Var};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};
use std::fmt;

pub type Rat = BigRational;

/// A three-valued truth value (Kleene).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tri {
    True,
    False,
    Unknown,
}

impl Tri {
    pub fn of(b: bool) -> Tri {
        if b {
            Tri::True
        } else {
            Tri::False
        }
    }
    #[allow(clippy::should_implement_trait)]
    pub fn not(self) -> Tri {
        match self {
            Tri::True => Tri::False,
            Tri::False => Tri::True,
            Tri::Unknown => Tri::Unknown,
        }
    }
    pub fn and(self, o: Tri) -> Tri {
        match (self, o) {
            (Tri::False, _) | (_, Tri::False) => Tri::False,
            (Tri::True, Tri::True) => Tri::True,
            _ => Tri::Unknown,
        }
    }
    pub fn or(self, o: Tri) -> Tri {
        self.not().and(o.not()).not()
    }
}

/// A closed rational interval; exact when `lo == hi`.
#[derive(Clone, Debug, PartialEq)]
pub struct Num {
    pub lo: Rat,
    pub hi: Rat,
}

impl Num {
    pub fn exact(r: Rat) -> Num {
        Num { lo: r.clone(), hi: r }
    }
    pub fn int(i: i64) -> Num {
        Num::exact(Rat::from_integer(BigInt::from(i)))
    }
    /// `[lo, hi]`, swapped if given in the wrong order.
    pub fn range(lo: Rat, hi: Rat) -> Num {
        if lo <= hi {
            Num { lo, hi }
        } else {
            Num { lo: hi, hi: lo }
        }
    }
    pub fn is_exact(&self) -> bool {
        self.lo == self.hi
    }
    /// The exact value, if this is one.
    pub fn value(&self) -> Option<&Rat> {
        self.is_exact().then_some(&self.lo)
    }
    pub fn contains_zero(&self) -> bool {
        !self.lo.is_positive() && !self.hi.is_negative()
    }
    pub fn mid(&self) -> Rat {
        (&self.lo + &self.hi) / Rat::from_integer(BigInt::from(2))
    }
    pub fn to_f64(&self) -> f64 {
        self.mid().to_f64().unwrap_or(f64::NAN)
    }
    pub fn neg(&self) -> Num {
        Num { lo: -&self.hi, hi: -&self.lo }
    }
    pub fn add(&self, o: &Num) -> Num {
        Num { lo: &self.lo + &o.lo, hi: &self.hi + &o.hi }
    }
    pub fn sub(&self, o: &Num) -> Num {
        self.add(&o.neg())
    }
    pub fn mul(&self, o: &Num) -> Num {
        if self.is_exact() && o.is_exact() {
            return Num::exact(&self.lo * &o.lo);
        }
        let ps = [&self.lo * &o.lo, &self.lo * &o.hi, &self.hi * &o.lo, &self.hi * &o.hi];
        let lo = ps.iter().min().cloned().unwrap_or_default();
        let hi = ps.iter().max().cloned().unwrap_or_default();
        Num { lo, hi }
    }
    fn div(&self, o: &Num) -> Result<Num, String> {
        if o.contains_zero() {
            return Err("a division by a number that may be 0".into());
        }
        let inv = Num::range(o.hi.recip(), o.lo.recip());
        Ok(self.mul(&inv))
    }
    pub fn hull(&self, o: &Num) -> Num {
        Num { lo: self.lo.clone().min(o.lo.clone()), hi: self.hi.clone().max(o.hi.clone()) }
    }
    fn lt(&self, o: &Num) -> Tri {
        if self.hi < o.lo {
            Tri::True
        } else if self.lo >= o.hi {
            Tri::False
        } else {
            Tri::Unknown
        }
    }
    /// `self <= o` for every pair of values of the two enclosures, for none, or undecided.
    pub fn le(&self, o: &Num) -> Tri {
        if self.hi <= o.lo {
            Tri::True
        } else if self.lo > o.hi {
            Tri::False
        } else {
            Tri::Unknown
        }
    }
    fn eq(&self, o: &Num) -> Tri {
        if self.is_exact() && o.is_exact() {
            Tri::of(self.lo == o.lo)
        } else if self.hi < o.lo || o.hi < self.lo {
            Tri::False
        } else {
            Tri::Unknown
        }
    }
}

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.value() {
            Some(r) => f.write_str(&decimal(r)),
            None => write!(f, "[{}, {}]", decimal(&self.lo), decimal(&self.hi)),
        }
    }
}

/// A rational for people: an integer, a short exact decimal, or 6 significant decimals
/// marked `≈`.
pub fn decimal(r: &Rat) -> String {
    if r.is_integer() {
        return r.numer().to_string();
    }
    // Exact when the denominator divides a power of ten of at most 6 digits.
    for k in 1..=6u32 {
        let scaled = r * Rat::from_integer(BigInt::from(10u64.pow(k)));
        if scaled.is_integer() {
            let v = r.to_f64().unwrap_or(f64::NAN);
            return format!("{v:.*}", k as usize);
        }
    }
    format!("≈{:.6}", r.to_f64().unwrap_or(f64::NAN))
}

/// A value of the language.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum Value {
    Bool(Tri),
    Num(Num),
    /// A point or a vector.
    Vec3([Num; 3]),
}

impl Value {
    pub fn rat(r: Rat) -> Value {
        Value::Num(Num::exact(r))
    }
    pub fn num(&self) -> Result<&Num, String> {
        match self {
            Value::Num(n) => Ok(n),
            _ => Err("a number was expected".into()),
        }
    }
    pub fn tri(&self) -> Result<Tri, String> {
        match self {
            Value::Bool(t) => Ok(*t),
            _ => Err("a truth value was expected".into()),
        }
    }
    /// Whether the value is known exactly (no enclosure, no unknown truth value).
    pub fn is_exact(&self) -> bool {
        match self {
            Value::Bool(t) => *t != Tri::Unknown,
            Value::Num(n) => n.is_exact(),
            Value::Vec3(v) => v.iter().all(Num::is_exact),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(Tri::True) => f.write_str("true"),
            Value::Bool(Tri::False) => f.write_str("false"),
            Value::Bool(Tri::Unknown) => f.write_str("unknown"),
            Value::Num(n) => write!(f, "{n}"),
            Value::Vec3([x, y, z]) => write!(f, "({x}, {y}, {z})"),
        }
    }
}

/// A decimal literal (`0.65`, `1e-3`, `-12`) as an exact rational.
pub fn parse_decimal(lit: &str) -> Option<Rat> {
    // One reader of decimals for the whole checker: the interval stage's.
    crate::bounds::decimal(lit.trim())
}

/// An exact rational as an expression (`n` or `n / d`), sort `real`.
pub fn literal(r: &Rat, loc: Loc) -> Expr {
    let lit = |i: &BigInt| Expr { kind: ExprKind::Real(i.to_string()), sort: Sort::Real, loc };
    if r.is_integer() {
        return lit(r.numer());
    }
    Expr {
        kind: ExprKind::Binary(BinOp::Div, Box::new(lit(r.numer())), Box::new(lit(r.denom()))),
        sort: Sort::Real,
        loc,
    }
}

/// The values of variables.
pub trait Env {
    fn get(&self, v: &Var) -> Option<Value>;
}

impl<F: Fn(&Var) -> Option<Value>> Env for F {
    fn get(&self, v: &Var) -> Option<Value> {
        self(v)
    }
}

/// Evaluates `e` under `env` (constants are evaluated from their definitions).
pub fn eval(prog: &Program, e: &Expr, env: &dyn Env) -> Result<Value, String> {
    crate::stack::deep(|| eval_inner(prog, e, env, 0))
}

/// Evaluates a predicate to a truth value; anything undecidable is `Unknown`.
pub fn holds(prog: &Program, e: &Expr, env: &dyn Env) -> Tri {
    match eval(prog, e, env).and_then(|v| v.tri()) {
        Ok(t) => t,
        Err(_) => Tri::Unknown,
    }
}

fn eval_inner(prog: &Program, e: &Expr, env: &dyn Env, depth: usize) -> Result<Value, String> {
    if depth > 10_000 {
        return Err("an expression nested too deeply".into());
    }
    let ev = |x: &Expr| crate::stack::deep(|| eval_inner(prog, x, env, depth + 1));
    let num = |x: &Expr| -> Result<Num, String> { ev(x)?.num().cloned() };
    Ok(match &e.kind {
        ExprKind::Bool(b) => Value::Bool(Tri::of(*b)),
        ExprKind::Int(i) => Value::Num(Num::int(*i)),
        ExprKind::Real(s) => Value::rat(parse_decimal(s).ok_or_else(|| format!("the number `{s}`"))?),
        ExprKind::Var(Var::Const(c)) => {
            let def = &prog.consts.get(c.idx()).ok_or("an unknown constant")?.value;
            ev(def)?
        }
        ExprKind::Var(v) => env.get(v).ok_or_else(|| format!("no value for {v:?}"))?,
        ExprKind::Unary(UnOp::Not, a) => Value::Bool(ev(a)?.tri()?.not()),
        ExprKind::Unary(UnOp::Neg, a) => match ev(a)? {
            Value::Num(n) => Value::Num(n.neg()),
            Value::Vec3(v) => Value::Vec3(v.map(|c| c.neg())),
            Value::Bool(_) => return Err("negation of a truth value".into()),
        },
        ExprKind::Binary(op, a, b) => binary(*op, ev(a)?, || ev(b))?,
        ExprKind::If(c, a, b) => match ev(c)?.tri()? {
            Tri::True => ev(a)?,
            Tri::False => ev(b)?,
            Tri::Unknown => match (ev(a)?, ev(b)?) {
                (Value::Num(x), Value::Num(y)) => Value::Num(x.hull(&y)),
                (Value::Vec3(x), Value::Vec3(y)) => Value::Vec3([x[0].hull(&y[0]), x[1].hull(&y[1]), x[2].hull(&y[2])]),
                (Value::Bool(x), Value::Bool(y)) if x == y => Value::Bool(x),
                _ => Value::Bool(Tri::Unknown),
            },
        },
        ExprKind::Call(f, args) => {
            let arg = |i: usize| args.get(i).ok_or_else(|| format!("`{}` without arguments", f.name()));
            match f {
                Builtin::Sqrt => Value::Num(sqrt(&num(arg(0)?)?)?),
                Builtin::Sin | Builtin::Cos => match crate::bounds::quarter_turn(prog, arg(0)?) {
                    // An exact multiple of π/2: 0 or ±1, exactly.
                    Some((c, s)) => Value::Num(Num::int(if *f == Builtin::Sin { s } else { c })),
                    None => Value::Num(trig(*f, &num(arg(0)?)?)),
                },
                Builtin::Pi => Value::Num(pi()),
                Builtin::Abs => {
                    let n = num(arg(0)?)?;
                    Value::Num(if !n.lo.is_negative() {
                        n
                    } else if !n.hi.is_positive() {
                        n.neg()
                    } else {
                        Num { lo: Rat::zero(), hi: n.hi.clone().max(-n.lo.clone()) }
                    })
                }
                Builtin::Min | Builtin::Max => {
                    let (x, y) = (num(arg(0)?)?, num(arg(1)?)?);
                    Value::Num(if *f == Builtin::Min {
                        Num { lo: x.lo.min(y.lo), hi: x.hi.min(y.hi) }
                    } else {
                        Num { lo: x.lo.max(y.lo), hi: x.hi.max(y.hi) }
                    })
                }
                Builtin::Point | Builtin::Vector => Value::Vec3([num(arg(0)?)?, num(arg(1)?)?, num(arg(2)?)?]),
                Builtin::Float32 | Builtin::Float64 => {
                    // Decided on an exact value; an enclosure wider than a point is undecided.
                    let x = num(arg(0)?)?;
                    let format = crate::float::float_format(*f).ok_or("a float format")?;
                    if x.lo != x.hi {
                        return Ok(Value::Bool(Tri::Unknown));
                    }
                    Value::Bool(Tri::of(crate::float::is_float(&x.lo, format)))
                }
                Builtin::HasFlag => {
                    let flag = crate::hir::expr::const_int(prog, arg(1)?).ok_or("a flag that is not a constant")?;
                    let x = num(arg(0)?)?;
                    if x.lo != x.hi || !x.lo.is_integer() {
                        return Ok(Value::Bool(Tri::Unknown));
                    }
                    Value::Bool(Tri::of(has_flag(&x.lo, flag)))
                }
                Builtin::Dot | Builtin::Norm2 => {
                    let u = vec3(ev(arg(0)?)?)?;
                    let v = if *f == Builtin::Dot { vec3(ev(arg(1)?)?)? } else { u.clone() };
                    Value::Num(u[0].mul(&v[0]).add(&u[1].mul(&v[1])).add(&u[2].mul(&v[2])))
                }
            }
        }
        ExprKind::Component(a, i) => {
            let v = vec3(ev(a)?)?;
            Value::Num(v[(*i).min(2)].clone())
        }
        ExprKind::Tuple(_) => return Err("tuples".into()),
    })
}

/// `has_flag(x, flag)` on exact integers: every bit `k` of `flag` (a positive constant)
/// has `floor(x / 2^k) mod 2 == 1`, as the SMT encoding says it (two's complement for a
/// negative `x`).
pub fn has_flag(x: &Rat, flag: i64) -> bool {
    let two = Rat::from_integer(BigInt::from(2));
    flag > 0
        && (0..63).filter(|k| flag >> k & 1 == 1).all(|k| {
            let q = (x / Rat::from_integer(BigInt::one() << k)).floor();
            (&q - &two * (&q / &two).floor()).is_one()
        })
}

fn vec3(v: Value) -> Result<[Num; 3], String> {
    match v {
        Value::Vec3(v) => Ok(v),
        _ => Err("a point or vector was expected".into()),
    }
}

fn binary(op: BinOp, a: Value, b: impl FnOnce() -> Result<Value, String>) -> Result<Value, String> {
    use BinOp::*;
    // Connectives: short-circuit only on a definite answer (an error on the other side
    // then does not matter: the result does not depend on it). Otherwise the right side is
    // evaluated, left to right as the static checks read definedness
    // (`hir::expr::definedness`): its error is the whole expression's. Reading it as
    // `Unknown` (Kleene) made `((x < 2) || (y / 0 < 1)) || true` true where mochi's
    // semantics has no value at all.
    match op {
        And | Or | Implies => {
            let x = a.tri()?;
            let decided = match op {
                And => x == Tri::False,
                Or => x == Tri::True,
                _ => x == Tri::False,
            };
            if decided {
                return Ok(Value::Bool(Tri::of(op != And)));
            }
            let y = b()?.tri()?;
            return Ok(Value::Bool(match op {
                And => x.and(y),
                Or => x.or(y),
                _ => x.not().or(y),
            }));
        }
        _ => {}
    }
    let b = b()?;
    Ok(match (op, a, b) {
        (Pow, Value::Num(x), Value::Num(n)) => {
            let n = n.value().and_then(|n| n.is_integer().then(|| n.numer().to_u32()).flatten());
            let n = n.ok_or("a power whose exponent is not a natural number")?;
            if n > 64 {
                return Err("a power above 64".into());
            }
            let mut acc = Num::int(1);
            for _ in 0..n {
                acc = acc.mul(&x);
            }
            // An even power of an interval around 0 is not negative.
            if n % 2 == 0 && acc.lo.is_negative() {
                acc.lo = Rat::zero();
            }
            Value::Num(acc)
        }
        (Eq | Ne, x, y) => {
            let t = match (x, y) {
                (Value::Bool(x), Value::Bool(y)) => {
                    if x == Tri::Unknown || y == Tri::Unknown {
                        Tri::Unknown
                    } else {
                        Tri::of(x == y)
                    }
                }
                (Value::Num(x), Value::Num(y)) => x.eq(&y),
                (Value::Vec3(x), Value::Vec3(y)) => x[0].eq(&y[0]).and(x[1].eq(&y[1])).and(x[2].eq(&y[2])),
                _ => return Err("`==` between values of different sorts".into()),
            };
            Value::Bool(if op == Eq { t } else { t.not() })
        }
        (Lt, Value::Num(x), Value::Num(y)) => Value::Bool(x.lt(&y)),
        (Le, Value::Num(x), Value::Num(y)) => Value::Bool(x.le(&y)),
        (Gt, Value::Num(x), Value::Num(y)) => Value::Bool(y.lt(&x)),
        (Ge, Value::Num(x), Value::Num(y)) => Value::Bool(y.le(&x)),
        (Add, Value::Num(x), Value::Num(y)) => Value::Num(x.add(&y)),
        (Sub, Value::Num(x), Value::Num(y)) => Value::Num(x.sub(&y)),
        (Mul, Value::Num(x), Value::Num(y)) => Value::Num(x.mul(&y)),
        (Div, Value::Num(x), Value::Num(y)) => Value::Num(x.div(&y)?),
        (Add, Value::Vec3(u), Value::Vec3(v)) => Value::Vec3([u[0].add(&v[0]), u[1].add(&v[1]), u[2].add(&v[2])]),
        (Sub, Value::Vec3(u), Value::Vec3(v)) => Value::Vec3([u[0].sub(&v[0]), u[1].sub(&v[1]), u[2].sub(&v[2])]),
        (Mul, Value::Vec3(v), Value::Num(s)) | (Mul, Value::Num(s), Value::Vec3(v)) => {
            Value::Vec3(v.map(|c| c.mul(&s)))
        }
        (Div, Value::Vec3(v), Value::Num(s)) => {
            let [x, y, z] = v;
            Value::Vec3([x.div(&s)?, y.div(&s)?, z.div(&s)?])
        }
        (op, _, _) => return Err(format!("`{}` on values of these sorts", op.symbol())),
    })
}

fn from_f64(v: f64) -> Option<Rat> {
    Rat::from_float(v)
}

/// `sqrt` of an interval of non-negative numbers: exact for perfect squares, otherwise
/// a rational enclosure whose bounds are checked by squaring.
fn sqrt(x: &Num) -> Result<Num, String> {
    if x.lo.is_negative() {
        return Err("the square root of a number that may be negative".into());
    }
    if let Some(r) = x.value() {
        let (n, d) = (r.numer().sqrt(), r.denom().sqrt());
        if &n * &n == *r.numer() && &d * &d == *r.denom() {
            return Ok(Num::exact(Rat::new(n, d)));
        }
    }
    let lo = root_bound(&x.lo, false)?;
    let hi = root_bound(&x.hi, true)?;
    Ok(Num { lo, hi })
}

/// `sqrt` of an interval of non-negative numbers to 1e-40 or better, from integer square
/// roots: `sqrt(n / d) = sqrt(n d) / d`, scaled by 10^40 and rounded outward. For
/// confirming a witness (`smt/confirm.rs`), where [`sqrt`]'s enclosure (as wide as 1e-12)
/// leaves close comparisons undecided.
pub fn sqrt_tight(x: &Num) -> Result<Num, String> {
    if x.lo.is_negative() {
        return Err("the square root of a number that may be negative".into());
    }
    let scale = BigInt::from(10u8).pow(40);
    let root = |v: &Rat, up: bool| -> Rat {
        let m = v.numer() * v.denom() * &scale * &scale;
        let r = m.sqrt();
        let r = if up && &r * &r != m { r + BigInt::one() } else { r };
        Rat::new(r, v.denom() * &scale)
    };
    Ok(Num { lo: root(&x.lo, false), hi: root(&x.hi, true) })
}

/// A rational `s >= 0` with `s^2 <= v` (`upper = false`) or `s^2 >= v` (`upper`).
fn root_bound(v: &Rat, upper: bool) -> Result<Rat, String> {
    if v.is_zero() {
        return Ok(Rat::zero());
    }
    let f = v.to_f64().filter(|f| f.is_finite()).ok_or("a square root out of range")?;
    let mut s = from_f64(f.sqrt()).ok_or("a square root out of range")?;
    let step = Rat::new(BigInt::one(), BigInt::from(1_000_000_000_000u64));
    for _ in 0..64 {
        let sq = &s * &s;
        if (upper && sq >= *v) || (!upper && sq <= *v) {
            return Ok(if upper { s } else { s.max(Rat::zero()) });
        }
        let scale = s.abs().max(Rat::one()) * &step;
        s = if upper { s + scale } else { s - scale };
    }
    Err("a square root that could not be enclosed".into())
}

/// π as the interval `[3.14159265358979323846, 3.14159265358979323847]` (20 decimals:
/// π = 3.14159265358979323846264...): never a point, so no comparison whose answer
/// depends on π's further digits is decided.
pub fn pi() -> Num {
    let d = BigInt::from(10u8).pow(20);
    let lo = BigInt::parse_bytes(b"314159265358979323846", 10).expect("literal");
    let hi = &lo + BigInt::one();
    Num::range(Rat::new(lo, d.clone()), Rat::new(hi, d))
}

/// π as an interval 1e-50 wide (π = 3.14159265358979323846264338327950288419716939937510
/// 58209...), for confirming a witness (`smt/confirm.rs`): narrow enough that
/// a comparison with π (or with `sin`/`cos` of a multiple of it, enclosed to 1e-40) is
/// decided when the two sides differ by more than the enclosure, and left undecided
/// otherwise: never a point.
pub fn pi_tight() -> Num {
    let d = BigInt::from(10u8).pow(50);
    let lo = BigInt::parse_bytes(b"314159265358979323846264338327950288419716939937510", 10).expect("literal");
    let hi = &lo + BigInt::one();
    Num::range(Rat::new(lo, d.clone()), Rat::new(hi, d))
}

/// `sin`/`cos` of a narrow interval around a moderate argument (`|x| <= 8`), to 1e-40:
/// the Taylor polynomial of degree 79 at the interval's exact midpoint `m`, whose
/// remainder is at most `|m|^80 / 80!` (< 1e-45 for `|m| <= 8`), widened by the interval's
/// half width (both functions are 1-Lipschitz) and rounded outward to multiples of 1e-40.
/// A pose turned by `1.5707963267948966` (1.9e-17 short of π/2) then has its cosine
/// decided positive, which the double-precision enclosure (±1e-9) cannot.
fn taylor(f: Builtin, x: &Num) -> Option<Num> {
    let m = x.mid();
    let eight = Rat::from_integer(BigInt::from(8));
    if m.abs() > eight {
        return None;
    }
    const DEGREE: u32 = 79;
    // The partial sum Σ ± m^k / k! over the used k, exactly, over one denominator: with
    // m = p / q (q > 0), each term is p^k q^(D-k) (D! / k!) / (q^D D!). Integer products
    // only, and one reduction at the end (a sum of rationals reduced at every step spent
    // most of its time in gcds of ever larger numbers).
    let (p, q) = (m.numer().clone(), m.denom().clone());
    let mut ppow = Vec::with_capacity(DEGREE as usize + 1);
    ppow.push(BigInt::one());
    for k in 1..=DEGREE as usize {
        let next = &ppow[k - 1] * &p;
        ppow.push(next);
    }
    let (mut num, mut qpow, mut ratio) = (BigInt::zero(), BigInt::one(), BigInt::one());
    for k in (0..=DEGREE).rev() {
        // sin: k = 1, 3, 5, ... with signs + - + ...; cos: k = 0, 2, 4, ...
        let used = if f == Builtin::Sin { k % 2 == 1 } else { k % 2 == 0 };
        if used {
            let negative = if f == Builtin::Sin { k % 4 == 3 } else { k % 4 == 2 };
            let term = &ppow[k as usize] * &qpow * &ratio;
            if negative {
                num -= term;
            } else {
                num += term;
            }
        }
        // From k to k - 1: q^(D-k+1) and D! / (k-1)! = (D! / k!) k.
        qpow *= &q;
        ratio *= BigInt::from(k);
    }
    let factorial = (1..=DEGREE).fold(BigInt::one(), |a, k| a * BigInt::from(k));
    let sum = Rat::new(num, q.pow(DEGREE) * factorial);
    // |m|^80 / 80! <= 8^80 / 80! < 1e-45; the interval's half width; rounding to 1e-40.
    let grid = BigInt::from(10u8).pow(40);
    let pad =
        Rat::new(BigInt::one(), BigInt::from(10u8).pow(45)) + (&x.hi - &x.lo) / Rat::from_integer(BigInt::from(2));
    let lo = ((&sum - &pad) * Rat::from_integer(grid.clone())).floor() / Rat::from_integer(grid.clone());
    let hi = ((&sum + &pad) * Rat::from_integer(grid.clone())).ceil() / Rat::from_integer(grid);
    let one = Rat::one();
    Some(Num { lo: lo.max(-one.clone()), hi: hi.min(one) })
}

/// `sin`/`cos` of an interval: exact at 0, to 1e-40 for narrow moderate arguments
/// ([`taylor`]), otherwise the double-precision value widened
/// by a margin (1e-9 plus the interval's width: both functions are 1-Lipschitz), and all
/// of `[-1, 1]` for wide or huge arguments.
pub fn trig(f: Builtin, x: &Num) -> Num {
    // The simulator evaluates the same few angles (a pose's, a state's heading) at every
    // point it tests: the enclosures are remembered per thread (a function of the
    // argument alone, so the answer is the same), up to a bounded number of arguments.
    type Memo = std::collections::HashMap<(bool, Rat, Rat), Num>;
    thread_local! {
        static MEMO: std::cell::RefCell<Memo> = std::cell::RefCell::new(Memo::new());
    }
    let key = (f == Builtin::Sin, x.lo.clone(), x.hi.clone());
    if let Some(v) = MEMO.with(|m| m.borrow().get(&key).cloned()) {
        return v;
    }
    let v = trig_uncached(f, x);
    MEMO.with(|m| {
        let mut m = m.borrow_mut();
        if m.len() >= 4096 {
            m.clear();
        }
        m.insert(key, v.clone());
    });
    v
}

fn trig_uncached(f: Builtin, x: &Num) -> Num {
    let full = Num::range(Rat::from_integer(BigInt::from(-1)), Rat::one());
    if x.value().is_some_and(Zero::is_zero) {
        return Num::int(if f == Builtin::Sin { 0 } else { 1 });
    }
    let width = (&x.hi - &x.lo).to_f64().unwrap_or(f64::INFINITY);
    let m = x.mid().to_f64().unwrap_or(f64::INFINITY);
    if width.is_nan() || width >= 1e-3 || m.is_nan() || m.abs() >= 1e6 {
        return full;
    }
    if let Some(t) = taylor(f, x) {
        return t;
    }
    let v = if f == Builtin::Sin { m.sin() } else { m.cos() };
    let pad = 1e-9 + width + m.abs() * 1e-15;
    let (Some(lo), Some(hi)) = (from_f64(v - pad), from_f64(v + pad)) else { return full };
    Num { lo: lo.max(full.lo.clone()), hi: hi.min(full.hi.clone()) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::first_guard;

    /// The Taylor enclosure is tight and right: cos(1.5707963267948966) is 1.9e-17 short
    /// of 0 from above, decided positive; cos and sin of 1.5708 to 40 digits (mpmath).
    #[test]
    fn trig_of_moderate_arguments_is_enclosed_to_1e_40() {
        let num = |v: &str| Num::exact(parse_decimal(v).expect("a number"));
        let c = trig(Builtin::Cos, &num("1.5707963267948966"));
        assert!(c.lo > Rat::zero(), "{c:?}");
        assert!(c.hi < parse_decimal("2e-17").expect("a number"), "{c:?}");
        let within = |n: &Num, v: &str| {
            let v = parse_decimal(v).expect("a number");
            n.lo <= v && v <= n.hi && &n.hi - &n.lo < parse_decimal("1e-39").expect("a number")
        };
        assert!(within(&trig(Builtin::Cos, &num("1.5708")), "-0.000003673205103372508597677367136963560942421"));
        assert!(within(&trig(Builtin::Sin, &num("1.5708")), "0.9999999999932537821342563234857847001743"));
        assert!(within(&trig(Builtin::Sin, &num("-3")), "-0.1411200080598672221007448028081102798469"));
        // Outside the Taylor range: the double-precision enclosure, still sound.
        let far = trig(Builtin::Sin, &num("100"));
        let v = parse_decimal("-0.5063656411097587936565576104597854320650").expect("a number");
        assert!(far.lo <= v && v <= far.hi, "{far:?}");
    }

    /// The guard of `A -> B : [p] go`, lowered, with `A.x` bound to `x`.
    fn eval_guard(consts: &str, p: &str, x: &str) -> Tri {
        let src = format!(
            "{consts} robot R {{ state x: real; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{p}] go. end;"
        );
        let (prog, g) = first_guard(&src);
        let xv = parse_decimal(x).expect("number");
        let env = |v: &Var| match v {
            Var::Role(r, _) if r.0 == 0 => Some(Value::rat(xv.clone())),
            _ => None,
        };
        holds(&prog, &g, &env)
    }

    #[test]
    fn decimals_are_exact() {
        assert_eq!(parse_decimal("0.1").map(|r| r * Rat::from_integer(10.into())), Some(Rat::one()));
        assert_eq!(parse_decimal("1e-3"), Some(Rat::new(1.into(), 1000.into())));
        assert_eq!(parse_decimal("-2.50"), Some(Rat::new((-5).into(), 2.into())));
        assert_eq!(parse_decimal("x"), None);
    }

    #[test]
    fn arithmetic_is_exact() {
        // 0.1 + 0.2 == 0.3 holds exactly (it fails in floating point).
        assert_eq!(eval_guard("", "x + 0.2 == 0.3", "0.1"), Tri::True);
        assert_eq!(eval_guard("", "x / 3 * 3 == x", "1"), Tri::True);
        assert_eq!(eval_guard("", "x^2 == 4 && abs(0 - x) == 2 && min(x, 1) == 1", "2"), Tri::True);
        assert_eq!(eval_guard("", "x > 1 => x > 2", "1.5"), Tri::False);
        assert_eq!(eval_guard("", "(if x > 0 then x else 0 - x) == 3", "-3"), Tri::True);
        assert_eq!(
            eval_guard("", "norm2(vector(x, 0, 1)) == 5 && dot(point(1,2,3), vector(x,x,x)) == 12", "2"),
            Tri::True
        );
    }

    #[test]
    fn pi_is_an_enclosure_and_quarter_turns_are_exact() {
        // x = 3.14159265358979323846 is below π by 2.6e-21: no answer depending on those
        // digits is given, either way.
        assert_eq!(eval_guard("", "x == pi", "3.14159265358979323846"), Tri::Unknown);
        assert_eq!(eval_guard("", "x < pi", "3.14159265358979323846"), Tri::Unknown);
        assert_eq!(eval_guard("", "x < pi", "3.1415926535897932384"), Tri::True);
        assert_eq!(eval_guard("", "x > pi", "3.1415926535897932385"), Tri::True);
        assert_eq!(eval_guard("", "x == pi", "3.141592653589793"), Tri::False);
        let p = pi();
        assert!(p.lo < p.hi && p.hi.clone() - p.lo.clone() <= parse_decimal("1e-20").unwrap());
        // Quarter turns: exact 0 and ±1, so equalities decide.
        assert_eq!(eval_guard("const q = pi / 2;", "cos(q) == 0 && sin(q) == x && cos(-pi) == -x", "1"), Tri::True);
        // A decimal near π/2 is enclosed: cos(1.5708) is not 0.
        assert_eq!(eval_guard("", "cos(1.5708) == x", "0"), Tri::False);
    }

    #[test]
    fn roots_and_trigonometry_are_enclosed() {
        assert_eq!(eval_guard("", "sqrt(x) == 1.5", "2.25"), Tri::True);
        // sqrt(2)^2 is enclosed around 2: `== 2` is undecided, `> 1.99` decided.
        assert_eq!(eval_guard("", "sqrt(x)^2 == 2", "2"), Tri::Unknown);
        assert_eq!(eval_guard("", "sqrt(x) > 1.4142 && sqrt(x) < 1.4143", "2"), Tri::True);
        assert_eq!(eval_guard("", "sin(x) == 0 && cos(x) == 1", "0"), Tri::True);
        assert_eq!(eval_guard("", "sin(x) > 0.99999 && cos(x) < 0.0001 && cos(x) > -0.0001", "1.5708"), Tri::True);
        assert_eq!(eval_guard("", "sin(x) > 1", "1.5708"), Tri::False);
        assert_eq!(eval_guard("", "sqrt(x) >= 0", "-1"), Tri::Unknown);
    }

    #[test]
    fn undefined_things_are_unknown_not_false() {
        assert_eq!(eval_guard("", "1 / (x - 1) > 0", "1"), Tri::Unknown);
        // A definite false side decides a connective even if the other is undefined.
        assert_eq!(eval_guard("", "x > 5 && 1 / (x - 1) > 0", "1"), Tri::False);
        assert_eq!(eval_guard("", "x < 5 || 1 / (x - 1) > 0", "1"), Tri::True);
    }

    #[test]
    fn literals_round_trip() {
        let r = Rat::new(BigInt::from(-7), BigInt::from(3));
        let e = literal(&r, Loc::default());
        let prog = Program::default();
        assert_eq!(eval(&prog, &e, &|_: &Var| None), Ok(Value::rat(r)));
    }
}
