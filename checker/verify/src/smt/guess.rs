//! A witness for a satisfiability question guessed from its terms and checked in exact
//! arithmetic, before any solver exists.
//!
//! The joint-motion questions ("the motion can end", [`super::goals::Part::CanEnd`]) are
//! mostly chains of definitions: a start state given by `init`, a duration pinned by its
//! two bounds, an end state given by the postcondition. Such a query is satisfiable at the
//! point the definitions give, and evaluating every assertion there, exactly, shows it
//! without Z3 (the 1,000-lane benchmark asks 2,000 of them, each differing from the others
//! by a lane's offset only, so no cache answers them).
//!
//! The guess: an equality `v = t` whose `t` has a value defines `v`; when none does, the
//! first variable with a bound takes its tightest non-strict bound (or a point between
//! strict ones); the variables left take 0. Then every assertion and side condition is
//! evaluated with rationals: all true is a model, so the query is satisfiable. Anything
//! else (a false assertion, an operator outside linear and polynomial arithmetic and the
//! connectives, a division by 0, an integer variable given a fraction) only means "not
//! shown": the solver is asked as before.
//!
//! Sound for exactly the queries it is used on: those whose terms mean what they say.
//! `sin`/`cos` values and `pi` are variables constrained to enclosures (see
//! `encode.rs`), so a point of the encoding need not be a point of the real functions:
//! queries with either are never guessed ([`super::encode::Encoder::encloses`]).

use super::goals::Query;
use super::key::{self, APP_AST, INT_SORT, NUMERAL_AST, REAL_SORT};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};
use std::collections::HashMap;
use z3::ast::Ast;
use z3_sys::{Z3_ast, Z3_context};

/// Whether a point guessed from `q`'s definitions satisfies every assertion of it.
pub fn satisfied(q: &Query) -> bool {
    if q.enc.encloses() {
        return false;
    }
    let mut r = Reader::default();
    let mut roots = Vec::new();
    for a in q.assertions.iter().chain(q.enc.side_conditions()) {
        let c = a.get_ctx().get_z3_context();
        match r.read(c, a.get_z3_ast()) {
            Some(n) => roots.push(n),
            None => return false,
        }
    }
    let mut conjuncts = Vec::new();
    for &n in &roots {
        r.flatten(n, &mut conjuncts);
    }
    let Some(point) = r.guess(&conjuncts) else { return false };
    let point: Vec<Option<BigRational>> = point.into_iter().map(Some).collect();
    let mut memo = HashMap::new();
    roots.iter().all(|&n| matches!(r.eval(n, &point, &mut memo), Some(Val::B(true))))
}

/// An operator the guess understands, by Z3's name of it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    True,
    False,
    And,
    Or,
    Not,
    Implies,
    Eq,
    Le,
    Ge,
    Lt,
    Gt,
    Add,
    Sub,
    Mul,
    Div,
    ToReal,
    Ite,
}

fn op(name: &str) -> Option<Op> {
    Some(match name {
        "true" => Op::True,
        "false" => Op::False,
        "and" => Op::And,
        "or" => Op::Or,
        "not" => Op::Not,
        "=>" => Op::Implies,
        "=" => Op::Eq,
        "<=" => Op::Le,
        ">=" => Op::Ge,
        "<" => Op::Lt,
        ">" => Op::Gt,
        "+" => Op::Add,
        "-" => Op::Sub,
        "*" => Op::Mul,
        "/" => Op::Div,
        "to_real" => Op::ToReal,
        "if" | "ite" => Op::Ite,
        _ => return None,
    })
}

enum Node {
    Num(BigRational),
    /// A free constant: its index in `Reader::vars`.
    Var(usize),
    App(Op, Vec<usize>),
}

#[derive(Default)]
struct Reader {
    nodes: Vec<Node>,
    /// Z3's id of each node read, to its index (the terms are a DAG).
    seen: HashMap<u32, usize>,
    /// Per variable: whether it is an integer.
    vars: Vec<bool>,
}

/// A variable's tightest bound on one side so far: the value and whether it is strict.
type Bound = Option<(BigRational, bool)>;

#[derive(Clone, Debug, PartialEq)]
enum Val {
    B(bool),
    N(BigRational),
}

