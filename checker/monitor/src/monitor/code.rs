//! Guards, refinements, recursion arguments and enum memberships compiled to a compact
//! form: a tree of [`Node`]s in one arena per protocol, evaluated over a session's
//! registers without allocating.
//!
//! Semantics, the same as the static checks' (`hir::expr::definedness`, `exact::eval`):
//! numbers are exact rationals ([`Q`]; a `float` value is the binary rational it is, a
//! decimal constant the rational it writes: `0.1` is 1/10); `/` is rational division;
//! `&&`, `||`, `=>` and `if` evaluate left to right and skip only what their left side
//! decides (the definedness the static checks ask is that of the evaluated part); a
//! division by zero or a negative power of zero is *undefined*, a violation; strings are
//! compared by their bytes up to the first NUL; `has_flag(x, F)` tests the bits of `F` in
//! `x`'s two's complement. An intermediate that leaves 128 bits, and the operators the
//! fixed-width form does not have (`sqrt`, `sin`, `cos`, `pi`, points and vectors), are
//! evaluated by `exact::eval` over unbounded rationals instead (the *fallback*, counted):
//! its enclosures decide every comparison that is not exactly on a boundary an irrational
//! value could sit on; an undecided one is reported as such, never passed.

use super::num::Q;
use crate::exact::{self, Rat, Tri};
use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, Sort, ValueId, Var};
use num_bigint::BigInt;
use num_traits::ToPrimitive;
use std::collections::HashMap;

/// A value in a register or on the evaluation's way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Val {
    /// A register not yet written (never read by a verified protocol: the static checks
    /// scope every name).
    Unset,
    Bool(bool),
    Num(Q),
    /// A float whose exact value does not fit [`Q`]: evaluated by the fallback.
    Wide(f64),
    /// A string literal of the program (its code, an index of `Program::strings`).
    Lit(u32),
    /// The string held by register `reg` (its bytes in the session's string area).
    Str(u16),
}

/// A node of the arena.
#[derive(Clone, Debug)]
pub enum Node {
    Const(Val),
    Reg(u16),
    Not(u32),
    Neg(u32),
    Bin(BinOp, u32, u32),
    If(u32, u32, u32),
    Min(u32, u32),
    Max(u32, u32),
    Abs(u32),
    HasFlag(u32, i64),
    /// `float32(x)` / `float64(x)` of a register decoded from a field of that format: true
    /// (a decoded value is finite, [`super::Monitor`] rejects NaN and infinities first).
    True,
    /// An operator the fixed-width form does not have: the whole predicate goes to the
    /// fallback.
    Slow,
    /// `reg OP c` for a comparison `OP` and a numeric constant `c` (either operand order in
    /// the source; the compiler puts the register first and mirrors the operator): one
    /// comparison of two [`Q`]s, an integer comparison when both are integers.
    CmpConst(BinOp, u16, Q),
    /// `a OP b` for a comparison `OP` of two registers (`s == i`, `i < count`).
    CmpRegs(BinOp, u16, u16),
    /// `reg` lies in one of these closed intervals with integer ends (sorted by their lower
    /// ends, pairwise disjoint as sets of reals): a disjunction of `reg == c` and `lo <= reg
    /// && reg <= hi` (an enum's entries, a choice of values) found by one binary search
    /// instead of one comparison per disjunct. Exact for any rational `reg`: an integer `lo`
    /// is `<= x` iff it is `<= floor(x)`, and `x <= hi` iff `ceil(x) <= hi`.
    InRuns(u16, Box<[(i128, i128)]>),
}

/// Why an evaluation stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// A partial operator applied outside its domain: a violation.
    Undefined(&'static str),
    /// Leave the fixed-width form: evaluate over big rationals.
    Fallback,
}

/// What a register holds and where it comes from.
#[derive(Clone, Debug)]
pub struct RegInfo {
    pub value: ValueId,
    pub name: String,
    pub sort: Sort,
    /// Offset and capacity of its bytes in the string area, for a `str` register.
    pub str_at: u32,
    pub str_cap: u16,
    /// The participants that know it (a bit per role).
    pub knowers: u64,
}

