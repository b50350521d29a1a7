//! Declared local types in the pipeline ([`crate::subtype::check_declared`], [T-SUB]), on
//! `tests/data/declared-subtype.chor`.

use crate::diag::{Code, Severity};
use crate::driver::{Config, Verdict};
use crate::fsload::check_source;
use crate::testing::repo;

const FILE: &str = "tests/data/declared-subtype.chor";

fn check(edit: &dyn Fn(String) -> String) -> (Verdict, Vec<Code>) {
    let text = std::fs::read_to_string(repo(FILE)).expect("the example exists");
    let edited = edit(text.clone());
    assert_ne!(edited, text, "the edit changes nothing");
    let mut db = crate::source::SourceDb::new();
    let r = check_source(&mut db, &repo(FILE).display().to_string(), &edited, &Config::default());
    let codes = r.diagnostics.iter().filter(|d| d.severity == Severity::Error).map(|d| d.code).collect();
    (r.verdict, codes)
}

/// The example verifies: its written local types are proper subtypes of the
/// projections (fewer sends, a stronger send refinement, more receptions, a weaker
/// receive refinement), and two E0711 obligations were proved. Before, two E0602.
#[test]
fn the_example_verifies_with_its_subtyping_obligations() {
    let mut db = crate::source::SourceDb::new();
    let r = crate::fsload::check_file(&mut db, &repo(FILE), &Config::default()).expect("readable");
    assert_eq!(r.verdict, Verdict::Verified, "{:?}", r.diagnostics);
    let typing = r.checks.iter().find(|c| c.name == "typing-obligations").expect("typing obligations");
    assert!(matches!(typing.detail, crate::driver::Detail::Obligations { total: 5, .. }), "{}", typing.detail);
}

/// The process is typed against the written local type, not the projection: a value
/// the projection allows (0.7) but `local p` does not (`n == 0.5`) is E0709.
#[test]
fn the_process_implements_the_declared_type() {
    let sends =
        |t: String| t.replace("process p = q!go(0.5).dt<move_to(0.5)>", "process p = q!go(0.7).dt<move_to(0.7)>");
    assert_eq!(check(&sends), (Verdict::Rejected, vec![Code::SendPredicate]));
    // `local q` receives `abort` too, so q's process must handle it.
    let drop = |t: String| t.replace(" + p?abort.dt<hold>.end;", ";");
    assert_eq!(check(&drop), (Verdict::Rejected, vec![Code::MissingBranch]));
}

/// Structural failures of `T <= G↾R` are E0602 at the `local` item.
#[test]
fn a_declared_type_that_is_no_subtype_is_e0602() {
    // A send the projection does not allow ([SUB-OUT]).
    let extra = |t: String| {
        t.replace("local p = q!go(n: real {n == 0.5})", "local p = +{ q!halt.dt<hold>.end, q!go(n: real {n == 0.5})")
    };
    let extra = |t: String| extra(t).replace(".dt<move_to(n)>.end;", ".dt<move_to(n)>.end };");
    assert_eq!(check(&extra), (Verdict::Rejected, vec![Code::LocalMismatch]));
    // A label the projection may deliver and the declared type misses ([SUB-IN]).
    let missing = |t: String| t.replace(" p?stop.dt<hold>.end, p?abort", " p?abort");
    assert_eq!(check(&missing).1.first(), Some(&Code::LocalMismatch));
}

/// [SUB-MOTION]: a declared motion must refine the projection's (Def 3.4, concrete on
/// the left): `wave` does not keep the joint still as `hold` guarantees (E0407).
#[test]
fn a_declared_motion_refines_the_projections() {
    let wave = |t: String| t.replace("p?go(m: real {m >= 0}).dt<hold>.end", "p?go(m: real {m >= 0}).dt<wave>.end");
    let wave = |t: String| wave(t).replace("process q = p?go(m).dt<hold>.end", "process q = p?go(m).dt<wave>.end");
    assert_eq!(check(&wave), (Verdict::Rejected, vec![Code::RefinementFails]));
}
