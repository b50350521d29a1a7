//! Encoding of HIR expressions into Z3 terms.
//!
//! - Integers and reals mix by promotion; booleans stay booleans.
//! - Points and vectors are triples of reals: `+`, `-`, scaling, components, `dot`,
//!   `norm2` and `==` work componentwise.
//! - `sqrt(e)` is a fresh `s` with the side condition `e >= 0 => (s >= 0 && s * s == e)`:
//!   exact wherever the square root is defined. Where it is not (`e < 0`), `s` is any real,
//!   as `x / 0` is Z3's unspecified quotient: sound in a fact that is assumed (it says
//!   less, never something false), unsound in one that is proved or asked to be
//!   satisfiable (some `v` equals the arbitrary value). So the obligations conjoin
//!   [`crate::hir::expr::definedness`] to every predicate they prove or ask to be
//!   satisfiable, before it reaches this encoder.
//! - `sin(e)`, `cos(e)` are fresh `s`, `c` (one pair per argument) with side conditions
//!   that hold of the real functions for every real argument: `s^2 + c^2 == 1`,
//!   `1 - e^2/2 <= c <= 1 - e^2/2 + e^4/24`, and `e - e^3/6 <= s <= e` for `e >= 0`
//!   (mirrored for `e <= 0`); for a constant argument (written as one, or an expression
//!   of parameters bound to constants at the call site, `go(pi / 4)`: its numeral is read
//!   back exactly, [`rational_value`], or the closed expression with the arguments put in,
//!   [`Encoder::constant_args`], is enclosed by [`crate::bounds::eval`]), its enclosure
//!   from [`crate::bounds::trig`], whose ends enter as the exact rationals of the doubles
//!   ([`real_of_f64`]). These over-approximate: a proof with them is a proof, but
//!   a counterexample may not be real, so [`Encoder::spurious_trig`] checks a model's
//!   trigonometric values against `f64::sin`/`cos` before it is reported as one.
//! - `pi` is one fresh real per query inside a rational enclosure 1e-20 wide
//!   ([`Encoder::pi`]); `sin`/`cos` of an exact multiple of π/2
//!   ([`crate::bounds::quarter_turn`]), written or through constant arguments, are the
//!   exact 0 or ±1.
//! - A motion primitive's contract is encoded under a [`Frame`] that says what its own
//!   variables, `old(x)`, parameters, `clock` and footprint point stand for.
//!
//! Constructs that cannot be encoded are refused with [`Unsupported`], which the caller
//! reports as unknown, never as a pass.

use crate::bounds;
use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, RoleId, Slot, Sort, ValueId, Var};
use num_rational::BigRational;
use num_traits::Zero;
use std::collections::{BTreeMap, HashMap};
use z3::ast::{Ast, Bool, Int, Real};

mod numeral;
mod term;

pub use numeral::{as_real, one, rational, rational_value, real_of_f64, real_of_rational, zero};
use numeral::{decimal, int_text};

/// A construct the encoding does not handle; the message names it.
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported(pub String);

#[derive(Clone)]
pub enum Term {
    B(Bool),
    I(Int),
    R(Real),
    /// A point or a vector.
    V([Real; 3]),
}

impl Term {
    /// `self == other` when both have the same sort.
    pub fn equals(&self, other: &Term) -> Option<Bool> {
        Some(match (self, other) {
            (Term::B(x), Term::B(y)) => x.eq(y),
            (Term::I(x), Term::I(y)) => x.eq(y),
            (Term::R(x), Term::R(y)) => x.eq(y),
            (Term::V(x), Term::V(y)) => Bool::and(&[x[0].eq(&y[0]), x[1].eq(&y[1]), x[2].eq(&y[2])]),
            _ => return None,
        })
    }
}

/// What a primitive's own variables mean while its contract is encoded.
#[derive(Clone, Default)]
pub struct Frame {
    /// `Var::Own(slot)`: the participant's variable at the time considered.
    pub own: BTreeMap<Slot, Term>,
    /// `Var::Old(i)`: state variable `i` when the motion started.
    pub old: Vec<Term>,
    /// `Var::Param(i)`: the i-th argument, already encoded.
    pub params: Vec<Term>,
    /// The i-th argument as written at the call site (in the caller's scope). Read only
    /// where it is closed (literals, constants, `pi`): then `sin`/`cos` of an expression
    /// of the parameters are enclosed as that constant's ([`Encoder::constant_args`]).
    /// Left empty where `params` are not these arguments' terms (free parameters).
    pub args: Vec<Expr>,
    pub clock: Option<Real>,
    /// The footprint's point in the participant's frame.
    pub point: Option<[Real; 3]>,
}