/// A compiled expression.
#[derive(Clone, Debug)]
pub struct Code {
    pub root: u32,
    /// Its index among the protocol's compiled predicates (for coverage).
    pub id: u32,
    /// Whether some node is [`Node::Slow`].
    pub slow: bool,
    /// The expression, for the fallback and for reports.
    pub expr: Expr,
}

/// The arena and the register map of one protocol.
#[derive(Clone, Debug, Default)]
pub struct Arena {
    pub nodes: Vec<Node>,
    pub regs: Vec<RegInfo>,
    pub reg_of: HashMap<ValueId, u16>,
    /// Registers decoded from a `float` (`Builtin::Float32`) or `double` field.
    pub float_regs: HashMap<u16, Builtin>,
    pub str_size: u32,
    /// Compile comparisons with constants and disjunctions of them to [`Node::CmpConst`] and
    /// [`Node::InRuns`] (the default); without it every operator stays a node of the tree
    /// (the evaluator as it was first written: the benchmark and the differential test run
    /// both).
    pub tree_only: bool,
}

impl Arena {
    fn push(&mut self, n: Node) -> u32 {
        self.nodes.push(n);
        (self.nodes.len() - 1) as u32
    }

    /// Compiles `e`; `Err` names what cannot be compiled (a variable that is not a register).
    pub fn compile(&mut self, prog: &Program, e: &Expr) -> Result<Code, String> {
        let mut slow = false;
        let root = self.node(prog, e, &mut slow, 0)?;
        Ok(Code { root, id: 0, slow, expr: e.clone() })
    }

    /// Calls `f` on every register node `n` reads.
    pub fn reads(&self, n: u32, f: &mut dyn FnMut(u16)) {
        match &self.nodes[n as usize] {
            Node::Reg(r) => f(*r),
            Node::Const(_) | Node::True | Node::Slow => {}
            Node::CmpConst(_, r, _) | Node::InRuns(r, _) => f(*r),
            Node::CmpRegs(_, a, b) => {
                f(*a);
                f(*b);
            }
            Node::Not(a) | Node::Neg(a) | Node::Abs(a) | Node::HasFlag(a, _) => self.reads(*a, f),
            Node::Bin(_, a, b) | Node::Min(a, b) | Node::Max(a, b) => {
                self.reads(*a, f);
                self.reads(*b, f);
            }
            Node::If(a, b, c) => {
                self.reads(*a, f);
                self.reads(*b, f);
                self.reads(*c, f);
            }
        }
    }

