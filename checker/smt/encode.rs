//! Encoding of HIR expressions into Z3 terms. Integers and reals mix by promotion;
//! `sqrt(e)` becomes a fresh variable `s` with the side condition
//! `e >= 0 => (s >= 0 && s * s == e)`, which every model of the query satisfies, so the
//! encoding proves nothing about a square root that is false of the real one.
//! Constructs not encoded yet (trigonometry, points and vectors, tuples, contract-only
//! variables) are refused with [`Unsupported`], which the caller reports as unknown.

use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, Var};
use std::collections::BTreeMap;
use z3::ast::{Bool, Int, Real};

/// A construct the encoding does not handle; the message names it.
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported(pub String);

#[derive(Clone)]
enum Term {
    B(Bool),
    I(Int),
    R(Real),
}

pub struct Encoder<'p> {
    prog: &'p Program,
    /// Free variables by their user-facing name, for the counterexample.
    vars: BTreeMap<String, Term>,
    side: Vec<Bool>,
}

impl<'p> Encoder<'p> {
    pub fn new(prog: &'p Program) -> Encoder<'p> {
        Encoder { prog, vars: BTreeMap::new(), side: Vec::new() }
    }

    /// Constraints introduced by the encoding (square roots), to assert with the query.
    pub fn side_conditions(&self) -> impl Iterator<Item = &Bool> {
        self.side.iter()
    }

    pub fn boolean(&mut self, e: &Expr) -> Result<Bool, Unsupported> {
        match self.term(e)? {
            Term::B(b) => Ok(b),
            _ => Err(Unsupported("a non-boolean predicate".into())),
        }
    }

    /// The values of the query's variables in `model`, by name.
    pub fn assignments(&self, model: &z3::Model) -> Vec<super::Assignment> {
        self.vars
            .iter()
            .filter_map(|(name, t)| {
                let value = match t {
                    Term::B(b) => model.eval(b, true).map(|v| v.to_string()),
                    Term::I(i) => model.eval(i, true).map(|v| v.to_string()),
                    Term::R(r) => model.eval(r, true).map(|v| decimal(&v)),
                }?;
                Some(super::Assignment { name: name.clone(), value })
            })
            .collect()
    }

    fn term(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.term_inner(e))
    }

    fn term_inner(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        Ok(match &e.kind {
            ExprKind::Bool(b) => Term::B(Bool::from_bool(*b)),
            ExprKind::Int(i) => Term::I(Int::from_i64(*i)),
            ExprKind::Real(r) => Term::R(rational(r).ok_or_else(|| Unsupported(format!("the number `{r}`")))?),
            ExprKind::Var(v) => self.var(v, &e.sort)?,
            ExprKind::Unary(UnOp::Not, a) => Term::B(self.boolean(a)?.not()),
            ExprKind::Unary(UnOp::Neg, a) => match self.term(a)? {
                Term::I(i) => Term::I(i.unary_minus()),
                Term::R(r) => Term::R(r.unary_minus()),
                Term::B(_) => return Err(Unsupported("negation of a boolean".into())),
            },
            ExprKind::Binary(op, a, b) => self.binary(*op, a, b)?,
            ExprKind::If(c, a, b) => {
                let c = self.boolean(c)?;
                match (self.term(a)?, self.term(b)?) {
                    (Term::B(x), Term::B(y)) => Term::B(c.ite(&x, &y)),
                    (Term::I(x), Term::I(y)) => Term::I(c.ite(&x, &y)),
                    (x, y) => Term::R(c.ite(&as_real(x)?, &as_real(y)?)),
                }
            }
            ExprKind::Call(f, args) => self.call(*f, args)?,
            ExprKind::Tuple(_) | ExprKind::Component(..) => {
                return Err(Unsupported("points, vectors and tuples".into()));
            }
        })
    }