/// π's enclosure in the solver, as numerator and denominator strings:
/// 3.14159265358979323846 < π < 3.14159265358979323847.
const PI_LO: (&str, &str) = ("314159265358979323846", "100000000000000000000");
const PI_HI: (&str, &str) = ("314159265358979323847", "100000000000000000000");

struct TrigPair {
    arg: Real,
    sin: Real,
    cos: Real,
}

/// Where a formula occurs in what is asserted ([`Encoder::polarity`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Polarity {
    /// Positively in a hypothesis: a weaker formula is sound.
    Assumed,
    /// Positively in the body of "some payload exists": exact, its witnesses bound.
    Chosen,
    /// Anywhere else: exact, or refused.
    Other,
}

/// Which solver a query needs ([`crate::smt::solver_for`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Logic {
    /// Real variables only: quantifier-free nonlinear real arithmetic (nlsat).
    Nra,
    /// Some integer variable: Z3's default solver.
    WithIntegers,
}

pub struct Encoder<'p> {
    prog: &'p Program,
    /// Free variables by their user-facing name, for the counterexample.
    vars: BTreeMap<String, Term>,
    side: Vec<Bool>,
    /// How many of `side`'s conditions are enclosures of `sin`, `cos` or `pi`, by their
    /// positions in `side` ([`Encoder::enclosing`]): true of the real functions, but a
    /// model of them need not be the functions' values.
    enclosing: Vec<usize>,
    /// Each `sqrt`'s fresh real, its argument and the position of its definition in
    /// `side`.
    roots: Vec<(Real, Real, usize)>,
    frame: Option<Frame>,
    trig: Vec<TrigPair>,
    trig_by_arg: HashMap<String, usize>,
    /// The query's `pi` ([`Encoder::pi`]), once met.
    pi: Option<Real>,
    /// The symbol of each value variable met so far. A value is its binding site: two
    /// values of one name (shadowing) are two symbols, `v` and `v#2`, in order of first
    /// appearance (so equal queries still have equal text).
    value_names: HashMap<ValueId, String>,
    /// Whether a quantifier was built ([`Encoder::quantified`]): the query then needs
    /// Z3's default solver, not the quantifier-free nlsat.
    quantified: bool,
    /// The variables of sort `str` (integers in the solver), so that a counterexample
    /// shows their values as the strings they stand for.
    strings: std::collections::HashSet<String>,
    /// Where the formula being encoded occurs: positively in a hypothesis
    /// ([`Encoder::assumed`]), positively in the body of the progress check's existential
    /// ([`Encoder::choosing`]), or anywhere else (a goal; under a negation, left of `=>`,
    /// in a condition or an equality of truth values). Only [`Builtin::Float32`] reads it.
    polarity: Polarity,
    /// The payload values the progress check is choosing ([`Encoder::choosing`]): that
    /// such a value is a float of its field's format is encoded exactly there.
    choosing: std::collections::HashSet<ValueId>,
    /// The significands introduced for [`Encoder::choosing`], to be bound with the values.
    chosen_aux: Vec<Int>,
    /// Which floats a chosen value may be ([`Encoder::integer_witnesses`]).
    witnesses: FloatWitnesses,
    /// Whether some chosen value had to be a float ([`Encoder::chose_floats`]).
    chose_floats: bool,
}

/// The witnesses "a chosen value is a float of its format" admits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FloatWitnesses {
    /// Every finite float of the format: `m * 2^q` over all its exponents.
    Exact,
    /// Its integers only (`m * 2^0`, `|m| < 2^p`): a subset, so "some payload exists"
    /// proved with them holds of the exact question too, at a fraction of its cost.
    Integers,
}