    fn node(&mut self, prog: &Program, e: &Expr, slow: &mut bool, depth: usize) -> Result<u32, String> {
        // The evaluator recurses over the tree on the hot path: a bound on the depth keeps
        // its stack small (protocols nest a few levels).
        if depth > MAX_DEPTH {
            return Err(format!("an expression nested more than {MAX_DEPTH} levels deep"));
        }
        let mut go = |this: &mut Arena, x: &Expr| this.node(prog, x, slow, depth + 1);
        let n = match &e.kind {
            ExprKind::Bool(b) => Node::Const(Val::Bool(*b)),
            ExprKind::Int(i) if e.sort == Sort::Str => Node::Const(Val::Lit(*i as u32)),
            ExprKind::Int(i) => Node::Const(Val::Num(Q::int(i128::from(*i)))),
            ExprKind::Real(_) | ExprKind::Var(Var::Const(_)) => match exact::eval(prog, e, &|_: &Var| None) {
                Ok(exact::Value::Num(n)) if n.is_exact() => match rat_to_q(&n.lo) {
                    Some(q) => Node::Const(Val::Num(q)),
                    None => {
                        *slow = true;
                        Node::Slow
                    }
                },
                Ok(exact::Value::Bool(Tri::True)) => Node::Const(Val::Bool(true)),
                Ok(exact::Value::Bool(Tri::False)) => Node::Const(Val::Bool(false)),
                _ if e.sort == Sort::Str => match &e.kind {
                    ExprKind::Var(Var::Const(c)) => {
                        let def = prog.consts.get(c.idx()).ok_or("an unknown constant")?.value.clone();
                        return go(self, &def);
                    }
                    _ => return Err("a string constant".into()),
                },
                _ => {
                    *slow = true;
                    Node::Slow
                }
            },
            ExprKind::Var(Var::Value(id, name)) => match self.reg_of.get(id) {
                Some(r) => Node::Reg(*r),
                None => return Err(format!("`{name}` is not a value of the protocol")),
            },
            ExprKind::Var(_) => {
                return Err("a participant's state variable (protocols without motion have none)".into())
            }
            ExprKind::Unary(UnOp::Not, a) => Node::Not(go(self, a)?),
            ExprKind::Unary(UnOp::Neg, a) => Node::Neg(go(self, a)?),
            ExprKind::Binary(op, a, b) => {
                let (x, y) = (go(self, a)?, go(self, b)?);
                if self.tree_only {
                    Node::Bin(*op, x, y)
                } else {
                    self.flat_bin(*op, x, y)
                }
            }
            ExprKind::If(c, a, b) => {
                let (x, y, z) = (go(self, c)?, go(self, a)?, go(self, b)?);
                Node::If(x, y, z)
            }
            ExprKind::Call(f, args) => match (f, args.as_slice()) {
                (Builtin::Min, [a, b]) => {
                    let (x, y) = (go(self, a)?, go(self, b)?);
                    Node::Min(x, y)
                }
                (Builtin::Max, [a, b]) => {
                    let (x, y) = (go(self, a)?, go(self, b)?);
                    Node::Max(x, y)
                }
                (Builtin::Abs, [a]) => Node::Abs(go(self, a)?),
                (Builtin::HasFlag, [a, flag]) => match crate::hir::expr::const_int(prog, flag) {
                    Some(f) if f > 0 => Node::HasFlag(go(self, a)?, f),
                    _ => return Err("`has_flag` with a flag that is not a positive constant".into()),
                },
                (Builtin::Float32 | Builtin::Float64, [a]) => match &a.kind {
                    ExprKind::Var(Var::Value(id, _))
                        if self.reg_of.get(id).and_then(|r| self.float_regs.get(r)) == Some(f) =>
                    {
                        Node::True
                    }
                    _ => {
                        *slow = true;
                        Node::Slow
                    }
                },
                _ => {
                    *slow = true;
                    Node::Slow
                }
            },
            ExprKind::Tuple(_) | ExprKind::Component(..) => {
                *slow = true;
                Node::Slow
            }
        };
        let folded = if self.tree_only { None } else { self.fold(prog, &n) };
        Ok(self.push(folded.unwrap_or(n)))
    }

    /// `n` as a constant when every operand is one and it evaluates in the fixed width
    /// (`2^64 - 1`, `MAX_SPEED * 2`): the value it has at every message. An operator that
    /// is undefined or leaves the fixed width on its constants stays one, so that the
    /// message reports it (or the fallback evaluates it) as before.
    fn fold(&mut self, prog: &Program, n: &Node) -> Option<Node> {
        let c = |k: &u32| matches!(self.nodes[*k as usize], Node::Const(_));
        let all = match n {
            Node::Not(a) | Node::Neg(a) | Node::Abs(a) | Node::HasFlag(a, _) => c(a),
            Node::Bin(_, a, b) | Node::Min(a, b) | Node::Max(a, b) => c(a) && c(b),
            Node::If(x, a, b) => c(x) && c(a) && c(b),
            _ => false,
        };
        if !all {
            return None;
        }
        let at = self.push(n.clone());
        let v = Env { regs: &[], strs: &[], arena: self, prog }.eval(at);
        self.nodes.pop();
        match v {
            Ok(v @ (Val::Bool(_) | Val::Num(_))) => Some(Node::Const(v)),
            _ => None,
        }
    }
}

