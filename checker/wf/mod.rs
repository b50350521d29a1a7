//! Well-formedness of the global type (Def 4.4), except the predicate parts:
//! [`side`] checks the side conditions of Def 4.1, [`scope`] well-scopedness and full
//! separation (Sec 4.1) with total motion (Def 4.4 (3)), and [`sync`]
//! synchronisability (Sec 4.1) on the happens-before relation. Predicates met on the
//! way (total choice, [AGCOMP] compatibility, separation of footprints) become
//! [`Obligation`]s.

pub mod scope;
pub mod side;
pub mod sync;

use crate::diag::Diagnostic;
use crate::hir::Program;
use crate::obligation::Obligation;

/// What the well-formedness checks found, one list per check, so the driver can report
/// each as its own line.
#[derive(Debug, Default)]
pub struct WfReport {
    /// Def 4.1 side conditions (E0301-E0306, E0314).
    pub side: Vec<Diagnostic>,
    /// Well-scopedness, full separation, total motion, at most one non-interruptible
    /// primitive (E0307-E0309, E0313, E0315, E0401).
    pub scope: Vec<Diagnostic>,
    /// Synchronisability (E0310-E0312); empty when earlier checks failed.
    pub sync: Vec<Diagnostic>,
    pub obligations: Vec<Obligation>,
    /// Whether synchronisability ran (it needs a well-scoped type).
    pub sync_ran: bool,
}

/// Runs the checks in order; synchronisability only runs on a type that passed the
/// side conditions and scoping, whose assumptions it relies on.
pub fn check(prog: &Program) -> WfReport {
    let mut r = WfReport::default();
    let Some(chor) = &prog.choreography else { return r };
    r.side = side::check(prog, &chor.body);
    let (scope, obligations) = scope::check(prog, &chor.body);
    r.scope = scope;
    r.obligations = obligations;
    if !r.side.iter().chain(&r.scope).any(Diagnostic::is_error) {
        r.sync = sync::check(prog, &chor.body);
        r.sync_ran = true;
    }
    r
}
