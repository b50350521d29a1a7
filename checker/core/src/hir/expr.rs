//! Resolved predicates and terms. No solver types appear here: the SMT stage
//! (`smt::encode`) encodes [`Expr`] into its own terms.
//!
//! Passes over an expression use its generic traversals, [`Expr::visit`], [`Expr::any`]
//! and [`Expr::map`]; the predicate helpers the later stages share ([`map_vars`],
//! [`subst_values`], [`mentions`], [`conjuncts`], [`and_all`], [`implies`], [`not`]) are
//! built on them here.

use super::{ConstId, Loc, RoleId, ValueId};
pub use crate::syntax::ast::{BinOp, UnOp};
use std::collections::HashMap;
use std::ops::ControlFlow;

/// Sorts of Sec 4.1 (`unit`, `real`, `point`, `vector`, products) plus `bool` and `int`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Sort {
    Unit,
    Bool,
    Int,
    Real,
    Point,
    Vector,
    Product(Vec<Sort>),
    /// A string: a MAVLink `char[N]` field or a string literal. The only
    /// operations are `==` and `!=`. Encoded as an integer: each distinct literal of the
    /// program is one code ([`Program::strings`](super::Program)), so two literals are equal
    /// iff they are the same text, and a variable is any integer (a code of a literal, or
    /// a string no literal writes). Sound and complete for `==`/`!=` (LANGUAGE.md).
    Str,
    /// The sort of a process binder before typing gives it the payload's: open, not
    /// wrong. An operation on it checks what it can and leaves the result open where
    /// it depends on it.
    Any,
    /// The sort of [`Expr::error`], an expression that failed to lower, its diagnostic
    /// already reported. It fits every sort (nothing more is said about it), and an
    /// expression with a failed part fails as a whole; see [`Expr::error`].
    Error,
}

