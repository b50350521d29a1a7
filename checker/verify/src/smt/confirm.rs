//! Confirming the witness of a satisfiability question whose encoding encloses `sin`,
//! `cos` or `pi`.
//!
//! The encoder reads `sin e`, `cos e` and `pi` as fresh reals inside enclosures
//! ([`super::encode`]). For a *validity* question that is sound (an unsat answer holds for
//! every value of the enclosure, the real one among them). For a *satisfiability*
//! question (can a motion end, Def 4.11; is a context satisfiable, the vacuity guard) it
//! is not: a model may put `sin 1` a few ulps away from sin 1, and `post: x == sin(1) &&
//! x == 0.8414709848078965` (a decimal 6.7e-17 from sin 1) then has an "end state"
//! although no real state satisfies it. So a `sat` answer to such a question counts only
//! when its witness is confirmed here, exactly:
//!
//! 1. **Atoms.** `pi`, each `sin e`/`cos e` and each `sqrt e` (where `e` is not negative)
//!    stand for their real values, which are irrational in general. Each is an *atom* with
//!    an exact enclosure ([`crate::exact::pi_tight`], 1e-50 wide; [`crate::exact::trig`] at
//!    the argument's value, 1e-40 wide for moderate arguments; [`crate::exact::sqrt_tight`]) and
//!    the identities it satisfies: `sin e² = 1 - cos e²`, `sqrt e² = e`.
//! 2. **Definitions.** A top-level equation `x == t` of a variable `x` whose right side
//!    reads an atom (directly or through another definition, without a cycle) *defines*
//!    `x`: `x` takes `t`'s real value instead of the model's, so `x == sin(1)` holds by
//!    construction and `x == sin(1) && x == 0.8414709848078965` needs sin 1 to equal the
//!    decimal, which it does not. Every other variable keeps the model's exact value.
//! 3. **Evaluation.** Every assertion and every side condition that is not an enclosure
//!    must evaluate to *true*. Numbers are polynomials with rational coefficients in the
//!    atoms, reduced by the identities, so that a witness that rests on `cos² + sin² = 1`
//!    (an end state `x = x0 + d cos t`, `y = y0 + d sin t` checked against
//!    `(x - x0) cos t + (y - y0) sin t <= d`) is decided exactly; a comparison whose difference does not
//!    reduce to a constant is decided by the atoms' enclosures, and otherwise undecided.
//!    An operation outside polynomials (a division by a non-constant, `if` on an
//!    undecided condition) falls back to an interval of the value.
//!
//! Sound: the atoms' and the defined variables' values are reals inside their intervals
//! that satisfy the identities used, the enclosures' side conditions hold of the real
//! functions by construction, and each remaining conjunct is true of every value of the
//! intervals; so the real question has this point as a witness. Incomplete, never
//! unsound: a conjunct undecided (a comparison closer than the enclosures, an identity
//! other than the two above, an algebraic model value such as `x * x == 2`) leaves the
//! witness unconfirmed, and the caller then looks for a witness with every trigonometric
//! argument 0, where the enclosures are exact, and otherwise answers unknown.

use super::goals::Query;
use super::key::{self, Node};
use crate::exact::{self, Num, Rat, Tri};
use crate::hir::Builtin;
use num_bigint::BigInt;
use num_traits::{One, Signed, Zero};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::str::FromStr;
use z3::ast::{Ast, Dynamic};

/// A product of atoms with their exponents, sorted by atom.
type Mono = Vec<(usize, u32)>;

/// A polynomial in the atoms with exact rational coefficients (no zero coefficient).
#[derive(Clone, Debug, PartialEq)]
struct Poly(BTreeMap<Mono, Rat>);

/// A polynomial with more terms is not multiplied out further (its value becomes an
/// interval): a guard against blow-up, never reached by the corpus.
const MAX_TERMS: usize = 4096;

impl Poly {
    fn constant(r: Rat) -> Poly {
        let mut m = BTreeMap::new();
        if !r.is_zero() {
            m.insert(Vec::new(), r);
        }
        Poly(m)
    }

    fn atom(a: usize) -> Poly {
        Poly(BTreeMap::from([(vec![(a, 1)], Rat::one())]))
    }

    fn as_constant(&self) -> Option<Rat> {
        match self.0.len() {
            0 => Some(Rat::zero()),
            1 => self.0.get(&Vec::new()).cloned(),
            _ => None,
        }
    }

