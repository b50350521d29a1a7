//! Witness queries for the simulator ([`crate::simulate`]): concrete states in, concrete
//! trajectories, payloads and points out. The contracts are read exactly as the
//! obligations read them (this module reuses [`Inst`](super::Inst)), but every variable
//! the simulator knows is pinned to its exact value, so the queries are small.
//!
//! Models come back as exact rationals ([`crate::exact::Value`]); an algebraic number
//! (from a square root) comes back as a rational enclosure 1e-25 wide.

use super::super::encode::{Encoder, Frame, Term};
use super::super::{Watchdog, Why};
use super::{connect, world_point, Inst, Query};
use crate::exact::{parse_decimal, Num, Rat, Tri, Value};
use crate::hir::{Expr, PrimApp, Program, RoleId, Slot};
use num_bigint::BigInt;
use std::cell::Cell;
use std::str::FromStr;
use std::time::Duration;
use z3::ast::{Bool, Int, Real};

/// A Z3 context on this thread with a watchdog (see [`Watchdog`]); every query of a
/// simulation runs in one.
pub struct Session<'a> {
    watchdog: &'a Watchdog,
    timeout: Duration,
    /// Queries asked so far.
    pub queries: Cell<usize>,
}

/// Runs `f` with a session whose queries time out after `timeout` each.
pub fn session<R>(timeout: Duration, f: impl FnOnce(&Session) -> R) -> R {
    let watchdog = Watchdog::default();
    let ctx = z3::Context::thread_local();
    let handle = ctx.handle();
    struct Stop<'w>(&'w Watchdog);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            self.0.stop();
        }
    }
    std::thread::scope(|s| {
        s.spawn(|| watchdog.run(handle));
        let _stop = Stop(&watchdog);
        f(&Session { watchdog: &watchdog, timeout, queries: Cell::new(0) })
    })
}

/// A participant about to run (or running) a primitive whose arguments are closed terms.
#[derive(Clone, Debug)]
pub struct Mover {
    pub role: RoleId,
    pub app: PrimApp,
    /// The state when the motion starts, one value per state variable of the kind.
    pub start: Vec<Value>,
    /// Inputs whose source does not move in this motion: their (constant) values.
    pub inputs: Vec<Option<Value>>,
}

/// States of the movers at one time of a joint motion.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Time since the motion started.
    pub time: Num,
    /// Per mover, one value per state variable.
    pub states: Vec<Vec<Value>>,
}

/// A trajectory of a joint motion, sampled; the last sample is the end.
#[derive(Clone, Debug)]
pub struct Trajectory {
    pub end: Num,
    pub samples: Vec<Sample>,
}

/// A participant in a footprint check: its motion, start state, state now and clock.
#[derive(Clone, Debug)]
pub struct Occupant {
    pub role: RoleId,
    pub app: PrimApp,
    pub start: Vec<Value>,
    pub now: Vec<Value>,
    pub clock: Num,
}

