//! Proof obligations: the predicate side conditions that the structural checks meet
//! and cannot decide themselves. Each names the rule that produced it and the source
//! span it comes from. The SMT stage (`mochi_verify::smt::discharge`) decides them, after
//! [`Obligation::trivially_holds`] has settled the syntactically trivial ones; what it
//! cannot decide is reported as undecided (`unknown`), never as passed.

use crate::hir::{Expr, ExprKind, PrimApp, PrimId, RoleId, Sort, ValueId};
use crate::source::Span;
use serde::Serialize;

/// The rule of the paper an obligation comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Rule {
    /// Def 4.4 (1): the guards of a choice cover every state.
    TotalChoice,
    /// [AGCOMP] (Sec 3.4) and Def 4.4 (3): a joint motion is compatible.
    AgComp,
    /// Sec 4.1: the footprints of the two sides of `*` are separated.
    FullSeparation,
    /// Def 3.4 (corrected direction) via [SUB-MOTION] or the merge of Def 4.7.
    Refinement,
    /// Table 1 [T-MOTION]: the context implies the primitive's precondition.
    TMotion,
    /// Table 1 [T-OUT]: the context implies the guard and the refinement of the value.
    TOut,
    /// Fig 5 [SUB-OUT] / [SUB-IN]: predicate implications between local types.
    Subtype,
    /// Table 1 [T-SESS]: initial states are collision free.
    TSess,
    /// Parameterised recursion (DATUM) in the global type: the refinement of a
    /// parameter holds of its initial value.
    RecInit,
    /// ... and of the arguments of each jump back.
    RecJump,
    /// Termination of refined recursion (`decreases E`): the measure is not negative at a
    /// jump back.
    MeasureBound,
    /// ... and the next iteration's measure is smaller than this one's.
    MeasureDecrease,
    /// Progress: in every reachable state at a message or choice, some branch has a true
    /// guard and a payload its refinements admit.
    Progress,
    /// An enum-typed MAVLink field: the refinement the protocol writes for it
    /// (with the guard and what is known there) admits only entries of its enum, or for a
    /// bitmask enum combinations of its flags.
    EnumEntry,
    /// [T-REC] with parameters: a process loop's refinement holds of its initial value.
    TRecInit,
    /// [T-VAR] with parameters: ... and of the arguments of each process jump.
    TRecJump,
    /// [T-REC]/[T-VAR] with parameters: the process's loop arguments equal its type's.
    TRecArgs,
    /// Fig 3 [NON-INTERRUPT]/[INTERRUPT]: a declared primitive admits a run that ends.
    Contract,
    /// Sec 3.1 (a footprint contains the robot's geometry): a primitive's footprint holds
    /// some point when it starts.
    Occupies,
    /// The vacuity guard: the context of a point the protocol reaches is satisfiable.
    Reachable,
    /// [T-SESS]: a participant's `init` and its kind's invariant have a state in common.
    InitInvariant,
    /// Sec 3.1 (`FP` contains `geom(p)`, Fig 3 [TRAJ-STEP]): a primitive's footprint
    /// contains the robot's body at every state its guarantee allows.
    Contains,
}

