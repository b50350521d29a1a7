//! Tests of the core's rules through the whole pipeline (the driver, Z3): lowering
//! ([`lower`]), MAVLink messages ([`mavlink`]), projection ([`project`]), the logical context
//! Σ ([`sigma_probe`]) and declared local types ([`subtype`]). The core's own unit tests
//! beside its modules use the core alone.

mod lower;
mod mavlink;
mod project;
mod sigma_probe;
mod subtype;