impl Reader {
    /// The node of `a`, or `None` for a term outside what the guess understands.
    fn read(&mut self, c: Z3_context, a: Z3_ast) -> Option<usize> {
        // SAFETY: as in `key.rs`: `a` is a live term of the live context `c`, reached
        // from a root the query holds; only read-only accessors are called, each on a
        // node of the kind it requires, and returned strings are copied at once.
        let id = unsafe { z3_sys::Z3_get_ast_id(c, a) };
        if let Some(&n) = self.seen.get(&id) {
            return Some(n);
        }
        let node = match unsafe { key::Z3_get_ast_kind(c, a) } {
            NUMERAL_AST => Node::Num(rational(&unsafe { key::string(z3_sys::Z3_get_numeral_string(c, a)) })?),
            APP_AST => {
                let app = unsafe { z3_sys::Z3_to_app(c, a) }?;
                let d = unsafe { z3_sys::Z3_get_app_decl(c, app) }?;
                let n = unsafe { z3_sys::Z3_get_app_num_args(c, app) };
                if unsafe { key::Z3_get_decl_kind(c, d) } == key::uninterpreted() {
                    if n > 0 {
                        return None;
                    }
                    let sort = unsafe { z3_sys::Z3_get_sort(c, a) }?;
                    let int = match unsafe { key::Z3_get_sort_kind(c, sort) } {
                        INT_SORT => true,
                        REAL_SORT => false,
                        // Boolean constants and other sorts: not guessed.
                        _ => return None,
                    };
                    self.vars.push(int);
                    Node::Var(self.vars.len() - 1)
                } else {
                    let o = op(&unsafe { key::decl_name(c, d) })?;
                    let mut args = Vec::with_capacity(n as usize);
                    for i in 0..n {
                        let arg = unsafe { z3_sys::Z3_get_app_arg(c, app, i) }?;
                        args.push(self.read(c, arg)?);
                    }
                    Node::App(o, args)
                }
            }
            _ => return None,
        };
        self.nodes.push(node);
        let n = self.nodes.len() - 1;
        self.seen.insert(id, n);
        Some(n)
    }

    /// The conjuncts of `n` (nested `and`s taken apart).
    fn flatten(&self, n: usize, out: &mut Vec<usize>) {
        match &self.nodes[n] {
            Node::App(Op::And, args) => args.iter().for_each(|&a| self.flatten(a, out)),
            _ => out.push(n),
        }
    }

    /// A point read off the conjuncts' definitions and bounds (every variable valued).
    fn guess(&self, conjuncts: &[usize]) -> Option<Vec<BigRational>> {
        let mut at: Vec<Option<BigRational>> = vec![None; self.vars.len()];
        loop {
            // Definitions first, to a fixpoint.
            let mut grew = true;
            while grew {
                grew = false;
                for &c in conjuncts {
                    let Node::App(Op::Eq, args) = &self.nodes[c] else { continue };
                    let [a, b] = args[..] else { continue };
                    for (lhs, rhs) in [(a, b), (b, a)] {
                        let Node::Var(v) = self.nodes[lhs] else { continue };
                        if at[v].is_some() {
                            continue;
                        }
                        if let Some(x) = self.number(rhs, &at) {
                            if self.vars[v] && !x.is_integer() {
                                continue;
                            }
                            at[v] = Some(x);
                            grew = true;
                            break;
                        }
                    }
                }
            }
            // Then one variable from its bounds, and definitions again.
            let mut bounds: Vec<(Bound, Bound)> = vec![(None, None); self.vars.len()];
            for &c in conjuncts {
                let Node::App(o @ (Op::Le | Op::Ge | Op::Lt | Op::Gt), args) = &self.nodes[c] else { continue };
                let [a, b] = args[..] else { continue };
                // `v <= t` is an upper bound of `v`, `t <= v` a lower one.
                for (var, other, upper) in [(a, b, matches!(o, Op::Le | Op::Lt)), (b, a, matches!(o, Op::Ge | Op::Gt))]
                {
                    let Node::Var(v) = self.nodes[var] else { continue };
                    if at[v].is_some() {
                        continue;
                    }
                    let Some(x) = self.number(other, &at) else { continue };
                    let strict = matches!(o, Op::Lt | Op::Gt);
                    let slot = if upper { &mut bounds[v].1 } else { &mut bounds[v].0 };
                    let tighter = match slot {
                        None => true,
                        Some((y, s)) => {
                            if upper {
                                x < *y || (x == *y && strict && !*s)
                            } else {
                                x > *y || (x == *y && strict && !*s)
                            }
                        }
                    };
                    if tighter {
                        *slot = Some((x, strict));
                    }
                }
            }
            let pick = bounds.iter().enumerate().find_map(|(v, (lo, hi))| {
                let x = match (lo, hi) {
                    (Some((l, false)), _) => l.clone(),
                    (_, Some((h, false))) => h.clone(),
                    (Some((l, true)), Some((h, true))) => (l + h) / BigRational::from_integer(2.into()),
                    (Some((l, true)), None) => l + BigRational::one(),
                    (None, Some((h, true))) => h - BigRational::one(),
                    (None, None) => return None,
                };
                Some((v, x))
            });
            match pick {
                Some((v, x)) => {
                    if self.vars[v] && !x.is_integer() {
                        return None;
                    }
                    at[v] = Some(x);
                }
                None => break,
            }
        }
        Some(at.into_iter().map(|x| x.unwrap_or_else(BigRational::zero)).collect())
    }

