//! The integration tests of mochi in one test binary: each file below is a module of it
//! (its own doc comment says what it tests). One binary links the solver and the geometry
//! engine once instead of once per file, and lets the test runner fill both cores with the
//! tests of every file instead of waiting for the slowest test of each binary in turn.
//!
//! Run one file's tests by its module name, one test by its path:
//!
//! ```text
//! cargo test --test suite -- mutation::
//! cargo test --test suite -- cli::explain_list_names_every_code
//! ```
//!
//! Two harnesses are binaries of their own: `tests/corpus.rs` (one test per file of the
//! corpus, with its own runner, `libtest-mimic`) and `tests/monitor.rs` (its counting
//! allocator, to measure the monitor's allocations, would count every other test's too).

#[path = "asyncruns.rs"]
mod asyncruns;
#[path = "cli.rs"]
mod cli;
/// The corpus and the checking shared by `metamorphic` and `differential`.
#[path = "metamorphic/common.rs"]
mod common;
#[path = "differential.rs"]
mod differential;
#[path = "generate.rs"]
mod generate;
#[path = "mavio.rs"]
mod mavio;
#[path = "mavproxy.rs"]
mod mavproxy;
#[path = "metamorphic.rs"]
mod metamorphic;
#[path = "mutation.rs"]
mod mutation;
/// The mutation operators, shared by `mutation`, `differential` and `simulate`.
#[path = "mutation/ops.rs"]
mod ops;
#[path = "props.rs"]
mod props;
#[path = "proxy.rs"]
mod proxy;
#[path = "refined.rs"]
mod refined;
#[path = "simulate.rs"]
mod simulate;
#[path = "tidy.rs"]
mod tidy;
#[path = "turning.rs"]
mod turning;