    fn binary(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Result<Term, Unsupported> {
        use BinOp::*;
        Ok(match op {
            And => Term::B(Bool::and(&[self.boolean(a)?, self.boolean(b)?])),
            Or => Term::B(Bool::or(&[self.boolean(a)?, self.boolean(b)?])),
            Implies => Term::B(self.boolean(a)?.implies(self.boolean(b)?)),
            Pow => {
                let ExprKind::Int(n) = b.kind else {
                    return Err(Unsupported("a power whose exponent is not an integer literal".into()));
                };
                let base = self.term(a)?;
                match base {
                    Term::I(i) => Term::I(if n == 0 { Int::from_i64(1) } else { Int::mul(&vec![i; n as usize]) }),
                    other => {
                        let r = as_real(other)?;
                        Term::R(if n == 0 {
                            rational("1").ok_or_else(|| Unsupported("1".into()))?
                        } else {
                            Real::mul(&vec![r; n as usize])
                        })
                    }
                }
            }
            Eq | Ne => {
                let eq = match (self.term(a)?, self.term(b)?) {
                    (Term::B(x), Term::B(y)) => x.eq(&y),
                    (Term::I(x), Term::I(y)) => x.eq(&y),
                    (x, y) => as_real(x)?.eq(&as_real(y)?),
                };
                Term::B(if op == Eq { eq } else { eq.not() })
            }
            Lt | Le | Gt | Ge | Add | Sub | Mul | Div => {
                let (x, y) = (self.term(a)?, self.term(b)?);
                if let (Term::I(x), Term::I(y), false) = (&x, &y, op == Div) {
                    return Ok(match op {
                        Lt => Term::B(x.lt(y)),
                        Le => Term::B(x.le(y)),
                        Gt => Term::B(x.gt(y)),
                        Ge => Term::B(x.ge(y)),
                        Add => Term::I(Int::add(&[x.clone(), y.clone()])),
                        Sub => Term::I(Int::sub(&[x.clone(), y.clone()])),
                        _ => Term::I(Int::mul(&[x.clone(), y.clone()])),
                    });
                }
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
        })
    }

    fn call(&mut self, f: Builtin, args: &[Expr]) -> Result<Term, Unsupported> {
        let num = |enc: &mut Self, i: usize| -> Result<Term, Unsupported> {
            args.get(i)
                .ok_or_else(|| Unsupported(format!("`{}` without arguments", f.name())))
                .and_then(|a| enc.term(a))
        };
        Ok(match f {
            Builtin::Sqrt => {
                let a = as_real(num(self, 0)?)?;
                let s = Real::fresh_const("sqrt");
                let zero = Int::from_i64(0).to_real();
                let def = Bool::and(&[s.ge(&zero), Real::mul(&[s.clone(), s.clone()]).eq(&a)]);
                self.side.push(a.ge(&zero).implies(&def));
                Term::R(s)
            }
            Builtin::Abs => match num(self, 0)? {
                Term::I(i) => Term::I(i.ge(Int::from_i64(0)).ite(&i, &i.unary_minus())),
                other => {
                    let r = as_real(other)?;
                    Term::R(r.ge(Int::from_i64(0).to_real()).ite(&r, &r.unary_minus()))
                }
            },
            Builtin::Min | Builtin::Max => {
                let (a, b) = (num(self, 0)?, num(self, 1)?);
                let pick_a = |x: &Real, y: &Real| if f == Builtin::Min { x.le(y) } else { x.ge(y) };
                match (a, b) {
                    (Term::I(x), Term::I(y)) => {
                        let c = if f == Builtin::Min { x.le(&y) } else { x.ge(&y) };
                        Term::I(c.ite(&x, &y))
                    }
                    (a, b) => {
                        let (x, y) = (as_real(a)?, as_real(b)?);
                        Term::R(pick_a(&x, &y).ite(&x, &y))
                    }
                }
            }
            Builtin::Sin | Builtin::Cos => return Err(Unsupported("trigonometry (sin, cos)".into())),
            Builtin::Point | Builtin::Vector | Builtin::Dot | Builtin::Norm2 => {
                return Err(Unsupported("points and vectors".into()));
            }
        })
    }

    /// `sort` is the occurrence's sort, used when the variable was declared without one
    /// (a process binder takes its sort from the payload field it receives).
    fn var(&mut self, v: &Var, sort: &crate::hir::Sort) -> Result<Term, Unsupported> {
        let (name, sort) = match v {
            Var::Const(c) => {
                // Constants are closed terms: encode their definition.
                let value = self.prog.consts[c.idx()].value.clone();
                return self.term(&value);
            }
            Var::Role(r, slot) => {
                let (n, s) = self.prog.kind_of(*r).var(*slot);
                (format!("{}.{n}", self.prog.role_name(*r)), s.clone())
            }
            Var::Snap(r, slot) => {
                let (n, s) = self.prog.kind_of(*r).var(*slot);
                (format!("old({}.{n})", self.prog.role_name(*r)), s.clone())
            }
            Var::Value(id, name) => {
                let declared = self.prog.value(*id).sort.clone();
                (format!("{name}#{}", id.0), if declared == crate::hir::Sort::Any { sort.clone() } else { declared })
            }
            Var::Own(_) | Var::Old(_) | Var::Param(_) | Var::Point(_) | Var::Clock => {
                return Err(Unsupported("a motion primitive's variables outside its contract".into()));
            }
        };
        if let Some(t) = self.vars.get(&name) {
            return Ok(t.clone());
        }
        let t = match sort {
            crate::hir::Sort::Bool => Term::B(Bool::new_const(name.as_str())),
            crate::hir::Sort::Int => Term::I(Int::new_const(name.as_str())),
            crate::hir::Sort::Real => Term::R(Real::new_const(name.as_str())),
            other => return Err(Unsupported(format!("variables of sort `{other}`"))),
        };
        // Value variables are shown under their source name.
        let shown = name.split('#').next().unwrap_or(&name).to_string();
        self.vars.insert(shown, t.clone());
        Ok(t)
    }
}

fn as_real(t: Term) -> Result<Real, Unsupported> {
    match t {
        Term::R(r) => Ok(r),
        Term::I(i) => Ok(i.to_real()),
        Term::B(_) => Err(Unsupported("a boolean used as a number".into())),
    }
}

/// A decimal literal (`0.65`, `1e-3`, `12`) as an exact Z3 rational.
fn rational(lit: &str) -> Option<Real> {
    let (mant, exp) = match lit.split_once(['e', 'E']) {
        Some((m, e)) => (m, e.parse::<i32>().ok()?),
        None => (lit, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let mut num = format!("{int}{frac}").trim_start_matches('0').to_string();
    if num.is_empty() {
        num = "0".into();
    }
    let scale = exp - frac.len() as i32;
    let (num, den) = if scale >= 0 {
        (format!("{num}{}", "0".repeat(scale as usize)), "1".to_string())
    } else {
        (num, format!("1{}", "0".repeat((-scale) as usize)))
    };
    Real::from_rational_str(&num, &den)
}

/// Z3 prints rationals as `(/ 13.0 20.0)`; users read `0.65`.
fn decimal(r: &Real) -> String {
    match r.as_rational() {
        Some((n, d)) if d != 0 => {
            let v = n as f64 / d as f64;
            if d == 1 {
                n.to_string()
            } else {
                format!("{v} (= {n}/{d})")
            }
        }
        _ => r.to_string(),
    }
}