impl Arena {
    /// `x OP y` in the cheapest exact form: [`Node::CmpConst`] for a register compared with
    /// a numeric constant, [`Node::InRuns`] for a disjunction of such comparisons of one
    /// register with integers, else [`Node::Bin`]. The forms agree with the tree: a register
    /// that holds no [`Q`] (a float too wide for one, or not a number) stops the evaluation
    /// for the fallback, as the tree's first comparison of it would; with a [`Q`], every
    /// disjunct is defined, so their order does not matter.
    fn flat_bin(&self, op: BinOp, x: u32, y: u32) -> Node {
        use BinOp::*;
        let (nx, ny) = (&self.nodes[x as usize], &self.nodes[y as usize]);
        match (op, nx, ny) {
            (Eq | Ne | Lt | Le | Gt | Ge, Node::Reg(r), Node::Const(Val::Num(c))) => Node::CmpConst(op, *r, *c),
            (Eq | Ne | Lt | Le | Gt | Ge, Node::Reg(a), Node::Reg(b)) => Node::CmpRegs(op, *a, *b),
            (Eq | Ne | Lt | Le | Gt | Ge, Node::Const(Val::Num(c)), Node::Reg(r)) => {
                let mirrored = match op {
                    Lt => Gt,
                    Le => Ge,
                    Gt => Lt,
                    Ge => Le,
                    o => o,
                };
                Node::CmpConst(mirrored, *r, *c)
            }
            (And, _, _) => match self.range(x, y) {
                Some((r, run)) => Node::InRuns(r, Box::new([run])),
                None => Node::Bin(op, x, y),
            },
            (Or, _, _) => match (self.runs(x), self.runs(y)) {
                (Some((r, mut a)), Some((s, b))) if r == s => {
                    a.extend(b);
                    Node::InRuns(r, merge_runs(a).into_boxed_slice())
                }
                _ => Node::Bin(op, x, y),
            },
            _ => Node::Bin(op, x, y),
        }
    }

    /// The register and intervals node `n` tests, if it is `reg == c` with an integer `c`
    /// or runs (a range `lo <= reg && reg <= hi` is compiled to runs of its own).
    fn runs(&self, n: u32) -> Option<(u16, Vec<(i128, i128)>)> {
        let int = |c: &Q| c.is_integer().then_some(c.num);
        match &self.nodes[n as usize] {
            Node::CmpConst(BinOp::Eq, r, c) => Some((*r, vec![(int(c)?, int(c)?)])),
            Node::InRuns(r, runs) => Some((*r, runs.to_vec())),
            _ => None,
        }
    }

    /// The register and interval of `a && b` when it is `lo <= reg && reg <= hi` (in
    /// either order) with integer constants `lo <= hi`.
    fn range(&self, a: u32, b: u32) -> Option<(u16, (i128, i128))> {
        let bound = |k: u32| match &self.nodes[k as usize] {
            Node::CmpConst(BinOp::Ge, r, c) if c.is_integer() => Some((*r, true, c.num)),
            Node::CmpConst(BinOp::Le, r, c) if c.is_integer() => Some((*r, false, c.num)),
            _ => None,
        };
        match (bound(a)?, bound(b)?) {
            ((r, true, lo), (s, false, hi)) | ((s, false, hi), (r, true, lo)) if r == s && lo <= hi => {
                Some((r, (lo, hi)))
            }
            _ => None,
        }
    }
}

/// Intervals sorted by their lower ends, those that meet (as sets of reals) merged.
fn merge_runs(mut runs: Vec<(i128, i128)>) -> Vec<(i128, i128)> {
    runs.sort_unstable();
    let mut out: Vec<(i128, i128)> = Vec::with_capacity(runs.len());
    for (lo, hi) in runs {
        match out.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => out.push((lo, hi)),
        }
    }
    out
}

/// Whether `x` lies in one of `runs` (sorted, disjoint closed intervals with integer ends).
fn in_runs(runs: &[(i128, i128)], x: Q) -> bool {
    let (floor, ceil) = if x.is_integer() {
        (x.num, x.num)
    } else {
        let floor = x.floor();
        (floor, floor + 1)
    };
    let k = runs.partition_point(|&(lo, _)| lo <= floor);
    k > 0 && ceil <= runs[k - 1].1
}

