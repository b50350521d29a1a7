//! mochi: a type checker and verifier for motion choreographies; this crate is the command
//! line (`main.rs`, [`render`], [`io`]) and the library's facade over `mochi-core` (the
//! language) and `mochi-verify` (the checks).
//!
//! The pipeline, stage by stage, which is also the order to read the modules in (the
//! `pub mod` list below is alphabetical; ARCHITECTURE.md tells the whole story):
//! source text → [`syntax`] (tokens, AST) → [`lower`] (names resolved, [`hir`]) →
//! [`wf`] (Def 4.1 side conditions, well-scopedness, synchronisability), with [`plan`] (the
//! global type's obligations, Σ threaded through it) →
//! [`project`] (local types, Defs 4.7-4.8) → [`typeck`] (processes, Table 1) →
//! [`smt`] (every predicate met on the way is an [`obligation`]: Z3 decides it, with the
//! vacuity guard; [`bounds`] settles what intervals can) → [`driver`] (the verdict).
//! [`render`] turns diagnostics and reports into text or JSON. Beside the pipeline,
//! [`simulate`] runs a choreography on concrete trajectories (an independent check of the
//! verdicts) and [`exact`] evaluates expressions in exact arithmetic for it and for the
//! replay of counterexamples. Also: [`source`] (files and spans) and [`diag`] (codes
//! and diagnostics), used by every stage; [`sigma`] (the logical context Σ that scoping
//! and typing thread); [`dialect`] (the MAVLink schema that lowering checks messages against,
//! read from the bundled XML definitions); [`subtype`] (subtyping of local types, Fig 5, and [T-SUB] for
//! written `local` items); [`library`] (`mochi check lib.mochi`); [`fsload`] (the IO
//! edge: source files from disk) and [`stack`] (stack growth for recursive passes).
//!
//! ```
//! use mochi::driver::{Config, Verdict};
//! use mochi::fsload::check_source;
//! let mut db = mochi::source::SourceDb::new();
//! // A file with no system and no choreography has nothing to verify: E0210.
//! let report = check_source(&mut db, "empty.chor", "const k = 1;", &Config::default());
//! assert_eq!(report.verdict, Verdict::Rejected);
//! assert_eq!(report.diagnostics[0].code.as_str(), "E0210");
//! ```

// The crates of mochi (ARCHITECTURE.md, "Code map"), re-exported module by module so that
// `mochi::driver::Config`, `mochi::source::SourceDb` and the rest name what they always did.
pub use mochi_core::{
    bounds, diag, dialect, exact, hir, lower, obligation, project, sigma, source, stack, subtype, syntax, xmlscan,
};
pub use mochi_monitor::{mavio, monitor, proxy};
pub use mochi_verify::{collision, driver, fsload, geometry, library, plan, simulate, smt, space, typeck, wf};

pub mod io;
pub mod render;

#[cfg(test)]
mod protocol_tests;
