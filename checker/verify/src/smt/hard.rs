//! What makes a query hard, read off its terms: the constructs outside the linear
//! arithmetic Z3 decides quickly, named so that an undecided obligation's report can say
//! which one to simplify and how ([`super::Why::Timeout`], [`super::Why::Incomplete`]).
//!
//! The walk reads the query as Z3 holds it (assertions and the encoder's side
//! conditions), so what it names is what the solver was given, not a guess from the
//! source: a product of two non-constant terms (nonlinear arithmetic), a division or
//! remainder by a non-constant, a quantifier, `sin`/`cos` of a non-constant (the encoder's
//! fresh `sin`/`cos` constants, [`super::encode`]), the exact float membership of a
//! chosen payload value (its fresh `significand`), integers mixed into real arithmetic
//! (`to_real` of a non-constant), and integer constants beyond 2^53 (a `uint64` field's
//! range). It only reads (the same C accessors as [`super::key`]) and never changes a
//! verdict: it explains an `unknown`.

use super::goals::Query;
use super::key::{
    decl_name, string, Z3_get_ast_kind, Z3_get_sort_kind, APP_AST, INT_SORT, NUMERAL_AST, QUANTIFIER_AST,
};
use std::collections::HashSet;
use z3::ast::Ast;
use z3_sys::{Z3_ast, Z3_context};

/// One construct that makes a query hard, with an example term as Z3 holds it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Construct {
    /// A product of two non-constant terms.
    Product(String),
    /// A division or remainder whose divisor is not a constant.
    Division(String),
    /// `sin` or `cos` of a term that is not a constant.
    Trig,
    /// A quantifier (`exists`, `forall`).
    Quantifier,
    /// The exact membership of a value in a float format (`float32`, `float64`).
    Float,
    /// An integer term used in real arithmetic.
    Mixed(String),
    /// An integer constant beyond 2^53 (a 64-bit field's range).
    Wide(String),
}

impl Construct {
    /// What it is, in a phrase.
    pub fn what(&self) -> String {
        match self {
            Construct::Product(t) => format!("the nonlinear product `{t}`"),
            Construct::Division(t) => format!("a division by a variable (`{t}`)"),
            Construct::Trig => "`sin`/`cos` of a variable (decided through polynomial enclosures)".into(),
            Construct::Quantifier => "a quantifier".into(),
            Construct::Float => {
                "the exact float32/float64 format of a payload value (a case split over the format's exponents)".into()
            }
            Construct::Mixed(t) => format!("an integer in real arithmetic (`{t}`)"),
            Construct::Wide(t) => format!("an integer constant as large as `{t}` (a 64-bit field's range)"),
        }
    }

    /// The simplification that removes it.
    pub fn advice(&self) -> &'static str {
        match self {
            Construct::Product(_) => {
                "make the product linear: fix one factor to a constant, or split the cases with guards so that each branch multiplies by a constant"
            }
            Construct::Division(_) => {
                "multiply out the division (`x < c * y` with `y > 0` known, instead of `x / y < c`), or divide by a constant"
            }
            Construct::Trig => {
                "use constant angles (multiples of `pi / 2` are exact), or bound the angle to a small range in the precondition"
            }
            Construct::Quantifier => "state the property for the values at hand instead of quantifying over them",
            Construct::Float => {
                "compare the float with constants only, or bound it to a range of integers, so that no float needs to be chosen"
            }
            Construct::Mixed(_) => {
                "compare integers with integers (scale the real side to an integer field, e.g. degrees * 1e7 kept as `int`)"
            }
            Construct::Wide(_) => {
                "bound the 64-bit field more tightly where the protocol allows (e.g. `t0 <= time_usec && time_usec <= t0 + 1000000`)"
            }
        }
    }
}

/// The hard constructs of a query, at most one of each kind, in a stable order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hard(pub Vec<Construct>);

impl Hard {
    pub fn of(q: &Query) -> Hard {
        let mut w = Walk::default();
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            let c = a.get_ctx().get_z3_context();
            w.node(c, a.get_z3_ast(), 0);
        }
        let mut found = w.found;
        found.sort();
        // One of each kind: the first example stands for the others.
        let mut kinds = HashSet::new();
        found.retain(|c| kinds.insert(std::mem::discriminant(c)));
        Hard(found)
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// "; what makes it hard: ..." or nothing.
    pub fn suffix(&self) -> String {
        if self.0.is_empty() {
            return String::new();
        }
        let w: Vec<String> = self.0.iter().map(Construct::what).collect();
        format!("; what makes it hard: {}", w.join(", "))
    }

