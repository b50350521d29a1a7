//! Expressions compiled once for many interval evaluations: the hot loop of the geometric
//! branch and bound (`collision/`) contracts every box by reading bounds off the same
//! guarantees and invariants, tens of thousands of times per question. [`super::eval`]
//! walks the tree each time, parses every decimal literal into a [`BigRational`], looks
//! each variable up through a closure and each constant up in a hash map; here the walk,
//! the parsing and the lookups are done once.
//!
//! **Same enclosures as [`super::eval`], by construction.** A subterm that mentions no
//! variable (only literals and constants) is evaluated once with [`super::eval`] and kept
//! as its enclosure. Every other subterm is evaluated on intervals only, exactly as
//! [`super::eval`] does once a variable is involved: a variable's value is never an exact
//! rational, so `lift2` there takes the interval branch whenever one operand mentions a
//! variable, powers of a non-constant base use [`Interval::pow`], `if` takes the hull of
//! its arms, `sin`/`cos` of a non-constant argument use [`super::trig`] (of the unbounded
//! interval when the argument cannot be bounded), and a quarter turn is only ever
//! recognised in a constant argument. So each compiled evaluation returns the enclosure
//! [`super::eval`] would for the same ranges: sound for the same reason (module doc of
//! [`super`]). A unit test compares the two on random ranges.
//!
//! Variables are numbered in the order they are first met ([`Compiled::vars`]); an
//! evaluation reads their ranges from a slice with that numbering (`None`: unbounded or
//! unknown, as [`super::Ranges`] returns).

use super::{bounded_var, eval, Interval};
use crate::hir::expr::{mentions, BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, Var};

/// One instruction of a compiled expression (postfix: operands are on the stack).
#[derive(Clone, Debug)]
enum Op {
    /// A constant subterm's enclosure (`None`: it has no bound, e.g. a division by 0).
    Const(Option<Interval>),
    /// The range of variable `k`.
    Load(usize),
    Neg,
    Add,
    Sub,
    Mul,
    Div,
    Pow(i64),
    Min,
    Max,
    Abs,
    Sqrt,
    Sin,
    Cos,
    /// `if`: the hull of the two arms (the condition is not evaluated).
    Hull,
    /// Drops the top operand and pushes `None` (a term [`super::eval`] cannot bound, such
    /// as a comparison used as a number or a negative power).
    Fail,
}

/// A variable numbering shared by several compiled expressions.
#[derive(Clone, Debug, Default)]
pub struct VarTable {
    vars: Vec<Var>,
}

impl VarTable {
    pub fn new() -> VarTable {
        VarTable::default()
    }

    /// The number of `v`, numbering it if it is new.
    pub fn index(&mut self, v: &Var) -> usize {
        match self.vars.iter().position(|x| x == v) {
            Some(k) => k,
            None => {
                self.vars.push(v.clone());
                self.vars.len() - 1
            }
        }
    }

    /// The number of `v`, if it has one.
    pub fn get(&self, v: &Var) -> Option<usize> {
        self.vars.iter().position(|x| x == v)
    }

    pub fn vars(&self) -> &[Var] {
        &self.vars
    }

    pub fn len(&self) -> usize {
        self.vars.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vars.is_empty()
    }
}

/// An expression compiled for interval evaluation (module doc).
#[derive(Clone, Debug)]
pub struct Compiled {
    ops: Vec<Op>,
}

fn is_variable(v: &Var) -> bool {
    !matches!(v, Var::Const(_))
}

impl Compiled {
    /// Compiles `e`, numbering its variables in `table`.
    pub fn new(prog: &Program, e: &Expr, table: &mut VarTable) -> Compiled {
        let mut ops = Vec::new();
        compile(prog, e, table, &mut ops);
        Compiled { ops }
    }

