//! The walk's tests: the hypotheses it gives (`context`), the refined sessions' rules decided
//! end to end (`refined`), and observed state (`observed`).

use crate::diag::Diagnostic;
use crate::hir::{Global, Program};
use crate::obligation::Obligation;

mod context;
mod crossing;
mod floats;
mod observed;
mod refined;

/// The obligations of `g` and its scoping errors, as the driver's well-scoped stage makes
/// them.
fn check(prog: &Program, g: &Global) -> (Vec<Obligation>, Vec<Diagnostic>) {
    (super::obligations(prog, g), crate::wf::scope::check(prog, g))
}
