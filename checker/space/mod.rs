//! The space robots occupy, between the HIR and the checks: bodies as footprint
//! predicates ([`region`]) where the SMT solver can decide them.

pub mod region;
pub mod truth;
