//! Unit tests of MAVLink messages in lowering (LANGUAGE.md, MAVLink messages): the
//! `dialect` item, labels, payload fields, wire ranges, commands, enum entries, strings,
//! `has_flag` and plain participants. They run against the bundled `common` dialect.

use super::tests::lower_src;
use super::*;

fn codes(d: &[Diagnostic]) -> Vec<&'static str> {
    d.iter().map(|d| d.code.as_str()).collect()
}

const SYS: &str = "dialect common;\nsystem S { participant GCS; participant UAV; }\n";

fn lower_mav(chor: &str) -> (Program, Vec<Diagnostic>) {
    lower_src(&format!("{SYS}choreography G = {chor};"))
}

fn first_msg(p: &Program) -> Msg {
    let mut g = p.choreography.as_ref().expect("a choreography").body.clone();
    loop {
        match g {
            Global::Seq(items, _) => g = items[0].clone(),
            Global::Rec { body, .. } => g = *body,
            Global::Msg(m) => return m,
            other => panic!("no message first: {other:?}"),
        }
    }
}

#[test]
fn a_mavlink_message_takes_sorts_and_wire_ranges_from_the_dialect() {
    let (p, d) = lower_mav("GCS -> UAV: MISSION_COUNT(count {1 <= count}, mission_type as mt). end");
    assert!(d.is_empty(), "{d:?}");
    let m = first_msg(&p);
    assert_eq!(m.label, "MISSION_COUNT");
    assert_eq!(m.payload.len(), 2);
    let count = &m.payload[0];
    assert_eq!(count.sort, Sort::Int);
    let mav = count.mav.as_ref().expect("a MAVLink field");
    assert_eq!((mav.field.as_str(), mav.implicit, mav.user), ("count", true, true));
    // The range of a uint16_t is conjoined to the user's refinement.
    let text = crate::hir::print::expr(&p, None, count.refinement.as_ref().expect("refined"));
    assert_eq!(text, "0 <= count && count <= 65535 && 1 <= count");
    let mt = &m.payload[1];
    assert_eq!(mt.name, "mt");
    assert_eq!(mt.mav.as_ref().map(|m| m.field.as_str()), Some("mission_type"));
    assert!(p.roles.iter().all(|r| r.name == "GCS" || r.name == "UAV"));
    assert!(p.is_plain(RoleId(0)) && p.is_plain(RoleId(1)));
}

#[test]
fn unknown_messages_fields_and_entries_suggest_the_closest_names() {
    let (_, d) = lower_mav("GCS -> UAV: MISION_COUNT(count). end");
    assert_eq!(codes(&d), ["E0232"]);
    assert!(d[0].help.as_deref().unwrap_or("").contains("MISSION_COUNT"), "{d:?}");
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT(cout). end");
    assert_eq!(codes(&d), ["E0233"]);
    assert!(d[0].help.as_deref().unwrap_or("").contains("`count`"), "{d:?}");
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT(mission_type {mission_type == MAV_MISSION_TYPE_MISION}). end");
    assert_eq!(codes(&d), ["E0205"]);
    assert!(d[0].help.as_deref().unwrap_or("").contains("MAV_MISSION_TYPE_MISSION"), "{d:?}");
}

#[test]
fn enum_entries_are_int_constants_that_nothing_may_hide() {
    let (p, d) = lower_mav("UAV -> GCS: MISSION_ACK(type {type == MAV_MISSION_ACCEPTED}). end");
    assert!(d.is_empty(), "{d:?}");
    let c = p.consts.iter().find(|c| c.name == "MAV_MISSION_ACCEPTED").expect("interned");
    assert_eq!((c.sort.clone(), c.value.kind.clone()), (Sort::Int, ExprKind::Int(0)));
    // A constant of an entry's name is E0206; a binder of one is E0240.
    let (_, d) = lower_src(&format!(
        "{SYS}const MAV_MISSION_ACCEPTED: int = 3;\nchoreography G = UAV -> GCS: MISSION_ACK. end;"
    ));
    assert_eq!(codes(&d), ["E0206"]);
    let (_, d) = lower_mav("UAV -> GCS: MISSION_ACK(type as MAV_MISSION_ACCEPTED). end");
    assert_eq!(codes(&d), ["E0240"]);
    let (_, d) = lower_mav("mu t(MAV_MISSION_ERROR: int = 0). UAV -> GCS: MISSION_ACK. end");
    assert_eq!(codes(&d), ["E0240"]);
}