impl Session<'_> {
    fn solve(&self, q: &Query) -> Result<Option<z3::Model>, Why> {
        self.queries.set(self.queries.get() + 1);
        let assert_all = |s: &z3::Solver| {
            for a in q.assertions.iter().chain(q.enc.side_conditions()) {
                s.assert(a);
            }
        };
        let solver = super::super::solver_for(q);
        assert_all(&solver);
        let seq = self.watchdog.arm(self.timeout);
        let r = solver.check();
        let timed_out = self.watchdog.disarm(seq);
        match r {
            z3::SatResult::Unsat => Ok(None),
            z3::SatResult::Sat => {
                let m =
                    solver.get_model().ok_or_else(|| Why::Incomplete("Z3 gave no model".into(), Default::default()))?;
                if q.enc.spurious_trig(&m) {
                    return Err(Why::Incomplete(
                        "the witness relies on the sin/cos enclosure".into(),
                        crate::smt::Hard::of(q),
                    ));
                }
                Ok(Some(m))
            }
            z3::SatResult::Unknown if timed_out => Err(Why::Timeout(self.timeout, crate::smt::Hard::of(q))),
            z3::SatResult::Unknown => Err(Why::Incomplete(
                solver.get_reason_unknown().unwrap_or_else(|| "unknown".into()),
                crate::smt::Hard::of(q),
            )),
        }
    }

    /// Values of `want` (terms over free value variables) satisfying `facts` (closed
    /// except for those variables), or `None` if there are none.
    pub fn values(&self, prog: &Program, facts: &[Expr], want: &[Expr]) -> Result<Option<Vec<Value>>, Why> {
        self.values_nudged(prog, facts, want, None)
    }

    /// [`Session::values`], then, with `nudge = Some((k, d))`, a second model with
    /// `want[k]` at least `d` above (or, `d < 0`, below) the first one's value, if there is
    /// one: Z3's first models sit on boundaries; this moves off them.
    pub fn values_nudged(
        &self,
        prog: &Program,
        facts: &[Expr],
        want: &[Expr],
        nudge: Option<(usize, Rat)>,
    ) -> Result<Option<Vec<Value>>, Why> {
        let mut q = query(prog);
        for f in facts {
            let b = q.enc.boolean(f).map_err(unsupported)?;
            q.assertions.push(b);
        }
        let terms: Vec<Term> = want.iter().map(|w| q.enc.any(w)).collect::<Result<_, _>>().map_err(unsupported)?;
        let Some(m) = self.solve(&q)? else { return Ok(None) };
        let first: Vec<Value> =
            terms.iter().map(|t| value_of(&m, t)).collect::<Option<Vec<_>>>().ok_or_else(unreadable)?;
        let Some((k, d)) = nudge else { return Ok(Some(first)) };
        let (Some(Term::R(t)), Some(Value::Num(v))) = (terms.get(k), first.get(k)) else { return Ok(Some(first)) };
        let Some(v) = v.value() else { return Ok(Some(first)) };
        let Some(bound) = real(&(v + &d)) else { return Ok(Some(first)) };
        q.assertions.push(if d >= Rat::from_integer(BigInt::from(0)) { t.ge(&bound) } else { t.le(&bound) });
        match self.solve(&q) {
            Ok(Some(m)) => Ok(terms.iter().map(|t| value_of(&m, t)).collect::<Option<Vec<_>>>().or(Some(first))),
            _ => Ok(Some(first)),
        }
    }

    /// A trajectory of the joint motion of `movers` from their start states: an end
    /// time `T` in every duration, states at `f * T` for each fraction `f` in `fracs`
    /// (the last must be 1, the end) satisfying each guarantee, assumption (inputs
    /// connected as in [AGCOMP]) and invariant, and each postcondition at `T`.
    /// `None` if the contracts admit no such trajectory. `end_at` fixes the end time
    /// (within an enclosure).
    ///
    /// With a non-interruptible mover, only its duration bounds `T` ([NON-INTERRUPT]: it
    /// ends by itself when its duration and post allow), so that the caller can check
    /// the others' durations at `T` exactly; `target` then asks for `T` at the start
    /// (`Some(false)`) or the end (`Some(true)`) of that duration.
    pub fn trajectory(
        &self,
        prog: &Program,
        movers: &[Mover],
        fracs: &[Rat],
        end_at: Option<&Num>,
    ) -> Result<Option<Trajectory>, Why> {
        self.trajectory_aimed(prog, movers, fracs, end_at, None)
    }

    /// [`Session::trajectory`] with a target for the end time (see there).
    pub fn trajectory_aimed(
        &self,
        prog: &Program,
        movers: &[Mover],
        fracs: &[Rat],
        end_at: Option<&Num>,
        target: Option<bool>,
    ) -> Result<Option<Trajectory>, Why> {
        let lead = movers.iter().position(|m| !prog.prim(m.app.prim).interruptible);
        let mut q = query(prog);
        let end = q.enc.named_real("end time");
        q.assertions.push(end.ge(zero()));
        if let Some(e) = end_at {
            q.assertions.push(in_range(&end, e).ok_or_else(unreadable)?);
        }
        let mut samples: Vec<(Real, Vec<Inst>)> = Vec::new();
        for (k, f) in fracs.iter().enumerate() {
            let fr = real(f).ok_or_else(unreadable)?;
            let clock = Real::mul(&[fr, end.clone()]);
            let tag = if k + 1 == fracs.len() { "end".to_string() } else { format!("s{k}") };
            let mut insts = Vec::new();
            for m in movers {
                insts.push(Inst::new(&mut q.enc, m.role, &m.app, clock.clone(), &tag).map_err(unsupported)?);
            }
            connect(&mut q, &mut insts);
            samples.push((clock, insts));
        }
        let Some((_, last)) = samples.last() else { return Ok(None) };
        for (i, m) in movers.iter().enumerate() {
            pin_start(&mut q, m.role, &m.start)?;
            let inst = &last[i];
            inst.started(&mut q).map_err(unsupported)?;
            if lead.is_none_or(|n| n == i) {
                let (lo, hi) = inst.duration(&mut q.enc).map_err(unsupported)?;
                q.assertions.push(lo.le(&end));
                match (target, &hi) {
                    (Some(false), _) if lead.is_some() => q.assertions.push(end.eq(&lo)),
                    (Some(true), Some(hi)) if lead.is_some() => q.assertions.push(end.eq(hi)),
                    _ => {}
                }
                if let Some(hi) = hi {
                    q.assertions.push(end.le(&hi));
                }
            }
            let post = inst.pred(&mut q.enc, &inst.prim.post, &inst.frame).map_err(unsupported)?;
            q.assertions.push(post);
        }
        for (_, insts) in &samples {
            for (i, inst) in insts.iter().enumerate() {
                running(&mut q, inst)?;
                let a = inst.pred(&mut q.enc, &inst.prim.assume, &inst.frame).map_err(unsupported)?;
                q.assertions.push(a);
                for (k, v) in movers[i].inputs.iter().enumerate() {
                    if let (Some(v), Some(t)) = (v, inst.frame.own.get(&Slot::Input(k))) {
                        let b = pin(t, v).ok_or_else(unreadable)?;
                        q.assertions.push(b);
                    }
                }
            }
        }
        let Some(model) = self.solve(&q)? else { return Ok(None) };
        let num = |r: &Real| match value_of(&model, &Term::R(r.clone())) {
            Some(Value::Num(n)) => Some(n),
            _ => None,
        };
        let end = num(&end).ok_or_else(unreadable)?;
        let mut out = Vec::new();
        for (clock, insts) in &samples {
            let time = num(clock).ok_or_else(unreadable)?;
            let mut states = Vec::new();
            for inst in insts {
                let n = prog.kind_of(inst.role).state.len();
                let s: Option<Vec<Value>> =
                    (0..n).map(|i| value_of(&model, inst.frame.own.get(&Slot::State(i))?)).collect();
                states.push(s.ok_or_else(unreadable)?);
            }
            out.push(Sample { time, states });
        }
        Ok(Some(Trajectory { end, samples: out }))
    }

    /// Inputs of mover `i` at time `clock` of the joint motion that the other movers'
    /// guarantees allow but `i`'s assumption does not ([AGCOMP]'s assumption
    /// discharge at a concrete start): the values of `i`'s inputs then, or `None`.
    pub fn assumption_breaks(
        &self,
        prog: &Program,
        movers: &[Mover],
        i: usize,
        clock: &Num,
    ) -> Result<Option<Vec<Value>>, Why> {
        let mut q = query(prog);
        let c = q.enc.named_real("time");
        q.assertions.push(in_range(&c, clock).ok_or_else(unreadable)?);
        let mut insts = Vec::new();
        for m in movers {
            insts.push(Inst::new(&mut q.enc, m.role, &m.app, c.clone(), "t").map_err(unsupported)?);
        }
        connect(&mut q, &mut insts);
        for (j, (m, inst)) in movers.iter().zip(&insts).enumerate() {
            pin_start(&mut q, m.role, &m.start)?;
            inst.started(&mut q).map_err(unsupported)?;
            if j != i {
                inst.running(&mut q).map_err(unsupported)?;
            }
        }
        for (k, v) in movers[i].inputs.iter().enumerate() {
            if let (Some(v), Some(t)) = (v, insts[i].frame.own.get(&Slot::Input(k))) {
                let b = pin(t, v).ok_or_else(unreadable)?;
                q.assertions.push(b);
            }
        }
        let a = insts[i].pred(&mut q.enc, &insts[i].prim.assume, &insts[i].frame).map_err(unsupported)?;
        q.assertions.push(a.not());
        let Some(m) = self.solve(&q)? else { return Ok(None) };
        let n = prog.kind_of(movers[i].role).inputs.len();
        let vals: Option<Vec<Value>> = (0..n).map(|k| value_of(&m, insts[i].frame.own.get(&Slot::Input(k))?)).collect();
        vals.map(Some).ok_or_else(unreadable)
    }

    /// A world point in the footprints of both occupants at their states and clocks, or
    /// `None` if they are disjoint. A primitive without a footprint fills all space; a
    /// footprint with a URDF or mesh part has no predicate and is unsupported here.
    pub fn overlap(&self, prog: &Program, a: &Occupant, b: &Occupant) -> Result<Option<[Num; 3]>, Why> {
        let mut q = query(prog);
        let p = world_point(&mut q);
        for (o, tag) in [(a, "a"), (b, "b")] {
            occupies(&mut q, o, tag, &p)?;
        }
        self.point(&q, &p)
    }

    /// A world point in the footprint of `a` at its state and clock and in `region` (a
    /// predicate over the world point, as an obstacle's), or `None` if there is none.
    pub fn overlap_region(&self, prog: &Program, a: &Occupant, region: &Expr) -> Result<Option<[Num; 3]>, Why> {
        let mut q = query(prog);
        let p = world_point(&mut q);
        occupies(&mut q, a, "a", &p)?;
        let frame = Frame { point: Some(p.clone()), ..Frame::default() };
        let inside = q.enc.in_frame(&frame, |enc| enc.boolean(region)).map_err(unsupported)?;
        q.assertions.push(inside);
        self.point(&q, &p)
    }

    /// The point `p` of a model of `q`, or `None` if `q` is unsatisfiable.
    fn point(&self, q: &Query, p: &[Real; 3]) -> Result<Option<[Num; 3]>, Why> {
        let Some(m) = self.solve(q)? else { return Ok(None) };
        let c = |r: &Real| match value_of(&m, &Term::R(r.clone())) {
            Some(Value::Num(n)) => Some(n),
            _ => None,
        };
        Ok(Some([c(&p[0]).ok_or_else(unreadable)?, c(&p[1]).ok_or_else(unreadable)?, c(&p[2]).ok_or_else(unreadable)?]))
    }
}

