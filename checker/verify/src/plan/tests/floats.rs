//! "Some value exists" questions that read a `float` field ask for a float32, not a real
//! (LANGUAGE.md, "Floats are float32"): a stream's invariant (E0410) and, at a choice with a
//! timeout, whether some message can come (E0410). A window with real solutions and no
//! float32 fails; the same window widened to hold one passes.

use crate::driver::Verdict;

/// The verdict of `src` (through the whole pipeline) and the codes of its errors.
fn verdict(src: &str) -> (Verdict, Vec<&'static str>) {
    let report = crate::fsload::check_source(
        &mut crate::source::SourceDb::new(),
        "virtual/floats.chor",
        src,
        &crate::driver::Config::patient(),
    );
    let errors = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code.as_str()).collect();
    (report.verdict, errors)
}

/// 0.1 and the next float32 up, 0.100000001490116...: no float32 lies strictly between 0.1
/// and `NARROW`, and 0.100000001490116... lies below `WIDE`.
const NARROW: &str = "0.1000000001";
const WIDE: &str = "0.1000001";

#[test]
fn a_stream_invariant_must_admit_a_float32_reading() {
    let stream = |hi: &str| {
        format!(
            "dialect common;
             system S {{ participant GCS; participant UAV;
                         stream UAV -> GCS: ATTITUDE(roll {{0.1 < roll && roll < {hi}}}); }}
             choreography G = GCS -> UAV: [roll > 0] PARAM_REQUEST_LIST. end;"
        )
    };
    assert_eq!(verdict(&stream(NARROW)), (Verdict::Rejected, vec!["E0410"]));
    assert_eq!(verdict(&stream(WIDE)), (Verdict::Verified, vec![]));
    // An integer field keeps the satisfiability question: 1 < n < 3 holds 2.
    let ints = "dialect common;
        system S { participant GCS; participant UAV; stream UAV -> GCS: SYS_STATUS(load {1 < load && load < 3}); }
        choreography G = GCS -> UAV: [load > 0] PARAM_REQUEST_LIST. end;";
    assert_eq!(verdict(ints), (Verdict::Verified, vec![]));
}

#[test]
fn a_message_before_a_timeout_must_admit_a_float32_payload() {
    let read = |hi: &str| {
        format!(
            "dialect common;
             system S {{ participant GCS; participant UAV; }}
             choreography G =
               GCS -> UAV: PARAM_REQUEST_LIST.
               ( UAV -> GCS: PARAM_VALUE(param_value as v {{0.1 < v && v < {hi}}}). end
               + after 1000 ms by GCS. end );"
        )
    };
    assert_eq!(verdict(&read(NARROW)), (Verdict::Rejected, vec!["E0410"]));
    assert_eq!(verdict(&read(WIDE)), (Verdict::Verified, vec![]));
}