    /// `n`'s number where every variable it reads has a value.
    fn number(&self, n: usize, at: &[Option<BigRational>]) -> Option<BigRational> {
        match self.eval(n, at, &mut HashMap::new())? {
            Val::N(x) => Some(x),
            Val::B(_) => None,
        }
    }

    /// `n`'s value at `point`, exactly; `None` where it has none (a variable without a
    /// value, a division by 0, sorts mixed).
    fn eval(&self, n: usize, point: &[Option<BigRational>], memo: &mut HashMap<usize, Val>) -> Option<Val> {
        if let Some(v) = memo.get(&n) {
            return Some(v.clone());
        }
        let num = |v: Val| match v {
            Val::N(x) => Some(x),
            Val::B(_) => None,
        };
        let boolean = |v: Val| match v {
            Val::B(b) => Some(b),
            Val::N(_) => None,
        };
        let v = match &self.nodes[n] {
            Node::Num(x) => Val::N(x.clone()),
            Node::Var(v) => Val::N(point[*v].clone()?),
            Node::App(o, args) => {
                let mut xs = Vec::with_capacity(args.len());
                for &a in args {
                    xs.push(self.eval(a, point, memo)?);
                }
                match o {
                    Op::True => Val::B(true),
                    Op::False => Val::B(false),
                    Op::And => Val::B(xs.into_iter().map(boolean).collect::<Option<Vec<_>>>()?.into_iter().all(|b| b)),
                    Op::Or => Val::B(xs.into_iter().map(boolean).collect::<Option<Vec<_>>>()?.into_iter().any(|b| b)),
                    Op::Not => Val::B(!boolean(xs.pop()?)?),
                    Op::Implies => {
                        let [a, b] = <[Val; 2]>::try_from(xs).ok()?;
                        Val::B(!boolean(a)? || boolean(b)?)
                    }
                    Op::Eq => {
                        let [a, b] = <[Val; 2]>::try_from(xs).ok()?;
                        Val::B(a == b)
                    }
                    Op::Le | Op::Ge | Op::Lt | Op::Gt => {
                        let [a, b] = <[Val; 2]>::try_from(xs).ok()?;
                        let (a, b) = (num(a)?, num(b)?);
                        Val::B(match o {
                            Op::Le => a <= b,
                            Op::Ge => a >= b,
                            Op::Lt => a < b,
                            _ => a > b,
                        })
                    }
                    Op::Add => Val::N(xs.into_iter().map(num).sum::<Option<BigRational>>()?),
                    Op::Mul => Val::N(xs.into_iter().map(num).product::<Option<BigRational>>()?),
                    Op::Sub => {
                        let mut it = xs.into_iter();
                        let first = num(it.next()?)?;
                        let rest: Vec<BigRational> = it.map(num).collect::<Option<_>>()?;
                        if rest.is_empty() {
                            Val::N(-first)
                        } else {
                            Val::N(rest.into_iter().fold(first, |acc, x| acc - x))
                        }
                    }
                    Op::Div => {
                        let [a, b] = <[Val; 2]>::try_from(xs).ok()?;
                        let (a, b) = (num(a)?, num(b)?);
                        if b.is_zero() {
                            return None;
                        }
                        Val::N(a / b)
                    }
                    Op::ToReal => xs.pop()?,
                    Op::Ite => {
                        let [c, a, b] = <[Val; 3]>::try_from(xs).ok()?;
                        if boolean(c)? {
                            a
                        } else {
                            b
                        }
                    }
                }
            }
        };
        memo.insert(n, v.clone());
        Some(v)
    }
}

