//! Well-formedness of the global type (Def 4.4), except the predicate parts:
//! [`side`] checks the side conditions of Def 4.1, [`scope`] well-scopedness and full
//! separation (Sec 4.1) with total motion (Def 4.4 (3)), and [`sync`]
//! synchronisability (Sec 4.1) on the happens-before relation. The predicates of the type
//! (total choice, [AGCOMP] compatibility, separation of footprints, ...) become
//! [`Obligation`](crate::obligation::Obligation)s in [`crate::plan`]. The driver runs the three checks, each
//! timed on its own; synchronisability only on a type that passed the other two, whose
//! assumptions it relies on.

pub mod scope;
pub mod side;
pub mod sync;
pub mod trace;
