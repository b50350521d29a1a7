//! Refinement (Def 3.4, read in the corrected direction of the seeds' README, item 1): a
//! concrete primitive `c` implements the abstract ones `s` (their meet, Def 4.7) iff
//! `Pre_s ⇒ Pre_c`, `A_s ⇒ A_c`, `G_c ⇒ G_s`, `Post_c ⇒ Post_s`, `FP_c ⊆ FP_s` at every state
//! and time, the interruptibility is the same, and the durations nest (interruptible
//! `D_s ⊆ D_c`, non-interruptible `D_c ⊆ D_s`); and `c` can end from a start `s` allows
//! (otherwise every item holds vacuously). One part per item.

use super::super::encode::{zero, Frame, Unsupported};
use super::frames::world_point;
use super::motion::{end_frame, ends, Inst};
use super::{Part, Plan, Query};
use crate::hir::body::{Body, Shape};
use crate::hir::{Expr, PrimApp, Primitive, Program, RoleId, Var};
use z3::ast::Bool;

/// The parts of a refinement obligation: none for a primitive refining itself, a failure
/// for a change of interruptibility, else one per item of Def 3.4.
pub(super) fn plan(prog: &Program, concrete: &PrimApp, abstract_: &[PrimApp]) -> Plan {
    if abstract_.len() == 1 && abstract_[0] == *concrete {
        return Plan::Holds(None); // a primitive refines itself
    }
    let c = prog.prim(concrete.prim);
    if let Some(s) = abstract_.iter().map(|a| prog.prim(a.prim)).find(|s| s.interruptible != c.interruptible) {
        return Plan::Fails(format!(
            "`{}` is {} but `{}` is {} (Def 3.4: refinement keeps interruptibility)",
            c.name,
            interruptibility(c),
            s.name,
            interruptibility(s)
        ));
    }
    use RefineItem::*;
    let ss: Vec<&Primitive> = abstract_.iter().map(|a| prog.prim(a.prim)).collect();
    let items = [Realisable, Pre, Assume, Guarantee, Post, Footprint, Duration];
    // A footprint item that holds by construction is not asked (see [`within`]).
    let asked = |i: &RefineItem| *i != Footprint || !matches!(within(prog, c, &ss), Within::Holds);
    Plan::Parts(items.into_iter().filter(asked).map(Part::Refine).collect())
}

/// How `FP_c ⊆ FP_s` is decided for the meet of `ss` (the intersection of their
/// footprints), by the kinds of the footprints (hir::Footprint), exhaustively.
#[derive(Debug, PartialEq)]
pub(super) enum Within {
    /// Both sides have predicates (all space is `true`): one query.
    Query,
    /// Holds whatever the state: `c`'s footprint is the kind's body (`footprint:
    /// geometry`) and so is every abstract one that is not all space, read at the same
    /// state and time; or every abstract footprint is all space.
    Holds,
    /// `c` declares no footprint (all space) and some abstract footprint is a body, which
    /// is bounded: fails whenever `c` can run from a start the abstract precondition
    /// allows (the query asks just that; no point is needed).
    AllSpaceInBody,
    /// A side has a URDF or mesh part, whose points the SMT solver cannot enumerate: not
    /// decided (unknown with this reason), never passed.
    Unknown(String),
}