    /// The enclosure of the expression when variable `k` ranges over `env[k]` (`None`:
    /// unbounded): what [`super::eval`] returns for the same ranges. `stack` is scratch
    /// space, reused between calls.
    pub fn eval(&self, env: &[Option<Interval>], stack: &mut Vec<Option<Interval>>) -> Option<Interval> {
        stack.clear();
        for op in &self.ops {
            let v = match op {
                Op::Const(c) => *c,
                Op::Load(k) => env.get(*k).copied().flatten(),
                Op::Fail => {
                    stack.pop();
                    None
                }
                Op::Neg => stack.pop()?.map(|x| -x),
                Op::Abs => stack.pop()?.map(|x| {
                    if x.lo >= 0.0 {
                        x
                    } else if x.hi <= 0.0 {
                        -x
                    } else {
                        Interval { lo: 0.0, hi: x.hi.max(-x.lo) }
                    }
                }),
                Op::Sqrt => stack.pop()?.and_then(Interval::sqrt),
                Op::Pow(n) => stack.pop()?.map(|x| x.pow(*n)),
                // An argument that cannot be bounded gives [-1, 1], as in `super::value`.
                Op::Sin => Some(super::trig(Builtin::Sin, stack.pop()?)),
                Op::Cos => Some(super::trig(Builtin::Cos, stack.pop()?)),
                Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Min | Op::Max | Op::Hull => {
                    let b = stack.pop()?;
                    let a = stack.pop()?;
                    match (a, b) {
                        (Some(x), Some(y)) => match op {
                            Op::Add => Some(x + y),
                            Op::Sub => Some(x + -y),
                            Op::Mul => Some(x * y),
                            Op::Div => x.div(y),
                            Op::Min => Some(Interval { lo: x.lo.min(y.lo), hi: x.hi.min(y.hi) }),
                            Op::Max => Some(Interval { lo: x.lo.max(y.lo), hi: x.hi.max(y.hi) }),
                            _ => Some(x.hull(y)),
                        },
                        _ => None,
                    }
                }
            };
            stack.push(v);
        }
        if stack.len() == 1 {
            stack.pop().flatten()
        } else {
            None
        }
    }
}

fn compile(prog: &Program, e: &Expr, table: &mut VarTable, ops: &mut Vec<Op>) {
    crate::stack::deep(|| compile_inner(prog, e, table, ops))
}

fn compile_inner(prog: &Program, e: &Expr, table: &mut VarTable, ops: &mut Vec<Op>) {
    if !mentions(e, &is_variable) {
        ops.push(Op::Const(eval(prog, e, &super::closed)));
        return;
    }
    match &e.kind {
        ExprKind::Var(v) => ops.push(Op::Load(table.index(v))),
        ExprKind::Unary(UnOp::Neg, a) => {
            compile(prog, a, table, ops);
            ops.push(Op::Neg);
        }
        ExprKind::Binary(BinOp::Pow, a, n) => {
            compile(prog, a, table, ops);
            match n.kind {
                ExprKind::Int(n) if n >= 0 => ops.push(Op::Pow(n)),
                _ => ops.push(Op::Fail),
            }
        }
        ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div), a, b) => {
            compile(prog, a, table, ops);
            compile(prog, b, table, ops);
            ops.push(match op {
                BinOp::Add => Op::Add,
                BinOp::Sub => Op::Sub,
                BinOp::Mul => Op::Mul,
                _ => Op::Div,
            });
        }
        ExprKind::If(_, a, b) => {
            compile(prog, a, table, ops);
            compile(prog, b, table, ops);
            ops.push(Op::Hull);
        }
        ExprKind::Call(f @ (Builtin::Min | Builtin::Max), args) if args.len() >= 2 => {
            compile(prog, &args[0], table, ops);
            compile(prog, &args[1], table, ops);
            ops.push(if *f == Builtin::Min { Op::Min } else { Op::Max });
        }
        ExprKind::Call(f @ (Builtin::Abs | Builtin::Sqrt | Builtin::Sin | Builtin::Cos), args) if !args.is_empty() => {
            compile(prog, &args[0], table, ops);
            ops.push(match f {
                Builtin::Abs => Op::Abs,
                Builtin::Sqrt => Op::Sqrt,
                Builtin::Sin => Op::Sin,
                _ => Op::Cos,
            });
        }
        // Everything `super::value` does not bound (comparisons, connectives, other calls,
        // a call missing its argument): no enclosure.
        _ => ops.push(Op::Const(None)),
    }
}