/// `o` at its state and clock, and the world point `p` in its footprint.
fn occupies(q: &mut Query, o: &Occupant, tag: &str, p: &[Real; 3]) -> Result<(), Why> {
    let clock = q.enc.named_real(&format!("clock {tag}"));
    q.assertions.push(in_range(&clock, &o.clock).ok_or_else(unreadable)?);
    let inst = Inst::new(&mut q.enc, o.role, &o.app, clock, tag).map_err(unsupported)?;
    pin_start(q, o.role, &o.start)?;
    for (i, v) in o.now.iter().enumerate() {
        let t = inst.frame.own.get(&Slot::State(i)).ok_or_else(unreadable)?;
        let b = pin(t, v).ok_or_else(unreadable)?;
        q.assertions.push(b);
    }
    let fp = inst.footprint(&mut q.enc, p).map_err(unsupported)?;
    q.assertions.push(fp);
    Ok(())
}

/// The motion is running at its clock: `t >= 0`, its guarantee and the invariant hold
/// now ([TRAJ-STEP]). Unlike [`Inst::running`], `t` is not bounded by the duration here:
/// the end time carries the durations (and the caller checks the others' at it).
fn running(q: &mut Query, inst: &Inst) -> Result<(), Why> {
    let t = inst.frame.clock.clone().unwrap_or_else(zero);
    q.assertions.push(t.ge(zero()));
    let g = inst.pred(&mut q.enc, &inst.prim.guarantee, &inst.frame).map_err(unsupported)?;
    q.assertions.push(g);
    if let Some(inv) = &q.enc.prog().kind(inst.prim.kind).invariant.clone() {
        let b = inst.pred(&mut q.enc, inv, &inst.frame).map_err(unsupported)?;
        q.assertions.push(b);
    }
    Ok(())
}

