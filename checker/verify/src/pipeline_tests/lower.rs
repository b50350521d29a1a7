//! Lowering through the whole pipeline (LANGUAGE.md "Sorts").

use crate::diag::{Code, Diagnostic};
use crate::source::SourceDb;
use crate::testing::repo;

fn codes(d: &[Diagnostic]) -> Vec<Code> {
    d.iter().map(|d| d.code).collect()
}

/// The same through the whole pipeline: a process that branches on `j.x` for a number `j`
/// it received used to be verified (`j.x` was `true`, a fine condition); a component is a
/// real, not a condition, so it is rejected (E0208).
#[test]
fn a_component_of_a_received_value_is_no_condition() {
    let src = std::fs::read_to_string(repo("choreographies/countdown.chor")).expect("countdown");
    let before = "mu loop. (p?more(j).(p!half.dt<hold>.loop + p!full.dt<hold>.loop)";
    assert!(src.contains(before));
    let src = src.replace(before, "mu loop. (p?more(j).(if j.x then p!half.dt<hold>.loop else p!full.dt<hold>.loop)");
    let mut db = SourceDb::new();
    let cfg = crate::driver::Config::default();
    let report = crate::fsload::check_source(
        &mut db,
        &repo("choreographies/binder-component.chor").display().to_string(),
        &src,
        &cfg,
    );
    assert_eq!(report.verdict, crate::driver::Verdict::Rejected);
    assert_eq!(codes(&report.diagnostics), vec![Code::SortMismatch], "{:?}", report.diagnostics);
}