/// Whether two geometric footprints are the same body at every state and time: the same
/// shapes with equal sizes, files and poses, none reading a parameter (the two primitives'
/// arguments differ; the state, `old(...)` and `clock` are shared in a refinement).
fn same_body(prog: &Program, a: &Body, b: &Body) -> bool {
    let no_param = |e: &Expr| !crate::hir::expr::mentions(e, &|v| matches!(v, Var::Param(_)));
    let exprs = |p: &crate::hir::body::BodyPart| -> Vec<Expr> {
        let mut out: Vec<Expr> = match &p.shape {
            Shape::Box(d) => d.to_vec(),
            Shape::Sphere(r) => vec![r.clone()],
            Shape::Cylinder(r, h) | Shape::Capsule(r, h) => vec![r.clone(), h.clone()],
            Shape::Urdf { .. } | Shape::Mesh { .. } => Vec::new(),
        };
        out.extend(p.place.iter().flat_map(|pose| pose.args.iter().cloned()));
        out
    };
    let same_shape = |x: &Shape, y: &Shape| match (x, y) {
        (Shape::Box(_), Shape::Box(_))
        | (Shape::Sphere(_), Shape::Sphere(_))
        | (Shape::Cylinder(..), Shape::Cylinder(..))
        | (Shape::Capsule(..), Shape::Capsule(..)) => true,
        (Shape::Urdf { path: p, .. }, Shape::Urdf { path: q, .. })
        | (Shape::Mesh { path: p, .. }, Shape::Mesh { path: q, .. }) => p == q,
        _ => false,
    };
    a.parts.len() == b.parts.len()
        && a.parts.iter().zip(&b.parts).all(|(x, y)| {
            let (ex, ey) = (exprs(x), exprs(y));
            same_shape(&x.shape, &y.shape)
                && x.place.is_some() == y.place.is_some()
                && ex.len() == ey.len()
                && ex.iter().zip(&ey).all(|(u, v)| crate::bounds::same_value(prog, u, v))
                && ex.iter().all(no_param)
        })
}

pub(super) fn within(prog: &Program, c: &Primitive, ss: &[&Primitive]) -> Within {
    use crate::hir::Footprint as F;
    // The abstract footprints that constrain anything (all space drops out of the meet).
    let bounded: Vec<&&Primitive> = ss.iter().filter(|s| s.footprint.is_declared()).collect();
    if bounded.is_empty() {
        return match &c.footprint {
            F::Everywhere | F::Predicate(_) | F::Shapes { .. } => Within::Query,
            F::Solid { .. } => Within::Holds,
        };
    }
    if c.footprint.is_own_geometry() && bounded.iter().all(|s| s.footprint.is_own_geometry()) {
        return Within::Holds;
    }
    if let Some(cb) = c.footprint.body() {
        if bounded.iter().all(|s| s.footprint.body().is_some_and(|sb| same_body(prog, cb, sb))) {
            return Within::Holds;
        }
    }
    let unknown = |side: &str, p: &Primitive| {
        Within::Unknown(format!(
            "a footprint with a URDF or mesh part (the {side} one, of `{}`), which has no predicate, so whether the footprint of `{}` lies within that of `{}` is not decided; write the footprints as predicates or with boxes, spheres, cylinders and capsules, or both as `footprint: geometry;`",
            p.name,
            c.name,
            bounded.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join("` ∧ `"),
        ))
    };
    if let Some(s) = bounded.iter().find(|s| matches!(s.footprint, F::Solid { .. })) {
        return match &c.footprint {
            F::Everywhere => Within::AllSpaceInBody,
            F::Predicate(_) | F::Shapes { .. } | F::Solid { .. } => unknown("abstract", s),
        };
    }
    match &c.footprint {
        F::Everywhere | F::Predicate(_) | F::Shapes { .. } => Within::Query,
        F::Solid { .. } => unknown("concrete", c),
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefineItem {
    Pre,
    Assume,
    Guarantee,
    Post,
    Footprint,
    Duration,
    /// The concrete primitive admits a run that ends from a start the abstract one
    /// allows (a sat question): otherwise the other items hold vacuously.
    Realisable,
}

impl RefineItem {
    pub fn text(self) -> &'static str {
        match self {
            RefineItem::Pre => "the abstract precondition implies the concrete one",
            RefineItem::Assume => "the abstract assumption implies the concrete one",
            RefineItem::Guarantee => "the concrete guarantee implies the abstract one",
            RefineItem::Post => "the concrete postcondition implies the abstract one",
            RefineItem::Footprint => "the concrete footprint lies within the abstract one",
            RefineItem::Duration => "the durations nest (Def 3.4, corrected)",
            RefineItem::Realisable => {
                "the concrete primitive can end (some time in its duration, an end state meeting its guarantee, postcondition and invariant) from a start the abstract precondition allows; otherwise every other item holds vacuously"
            }
        }
    }
}

pub(super) fn interruptibility(p: &Primitive) -> &'static str {
    if p.interruptible {
        "interruptible"
    } else {
        "non-interruptible"
    }
}

