//! From obligations to satisfiability queries: the plan. Each [`Goal`] splits into
//! [`Part`]s, one query each, so that a failure names exactly what failed (an assumption,
//! two footprints, a duration). A part holds iff its query is unsatisfiable (but for the
//! sat questions, [`Part::is_sat_question`]); a plan may also settle an obligation without
//! a query ([`Plan::Holds`], [`Plan::Fails`]).
//!
//! The rules, one module each: [AGCOMP] (Sec 3.4) in [`agcomp`], refinement (Def 3.4,
//! corrected direction) in [`refine`], separation (Sec 4.1, full separation) and [T-SESS]'s
//! initial states by boxes in [`boxes`]. How a participant running a primitive is encoded
//! is [`motion`]'s, the participant's frame (its pose) [`frames`]'s, the query of each part
//! and the slicing of Σ [`query`]'s, and the cheap satisfiability test without Z3
//! [`candidate`]'s.

mod agcomp;
mod boxes;
mod candidate;
mod frames;
pub mod geo;
mod motion;
mod progress;
mod query;
mod refine;
pub mod witness;

use super::encode::{Encoder, Unsupported};
use crate::hir::Program;
use crate::obligation::{Goal, Obligation};
use z3::ast::{Bool, Real};

pub use boxes::{run_box, side_boxes};
pub use candidate::witnessed;
pub use query::{build, build_integer_witnesses, context_of};
pub use refine::RefineItem;
// For `witness`, which encodes the same motions for the simulator.
use agcomp::connect;
use frames::world_point;
use motion::Inst;

/// One question about an obligation.
#[derive(Clone, Debug, PartialEq)]
pub enum Part {
    /// `hyps ⇒ goal`.
    Valid,
    /// [AGCOMP] "compatible from Pre": part `i`'s precondition holds at the `dt`.
    Pre(usize),
    /// The joint motion can end (a **sat** question; see [`Part::is_sat_question`]):
    /// from Σ and every part's precondition, some time `t` in every part's duration and
    /// an end state of every part at which its guarantee (at 0 and at `t`), its
    /// postcondition and its kind's invariant hold together, inputs reading their
    /// sources' end states ([M-PAR], [NON-INTERRUPT], [INTERRUPT], Def 4.11 (5), (8)).
    CanEnd,
    /// The joint motion can start: Σ and every part's precondition and invariant are
    /// consistent (a sat question, asked when it cannot end: a precondition that
    /// contradicts a satisfiable context is [AGCOMP]'s pre part's or [T-MOTION]'s to
    /// report).
    CanStart,
    /// The obligation's hypotheses alone are satisfiable (a sat question): asked when a
    /// joint motion cannot end, to tell a stuck motion from an unreachable point, and
    /// for [`Goal::Reachable`].
    Context,
    /// [`Goal::Reachable`]: the context before the step (its `k`-th) is satisfiable.
    Before(usize),
    /// [`Goal::CanEnd`]: the declared primitive admits a run that ends.
    Realisable,
    /// [`Goal::Occupies`]: the primitive's footprint holds some point when it starts (a footprint no point satisfies would make
    /// every collision check about it hold vacuously).
    Occupies,
    /// [`Goal::Contains`]: part `k` of the kind's body lies in the footprint.
    Contains(usize),
    /// Conjunct `k` of a `Valid` goal.
    Conjunct(usize),
    /// [AGCOMP]: the others' guarantees discharge part `i`'s assumption.
    Assume(usize),
    /// [AGCOMP]: the footprints of parts `i` and `j` are disjoint at every time.
    Disjoint(usize, usize),
    /// [AGCOMP] with the system's static obstacles: part `i`'s footprint never meets
    /// obstacle `o` (`Program::obstacles`).
    ClearOf { i: usize, o: usize },
    /// [AGCOMP]: the non-interruptible part `i`'s duration lies within part `j`'s.
    Within(usize, usize),
    /// Joint end (ARCHITECTURE.md): the non-interruptible parts `i` and `j` end at one
    /// common time, forced by their durations: `Σ ∧ Pre ⇒ lo_i = hi_i = lo_j = hi_j`.
    CommonEnd(usize, usize),
    /// [AGCOMP] with no non-interruptible part: the durations share a time.
    Meet,
    /// Separation: run `ra` of side `a` and run `rb` of side `b` never overlap.
    Apart { a: usize, ra: usize, b: usize, rb: usize },
    /// Def 3.4 (corrected direction), one item.
    Refine(RefineItem),
    /// [T-SESS]: the first motions of `r` and `s` start with disjoint footprints.
    InitiallyApart { r: usize, s: usize },
    /// A written partition: the regions of sides `a` and `b` are disjoint.
    RegionsApart(usize, usize),
    /// A written partition: run `ra` of side `a` stays in the side's region.
    InRegion { a: usize, ra: usize },
}