fn query(prog: &Program) -> Query<'_> {
    Query { enc: Encoder::new(prog), assertions: Vec::new(), point: None, times: Vec::new() }
}

fn unsupported(u: super::Unsupported) -> Why {
    Why::Unsupported(u.0)
}

fn unreadable() -> Why {
    Why::Incomplete("a value the simulator cannot read back".into(), Default::default())
}

fn zero() -> Real {
    Int::from_i64(0).to_real()
}

/// Pins `role`'s state variables (as the shared vocabulary names them) to `start`.
fn pin_start(q: &mut Query, role: RoleId, start: &[Value]) -> Result<(), Why> {
    for (i, v) in start.iter().enumerate() {
        let t = q.enc.role_var(role, Slot::State(i)).map_err(unsupported)?;
        let b = pin(&t, v).ok_or_else(unreadable)?;
        q.assertions.push(b);
    }
    Ok(())
}

/// An exact rational as a Z3 real.
fn real(r: &Rat) -> Option<Real> {
    Real::from_rational_str(&r.numer().to_string(), &r.denom().to_string())
}

fn in_range(t: &Real, n: &Num) -> Option<Bool> {
    Some(match n.value() {
        Some(v) => t.eq(real(v)?),
        None => Bool::and(&[t.ge(real(&n.lo)?), t.le(real(&n.hi)?)]),
    })
}

