//! The canonical form of a fact of Σ (ARCHITECTURE.md, "The logical context Σ"):
//! comparisons in one orientation and arithmetic on number literals computed exactly,
//! so that the syntactic comparisons of the loop handling see equal facts as equal; and
//! which conjuncts Σ may store at all (those describing one state).

use crate::hir::expr::BinOp;
use crate::hir::*;

/// Whether a conjunct may be stored: it describes one state (no `clock`, no footprint
/// point, no contract variable left uninstantiated), mentions some variable, and is
/// not literally reflexive (`e == e`, `e <= e`).
pub(super) fn admissible(e: &Expr) -> bool {
    let mut state = false;
    let mut foreign = false;
    e.visit_vars(&mut |v, _| match v {
        Var::Role(..) | Var::Snap(..) | Var::Value(..) => state = true,
        Var::Const(_) => {}
        Var::Own(_) | Var::Old(_) | Var::Param(_) | Var::Point(_) | Var::Clock => foreign = true,
    });
    let reflexive = matches!(&e.kind, ExprKind::Binary(BinOp::Eq | BinOp::Le | BinOp::Ge, a, b) if a == b);
    state && !foreign && !reflexive && !e.is_true()
}

/// One orientation per comparison: `a >= b` is `b <= a`, `a > b` is `b < a`, and `==`,
/// `!=` put a participant's variable (else a value variable) on the left.
pub(super) fn normalize(e: Expr) -> Expr {
    let e = if needs_fold(&e) { fold(&e) } else { e };
    let rank = |x: &Expr| match &x.kind {
        ExprKind::Var(Var::Role(..) | Var::Snap(..)) => 2,
        ExprKind::Var(Var::Value(..)) => 1,
        _ => 0,
    };
    match e.kind {
        ExprKind::Binary(BinOp::Ge, a, b) => Expr { kind: ExprKind::Binary(BinOp::Le, b, a), ..e },
        ExprKind::Binary(BinOp::Gt, a, b) => Expr { kind: ExprKind::Binary(BinOp::Lt, b, a), ..e },
        ExprKind::Binary(op @ (BinOp::Eq | BinOp::Ne), a, b) if rank(&b) > rank(&a) => {
            Expr { kind: ExprKind::Binary(op, b, a), ..e }
        }
        kind => Expr { kind, ..e },
    }
}

/// Computes `+`, `-` and `*` (and unary `-`) of number literals exactly, bottom-up.
/// Results are written as the parser would read them: an integer as an `int` literal, a
/// negative number as `-` applied to a literal. What would overflow is left as it is.
fn fold(e: &Expr) -> Expr {
    e.map(&mut |n| {
        if let ExprKind::Binary(op, a, b) = &n.kind {
            let value = match (literal(a), literal(b), op) {
                (Some(x), Some(y), BinOp::Add) => x.add(y),
                (Some(x), Some(y), BinOp::Sub) => y.neg().and_then(|n| x.add(n)),
                (Some(x), Some(y), BinOp::Mul) => x.mul(y),
                _ => None,
            };
            if let Some(v) = value.and_then(|v| v.expr(n.loc)) {
                return v;
            }
        }
        n
    })
}

/// Whether [`fold`] would change `e`: some `+`, `-` or `*` has number literals (or
/// arithmetic on them) on both sides.
fn needs_fold(e: &Expr) -> bool {
    fn constant(e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, a, b) => constant(a) && constant(b),
            _ => literal(e).is_some(),
        }
    }
    e.any(|x| matches!(&x.kind, ExprKind::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, a, b) if constant(a) && constant(b)))
}

/// A decimal number `num / 10^scale`, exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Decimal {
    num: i128,
    scale: u32,
}

/// The most decimal places kept: enough for any literal a user writes, far from
/// overflowing `i128`.
const MAX_SCALE: u32 = 18;

impl Decimal {
    fn parse(lit: &str) -> Option<Decimal> {
        let (mant, exp) = match lit.split_once(['e', 'E']) {
            Some((m, e)) => (m, e.parse::<i32>().ok()?),
            None => (lit, 0),
        };
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let digits: i128 = format!("{int}{frac}").parse().ok()?;
        let scale = i32::try_from(frac.len()).ok()?.checked_sub(exp)?;
        if scale >= 0 {
            Decimal { num: digits, scale: scale as u32 }.reduced()
        } else {
            Decimal { num: digits.checked_mul(10i128.checked_pow((-scale) as u32)?)?, scale: 0 }.reduced()
        }
    }

    /// Without trailing zeros, within [`MAX_SCALE`].
    fn reduced(mut self) -> Option<Decimal> {
        while self.scale > 0 && self.num % 10 == 0 {
            self.num /= 10;
            self.scale -= 1;
        }
        (self.scale <= MAX_SCALE && self.num.unsigned_abs() < 1u128 << 100).then_some(self)
    }

    fn at_scale(self, scale: u32) -> Option<i128> {
        self.num.checked_mul(10i128.checked_pow(scale - self.scale)?)
    }

    pub(super) fn add(self, o: Decimal) -> Option<Decimal> {
        let scale = self.scale.max(o.scale);
        Decimal { num: self.at_scale(scale)?.checked_add(o.at_scale(scale)?)?, scale }.reduced()
    }

    pub(super) fn neg(self) -> Option<Decimal> {
        Some(Decimal { num: self.num.checked_neg()?, scale: self.scale })
    }

    pub(super) fn mul(self, o: Decimal) -> Option<Decimal> {
        Decimal { num: self.num.checked_mul(o.num)?, scale: self.scale + o.scale }.reduced()
    }

    /// As an expression: an `int` literal when whole, else a real literal; `-` in front
    /// when negative.
    pub(super) fn expr(self, loc: Loc) -> Option<Expr> {
        let abs = self.num.unsigned_abs();
        let lit = if self.scale == 0 {
            Expr { kind: ExprKind::Int(i64::try_from(abs).ok()?), sort: Sort::Int, loc }
        } else {
            let digits = format!("{abs:0>width$}", width = self.scale as usize + 1);
            let (int, frac) = digits.split_at(digits.len() - self.scale as usize);
            Expr { kind: ExprKind::Real(format!("{int}.{frac}")), sort: Sort::Real, loc }
        };
        Some(if self.num < 0 {
            let sort = lit.sort.clone();
            Expr { kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(lit)), sort, loc }
        } else {
            lit
        })
    }
}

/// The value of a number literal, or of `-` applied to one.
pub(super) fn literal(e: &Expr) -> Option<Decimal> {
    match &e.kind {
        ExprKind::Int(n) => Some(Decimal { num: *n as i128, scale: 0 }),
        ExprKind::Real(r) => Decimal::parse(r),
        ExprKind::Unary(crate::hir::expr::UnOp::Neg, a) => literal(a)?.neg(),
        _ => None,
    }
}

pub(super) fn var(v: Var, sort: &Sort) -> Expr {
    Expr { kind: ExprKind::Var(v), sort: sort.clone(), loc: Loc::default() }
}

pub(super) fn binary(op: BinOp, a: &Expr, b: &Expr) -> Expr {
    Expr { kind: ExprKind::Binary(op, Box::new(a.clone()), Box::new(b.clone())), sort: Sort::Bool, loc: Loc::default() }
}