impl<'p> Encoder<'p> {
    pub fn new(prog: &'p Program) -> Encoder<'p> {
        Encoder {
            prog,
            vars: BTreeMap::new(),
            side: Vec::new(),
            enclosing: Vec::new(),
            roots: Vec::new(),
            frame: None,
            trig: Vec::new(),
            trig_by_arg: HashMap::new(),
            pi: None,
            value_names: HashMap::new(),
            quantified: false,
            strings: std::collections::HashSet::new(),
            polarity: Polarity::Other,
            choosing: std::collections::HashSet::new(),
            chosen_aux: Vec::new(),
            witnesses: FloatWitnesses::Exact,
            chose_floats: false,
        }
    }

    /// An encoder whose chosen floats are integers only: "some payload exists" becomes a
    /// stronger statement (fewer witnesses), so a progress query it proves (unsat) is
    /// proved for every float; a satisfiable one decides nothing and the exact encoding
    /// is asked ([`crate::smt`]'s worker). Z3 decides the integer form quickly, where the
    /// disjunction over 254 exponents of the exact form can take seconds.
    pub fn with_integer_witnesses(prog: &'p Program) -> Encoder<'p> {
        Encoder { witnesses: FloatWitnesses::Integers, ..Encoder::new(prog) }
    }

    /// Whether encoding chose a value that must be a float (so that the integer
    /// witnesses made the question stronger than asked).
    pub fn chose_floats(&self) -> bool {
        self.chose_floats
    }

    /// Encodes `f` as asserted (a hypothesis): [`Builtin::Float32`] of a value not known
    /// to be a float may then be weakened to `true`.
    pub fn assumed<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        self.at(Polarity::Assumed, f)
    }

    fn at<T>(&mut self, p: Polarity, f: impl FnOnce(&mut Self) -> T) -> T {
        let saved = std::mem::replace(&mut self.polarity, p);
        let r = f(self);
        self.polarity = saved;
        r
    }

    /// Encodes `f`, the body of "some payload `ids` exists" (asserted positively inside
    /// the existential): that a chosen value of a `float` field is a binary32 is encoded
    /// exactly, with an integer significand per value. Returns the significands, which
    /// the caller binds together with the values.
    pub fn choosing<T>(&mut self, ids: &[ValueId], f: impl FnOnce(&mut Self) -> T) -> (T, Vec<Int>) {
        let saved = std::mem::replace(&mut self.choosing, ids.iter().copied().collect());
        let aux = std::mem::take(&mut self.chosen_aux);
        let r = self.at(Polarity::Chosen, f);
        self.choosing = saved;
        (r, std::mem::replace(&mut self.chosen_aux, aux))
    }

    /// Encodes `f` in a position that is not positive (see [`Encoder::polarity`]).
    fn mixed<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        self.at(Polarity::Other, f)
    }

    /// `x` is a finite float of `format`, exactly: `x = m * 2^q` for an integer `m` with
    /// `|m| <= 2^p - 1` and one of the format's exponents `q` (a disjunction over them),
    /// `m` fresh. Correct where it is asserted positively (`m` is an existential's
    /// witness), so only [`Encoder::choosing`] uses it.
    fn float_member(&mut self, x: &Real, format: crate::lower::FloatFormat) -> Result<Bool, Unsupported> {
        let m = Int::fresh_const("significand");
        self.chosen_aux.push(m.clone());
        self.chose_floats = true;
        let big = Int::from_i64((1i64 << format.p) - 1);
        let mr = m.to_real();
        // The integers first (`m * 2^0`): a witness such as `0` or `1` is found there
        // without a case split over the exponents.
        let mut alts = vec![x.eq(&mr)];
        let every_exponent = self.witnesses == FloatWitnesses::Exact;
        for q in (format.qmin..=format.qmax).filter(|_| every_exponent) {
            let scale = real_of_rational(&crate::lower::pow2(q))
                .ok_or_else(|| Unsupported("a power of two too large for the solver".into()))?;
            alts.push(x.eq(Real::mul(&[mr.clone(), scale])));
        }
        Ok(Bool::and(&[m.le(&big), m.ge(big.unary_minus()), Bool::or(&alts)]))
    }

