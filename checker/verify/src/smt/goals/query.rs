//! The query of each part: hypotheses (the context Σ, sliced to the cone of influence of
//! what the part is about), the instances of the motions involved ([`super::motion`]) and
//! the negated goal. [T-SESS]'s first footprints, separation's runs, the partition's
//! regions, the primitives' contracts (Def 4.11: each can end) and the reachability
//! questions are built here; [AGCOMP]'s and refinement's parts in their modules.

use super::super::encode::Encoder;
use super::super::encode::{zero, Frame, Unsupported};
use super::agcomp::compat;
use super::frames::{to_local, world_point};
use super::motion::{ends, Inst};
use super::refine::refine;
use super::{Part, Query};
// The helpers every part's query uses, for the goals of `geo` too.
pub(super) use super::hyps;
use crate::hir::{Expr, Footprint, PrimApp, Program, Var};
use crate::obligation::{Goal, Obligation};
use crate::sigma::cone::vars_of;
pub(super) use crate::sigma::cone::{seeds_of, slice};
use z3::ast::{Bool, Real};

/// Builds the query of one part.
pub fn build<'p>(prog: &'p Program, ob: &Obligation, part: &Part) -> Result<Query<'p>, Unsupported> {
    build_with(Encoder::new(prog), ob, part)
}

/// The query of one part with the payload floats it chooses restricted to integers
/// ([`Encoder::with_integer_witnesses`]): a stronger question, whose unsat answer proves
/// the part. `None` when the part chooses no float (the query would be the same).
pub fn build_integer_witnesses<'p>(
    prog: &'p Program,
    ob: &Obligation,
    part: &Part,
) -> Option<Result<Query<'p>, Unsupported>> {
    let q = build_with(Encoder::with_integer_witnesses(prog), ob, part);
    match &q {
        Ok(q) if !q.enc.chose_floats() => None,
        _ => Some(q),
    }
}