/// The deepest expression the monitor compiles.
pub const MAX_DEPTH: usize = 256;

/// A big rational as a [`Q`], if it fits.
pub fn rat_to_q(r: &Rat) -> Option<Q> {
    Q::new(r.numer().to_i128()?, r.denom().to_i128()?)
}

/// A [`Q`] as a big rational.
pub fn q_to_rat(q: Q) -> Rat {
    Rat::new(BigInt::from(q.num), BigInt::from(q.den))
}

/// What an evaluation reads: the registers and the string area of a session.
pub struct Env<'a> {
    pub regs: &'a [Val],
    pub strs: &'a [u8],
    pub arena: &'a Arena,
    pub prog: &'a Program,
}

impl Env<'_> {
    fn bytes(&self, v: Val) -> Option<&[u8]> {
        match v {
            Val::Lit(c) => self.prog.strings.get(c as usize).map(|s| cut(s.as_bytes())),
            Val::Str(r) => {
                let info = self.arena.regs.get(r as usize)?;
                let s = self.strs.get(info.str_at as usize..info.str_at as usize + info.str_cap as usize)?;
                Some(cut(s))
            }
            _ => None,
        }
    }

    fn num(&self, v: Val) -> Result<Q, Stop> {
        match v {
            Val::Num(q) => Ok(q),
            Val::Wide(_) => Err(Stop::Fallback),
            _ => Err(Stop::Fallback),
        }
    }

    /// Evaluates node `n` in the fixed-width form.
    pub fn eval(&self, n: u32) -> Result<Val, Stop> {
        let of = |x: Option<Q>| x.map(Val::Num).ok_or(Stop::Fallback);
        Ok(match &self.arena.nodes[n as usize] {
            Node::Const(v) => *v,
            Node::Reg(r) => self.regs[*r as usize],
            Node::True => Val::Bool(true),
            Node::Slow => return Err(Stop::Fallback),
            Node::CmpConst(..) | Node::CmpRegs(..) | Node::InRuns(..) => Val::Bool(self.bool(n)?),
            Node::Not(a) => Val::Bool(!self.bool(*a)?),
            Node::Neg(a) => of(self.num(self.eval(*a)?)?.neg())?,
            Node::Abs(a) => of(self.num(self.eval(*a)?)?.abs())?,
            Node::Min(a, b) | Node::Max(a, b) => {
                let (x, y) = (self.num(self.eval(*a)?)?, self.num(self.eval(*b)?)?);
                let le = x.cmp(y).ok_or(Stop::Fallback)?.is_le();
                let min = matches!(self.arena.nodes[n as usize], Node::Min(..));
                Val::Num(if le == min { x } else { y })
            }
            Node::HasFlag(a, flag) => {
                let x = self.num(self.eval(*a)?)?;
                if !x.is_integer() {
                    return Err(Stop::Fallback);
                }
                Val::Bool((0..63).filter(|k| flag >> k & 1 == 1).all(|k| (x.num >> k) & 1 == 1))
            }
            Node::If(c, a, b) => {
                if self.bool(*c)? {
                    self.eval(*a)?
                } else {
                    self.eval(*b)?
                }
            }
            Node::Bin(op, a, b) => {
                use BinOp::*;
                match op {
                    And => Val::Bool(self.bool(*a)? && self.bool(*b)?),
                    Or => Val::Bool(self.bool(*a)? || self.bool(*b)?),
                    Implies => Val::Bool(!self.bool(*a)? || self.bool(*b)?),
                    _ => {
                        let (x, y) = (self.eval(*a)?, self.eval(*b)?);
                        match op {
                            Eq | Ne | Lt | Le | Gt | Ge => Val::Bool(self.compare(*op, x, y)?),
                            Add => of(self.num(x)?.add(self.num(y)?))?,
                            Sub => of(self.num(x)?.sub(self.num(y)?))?,
                            Mul => of(self.num(x)?.mul(self.num(y)?))?,
                            Div => {
                                let d = self.num(y)?;
                                if d.num == 0 {
                                    return Err(Stop::Undefined("a division by zero"));
                                }
                                of(self.num(x)?.div(d))?
                            }
                            Pow => {
                                let (base, k) = (self.num(x)?, self.num(y)?);
                                if !k.is_integer() || k.num.abs() > 64 {
                                    return Err(Stop::Fallback);
                                }
                                if k.num < 0 && base.num == 0 {
                                    return Err(Stop::Undefined("a negative power of zero"));
                                }
                                of(base.pow(k.num as i64))?
                            }
                            And | Or | Implies => return Err(Stop::Fallback),
                        }
                    }
                }
            }
        })
    }

    /// `x OP y` for a comparison `OP`: truth values and strings by equality only, numbers
    /// exactly.
    fn compare(&self, op: BinOp, x: Val, y: Val) -> Result<bool, Stop> {
        use BinOp::*;
        let o = match (op, x, y) {
            (_, Val::Num(p), Val::Num(q)) => {
                if p.den == 1 && q.den == 1 {
                    p.num.cmp(&q.num)
                } else {
                    p.cmp(q).ok_or(Stop::Fallback)?
                }
            }
            (Eq | Ne, Val::Bool(p), Val::Bool(q)) => return Ok((p == q) == (op == Eq)),
            (Eq | Ne, Val::Lit(_) | Val::Str(_), _) | (Eq | Ne, _, Val::Lit(_) | Val::Str(_)) => {
                return match (self.bytes(x), self.bytes(y)) {
                    (Some(p), Some(q)) => Ok((p == q) == (op == Eq)),
                    _ => Err(Stop::Fallback),
                }
            }
            _ => return Err(Stop::Fallback),
        };
        Ok(match op {
            Eq => o.is_eq(),
            Ne => o.is_ne(),
            Lt => o.is_lt(),
            Le => o.is_le(),
            Gt => o.is_gt(),
            _ => o.is_ge(),
        })
    }

    /// Evaluates a truth-valued node: the compiled comparisons and the connectives
    /// directly, without a [`Val`] on the way; anything else through [`Env::eval`].
    fn bool(&self, n: u32) -> Result<bool, Stop> {
        match &self.arena.nodes[n as usize] {
            Node::CmpConst(op, r, c) => match self.regs[*r as usize] {
                x @ Val::Num(_) => self.compare(*op, x, Val::Num(*c)),
                _ => Err(Stop::Fallback),
            },
            Node::CmpRegs(op, a, b) => self.compare(*op, self.regs[*a as usize], self.regs[*b as usize]),
            Node::InRuns(r, runs) => match self.regs[*r as usize] {
                Val::Num(x) => Ok(in_runs(runs, x)),
                _ => Err(Stop::Fallback),
            },
            Node::Bin(BinOp::And, a, b) => Ok(self.bool(*a)? && self.bool(*b)?),
            Node::Bin(BinOp::Or, a, b) => Ok(self.bool(*a)? || self.bool(*b)?),
            Node::Bin(BinOp::Implies, a, b) => Ok(!self.bool(*a)? || self.bool(*b)?),
            Node::Not(a) => Ok(!self.bool(*a)?),
            Node::True => Ok(true),
            _ => match self.eval(n)? {
                Val::Bool(b) => Ok(b),
                _ => Err(Stop::Fallback),
            },
        }
    }

    /// A register's value as `exact` sees it: strings as codes (a literal's code, or a
    /// code above every literal shared by the registers that hold the same bytes).
    fn exact_value(&self, r: u16) -> Option<exact::Value> {
        let v = self.regs.get(r as usize).copied()?;
        Some(match v {
            Val::Unset => return None,
            Val::Bool(b) => exact::Value::Bool(Tri::of(b)),
            Val::Num(q) => exact::Value::rat(q_to_rat(q)),
            Val::Wide(x) => exact::Value::rat(Rat::from_float(x)?),
            Val::Lit(c) => exact::Value::rat(Rat::from_integer(BigInt::from(c))),
            Val::Str(_) => {
                let bytes = self.bytes(v)?;
                let code = match self.prog.strings.iter().position(|s| cut(s.as_bytes()) == bytes) {
                    Some(c) => c,
                    None => {
                        let first = (0..self.regs.len())
                            .find(|&k| matches!(self.regs[k], Val::Str(_)) && self.bytes(self.regs[k]) == Some(bytes))
                            .unwrap_or(r as usize);
                        self.prog.strings.len() + first
                    }
                };
                exact::Value::rat(Rat::from_integer(BigInt::from(code)))
            }
        })
    }

    /// Evaluates `code` over unbounded rationals (`exact::eval`).
    pub fn fallback(&self, code: &Code) -> Result<exact::Value, String> {
        let env = |v: &Var| match v {
            Var::Value(id, _) => self.arena.reg_of.get(id).and_then(|r| self.exact_value(*r)),
            _ => None,
        };
        // `exact::eval` reads connectives left to right, as the fixed width and the static
        // checks' definedness do: an undefined operation it reaches is an error.
        exact::eval(self.prog, &code.expr, &env)
    }

    /// A predicate's truth: `Ok(true/false)`, or why it has none.
    pub fn holds(&self, code: &Code, fallbacks: &mut u64) -> Result<bool, Verdict> {
        if !code.slow {
            match self.bool(code.root) {
                Ok(b) => return Ok(b),
                Err(Stop::Undefined(why)) => return Err(Verdict::Undefined(why)),
                Err(Stop::Fallback) => {}
            }
        }
        *fallbacks += 1;
        match self.fallback(code) {
            Ok(exact::Value::Bool(Tri::True)) => Ok(true),
            Ok(exact::Value::Bool(Tri::False)) => Ok(false),
            Ok(_) => Err(Verdict::Undecided),
            Err(why) => Err(Verdict::Undefined(undefined_reason(&why))),
        }
    }

    /// A numeric or boolean value (a recursion argument).
    pub fn value(&self, code: &Code, fallbacks: &mut u64) -> Result<Val, Verdict> {
        if !code.slow {
            match self.eval(code.root) {
                Ok(v) => return Ok(v),
                Err(Stop::Undefined(why)) => return Err(Verdict::Undefined(why)),
                Err(Stop::Fallback) => {}
            }
        }
        *fallbacks += 1;
        match self.fallback(code) {
            Ok(exact::Value::Bool(Tri::True)) => Ok(Val::Bool(true)),
            Ok(exact::Value::Bool(Tri::False)) => Ok(Val::Bool(false)),
            Ok(exact::Value::Num(n)) if n.is_exact() => match rat_to_q(&n.lo) {
                Some(q) => Ok(Val::Num(q)),
                // A value no register can hold (beyond 128-bit rationals): refused, not rounded.
                None => Err(Verdict::Undecided),
            },
            Ok(_) => Err(Verdict::Undecided),
            Err(why) => Err(Verdict::Undefined(undefined_reason(&why))),
        }
    }
}

/// The reason the fixed width would give for what the exact evaluator refused, so that a
/// report reads the same whichever path evaluated the expression (the fallback runs after an
/// overflow, and may meet the division by zero the fixed width would have met).
fn undefined_reason(why: &str) -> &'static str {
    // The exact evaluator's enclosures (a `sqrt` in the divisor) may leave the sign open:
    // say so, rather than claim the divisor is zero.
    if why.starts_with("a division by") {
        "a division by a divisor that is, or may be, zero"
    } else if why.starts_with("the square root") {
        "the square root of a number that is, or may be, negative"
    } else {
        "an operation undefined at these values"
    }
}

/// Why a predicate has no truth value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// A partial operator outside its domain (the static checks ask definedness).
    Undefined(&'static str),
    /// Exact evaluation could not decide it (an irrational value on a boundary, or a value
    /// beyond what a register holds).
    Undecided,
}

/// A string's bytes up to its first NUL.
pub fn cut(s: &[u8]) -> &[u8] {
    match s.iter().position(|&b| b == 0) {
        Some(n) => &s[..n],
        None => s,
    }
}