    fn add(&self, o: &Poly) -> Poly {
        let mut m = self.0.clone();
        for (k, c) in &o.0 {
            let e = m.entry(k.clone()).or_insert_with(Rat::zero);
            *e += c;
            if e.is_zero() {
                m.remove(k);
            }
        }
        Poly(m)
    }

    fn scale(&self, r: &Rat) -> Poly {
        if r.is_zero() {
            return Poly::constant(Rat::zero());
        }
        Poly(self.0.iter().map(|(k, c)| (k.clone(), c * r)).collect())
    }

    fn neg(&self) -> Poly {
        self.scale(&-Rat::one())
    }
}

/// What an atom is, for its identities.
#[derive(Clone, Debug)]
enum AtomKind {
    Pi,
    /// `sin e`, with the atom of `cos e`: `sin² = 1 - cos²`.
    Sin(usize),
    Cos,
    /// `sqrt e` of a non-negative `e`: `sqrt² = e`.
    Sqrt(Poly),
}

#[derive(Clone, Debug)]
struct Atom {
    kind: AtomKind,
    value: Num,
}

/// A value of a term: a truth value, a polynomial in the atoms, or (outside polynomials)
/// an enclosure of a number.
#[derive(Clone, Debug)]
enum Val {
    B(Tri),
    P(Poly),
    N(Num),
}

/// What a free constant stands for.
enum Def {
    Pi,
    /// `sin` or `cos` of a term (the first), with the pair's `sin` and `cos` constants.
    Trig(Builtin, Dynamic, [Dynamic; 2]),
    /// A variable defined by an equation (step 2 of the module doc).
    Defined(Dynamic),
    /// `sqrt` of a term: its real value where the term is not negative (its definition
    /// in the encoding then holds by construction), the model's where it is negative (the
    /// definition then says nothing).
    Sqrt(Dynamic),
}

/// `Ok` when `model` confirms a witness of `q` (see the module doc); otherwise why not,
/// naming the first conjunct not shown true.
pub fn confirm(q: &Query, model: &z3::Model) -> Result<(), String> {
    let mut defs: HashMap<u32, Def> = HashMap::new();
    if let Some(pi) = q.enc.pi_term() {
        defs.insert(key::id(&Dynamic::from_ast(pi)), Def::Pi);
    }
    for (arg, sin, cos) in q.enc.trig_terms() {
        let pair = [Dynamic::from_ast(sin), Dynamic::from_ast(cos)];
        defs.insert(key::id(&pair[0]), Def::Trig(Builtin::Sin, Dynamic::from_ast(arg), pair.clone()));
        defs.insert(key::id(&pair[1]), Def::Trig(Builtin::Cos, Dynamic::from_ast(arg), pair));
    }
    for (s, arg) in q.enc.root_terms() {
        defs.insert(key::id(&Dynamic::from_ast(s)), Def::Sqrt(Dynamic::from_ast(arg)));
    }
    let mut conjuncts = Vec::new();
    for a in q.assertions.iter().chain(q.enc.exact_side_conditions()) {
        flatten(&Dynamic::from_ast(a), &mut conjuncts);
    }
    // Definitions, in order, each reading only atoms, model values and earlier
    // definitions (so there is no cycle), until none is added.
    let mut definitions: HashSet<usize> = HashSet::new();
    loop {
        let mut added = false;
        for (k, c) in conjuncts.iter().enumerate() {
            if definitions.contains(&k) {
                continue;
            }
            let Node::App(op, args) = key::view(c) else { continue };
            if op != "=" || args.len() != 2 {
                continue;
            }
            for (x, t) in [(&args[0], &args[1]), (&args[1], &args[0])] {
                let xid = key::id(x);
                if !matches!(key::view(x), Node::Const) || defs.contains_key(&xid) || x.as_real().is_none() {
                    continue;
                }
                let mut reads = Reads::default();
                reads.walk(t, &defs);
                if reads.enclosed && !reads.free.contains(&xid) {
                    defs.insert(xid, Def::Defined(t.clone()));
                    definitions.insert(k);
                    added = true;
                    break;
                }
            }
        }
        if !added {
            break;
        }
    }
    let mut ev = Eval { model, defs: &defs, memo: HashMap::new(), atoms: Vec::new(), atom_of: HashMap::new() };
    for (k, c) in conjuncts.iter().enumerate() {
        if definitions.contains(&k) {
            continue;
        }
        match ev.val(c) {
            Ok(Val::B(Tri::True)) => {}
            Ok(Val::B(Tri::False)) => return Err(format!("`{c}` is false of the real functions' values")),
            Ok(_) => return Err(format!("`{c}` is not decided exactly")),
            Err(why) => return Err(format!("`{c}` cannot be evaluated exactly: {why}")),
        }
    }
    Ok(())
}

