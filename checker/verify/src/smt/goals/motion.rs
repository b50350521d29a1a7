//! A participant running a primitive, encoded (Def 3.4, Sec 3.4, Fig 3 [M-PAR],
//! [TRAJ-STEP]). How a primitive run by participant `p` is read:
//! - its state when it starts is `p.x` — the same variables the context Σ speaks of;
//! - its state at time `t` of the motion is `p.x(t)`, at its end `p.x(end)`;
//! - `old(x)` is the start state, parameters are the arguments, `clock` is `t`;
//! - an input `w` is the connected participant's `w(t)` when that participant is part
//!   of the same joint motion, and unconstrained otherwise;
//! - the kind's invariant holds of every state (assumed, as in typing);
//! - footprints are in the participant's frame: the world point `(x, y, z)` is moved
//!   into it by the inverse of the participant's `pose` ([`super::frames`]).

use super::super::encode::{zero, Encoder, Frame, Term, Unsupported};
use super::frames::to_local;
use super::Query;
use crate::hir::{Expr, Footprint, PrimApp, Primitive, RoleId, Slot};
use z3::ast::{Bool, Real};

/// A participant running a primitive, encoded.
#[derive(Clone)]
pub(super) struct Inst<'a> {
    pub(super) role: RoleId,
    pub(super) prim: &'a Primitive,
    pub(super) frame: Frame,
    /// The state at the start (`role.x`), for the frame of durations and `Pre`.
    pub(super) start: std::collections::BTreeMap<Slot, Term>,
    /// The arguments can be evaluated (`hir::expr::definedness` of each, read where the
    /// motion is called): a motion called with `sqrt` of a negative or a quotient by zero
    /// never starts, whatever its precondition says.
    pub(super) args_defined: Bool,
}