    /// The matching simplifications, or `None` when nothing hard was found.
    pub fn advice(&self) -> Option<String> {
        let a: Vec<&str> = self.0.iter().map(Construct::advice).collect();
        (!a.is_empty()).then(|| a.join("; "))
    }
}

/// A term printed by Z3, on one line and cut to a readable length.
fn text(c: Z3_context, a: Z3_ast) -> String {
    // SAFETY: `a` is a live term of `c` (see `Walk::node`).
    let t = unsafe { string(z3_sys::Z3_ast_to_string(c, a)) };
    let t: String = t.split_whitespace().collect::<Vec<_>>().join(" ");
    if t.chars().count() > 60 {
        format!("{}...", t.chars().take(57).collect::<String>())
    } else {
        t
    }
}

/// `x * y * z` when every argument is a constant or a numeral (the user's names, as the
/// encoder declares them: `A.n`), else `None` (Z3's own text is shown).
fn infix(c: Z3_context, args: &[Z3_ast], op: &str) -> Option<String> {
    let mut parts = Vec::new();
    for &x in args {
        // SAFETY: as in `Walk::node`.
        match unsafe { Z3_get_ast_kind(c, x) } {
            NUMERAL_AST => parts.push(unsafe { string(z3_sys::Z3_get_numeral_string(c, x)) }),
            APP_AST => {
                let app = unsafe { z3_sys::Z3_to_app(c, x) }?;
                if unsafe { z3_sys::Z3_get_app_num_args(c, app) } != 0 {
                    return None;
                }
                let d = unsafe { z3_sys::Z3_get_app_decl(c, app) }?;
                parts.push(unsafe { decl_name(c, d) });
            }
            _ => return None,
        }
    }
    Some(parts.join(op))
}

/// Deeper than this, the walk stops (a query's terms are shallow; this bounds the stack).
const MAX_DEPTH: usize = 200;

#[derive(Default)]
struct Walk {
    seen: HashSet<u32>,
    found: Vec<Construct>,
}

impl Walk {
    fn node(&mut self, c: Z3_context, a: Z3_ast, depth: usize) {
        // SAFETY (as in `key::Walk::node`): `c` is the live context of the query's terms
        // and `a` a term of it, reachable from a root the query holds; only read-only
        // accessors are called, each on a node of the kind it requires.
        let id = unsafe { z3_sys::Z3_get_ast_id(c, a) };
        if depth > MAX_DEPTH || !self.seen.insert(id) {
            return;
        }
        match unsafe { Z3_get_ast_kind(c, a) } {
            APP_AST => self.app(c, a, depth),
            QUANTIFIER_AST => {
                self.found.push(Construct::Quantifier);
                if let Some(body) = unsafe { z3_sys::Z3_get_quantifier_body(c, a) } {
                    self.node(c, body, depth + 1);
                }
            }
            NUMERAL_AST => {
                let s = unsafe { string(z3_sys::Z3_get_numeral_string(c, a)) };
                let digits = s.trim_start_matches('-');
                // 2^53 = 9007199254740992 has 16 digits.
                if digits.bytes().all(|b| b.is_ascii_digit())
                    && (digits.len() > 16 || (digits.len() == 16 && digits > "9007199254740992"))
                {
                    self.found.push(Construct::Wide(s));
                }
            }
            _ => {}
        }
    }

    fn app(&mut self, c: Z3_context, a: Z3_ast, depth: usize) {
        let Some(app) = (unsafe { z3_sys::Z3_to_app(c, a) }) else { return };
        let Some(d) = (unsafe { z3_sys::Z3_get_app_decl(c, app) }) else { return };
        let n = unsafe { z3_sys::Z3_get_app_num_args(c, app) };
        let name = unsafe { decl_name(c, d) };
        let args: Vec<Z3_ast> = (0..n).filter_map(|i| unsafe { z3_sys::Z3_get_app_arg(c, app, i) }).collect();
        if n == 0 {
            // A free constant: the encoder's fresh ones name what they stand for.
            if name.starts_with("sin!") || name.starts_with("cos!") {
                self.found.push(Construct::Trig);
            } else if name.starts_with("significand!") {
                self.found.push(Construct::Float);
            }
            return;
        }
        let constant = |x: Z3_ast| closed(c, x, 0);
        match name.as_str() {
            "*" if args.iter().filter(|x| !constant(**x)).count() >= 2 => {
                self.found.push(Construct::Product(infix(c, &args, " * ").unwrap_or_else(|| text(c, a))));
            }
            "/" | "div" | "mod" | "rem" if args.iter().skip(1).any(|x| !constant(*x)) => {
                let op = match name.as_str() {
                    "/" | "div" => " / ",
                    _ => " % ",
                };
                self.found.push(Construct::Division(infix(c, &args, op).unwrap_or_else(|| text(c, a))));
            }
            "to_real" if args.first().is_some_and(|x| !constant(*x) && int_sorted(c, *x)) => {
                self.found.push(Construct::Mixed(text(c, a)));
            }
            _ => {}
        }
        for x in args {
            self.node(c, x, depth + 1);
        }
    }
}