/// The conjuncts of `t` (nested `and`s taken apart).
fn flatten(t: &Dynamic, out: &mut Vec<Dynamic>) {
    match key::view(t) {
        Node::App(op, args) if op == "and" => {
            for a in &args {
                flatten(a, out);
            }
        }
        _ => out.push(t.clone()),
    }
}

/// The free constants a term reads, and whether it reads an atom (directly or through a
/// definition).
#[derive(Default)]
struct Reads {
    free: HashSet<u32>,
    enclosed: bool,
    seen: HashSet<u32>,
}

impl Reads {
    fn walk(&mut self, t: &Dynamic, defs: &HashMap<u32, Def>) {
        let id = key::id(t);
        if !self.seen.insert(id) {
            return;
        }
        match key::view(t) {
            Node::Const => {
                self.free.insert(id);
                match defs.get(&id) {
                    Some(Def::Pi) => self.enclosed = true,
                    Some(Def::Trig(_, e, _) | Def::Defined(e) | Def::Sqrt(e)) => {
                        self.enclosed = true;
                        self.walk(e, defs);
                    }
                    None => {}
                }
            }
            Node::App(_, args) => {
                for a in &args {
                    self.walk(a, defs);
                }
            }
            Node::Numeral(_) | Node::Other(_) => {}
        }
    }
}

struct Eval<'a> {
    model: &'a z3::Model,
    defs: &'a HashMap<u32, Def>,
    memo: HashMap<u32, Val>,
    atoms: Vec<Atom>,
    /// The atom of each constant that is one (by the constant's id).
    atom_of: HashMap<u32, usize>,
}