impl Sort {
    pub fn is_numeric(&self) -> bool {
        matches!(self, Sort::Int | Sort::Real | Sort::Any | Sort::Error)
    }
    pub fn is_spatial(&self) -> bool {
        matches!(self, Sort::Point | Sort::Vector | Sort::Any | Sort::Error)
    }
    /// Whether a value of sort `self` may stand where `want` is expected (ints promote).
    pub fn fits(&self, want: &Sort) -> bool {
        match (self, want) {
            (Sort::Any | Sort::Error, _) | (_, Sort::Any | Sort::Error) => true,
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
            Sort::Str => f.write_str("str"),
            Sort::Any => f.write_str("_"),
            // Never in a message: every check accepts it.
            Sort::Error => f.write_str("{error}"),
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
    /// `has_flag(x, F)` (MAVLink bitmasks): every bit set in the constant
    /// positive integer `F` is set in the integer `x`. Lowering checks that `F` is one
    /// ([`const_int`]); the SMT stage encodes each bit `k` exactly as
    /// `(x div 2^k) mod 2 == 1` (Euclidean division, so a negative `x` reads as its
    /// two's complement with infinitely many leading ones).
    HasFlag,
    /// `x` is a finite IEEE 754 binary32 value (a MAVLink `float` field's value on the
    /// wire). Not written by users: lowering conjoins it to a `float` field's refinement,
    /// as it conjoins an integer field's wire range (`lower::mav`, "Floats are float32").
    Float32,
    /// `x` is a finite IEEE 754 binary64 value (a MAVLink `double` field).
    Float64,
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
            "has_flag" => Builtin::HasFlag,
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
            Builtin::HasFlag => "has_flag",
            Builtin::Float32 => "float32",
            Builtin::Float64 => "float64",
        }
    }
    pub fn arity(self) -> usize {
        match self {
            Builtin::Sqrt
            | Builtin::Abs
            | Builtin::Sin
            | Builtin::Cos
            | Builtin::Norm2
            | Builtin::Float32
            | Builtin::Float64 => 1,
            Builtin::Min | Builtin::Max | Builtin::Dot | Builtin::HasFlag => 2,
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

    /// An expression that failed to lower; the error that says why is reported already.
    /// Its sort is [`Sort::Error`] (it fits everywhere, so nothing cascades from it) and
    /// its kind the empty tuple, which no later stage gives a value: the SMT encoding and
    /// exact evaluation refuse tuples, so if one ever got that far it would make a query
    /// unknown, never hold (as `true` would). It does not get that far:
    /// a program lowered with errors is rejected before any later stage runs (the driver
    /// stops after `names`, `mochi simulate` before simulating).
    pub fn error(loc: Loc) -> Expr {
        Expr { kind: ExprKind::Tuple(Vec::new()), sort: Sort::Error, loc }
    }

    pub fn is_error(&self) -> bool {
        self.sort == Sort::Error
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
        self.visit(|e| {
            if let ExprKind::Var(v) = &e.kind {
                f(v, e.loc)
            }
        })
    }

    // ---- the generic traversals ---------------------------------------------------
    //
    // Every pass over an expression is one of these: `visit` and `any` read it (pre-order),
    // `map` rebuilds it bottom-up; all grow the stack on demand (`crate::stack::deep`), so
    // no depth exhausts it. A new `ExprKind` is handled here once, not in each pass.

    /// Calls `f` on every node of `self`, parents before children, left to right.
    pub fn visit(&self, mut f: impl FnMut(&Expr)) {
        let _: ControlFlow<()> = self.walk(&mut |e| {
            f(e);
            ControlFlow::Continue(())
        });
    }

    /// Whether some node of `self` satisfies `pred` (pre-order; stops at the first).
    pub fn any(&self, mut pred: impl FnMut(&Expr) -> bool) -> bool {
        self.walk(&mut |e| if pred(e) { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }).is_break()
    }

    fn walk<B>(&self, f: &mut impl FnMut(&Expr) -> ControlFlow<B>) -> ControlFlow<B> {
        f(self)?;
        // Recursion (no allocation: these run for every fact of every obligation), each
        // step on a stack that grows on demand.
        let mut sub = |e: &Expr| crate::stack::deep(|| e.walk(f));
        match &self.kind {
            ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => ControlFlow::Continue(()),
            ExprKind::Unary(_, a) | ExprKind::Component(a, _) => sub(a),
            ExprKind::Binary(_, a, b) => {
                sub(a)?;
                sub(b)
            }
            ExprKind::If(a, b, c) => {
                sub(a)?;
                sub(b)?;
                sub(c)
            }
            ExprKind::Call(_, xs) | ExprKind::Tuple(xs) => xs.iter().try_for_each(sub),
        }
    }

    /// Rebuilds `self` bottom-up: each node, with its children already mapped, is given
    /// to `f`, which returns it or its replacement (a replacement is not traversed again).
    pub fn map(&self, f: &mut impl FnMut(Expr) -> Expr) -> Expr {
        crate::stack::deep(|| {
            let kind = match &self.kind {
                ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => self.kind.clone(),
                ExprKind::Unary(op, a) => ExprKind::Unary(*op, Box::new(a.map(f))),
                ExprKind::Component(a, i) => ExprKind::Component(Box::new(a.map(f)), *i),
                ExprKind::Binary(op, a, b) => ExprKind::Binary(*op, Box::new(a.map(f)), Box::new(b.map(f))),
                ExprKind::If(a, b, c) => ExprKind::If(Box::new(a.map(f)), Box::new(b.map(f)), Box::new(c.map(f))),
                ExprKind::Call(b, xs) => ExprKind::Call(*b, xs.iter().map(|a| a.map(f)).collect()),
                ExprKind::Tuple(xs) => ExprKind::Tuple(xs.iter().map(|a| a.map(f)).collect()),
            };
            f(Expr { kind, sort: self.sort.clone(), loc: self.loc })
        })
    }
}

// ---- predicate helpers (on top of the traversals; used by subtyping, Σ and typing) ----

/// A value variable as an expression.
/// The value of a closed integer term: an integer literal, a constant whose value is one,
/// and `-`, `+`, `-`, `*` of those (checked: `None` on overflow or anything else). Used
/// for `has_flag`'s flag (lowering checks it, the SMT stage and the exact evaluator read
/// it back); constants are acyclic once lowered, and the depth is bounded by `fuel`.
pub fn const_int(prog: &super::Program, e: &Expr) -> Option<i64> {
    fn go(prog: &super::Program, e: &Expr, fuel: u32) -> Option<i64> {
        let fuel = fuel.checked_sub(1)?;
        match &e.kind {
            ExprKind::Int(i) if e.sort == Sort::Int => Some(*i),
            ExprKind::Var(Var::Const(c)) => {
                let c = prog.consts.get(c.idx())?;
                if c.sort != Sort::Int {
                    return None;
                }
                go(prog, &c.value, fuel)
            }
            ExprKind::Unary(UnOp::Neg, a) => go(prog, a, fuel)?.checked_neg(),
            ExprKind::Binary(op, a, b) => {
                let (a, b) = (go(prog, a, fuel)?, go(prog, b, fuel)?);
                match op {
                    BinOp::Add => a.checked_add(b),
                    BinOp::Sub => a.checked_sub(b),
                    BinOp::Mul => a.checked_mul(b),
                    BinOp::Pow => a.checked_pow(u32::try_from(b).ok()?),
                    _ => None,
                }
            }
            _ => None,
        }
    }
    go(prog, e, 64)
}

pub fn value_expr(id: ValueId, name: &str, sort: &Sort) -> Expr {
    Expr { kind: ExprKind::Var(Var::Value(id, name.to_string())), sort: sort.clone(), loc: Loc::default() }
}

/// Rebuilds `e`, replacing each variable occurrence (given with its sort) for which
/// `f` answers; the replacement takes the occurrence's location.
pub fn map_vars(e: &Expr, f: &mut dyn FnMut(&Var, &Sort) -> Option<Expr>) -> Expr {
    e.map(&mut |n| match &n.kind {
        ExprKind::Var(v) => match f(v, &n.sort) {
            Some(r) => Expr { loc: n.loc, ..r },
            None => n,
        },
        _ => n,
    })
}

/// Substitutes value variables by binding site.
pub fn subst_values(e: &Expr, map: &HashMap<ValueId, Expr>) -> Expr {
    if map.is_empty() {
        return e.clone();
    }
    map_vars(e, &mut |v, _| match v {
        Var::Value(id, _) => map.get(id).cloned(),
        _ => None,
    })
}

/// Whether some variable of `e` satisfies `pred`.
pub fn mentions(e: &Expr, pred: &dyn Fn(&Var) -> bool) -> bool {
    e.any(|n| matches!(&n.kind, ExprKind::Var(v) if pred(v)))
}

/// The conjuncts of `e`, without `true`, appended to `out`.
pub fn conjuncts(e: &Expr, out: &mut Vec<Expr>) {
    out.extend(e.conjuncts().into_iter().cloned());
}

/// The conjunction of `items` (`true` when empty).
pub fn and_all(items: impl IntoIterator<Item = Expr>, loc: Loc) -> Expr {
    items.into_iter().fold(Expr::bool(true, loc), Expr::and)
}

/// `a => b`, or `b` when `a` is `true`.
pub fn implies(a: Expr, b: Expr) -> Expr {
    if a.is_true() {
        return b;
    }
    let loc = b.loc;
    Expr { kind: ExprKind::Binary(BinOp::Implies, Box::new(a), Box::new(b)), sort: Sort::Bool, loc }
}

/// `!a`.
pub fn not(a: Expr) -> Expr {
    let loc = a.loc;
    Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(a)), sort: Sort::Bool, loc }
}

