//! [AGCOMP] (Sec 3.4): the parts of a joint motion `dt<p1: a1, ..., pn: an>` compose when
//! each part's precondition holds at the `dt` ("compatible from Pre"), the others'
//! guarantees discharge each part's assumption, their footprints are pairwise disjoint at
//! every time, their durations fit (a non-interruptible part's within every other's, or,
//! with none, a common time), and the joint motion can end. This module plans those parts
//! and builds their queries; pairs of footprints whose boxes are apart are proved by
//! [`super::boxes`] without a query.

use super::super::encode::Unsupported;
use super::frames::world_point;
use super::motion::{ends, Inst};
use super::query::{hyps, seeds_of, slice, zero};
use super::{Part, Plan, Query};
use crate::hir::{Expr, PrimApp, Program, RoleId, Slot};
use z3::ast::Bool;

/// The parts of a `dt`'s [AGCOMP] obligation.
pub(super) fn plan(prog: &Program, parts: &[(RoleId, PrimApp)]) -> Plan {
    let mut out = Vec::new();
    // A lone primitive's precondition is [T-MOTION]'s to check, in its process.
    let lone = parts.len() == 1;
    for (i, (_, app)) in parts.iter().enumerate() {
        let p = prog.prim(app.prim);
        if !p.pre.is_true() && !lone {
            out.push(Part::Pre(i));
        }
        if !p.assume.is_true() {
            out.push(Part::Assume(i));
        }
    }
    for i in 0..parts.len() {
        for j in i + 1..parts.len() {
            let (a, b) = (prog.prim(parts[i].1.prim), prog.prim(parts[j].1.prim));
            if a.footprint.is_none() || b.footprint.is_none() {
                let who = if a.footprint.is_none() { &parts[i] } else { &parts[j] };
                return Plan::Fails(format!(
                    "`{}` of `{}` declares no footprint, so it may occupy all space and meets every other footprint",
                    prog.prim(who.1.prim).name,
                    prog.role_name(who.0)
                ));
            }
            out.push(Part::Disjoint(i, j));
        }
    }
    // One can-end question for the whole `dt`: the parts end together.
    out.push(Part::CanEnd);
    let non: Vec<usize> = (0..parts.len()).filter(|&i| !prog.prim(parts[i].1.prim).interruptible).collect();
    match non.first() {
        Some(&n) => out.extend((0..parts.len()).filter(|&j| j != n).map(|j| Part::Within(n, j))),
        None if parts.len() > 1 => out.push(Part::Meet),
        None => {}
    }
    Plan::Parts(out)
}

pub(super) fn compat(q: &mut Query, hs: &[Expr], parts: &[(RoleId, PrimApp)], part: &Part) -> Result<(), Unsupported> {
    if matches!(part, Part::CanEnd | Part::CanStart) {
        hyps(q, hs)?;
    } else {
        hyps(q, &slice(q.enc.prog(), hs, seeds_of(q.enc.prog(), parts)))?;
    }
    let t = q.enc.named_real("time");
    let mut insts = Vec::new();
    for (r, app) in parts {
        insts.push(Inst::new(&mut q.enc, *r, app, t.clone(), "t")?);
    }
    connect(q, &mut insts);
    match part {
        // No hypotheses sliced away: a contradiction anywhere in Σ must show.
        Part::CanEnd => ends(q, &insts, &t)?,
        Part::CanStart => {
            for inst in &insts {
                inst.started(q)?;
            }
        }
        Part::Pre(i) => {
            let inst = &insts[*i];
            if let Some(inv) = q.enc.prog().kind(inst.prim.kind).invariant.clone() {
                let b = inst.pred(&mut q.enc, &inv, &inst.start_frame())?;
                q.assertions.push(b);
            }
            let pre = inst.pred(&mut q.enc, &inst.prim.pre, &inst.start_frame())?;
            q.assertions.push(pre.not());
        }
        Part::Assume(i) => {
            for (j, inst) in insts.iter().enumerate() {
                inst.started(q)?;
                if j == *i {
                    // Its own guarantee is not assumed: that would be circular.
                    q.assertions.push(t.ge(zero()));
                } else {
                    inst.running(q)?;
                }
            }
            let a = insts[*i].pred(&mut q.enc, &insts[*i].prim.assume, &insts[*i].frame)?;
            q.assertions.push(a.not());
        }
        Part::Disjoint(i, j) => {
            for inst in &insts {
                inst.started(q)?;
                inst.running(q)?;
            }
            let p = world_point(q);
            insts[*i].occupies(q, &p)?;
            insts[*j].occupies(q, &p)?;
            q.point = Some(p);
            q.times = vec![t];
        }
        Part::Within(n, j) => {
            for inst in &insts {
                inst.started(q)?;
            }
            let (nlo, nhi) = insts[*n].duration(&mut q.enc)?;
            let (jlo, jhi) = insts[*j].duration(&mut q.enc)?;
            let inside = match (nhi, jhi) {
                (_, None) => jlo.le(&nlo),
                (Some(nhi), Some(jhi)) => Bool::and(&[jlo.le(&nlo), nhi.le(&jhi)]),
                // An unbounded non-interruptible duration never fits a bounded one.
                (None, Some(_)) => Bool::from_bool(false),
            };
            q.assertions.push(inside.not());
        }
        Part::Meet => {
            for inst in &insts {
                inst.started(q)?;
            }
            let mut ds = Vec::new();
            for inst in &insts {
                ds.push(inst.duration(&mut q.enc)?);
            }
            let mut ok = Vec::new();
            for (lo, _) in &ds {
                for (_, hi) in &ds {
                    if let Some(hi) = hi {
                        ok.push(lo.le(hi));
                    }
                }
            }
            q.assertions.push(Bool::and(&ok).not());
        }
        _ => return Err(Unsupported("an [AGCOMP] obligation split into a part of another kind".into())),
    }
    Ok(())
}

/// Inputs read the state of the participant they are connected to, when it moves in
/// the same joint motion.
pub(super) fn connect(q: &mut Query, insts: &mut [Inst]) {
    let prog = q.enc.prog();
    let mut eqs = Vec::new();
    for a in insts.iter() {
        for (i, src) in prog.role(a.role).input_sources.iter().enumerate() {
            let Some(src) = src else { continue };
            let Some(b) = insts.iter().find(|b| b.role == *src) else { continue };
            let name = &prog.kind_of(a.role).inputs[i].0;
            let Some((slot, _)) = prog.kind_of(*src).slot(name) else { continue };
            if let (Some(x), Some(y)) = (a.frame.own.get(&Slot::Input(i)), b.frame.own.get(&slot)) {
                eqs.extend(x.equals(y));
            }
        }
    }
    q.assertions.extend(eqs);
}
