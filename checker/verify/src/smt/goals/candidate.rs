//! A cheap, sufficient satisfiability test without Z3: a candidate point in exact
//! rational arithmetic. It serves the vacuity guard (a context Σ shown satisfiable needs no
//! query) and the reachability questions; `false` only means "not shown".

use crate::bounds::{self, Interval};
use crate::hir::{Builtin, Expr, ExprKind, Program, Slot, Var};
use std::collections::{HashMap, HashSet};

/// A cheap, sufficient test that `facts` are satisfiable, without Z3: a candidate point
/// in exact rational arithmetic. Equalities `v == e` define `v` as `e`'s exact value, in
/// order, once `e`'s variables have values; every other variable takes a simple value read
/// off the ranges the facts give it (a point range's value, a finite range's midpoint, a
/// bound plus or minus one, else 0; integers rounded); then every fact is evaluated
/// exactly at that point. `false` means only "not shown": facts over inputs (their
/// sources' variables under another name), booleans, points, `sqrt`, `sin`, `cos`, or
/// numbers beyond 128-bit rationals are left to Z3.
pub fn witnessed(prog: &Program, facts: &[Expr]) -> bool {
    // Only real and integer state, snapshot and value variables.
    let mut simple = true;
    let mut ints = HashSet::new();
    for f in facts {
        f.visit_vars(&mut |v, _| {
            let sort = match v {
                Var::Const(_) => return,
                Var::Role(r, slot @ Slot::State(_)) | Var::Snap(r, slot @ Slot::State(_)) => {
                    prog.kind_of(*r).var(*slot).1.clone()
                }
                Var::Value(id, _) => prog.value(*id).sort.clone(),
                _ => {
                    simple = false;
                    return;
                }
            };
            match sort {
                crate::hir::Sort::Int => {
                    ints.insert(v.clone());
                }
                crate::hir::Sort::Real => {}
                _ => simple = false,
            }
        });
    }
    if !simple {
        return false;
    }
    let mut at: HashMap<Var, Rat> = HashMap::new();
    let mut defining = vec![false; facts.len()];
    loop {
        let mut grew = false;
        for (i, f) in facts.iter().enumerate() {
            if defining[i] {
                continue;
            }
            let ExprKind::Binary(crate::hir::expr::BinOp::Eq, a, b) = &f.kind else { continue };
            for (lhs, rhs) in [(a, b), (b, a)] {
                let ExprKind::Var(v) = &lhs.kind else { continue };
                if matches!(v, Var::Const(_)) || at.contains_key(v) {
                    continue;
                }
                let Some(x) = Rat::eval(prog, rhs, &at) else { continue };
                if ints.contains(v) && x.1 != 1 {
                    continue;
                }
                at.insert(v.clone(), x);
                defining[i] = true;
                grew = true;
                break;
            }
        }
        if !grew {
            break;
        }
    }
    let rest: Vec<&Expr> = facts.iter().zip(&defining).filter(|(_, d)| !**d).map(|(f, _)| f).collect();
    // Ranges only guide the choice of values (every fact is then checked exactly).
    let known = |v: &Var| at.get(v).map(|r| Interval::new(r.0 as f64 / r.1 as f64, r.0 as f64 / r.1 as f64));
    let ranges = bounds::ranges_from(prog, &rest, &known);
    let mut free = Vec::new();
    for f in &rest {
        f.visit_vars(&mut |v, _| {
            if !matches!(v, Var::Const(_)) && !at.contains_key(v) {
                free.push(v.clone());
            }
        });
    }
    for v in free {
        let i = ranges.get(&v).copied().unwrap_or(Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY });
        let x = if i.lo == i.hi {
            i.lo
        } else if i.lo.is_finite() && i.hi.is_finite() {
            i.lo / 2.0 + i.hi / 2.0
        } else if i.lo.is_finite() {
            i.lo.floor() + 1.0
        } else if i.hi.is_finite() {
            i.hi.ceil() - 1.0
        } else {
            0.0
        };
        let x = if ints.contains(&v) { x.round() } else { x };
        let Some(x) = Rat::of_f64(x) else { return false };
        at.entry(v).or_insert(x);
    }
    rest.iter().all(|f| Rat::truth(prog, f, &at) == Some(true))
}

/// An exact rational `(numerator, denominator)`, denominator positive, in lowest terms.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rat(i128, i128);

impl Rat {
    fn new(n: i128, d: i128) -> Option<Rat> {
        if d == 0 {
            return None;
        }
        let g = gcd(n.unsigned_abs(), d.unsigned_abs()).max(1) as i128;
        let (n, d) = (n / g, d / g);
        Some(if d < 0 { Rat(n.checked_neg()?, d.checked_neg()?) } else { Rat(n, d) })
    }