/// The conjuncts `v op e`, `e op v`, `v == e` of some facts, compiled: the contraction of
/// [`super::ranges_from`], for repeated use (module doc). Variables are numbered in
/// [`Facts::table`].
#[derive(Clone, Debug)]
pub struct Facts {
    table: VarTable,
    rules: Vec<Rule>,
}

/// One conjunct `lhs op rhs` (`op` one of `<=`, `<`, `==` after flipping `>=`, `>`).
#[derive(Clone, Debug)]
struct Rule {
    eq: bool,
    /// `lhs` is a variable: its number and `rhs` compiled.
    left: Option<(usize, Compiled)>,
    /// `rhs` is a variable: its number and `lhs` compiled.
    right: Option<(usize, Compiled)>,
}

impl Facts {
    pub fn new(prog: &Program, facts: &[&Expr]) -> Facts {
        let mut table = VarTable::new();
        let mut rules = Vec::new();
        for c in facts.iter().flat_map(|f| f.conjuncts()) {
            let Some((lhs, rhs, op)) = super::as_bound(c) else { continue };
            let left = bounded_var(lhs).map(|v| (table.index(v), Compiled::new(prog, rhs, &mut table)));
            let right = bounded_var(rhs).map(|v| (table.index(v), Compiled::new(prog, lhs, &mut table)));
            rules.push(Rule { eq: op == BinOp::Eq, left, right });
        }
        Facts { table, rules }
    }

    pub fn table(&self) -> &VarTable {
        &self.table
    }

    /// Compiles another expression with this contraction's numbering (adding its new
    /// variables), to be evaluated on the same ranges.
    pub fn compile(&mut self, prog: &Program, e: &Expr) -> Compiled {
        Compiled::new(prog, e, &mut self.table)
    }

    /// The number of `v`, numbering it if it is new.
    pub fn index(&mut self, v: &Var) -> usize {
        self.table.index(v)
    }

    /// [`super::ranges_from`] with the variables' starting ranges `start` (numbered as in
    /// [`Facts::table`]): for each variable, the bound the conjuncts give it (`None`: none),
    /// not met with its start. Two passes, as there. `work` is scratch space.
    pub fn ranges(&self, start: &[Option<Interval>], work: &mut Scratch) -> Vec<Option<Interval>> {
        let n = self.table.len();
        let mut known: Vec<Option<Interval>> = vec![None; n];
        // `cur[k]`: the lookup of `super::ranges_from`, the known bound met with the start.
        work.cur.clear();
        work.cur.extend((0..n).map(|k| start.get(k).copied().flatten()));
        for _ in 0..2 {
            for r in &self.rules {
                let from_left = r.left.as_ref().and_then(|(v, rhs)| {
                    let x = rhs.eval(&work.cur, &mut work.stack)?;
                    Some((*v, Interval { lo: if r.eq { x.lo } else { f64::NEG_INFINITY }, hi: x.hi }))
                });
                let found = from_left.or_else(|| {
                    let (v, lhs) = r.right.as_ref()?;
                    let x = lhs.eval(&work.cur, &mut work.stack)?;
                    Some((*v, Interval { lo: x.lo, hi: if r.eq { x.hi } else { f64::INFINITY } }))
                });
                if let Some((v, iv)) = found {
                    let k = known[v].map_or(iv, |old| old.meet(iv));
                    known[v] = Some(k);
                    work.cur[v] = Some(match start.get(v).copied().flatten() {
                        Some(s) => k.meet(s),
                        None => k,
                    });
                }
            }
        }
        known
    }
}

