//! The answer cache's keys, read off a query's terms before any solver exists.
//!
//! A query is its assertions (with the encoder's side conditions) and the solver its
//! logic picks ([`super::solver_for`]). Z3's terms are hash-consed DAGs, so one walk over
//! them writes a key that is the query itself, node by node:
//!
//! - **exact**: the query with every name as written (any cached answer serves, a model
//!   included: its values are named as this query's are);
//! - **canonical**: the same with the free constants renamed `v0`, `v1`, ... in order of
//!   first occurrence (two queries with one canonical key are equisatisfiable, the one
//!   a renaming of the other; only answers without a model serve).
//!
//! Exact by construction: every node is written with what makes it itself (an
//! interpreted operator's kind and parameters, a numeral's exact value and sort, a
//! constant's name and sort, a bound variable's index and sort, a quantifier's kind,
//! bound sorts, weight and body); shared subterms are written once and then referred to
//! by their position, which only makes the key shorter. What the walk cannot take apart
//! (patterns, lambdas, unknown kinds) is written as Z3 prints it, names included, and the
//! query then has no canonical key (a renaming inside printed text would go unseen).
//!
//! Why by hand: building a solver and asserting into it is most of a cached query's cost
//! (47% of the instructions of the 100-lane benchmark, the printing another 21%), and
//! nothing in the `z3` crate reads a term's structure without wrapping every node. This
//! module is the one place mochi calls Z3's C API directly (`z3-sys`, the crate `z3` is
//! built on), read-only; [`view`] gives the same access, node by node, to
//! [`super::confirm`].

use super::encode::Logic;
use super::goals::Query;
use std::collections::HashMap;
use std::ffi::CStr;
use std::fmt::Write;
use std::sync::OnceLock;
use z3::ast::Ast;
use z3_sys::{Z3_ast, Z3_context, Z3_func_decl, Z3_sort};

// The accessors that return one of Z3's C enums, declared here to return its number:
// `z3-sys` types them as Rust enums generated from a newer Z3, whose numbering of
// declaration kinds differs from the 4.8.12 mochi links (and a number outside a Rust
// enum is undefined behaviour). The numbers used below are stable across versions
// (`Z3_ast_kind`, `Z3_sort_kind`'s first ones, `Z3_symbol_kind`); a declaration's kind
// is only compared with the kind of a constant mochi declares itself ([`uninterpreted`]).
unsafe extern "C" {
    pub(super) fn Z3_get_ast_kind(c: Z3_context, a: Z3_ast) -> u32;
    pub(super) fn Z3_get_decl_kind(c: Z3_context, d: Z3_func_decl) -> u32;
    pub(super) fn Z3_get_sort_kind(c: Z3_context, s: Z3_sort) -> u32;
    pub(super) fn Z3_get_symbol_kind(c: Z3_context, s: z3_sys::Z3_symbol) -> u32;
}

pub(super) const NUMERAL_AST: u32 = 0;
pub(super) const APP_AST: u32 = 1;
pub(super) const VAR_AST: u32 = 2;
pub(super) const QUANTIFIER_AST: u32 = 3;
pub(super) const BOOL_SORT: u32 = 1;
pub(super) const INT_SORT: u32 = 2;
pub(super) const REAL_SORT: u32 = 3;
pub(super) const INT_SYMBOL: u32 = 0;

/// The declaration kind of a free constant (`Z3_OP_UNINTERPRETED`) in the Z3 mochi runs
/// with, read off a constant declared for the purpose.
pub(super) fn uninterpreted() -> u32 {
    static KIND: OnceLock<u32> = OnceLock::new();
    *KIND.get_or_init(|| {
        let probe = z3::ast::Real::new_const("mochi-key-probe");
        let pc = probe.get_ctx().get_z3_context();
        // SAFETY: a constant of the live context `pc` is an application with a declaration.
        unsafe {
            let app = z3_sys::Z3_to_app(pc, probe.get_z3_ast()).expect("a constant is an application");
            let d = z3_sys::Z3_get_app_decl(pc, app).expect("a constant has a declaration");
            Z3_get_decl_kind(pc, d)
        }
    })
}

/// The keys of one query.
pub struct Keys {
    pub exact: String,
    /// `None` when part of the query was written as printed text (see the module doc).
    pub canonical: Option<String>,
}

/// The keys of `q`, solved with the solver for `logic`.
pub fn of(q: &Query, logic: Logic) -> Keys {
    let mut w = Walk::default();
    w.out.push_str(match logic {
        Logic::Nra => "N",
        Logic::WithIntegers => "I",
    });
    for a in q.assertions.iter().chain(q.enc.side_conditions()) {
        let ctx = a.get_ctx().get_z3_context();
        w.out.push('\n');
        w.node(ctx, a.get_z3_ast());
    }
    // The names, each with its length so that no name can run into the next.
    let mut exact = w.out.clone();
    exact.push('\n');
    for n in &w.names {
        let _ = write!(exact, "{}:{n};", n.len());
    }
    Keys { exact, canonical: (!w.printed).then_some(w.out) }
}

