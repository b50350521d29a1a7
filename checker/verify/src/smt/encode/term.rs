//! The translation of expressions into Z3 terms: operators, builtins (`sqrt`, `sin`/`cos`
//! with their enclosures, `pi`), and variables under a frame.

use super::*;

impl<'p> Encoder<'p> {
    pub(super) fn term(&mut self, e: &Expr) -> Result<Term, Unsupported> {
        crate::stack::deep(|| self.term_inner(e))
    }

    pub(super) fn term_inner(&mut self, e: &Expr) -> Result<Term, Unsupported> {
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

    pub(super) fn binary(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Result<Term, Unsupported> {
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

    pub(super) fn call(&mut self, f: Builtin, args: &[Expr]) -> Result<Term, Unsupported> {
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
    pub(super) fn pi(&mut self) -> Real {
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
    pub(super) fn constant_args(&self, e: &Expr) -> Option<Expr> {
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
    pub(super) fn trig_pair(&mut self, e: &Expr, constant: Option<&Expr>) -> Result<(Real, Real), Unsupported> {
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
    pub(super) fn var(&mut self, v: &Var, sort: &Sort) -> Result<Term, Unsupported> {
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
pub(super) fn mentions_free(e: &Expr) -> bool {
    let mut free = false;
    e.visit_vars(&mut |v, _| free |= !matches!(v, Var::Const(_)));
    free
}

pub(super) fn dot(u: &[Real; 3], v: &[Real; 3]) -> Real {
    Real::add(&[
        Real::mul(&[u[0].clone(), v[0].clone()]),
        Real::mul(&[u[1].clone(), v[1].clone()]),
        Real::mul(&[u[2].clone(), v[2].clone()]),
    ])
}

pub(super) fn op_text(op: BinOp) -> &'static str {
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

/// An integer term against a real numeral of integral value (`2^64 - 1`, a `uint64_t`
/// field's wire bound, is beyond `i64` and so written as a real): the numeral as an
/// integer, so that the comparison or sum stays in integer arithmetic. Exact (the numeral
/// is that integer); a `to_real` of an integer variable next to a 20-digit real makes Z3's
/// quantified integer queries (progress over a `uint64_t` field) time out, where the
/// integer form is decided at once.
pub(super) fn integral_pair(pair: (Term, Term)) -> (Term, Term) {
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