impl<'a> Inst<'a> {
    pub(super) fn new(
        enc: &mut Encoder<'a>,
        role: RoleId,
        app: &PrimApp,
        clock: Real,
        tag: &str,
    ) -> Result<Inst<'a>, Unsupported> {
        let prog = enc.prog();
        let prim = prog.prim(app.prim);
        let kind = prog.kind_of(role);
        let mut frame = Frame::default();
        let mut start = std::collections::BTreeMap::new();
        for i in 0..kind.state.len() {
            let slot = Slot::State(i);
            let s = enc.role_var(role, slot)?;
            frame.old.push(s.clone());
            start.insert(slot, s);
            let (n, sort) = kind.var(slot).clone();
            let now = enc.named(&format!("{}.{n}({tag})", prog.role_name(role)), &sort)?;
            frame.own.insert(slot, now);
        }
        for i in 0..kind.inputs.len() {
            let slot = Slot::Input(i);
            let (n, sort) = kind.var(slot).clone();
            // At time t: connected later by `connect` when the source moves in the same motion.
            let now = enc.named(&format!("{}.{n}({tag})", prog.role_name(role)), &sort)?;
            frame.own.insert(slot, now.clone());
            // At the start the input *is* its source's state (the variable Σ speaks
            // of), not a fresh value: a precondition the source's state proves holds.
            let s = enc.role_var(role, slot)?;
            start.insert(slot, s);
        }
        frame.params = app.args.iter().map(|a| enc.any(a)).collect::<Result<_, _>>()?;
        let defined = crate::hir::expr::and_all(app.args.iter().map(crate::hir::expr::definedness), app.loc);
        let args_defined = enc.boolean(&defined)?;
        frame.args = app.args.clone();
        frame.clock = Some(clock);
        Ok(Inst { role, prim, frame, start, args_defined })
    }

    pub(super) fn start_frame(&self) -> Frame {
        Frame { own: self.start.clone(), ..self.frame.clone() }
    }

    /// A contract predicate under `frame`, with what it means where a partial operator is
    /// undefined: false (`hir::expr::defined_and`). The encoding alone makes `sqrt` of a
    /// negative and `x / 0` arbitrary numbers, so a postcondition `x == sqrt(old(x) - 5)`
    /// from `x == 0` could "end" at some arbitrary `x`, and a motion that can never end
    /// passed its can-end question.
    pub(super) fn pred(&self, enc: &mut Encoder, e: &Expr, frame: &Frame) -> Result<Bool, Unsupported> {
        let e = crate::hir::expr::defined_and(e.clone());
        enc.in_frame(frame, |enc| enc.boolean(&e))
    }

    /// `now` equals the start state (for time 0).
    pub(super) fn at_start(&self) -> Bool {
        let eqs: Vec<Bool> =
            self.frame.own.iter().filter_map(|(slot, now)| now.equals(self.start.get(slot)?)).collect();
        Bool::and(&eqs)
    }

    /// The motion started: its arguments could be evaluated, and its precondition and the
    /// invariant held at the start.
    pub(super) fn started(&self, q: &mut Query) -> Result<(), Unsupported> {
        q.assertions.push(self.args_defined.clone());
        let sf = self.start_frame();
        let pre = self.pred(&mut q.enc, &self.prim.pre, &sf)?;
        q.assertions.push(pre);
        if let Some(inv) = &q.enc.prog().kind(self.prim.kind).invariant.clone() {
            let b = self.pred(&mut q.enc, inv, &sf)?;
            q.assertions.push(b);
        }
        Ok(())
    }

    /// The motion is running at its clock: `0 <= t <= hi`, its guarantee and the
    /// invariant hold of the state now.
    pub(super) fn running(&self, q: &mut Query) -> Result<(), Unsupported> {
        let t = self.frame.clock.clone().unwrap_or_else(zero);
        q.assertions.push(t.ge(zero()));
        if let Some(hi) = &self.prim.duration.hi {
            let hi = q.enc.in_frame(&self.start_frame(), |enc| enc.real(hi))?;
            q.assertions.push(t.le(&hi));
        }
        let g = self.pred(&mut q.enc, &self.prim.guarantee, &self.frame)?;
        q.assertions.push(g);
        if let Some(inv) = &q.enc.prog().kind(self.prim.kind).invariant.clone() {
            let b = self.pred(&mut q.enc, inv, &self.frame)?;
            q.assertions.push(b);
        }
        Ok(())
    }

    /// The world point `p` is in the footprint now.
    pub(super) fn occupies(&self, q: &mut Query, p: &[Real; 3]) -> Result<(), Unsupported> {
        let fp = self.footprint(&mut q.enc, p)?;
        q.assertions.push(fp);
        Ok(())
    }

    /// "The world point `p` is in the footprint now", exactly: all space is `true` (Def
    /// 3.4, no footprint written), a predicate or shapes their predicate. A footprint with
    /// a URDF or mesh part has no predicate: unsupported here (the geometric procedure
    /// decides the questions it can; every other one is unknown), never `true`.
    pub(super) fn footprint(&self, enc: &mut Encoder, p: &[Real; 3]) -> Result<Bool, Unsupported> {
        match &self.prim.footprint {
            Footprint::Everywhere => return Ok(Bool::from_bool(true)),
            Footprint::Predicate(_) | Footprint::Shapes { .. } => {}
            Footprint::Solid { .. } => return Err(no_predicate(self.prim)),
        }
        let local = to_local(enc, self.role, p)?;
        self.footprint_at(enc, &local)
    }

    /// "The point `local` of the participant's own frame is in the footprint now", as
    /// [`Inst::footprint`] but with the world point already moved into the frame: two
    /// footprints of one participant read one local point (each move has its own
    /// rotation slack, so two moves could place one world point at two local points).
    pub(super) fn footprint_at(&self, enc: &mut Encoder, local: &[Real; 3]) -> Result<Bool, Unsupported> {
        let fp = match &self.prim.footprint {
            Footprint::Everywhere => return Ok(Bool::from_bool(true)),
            Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => fp,
            Footprint::Solid { .. } => return Err(no_predicate(self.prim)),
        };
        let frame = Frame { point: Some(local.clone()), ..self.frame.clone() };
        self.pred(enc, &fp.pred, &frame)
    }

    /// `(lo, hi)` of the duration, in the start frame; `hi = None` for infinity.
    pub(super) fn duration(&self, enc: &mut Encoder) -> Result<(Real, Option<Real>), Unsupported> {
        let sf = self.start_frame();
        let lo = enc.in_frame(&sf, |enc| enc.real(&self.prim.duration.lo))?;
        let hi = match &self.prim.duration.hi {
            Some(h) => Some(enc.in_frame(&sf, |enc| enc.real(h))?),
            None => None,
        };
        Ok((lo, hi))
    }
}

/// Why a footprint with a URDF or mesh part is not a formula.
pub(super) fn no_predicate(prim: &Primitive) -> Unsupported {
    Unsupported(format!(
        "a footprint with a URDF or mesh part (that of `{}`), which has no predicate, in a question the geometric procedure does not decide",
        prim.name
    ))
}

