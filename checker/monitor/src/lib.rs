//! mochi's run-time monitor: refined MAVLink sessions that `mochi check` verified, enforced
//! on frames read from logs and links (DATUM, seed 000 Sec 2 and 4).
//!
//! - [`mavio`]: MAVLink input: frames read from `.tlog`, raw and `.pcapng` logs and from
//!   links, mission files and the upload traces they imply.
//! - [`monitor`]: a verified protocol compiled to a flat automaton and run over frames.
//! - [`proxy`]: the monitor between a ground station and a vehicle, dropping (or reporting)
//!   every message that would break a protocol.
//!
//! This crate depends on the verification core (`mochi-core`) alone: no solver, no geometry
//! engine (tests/tidy.rs, rule (h)). The core's modules are re-exported under their own
//! names, so that the monitor reads `crate::hir`, `crate::exact`, ... as the verifier does.

pub use mochi_core::{diag, dialect, exact, hir, lower, project, sigma, source, syntax};

pub mod mavio;
pub mod monitor;
pub mod proxy;
