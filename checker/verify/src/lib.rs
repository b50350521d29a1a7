//! mochi-verify: the checks of mochi, on the programs `mochi-core` builds.
//!
//! [`driver`] is the one place the stages are wired, in order: the core's parse and lower,
//! the geometry stage ([`space`] turns bodies and footprints into predicates where Z3 can
//! decide them, and into the [`geometry`] engine's solids where it cannot), [`wf`] (Def 4.1
//! side conditions, well-scopedness, synchronisability) with [`plan`] (the obligations of the
//! global type, each with the logical context Σ of its point), the core's projection, [`typeck`]
//! (processes, Table 1), then [`smt`] (every predicate met on the way is an obligation: Z3
//! decides it, with the vacuity guard, or the geometric search does) and the verdict.
//! [`library`] checks a `.mochi` library on its own; [`simulate`] runs a choreography on
//! concrete trajectories (an independent check of the verdicts); [`fsload`] is the
//! file-system loader the pipeline is given by the command line and by tests.
//!
//! The core's modules are re-exported under their own names, so that `crate::hir::...`
//! reads the same here as in the core.

pub use mochi_core::{bounds, diag, dialect, exact, hir, obligation, sigma, source, stack, subtype, syntax, xmlscan};

/// Lowering ([`mochi_core::lower`]).
pub mod lower {
    pub use mochi_core::lower::*;
    /// The core's lowering helpers for the unit tests of the later stages.
    #[cfg(test)]
    pub(crate) mod tests {
        pub(crate) use mochi_core::testing::{first_guard, lower_src, HEADER};
    }
}

/// Projection ([`mochi_core::project`]).
pub mod project {
    pub use mochi_core::project::*;
    /// The core's projection examples for the unit tests of typing.
    #[cfg(test)]
    pub(crate) mod tests {
        pub(crate) use mochi_core::testing::CART_ARMS;
    }
}

pub mod collision;
pub mod driver;
pub mod fsload;
pub mod geometry;
pub mod library;
pub mod plan;
pub mod simulate;
pub mod smt;
pub mod space;
pub mod typeck;
pub mod wf;

#[cfg(test)]
pub(crate) use mochi_core::testing;

/// The rules of the core checked through the whole pipeline (the driver, Z3): their tests
/// need the verifier, so they live here rather than beside the core's modules.
#[cfg(test)]
mod pipeline_tests;

/// The parallel-lanes generator (not part of the library: it lives beside the example
/// and the benchmark that use it), for the unit tests that check generated lanes.
#[cfg(test)]
#[path = "../../../examples/common/lanes.rs"]
#[allow(dead_code)]
pub(crate) mod lanes;