/// A numeral as Z3 writes it: `3`, `-3`, `13/20`, `0.65`.
fn rational(s: &str) -> Option<BigRational> {
    let (neg, s) = match s.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, s),
    };
    let x = if let Some((n, d)) = s.split_once('/') {
        let d: BigInt = d.trim().parse().ok()?;
        if d.is_zero() {
            return None;
        }
        BigRational::new(n.trim().parse().ok()?, d)
    } else if let Some((i, f)) = s.split_once('.') {
        let digits = format!("{i}{f}");
        let scale = BigInt::from(10).pow(u32::try_from(f.len()).ok()?);
        BigRational::new(digits.parse().ok()?, scale)
    } else {
        BigRational::from_integer(s.parse().ok()?)
    };
    Some(if neg { -x } else { x })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numerals_read_exactly() {
        let r = |s| rational(s).unwrap();
        assert_eq!(r("13/20"), BigRational::new(13.into(), 20.into()));
        assert_eq!(r("0.65"), BigRational::new(13.into(), 20.into()));
        assert_eq!(r("-3"), BigRational::from_integer((-3).into()));
        assert!(rational("1/0").is_none());
        assert!(rational("x").is_none());
    }
}

#[cfg(test)]
mod proofs {
    use super::*;
    use crate::smt::key::tests::{program, query};
    use proptest::prelude::*;
    use proptest::strategy::ValueTree;
    use z3::ast::{Bool, Int, Real};

    fn num(n: i64, d: i64) -> Real {
        Real::from_rational_str(&n.to_string(), &d.to_string()).unwrap()
    }

    fn guessed(assertions: Vec<Bool>) -> bool {
        let prog = program();
        satisfied(&query(&prog, assertions))
    }

    #[test]
    fn a_chain_of_definitions_is_a_model() {
        let (x, t, xt) = (Real::new_const("x"), Real::new_const("time"), Real::new_const("x(t)"));
        let chain = vec![
            x.eq(num(0, 1)),
            t.ge(num(5, 1)),
            t.le(num(5, 1)),
            xt.eq(&x + &t * num(1, 10)),
            Bool::and(&[xt.le(num(10, 1)), xt.ge(&x)]),
        ];
        assert!(guessed(chain.clone()));
        // The same with an end state out of bounds: not shown.
        let mut off = chain;
        off.push(xt.ge(num(1, 1)));
        assert!(!guessed(off));
    }

    #[test]
    fn a_contradiction_an_integer_fraction_and_a_division_by_zero_are_not_shown() {
        let x = Real::new_const("x");
        assert!(!guessed(vec![x.eq(num(0, 1)), x.ge(num(1, 1))]));
        let n = Int::new_const("n");
        assert!(!guessed(vec![n.to_real().eq(num(1, 2))]));
        assert!(!guessed(vec![
            n.le(Int::from_i64(3)),
            n.ge(Int::from_i64(3)),
            x.eq(num(1, 1) / (n.to_real() - num(3, 1)))
        ]));
    }

    /// An atom over `x`, `y`, `z`: `a·x + b·y + c·z ⋈ k`, or a definition `v = a·w + k`.
    fn atom() -> impl Strategy<Value = (u8, [i64; 3], i64, u8)> {
        (0u8..6, [-2i64..3, -2i64..3, -2i64..3], -4i64..5, 0u8..3)
    }

    fn build((kind, c, k, v): (u8, [i64; 3], i64, u8)) -> Bool {
        let vars = [Real::new_const("x"), Real::new_const("y"), Real::new_const("z")];
        let lhs = Real::add(&[&vars[0] * num(c[0], 1), &vars[1] * num(c[1], 1), &vars[2] * num(c[2], 1)]);
        match kind {
            0 => lhs.le(num(k, 1)),
            1 => lhs.ge(num(k, 1)),
            2 => lhs.lt(num(k, 2)),
            3 => lhs.gt(num(k, 2)),
            4 => lhs.eq(num(k, 3)),
            _ => vars[v as usize].eq(&vars[(v as usize + 1) % 3] * num(c[0], 1) + num(k, 1)),
        }
    }

    /// The guess is a model: whenever it shows a conjunction satisfiable, Z3 agrees; and it
    /// does show some (a property that never met a guessed point would hold vacuously).
    #[test]
    fn a_guessed_point_is_a_model() {
        let mut runner = proptest::test_runner::TestRunner::deterministic();
        let strategy = prop::collection::vec(atom(), 1..6);
        let mut guessed_any = 0;
        for _ in 0..300 {
            let atoms = strategy.new_tree(&mut runner).expect("a case").current();
            let assertions: Vec<Bool> = atoms.into_iter().map(build).collect();
            if guessed(assertions.clone()) {
                guessed_any += 1;
                let solver = z3::Solver::new();
                for a in &assertions {
                    solver.assert(a);
                }
                assert_eq!(solver.check(), z3::SatResult::Sat, "{assertions:?}");
            }
        }
        assert!(guessed_any >= 20, "only {guessed_any} of 300 cases were guessed");
    }
}
