//! Three-valued truth of a footprint's rewritten predicate on a piece of the search, over
//! compiled terms.

use super::*;

/// A predicate compiled for many three-valued evaluations (the rules of
/// [`crate::bounds::truth`], on [`Compiled`] terms).
pub(super) enum Tree {
    Const(bool),
    Not(Box<Tree>),
    And(Box<Tree>, Box<Tree>),
    Or(Box<Tree>, Box<Tree>),
    Cmp(BinOp, Compiled, Compiled),
    Unknown,
}

impl Tree {
    pub(super) fn new(prog: &Program, e: &Expr, table: &mut VarTable) -> Tree {
        crate::stack::deep(|| match &e.kind {
            ExprKind::Bool(b) => Tree::Const(*b),
            ExprKind::Unary(UnOp::Not, a) => Tree::Not(Box::new(Tree::new(prog, a, table))),
            ExprKind::Binary(BinOp::And, a, b) => {
                Tree::And(Box::new(Tree::new(prog, a, table)), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(BinOp::Or, a, b) => {
                Tree::Or(Box::new(Tree::new(prog, a, table)), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(BinOp::Implies, a, b) => {
                Tree::Or(Box::new(Tree::Not(Box::new(Tree::new(prog, a, table)))), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
                if a.sort.is_numeric() && b.sort.is_numeric() =>
            {
                Tree::Cmp(*op, Compiled::new(prog, a, table), Compiled::new(prog, b, table))
            }
            _ => Tree::Unknown,
        })
    }

    /// The first comparison (in the order the connectives read them) whose truth is not
    /// settled on the box, if the predicate's is not.
    pub(super) fn undecided(&self, env: &[Option<Interval>], work: &mut Vec<Option<Interval>>) -> Option<&Tree> {
        match self {
            Tree::Const(_) | Tree::Unknown => None,
            Tree::Not(a) => a.undecided(env, work),
            Tree::And(a, b) | Tree::Or(a, b) => match a.truth(env, work) {
                None => a.undecided(env, work),
                Some(_) => b.undecided(env, work),
            },
            Tree::Cmp(..) => (self.truth(env, work).is_none()).then_some(self),
        }
    }

    /// `Some(b)` when the predicate is `b` at every point of the box `env`.
    pub(super) fn truth(&self, env: &[Option<Interval>], work: &mut Vec<Option<Interval>>) -> Option<bool> {
        match self {
            Tree::Const(b) => Some(*b),
            Tree::Unknown => None,
            Tree::Not(a) => a.truth(env, work).map(|b| !b),
            Tree::And(a, b) => match a.truth(env, work) {
                Some(false) => Some(false),
                x => match (x, b.truth(env, work)) {
                    (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
            },
            Tree::Or(a, b) => match a.truth(env, work) {
                Some(true) => Some(true),
                x => match (x, b.truth(env, work)) {
                    (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
            },
            Tree::Cmp(op, a, b) => {
                let (x, y) = (a.eval(env, work)?, b.eval(env, work)?);
                crate::bounds::truth::compare(*op, x, y)
            }
        }
    }
}