#[derive(Default)]
struct Walk {
    out: String,
    /// Each node written so far (by Z3's id, unique among live terms of a context) and
    /// its position in the order of writing.
    seen: HashMap<u32, usize>,
    /// The free constants' names, in order of first occurrence (`v0`, `v1`, ...).
    names: Vec<String>,
    /// Whether some part was written as Z3's printed text.
    printed: bool,
}

impl Walk {
    fn node(&mut self, c: Z3_context, a: Z3_ast) {
        // SAFETY (this function and the helpers below): `c` is the live context of the
        // query's terms and `a` a term of it, kept alive by the query (every child is
        // reachable from a root the query holds). Only Z3's read-only accessors are
        // called, each on a node of the kind it requires (checked first); strings Z3
        // returns are copied before the next call.
        let id = unsafe { z3_sys::Z3_get_ast_id(c, a) };
        if let Some(k) = self.seen.get(&id) {
            let _ = write!(self.out, "#{k}");
            return;
        }
        let k = self.seen.len();
        self.seen.insert(id, k);
        match unsafe { Z3_get_ast_kind(c, a) } {
            NUMERAL_AST => {
                self.out.push('n');
                self.sort_of(c, a);
                let s = unsafe { string(z3_sys::Z3_get_numeral_string(c, a)) };
                let _ = write!(self.out, "={s}");
            }
            APP_AST => self.app(c, a),
            VAR_AST => {
                let i = unsafe { z3_sys::Z3_get_index_value(c, a) };
                let _ = write!(self.out, "b{i}");
                self.sort_of(c, a);
            }
            QUANTIFIER_AST => self.quantifier(c, a),
            _ => self.print(c, a),
        }
    }

    fn app(&mut self, c: Z3_context, a: Z3_ast) {
        let Some(app) = (unsafe { z3_sys::Z3_to_app(c, a) }) else { return self.print(c, a) };
        let Some(d) = (unsafe { z3_sys::Z3_get_app_decl(c, app) }) else { return self.print(c, a) };
        let n = unsafe { z3_sys::Z3_get_app_num_args(c, app) };
        let kind = unsafe { Z3_get_decl_kind(c, d) };
        let free = kind == uninterpreted();
        if free && n == 0 {
            // A free constant: `v<k>` and its sort; the name goes to the exact key.
            let _ = write!(self.out, "v{}", self.names.len());
            self.sort_of(c, a);
            self.names.push(unsafe { decl_name(c, d) });
            return;
        }
        // The operator by its kind and its name (`+`, `<=`, or a function symbol's, none
        // in mochi's encoding today: written as is in both keys).
        let name = unsafe { decl_name(c, d) };
        let _ = write!(self.out, "({kind}:{}:{name}", name.len());
        if free {
            self.sort_of(c, a);
        } else if unsafe { z3_sys::Z3_get_decl_num_parameters(c, d) } > 0 {
            // An indexed operator: its parameters as Z3 prints the declaration.
            let s = unsafe { decl_text(c, d) };
            let _ = write!(self.out, "[{}:{s}]", s.len());
        }
        for i in 0..n {
            let Some(arg) = (unsafe { z3_sys::Z3_get_app_arg(c, app, i) }) else { return self.print(c, a) };
            self.out.push(' ');
            self.node(c, arg);
        }
        self.out.push(')');
    }

    fn quantifier(&mut self, c: Z3_context, a: Z3_ast) {
        let patterns =
            unsafe { z3_sys::Z3_get_quantifier_num_patterns(c, a) + z3_sys::Z3_get_quantifier_num_no_patterns(c, a) };
        if patterns > 0 || unsafe { z3_sys::Z3_is_lambda(c, a) } {
            return self.print(c, a);
        }
        let forall = unsafe { z3_sys::Z3_is_quantifier_forall(c, a) };
        let bound = unsafe { z3_sys::Z3_get_quantifier_num_bound(c, a) };
        let weight = unsafe { z3_sys::Z3_get_quantifier_weight(c, a) };
        let _ = write!(self.out, "(Q{}{bound}w{weight}", if forall { 'A' } else { 'E' });
        for i in 0..bound {
            match unsafe { z3_sys::Z3_get_quantifier_bound_sort(c, a, i) } {
                Some(s) => self.sort(c, s),
                None => return self.print(c, a),
            }
        }
        match unsafe { z3_sys::Z3_get_quantifier_body(c, a) } {
            Some(body) => {
                self.out.push(' ');
                self.node(c, body);
            }
            None => return self.print(c, a),
        }
        self.out.push(')');
    }