    /// The exact value of a double (dyadic), when it fits.
    fn of_f64(x: f64) -> Option<Rat> {
        if !x.is_finite() {
            return None;
        }
        let mut d: i128 = 1;
        let mut y = x;
        while y.fract() != 0.0 {
            y *= 2.0;
            d = d.checked_mul(2)?;
        }
        if y.abs() >= 1e30 {
            return None;
        }
        Rat::new(y as i128, d)
    }

    /// The exact value of a decimal literal such as `0.65` or `1e-3`.
    fn of_decimal(s: &str) -> Option<Rat> {
        let (mant, exp) = match s.find(['e', 'E']) {
            Some(i) => (&s[..i], s[i + 1..].parse::<i32>().ok()?),
            None => (s, 0),
        };
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let digits: i128 = format!("{int}{frac}").parse().ok()?;
        let scale = exp.checked_sub(i32::try_from(frac.len()).ok()?)?;
        let pow = 10i128.checked_pow(scale.unsigned_abs())?;
        if scale >= 0 {
            Rat::new(digits.checked_mul(pow)?, 1)
        } else {
            Rat::new(digits, pow)
        }
    }

    fn add(self, o: Rat) -> Option<Rat> {
        Rat::new(self.0.checked_mul(o.1)?.checked_add(o.0.checked_mul(self.1)?)?, self.1.checked_mul(o.1)?)
    }

    fn mul(self, o: Rat) -> Option<Rat> {
        Rat::new(self.0.checked_mul(o.0)?, self.1.checked_mul(o.1)?)
    }

    fn neg(self) -> Option<Rat> {
        Some(Rat(self.0.checked_neg()?, self.1))
    }

    fn cmp(self, o: Rat) -> Option<std::cmp::Ordering> {
        Some(self.0.checked_mul(o.1)?.cmp(&o.0.checked_mul(self.1)?))
    }