impl Rule {
    pub fn name(self) -> &'static str {
        match self {
            Rule::TotalChoice => "total choice (Def 4.4 (1))",
            Rule::AgComp => "[AGCOMP] compatibility",
            Rule::FullSeparation => "full separation of `*`",
            Rule::Refinement => "primitive refinement (Def 3.4)",
            Rule::TMotion => "[T-MOTION]",
            Rule::TOut => "[T-OUT]",
            Rule::Subtype => "[SUB-OUT]/[SUB-IN]",
            Rule::TSess => "[T-SESS]",
            Rule::RecInit => "recursion parameter at entry (DATUM)",
            Rule::RecJump => "recursion parameter at a jump (DATUM)",
            Rule::MeasureBound => "termination: the measure is not negative at a jump",
            Rule::MeasureDecrease => "termination: the measure decreases at a jump",
            Rule::Progress => "progress: some branch can be taken",
            Rule::EnumEntry => "an enum-typed field takes only entries of its enum (MAVLink dialect)",
            Rule::TRecInit => "[T-REC] with parameters",
            Rule::TRecJump => "[T-VAR] with parameters",
            Rule::TRecArgs => "[T-REC]/[T-VAR]: parameters as the type's",
            Rule::Contract => "a primitive can end (Fig 3 [NON-INTERRUPT], [INTERRUPT])",
            Rule::Occupies => "a footprint holds a point (Sec 3.1, FP contains geom(p))",
            Rule::Reachable => "a reachable context is satisfiable (vacuity guard)",
            Rule::InitInvariant => "[T-SESS]: init allows a state within the invariant",
            Rule::Contains => "a footprint contains the robot's body (Sec 3.1)",
        }
    }

    /// The check (in the report's list of checks) this obligation belongs to.
    pub fn check(self) -> &'static str {
        match self {
            Rule::TotalChoice => "total-choice",
            Rule::AgComp => "compatibility",
            Rule::FullSeparation => "separation",
            Rule::RecInit | Rule::RecJump => "recursion-parameters",
            Rule::MeasureBound | Rule::MeasureDecrease => "termination",
            Rule::Progress => "progress",
            Rule::EnumEntry => "enum-entries",
            Rule::Refinement
            | Rule::TMotion
            | Rule::TOut
            | Rule::Subtype
            | Rule::TSess
            | Rule::TRecInit
            | Rule::TRecJump
            | Rule::TRecArgs => "typing-obligations",
            Rule::Contract | Rule::Occupies | Rule::Contains => "contracts",
            Rule::Reachable | Rule::InitInvariant => "reachability",
        }
    }

    /// The rule's name as a file-name-safe word (`agcomp`, `tmotion`): the variant's
    /// name in lower case, for labels such as dumped queries' file names.
    pub fn slug(self) -> &'static str {
        match self {
            Rule::TotalChoice => "totalchoice",
            Rule::AgComp => "agcomp",
            Rule::FullSeparation => "fullseparation",
            Rule::Refinement => "refinement",
            Rule::TMotion => "tmotion",
            Rule::TOut => "tout",
            Rule::Subtype => "subtype",
            Rule::TSess => "tsess",
            Rule::RecInit => "recinit",
            Rule::RecJump => "recjump",
            Rule::MeasureBound => "measurebound",
            Rule::MeasureDecrease => "measuredecrease",
            Rule::Progress => "progress",
            Rule::EnumEntry => "enumentry",
            Rule::TRecInit => "trecinit",
            Rule::TRecJump => "trecjump",
            Rule::TRecArgs => "trecargs",
            Rule::Contract => "contract",
            Rule::Occupies => "occupies",
            Rule::Reachable => "reachable",
            Rule::InitInvariant => "initinvariant",
            Rule::Contains => "contains",
        }
    }
}

/// What must be shown.
#[derive(Clone, Debug)]
pub enum Goal {
    /// `hyps => pred` is valid.
    Valid(Expr),
    /// The joint motion is compatible from the context ([AGCOMP] applied repeatedly).
    Compatible { parts: Vec<(RoleId, PrimApp)> },
    /// `concrete <= meet(abstract)`, in the corrected direction of the seeds README.
    Refines { role: RoleId, concrete: PrimApp, abstract_: Vec<PrimApp> },
    /// The groups of `g1 * ... * gn` have pairwise disjoint footprints, each containing
    /// the footprints of its own motions. `sides[i]` lists every primitive side `i` may
    /// run (each part of a joint motion separately), with the context it starts in.
    Separated { sides: Vec<Side> },
    /// The participants' initial geometries are pairwise disjoint. `firsts` lists, for
    /// each participant that moves, the primitives it may run first (one per path); the
    /// footprints of all of them at time 0 contain it in its initial state.
    InitiallyDisjoint { firsts: Vec<(RoleId, Vec<PrimApp>)> },
    /// A primitive's contract admits a run that ends, for some arguments and start state
    /// (a satisfiability question; the obligation's `hyps` are empty).
    CanEnd { prim: PrimId },
    /// A primitive's footprint holds a point: some argument, start state, time in its
    /// duration and state its guarantee allows then, and a point its footprint's predicate
    /// holds of (a satisfiability question; the obligation's `hyps` are empty).
    Occupies { prim: PrimId },
    /// The obligation's `hyps` (Σ after a step) are satisfiable. When they are not, the
    /// step is where the protocol gets stuck, provided every context in `before` (Σ
    /// before the step) is satisfiable; otherwise an earlier step is to blame. With
    /// `dead_branch`, the step is the guard of one branch among several: an unsatisfiable
    /// context there is a dead branch (a warning), not a stuck protocol.
    Reachable { before: Vec<Vec<Expr>>, dead_branch: bool },
    /// Progress at a message or a choice: `hyps ⇒ ∨_b (guard_b ∧ ∃ fields_b. refinement_b)`,
    /// some branch's guard holds and some payload satisfies its refinements.
    Progress { branches: Vec<Enabled> },
    /// The footprint of `prim` (a predicate) contains its kind's body, at every time and
    /// state its guarantee and the invariant allow from every start its precondition
    /// allows, for every argument (the obligation's `hyps` are empty).
    Contains { prim: PrimId },
}

/// When one branch of a choice (or a lone message) can be taken: its guard holds and
/// some values of `fields` satisfy `refinement` (the conjunction of its payload's
/// refinements, fields defined by an equality already replaced by their definition).
#[derive(Clone, Debug)]
pub struct Enabled {
    /// The message as the user wrote it, for the report (`p -> q: l`).
    pub what: String,
    pub guard: Option<Expr>,
    /// The payload values still to be chosen (existentially quantified).
    pub fields: Vec<(ValueId, String, Sort)>,
    pub refinement: Expr,
}