fn build_with<'p>(enc: Encoder<'p>, ob: &Obligation, part: &Part) -> Result<Query<'p>, Unsupported> {
    let prog = enc.prog();
    let mut q = Query { enc, assertions: Vec::new(), point: None, times: Vec::new() };
    match (&ob.goal, part) {
        (Goal::Valid(goal), Part::Valid) => {
            let seeds = vars_of(prog, [goal]);
            hyps(&mut q, &slice(prog, &ob.hyps, seeds))?;
            let g = q.enc.boolean(goal)?;
            q.assertions.push(g.not());
        }
        (Goal::Valid(goal), Part::Conjunct(k)) => {
            let c = goal.conjuncts()[*k];
            hyps(&mut q, &slice(prog, &ob.hyps, vars_of(prog, [c])))?;
            let g = q.enc.boolean(c)?;
            q.assertions.push(g.not());
        }
        (Goal::Progress { branches }, Part::Valid) => {
            let seeds =
                vars_of(prog, branches.iter().flat_map(|b| b.guard.iter().chain(std::iter::once(&b.refinement))));
            hyps(&mut q, &slice(prog, &ob.hyps, seeds))?;
            let mut some = Vec::new();
            for b in branches {
                some.push(super::progress::enabled(&mut q.enc, b)?);
            }
            q.assertions.push(Bool::or(&some).not());
        }
        // Σ alone, whatever the goal (the vacuity guard; a stuck motion).
        (_, Part::Context) => hyps(&mut q, &context_of(prog, ob))?,
        (Goal::Compatible { parts }, _) => compat(&mut q, &ob.hyps, parts, part)?,
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let (x, y) = (&sides[*a].runs[*ra], &sides[*b].runs[*rb]);
            let p = world_point(&mut q);
            let mut times = Vec::new();
            for (run, tag) in [(x, "t1"), (y, "t2")] {
                hyps(&mut q, &slice(prog, &run.hyps, seeds_of(prog, &[(run.role, run.app.clone())])))?;
                let t = q.enc.named_real(if tag == "t1" { "time 1" } else { "time 2" });
                let inst = Inst::new(&mut q.enc, run.role, &run.app, t.clone(), tag)?;
                inst.started(&mut q)?;
                inst.running(&mut q)?;
                inst.occupies(&mut q, &p)?;
                times.push(t);
            }
            q.point = Some(p);
            q.times = times;
        }
        (Goal::Separated { .. }, Part::RegionsApart(a, b)) => {
            let p = world_point(&mut q);
            let regions = &prog.partition(ob.span).ok_or_else(|| Unsupported("a partition".into()))?.regions;
            let frame = Frame { point: Some(p.clone()), ..Frame::default() };
            for i in [*a, *b] {
                let r = q.enc.in_frame(&frame, |enc| enc.boolean(&regions[i]))?;
                q.assertions.push(r);
            }
            q.point = Some(p);
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => {
            let run = &sides[*a].runs[*ra];
            let regions = &prog.partition(ob.span).ok_or_else(|| Unsupported("a partition".into()))?.regions;
            hyps(&mut q, &slice(prog, &run.hyps, seeds_of(prog, &[(run.role, run.app.clone())])))?;
            let p = world_point(&mut q);
            let t = q.enc.named_real("time");
            let inst = Inst::new(&mut q.enc, run.role, &run.app, t.clone(), "t")?;
            inst.started(&mut q)?;
            inst.running(&mut q)?;
            inst.occupies(&mut q, &p)?;
            let frame = Frame { point: Some(p.clone()), ..Frame::default() };
            let r = q.enc.in_frame(&frame, |enc| enc.boolean(&regions[*a]))?;
            q.assertions.push(r.not());
            q.point = Some(p);
            q.times = vec![t];
        }
        (Goal::Refines { role, concrete, abstract_ }, Part::Refine(item)) => {
            refine(&mut q, *role, concrete, abstract_, *item)?
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => {
            let mut involved = Vec::new();
            for (role, apps) in [&firsts[*r], &firsts[*s]] {
                involved.extend(apps.iter().map(|a| (*role, a.clone())));
            }
            hyps(&mut q, &slice(prog, &ob.hyps, seeds_of(prog, &involved)))?;
            let p = world_point(&mut q);
            let zero = zero();
            let mut any = Vec::new();
            for (role, apps) in [&firsts[*r], &firsts[*s]] {
                // Whichever first motion the participant takes, it starts inside it.
                let mut inside = Vec::new();
                let mut solid = None;
                for app in apps {
                    let inst = Inst::new(&mut q.enc, *role, app, zero.clone(), "0")?;
                    let fp = match &inst.prim.footprint {
                        // The footprint's predicate; all space is `true`, exact (Def 3.4)
                        // and the worst case here (a larger footprint only makes two meet).
                        Footprint::Everywhere | Footprint::Predicate(_) | Footprint::Shapes { .. } => {
                            inst.footprint(&mut q.enc, &p)?
                        }
                        // No predicate: the robot is placed by its body below instead.
                        Footprint::Solid { .. } => {
                            solid = Some(inst.prim);
                            Bool::from_bool(true)
                        }
                    };
                    let start_is_now = inst.at_start();
                    inside.push(Bool::and(&[fp, start_is_now]));
                }
                if let (Some(prim), Some(app)) = (solid, apps.first()) {
                    // The robot at time 0 is its kind's body placed by the start state,
                    // which lies in every first footprint (E0512 asks it of each).
                    let inst = Inst::new(&mut q.enc, *role, app, zero.clone(), "0")?;
                    let body = initial_body(&mut q.enc, &inst, prim, &p)?;
                    inside.push(Bool::and(&[body, inst.at_start()]));
                }
                // Each first footprint contains the robot at time 0, so the robot lies in
                // their intersection (not merely their union).
                any.push(Bool::and(&inside));
            }
            q.assertions.extend(any);
            q.point = Some(p);
        }
        (Goal::Reachable { before, .. }, Part::Before(k)) => {
            hyps(&mut q, before.get(*k).map(Vec::as_slice).unwrap_or_default())?
        }
        (Goal::CanEnd { prim }, Part::Realisable) => {
            // Some arguments, start state and time: every parameter is free.
            let prog = q.enc.prog();
            let p = prog.prim(*prim);
            // Read in the frame of some participant of the kind (the driver asks only
            // about kinds that have one): its name shows in the counterexample.
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let Some(role) = role else { return Err(Unsupported("a primitive of a kind no participant has".into())) };
            let app = PrimApp { prim: *prim, args: Vec::new(), loc: Default::default() };
            let t = q.enc.named_real("time");
            let mut inst = Inst::new(&mut q.enc, role, &app, t.clone(), "t")?;
            inst.frame.params = p.params.iter().map(|(n, sort)| q.enc.named(n, sort)).collect::<Result<_, _>>()?;
            ends(&mut q, std::slice::from_ref(&inst), &t)?;
        }
        (Goal::Occupies { prim }, Part::Occupies) => {
            // Some arguments, state and point (in the robot's own frame: a pose only moves
            // it) satisfy the footprint's predicate at time 0. Deliberately weak and cheap:
            // it catches footprints no point satisfies (`false`, contradictory bounds).
            let prog = q.enc.prog();
            let p = prog.prim(*prim);
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let Some(role) = role else { return Err(Unsupported("a primitive of a kind no participant has".into())) };
            let fp = match &p.footprint {
                Footprint::Predicate(fp) => fp.clone(),
                // Planned for predicates only (library::contracts): a body of shapes of
                // positive sizes (E0511) or a mesh or URDF holds a point by construction,
                // and all space holds every point. Asked anyway: the empty question.
                Footprint::Everywhere | Footprint::Shapes { .. } | Footprint::Solid { .. } => {
                    q.assertions.push(Bool::from_bool(true));
                    return Ok(q);
                }
            };
            let app = PrimApp { prim: *prim, args: Vec::new(), loc: Default::default() };
            let mut inst = Inst::new(&mut q.enc, role, &app, zero(), "t")?;
            inst.frame.params = p.params.iter().map(|(n, sort)| q.enc.named(n, sort)).collect::<Result<_, _>>()?;
            let local = [q.enc.named_real("point.x"), q.enc.named_real("point.y"), q.enc.named_real("point.z")];
            let frame = Frame { point: Some(local.clone()), ..inst.frame.clone() };
            let holds = inst.pred(&mut q.enc, &fp.pred, &frame)?;
            q.assertions.push(holds);
        }
        (Goal::Contains { prim }, Part::Contains(k)) => {
            // Some arguments, start, time and state the contract allows, and a point of
            // body part `k` (in the robot's own frame, placed by the state at that time)
            // outside the footprint. Footprint and body are both in the participant's frame,
            // so its pose plays no part.
            let prog = q.enc.prog();
            let p = prog.prim(*prim);
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let Some(role) = role else { return Err(Unsupported("a primitive of a kind no participant has".into())) };
            let fp = match &p.footprint {
                Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => fp.clone(),
                // Planned only when the footprint has a predicate (goals::plan decides
                // the other kinds without a query, or reports them unknown).
                Footprint::Everywhere | Footprint::Solid { .. } => {
                    return Err(Unsupported(format!("the footprint of `{}`, which has no predicate", p.name)))
                }
            };
            let body = prog.kind(p.kind).body.as_ref().ok_or_else(|| Unsupported("a kind with no body".into()))?;
            let part = body.parts.get(*k).ok_or_else(|| Unsupported("a body part out of range".into()))?;
            let one = crate::hir::body::Body { parts: vec![part.clone()], span: part.span };
            let point = [0, 1, 2].map(|i| crate::hir::Expr {
                kind: crate::hir::ExprKind::Var(crate::hir::Var::Point(i)),
                sort: crate::hir::Sort::Real,
                loc: Default::default(),
            });
            let region = crate::space::region::region(prog, &one, &point)
                .ok_or_else(|| Unsupported("a URDF or mesh body, which the SMT solver cannot represent".into()))?;
            let app = PrimApp { prim: *prim, args: Vec::new(), loc: Default::default() };
            let t = q.enc.named_real("time");
            let mut inst = Inst::new(&mut q.enc, role, &app, t.clone(), "t")?;
            inst.frame.params = p.params.iter().map(|(n, sort)| q.enc.named(n, sort)).collect::<Result<_, _>>()?;
            inst.started(&mut q)?;
            inst.running(&mut q)?;
            let local = [q.enc.named_real("point.x"), q.enc.named_real("point.y"), q.enc.named_real("point.z")];
            let frame = Frame { point: Some(local.clone()), ..inst.frame.clone() };
            let inside = inst.pred(&mut q.enc, &region, &frame)?;
            let covered = inst.pred(&mut q.enc, &fp.pred, &frame)?;
            q.assertions.push(inside);
            q.assertions.push(covered.not());
            q.point = Some(local);
            q.times = vec![t];
        }
        _ => return Err(Unsupported("an obligation split into a part of another kind".into())),
    }
    Ok(q)
}