    /// [`Builtin::Float32`] / [`Builtin::Float64`] of `a`: decided exactly for a constant;
    /// `true` for a value of a field of that format or a narrower one (a fact of the
    /// model: [`Program::wire_floats`]) unless it is being chosen, exact for a chosen one;
    /// otherwise `true` in a hypothesis (a weaker one) and refused elsewhere, in an
    /// existential's body too, where `true` would be stronger (a computed value's rounding
    /// is not modelled).
    fn float_call(&mut self, f: Builtin, a: &Expr) -> Result<Term, Unsupported> {
        let format = crate::lower::float_format(f).ok_or_else(|| Unsupported("a float format".into()))?;
        if let Some(r) = crate::lower::exact_constant(self.prog, a) {
            return Ok(Term::B(Bool::from_bool(crate::lower::is_float(&r, format))));
        }
        if let ExprKind::Var(Var::Value(id, _)) = &a.kind {
            if self.choosing.contains(id) {
                if self.polarity != Polarity::Chosen {
                    return Err(Unsupported("a float payload value under a negation".into()));
                }
                let x = as_real(self.term(a)?)?;
                return Ok(Term::B(self.float_member(&x, format)?));
            }
            let narrower = |w: &Builtin| *w == f || (*w == Builtin::Float32 && f == Builtin::Float64);
            if self.prog.wire_floats.get(id).is_some_and(narrower) {
                return Ok(Term::B(Bool::from_bool(true)));
            }
        }
        if self.polarity == Polarity::Assumed {
            return Ok(Term::B(Bool::from_bool(true)));
        }
        Err(Unsupported(format!(
            "whether `{}` is a {} value (the rounding of a computed value to a MAVLink float is not modelled: send a literal or a value received in a field of that format)",
            crate::hir::print::expr(self.prog, None, a),
            if f == Builtin::Float32 { "float32" } else { "float64" }
        )))
    }

