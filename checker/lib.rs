//! mochi: a type checker and verifier for motion choreographies.
//!
//! The pipeline, stage by stage, which is also the order to read the modules in (the
//! `pub mod` list below is alphabetical; ARCHITECTURE.md tells the whole story):
//! source text → [`syntax`] (tokens, AST) → [`lower`] (names resolved, [`hir`]) →
//! [`wf`] (Def 4.1 side conditions, well-scopedness, synchronisability) →
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

pub mod bounds;
pub mod diag;
pub mod dialect;
pub mod driver;
pub mod exact;
pub mod fsload;
pub mod geometry;
pub mod hir;
pub mod io;
pub mod library;
pub mod lower;
pub mod mavio;
pub mod obligation;
pub mod project;
pub mod render;
pub mod sigma;
pub mod simulate;
pub mod smt;
pub mod source;
pub mod space;
pub mod stack;
pub mod subtype;
pub mod syntax;
#[cfg(test)]
pub(crate) mod testing;
pub mod typeck;
pub mod wf;
pub mod xmlscan;

/// The parallel-lanes generator (not part of the library: it lives beside the example
/// and the benchmark that use it), for the unit tests that check generated lanes.
#[cfg(test)]
#[path = "../examples/common/lanes.rs"]
#[allow(dead_code)]
pub(crate) mod lanes;