/// `term == value` (or within the value's enclosure).
fn pin(t: &Term, v: &Value) -> Option<Bool> {
    match (t, v) {
        (Term::B(b), Value::Bool(Tri::True)) => Some(b.clone()),
        (Term::B(b), Value::Bool(Tri::False)) => Some(b.not()),
        (Term::B(_), Value::Bool(Tri::Unknown)) => Some(Bool::from_bool(true)),
        (Term::I(i), Value::Num(n)) => match n.value() {
            Some(v) if v.is_integer() => Some(i.eq(Int::from_str(&v.numer().to_string()).ok()?)),
            _ => in_range(&i.to_real(), n),
        },
        (Term::R(r), Value::Num(n)) => in_range(r, n),
        (Term::V(c), Value::Vec3(n)) => {
            Some(Bool::and(&[in_range(&c[0], &n[0])?, in_range(&c[1], &n[1])?, in_range(&c[2], &n[2])?]))
        }
        _ => None,
    }
}

/// The exact value of a term in a model.
pub(crate) fn value_of(m: &z3::Model, t: &Term) -> Option<Value> {
    Some(match t {
        Term::B(b) => Value::Bool(match m.eval(b, true)?.as_bool() {
            Some(x) => Tri::of(x),
            None => Tri::Unknown,
        }),
        Term::I(i) => {
            let v = m.eval(i, true)?;
            Value::rat(Rat::from_integer(
                BigInt::from_str(&v.to_string()).ok().or_else(|| v.as_i64().map(BigInt::from))?,
            ))
        }
        Term::R(r) => Value::Num(num_of(&m.eval(r, true)?)?),
        Term::V(c) => Value::Vec3([
            num_of(&m.eval(&c[0], true)?)?,
            num_of(&m.eval(&c[1], true)?)?,
            num_of(&m.eval(&c[2], true)?)?,
        ]),
    })
}

/// A Z3 real value: exact for rationals (any size), an enclosure for algebraic numbers.
pub(crate) fn num_of(r: &Real) -> Option<Num> {
    if let Some((n, d)) = r.as_rational() {
        if d != 0 {
            return Some(Num::exact(Rat::new(BigInt::from(n), BigInt::from(d))));
        }
    }
    if let Some(v) = numeral(&r.to_string()) {
        return Some(Num::exact(v));
    }
    // An algebraic number: Z3's decimal approximation is within 10^-precision.
    let approx = r.approx(30);
    let v = parse_decimal(approx.trim_end_matches('?'))?;
    let eps = Rat::new(BigInt::from(1), num_traits::pow(BigInt::from(10), 25));
    Some(Num::range(&v - &eps, &v + &eps))
}

/// Parses Z3's printing of a rational numeral: `13.0`, `(- 2.0)`, `(/ 13.0 20.0)`,
/// `(- (/ 1.0 3.0))`.
fn numeral(s: &str) -> Option<Rat> {
    let s = s.trim();
    if let Some(inner) = s.strip_prefix("(-").and_then(|r| r.strip_suffix(')')) {
        return numeral(inner).map(|v| -v);
    }
    if let Some(inner) = s.strip_prefix("(/").and_then(|r| r.strip_suffix(')')) {
        let inner = inner.trim();
        // Split at the top-level space between the two operands.
        let mut depth = 0;
        for (i, ch) in inner.char_indices() {
            match ch {
                '(' => depth += 1,
                ')' => depth -= 1,
                ' ' if depth == 0 => {
                    let (a, b) = (numeral(&inner[..i])?, numeral(&inner[i + 1..])?);
                    return (b != Rat::from_integer(BigInt::from(0))).then(|| a / b);
                }
                _ => {}
            }
        }
        return None;
    }
    parse_decimal(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use z3::ast::Ast;

    #[test]
    fn numerals_read_back_exactly() {
        let third = Rat::new(BigInt::from(1), BigInt::from(3));
        assert_eq!(numeral("(/ 1.0 3.0)"), Some(third.clone()));
        assert_eq!(numeral("(- (/ 1.0 3.0))"), Some(-third));
        assert_eq!(numeral("13.0"), parse_decimal("13"));
        assert_eq!(numeral("(root-obj (+ (^ x 2) (- 2)) 2)"), None);
        let big = Real::from_rational_str("123456789012345678901234567890", "7").expect("numeral");
        assert_eq!(
            num_of(&big.simplify()),
            Some(Num::exact(Rat::new(BigInt::from_str("123456789012345678901234567890").unwrap(), BigInt::from(7))))
        );
    }
}
