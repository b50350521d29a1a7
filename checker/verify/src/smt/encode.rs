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

    /// Every argument of `sin`/`cos` equals 0, where the encoding's enclosure is exact
    /// (`sin 0 = 0`, `cos 0 = 1`): a model with these added is a genuine one.
    /// Whether the query has variables that stand for real functions' values only
    /// through enclosures (`sin`, `cos`, `pi`): a point of the encoding need not be one of
    /// the functions (`guess.rs` guesses no such query).
    pub fn encloses(&self) -> bool {
        !self.trig.is_empty() || self.pi.is_some()
    }

    pub fn trig_at_zero(&self) -> Vec<Bool> {
        let zero = Int::from_i64(0).to_real();
        self.trig.iter().map(|t| t.arg.eq(&zero)).collect()
    }

    fn term(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        crate::stack::deep(|| self.term_inner(e))
    }

    fn term_inner(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        Ok(match &e.kind {
            ExprKind::Bool(b) => Term::B(Bool::from_bool(*b)),
            ExprKind::Int(i) => Term::I(Int::from_i64(*i)),
            ExprKind::Real(r) => Term::R(rational(r).ok_or_else(|| Unsupported(format!("the number `{r}`")))?),
            ExprKind::Var(v) => self.var(v, &e.sort)?,
            ExprKind::Unary(UnOp::Not, a) => Term::B(self.mixed(|enc| enc.boolean(a))?.not()),
            ExprKind::Unary(UnOp::Neg, a) => match self.term(a)? {
                Term::I(i) => Term::I(i.unary_minus()),
                Term::R(r) => Term::R(r.unary_minus()),
                Term::V(v) => Term::V(v.map(|c| c.unary_minus())),
                Term::B(_) => return Err(Unsupported("negation of a boolean".into())),
            },
            ExprKind::Binary(op, a, b) => self.binary(*op, a, b)?,
            ExprKind::If(c, a, b) => {
                let c = self.mixed(|enc| enc.boolean(c))?;
                match (self.term(a)?, self.term(b)?) {
                    (Term::B(x), Term::B(y)) => Term::B(c.ite(&x, &y)),
                    (Term::I(x), Term::I(y)) => Term::I(c.ite(&x, &y)),
                    (Term::V(x), Term::V(y)) => {
                        Term::V([c.ite(&x[0], &y[0]), c.ite(&x[1], &y[1]), c.ite(&x[2], &y[2])])
                    }
                    (x, y) => Term::R(c.ite(&as_real(x)?, &as_real(y)?)),
                }
            }
            ExprKind::Call(f, args) => self.call(*f, args)?,
            ExprKind::Component(a, i) => match self.term(a)? {
                Term::V(v) => Term::R(v[(*i).min(2)].clone()),
                _ => return Err(Unsupported("a component of something that is not a point".into())),
            },
            ExprKind::Tuple(_) => return Err(Unsupported("tuples".into())),
        })
    }

    fn binary(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Result<Term, Unsupported> {
        use BinOp::*;
        Ok(match op {
            And => Term::B(Bool::and(&[self.boolean(a)?, self.boolean(b)?])),
            Or => Term::B(Bool::or(&[self.boolean(a)?, self.boolean(b)?])),
            Implies => Term::B(self.mixed(|enc| enc.boolean(a))?.implies(self.boolean(b)?)),
            Pow => {
                let ExprKind::Int(n) = b.kind else {
                    return Err(Unsupported("a power whose exponent is not an integer literal".into()));
                };
                if n < 0 {
                    return Err(Unsupported("a negative power".into()));
                }
                match self.term(a)? {
                    Term::I(i) => Term::I(if n == 0 { Int::from_i64(1) } else { Int::mul(&vec![i; n as usize]) }),
                    other => {
                        let r = as_real(other)?;
                        Term::R(if n == 0 { one() } else { Real::mul(&vec![r; n as usize]) })
                    }
                }
            }
            Eq | Ne => {
                let pair = self.mixed(|enc| Ok::<_, Unsupported>((enc.term(a)?, enc.term(b)?)))?;
                let eq = match integral_pair(pair) {
                    (Term::B(x), Term::B(y)) => x.eq(&y),
                    (Term::I(x), Term::I(y)) => x.eq(&y),
                    (Term::V(x), Term::V(y)) => Bool::and(&[x[0].eq(&y[0]), x[1].eq(&y[1]), x[2].eq(&y[2])]),
                    (x, y) => as_real(x)?.eq(&as_real(y)?),
                };
                Term::B(if op == Eq { eq } else { eq.not() })
            }
            Lt | Le | Gt | Ge | Add | Sub | Mul | Div => {
                let (x, y) = (self.term(a)?, self.term(b)?);
                let pair = if op == Div { (x, y) } else { integral_pair((x, y)) };
                match pair {
                    (Term::V(u), Term::V(v)) if matches!(op, Add | Sub) => Term::V(std::array::from_fn(|k| {
                        if op == Add {
                            Real::add(&[u[k].clone(), v[k].clone()])
                        } else {
                            Real::sub(&[u[k].clone(), v[k].clone()])
                        }
                    })),
                    (Term::V(v), s) | (s, Term::V(v)) if op == Mul => {
                        let s = as_real(s)?;
                        Term::V(v.map(|c| Real::mul(&[s.clone(), c])))
                    }
                    (Term::V(v), s) if op == Div => {
                        let s = as_real(s)?;
                        Term::V(v.map(|c| c.div(&s)))
                    }
                    (Term::V(_), _) | (_, Term::V(_)) => {
                        return Err(Unsupported(format!("`{}` on points or vectors", op_text(op))));
                    }
                    (Term::I(x), Term::I(y)) if op != Div => match op {
                        Lt => Term::B(x.lt(&y)),
                        Le => Term::B(x.le(&y)),
                        Gt => Term::B(x.gt(&y)),
                        Ge => Term::B(x.ge(&y)),
                        Add => Term::I(Int::add(&[x, y])),
                        Sub => Term::I(Int::sub(&[x, y])),
                        _ => Term::I(Int::mul(&[x, y])),
                    },
                    (x, y) => {
                        let (x, y) = (as_real(x)?, as_real(y)?);
                        match op {
                            Lt => Term::B(x.lt(&y)),
                            Le => Term::B(x.le(&y)),
                            Gt => Term::B(x.gt(&y)),
                            Ge => Term::B(x.ge(&y)),
                            Add => Term::R(Real::add(&[x, y])),
                            Sub => Term::R(Real::sub(&[x, y])),
                            Mul => Term::R(Real::mul(&[x, y])),
                            _ => Term::R(x.div(&y)),
                        }
                    }
                }
            }
        })
    }

    fn call(&mut self, f: Builtin, args: &[Expr]) -> Result<Term, Unsupported> {
        let arg = |enc: &mut Self, i: usize| -> Result<Term, Unsupported> {
            args.get(i)
                .ok_or_else(|| Unsupported(format!("`{}` without arguments", f.name())))
                .and_then(|a| enc.term(a))
        };
        let zero = || Int::from_i64(0).to_real();
        Ok(match f {
            Builtin::Float32 | Builtin::Float64 => {
                let a = args.first().ok_or_else(|| Unsupported(format!("`{}` without arguments", f.name())))?;
                self.float_call(f, a)?
            }
            Builtin::HasFlag => {
                // Exact: bit k of x is (x div 2^k) mod 2 (Euclidean, so a negative x reads as
                // its two's complement), for every bit k of the constant flag.
                let flag = args
                    .get(1)
                    .and_then(|a| crate::hir::expr::const_int(self.prog, a))
                    .filter(|f| *f > 0)
                    .ok_or_else(|| Unsupported("`has_flag` with a flag that is not a positive constant".into()))?;
                let Term::I(x) = arg(self, 0)? else {
                    return Err(Unsupported("`has_flag` of a term that is not an integer".into()));
                };
                let bits: Vec<Bool> = (0..63)
                    .filter(|k| flag >> k & 1 == 1)
                    .map(|k| x.div(Int::from_i64(1 << k)).modulo(Int::from_i64(2)).eq(Int::from_i64(1)))
                    .collect();
                Term::B(Bool::and(&bits))
            }
            Builtin::Sqrt => {
                let a = as_real(arg(self, 0)?)?;
                let s = Real::fresh_const("sqrt");
                let def = Bool::and(&[s.ge(zero()), Real::mul(&[s.clone(), s.clone()]).eq(&a)]);
                self.roots.push((s.clone(), a.clone(), self.side.len()));
                self.side.push(a.ge(zero()).implies(&def));
                Term::R(s)
            }
            Builtin::Abs => match arg(self, 0)? {
                Term::I(i) => Term::I(i.ge(Int::from_i64(0)).ite(&i, &i.unary_minus())),
                other => {
                    let r = as_real(other)?;
                    Term::R(r.ge(zero()).ite(&r, &r.unary_minus()))
                }
            },
            Builtin::Min | Builtin::Max => {
                let min = f == Builtin::Min;
                match (arg(self, 0)?, arg(self, 1)?) {
                    (Term::I(x), Term::I(y)) => Term::I(if min { x.le(&y) } else { x.ge(&y) }.ite(&x, &y)),
                    (a, b) => {
                        let (x, y) = (as_real(a)?, as_real(b)?);
                        Term::R(if min { x.le(&y) } else { x.ge(&y) }.ite(&x, &y))
                    }
                }
            }
            Builtin::Sin | Builtin::Cos => {
                let e = args.first().ok_or_else(|| Unsupported(format!("`{}` without arguments", f.name())))?;
                // A parameter bound to a constant (`go(pi / 4)`) is read as that constant.
                let constant = self.constant_args(e);
                if let Some((c, s)) = bounds::quarter_turn(self.prog, constant.as_ref().unwrap_or(e)) {
                    // An exact multiple of π/2: 0 or ±1, exactly (no fresh pair).
                    return Ok(Term::R(Int::from_i64(if f == Builtin::Sin { s } else { c }).to_real()));
                }
                let (s, c) = self.trig_pair(e, constant.as_ref())?;
                Term::R(if f == Builtin::Sin { s } else { c })
            }
            Builtin::Point | Builtin::Vector => {
                let (x, y, z) = (as_real(arg(self, 0)?)?, as_real(arg(self, 1)?)?, as_real(arg(self, 2)?)?);
                Term::V([x, y, z])
            }
            Builtin::Dot => match (arg(self, 0)?, arg(self, 1)?) {
                (Term::V(u), Term::V(v)) => Term::R(dot(&u, &v)),
                _ => return Err(Unsupported("`dot` of something that is not a vector".into())),
            },
            Builtin::Norm2 => match arg(self, 0)? {
                Term::V(v) => Term::R(dot(&v, &v)),
                _ => return Err(Unsupported("`norm2` of something that is not a vector".into())),
            },
            Builtin::Pi => Term::R(self.pi()),
        })
    }

    /// π: one fresh real per query, constrained to `[PI_LO, PI_HI]` (a rational enclosure
    /// 2e-20 wide). Sound: an unsat answer holds for every value in the enclosure, π
    /// among them; a model's value for it is merely near π, so a counterexample that
    /// depends on it is replayed ([`crate::exact`] encloses π too) before it is shown.
    fn pi(&mut self) -> Real {
        if let Some(p) = &self.pi {
            return p.clone();
        }
        let p = Real::fresh_const("pi");
        let lo = Real::from_rational_str(PI_LO.0, PI_LO.1).expect("literal");
        let hi = Real::from_rational_str(PI_HI.0, PI_HI.1).expect("literal");
        self.enclose(Bool::and(&[p.ge(&lo), p.le(&hi)]));
        self.pi = Some(p.clone());
        p
    }

    /// `e` with each parameter of the current frame replaced by its argument at the call
    /// site, when that makes it closed (literals, constants and `pi` only) and `e` reads
    /// some parameter; `None` otherwise. Sound: in a primitive run as `go(a1, ..., an)`
    /// the parameter `i` *is* `ai` (the frame encodes it as `ai`'s term), so the closed
    /// expression has the value of `e`, and its enclosures ([`bounds::quarter_turn`],
    /// [`bounds::eval`]) enclose `e`'s.
    fn constant_args(&self, e: &Expr) -> Option<Expr> {
        let frame = self.frame.as_ref()?;
        // The arguments must be the ones the parameters' terms encode (a frame with free
        // parameters, as in a declaration's own contract check, has none).
        if frame.args.len() != frame.params.len() {
            return None;
        }
        let mut reads_param = false;
        e.visit_vars(&mut |v, _| reads_param |= matches!(v, Var::Param(_)));
        if !reads_param {
            return None;
        }
        let closed = crate::hir::expr::map_vars(e, &mut |v, _| match v {
            Var::Param(i) => frame.args.get(*i).cloned(),
            _ => None,
        });
        (!mentions_free(&closed)).then_some(closed)
    }

    /// The fresh `(sin e, cos e)` pair for `e`, with its enclosing side conditions;
    /// `constant` is `e` read with constant arguments ([`Encoder::constant_args`]).
    fn trig_pair(&mut self, e: &Expr, constant: Option<&Expr>) -> Result<(Real, Real), Unsupported> {
        let a = as_real(self.term(e)?)?;
        let key = a.to_string();
        if let Some(&i) = self.trig_by_arg.get(&key) {
            return Ok((self.trig[i].sin.clone(), self.trig[i].cos.clone()));
        }
        let (s, c) = (Real::fresh_const("sin"), Real::fresh_const("cos"));
        let unit = Real::add(&[Real::mul(&[s.clone(), s.clone()]), Real::mul(&[c.clone(), c.clone()])]).eq(one());
        self.enclose(unit);
        // A constant argument, written as one or bound to a parameter (the encoding of
        // `go(0.7853981633974483)`'s parameter simplifies to that rational): enclose its
        // value. The rational is read exactly, whatever its size.
        let constant_value = rational_value(&a.simplify()).map(|q| bounds::Interval::of_rational(&q));
        // Otherwise a closed expression, as written or through constant arguments (`pi`
        // among them, which the numeral above cannot show): its interval enclosure.
        let closed = constant.or_else(|| (!mentions_free(e)).then_some(e));
        let bound = constant_value
            .or_else(|| closed.and_then(|e| bounds::eval(self.prog, e, &bounds::closed)))
            .filter(|i| i.is_finite());
        if let Some(iv) = bound {
            for (f, t) in [(Builtin::Sin, &s), (Builtin::Cos, &c)] {
                let b = bounds::trig(f, Some(iv));
                if let (Some(lo), Some(hi)) = (real_of_f64(b.lo), real_of_f64(b.hi)) {
                    self.enclose(if b.lo == b.hi { t.eq(&lo) } else { Bool::and(&[t.ge(&lo), t.le(&hi)]) });
                }
            }
        } else {
            // Taylor enclosures valid for every real argument.
            let a2 = Real::mul(&[a.clone(), a.clone()]);
            let a3 = Real::mul(&[a2.clone(), a.clone()]);
            let a4 = Real::mul(&[a2.clone(), a2.clone()]);
            let half = rational("0.5").expect("literal");
            let sixth = Real::from_rational_str("1", "6").expect("literal");
            let inv24 = Real::from_rational_str("1", "24").expect("literal");
            let c_lo = Real::sub(&[one(), Real::mul(&[half, a2])]);
            let c_hi = Real::add(&[c_lo.clone(), Real::mul(&[inv24, a4])]);
            let s_cubic = Real::sub(&[a.clone(), Real::mul(&[sixth, a3])]);
            let zero = Int::from_i64(0).to_real();
            let m1 = Int::from_i64(-1).to_real();
            self.enclose(Bool::and(&[
                c.ge(&c_lo),
                c.le(&c_hi),
                a.ge(&zero).implies(Bool::and(&[s.ge(&s_cubic), s.le(&a)])),
                a.le(&zero).implies(Bool::and(&[s.le(&s_cubic), s.ge(&a)])),
                s.ge(&m1),
                s.le(one()),
                c.ge(&m1),
                c.le(one()),
            ]));
        }
        self.trig_by_arg.insert(key, self.trig.len());
        self.trig.push(TrigPair { arg: a, sin: s.clone(), cos: c.clone() });
        Ok((s, c))
    }

    /// `sort` is the occurrence's sort, used when the variable was declared without one
    /// (a process binder takes its sort from the payload field it receives).
    fn var(&mut self, v: &Var, sort: &Sort) -> Result<Term, Unsupported> {
        let frame_var = |what: &str, t: Option<Term>| {
            t.ok_or_else(|| Unsupported(format!("{what} outside a motion primitive's contract")))
        };
        match v {
            Var::Const(c) => {
                // Constants are closed terms: encode their definition.
                let value = self.prog.consts[c.idx()].value.clone();
                self.term(&value)
            }
            Var::Role(r, slot) => self.role_var(*r, *slot),
            Var::Snap(r, slot) => {
                let (n, s) = self.prog.kind_of(*r).var(*slot);
                let name = format!("old({}.{n})", self.prog.role_name(*r));
                self.named(&name, &s.clone())
            }
            Var::Value(id, name) => {
                let declared = self.prog.value(*id).sort.clone();
                let sort = if declared == Sort::Any { sort.clone() } else { declared };
                let symbol = match self.value_names.get(id) {
                    Some(s) => s.clone(),
                    None => {
                        let s = self.value_symbol(name);
                        self.value_names.insert(*id, s.clone());
                        s
                    }
                };
                self.named(&symbol, &sort)
            }
            Var::Own(slot) => {
                let t = self.frame.as_ref().and_then(|f| f.own.get(slot).cloned());
                frame_var("a primitive's own variable", t)
            }
            Var::Old(i) => {
                let t = self.frame.as_ref().and_then(|f| f.old.get(*i).cloned());
                frame_var("`old(..)`", t)
            }
            Var::Param(i) => {
                let t = self.frame.as_ref().and_then(|f| f.params.get(*i).cloned());
                frame_var("a primitive's parameter", t)
            }
            Var::Clock => {
                let t = self.frame.as_ref().and_then(|f| f.clock.clone()).map(Term::R);
                frame_var("`clock`", t)
            }
            Var::Point(i) => {
                let t = self.frame.as_ref().and_then(|f| f.point.as_ref()).map(|p| Term::R(p[(*i).min(2)].clone()));
                frame_var("a footprint's point", t)
            }
        }
    }
}

