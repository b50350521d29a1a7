//! MAVLink messages through the whole pipeline (LANGUAGE.md, MAVLink messages): enum
//! entries (E0243), what a receiver assumes of them, and the finite-float model, against
//! the bundled `common` dialect.

use crate::diag::Diagnostic;
use crate::hir::Program;
use crate::lower::tests::lower_src;

const SYS: &str = "dialect common;\nsystem S { participant GCS; participant UAV; }\n";

fn lower_mav(chor: &str) -> (Program, Vec<Diagnostic>) {
    lower_src(&format!("{SYS}choreography G = {chor};"))
}

/// The whole pipeline on `chor` (with the common dialect): the verdict and the codes of the
/// errors.
fn verdict(chor: &str) -> (crate::driver::Verdict, Vec<&'static str>) {
    let src = format!("{SYS}choreography G = {chor};");
    let report = crate::fsload::check_source(
        &mut crate::source::SourceDb::new(),
        "virtual/enum.chor",
        &src,
        &crate::driver::Config::patient(),
    );
    let errors = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code.as_str()).collect();
    (report.verdict, errors)
}

#[test]
fn a_refinement_that_leaves_no_entry_is_e0243_and_narrowing_is_fine() {
    use crate::driver::Verdict;
    let arm =
        |v: &str| verdict(&format!("GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm {{arm == {v}}}). end"));
    // A float parameter of enum MAV_BOOL: 1.0 is MAV_BOOL_TRUE, 1.001 and 7 are none.
    assert_eq!(arm("1.0"), (Verdict::Verified, vec![]));
    assert_eq!(arm("MAV_BOOL_TRUE"), (Verdict::Verified, vec![]));
    assert_eq!(arm("1.001"), (Verdict::Rejected, vec!["E0243"]));
    assert_eq!(arm("7"), (Verdict::Rejected, vec!["E0243"]));
    // A MAV_RESULT of 42 (the progress failure at the same message is not repeated).
    let ack = |r: &str| {
        verdict(&format!(
            "GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm {{arm == MAV_BOOL_TRUE}}).
             UAV -> GCS: COMMAND_ACK(command {{command == MAV_CMD_COMPONENT_ARM_DISARM}}, result {{{r}}}). end"
        ))
    };
    assert_eq!(ack("result == 42"), (Verdict::Rejected, vec!["E0243"]));
    assert_eq!(ack("result > MAV_RESULT_NOT_IN_CONTROL"), (Verdict::Rejected, vec!["E0243"]));
    // A refinement narrows the enum: "every result but ACCEPTED" is the ten others.
    assert_eq!(ack("result != MAV_RESULT_ACCEPTED"), (Verdict::Verified, vec![]));
    // Bitmasks: flags summed are a combination, a bit no flag has is not.
    let mask = |m: &str| verdict(&format!("GCS -> UAV: SET_ATTITUDE_TARGET(type_mask {{type_mask == {m}}}). end"));
    let flags = "ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE + ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE";
    assert_eq!(mask(flags), (Verdict::Verified, vec![]));
    assert_eq!(mask("0"), (Verdict::Verified, vec![]));
    assert_eq!(mask(&format!("{flags} + 16")), (Verdict::Rejected, vec!["E0243"]));
    // In a choice, a branch no entry fits is an error (before it was a dead branch, a
    // warning, at most).
    let choice = verdict(
        "UAV -> GCS: MISSION_ACK(type as t {t == 16}). end
         + UAV -> GCS: MISSION_CURRENT(seq {seq == 0}). end",
    );
    assert_eq!(choice, (Verdict::Rejected, vec!["E0243"]));
    // Where the value depends on the state, the refinement must leave an entry in some
    // state; a state where it leaves none is the progress check's (E0419).
    let counted = verdict(
        "GCS -> UAV: MISSION_COUNT(count as n {n <= 20}).
         UAV -> GCS: MISSION_ACK(type as t {t == n}). end",
    );
    assert_eq!(counted, (Verdict::Rejected, vec!["E0419"]));
}