#[test]
fn commands_fix_the_command_and_name_their_parameters_by_label() {
    let (p, d) = lower_mav("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUTE](action {action == PARACHUTE_RELEASE}). end");
    assert!(d.is_empty(), "{d:?}");
    let m = first_msg(&p);
    assert_eq!(m.label, "COMMAND_LONG[MAV_CMD_DO_PARACHUTE]");
    let f = &m.payload[0];
    assert_eq!(f.sort, Sort::Real);
    assert_eq!(f.mav.as_ref().map(|m| (m.field.as_str(), m.written.as_str())), Some(("param1", "action")));
    // A float field has no range: the refinement is the user's alone.
    assert!(!f.mav.as_ref().is_some_and(|m| m.implicit));
    // `command` listed: fixed to the command by the label.
    let (p, d) = lower_mav("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUTE](command). end");
    assert!(d.is_empty(), "{d:?}");
    let text = crate::hir::print::expr(&p, None, first_msg(&p).payload[0].refinement.as_ref().expect("implicit"));
    assert_eq!(text, "0 <= command && command <= 65535 && command == 208");
    let (_, d) = lower_mav("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUT]. end");
    assert_eq!(codes(&d), ["E0237"]);
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT[MAV_CMD_DO_PARACHUTE]. end");
    assert_eq!(codes(&d), ["E0237"]);
    let (_, d) = lower_mav("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_CHANGE_SPEED](param4). end");
    assert_eq!(codes(&d), ["E0238"]);
    // One parameter by label and by index is listed twice.
    let (_, d) = lower_mav("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUTE](action, param1 as p). end");
    assert_eq!(codes(&d), ["E0206"]);
}

#[test]
fn field_sorts_must_agree_with_the_wire_and_arrays_are_refused() {
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT(count: real). end");
    assert_eq!(codes(&d), ["E0234"]);
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT(count: int). end");
    assert!(d.is_empty(), "{d:?}");
    let (_, d) = lower_mav("UAV -> GCS: GPS_STATUS(satellite_prn). end");
    assert_eq!(codes(&d), ["E0235"]);
}

#[test]
fn strings_compare_with_char_fields_and_must_fit_them() {
    let (p, d) = lower_mav("GCS -> UAV: PARAM_SET(param_id {param_id == \"MC_PITCH_P\"}). end");
    assert!(d.is_empty(), "{d:?}");
    let f = &first_msg(&p).payload[0];
    assert_eq!(f.sort, Sort::Str);
    assert_eq!(p.strings, vec!["MC_PITCH_P".to_string()]);
    let (_, d) = lower_mav("GCS -> UAV: PARAM_SET(param_id {param_id == \"A_NAME_OF_SEVENTEEN\"}). end");
    assert_eq!(codes(&d), ["E0236"]);
    // Strings are compared with `==` and `!=` only.
    let (_, d) = lower_mav("GCS -> UAV: PARAM_SET(param_id {param_id < \"A\"}). end");
    assert!(!d.is_empty() && codes(&d).iter().all(|c| *c == "E0208"), "{d:?}");
}

#[test]
fn has_flag_needs_an_int_and_a_positive_constant() {
    let (_, d) = lower_mav("UAV -> GCS: HEARTBEAT(base_mode {has_flag(base_mode, MAV_MODE_FLAG_SAFETY_ARMED)}). end");
    assert!(d.is_empty(), "{d:?}");
    let (_, d) = lower_mav("UAV -> GCS: HEARTBEAT(base_mode, custom_mode {has_flag(custom_mode, base_mode)}). end");
    assert_eq!(codes(&d), ["E0239"]);
    let (_, d) = lower_mav("GCS -> UAV: PARAM_SET(param_value {has_flag(param_value, 1)}). end");
    assert_eq!(codes(&d), ["E0239"]);
}

#[test]
fn dialects_are_named_once() {
    let (_, d) = lower_src(
        "dialect comon;\nsystem S { participant GCS; participant UAV; }\nchoreography G = GCS -> UAV: ping. end;",
    );
    assert_eq!(codes(&d), ["E0230"]);
    assert!(d[0].help.as_deref().unwrap_or("").contains("`common`"), "{d:?}");
    let (_, d) = lower_src(&format!("{SYS}dialect common;\nchoreography G = GCS -> UAV: HEARTBEAT. end;"));
    assert!(d.is_empty(), "{d:?}");
    let (_, d) = lower_src(&format!("{SYS}dialect minimal;\nchoreography G = GCS -> UAV: HEARTBEAT. end;"));
    assert_eq!(codes(&d), ["E0231"]);
}

#[test]
fn mavlink_syntax_outside_a_dialect_is_refused() {
    let sys = "system S { participant GCS; participant UAV; }\n";
    let (_, d) = lower_src(&format!("{sys}choreography G = GCS -> UAV: ping(x). end;"));
    assert_eq!(codes(&d), ["E0241"]);
    let (_, d) = lower_src(&format!("{sys}choreography G = GCS -> UAV: ping(x as y: int). end;"));
    assert_eq!(codes(&d), ["E0241"]);
    let (_, d) = lower_src(&format!("{sys}choreography G = GCS -> UAV: COMMAND_LONG[MAV_CMD_X]. end;"));
    assert_eq!(codes(&d), ["E0237"]);
    // Plain participants need no dialect, and ordinary labels keep working.
    let (_, d) = lower_src(&format!("{sys}choreography G = GCS -> UAV: ping(x: int {{x > 0}}). end;"));
    assert!(d.is_empty(), "{d:?}");
}