/// Whether `e` mentions any variable other than constants.
fn mentions_free(e: &Expr) -> bool {
    let mut free = false;
    e.visit_vars(&mut |v, _| free |= !matches!(v, Var::Const(_)));
    free
}

fn dot(u: &[Real; 3], v: &[Real; 3]) -> Real {
    Real::add(&[
        Real::mul(&[u[0].clone(), v[0].clone()]),
        Real::mul(&[u[1].clone(), v[1].clone()]),
        Real::mul(&[u[2].clone(), v[2].clone()]),
    ])
}

fn op_text(op: BinOp) -> &'static str {
    match op {
        BinOp::Lt => "<",
        BinOp::Le => "<=",
        BinOp::Gt => ">",
        BinOp::Ge => ">=",
        BinOp::Mul => "*",
        BinOp::Div => "/",
        _ => "this operator",
    }
}

pub fn as_real(t: Term) -> Result<Real, Unsupported> {
    match t {
        Term::R(r) => Ok(r),
        Term::I(i) => Ok(i.to_real()),
        Term::B(_) => Err(Unsupported("a boolean used as a number".into())),
        Term::V(_) => Err(Unsupported("a point or vector used as a number".into())),
    }
}

pub fn one() -> Real {
    Int::from_i64(1).to_real()
}