/// Whether `a` is an integer term.
fn int_sorted(c: Z3_context, a: Z3_ast) -> bool {
    // SAFETY: as in `Walk::node`.
    unsafe { z3_sys::Z3_get_sort(c, a) }.is_some_and(|s| unsafe { Z3_get_sort_kind(c, s) } == INT_SORT)
}

/// Whether `a` has no free constant (a numeral, or an operator over numerals).
fn closed(c: Z3_context, a: Z3_ast, depth: usize) -> bool {
    if depth > MAX_DEPTH {
        return false;
    }
    // SAFETY: as in `Walk::node`.
    match unsafe { Z3_get_ast_kind(c, a) } {
        NUMERAL_AST => true,
        APP_AST => {
            let Some(app) = (unsafe { z3_sys::Z3_to_app(c, a) }) else { return false };
            let n = unsafe { z3_sys::Z3_get_app_num_args(c, app) };
            n > 0
                && (0..n).all(|i| unsafe { z3_sys::Z3_get_app_arg(c, app, i) }.is_some_and(|x| closed(c, x, depth + 1)))
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smt::key::tests::{program, query};
    use z3::ast::{Bool, Int, Real};

    fn hard(assertions: Vec<Bool>) -> Hard {
        let prog = program();
        Hard::of(&query(&prog, assertions))
    }

    #[test]
    fn linear_queries_are_not_hard() {
        let (x, y) = (Int::new_const("A.x"), Int::new_const("A.y"));
        let h = hard(vec![(&x * Int::from_i64(3)).le(&y), x.ge(Int::from_i64(0))]);
        assert!(h.is_empty(), "{h:?}");
        assert_eq!(h.advice(), None);
    }

    #[test]
    fn each_construct_is_named_from_the_terms() {
        let (x, y) = (Int::new_const("A.n"), Int::new_const("A.m"));
        let h = hard(vec![(&x * &y).le(Int::from_i64(3))]);
        assert_eq!(h.0, vec![Construct::Product("A.n * A.m".into())]);
        assert!(h.suffix().contains("the nonlinear product `A.n * A.m`"), "{}", h.suffix());
        let (r, s) = (Real::new_const("p.r"), Real::new_const("p.s"));
        let h = hard(vec![(&r / &s).le(Real::from_rational_str("1", "1").expect("a rational"))]);
        assert!(matches!(&h.0[..], [Construct::Division(t)] if t.contains("p.s")), "{h:?}");
        let h = hard(vec![x.to_real().le(&r)]);
        assert!(matches!(&h.0[..], [Construct::Mixed(_)]), "{h:?}");
        let big = Int::from_u64(u64::MAX);
        let h = hard(vec![x.le(&big)]);
        assert!(matches!(&h.0[..], [Construct::Wide(t)] if t == "18446744073709551615"), "{h:?}");
        let h = hard(vec![Real::fresh_const("sin").le(&r)]);
        assert_eq!(h.0, vec![Construct::Trig]);
        let h = hard(vec![Int::fresh_const("significand").eq(&y)]);
        assert_eq!(h.0, vec![Construct::Float]);
        let q = z3::ast::exists_const(&[&x], &[], &x.gt(&y));
        let h = hard(vec![q]);
        assert_eq!(h.0, vec![Construct::Quantifier]);
    }

    #[test]
    fn products_and_divisions_by_constants_are_linear() {
        let r = Real::new_const("p.r");
        let h = hard(vec![(&r * Real::from_rational_str("1", "2").expect("a rational"))
            .le(&r / Real::from_rational_str("3", "1").expect("a rational"))]);
        assert!(h.is_empty(), "{h:?}");
    }
}