/// "The world point `p` is in the body of `inst`'s participant now" (its kind's
/// `geometry:`), for [T-SESS] when a first footprint (`prim`'s) has no predicate. Unknown
/// when the kind has no body, or one with a URDF or mesh part (the geometric procedure
/// takes those), rather than reading the footprint as all space.
fn initial_body(
    enc: &mut Encoder,
    inst: &Inst,
    prim: &crate::hir::Primitive,
    p: &[Real; 3],
) -> Result<Bool, Unsupported> {
    let prog = enc.prog();
    let point = [0, 1, 2].map(|i| Expr {
        kind: crate::hir::ExprKind::Var(Var::Point(i)),
        sort: crate::hir::Sort::Real,
        loc: Default::default(),
    });
    let region = prog
        .kind(inst.prim.kind)
        .body
        .as_ref()
        .and_then(|b| crate::space::region::region(prog, b, &point))
        .ok_or_else(|| Unsupported(format!(
            "a first footprint with a URDF or mesh part (that of `{}`) of a robot kind with no `geometry:` of shapes to place the robot at the start",
            prim.name
        )))?;
    let local = to_local(enc, inst.role, p)?;
    let frame = Frame { point: Some(local), ..inst.frame.clone() };
    inst.pred(enc, &region, &frame)
}

/// The hypotheses a proof of `ob` rests on, for the vacuity guard: for a validity goal
/// the slice its parts use (each conjunct's cone of influence lies within the goal's),
/// otherwise all of them. The proof is vacuous iff these are unsatisfiable.
pub fn context_of(prog: &Program, ob: &Obligation) -> Vec<Expr> {
    match &ob.goal {
        Goal::Valid(goal) => slice(prog, &ob.hyps, vars_of(prog, [goal])),
        Goal::Progress { branches } => slice(
            prog,
            &ob.hyps,
            vars_of(prog, branches.iter().flat_map(|b| b.guard.iter().chain(std::iter::once(&b.refinement)))),
        ),
        _ => ob.hyps.clone(),
    }
}