#[test]
fn plain_participants_have_no_variables_and_no_motions() {
    let (_, d) = lower_mav("GCS -> UAV: HEARTBEAT(type {type == UAV.x}). end");
    assert_eq!(codes(&d), ["E0205"]);
    assert!(d[0].message.contains("plain participant"), "{d:?}");
    let (_, d) = lower_mav("dt<UAV: hover>. end");
    assert_eq!(codes(&d), ["E0203"]);
    assert!(d[0].message.contains("plain participant"), "{d:?}");
}

/// What `mochi project` prints of a MAVLink protocol parses and lowers back to the same
/// local type (the golden test does this for `choreographies/`): `FIELD as NAME`, the
/// wire range left out and added back, a command label, a string.
#[test]
fn printed_mavlink_projections_lower_back_to_the_same_type() {
    let (p, d) = lower_mav(
        "GCS -> UAV: MISSION_COUNT(count {1 <= count}, mission_type as mt {mt == MAV_MISSION_TYPE_MISSION}).
         GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUTE](action {action == PARACHUTE_RELEASE}, command, param2 as p2).
         GCS -> UAV: PARAM_SET(param_id {param_id == \"MC_PITCH_P\"}, param_value).
         UAV -> GCS: HEARTBEAT(base_mode as b {has_flag(b, MAV_MODE_FLAG_SAFETY_ARMED)}, custom_mode: int).
         end",
    );
    assert!(d.is_empty(), "{d:?}");
    let (locals, d) = crate::project::project_all(&p);
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(locals.len(), 2);
    for (role, t) in &locals {
        let text = crate::hir::print::local(&p, t);
        let mut db = crate::source::SourceDb::new();
        let file = db.add("printed", text.clone());
        let (ast, d) = crate::syntax::parser::parse_local(file, &text);
        assert!(d.is_empty(), "{text}: {d:?}");
        let (back, d) = lower_local(&p, *role, &ast.expect("parsed"));
        assert!(d.is_empty(), "{text}: {d:?}");
        assert!(crate::project::alpha_equal(&back, t), "{text}");
        assert_eq!(crate::hir::print::local(&p, &back), text);
    }
    let uav = crate::hir::print::local(&p, &locals[&RoleId(1)]);
    assert!(uav.contains("GCS?COMMAND_LONG[MAV_CMD_DO_PARACHUTE](action: real { action == PARACHUTE_RELEASE }, command: int, param2 as p2: real)"), "{uav}");
    assert!(uav.contains("param_id: str { param_id == \"MC_PITCH_P\" }"), "{uav}");
    assert!(uav.contains("base_mode as b: int { has_flag(b, MAV_MODE_FLAG_SAFETY_ARMED) }"), "{uav}");
}

/// A field listed in a different place is another field: two projections that list
/// `target_system` and `target_component` (both `uint8_t`) in swapped places do not merge as equal.
#[test]
fn mavlink_fields_are_compared_by_field_not_by_place() {
    use crate::project::alpha_equal;
    let (p, d) = lower_mav("GCS -> UAV: MISSION_REQUEST_INT(target_system as a, target_component as b). end");
    assert!(d.is_empty(), "{d:?}");
    let (q, d) = lower_mav("GCS -> UAV: MISSION_REQUEST_INT(target_component as a, target_system as b). end");
    assert!(d.is_empty(), "{d:?}");
    let (lp, _) = crate::project::project_all(&p);
    let (lq, _) = crate::project::project_all(&q);
    assert!(!alpha_equal(&lp[&RoleId(1)], &lq[&RoleId(1)]));
    assert!(alpha_equal(&lp[&RoleId(1)], &lp[&RoleId(1)]));
}

/// A dialect that includes `common` has its entries and its own: ArduPilot's copter modes.
#[test]
fn ardupilotmega_has_commons_messages_and_its_own_entries() {
    let src = "dialect ardupilotmega;\nsystem S { participant GCS; participant UAV; }\n\
               choreography G = UAV -> GCS: HEARTBEAT(custom_mode {custom_mode != COPTER_MODE_ACRO}). end;";
    let (p, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let c = p.consts.iter().find(|c| c.name == "COPTER_MODE_ACRO").expect("interned");
    assert_eq!(c.value.kind, ExprKind::Int(1));
}

/// A field is bound from its message on: reading `seq` before MISSION_REQUEST_INT is E0205
/// (not a constant, not an entry: nothing else answers to it).
#[test]
fn a_field_read_before_its_message_is_unknown() {
    let (_, d) =
        lower_mav("GCS -> UAV: MISSION_COUNT(count {count == seq}). UAV -> GCS: MISSION_REQUEST_INT(seq). end");
    assert_eq!(codes(&d), ["E0205"]);
}

/// Robot variables, primitive parameters and footprint coordinates are binders too.
#[test]
fn robot_names_may_not_hide_entries_either() {
    let (_, d) = lower_src(
        "dialect common;\nrobot R { state MAV_MISSION_ACCEPTED: real; }\n\
         motion R.m(MAV_CMD_DO_PARACHUTE: real) { interruptible: true; footprint(PARACHUTE_RELEASE, y, z): true; }\n\
         system S { participant A: R; participant GCS; }\nchoreography G = GCS -> A: HEARTBEAT. end;",
    );
    assert_eq!(codes(&d), ["E0240", "E0240", "E0240"]);
}