impl Eval<'_> {
    fn val(&mut self, t: &Dynamic) -> Result<Val, String> {
        let id = key::id(t);
        if let Some(v) = self.memo.get(&id) {
            return Ok(v.clone());
        }
        // Definitions are acyclic, so the recursion follows the terms' depth.
        let v = crate::stack::deep(|| self.compute(t))?;
        self.memo.insert(id, v.clone());
        Ok(v)
    }

    fn tri(&mut self, t: &Dynamic) -> Result<Tri, String> {
        match self.val(t)? {
            Val::B(b) => Ok(b),
            _ => Err("a number where a truth value was expected".into()),
        }
    }

    /// A number's enclosure.
    fn interval(&self, v: &Val) -> Result<Num, String> {
        match v {
            Val::N(n) => Ok(n.clone()),
            Val::P(p) => Ok(self.enclose(p)),
            Val::B(_) => Err("a truth value where a number was expected".into()),
        }
    }

    fn enclose(&self, p: &Poly) -> Num {
        let mut acc = Num::int(0);
        for (m, c) in &p.0 {
            let mut term = Num::exact(c.clone());
            for &(a, e) in m {
                let mut pow = Num::int(1);
                for _ in 0..e {
                    pow = pow.mul(&self.atoms[a].value);
                }
                if e % 2 == 0 && pow.lo.is_negative() {
                    pow.lo = Rat::zero();
                }
                term = term.mul(&pow);
            }
            acc = acc.add(&term);
        }
        acc
    }

    /// `p` with `sin² = 1 - cos²` and `sqrt e² = e` applied until neither applies.
    fn reduce(&self, p: Poly) -> Poly {
        let mut out = Poly::constant(Rat::zero());
        let mut work: Vec<(Mono, Rat)> = p.0.into_iter().collect();
        while let Some((m, c)) = work.pop() {
            let Some(i) = m
                .iter()
                .position(|&(a, e)| e >= 2 && matches!(self.atoms[a].kind, AtomKind::Sin(_) | AtomKind::Sqrt(_)))
            else {
                out = out.add(&Poly(BTreeMap::from([(m, c)])));
                continue;
            };
            let (a, e) = m[i];
            let mut rest = m.clone();
            if e == 2 {
                rest.remove(i);
            } else {
                rest[i].1 = e - 2;
            }
            let replacement = match &self.atoms[a].kind {
                AtomKind::Sin(cos) => Poly::constant(Rat::one()).add(&Poly::atom(*cos).mul_mono(&[(*cos, 1)]).neg()),
                AtomKind::Sqrt(e) => e.clone(),
                AtomKind::Pi | AtomKind::Cos => unreachable!("only sin and sqrt are reduced"),
            };
            for (rm, rc) in replacement.0 {
                work.push((mono_mul(&rest, &rm), &c * &rc));
            }
            if work.len() > MAX_TERMS {
                // Give up reducing: the rest stays as it is (still a correct polynomial).
                for (m, c) in work.drain(..) {
                    out = out.add(&Poly(BTreeMap::from([(m, c)])));
                }
            }
        }
        out
    }

    fn mul(&self, a: &Val, b: &Val) -> Result<Val, String> {
        match (a, b) {
            (Val::P(x), Val::P(y)) if x.0.len() * y.0.len() <= MAX_TERMS => {
                let mut out = Poly::constant(Rat::zero());
                for (mx, cx) in &x.0 {
                    for (my, cy) in &y.0 {
                        out = out.add(&Poly(BTreeMap::from([(mono_mul(mx, my), cx * cy)])));
                    }
                }
                Ok(Val::P(self.reduce(out)))
            }
            _ => Ok(Val::N(self.interval(a)?.mul(&self.interval(b)?))),
        }
    }

    fn add(&self, a: &Val, b: &Val) -> Result<Val, String> {
        match (a, b) {
            (Val::P(x), Val::P(y)) => Ok(Val::P(x.add(y))),
            _ => Ok(Val::N(self.interval(a)?.add(&self.interval(b)?))),
        }
    }

    fn neg(&self, a: &Val) -> Result<Val, String> {
        match a {
            Val::P(x) => Ok(Val::P(x.neg())),
            _ => Ok(Val::N(self.interval(a)?.neg())),
        }
    }

    /// `a <= b`, `a < b` (`strict`).
    fn compare(&self, a: &Val, b: &Val, strict: bool) -> Result<Tri, String> {
        let d = self.add(b, &self.neg(a)?)?;
        if let Val::P(p) = &d {
            if let Some(c) = p.as_constant() {
                return Ok(Tri::of(if strict { c.is_positive() } else { !c.is_negative() }));
            }
        }
        let d = self.interval(&d)?;
        Ok(if strict {
            if d.lo.is_positive() {
                Tri::True
            } else if !d.hi.is_positive() {
                Tri::False
            } else {
                Tri::Unknown
            }
        } else if !d.lo.is_negative() {
            Tri::True
        } else if d.hi.is_negative() {
            Tri::False
        } else {
            Tri::Unknown
        })
    }

    fn equal(&self, a: &Val, b: &Val) -> Result<Tri, String> {
        match (a, b) {
            (Val::B(x), Val::B(y)) => {
                Ok(if *x == Tri::Unknown || *y == Tri::Unknown { Tri::Unknown } else { Tri::of(x == y) })
            }
            (Val::B(_), _) | (_, Val::B(_)) => Err("`=` between a truth value and a number".into()),
            _ => Ok(self.compare(a, b, false)?.and(self.compare(b, a, false)?)),
        }
    }

    fn compute(&mut self, t: &Dynamic) -> Result<Val, String> {
        match key::view(t) {
            Node::Numeral(s) => Ok(Val::P(Poly::constant(numeral(&s).ok_or_else(|| format!("the numeral `{s}`"))?))),
            Node::Const => self.constant(t),
            Node::Other(s) => Err(format!("the term `{s}`")),
            Node::App(op, args) => self.app(&op, &args),
        }
    }

    fn new_atom(&mut self, t: &Dynamic, kind: AtomKind, value: Num) -> Val {
        let i = self.atoms.len();
        self.atoms.push(Atom { kind, value });
        self.atom_of.insert(key::id(t), i);
        Val::P(Poly::atom(i))
    }

    fn constant(&mut self, t: &Dynamic) -> Result<Val, String> {
        if let Some(&a) = self.atom_of.get(&key::id(t)) {
            return Ok(Val::P(Poly::atom(a)));
        }
        match self.defs.get(&key::id(t)) {
            Some(Def::Pi) => Ok(self.new_atom(t, AtomKind::Pi, exact::pi_tight())),
            Some(Def::Trig(f, arg, [sin, cos])) => {
                let v = self.val(arg)?;
                let a = self.interval(&v)?;
                // Both halves of the pair at once, so that `sin` knows its `cos`.
                let c = self.atoms.len();
                self.atoms.push(Atom { kind: AtomKind::Cos, value: exact::trig(Builtin::Cos, &a) });
                self.atom_of.insert(key::id(cos), c);
                self.atoms.push(Atom { kind: AtomKind::Sin(c), value: exact::trig(Builtin::Sin, &a) });
                self.atom_of.insert(key::id(sin), c + 1);
                Ok(Val::P(Poly::atom(if *f == Builtin::Sin { c + 1 } else { c })))
            }
            Some(Def::Defined(e)) => self.val(e),
            Some(Def::Sqrt(e)) => {
                let v = self.val(e)?;
                let a = self.interval(&v)?;
                if !a.lo.is_negative() {
                    if let Val::P(p) = &v {
                        if let Some(c) = p.as_constant() {
                            // A perfect square stays exact.
                            let r = exact::sqrt_tight(&Num::exact(c))?;
                            if let Some(r) = r.value() {
                                return Ok(Val::P(Poly::constant(r.clone())));
                            }
                        }
                        let value = exact::sqrt_tight(&a)?;
                        return Ok(self.new_atom(t, AtomKind::Sqrt(p.clone()), value));
                    }
                    Ok(Val::N(exact::sqrt_tight(&a)?))
                } else if a.hi.is_negative() {
                    self.model_value(t)
                } else {
                    Err("a square root of a number that may be negative or not".into())
                }
            }
            None => self.model_value(t),
        }
    }

    /// A variable's value in the model, exactly (an algebraic number as an enclosure).
    fn model_value(&mut self, t: &Dynamic) -> Result<Val, String> {
        let v = self.model.eval(t, true).ok_or("a variable the model does not value")?;
        if let Some(b) = v.as_bool() {
            return Ok(Val::B(match b.as_bool() {
                Some(x) => Tri::of(x),
                None => Tri::Unknown,
            }));
        }
        if let Some(i) = v.as_int() {
            let r = BigInt::from_str(&i.to_string()).map_err(|_| format!("the integer `{i}`"))?;
            return Ok(Val::P(Poly::constant(Rat::from_integer(r))));
        }
        if let Some(r) = v.as_real() {
            let n = super::goals::witness::num_of(&r).ok_or_else(|| format!("the model's value `{r}`"))?;
            return Ok(match n.value() {
                Some(x) => Val::P(Poly::constant(x.clone())),
                None => Val::N(n),
            });
        }
        Err(format!("a variable of sort {}", v.get_sort()))
    }

    fn app(&mut self, op: &str, args: &[Dynamic]) -> Result<Val, String> {
        Ok(match (op, args.len()) {
            ("true", 0) => Val::B(Tri::True),
            ("false", 0) => Val::B(Tri::False),
            ("not", 1) => Val::B(self.tri(&args[0])?.not()),
            ("and", _) => {
                let mut acc = Tri::True;
                for a in args {
                    acc = acc.and(self.tri(a)?);
                    if acc == Tri::False {
                        break;
                    }
                }
                Val::B(acc)
            }
            ("or", _) => {
                let mut acc = Tri::False;
                for a in args {
                    acc = acc.or(self.tri(a)?);
                    if acc == Tri::True {
                        break;
                    }
                }
                Val::B(acc)
            }
            ("=>", 2) => Val::B(self.tri(&args[0])?.not().or(self.tri(&args[1])?)),
            ("xor", 2) => {
                let (a, b) = (self.tri(&args[0])?, self.tri(&args[1])?);
                Val::B(a.and(b.not()).or(a.not().and(b)))
            }
            ("if" | "ite", 3) => match self.tri(&args[0])? {
                Tri::True => self.val(&args[1])?,
                Tri::False => self.val(&args[2])?,
                Tri::Unknown => match (self.val(&args[1])?, self.val(&args[2])?) {
                    (Val::B(a), Val::B(b)) => Val::B(if a == b { a } else { Tri::Unknown }),
                    (Val::P(a), Val::P(b)) if a == b => Val::P(a),
                    (a, b) => Val::N(self.interval(&a)?.hull(&self.interval(&b)?)),
                },
            },
            ("=", 2) | ("distinct", 2) => {
                // A term equals itself, whatever its value.
                let eq = if key::id(&args[0]) == key::id(&args[1]) {
                    Tri::True
                } else {
                    let (a, b) = (self.val(&args[0])?, self.val(&args[1])?);
                    self.equal(&a, &b)?
                };
                Val::B(if op == "=" { eq } else { eq.not() })
            }
            ("<=" | ">=" | "<" | ">", 2) => {
                let (a, b) = (self.val(&args[0])?, self.val(&args[1])?);
                Val::B(match op {
                    "<=" => self.compare(&a, &b, false)?,
                    ">=" => self.compare(&b, &a, false)?,
                    "<" => self.compare(&a, &b, true)?,
                    _ => self.compare(&b, &a, true)?,
                })
            }
            ("+", _) => {
                let mut acc = Val::P(Poly::constant(Rat::zero()));
                for a in args {
                    let v = self.val(a)?;
                    acc = self.add(&acc, &v)?;
                }
                acc
            }
            ("*", _) => {
                let mut acc = Val::P(Poly::constant(Rat::one()));
                for a in args {
                    let v = self.val(a)?;
                    acc = self.mul(&acc, &v)?;
                }
                acc
            }
            ("-", 1) => {
                let v = self.val(&args[0])?;
                self.neg(&v)?
            }
            ("-", k) if k >= 2 => {
                let mut acc = self.val(&args[0])?;
                for a in &args[1..] {
                    let v = self.val(a)?;
                    acc = self.add(&acc, &self.neg(&v)?)?;
                }
                acc
            }
            ("/", 2) => {
                let (a, b) = (self.val(&args[0])?, self.val(&args[1])?);
                match (&a, &b) {
                    (Val::P(p), Val::P(d)) if d.as_constant().is_some_and(|c| !c.is_zero()) => {
                        Val::P(p.scale(&d.as_constant().unwrap_or_else(Rat::one).recip()))
                    }
                    _ => {
                        let (a, b) = (self.interval(&a)?, self.interval(&b)?);
                        if b.contains_zero() {
                            return Err("a division by a number that may be 0".into());
                        }
                        Val::N(a.mul(&Num::range(b.hi.recip(), b.lo.recip())))
                    }
                }
            }
            ("to_real", 1) => self.val(&args[0])?,
            ("div" | "mod", 2) => {
                let (a, b) = (self.val(&args[0])?, self.val(&args[1])?);
                let (Val::P(a), Val::P(b)) = (a, b) else { return Err(format!("`{op}` of numbers not known exactly")) };
                let (Some(a), Some(b)) = (a.as_constant(), b.as_constant()) else {
                    return Err(format!("`{op}` of numbers not known exactly"));
                };
                if b.is_zero() || !a.is_integer() || !b.is_integer() {
                    return Err(format!("`{op}` by 0 or of a non-integer"));
                }
                // SMT-LIB's integer division: a = b q + r with 0 <= r < |b|.
                let (a, b) = (a.to_integer(), b.to_integer());
                let mut r = &a % &b;
                if r.is_negative() {
                    r += b.abs();
                }
                let q = (&a - &r) / &b;
                Val::P(Poly::constant(Rat::from_integer(if op == "div" { q } else { r })))
            }
            ("^", 2) => {
                let base = self.val(&args[0])?;
                let e = match self.val(&args[1])? {
                    Val::P(p) => p.as_constant(),
                    _ => None,
                };
                let e = e
                    .filter(|e| e.is_integer() && !e.is_negative() && *e <= Rat::from_integer(BigInt::from(64)))
                    .ok_or("a power whose exponent is not a natural number up to 64")?;
                let mut acc = Val::P(Poly::constant(Rat::one()));
                let mut k = Rat::zero();
                while k < e {
                    acc = self.mul(&acc, &base)?;
                    k += Rat::one();
                }
                acc
            }
            _ => return Err(format!("the operator `{op}`")),
        })
    }
}

impl Poly {
    /// `self` times one monomial.
    fn mul_mono(&self, m: &[(usize, u32)]) -> Poly {
        Poly(self.0.iter().map(|(k, c)| (mono_mul(k, m), c.clone())).collect())
    }
}

/// The product of two monomials.
fn mono_mul(a: &[(usize, u32)], b: &[(usize, u32)]) -> Mono {
    let mut out: BTreeMap<usize, u32> = a.iter().copied().collect();
    for &(x, e) in b {
        *out.entry(x).or_insert(0) += e;
    }
    out.into_iter().collect()
}

/// A numeral as Z3 writes it: `3`, `-7`, `7/2`, `-7/2`.
fn numeral(s: &str) -> Option<Rat> {
    let s = s.trim();
    match s.split_once('/') {
        Some((n, d)) => {
            let (n, d) = (BigInt::from_str(n.trim()).ok()?, BigInt::from_str(d.trim()).ok()?);
            (!d.is_zero()).then(|| Rat::new(n, d))
        }
        None => Some(Rat::from_integer(BigInt::from_str(s).ok()?)),
    }
}