impl Part {
    /// Parts that must be satisfiable (a model is the witness) rather than unsat.
    pub fn is_sat_question(&self) -> bool {
        matches!(
            self,
            Part::CanEnd
                | Part::CanStart
                | Part::Context
                | Part::Before(_)
                | Part::Realisable
                | Part::Occupies
                | Part::Refine(RefineItem::Realisable)
        )
    }
}

/// A query: the part holds iff `assertions` (with the encoder's side conditions) are
/// unsatisfiable. `point` and `times` name the variables of an overlap, if any.
pub struct Query<'p> {
    pub enc: Encoder<'p>,
    pub assertions: Vec<Bool>,
    pub point: Option<[Real; 3]>,
    pub times: Vec<Real>,
}

/// What an obligation splits into; an `Err` settles it without a solver.
pub enum Plan {
    Parts(Vec<Part>),
    /// Decided without a query (for example separation by boxes), with a note.
    Holds(Option<String>),
    /// Fails without a query, with the reason.
    Fails(String),
    Unknown(Unsupported),
    /// Undecided by a procedure other than the SMT encoding (the interval search of
    /// `space::enclose` or `space::contain`), with its reason.
    Undecided(super::Why),
}

pub fn plan(prog: &Program, ob: &Obligation) -> Plan {
    match &ob.goal {
        Goal::Valid(e) => {
            // One part per conjunct, so that a failure names the conjunct that fails.
            let n = e.conjuncts().len();
            Plan::Parts(if n > 1 { (0..n).map(Part::Conjunct).collect() } else { vec![Part::Valid] })
        }
        Goal::Compatible { parts } => agcomp::plan(prog, &ob.hyps, parts),
        Goal::Separated { sides } => match prog.partition(ob.span) {
            Some(p) if p.regions.len() == sides.len() => {
                let mut parts = Vec::new();
                for a in 0..sides.len() {
                    for b in a + 1..sides.len() {
                        parts.push(Part::RegionsApart(a, b));
                    }
                    parts.extend((0..sides[a].runs.len()).map(|ra| Part::InRegion { a, ra }));
                }
                Plan::Parts(parts)
            }
            Some(_) => Plan::Fails("the partition does not have one region per side".into()),
            None => boxes::separation_plan(prog, sides),
        },
        Goal::Refines { concrete, abstract_, .. } => refine::plan(prog, concrete, abstract_),
        Goal::InitiallyDisjoint { firsts } => boxes::initially_disjoint(prog, ob, firsts),
        Goal::Occupies { .. } => Plan::Parts(vec![Part::Occupies]),
        Goal::CanEnd { .. } => Plan::Parts(vec![Part::Realisable]),
        Goal::Reachable { .. } => Plan::Parts(vec![Part::Context]),
        Goal::Progress { .. } => Plan::Parts(vec![Part::Valid]),
        Goal::Contains { prim } => {
            let p = prog.prim(*prim);
            let n = prog.kind(p.kind).body.as_ref().map_or(0, |b| b.parts.len());
            match &p.footprint {
                // All space contains every body; `footprint: geometry` is the body itself.
                crate::hir::Footprint::Everywhere => Plan::Holds(Some("the footprint is all space".into())),
                f if f.is_own_geometry() => Plan::Holds(Some("the footprint is the robot's own geometry".into())),
                // A predicate that turns with the state (its `cos`/`sin`, or the body's) is
                // decided first by the interval search of `space::enclose` with a small
                // budget, then by Z3 (`Worker::contains_turning` orders the engines).
                // A body with a URDF or mesh part (no predicate for Z3): those parts are
                // decided by the interval search against stand-ins (`space::enclose::solid`),
                // the others by Z3.
                crate::hir::Footprint::Predicate(_) | crate::hir::Footprint::Shapes { .. } => {
                    use crate::space::enclose::{solid_parts_in_predicate, Solids};
                    match solid_parts_in_predicate(prog, *prim) {
                        None => Plan::Parts((0..n).map(Part::Contains).collect()),
                        Some((Solids::Fails(why), _)) => Plan::Fails(why),
                        Some((Solids::Unknown(why), _)) => Plan::Undecided(super::Why::Interval(format!(
                            "branch and bound over the state and stand-ins for the body's solids, and no SMT query can decide it: a URDF or mesh body in the predicate footprint of `{}`: {why}",
                            p.name
                        ))),
                        Some((Solids::Holds(note), others)) if others.is_empty() => Plan::Holds(Some(note)),
                        Some((Solids::Holds(_), others)) => {
                            Plan::Parts(others.into_iter().map(Part::Contains).collect())
                        }
                    }
                }
                // No predicate: decided by the solids when each part of the body lies in a
                // part of the footprint placed the same way, else unknown.
                crate::hir::Footprint::Solid { .. } => {
                    match crate::space::contain::body_within_footprint(prog, *prim) {
                        crate::space::contain::Contained::Yes(note) => Plan::Holds(Some(note)),
                        crate::space::contain::Contained::No(why) => Plan::Fails(why),
                        crate::space::contain::Contained::Unknown(why) => {
                            Plan::Undecided(super::Why::Interval(format!(
                        "branch and bound over the state and stand-ins for the body's solids, and no SMT query can decide it: a footprint with a URDF or mesh part (that of `{}`) as a container of the robot's body: {why}",
                        p.name
                    )))
                        }
                    }
                }
            }
        }
    }
}