    pub fn prog(&self) -> &'p Program {
        self.prog
    }

    /// Constraints introduced by the encoding (roots, trigonometry), to assert with
    /// the query.
    pub fn side_conditions(&self) -> impl Iterator<Item = &Bool> {
        self.side.iter()
    }

    /// A side condition that encloses `sin`, `cos` or `pi` (see `enclosing`).
    fn enclose(&mut self, b: Bool) {
        self.enclosing.push(self.side.len());
        self.side.push(b);
    }

    /// The side conditions that are neither enclosures nor `sqrt`'s definitions
    /// ([`Encoder::root_terms`]): facts of the query (requirements such as `t >= 0`),
    /// which a witness must satisfy like its assertions.
    pub fn exact_side_conditions(&self) -> impl Iterator<Item = &Bool> {
        self.side
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.enclosing.contains(i) && !self.roots.iter().any(|r| r.2 == *i))
            .map(|(_, b)| b)
    }

    /// Each `sqrt e` of the query, as its fresh real and `e`: defined by `e >= 0 => (s >=
    /// 0 && s * s == e)`.
    pub fn root_terms(&self) -> impl Iterator<Item = (&Real, &Real)> {
        self.roots.iter().map(|(s, a, _)| (s, a))
    }

    /// The query's `pi`, if it reads it.
    pub fn pi_term(&self) -> Option<&Real> {
        self.pi.as_ref()
    }

    /// The query's `(argument, sin, cos)` triples, one per trigonometric argument.
    pub fn trig_terms(&self) -> impl Iterator<Item = (&Real, &Real, &Real)> {
        self.trig.iter().map(|t| (&t.arg, &t.sin, &t.cos))
    }

    /// Whether the query reads `sin` or `cos`.
    pub fn has_trig(&self) -> bool {
        !self.trig.is_empty()
    }

    /// Adds a constraint that every model must satisfy (for example `t >= 0`).
    pub fn require(&mut self, b: Bool) {
        self.side.push(b);
    }

    /// Encodes `e` with the primitive variables read through `frame`.
    pub fn in_frame<T>(&mut self, frame: &Frame, f: impl FnOnce(&mut Self) -> T) -> T {
        let saved = self.frame.replace(frame.clone());
        let r = f(self);
        self.frame = saved;
        r
    }

    pub fn boolean(&mut self, e: &Expr) -> Result<Bool, Unsupported> {
        match self.term(e)? {
            Term::B(b) => Ok(b),
            _ => Err(Unsupported("a non-boolean predicate".into())),
        }
    }

    /// Encodes a term of any sort (an argument of a primitive).
    pub fn any(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        self.term(e)
    }

    pub fn real(&mut self, e: &Expr) -> Result<Real, Unsupported> {
        as_real(self.term(e)?)
    }

    /// A named real variable, shown in counterexamples under `name`.
    pub fn named_real(&mut self, name: &str) -> Real {
        match self.vars.get(name) {
            Some(Term::R(r)) => r.clone(),
            _ => {
                let r = Real::new_const(name);
                self.vars.insert(name.to_string(), Term::R(r.clone()));
                r
            }
        }
    }

    /// A fresh variable of `sort` named `name` (shown in counterexamples).
    pub fn named(&mut self, name: &str, sort: &Sort) -> Result<Term, Unsupported> {
        if let Some(t) = self.vars.get(name) {
            return Ok(t.clone());
        }
        let t = match sort {
            Sort::Bool => Term::B(Bool::new_const(name)),
            // A string is an integer: literals are their codes (`Program::strings`).
            Sort::Int | Sort::Str => Term::I(Int::new_const(name)),
            Sort::Real | Sort::Any => Term::R(Real::new_const(name)),
            Sort::Point | Sort::Vector => Term::V([
                Real::new_const(format!("{name}.x")),
                Real::new_const(format!("{name}.y")),
                Real::new_const(format!("{name}.z")),
            ]),
            other => return Err(Unsupported(format!("variables of sort `{other}`"))),
        };
        if *sort == Sort::Str {
            self.strings.insert(name.to_string());
        }
        self.vars.insert(name.to_string(), t.clone());
        Ok(t)
    }

    /// The logic of the query: whether it declared an integer variable (those are
    /// declared only by [`Encoder::named`]).
    /// Marks the query as quantified (progress: some payload exists, `goals::progress`).
    pub fn quantified(&mut self) {
        self.quantified = true;
    }

    /// Marks the query as one of integer arithmetic though it may declare no integer
    /// variable (an integer payload value eliminated into `to_int` of reals,
    /// `goals::progress`): nlsat has no `to_int`.
    pub fn integer_terms(&mut self) {
        self.quantified = true;
    }

    pub fn logic(&self) -> Logic {
        if self.quantified || self.vars.values().any(|t| matches!(t, Term::I(_))) {
            Logic::WithIntegers
        } else {
            Logic::Nra
        }
    }

    /// The values of this query that share their name with another of its values: their
    /// symbol, their name and where they are bound (so that a counterexample naming `v`
    /// and `v#2` can say which is which).
    pub fn shared_names(&self) -> Vec<(String, String, crate::source::Span)> {
        let mut out: Vec<(String, String, crate::source::Span)> = self
            .value_names
            .iter()
            .filter(|(id, _)| {
                let name = &self.prog.value(**id).name;
                self.value_names.keys().any(|o| o != *id && self.prog.value(*o).name == *name)
            })
            .map(|(id, sym)| (sym.clone(), self.prog.value(*id).name.clone(), self.prog.value(*id).span))
            .collect();
        out.sort_by(|a, b| a.0.cmp(&b.0));
        out
    }

    /// A symbol for a new value variable named `name`: the name itself unless another
    /// value, a participant (whose variables are `Name.x`, as a point value's components
    /// are) or the time of a motion already has it, else `name#2`, `name#3`, ...
    fn value_symbol(&self, name: &str) -> String {
        let taken = |s: &str| {
            s == "time"
                || s == "point"
                || self.vars.contains_key(s)
                || self.value_names.values().any(|n| n == s)
                || self.prog.roles.iter().any(|r| r.name == s)
        };
        if !taken(name) {
            return name.to_string();
        }
        (2..).map(|k| format!("{name}#{k}")).find(|s| !taken(s)).unwrap_or_else(|| name.to_string())
    }

    /// The term of participant `r`'s variable in the shared vocabulary (`Cart.x`). An
    /// input is the state variable of the participant it is connected to (Sec 3.1), so
    /// `DCart.d` is `Env.d`: what is known of one is known of the other.
    pub fn role_var(&mut self, r: RoleId, slot: Slot) -> Result<Term, Unsupported> {
        if let Var::Role(src, src_slot @ Slot::State(_)) = self.prog.source_of(&Var::Role(r, slot)) {
            if src != r {
                return self.role_var(src, src_slot);
            }
        }
        let (n, s) = self.prog.kind_of(r).var(slot);
        let name = format!("{}.{n}", self.prog.role_name(r));
        self.named(&name, &s.clone())
    }

    /// The query's named variables (for replaying a model exactly).
    pub fn terms(&self) -> impl Iterator<Item = (&String, &Term)> {
        self.vars.iter()
    }

    /// The symbol each value variable of the query got (`v`, or `v#2` for a second value
    /// named `v`): values are told apart by their binding site, not their name.
    pub fn value_symbols(&self) -> impl Iterator<Item = (&crate::hir::ValueId, &String)> {
        self.value_names.iter()
    }

    /// The values of the query's variables in `model`, by name. Variables the query
    /// does not constrain (absent from the model) are left out.
    pub fn assignments(&self, model: &z3::Model) -> Vec<super::Assignment> {
        let real = |r: &Real| model.eval(r, true).map(|v| decimal(&v));
        self.vars
            .iter()
            .filter_map(|(name, t)| {
                let value = match t {
                    Term::B(b) => {
                        model.get_const_interp(b)?;
                        model.eval(b, true).map(|v| v.to_string())
                    }
                    Term::I(i) if self.strings.contains(name) => {
                        // A string's code: the literal it is, or a string none writes.
                        model.get_const_interp(i)?;
                        let code = model.eval(i, true)?.as_i64();
                        Some(match code.and_then(|c| self.prog.string(c)) {
                            Some(text) => format!("\"{text}\""),
                            None => "a string no literal of the protocol writes".to_string(),
                        })
                    }
                    Term::I(i) => {
                        model.get_const_interp(i)?;
                        model.eval(i, true).map(|v| int_text(&v.to_string()))
                    }
                    Term::R(r) => {
                        model.get_const_interp(r)?;
                        real(r)
                    }
                    Term::V([x, y, z]) => {
                        if [x, y, z].iter().all(|c| model.get_const_interp(*c).is_none()) {
                            return None;
                        }
                        Some(format!("({}, {}, {})", real(x)?, real(y)?, real(z)?))
                    }
                }?;
                Some(super::Assignment { name: name.clone(), value })
            })
            .collect()
    }

    /// The value of a real term in `model`, as a float (algebraic numbers approximated).
    pub fn value_of(model: &z3::Model, r: &Real) -> Option<f64> {
        let v = model.eval(r, true)?;
        match v.as_rational() {
            Some((n, d)) if d != 0 => Some(n as f64 / d as f64),
            _ => v.approx(17).parse().ok(),
        }
    }

    /// Whether `model` gives some `sin`/`cos` a value the real function does not take
    /// (beyond 1e-6): the counterexample is then an artefact of the enclosure.
    pub fn spurious_trig(&self, model: &z3::Model) -> bool {
        self.trig.iter().any(|t| {
            let (Some(a), Some(s), Some(c)) =
                (Self::value_of(model, &t.arg), Self::value_of(model, &t.sin), Self::value_of(model, &t.cos))
            else {
                return true;
            };
            (a.sin() - s).abs() > 1e-6 || (a.cos() - c).abs() > 1e-6
        })
    }

    /// Whether the query has variables that stand for real functions' values only
    /// through enclosures (`sin`, `cos`, `pi`): a point of the encoding need not be one of
    /// the functions (`guess.rs` guesses no such query).
    pub fn encloses(&self) -> bool {
        !self.trig.is_empty() || self.pi.is_some()
    }

    /// Every argument of `sin`/`cos` equals 0, where the encoding's enclosure is exact
    /// (`sin 0 = 0`, `cos 0 = 1`): a model with these added is a genuine one.
    pub fn trig_at_zero(&self) -> Vec<Bool> {
        let zero = Int::from_i64(0).to_real();
        self.trig.iter().map(|t| t.arg.eq(&zero)).collect()
    }
}

#[cfg(test)]
mod tests;

/// Trigonometry of parameters bound to constants (ARCHITECTURE.md, "Trig of constant
/// arguments"), through the whole pipeline.
#[cfg(test)]
mod constant_arg_tests;