/// A decimal literal (`0.65`, `1e-3`, `12`) as an exact Z3 rational.
pub fn rational(lit: &str) -> Option<Real> {
    // One reader of decimals for the whole checker: the interval stage's.
    real_of_rational(&bounds::decimal(lit)?)
}

/// An f64 as the exact rational it is (not its shortest round-trip decimal, which may
/// lie on either side of it: an enclosure's end must not move inward).
pub fn real_of_f64(v: f64) -> Option<Real> {
    real_of_rational(&BigRational::from_float(v)?)
}

/// An integer term against a real numeral of integral value (`2^64 - 1`, a `uint64_t`
/// field's wire bound, is beyond `i64` and so written as a real): the numeral as an
/// integer, so that the comparison or sum stays in integer arithmetic. Exact (the numeral
/// is that integer); a `to_real` of an integer variable next to a 20-digit real makes Z3's
/// quantified integer queries (progress over a `uint64_t` field) time out, where the
/// integer form is decided at once.
fn integral_pair(pair: (Term, Term)) -> (Term, Term) {
    let int_of = |r: &Real| {
        let q = rational_value(r).filter(|q| q.is_integer())?;
        q.numer().to_string().parse::<Int>().ok()
    };
    match pair {
        (Term::I(x), Term::R(r)) => match int_of(&r) {
            Some(y) => (Term::I(x), Term::I(y)),
            None => (Term::I(x), Term::R(r)),
        },
        (Term::R(r), Term::I(y)) => match int_of(&r) {
            Some(x) => (Term::I(x), Term::I(y)),
            None => (Term::R(r), Term::I(y)),
        },
        other => other,
    }
}