/// The condition under which evaluating `e` is defined: every division has a non-zero
/// divisor, every `sqrt` a non-negative argument, every power with a negative exponent a
/// non-zero base. `&&`, `||`, `=>` and `if` evaluate left to right and only what they
/// need, so `p != 0 && r == 540 / p` is defined everywhere: the condition of the right
/// operand is asked only where the left one lets it be evaluated. `true` when `e` has no
/// partial operator (every other operator and builtin is total). The one definition every
/// obligation that asks whether a value can be or must be computed conjoins: see
/// [`defined_and`].
///
/// Why: the SMT encoding makes an undefined value an unconstrained one (`sqrt` of a
/// negative is a fresh real, `x / 0` Z3's unspecified quotient). That is sound where the
/// expression is *assumed* (a fact about a value that exists says nothing false when the
/// value is arbitrary), and unsound where it is *proved* or asked to be *satisfiable*: a
/// refinement `v == sqrt(e)` with `e < 0` is satisfied by some arbitrary `v` in the
/// encoding, while no value on the wire satisfies it.
pub fn definedness(e: &Expr) -> Expr {
    crate::stack::deep(|| {
        let loc = e.loc;
        let zero = Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc };
        let cmp = |op: BinOp, a: &Expr| Expr {
            kind: ExprKind::Binary(op, Box::new(a.clone()), Box::new(zero.clone())),
            sort: Sort::Bool,
            loc,
        };
        // `a => d`, folding a `true` consequent (the antecedent is folded by `implies`).
        let when = |a: Expr, d: Expr| if d.is_true() { d } else { implies(a, d) };
        // A literal's sign, when it is read off exactly (a decimal that underflows a double
        // reads as 0: its condition is kept, which only asks more).
        let sign = |a: &Expr| match &a.kind {
            ExprKind::Int(i) => Some(i.signum() as f64),
            ExprKind::Real(r) => r.parse::<f64>().ok().map(|v| if v == 0.0 { 0.0 } else { v.signum() }),
            _ => None,
        };
        let nonzero =
            |a: &Expr| if sign(a).is_some_and(|s| s != 0.0) { Expr::bool(true, loc) } else { cmp(BinOp::Ne, a) };
        match &e.kind {
            ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => Expr::bool(true, loc),
            ExprKind::Unary(_, a) | ExprKind::Component(a, _) => definedness(a),
            ExprKind::Tuple(xs) => and_all(xs.iter().map(definedness), loc),
            ExprKind::Call(b, xs) => {
                let args = and_all(xs.iter().map(definedness), loc);
                match (b, xs.first()) {
                    (Builtin::Sqrt, Some(a)) if sign(a).is_some_and(|s| s >= 0.0) => args,
                    (Builtin::Sqrt, Some(a)) => args.and(cmp(BinOp::Ge, a)),
                    _ => args,
                }
            }
            ExprKind::If(c, x, y) => {
                definedness(c).and(when((**c).clone(), definedness(x))).and(when(not((**c).clone()), definedness(y)))
            }
            ExprKind::Binary(op, a, b) => {
                let (da, db) = (definedness(a), definedness(b));
                match op {
                    BinOp::And | BinOp::Implies => da.and(when((**a).clone(), db)),
                    BinOp::Or => da.and(when(not((**a).clone()), db)),
                    BinOp::Div => da.and(db).and(nonzero(b)),
                    BinOp::Pow if matches!(b.kind, ExprKind::Int(n) if n < 0) => da.and(db).and(nonzero(a)),
                    _ => da.and(db),
                }
            }
        }
    })
}