/// Scratch space of [`Facts::ranges`] and [`Compiled::eval`], reused between calls.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    cur: Vec<Option<Interval>>,
    pub stack: Vec<Option<Interval>>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::{ranges_from, Ranges};
    use crate::lower::tests::lower_src;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// The guarantee of a motion of a robot with state x, y, z: its conjuncts are the
    /// facts; the program lowers `old(..)`, parameters and constants as usual.
    fn facts_of(body: &str) -> (Program, Expr) {
        let src = format!(
            "const k = 0.1; const half = pi / 2;
             robot R {{ state x: real, y: real, z: real; }}
             motion R.m(a: real, d: real) {{ interruptible: false; pre: true; assume: true;
               guarantee: {body}; post: true; footprint(px, py, pz): true; duration: [d, d]; }}
             system S {{ participant A: R; }}
             choreography G = end;"
        );
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let g = prog.prims[0].guarantee.clone();
        (prog, g)
    }

    const BODIES: &[&str] = &[
        "x <= old(x) + (a - old(x)) * clock / d + k && old(x) + (a - old(x)) * clock / d - k <= x",
        "x^2 + y^2 <= (a + k)^2 && z == sin(old(z)) * cos(x + half) && y >= -abs(old(y) - 1) / 3",
        "x == (if old(x) > 0 then old(x) else -old(x)) && y <= min(x, a) && max(y, 0.5) <= z + sqrt(old(z))",
        "x >= 1e-300 * a / (1 + old(y)^2) && y == half * 2 && z <= x^3 - 2 * x && z >= -(y^4)",
    ];

    fn vars_of(e: &Expr) -> Vec<Var> {
        let mut vs: Vec<Var> = Vec::new();
        e.visit_vars(&mut |v, _| {
            if is_variable(v) && !vs.contains(v) {
                vs.push(v.clone());
            }
        });
        vs
    }

    fn interval(a: f64, b: f64, unbounded: bool) -> Option<Interval> {
        (!unbounded).then(|| Interval::new(a.min(b), a.max(b)))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// The compiled contraction returns exactly what `ranges_from` returns, and each
        /// compiled side exactly what `eval` returns, on random ranges (some unbounded).
        #[test]
        fn compiled_matches_the_tree_walk(
            which in 0..BODIES.len(),
            ends in prop::collection::vec((-5.0f64..5.0, -5.0f64..5.0, 0u8..6), 12),
        ) {
            let (prog, g) = facts_of(BODIES[which]);
            let vs = vars_of(&g);
            let ranges: HashMap<Var, Interval> = vs
                .iter()
                .zip(&ends)
                .filter_map(|(v, (a, b, u))| interval(*a, *b, *u == 0).map(|iv| (v.clone(), iv)))
                .collect();
            let lookup = |v: &Var| ranges.get(v).copied();
            let facts = Facts::new(&prog, &[&g]);
            let start: Vec<Option<Interval>> = facts.table().vars().iter().map(|v| lookup.range(v)).collect();
            let mut work = Scratch::default();
            let got = facts.ranges(&start, &mut work);
            let want = ranges_from(&prog, &[&g], &lookup);
            for (k, v) in facts.table().vars().iter().enumerate() {
                prop_assert_eq!(got[k], want.get(v).copied(), "variable {:?} of {}", v, BODIES[which]);
            }
            for (v, iv) in &want {
                prop_assert!(facts.table().get(v).is_some(), "{:?} {:?} bounded but not numbered", v, iv);
            }
            // Each side of each conjunct, evaluated alone.
            for c in g.conjuncts() {
                let ExprKind::Binary(_, a, b) = &c.kind else { continue };
                for side in [a, b] {
                    let mut table = facts.table().clone();
                    let comp = Compiled::new(&prog, side, &mut table);
                    let env: Vec<Option<Interval>> = table.vars().iter().map(|v| lookup.range(v)).collect();
                    let mut stack = Vec::new();
                    prop_assert_eq!(comp.eval(&env, &mut stack), eval(&prog, side, &lookup));
                }
            }
        }
    }

    #[test]
    fn a_constant_subterm_keeps_its_exact_enclosure() {
        // `1 - 1e-20 - 1` is the interval around -1e-20 (exact rational arithmetic), not 0:
        // folded once at compile time, it stays that in every evaluation.
        let (prog, g) = facts_of("x <= y + (1 - 1e-20 - 1)");
        let facts = Facts::new(&prog, &[&g]);
        let y = facts.table().vars().iter().position(|v| *v != facts.table().vars()[0]).expect("y");
        let mut start = vec![None; facts.table().len()];
        start[y] = Some(Interval::point(0.0));
        let got = facts.ranges(&start, &mut Scratch::default());
        let x = got[0].expect("x is bounded");
        assert!(x.hi < 0.0 && x.hi > -1e-19, "{x:?}");
    }
}