/// An exact rational as a Z3 real.
pub fn real_of_rational(q: &BigRational) -> Option<Real> {
    Real::from_rational_str(&q.numer().to_string(), &q.denom().to_string())
}

/// The exact value of a Z3 numeral (`3.0`, `(/ 1.0 3.0)`, `(- (/ 7.0 2.0))`), of any
/// size; `None` for anything that is not a rational numeral.
pub fn rational_value(r: &Real) -> Option<BigRational> {
    if let Some((n, d)) = r.as_rational().filter(|&(_, d)| d != 0) {
        return Some(BigRational::new(n.into(), d.into()));
    }
    let text = r.to_string().replace(['(', ')'], " ");
    let mut toks: Vec<&str> = text.split_whitespace().collect();
    let mut neg = false;
    while let Some(i) = toks.iter().position(|t| *t == "-") {
        toks.remove(i);
        neg = !neg;
    }
    let q = match toks.as_slice() {
        [n] => bounds::decimal(n)?,
        ["/", n, d] => {
            let d = bounds::decimal(d)?;
            if d.is_zero() {
                return None;
            }
            bounds::decimal(n)? / d
        }
        _ => return None,
    };
    Some(if neg { -q } else { q })
}

/// Z3 prints rationals as `(/ 13.0 20.0)`; users read `0.65` (rounded to 1e-6 m or s,
/// far below any tolerance of the robots modelled).
fn decimal(r: &Real) -> String {
    // The exact value: a decimal of at most 30 places (Z3's models are mostly short
    // rationals), else a fraction. Never a value rounded to a few places that reads as exact:
    // `th == pi / 2` holds of a model's value in π's enclosure, halved, as far as exact
    // arithmetic can tell, and not of 1.570796.
    if let Some(q) = rational_value(r) {
        if let Some(text) = exact_decimal(&q, 30) {
            return text;
        }
        // A fraction that is no short decimal (a dyadic one from Z3's arithmetic, n / 2^68):
        // exactly, while it stays readable.
        let (n, d) = (q.numer().to_string(), q.denom().to_string());
        if n.len() <= 30 && d.len() <= 30 {
            return format!("{n}/{d}");
        }
    }
    // Otherwise (an algebraic number, a huge fraction) the nearest double, marked as such.
    let v = match r.approx(17).parse::<f64>() {
        Ok(v) => v,
        Err(_) => return r.to_string(),
    };
    if v != 0.0 && v.abs() < 1e-4 {
        format!("≈{v:e}")
    } else {
        format!("≈{v}")
    }
}