/// `definedness(e) && e`: `e` holds and can be evaluated. What an obligation proves or asks
/// to be satisfiable, wherever `e` may apply a partial operator ([`definedness`]).
pub fn defined_and(e: Expr) -> Expr {
    definedness(&e).and(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(i: usize) -> Expr {
        Expr { kind: ExprKind::Var(Var::Param(i)), sort: Sort::Real, loc: Loc::default() }
    }

    fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
        Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Real, loc: Loc::default() }
    }

    /// `if p0 < p1 then min(p2, -p3) else (p4, p5).x`, every node kind with children.
    fn sample() -> Expr {
        let call = Expr {
            kind: ExprKind::Call(
                Builtin::Min,
                vec![param(2), Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(param(3))), ..param(3) }],
            ),
            ..param(0)
        };
        let tuple = Expr { kind: ExprKind::Tuple(vec![param(4), param(5)]), ..param(0) };
        let comp = Expr { kind: ExprKind::Component(Box::new(tuple), 0), ..param(0) };
        let cond = bin(BinOp::Lt, param(0), param(1));
        Expr { kind: ExprKind::If(Box::new(cond), Box::new(call), Box::new(comp)), ..param(0) }
    }

    fn params(e: &Expr) -> Vec<usize> {
        let mut out = Vec::new();
        e.visit_vars(&mut |v, _| {
            if let Var::Param(i) = v {
                out.push(*i)
            }
        });
        out
    }

    #[test]
    fn visit_reaches_every_node_parents_first_left_to_right() {
        let e = sample();
        assert_eq!(params(&e), vec![0, 1, 2, 3, 4, 5]);
        let mut n = 0;
        e.visit(|_| n += 1);
        // if, <, p0, p1, min, p2, -, p3, .x, tuple, p4, p5
        assert_eq!(n, 12);
    }

    #[test]
    fn any_stops_at_the_first_match() {
        let e = sample();
        let mut seen = 0;
        assert!(e.any(|n| {
            seen += 1;
            matches!(n.kind, ExprKind::Var(Var::Param(1)))
        }));
        assert_eq!(seen, 4, "if, <, p0, p1");
        assert!(mentions(&e, &|v| *v == Var::Param(5)));
        assert!(!mentions(&e, &|v| *v == Var::Param(6)));
    }

    #[test]
    fn map_rebuilds_bottom_up_and_does_not_revisit_replacements() {
        let e = sample();
        // Each p_i becomes p_{i+1}: a replacement that is itself a variable is not mapped again.
        let shifted = map_vars(&e, &mut |v, _| match v {
            Var::Param(i) => Some(param(i + 1)),
            _ => None,
        });
        assert_eq!(params(&shifted), vec![1, 2, 3, 4, 5, 6]);
        // Bottom-up: a node sees its children already mapped.
        let mut order = Vec::new();
        e.map(&mut |n| {
            if let ExprKind::Var(Var::Param(i)) = n.kind {
                order.push(i);
            }
            if let ExprKind::Binary(_, a, _) = &n.kind {
                assert!(matches!(a.kind, ExprKind::Var(_)));
            }
            n
        });
        assert_eq!(order, vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(e.map(&mut |n| n), e);
    }

    #[test]
    fn traversals_do_not_exhaust_the_stack() {
        // 200,000 nested negations, on a 1 MiB thread: the traversals grow the call stack
        // on demand (`crate::stack::deep`).
        let t = std::thread::Builder::new().stack_size(1 << 20).spawn(|| {
            let mut e = param(7);
            for _ in 0..200_000 {
                e = Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(e)), ..param(0) };
            }
            let mapped = map_vars(&e, &mut |_, _| Some(param(8)));
            let found = (params(&e), mentions(&mapped, &|v| *v == Var::Param(8)));
            // Dropping a tree this deep recurses; these two are leaked on purpose.
            std::mem::forget((e, mapped));
            found
        });
        let (ps, found) = t.expect("spawn").join().expect("no stack overflow");
        assert_eq!((ps, found), (vec![7], true));
    }

    fn real(v: &str) -> Expr {
        Expr { kind: ExprKind::Real(v.into()), sort: Sort::Real, loc: Loc::default() }
    }

    fn text(e: &Expr) -> String {
        match &e.kind {
            ExprKind::Int(i) => i.to_string(),
            ExprKind::Real(r) => r.clone(),
            ExprKind::Bool(b) => b.to_string(),
            ExprKind::Var(Var::Param(i)) => format!("p{i}"),
            ExprKind::Unary(UnOp::Not, a) => format!("!{}", text(a)),
            ExprKind::Binary(op, a, b) => format!("({} {} {})", text(a), op.symbol(), text(b)),
            ExprKind::Call(b, xs) => format!("{}({})", b.name(), xs.iter().map(text).collect::<Vec<_>>().join(", ")),
            other => format!("{other:?}"),
        }
    }

    #[test]
    fn definedness_asks_each_partial_operator_where_it_is_evaluated() {
        let d = |e: Expr| text(&definedness(&e));
        let sqrt = |a: Expr| Expr { kind: ExprKind::Call(Builtin::Sqrt, vec![a]), ..param(0) };
        let cmp = |op, a, b| Expr { sort: Sort::Bool, ..bin(op, a, b) };
        // Total: nothing to ask; a literal divisor or `sqrt` argument of a known sign neither.
        assert_eq!(d(bin(BinOp::Div, param(0), real("2"))), "true");
        assert_eq!(d(sqrt(real("0.5"))), "true");
        assert_eq!(d(bin(BinOp::Div, param(0), real("0.0"))), "(0.0 != 0)");
        assert_eq!(d(sqrt(real("-1"))), "(-1 >= 0)");
        assert_eq!(d(bin(BinOp::Add, param(0), bin(BinOp::Mul, param(1), real("2")))), "true");
        assert_eq!(d(sample()), "true");
        // Each partial operator, nested ones outermost last.
        assert_eq!(d(bin(BinOp::Div, real("540"), param(1))), "(p1 != 0)");
        assert_eq!(d(sqrt(bin(BinOp::Sub, param(0), param(1)))), "((p0 - p1) >= 0)");
        assert_eq!(d(sqrt(bin(BinOp::Div, param(0), param(1)))), "((p1 != 0) && ((p0 / p1) >= 0))");
        let neg = Expr { kind: ExprKind::Int(-2), sort: Sort::Int, loc: Loc::default() };
        assert_eq!(d(bin(BinOp::Pow, param(0), neg)), "(p0 != 0)");
        // Short-circuit: the right operand only where it is evaluated.
        let guarded = cmp(
            BinOp::And,
            cmp(BinOp::Ne, param(1), real("0")),
            cmp(BinOp::Eq, param(2), bin(BinOp::Div, real("540"), param(1))),
        );
        assert_eq!(d(guarded.clone()), "((p1 != 0) => (p1 != 0))");
        let or = cmp(
            BinOp::Or,
            cmp(BinOp::Eq, param(1), real("0")),
            cmp(BinOp::Lt, bin(BinOp::Div, real("1"), param(1)), real("2")),
        );
        assert_eq!(d(or), "(!(p1 == 0) => (p1 != 0))");
        let ite = Expr {
            kind: ExprKind::If(
                Box::new(cmp(BinOp::Lt, param(0), real("0"))),
                Box::new(real("0")),
                Box::new(sqrt(param(0))),
            ),
            ..param(0)
        };
        assert_eq!(d(ite), "(!(p0 < 0) => (p0 >= 0))");
        // Both operands of a comparison are evaluated.
        let both = cmp(BinOp::Lt, bin(BinOp::Div, real("1"), param(1)), sqrt(param(2)));
        assert_eq!(d(both.clone()), "((p1 != 0) && (p2 >= 0))");
        assert_eq!(text(&defined_and(both)), "(((p1 != 0) && (p2 >= 0)) && ((1 / p1) < sqrt(p2)))");
    }
}