/// The parts end together at time `t` ([M-PAR]: one elapsed time for all): every part
/// started (precondition, invariant), `t` lies in every part's duration (Def 4.11 (5):
/// `t <= ⌈D⌉`; (8)(a), (b) and [NON-INTERRUPT]/[INTERRUPT]: `t ∈ D`), the guarantee
/// held at time 0 of the start state and at `t` of the end state (the two ends of
/// [TRAJ-STEP]'s `[0, t]`), and the postcondition and invariant hold of the end state.
/// The state at `t` is each instance's frame, so `connect` already makes an input its
/// source's end state when the source is a part.
pub(super) fn ends(q: &mut Query, insts: &[Inst], t: &Real) -> Result<(), Unsupported> {
    q.assertions.push(t.ge(zero()));
    for inst in insts {
        inst.started(q)?;
        let (lo, hi) = inst.duration(&mut q.enc)?;
        q.assertions.push(t.ge(&lo));
        if let Some(hi) = hi {
            q.assertions.push(t.le(&hi));
        }
        let at_zero = Frame { clock: Some(zero()), ..inst.start_frame() };
        let g0 = inst.pred(&mut q.enc, &inst.prim.guarantee, &at_zero)?;
        let gt = inst.pred(&mut q.enc, &inst.prim.guarantee, &inst.frame)?;
        let post = inst.pred(&mut q.enc, &inst.prim.post, &inst.frame)?;
        q.assertions.extend([g0, gt, post]);
        if let Some(inv) = q.enc.prog().kind(inst.prim.kind).invariant.clone() {
            let b = inst.pred(&mut q.enc, &inv, &inst.frame)?;
            q.assertions.push(b);
        }
        // The robot's joints move no faster than its URDF's velocity limits: the end state
        // lies within `velocity * t` of the start, per joint.
        if let Some(speed) = q.enc.prog().kind(inst.prim.kind).speed.clone() {
            let b = inst.pred(&mut q.enc, &speed, &inst.frame)?;
            q.assertions.push(b);
        }
    }
    Ok(())
}

/// The frame at the end of the motion: own variables are fresh `role.x(end)`.
pub(super) fn end_frame(enc: &mut Encoder, inst: &Inst) -> Result<Frame, Unsupported> {
    let prog = enc.prog();
    let kind = prog.kind_of(inst.role);
    let mut own = inst.frame.own.clone();
    for i in 0..kind.state.len() {
        let (n, sort) = kind.var(Slot::State(i)).clone();
        own.insert(Slot::State(i), enc.named(&format!("{}.{n}(end)", prog.role_name(inst.role)), &sort)?);
    }
    Ok(Frame { own, clock: None, ..inst.frame.clone() })
}

#[cfg(test)]
mod tests {
    use super::super::super::{discharge, Decision, SmtConfig};
    use crate::obligation::{Goal, Obligation, Rule};

    /// Can `R.m` (with the given contract) end, from some start and arguments? (Def 4.11:
    /// some time in its duration and an end state meeting its guarantee, postcondition and
    /// the invariant, [`super::ends`].)
    fn can_end(contract: &str) -> Decision {
        let src = format!(
            "robot R {{ state x: real; invariant: 0 <= x <= 10; }}
             motion R.m(d: real) {{ interruptible: true; {contract} }}
             system S {{ participant A: R {{ init: x == 1; }} }} choreography G = dt<A: m(1)>. end;"
        );
        let (prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let ob = Obligation {
            rule: Rule::Contract,
            span: Default::default(),
            what: "m can end".into(),
            hyps: Vec::new(),
            goal: Goal::CanEnd {
                prim: prog.prims.iter().position(|p| p.name == "m").map(|i| crate::hir::PrimId(i as u32)).expect("m"),
            },
        };
        discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0
    }

    #[test]
    fn a_motion_ends_where_its_post_guarantee_and_invariant_meet() {
        assert_eq!(can_end("post: x == old(x) + d; duration: [0, 5];"), Decision::Holds(None));
        // The end state must satisfy the invariant (x <= 10) and the post together.
        assert!(matches!(can_end("post: x == old(x) + 20; guarantee: x >= old(x);"), Decision::Fails(_)));
        // An empty duration: no time to end at.
        assert!(matches!(can_end("duration: [2, 1];"), Decision::Fails(_)));
        // The guarantee must hold at the end too.
        assert!(matches!(can_end("guarantee: x > 100;"), Decision::Fails(_)));
    }
}
