//! Resolved predicates and terms. No solver types appear here: the SMT stage
//! (`smt::encode`) encodes [`Expr`] into its own terms.

use super::{ConstId, Loc, RoleId, ValueId};
pub use crate::syntax::ast::{BinOp, UnOp};

/// Sorts of Sec 4.1 (`unit`, `real`, `point`, `vector`, products) plus `bool` and `int`.
/// `Any` is the sort of a process binder before typing gives it one.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Sort {
    Unit,
    Bool,
    Int,
    Real,
    Point,
    Vector,
    Product(Vec<Sort>),
    Any,
}

impl Sort {
    pub fn is_numeric(&self) -> bool {
        matches!(self, Sort::Int | Sort::Real | Sort::Any)
    }
    pub fn is_spatial(&self) -> bool {
        matches!(self, Sort::Point | Sort::Vector | Sort::Any)
    }
    /// Whether a value of sort `self` may stand where `want` is expected (ints promote).
    pub fn fits(&self, want: &Sort) -> bool {
        match (self, want) {
            (Sort::Any, _) | (_, Sort::Any) => true,
            (Sort::Int, Sort::Real) => true,
            (Sort::Product(a), Sort::Product(b)) => a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.fits(y)),
            (a, b) => a == b,
        }
    }
}

impl std::fmt::Display for Sort {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Sort::Unit => f.write_str("unit"),
            Sort::Bool => f.write_str("bool"),
            Sort::Int => f.write_str("int"),
            Sort::Real => f.write_str("real"),
            Sort::Point => f.write_str("point"),
            Sort::Vector => f.write_str("vector"),
            Sort::Any => f.write_str("_"),
            Sort::Product(ss) => {
                f.write_str("(")?;
                for (i, s) in ss.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{s}")?;
                }
                f.write_str(")")
            }
        }
    }
}

/// A robot variable: the i-th state (X) or input (W) variable of its kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Slot {
    State(usize),
    Input(usize),
}

/// What a variable occurrence refers to. Equality and hashing are by identity: a value
/// variable is its binding site ([`ValueId`]); its name is carried for printing only.
/// Two values of one name (shadowing) are two variables everywhere: in Σ, in
/// obligations and in the SMT encoding. Where alpha-equivalence is meant (merging and
/// comparing local types, Defs 4.7-4.8), `project::equal` establishes it explicitly.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    Const(ConstId),
    /// This robot's variable, inside a primitive's contract or a kind's invariant.
    Own(Slot),
    /// `old(x)`: state variable `x` when the motion started.
    Old(usize),
    /// A primitive's parameter.
    Param(usize),
    /// A coordinate of the footprint's point (0, 1, 2 for x, y, z).
    Point(usize),
    /// Time elapsed since the motion started.
    Clock,
    /// A participant's variable (`Cart.x`).
    Role(RoleId, Slot),
    /// A value variable: its binding site, and its name for printing.
    Value(ValueId, String),
    /// A participant's state variable as it was when its latest motion started: what
    /// `old(x)` of that motion refers to, kept in the logical context Σ after the
    /// motion so that a post such as `x == old(x)` still links to earlier facts.
    Snap(RoleId, Slot),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Builtin {
    Sqrt,
    Min,
    Max,
    Abs,
    Sin,
    Cos,
    Point,
    Vector,
    Dot,
    Norm2,
    /// The constant π (exactly; written `pi`, a reserved word, and held as a call with
    /// no arguments). Being irrational, it is never a rational value anywhere: bounds
    /// enclose it, the solver sees a fresh real inside a rational enclosure.
    Pi,
}

impl Builtin {
    pub fn from_name(s: &str) -> Option<Builtin> {
        Some(match s {
            "sqrt" => Builtin::Sqrt,
            "min" => Builtin::Min,
            "max" => Builtin::Max,
            "abs" => Builtin::Abs,
            "sin" => Builtin::Sin,
            "cos" => Builtin::Cos,
            "point" => Builtin::Point,
            "vector" => Builtin::Vector,
            "dot" => Builtin::Dot,
            "norm2" => Builtin::Norm2,
            "pi" => Builtin::Pi,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            Builtin::Sqrt => "sqrt",
            Builtin::Min => "min",
            Builtin::Max => "max",
            Builtin::Abs => "abs",
            Builtin::Sin => "sin",
            Builtin::Cos => "cos",
            Builtin::Point => "point",
            Builtin::Vector => "vector",
            Builtin::Dot => "dot",
            Builtin::Norm2 => "norm2",
            Builtin::Pi => "pi",
        }
    }
    pub fn arity(self) -> usize {
        match self {
            Builtin::Sqrt | Builtin::Abs | Builtin::Sin | Builtin::Cos | Builtin::Norm2 => 1,
            Builtin::Min | Builtin::Max | Builtin::Dot => 2,
            Builtin::Point | Builtin::Vector => 3,
            Builtin::Pi => 0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Expr {
    pub kind: ExprKind,
    pub sort: Sort,
    pub loc: Loc,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ExprKind {
    Int(i64),
    Real(String),
    Bool(bool),
    Var(Var),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    Call(Builtin, Vec<Expr>),
    If(Box<Expr>, Box<Expr>, Box<Expr>),
    Tuple(Vec<Expr>),
    /// Component 0, 1 or 2 of a point or vector.
    Component(Box<Expr>, usize),
}

impl Expr {
    pub fn bool(b: bool, loc: Loc) -> Expr {
        Expr { kind: ExprKind::Bool(b), sort: Sort::Bool, loc }
    }

    pub fn is_true(&self) -> bool {
        matches!(self.kind, ExprKind::Bool(true))
    }

    /// `self && other`, folding `true`.
    pub fn and(self, other: Expr) -> Expr {
        if self.is_true() {
            return other;
        }
        if other.is_true() {
            return self;
        }
        let loc = self.loc;
        Expr { kind: ExprKind::Binary(BinOp::And, Box::new(self), Box::new(other)), sort: Sort::Bool, loc }
    }

    /// The conjuncts of `self` (split at every `&&`), left to right, without `true`.
    /// Iterative, so that long conjunctions cannot exhaust the stack.
    pub fn conjuncts(&self) -> Vec<&Expr> {
        let mut out = Vec::new();
        let mut todo = vec![self];
        while let Some(e) = todo.pop() {
            match &e.kind {
                ExprKind::Binary(BinOp::And, a, b) => {
                    todo.push(b);
                    todo.push(a);
                }
                _ if e.is_true() => {}
                _ => out.push(e),
            }
        }
        out
    }

    /// Calls `f` on every variable occurrence.
    pub fn visit_vars(&self, f: &mut dyn FnMut(&Var, Loc)) {
        match &self.kind {
            ExprKind::Var(v) => f(v, self.loc),
            ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) => {}
            ExprKind::Unary(_, a) | ExprKind::Component(a, _) => a.visit_vars(f),
            ExprKind::Binary(_, a, b) => {
                a.visit_vars(f);
                b.visit_vars(f);
            }
            ExprKind::If(a, b, c) => {
                a.visit_vars(f);
                b.visit_vars(f);
                c.visit_vars(f);
            }
            ExprKind::Call(_, args) | ExprKind::Tuple(args) => args.iter().for_each(|a| a.visit_vars(f)),
        }
    }
}