#[test]
fn the_receiver_assumes_the_enum_and_a_process_must_send_an_entry() {
    use crate::driver::Verdict;
    // Total only because MISSION_ACK.type is a MAV_MISSION_RESULT (0..=15): E0316 before.
    let total = verdict(
        "UAV -> GCS: MISSION_ACK(type as t).
         ( GCS -> UAV: [t == MAV_MISSION_ACCEPTED] MISSION_REQUEST_LIST(mission_type {mission_type == MAV_MISSION_TYPE_MISSION}). end
         + GCS -> UAV: [MAV_MISSION_ERROR <= t && t <= MAV_MISSION_OPERATION_CANCELLED] MISSION_CLEAR_ALL(). end )",
    );
    assert_eq!(total, (Verdict::Verified, vec![]));
    // A process sending 42 where the type says MAV_MISSION_RESULT fails [T-OUT] (verified
    // before: the field's type was the uint8_t range).
    let procs = |ack: &str| {
        let src = format!(
            "{SYS}choreography G = GCS -> UAV: MISSION_COUNT(count {{count == 0}}). UAV -> GCS: MISSION_ACK(type). end;
             process GCS = UAV!MISSION_COUNT(0).UAV?MISSION_ACK(r).end;
             process UAV = GCS?MISSION_COUNT(n).GCS!MISSION_ACK({ack}).end;"
        );
        let report = crate::fsload::check_source(
            &mut crate::source::SourceDb::new(),
            "virtual/enum.chor",
            &src,
            &crate::driver::Config::default(),
        );
        let errors: Vec<&str> = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code.as_str()).collect();
        (report.verdict, errors)
    };
    assert_eq!(procs("MAV_MISSION_ACCEPTED"), (Verdict::Verified, vec![]));
    assert_eq!(procs("42"), (Verdict::Rejected, vec!["E0709"]));
}

/// E0243 asks nothing of a refinement that pins the field to an allowed constant or to a value
/// of the same enum, in every disjunct.
#[test]
fn pinned_enum_fields_ask_nothing() {
    let asked = |chor: &str| {
        let (p, d) = lower_mav(chor);
        assert!(d.is_empty(), "{d:?}");
        let body = &p.choreography.as_ref().expect("choreography").body;
        let (obs, d) = (crate::plan::obligations(&p, body), crate::wf::scope::check(&p, body));
        assert!(d.is_empty(), "{d:?}");
        obs.iter().filter(|o| o.rule == crate::obligation::Rule::EnumEntry).count()
    };
    let chor =
        "GCS -> UAV: MISSION_COUNT(mission_type as mt {mt == MAV_MISSION_TYPE_FENCE || mt == MAV_MISSION_TYPE_RALLY}).
                UAV -> GCS: MISSION_ACK(type {type != MAV_MISSION_ACCEPTED}, mission_type {mission_type == mt}). end";
    assert_eq!(asked(chor), 1, "only MISSION_ACK.type");
    // A constant that is no entry, or a value of another enum, is asked.
    assert_eq!(asked("GCS -> UAV: MISSION_COUNT(mission_type {mission_type == 3}). end"), 1);
    let other = "UAV -> GCS: MISSION_ACK(type as t). GCS -> UAV: MISSION_COUNT(mission_type {mission_type == t}). end";
    assert_eq!(asked(other), 1);
}

/// Under the finite-float model, `[v < 0] + [v >= 0]` over a received float is total
/// (no NaN arrives: the monitor rejects it), the window (0.1, 0.1000000001) holds no
/// binary32 (E0419) while (0.1, 0.1000001) does, and `v == 0.1` has no binary32 either.
#[test]
fn progress_asks_for_a_float32_payload() {
    use crate::driver::Verdict;
    let window = |hi: &str| verdict(&format!("GCS -> UAV: PARAM_SET(param_value as v {{0.1 < v && v < {hi}}}). end"));
    assert_eq!(window("0.1000000001"), (Verdict::Rejected, vec!["E0419"]));
    assert_eq!(window("0.1000001"), (Verdict::Verified, vec![]));
    assert_eq!(verdict("GCS -> UAV: PARAM_SET(param_value as v {v == 0.1}). end"), (Verdict::Rejected, vec!["E0419"]));
    assert_eq!(verdict("GCS -> UAV: PARAM_SET(param_value as v {v == 0.5}). end"), (Verdict::Verified, vec![]));
    // An echo of a received float is a float.
    assert_eq!(
        verdict(
            "GCS -> UAV: PARAM_SET(param_value as v {0 <= v && v <= 1}). UAV -> GCS: PARAM_VALUE(param_value as w {w == v}). end"
        ),
        (Verdict::Verified, vec![])
    );
    let total = verdict(
        "UAV -> GCS: PARAM_VALUE(param_value as v).
         ( GCS -> UAV: [v < 0] PARAM_REQUEST_LIST(). end
         + GCS -> UAV: [v >= 0] MISSION_CLEAR_ALL(). end )",
    );
    assert_eq!(total, (Verdict::Verified, vec![]));
}