    /// The exact value of a numeric term at `at`, when it has one.
    fn eval(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<Rat> {
        use crate::hir::expr::{BinOp, UnOp};
        match &e.kind {
            ExprKind::Int(i) => Rat::new(*i as i128, 1),
            ExprKind::Real(r) => Rat::of_decimal(r),
            ExprKind::Var(Var::Const(c)) => Rat::eval(prog, &prog.consts[c.idx()].value, at),
            ExprKind::Var(v) => at.get(v).copied(),
            ExprKind::Unary(UnOp::Neg, a) => Rat::eval(prog, a, at)?.neg(),
            ExprKind::Binary(op, a, b) => {
                let x = Rat::eval(prog, a, at)?;
                if *op == BinOp::Pow {
                    let ExprKind::Int(n) = b.kind else { return None };
                    let mut r = Rat(1, 1);
                    for _ in 0..u32::try_from(n).ok().filter(|n| *n <= 64)? {
                        r = r.mul(x)?;
                    }
                    return Some(r);
                }
                let y = Rat::eval(prog, b, at)?;
                match op {
                    BinOp::Add => x.add(y),
                    BinOp::Sub => x.add(y.neg()?),
                    BinOp::Mul => x.mul(y),
                    BinOp::Div => x.mul(Rat::new(y.1, y.0)?),
                    _ => None,
                }
            }
            ExprKind::If(c, a, b) => match Rat::truth(prog, c, at)? {
                true => Rat::eval(prog, a, at),
                false => Rat::eval(prog, b, at),
            },
            ExprKind::Call(f, args) => {
                let x = Rat::eval(prog, args.first()?, at)?;
                let y = || Rat::eval(prog, args.get(1)?, at);
                match f {
                    Builtin::Min => Some(if x.cmp(y()?)?.is_le() { x } else { y()? }),
                    Builtin::Max => Some(if x.cmp(y()?)?.is_ge() { x } else { y()? }),
                    Builtin::Abs => Some(if x.0 < 0 { x.neg()? } else { x }),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// Rational bounds `(lo, hi)` on a numeric term at `at` that mentions `pi` (enclosed
    /// in `[3.141592653589793, 3.141592653589794]`): sums, differences, negation,
    /// products and quotients by a nonzero rational. `None` otherwise.
    fn enclose(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<(Rat, Rat)> {
        use crate::hir::expr::{BinOp, UnOp};
        if let Some(x) = Rat::eval(prog, e, at) {
            return Some((x, x));
        }
        match &e.kind {
            ExprKind::Call(Builtin::Pi, _) => Some((
                Rat::new(3_141_592_653_589_793, 10i128.pow(15))?,
                Rat::new(3_141_592_653_589_794, 10i128.pow(15))?,
            )),
            ExprKind::Var(Var::Const(c)) => Rat::enclose(prog, &prog.consts[c.idx()].value, at),
            ExprKind::Unary(UnOp::Neg, a) => {
                let (lo, hi) = Rat::enclose(prog, a, at)?;
                Some((hi.neg()?, lo.neg()?))
            }
            ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div), a, b) => {
                let (alo, ahi) = Rat::enclose(prog, a, at)?;
                let (blo, bhi) = Rat::enclose(prog, b, at)?;
                let ends = match op {
                    BinOp::Add => return Some((alo.add(blo)?, ahi.add(bhi)?)),
                    BinOp::Sub => return Some((alo.add(bhi.neg()?)?, ahi.add(blo.neg()?)?)),
                    BinOp::Mul => [alo.mul(blo)?, alo.mul(bhi)?, ahi.mul(blo)?, ahi.mul(bhi)?],
                    _ => {
                        // Only by a nonzero rational (a point).
                        if blo != bhi || blo.0 == 0 {
                            return None;
                        }
                        let inv = Rat::new(blo.1, blo.0)?;
                        [alo.mul(inv)?, ahi.mul(inv)?, alo.mul(inv)?, ahi.mul(inv)?]
                    }
                };
                let mut lo = ends[0];
                let mut hi = ends[0];
                for x in &ends[1..] {
                    if x.cmp(lo)?.is_lt() {
                        lo = *x;
                    }
                    if x.cmp(hi)?.is_gt() {
                        hi = *x;
                    }
                }
                Some((lo, hi))
            }
            _ => None,
        }
    }

    /// The exact truth of a predicate at `at`, when it can be computed.
    fn truth(prog: &Program, e: &Expr, at: &HashMap<Var, Rat>) -> Option<bool> {
        use crate::hir::expr::{BinOp, UnOp};
        match &e.kind {
            ExprKind::Bool(b) => Some(*b),
            ExprKind::Unary(UnOp::Not, a) => Some(!Rat::truth(prog, a, at)?),
            ExprKind::Binary(BinOp::And, a, b) => Some(Rat::truth(prog, a, at)? && Rat::truth(prog, b, at)?),
            ExprKind::Binary(BinOp::Or, a, b) => Some(Rat::truth(prog, a, at)? || Rat::truth(prog, b, at)?),
            ExprKind::Binary(BinOp::Implies, a, b) => Some(!Rat::truth(prog, a, at)? || Rat::truth(prog, b, at)?),
            ExprKind::Binary(op, a, b) => {
                let (Some(x), Some(y)) = (Rat::eval(prog, a, at), Rat::eval(prog, b, at)) else {
                    // A side that is no rational (it mentions `pi`): decided only when the
                    // enclosures of the two sides are apart.
                    let ((alo, ahi), (blo, bhi)) = (Rat::enclose(prog, a, at)?, Rat::enclose(prog, b, at)?);
                    let below = ahi.cmp(blo)?.is_lt();
                    let above = alo.cmp(bhi)?.is_gt();
                    let (le, ge) = (ahi.cmp(blo)?.is_le(), alo.cmp(bhi)?.is_ge());
                    return match op {
                        BinOp::Lt | BinOp::Le if below => Some(true),
                        BinOp::Le if le => Some(true),
                        BinOp::Lt | BinOp::Le if ge && (above || *op == BinOp::Lt) => Some(false),
                        BinOp::Gt | BinOp::Ge if above => Some(true),
                        BinOp::Ge if ge => Some(true),
                        BinOp::Gt | BinOp::Ge if le && (below || *op == BinOp::Gt) => Some(false),
                        BinOp::Eq | BinOp::Ne if below || above => Some(*op == BinOp::Ne),
                        _ => None,
                    };
                };
                let o = x.cmp(y)?;
                match op {
                    BinOp::Eq => Some(o.is_eq()),
                    BinOp::Ne => Some(o.is_ne()),
                    BinOp::Lt => Some(o.is_lt()),
                    BinOp::Le => Some(o.is_le()),
                    BinOp::Gt => Some(o.is_gt()),
                    BinOp::Ge => Some(o.is_ge()),
                    _ => None,
                }
            }
            _ => None,
        }
    }
}

pub(super) fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    #[test]
    fn witnesses_compare_with_pi_through_its_enclosure() {
        let facts = |p: &str| {
            let src = format!(
                "robot R {{ state x: real, c: real; }} system S {{ participant A: R; participant B: R; }}
                 choreography G = A -> B : [{p}] go. end;"
            );
            let (prog, g) = crate::lower::tests::first_guard(&src);
            let fs: Vec<crate::hir::Expr> = g.conjuncts().into_iter().cloned().collect();
            (prog, fs)
        };
        let shown = |p: &str| {
            let (prog, fs) = facts(p);
            super::witnessed(&prog, &fs)
        };
        assert!(shown("x == 0 && -pi <= c && c <= pi"));
        assert!(shown("x == 3.1415926535897 && x < pi && 2 * x - pi > 0"));
        // Never a witness that depends on π's digits, and never one for an empty set.
        assert!(!shown("x == 3.14159265358979323846 && x < pi"));
        assert!(!shown("x == 3.2 && x < pi"));
        assert!(!shown("c > pi && c < 3.14"));
    }
}