pub(super) fn refine(
    q: &mut Query,
    role: RoleId,
    c: &PrimApp,
    ss: &[PrimApp],
    item: RefineItem,
) -> Result<(), Unsupported> {
    let t = q.enc.named_real("time");
    let ci = Inst::new(&mut q.enc, role, c, t.clone(), "t")?;
    let mut sis = Vec::new();
    for s in ss {
        let mut si = Inst::new(&mut q.enc, role, s, t.clone(), "t")?;
        // The same participant: the abstract primitive reads the same state.
        si.frame.own = ci.frame.own.clone();
        sis.push(si);
    }
    let sf = ci.start_frame();
    // Pre_S of the meet is the disjunction of the abstract preconditions, each read with
    // its own primitive's arguments (the start frame is the concrete primitive's: read with
    // it, `a(k)`'s `s >= k` took the concrete `c(j)`'s argument `j` for `k`, and a refinement
    // that fails from a start only the abstract arguments allow was proved).
    let mut pres = Vec::new();
    for si in &sis {
        let fr = Frame { params: si.frame.params.clone(), args: si.frame.args.clone(), ..sf.clone() };
        pres.push(si.pred(&mut q.enc, &si.prim.pre, &fr)?);
    }
    let pre_s = Bool::or(&pres);
    let all =
        |q: &mut Query, f: &dyn Fn(&Primitive) -> &Expr, frame: &Frame, conj: bool| -> Result<Bool, Unsupported> {
            let mut bs = Vec::new();
            for si in &sis {
                let fr = Frame { params: si.frame.params.clone(), args: si.frame.args.clone(), ..frame.clone() };
                bs.push(si.pred(&mut q.enc, f(si.prim), &fr)?);
            }
            Ok(if conj { Bool::and(&bs) } else { Bool::or(&bs) })
        };
    if let Some(inv) = q.enc.prog().kind(ci.prim.kind).invariant.clone() {
        let b = ci.pred(&mut q.enc, &inv, &sf)?;
        q.assertions.push(b);
    }
    match item {
        RefineItem::Realisable => {
            q.assertions.push(pre_s);
            ends(q, std::slice::from_ref(&ci), &t)?;
        }
        RefineItem::Pre => {
            let pc = ci.pred(&mut q.enc, &ci.prim.pre, &sf)?;
            q.assertions.extend([pre_s, pc.not()]);
        }
        RefineItem::Assume => {
            let a_s = all(q, &|p| &p.assume, &ci.frame, false)?;
            let a_c = ci.pred(&mut q.enc, &ci.prim.assume, &ci.frame)?;
            q.assertions.extend([pre_s, t.ge(zero()), a_s, a_c.not()]);
        }
        RefineItem::Guarantee | RefineItem::Footprint => {
            q.assertions.push(pre_s);
            ci.running(q)?;
            if item == RefineItem::Guarantee {
                let g_s = all(q, &|p| &p.guarantee, &ci.frame, true)?;
                q.assertions.push(g_s.not());
            } else {
                let ss: Vec<&Primitive> = sis.iter().map(|si| si.prim).collect();
                match within(q.enc.prog(), ci.prim, &ss) {
                    Within::Query => {}
                    // Not planned (it holds by construction); the empty question if asked.
                    Within::Holds => {
                        q.assertions.push(Bool::from_bool(false));
                        return Ok(());
                    }
                    // Any run of `c` has points of all space outside the bounded body.
                    Within::AllSpaceInBody => {
                        q.times = vec![t];
                        return Ok(());
                    }
                    Within::Unknown(why) => return Err(Unsupported(why)),
                }
                let p = world_point(q);
                // One participant, one frame: both footprints read the same local point.
                let local = super::frames::to_local(&mut q.enc, role, &p)?;
                let fc = ci.footprint_at(&mut q.enc, &local)?;
                let mut fs = Vec::new();
                for si in &sis {
                    let si_now = Inst { frame: Frame { own: ci.frame.own.clone(), ..si.frame.clone() }, ..si.clone() };
                    fs.push(si_now.footprint_at(&mut q.enc, &local)?);
                }
                q.assertions.extend([fc, Bool::and(&fs).not()]);
                q.point = Some(p);
                q.times = vec![t];
            }
        }
        RefineItem::Post => {
            let end = end_frame(&mut q.enc, &ci)?;
            let pc = ci.pred(&mut q.enc, &ci.prim.post, &end)?;
            let p_s = all(q, &|p| &p.post, &end, true)?;
            if let Some(inv) = q.enc.prog().kind(ci.prim.kind).invariant.clone() {
                let b = ci.pred(&mut q.enc, &inv, &end)?;
                q.assertions.push(b);
            }
            q.assertions.extend([pre_s, pc, p_s.not()]);
        }
        RefineItem::Duration => {
            q.assertions.push(pre_s);
            let (clo, chi) = ci.duration(&mut q.enc)?;
            // The meet's duration is the intersection of the abstract ones.
            let mut nested = Vec::new();
            for si in &sis {
                let si_start = Inst { frame: Frame { own: ci.start.clone(), ..si.frame.clone() }, ..si.clone() };
                let (slo, shi) = si_start.duration(&mut q.enc)?;
                let (outer_lo, outer_hi, inner_lo, inner_hi) = if ci.prim.interruptible {
                    (clo.clone(), chi.clone(), slo, shi) // D_s ⊆ D_c
                } else {
                    (slo, shi, clo.clone(), chi.clone()) // D_c ⊆ D_s
                };
                let hi_ok = match (inner_hi, outer_hi) {
                    (_, None) => Bool::from_bool(true),
                    (Some(i), Some(o)) => i.le(&o),
                    (None, Some(_)) => Bool::from_bool(false),
                };
                nested.push(Bool::and(&[outer_lo.le(&inner_lo), hi_ok]));
            }
            q.assertions.push(Bool::and(&nested).not());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::super::{discharge, Decision, SmtConfig};
    use super::super::tests::parts;
    use super::super::{Part, RefineItem};
    use crate::hir::{PrimApp, PrimId, Program};
    use crate::obligation::{Goal, Obligation, Rule};

    /// Does `concrete` refine `abstract_`? Both primitives of `R`, with state `x` in
    /// [0, 10] (the participant starts at 1).
    fn refines(prims: &str, concrete: &str, abstract_: &str) -> (Program, Obligation) {
        let src = format!(
            "robot R {{ state x: real; invariant: 0 <= x <= 10; }} {prims}
             system S {{ participant A: R {{ init: x == 1; }} }} choreography G = dt<A: wait>. end;"
        );
        let (prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let ob = refinement(&prog, concrete, abstract_);
        (prog, ob)
    }

    /// The refinement obligation of the only participant: `concrete` (by name) refines
    /// `abstract_`, under the participants' `init`s.
    fn refinement(prog: &Program, concrete: &str, abstract_: &str) -> Obligation {
        let app = |name: &str| {
            let i = prog.prims.iter().position(|p| p.name == name).expect("a primitive");
            PrimApp { prim: PrimId(i as u32), args: Vec::new(), loc: Default::default() }
        };
        let role = prog.role_ids().next().expect("a participant");
        Obligation {
            rule: Rule::Refinement,
            span: Default::default(),
            what: "refinement".into(),
            hyps: prog.roles.iter().filter_map(|r| r.init.clone()).collect(),
            goal: Goal::Refines { role, concrete: app(concrete), abstract_: vec![app(abstract_)] },
        }
    }

    const PRIMS: &str = "
        motion R.slow { interruptible: false; guarantee: x == old(x); duration: [2, 2]; }
        motion R.spec { interruptible: false; guarantee: x >= old(x) - 1; duration: [1, 3]; }
        motion R.wait { interruptible: true; duration: [0, inf]; }";

    #[test]
    fn a_refinement_plans_one_part_per_item_of_def_3_4() {
        let (prog, ob) = refines(PRIMS, "slow", "spec");
        let expected: Vec<Part> = [
            RefineItem::Realisable,
            RefineItem::Pre,
            RefineItem::Assume,
            RefineItem::Guarantee,
            RefineItem::Post,
            RefineItem::Footprint,
            RefineItem::Duration,
        ]
        .into_iter()
        .map(Part::Refine)
        .collect();
        assert_eq!(parts(&prog, &ob), Ok(expected));
        // A primitive refines itself without a question; interruptibility must match.
        let (prog, ob) = refines(PRIMS, "slow", "slow");
        assert_eq!(parts(&prog, &ob), Err("holds (None)".into()));
        let (prog, ob) = refines(PRIMS, "wait", "spec");
        assert!(parts(&prog, &ob).is_err_and(|e| e.contains("interruptib")));
    }

    /// Refinements between footprints of each kind, `R` with a mesh body.
    const GEOMETRIC: &str = "
        motion R.mesh { interruptible: true; footprint: mesh(\"gear.stl\") at pose(x, 0, 0); duration: [0, inf]; }
        motion R.own { interruptible: true; footprint: geometry; duration: [0, inf]; }
        motion R.own2 { interruptible: true; footprint: geometry; guarantee: x == old(x); duration: [0, inf]; }
        motion R.wide { interruptible: true; footprint(px, py, pz): px^2 + py^2 + pz^2 <= 100; duration: [0, inf]; }
        motion R.all { interruptible: true; duration: [0, inf]; }
        motion R.mesh2 { interruptible: true; guarantee: x == old(x); footprint: mesh(\"gear.stl\") at pose(x, 0, 0); duration: [0, inf]; }
        motion R.moved(d: real) { interruptible: true; footprint: mesh(\"gear.stl\") at pose(x + d, 0, 0); duration: [0, inf]; }";

    #[test]
    fn a_footprint_without_a_predicate_is_never_read_as_all_space() {
        let src = format!(
            "robot R {{ state x: real; invariant: 0 <= x <= 10; geometry: mesh(\"gear.stl\"); }} {GEOMETRIC}
             system S {{ participant A: R {{ init: x == 1; }} }} choreography G = dt<A: all>. end;"
        );
        let (prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let decide = |c: &str, s: &str| {
            let ob = refinement(&prog, c, s);
            let planned = parts(&prog, &ob);
            let decision = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0;
            (planned, decision)
        };
        // A 10 m ball within a mesh: not decided (the mesh has no predicate), never passed.
        let (_, d) = decide("wide", "mesh");
        let Decision::Unknown { part, why } = d else { panic!("unknown, not {d:?}") };
        assert!(part.contains("footprint"), "{part}");
        assert!(format!("{why:?}").contains("URDF or mesh"), "{why:?}");
        let (_, d) = decide("mesh", "wide");
        assert!(matches!(d, Decision::Unknown { .. }), "{d:?}");
        // All space is not within a body, which is bounded.
        let (_, d) = decide("all", "mesh");
        let Decision::Fails(f) = d else { panic!("fails, not {d:?}") };
        assert_eq!(f.which, Some(Part::Refine(RefineItem::Footprint)));
        // Anything lies within all space; the robot's own geometry within itself.
        let (planned, d) = decide("mesh", "all");
        assert!(planned.is_ok_and(|p| !p.contains(&Part::Refine(RefineItem::Footprint))));
        assert!(matches!(d, Decision::Holds(_)), "{d:?}");
        let (planned, d) = decide("own", "own2");
        assert!(planned.is_ok_and(|p| !p.contains(&Part::Refine(RefineItem::Footprint))));
        assert!(matches!(d, Decision::Fails(_)), "own's guarantee is weaker than own2's: {d:?}");
        let (planned, _) = decide("own2", "own");
        assert!(planned.is_ok_and(|p| !p.contains(&Part::Refine(RefineItem::Footprint))));
        // The same mesh placed by the same pose; one placed by a parameter is not compared.
        let (planned, d) = decide("mesh2", "mesh");
        assert!(planned.is_ok_and(|p| !p.contains(&Part::Refine(RefineItem::Footprint))));
        assert!(matches!(d, Decision::Holds(_)), "{d:?}");
        let (_, d) = decide("moved", "moved");
        assert!(matches!(d, Decision::Holds(_)), "a primitive refines itself: {d:?}");
        let prim = |n: &str| prog.prims.iter().find(|p| p.name == n).expect("a primitive");
        assert!(matches!(super::within(&prog, prim("mesh"), &[prim("moved")]), super::Within::Unknown(_)));
        assert_eq!(super::within(&prog, prim("mesh"), &[prim("mesh2")]), super::Within::Holds);
    }

    #[test]
    fn durations_nest_in_the_corrected_direction() {
        // Non-interruptible: the concrete duration [2, 2] lies within the abstract [1, 3].
        let (prog, ob) = refines(PRIMS, "slow", "spec");
        assert_eq!(discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0, Decision::Holds(None));
        // The other way round it does not: [1, 3] is not within [2, 2].
        let (prog, ob) = refines(PRIMS, "spec", "slow");
        let Decision::Fails(f) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 else {
            panic!("spec does not refine slow")
        };
        assert!(matches!(f.which, Some(Part::Refine(RefineItem::Guarantee | RefineItem::Duration))), "{f:?}");
    }

    /// Each item of Def 3.4 in the corrected direction, on its own: a concrete primitive
    /// that differs from `base` only in that item, the right way, refines it (a weaker
    /// precondition, a stronger guarantee, a smaller footprint, a stronger postcondition, a
    /// shorter non-interruptible duration within the abstract one); its twin that differs
    /// the wrong way does not, and the failing part is that item.
    #[test]
    fn each_item_refines_in_the_corrected_direction_and_its_twin_does_not() {
        let base = "pre: x >= 0.5; guarantee: x >= old(x) - 0.5; post: x >= 1; \
                    footprint(px, py, pz): px^2 + py^2 + pz^2 <= 4; duration: [1, 3];";
        let cases = [
            (RefineItem::Pre, ("pre: x >= 0.5;", "pre: x >= 0;"), "pre: x >= 2;"),
            (
                RefineItem::Guarantee,
                ("guarantee: x >= old(x) - 0.5;", "guarantee: x >= old(x);"),
                "guarantee: x >= old(x) - 1;",
            ),
            (
                RefineItem::Footprint,
                ("footprint(px, py, pz): px^2 + py^2 + pz^2 <= 4;", "footprint(px, py, pz): px^2 + py^2 + pz^2 <= 1;"),
                "footprint(px, py, pz): px^2 + py^2 + pz^2 <= 9;",
            ),
            (RefineItem::Post, ("post: x >= 1;", "post: x >= 1.5;"), "post: x >= 0.5;"),
            (RefineItem::Duration, ("duration: [1, 3];", "duration: [1.5, 2.5];"), "duration: [0.5, 3];"),
        ];
        for (item, (old, good), bad) in cases {
            let prims = format!(
                "motion R.base {{ interruptible: false; {base} }}
                 motion R.good {{ interruptible: false; {} }}
                 motion R.bad {{ interruptible: false; {} }}
                 motion R.wait {{ interruptible: true; duration: [0, inf]; }}",
                base.replace(old, good),
                base.replace(old, bad)
            );
            let (prog, ob) = refines(&prims, "good", "base");
            let d = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0;
            assert_eq!(d, Decision::Holds(None), "{item:?}: {good} refines {old}");
            let (prog, ob) = refines(&prims, "bad", "base");
            let Decision::Fails(f) = discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0 else {
                panic!("{item:?}: {bad} does not refine {old}")
            };
            assert_eq!(f.which, Some(Part::Refine(item)), "{item:?}: {f:?}");
        }
    }
}