/// `q` written exactly in decimal, if it has at most `places` decimal places: `0.65`,
/// `-7`, `1e-9` (scientific below 1e-4, as Rust prints small doubles).
fn exact_decimal(q: &BigRational, places: u32) -> Option<String> {
    let ten = num_bigint::BigInt::from(10u8);
    let mut scaled = q.clone();
    let mut k = 0u32;
    while !scaled.is_integer() {
        if k == places {
            return None;
        }
        scaled *= BigRational::from_integer(ten.clone());
        k += 1;
    }
    let n = scaled.to_integer();
    let (neg, digits) = (n.sign() == num_bigint::Sign::Minus, n.magnitude().to_string());
    let sign = if neg { "-" } else { "" };
    if k == 0 {
        return Some(format!("{sign}{digits}"));
    }
    let small = !n.is_zero() && (digits.len() as i64 - k as i64) < -3;
    let text = if small {
        // d.ddd e-x: the exponent of the leading digit.
        let exp = digits.len() as i64 - 1 - k as i64;
        let mant = digits.trim_end_matches('0');
        match mant.len() {
            1 => format!("{mant}e{exp}"),
            _ => format!("{}.{}e{exp}", &mant[..1], &mant[1..]),
        }
    } else if digits.len() as u32 > k {
        let (int, frac) = digits.split_at(digits.len() - k as usize);
        format!("{int}.{}", frac.trim_end_matches('0'))
    } else {
        format!("0.{}{}", "0".repeat((k as usize) - digits.len()), digits.trim_end_matches('0'))
    };
    Some(format!("{sign}{}", text.trim_end_matches('.')))
}

/// An integer of a Z3 model as the user writes it: Z3 prints a negative one as `(- 1)`.
fn int_text(z3: &str) -> String {
    match z3.strip_prefix("(- ").and_then(|r| r.strip_suffix(')')) {
        Some(n) if n.bytes().all(|b| b.is_ascii_digit()) => format!("-{n}"),
        _ => z3.to_string(),
    }
}

#[cfg(test)]
mod tests;

/// Trigonometry of parameters bound to constants (ARCHITECTURE.md, "Trig of constant
/// arguments"), through the whole pipeline.
#[cfg(test)]
mod constant_arg_tests;
