//! mochi-core: the language of mochi, without a solver, a geometry engine or a file system.
//!
//! Source text → [`syntax`] (tokens, AST; imports read through a loader the caller passes)
//! → [`lower`] (names resolved, sorts checked, MAVLink messages against a [`dialect`]) →
//! [`hir`] (the program every later stage reads) → [`project`] (local types, Defs 4.7-4.8)
//! and [`subtype`] (Fig 5). Beside them: [`source`] (files and spans) and [`diag`] (codes
//! and diagnostics), used by every stage; [`sigma`] (the logical context Σ that scoping and
//! typing thread); [`obligation`] (what a check asks a decision procedure, as data);
//! [`exact`] (exact arithmetic over rationals) and [`bounds`] (interval enclosures);
//! [`stack`] (stack growth for recursive passes), [`xmlscan`] (the linear pre-scan of
//! XML documents) and [`splitmix`] (the seeded generator of the simulator and the tests).
//! The checks that decide obligations (Z3, the geometry engine) are in
//! `mochi-verify`; the run-time monitor depends on this crate alone (ARCHITECTURE.md).

pub mod bounds;
pub mod diag;
pub mod dialect;
pub mod exact;
pub mod float;
pub mod hir;
pub mod lower;
pub mod obligation;
pub mod project;
pub mod sigma;
pub mod source;
pub mod splitmix;
pub mod stack;
pub mod subtype;
pub mod syntax;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod xmlscan;