/// Assumes the facts `hs` in the query `q`.
pub(super) fn hyps(q: &mut Query, hs: &[crate::hir::Expr]) -> Result<(), super::encode::Unsupported> {
    for h in hs {
        let b = q.enc.assumed(|enc| enc.boolean(h))?;
        q.assertions.push(b);
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::hir::{PrimApp, RoleId};
    use crate::obligation::Rule;

    /// Lowers `src` (which must be clean) and gives its program with the [AGCOMP]
    /// obligation of the choreography's first joint motion, from the initial states: every
    /// participant's first primitive is one part.
    pub(crate) fn first_dt(src: &str) -> (Program, Obligation) {
        let (prog, d) = crate::lower::tests::lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let hyps = prog.roles.iter().filter_map(|r| r.init.clone()).collect();
        let parts: Vec<(RoleId, PrimApp)> =
            prog.first_motions().into_iter().filter_map(|(r, apps)| Some((r, apps.first()?.clone()))).collect();
        let ob = Obligation {
            rule: Rule::AgComp,
            span: Default::default(),
            what: "the first joint motion".into(),
            hyps,
            goal: Goal::Compatible { parts },
        };
        (prog, ob)
    }

    /// The parts `plan` gives, or a description of what it decided instead.
    pub(crate) fn parts(prog: &Program, ob: &Obligation) -> Result<Vec<Part>, String> {
        match plan(prog, ob) {
            Plan::Parts(ps) => Ok(ps),
            Plan::Holds(n) => Err(format!("holds ({n:?})")),
            Plan::Fails(why) => Err(format!("fails: {why}")),
            Plan::Unknown(u) => Err(format!("unknown: {}", u.0)),
            Plan::Undecided(why) => Err(format!("unknown: {why}")),
        }
    }

    #[test]
    fn a_valid_goal_has_one_part_per_conjunct() {
        let (prog, g) = crate::lower::tests::first_guard(
            "robot R { state x: real; } system S { participant A: R; participant B: R; }
             choreography G = A -> B : [x >= 0 && x <= 1 && x != 2] go. end;",
        );
        let ob = |goal| Obligation {
            rule: Rule::TOut,
            span: Default::default(),
            what: String::new(),
            hyps: Vec::new(),
            goal: Goal::Valid(goal),
        };
        assert_eq!(parts(&prog, &ob(g.clone())), Ok(vec![Part::Conjunct(0), Part::Conjunct(1), Part::Conjunct(2)]));
        let one = g.conjuncts()[0].clone();
        assert_eq!(parts(&prog, &ob(one)), Ok(vec![Part::Valid]));
    }

    #[test]
    fn sat_questions_are_the_witness_parts() {
        for p in [Part::CanEnd, Part::CanStart, Part::Context, Part::Before(0), Part::Realisable, Part::Occupies] {
            assert!(p.is_sat_question(), "{p:?}");
        }
        for p in [Part::Valid, Part::Pre(0), Part::Disjoint(0, 1), Part::Meet, Part::Refine(RefineItem::Post)] {
            assert!(!p.is_sat_question(), "{p:?}");
        }
        assert!(Part::Refine(RefineItem::Realisable).is_sat_question());
    }
}