    fn sort_of(&mut self, c: Z3_context, a: Z3_ast) {
        match unsafe { z3_sys::Z3_get_sort(c, a) } {
            Some(s) => self.sort(c, s),
            None => self.out.push_str(":?"),
        }
    }

    fn sort(&mut self, c: Z3_context, s: Z3_sort) {
        match unsafe { Z3_get_sort_kind(c, s) } {
            BOOL_SORT => self.out.push_str(":B"),
            INT_SORT => self.out.push_str(":I"),
            REAL_SORT => self.out.push_str(":R"),
            // Other sorts carry parameters (a bit-vector's width): as Z3 prints them.
            _ => {
                let t = unsafe { string(z3_sys::Z3_sort_to_string(c, s)) };
                let _ = write!(self.out, ":{}:{t}", t.len());
            }
        }
    }

    /// A node the walk does not take apart: Z3's text of it, names included.
    fn print(&mut self, c: Z3_context, a: Z3_ast) {
        self.printed = true;
        let t = unsafe { string(z3_sys::Z3_ast_to_string(c, a)) };
        let _ = write!(self.out, "{{{}:{t}}}", t.len());
    }
}

/// A string Z3 returned, copied (Z3 reuses its buffer on the next call).
///
/// # Safety
/// `p` is null or a NUL-terminated string Z3 just returned.
pub(super) unsafe fn string(p: *const std::ffi::c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// A declaration's name: its string, or `!n` for Z3's numbered symbols.
///
/// # Safety
/// `d` is a live declaration of `c`.
pub(super) unsafe fn decl_name(c: Z3_context, d: Z3_func_decl) -> String {
    let Some(sym) = (unsafe { z3_sys::Z3_get_decl_name(c, d) }) else { return "?".into() };
    match unsafe { Z3_get_symbol_kind(c, sym) } {
        INT_SYMBOL => format!("!{}", unsafe { z3_sys::Z3_get_symbol_int(c, sym) }),
        _ => unsafe { string(z3_sys::Z3_get_symbol_string(c, sym)) },
    }
}

/// A declaration as Z3 prints it.
///
/// # Safety
/// `d` is a live declaration of `c`.
unsafe fn decl_text(c: Z3_context, d: Z3_func_decl) -> String {
    unsafe { string(z3_sys::Z3_func_decl_to_string(c, d)) }
}

/// One node of a term, read through Z3's C API for [`super::confirm`] (this module is the
/// one place that reads terms' structure).
pub(super) enum Node {
    /// A numeral: its exact value as Z3 writes it (`3`, `-7/2`).
    Numeral(String),
    /// A free constant (a variable of the query).
    Const,
    /// An interpreted operator (`+`, `<=`, `and`, `ite`, ...) by its name, and its
    /// arguments.
    App(String, Vec<z3::ast::Dynamic>),
    /// Anything else (a quantifier, a bound variable), as Z3 prints it.
    Other(String),
}

/// Z3's id of a term, unique among the live terms of its context.
pub(super) fn id(t: &z3::ast::Dynamic) -> u32 {
    let c = t.get_ctx().get_z3_context();
    // SAFETY: `t` is a live term of the live context `c`.
    unsafe { z3_sys::Z3_get_ast_id(c, t.get_z3_ast()) }
}

/// The top node of `t`.
pub(super) fn view(t: &z3::ast::Dynamic) -> Node {
    let ctx = t.get_ctx();
    let c = ctx.get_z3_context();
    let a = t.get_z3_ast();
    // SAFETY: as in `Walk::node`: `a` is a live term of the live context `c`, only
    // read-only accessors are called, each on a node of the kind it requires, and every
    // child is wrapped (which takes a reference on it) before it is returned.
    unsafe {
        match Z3_get_ast_kind(c, a) {
            NUMERAL_AST => Node::Numeral(string(z3_sys::Z3_get_numeral_string(c, a))),
            APP_AST => {
                let Some(app) = z3_sys::Z3_to_app(c, a) else { return Node::Other(t.to_string()) };
                let Some(d) = z3_sys::Z3_get_app_decl(c, app) else { return Node::Other(t.to_string()) };
                let n = z3_sys::Z3_get_app_num_args(c, app);
                if Z3_get_decl_kind(c, d) == uninterpreted() {
                    return if n == 0 { Node::Const } else { Node::Other(t.to_string()) };
                }
                let mut args = Vec::with_capacity(n as usize);
                for i in 0..n {
                    let Some(arg) = z3_sys::Z3_get_app_arg(c, app, i) else { return Node::Other(t.to_string()) };
                    args.push(<z3::ast::Dynamic as z3::ast::Ast>::wrap(ctx, arg));
                }
                Node::App(decl_name(c, d), args)
            }
            _ => Node::Other(t.to_string()),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::hir::Program;
    use crate::smt::encode::Encoder;
    use proptest::prelude::*;
    use z3::ast::{Bool, Int, Real};

    pub(crate) fn program() -> Program {
        crate::lower::tests::lower_src("robot R { state x: real; } system S { participant A: R; }").0
    }

    pub(crate) fn query(prog: &Program, assertions: Vec<Bool>) -> Query<'_> {
        Query { enc: Encoder::new(prog), assertions, point: None, times: Vec::new() }
    }

    fn keys(assertions: Vec<Bool>, logic: Logic) -> Keys {
        let prog = program();
        of(&query(&prog, assertions), logic)
    }

    fn le(name: &str, bound: &str) -> Bool {
        Real::new_const(name).le(Real::from_rational_str(bound, "1").unwrap())
    }

    #[test]
    fn a_renaming_keeps_the_canonical_key_only() {
        let a = keys(vec![le("C1.x", "10")], Logic::Nra);
        let b = keys(vec![le("C2.x", "10")], Logic::Nra);
        assert_eq!(a.canonical, b.canonical);
        assert!(a.canonical.is_some());
        assert_ne!(a.exact, b.exact);
    }

    #[test]
    fn numbers_sorts_order_and_the_logic_are_part_of_both_keys() {
        let base = keys(vec![le("x", "10")], Logic::Nra);
        let differ = |k: Keys| {
            assert_ne!(k.canonical, base.canonical);
            assert_ne!(k.exact, base.exact);
        };
        differ(keys(vec![le("x", "11")], Logic::Nra));
        differ(keys(vec![le("x", "10")], Logic::WithIntegers));
        differ(keys(vec![Int::new_const("x").le(Int::from_i64(10))], Logic::Nra));
        differ(keys(vec![Real::new_const("x").ge(Real::from_rational_str("10", "1").unwrap())], Logic::Nra));
        differ(keys(vec![le("x", "10"), le("x", "10")], Logic::Nra));
        // Two constants versus one.
        let (x, y) = (Real::new_const("x"), Real::new_const("y"));
        let one = keys(vec![(&x + &x).le(&x)], Logic::Nra);
        let two = keys(vec![(&x + &y).le(&x)], Logic::Nra);
        assert_ne!(one.canonical, two.canonical);
        let swapped = keys(vec![(&y + &x).le(&x)], Logic::Nra);
        assert_ne!(two.canonical, swapped.canonical);
    }

    /// A term over `a`, `b`, `c` from a small grammar, as a recipe (so that the same
    /// recipe can be built under other names).
    #[derive(Clone, Debug)]
    enum T {
        Var(u8),
        Num(i32, u32),
        Add(Box<T>, Box<T>),
        Mul(Box<T>, Box<T>),
        Neg(Box<T>),
    }

    fn term() -> impl Strategy<Value = T> {
        let leaf = prop_oneof![(0u8..3).prop_map(T::Var), (-3i32..4, 1u32..4).prop_map(|(n, d)| T::Num(n, d))];
        leaf.prop_recursive(4, 24, 2, |inner| {
            prop_oneof![
                (inner.clone(), inner.clone()).prop_map(|(a, b)| T::Add(Box::new(a), Box::new(b))),
                (inner.clone(), inner.clone()).prop_map(|(a, b)| T::Mul(Box::new(a), Box::new(b))),
                inner.prop_map(|a| T::Neg(Box::new(a))),
            ]
        })
    }

    fn build(t: &T, names: &[&str; 3]) -> Real {
        match t {
            T::Var(i) => Real::new_const(names[*i as usize]),
            T::Num(n, d) => Real::from_rational_str(&n.to_string(), &d.to_string()).unwrap(),
            T::Add(a, b) => build(a, names) + build(b, names),
            T::Mul(a, b) => build(a, names) * build(b, names),
            T::Neg(a) => build(a, names).unary_minus(),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        /// Exact by construction: two queries have one exact key iff Z3 holds them as one
        /// term (its terms are hash-consed), and a renaming keeps the canonical key.
        #[test]
        fn the_exact_key_is_the_term(s in term(), t in term()) {
            let names = ["a", "b", "c"];
            let (x, y) = (build(&s, &names).le(Real::from_rational_str("0", "1").unwrap()), build(&t, &names).le(Real::from_rational_str("0", "1").unwrap()));
            let same = x == y;
            let (kx, ky) = (keys(vec![x.clone()], Logic::Nra), keys(vec![y], Logic::Nra));
            prop_assert_eq!(kx.exact == ky.exact, same);
            prop_assert_eq!(kx.canonical == ky.canonical || !same, true);
            let renamed = build(&s, &["p", "q", "r"]).le(Real::from_rational_str("0", "1").unwrap());
            prop_assert_eq!(keys(vec![renamed], Logic::Nra).canonical, kx.canonical);
        }
    }
}
