//! Footprints whose comparisons are affine in the shape's point: the predicate as a tree of
//! such comparisons over the state, for the search that splits only the state.

use super::*;

/// A goal whose comparisons are affine in the shape's point, compiled over the state.
pub(super) enum ATree {
    Const(bool),
    Not(Box<ATree>),
    And(Box<ATree>, Box<ATree>),
    Or(Box<ATree>, Box<ATree>),
    /// `Σ a_i q_i + b op 0` (a missing coefficient is 0).
    Cmp {
        op: BinOp,
        a: [Option<Compiled>; 3],
        b: Compiled,
    },
}

/// `Σ a_i q_i + b`, each coefficient an expression free of the point (`None`: 0).
pub(super) type Affine = ([Option<Expr>; 3], Option<Expr>);

impl ATree {
    /// `None` unless every comparison of `e` is affine in the shape's point.
    pub(super) fn new(prog: &Program, e: &Expr, table: &mut VarTable) -> Option<ATree> {
        crate::stack::deep(|| {
            Some(match &e.kind {
                ExprKind::Bool(b) => ATree::Const(*b),
                ExprKind::Unary(UnOp::Not, a) => ATree::Not(Box::new(ATree::new(prog, a, table)?)),
                ExprKind::Binary(BinOp::And, a, b) => {
                    ATree::And(Box::new(ATree::new(prog, a, table)?), Box::new(ATree::new(prog, b, table)?))
                }
                ExprKind::Binary(BinOp::Or, a, b) => {
                    ATree::Or(Box::new(ATree::new(prog, a, table)?), Box::new(ATree::new(prog, b, table)?))
                }
                ExprKind::Binary(BinOp::Implies, a, b) => ATree::Or(
                    Box::new(ATree::Not(Box::new(ATree::new(prog, a, table)?))),
                    Box::new(ATree::new(prog, b, table)?),
                ),
                ExprKind::Binary(
                    op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne),
                    l,
                    r,
                ) if l.sort.is_numeric() && r.sort.is_numeric() => {
                    let (a, b) = affine(&bin(BinOp::Sub, (**l).clone(), (**r).clone()))?;
                    let a = a.map(|c| c.map(|c| Compiled::new(prog, &c, table)));
                    let b = Compiled::new(prog, &b.unwrap_or_else(|| int(0)), table);
                    ATree::Cmp { op: *op, a, b }
                }
                _ => return None,
            })
        })
    }

    /// `Some(v)` when the goal is `v` at every point of the shape, at every state of `env`.
    pub(super) fn truth(
        &self,
        env: &[Option<Interval>],
        work: &mut Vec<Option<Interval>>,
        support: &Support,
    ) -> Option<bool> {
        match self {
            ATree::Const(b) => Some(*b),
            ATree::Not(a) => a.truth(env, work, support).map(|b| !b),
            ATree::And(a, b) => match a.truth(env, work, support) {
                Some(false) => Some(false),
                x => match (x, b.truth(env, work, support)) {
                    (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
            },
            ATree::Or(a, b) => match a.truth(env, work, support) {
                Some(true) => Some(true),
                x => match (x, b.truth(env, work, support)) {
                    (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
            },
            ATree::Cmp { op, a, b } => {
                let b = b.eval(env, work)?;
                let mut coef = [Interval::point(0.0); 3];
                for (c, x) in coef.iter_mut().zip(a) {
                    if let Some(x) = x {
                        *c = x.eval(env, work)?;
                    }
                }
                crate::bounds::truth::compare(*op, support.range(coef, b), Interval::point(0.0))
            }
        }
    }
}

/// `e` as `Σ a_i q_i + b` with every `a_i` and `b` free of the point, by the identities of
/// sums and of products and quotients by a factor free of the point; `None` otherwise.
pub(super) fn affine(e: &Expr) -> Option<Affine> {
    let has_q = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Point(_)));
    if !has_q(e) {
        return Some(([None, None, None], Some(e.clone())));
    }
    let add = |x: Option<Expr>, y: Option<Expr>| match (x, y) {
        (Some(x), Some(y)) => Some(bin(BinOp::Add, x, y)),
        (x, None) => x,
        (None, y) => y,
    };
    let map = |(a, b): Affine, f: &dyn Fn(Expr) -> Expr| -> Affine { (a.map(|c| c.map(f)), b.map(f)) };
    let neg = |x: Expr| Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(x)), sort: Sort::Real, loc: Loc::default() };
    crate::stack::deep(|| match &e.kind {
        ExprKind::Var(Var::Point(i)) if *i < 3 => {
            let mut a = [None, None, None];
            a[*i] = Some(int(1));
            Some((a, None))
        }
        ExprKind::Unary(UnOp::Neg, x) => Some(map(affine(x)?, &neg)),
        ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), x, y) => {
            let (ax, bx) = affine(x)?;
            let mut y = affine(y)?;
            if *op == BinOp::Sub {
                y = map(y, &neg);
            }
            let (ay, by) = y;
            let [x0, x1, x2] = ax;
            let [y0, y1, y2] = ay;
            Some(([add(x0, y0), add(x1, y1), add(x2, y2)], add(bx, by)))
        }
        ExprKind::Binary(BinOp::Mul, x, y) if !has_q(x) => {
            Some(map(affine(y)?, &|t| bin(BinOp::Mul, (**x).clone(), t)))
        }
        ExprKind::Binary(BinOp::Mul, x, y) if !has_q(y) => {
            Some(map(affine(x)?, &|t| bin(BinOp::Mul, t, (**y).clone())))
        }
        ExprKind::Binary(BinOp::Div, x, y) if !has_q(y) => {
            Some(map(affine(x)?, &|t| bin(BinOp::Div, t, (**y).clone())))
        }
        _ => None,
    })
}

/// `e` with every comparison `abs(u) <= v` (`<`, and `v >= abs(u)`, `v > abs(u)`) written
/// `u <= v && -u <= v`: the same truth at every point (`abs` is total), and two comparisons
/// each affine where `u` and `v` are.
pub(super) fn split_abs(e: &Expr) -> Expr {
    let neg =
        |x: &Expr| Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(x.clone())), sort: x.sort.clone(), loc: x.loc };
    let abs_of = |x: &Expr| match &x.kind {
        ExprKind::Call(Builtin::Abs, args) if args.len() == 1 => Some(args[0].clone()),
        _ => None,
    };
    crate::stack::deep(|| match &e.kind {
        ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => bin(*op, split_abs(a), split_abs(b)),
        ExprKind::Unary(UnOp::Not, a) => Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(split_abs(a))), ..e.clone() },
        ExprKind::Binary(op @ (BinOp::Le | BinOp::Lt), a, b) if abs_of(a).is_some() => {
            let u = abs_of(a).unwrap_or_else(|| (**a).clone());
            bin(BinOp::And, bin(*op, u.clone(), (**b).clone()), bin(*op, neg(&u), (**b).clone()))
        }
        ExprKind::Binary(op @ (BinOp::Ge | BinOp::Gt), a, b) if abs_of(b).is_some() => {
            let u = abs_of(b).unwrap_or_else(|| (**b).clone());
            bin(BinOp::And, bin(*op, (**a).clone(), u.clone()), bin(*op, (**a).clone(), neg(&u)))
        }
        _ => e.clone(),
    })
}