/// One side of a `*`: its participants and the primitives they may run on it.
#[derive(Clone, Debug, Default)]
pub struct Side {
    pub roles: Vec<RoleId>,
    pub runs: Vec<RoleMotion>,
}

/// A primitive run by one participant, with the logical context (conjuncts over the
/// participants' variables, `Var::Role`/`Var::Snap`, and values) when it starts.
#[derive(Clone, Debug)]
pub struct RoleMotion {
    pub role: RoleId,
    pub app: PrimApp,
    pub hyps: Vec<Expr>,
}

#[derive(Clone, Debug)]
pub struct Obligation {
    pub rule: Rule,
    pub span: Span,
    /// A short description in the user's terms ("guards of the choice at Cart -> GRobot").
    pub what: String,
    /// The logical context Σ assumed (conjuncts).
    pub hyps: Vec<Expr>,
    pub goal: Goal,
}

impl Obligation {
    /// Settles what needs no solver: a goal `true`, or a goal among the hypotheses.
    pub fn trivially_holds(&self) -> bool {
        match &self.goal {
            Goal::Valid(e) => {
                e.is_true()
                    || self.hyps.iter().any(|h| h == e)
                    || matches!(&e.kind, ExprKind::Binary(crate::hir::expr::BinOp::Or, a, b) if a.is_true() || b.is_true())
            }
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hir::{Loc, Sort};

    #[test]
    fn only_syntactically_trivial_goals_hold_without_a_solver() {
        let t = Expr::bool(true, Loc::default());
        let x = Expr { kind: ExprKind::Int(1), sort: Sort::Int, loc: Loc::default() };
        let ob = |hyps: Vec<Expr>, goal: Expr| Obligation {
            rule: Rule::TOut,
            span: Span::default(),
            what: String::new(),
            hyps,
            goal: Goal::Valid(goal),
        };
        assert!(ob(vec![], t.clone()).trivially_holds());
        assert!(ob(vec![x.clone()], x.clone()).trivially_holds());
        assert!(!ob(vec![], x).trivially_holds());
        assert!(!Obligation { goal: Goal::InitiallyDisjoint { firsts: Vec::new() }, ..ob(vec![], t) }.trivially_holds());
    }

    /// A goal about one `v` is not settled by the same text about another `v` (two
    /// binding sites of one name). Before, values compared by name and it was.
    #[test]
    fn a_hypothesis_about_another_value_of_the_same_name_settles_nothing() {
        use crate::hir::{ValueId, Var};
        let v = |id: u32| Expr {
            kind: ExprKind::Var(Var::Value(ValueId(id), "v".into())),
            sort: Sort::Real,
            loc: Loc::default(),
        };
        let zero = Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc: Loc::default() };
        let pos = |id: u32| Expr {
            kind: ExprKind::Binary(crate::hir::expr::BinOp::Lt, Box::new(zero.clone()), Box::new(v(id))),
            sort: Sort::Bool,
            loc: Loc::default(),
        };
        let ob = |hyp: Expr, goal: Expr| Obligation {
            rule: Rule::TotalChoice,
            span: Span::default(),
            what: String::new(),
            hyps: vec![hyp],
            goal: Goal::Valid(goal),
        };
        assert!(ob(pos(0), pos(0)).trivially_holds());
        assert!(!ob(pos(0), pos(1)).trivially_holds());
    }

    /// `slug` is what the driver's labels were (`format!("{:?}", rule).to_lowercase()`),
    /// so dumped file names do not change, and every slug is distinct.
    #[test]
    fn slugs_are_the_lowercase_variant_names() {
        let all = [
            Rule::TotalChoice,
            Rule::AgComp,
            Rule::FullSeparation,
            Rule::Refinement,
            Rule::TMotion,
            Rule::TOut,
            Rule::Subtype,
            Rule::TSess,
            Rule::RecInit,
            Rule::RecJump,
            Rule::MeasureBound,
            Rule::MeasureDecrease,
            Rule::Progress,
            Rule::EnumEntry,
            Rule::TRecInit,
            Rule::TRecJump,
            Rule::TRecArgs,
            Rule::Contract,
            Rule::Occupies,
            Rule::Reachable,
            Rule::InitInvariant,
            Rule::Contains,
        ];
        for r in all {
            assert_eq!(r.slug(), format!("{r:?}").to_lowercase());
            assert!(r.slug().chars().all(|c| c.is_ascii_lowercase()), "{r:?}");
        }
        let mut slugs: Vec<&str> = all.iter().map(|r| r.slug()).collect();
        slugs.sort();
        slugs.dedup();
        assert_eq!(slugs.len(), all.len());
    }
}
