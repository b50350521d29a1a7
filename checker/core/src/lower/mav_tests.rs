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
    // A float field has no range; param1 of DO_PARACHUTE is of enum PARACHUTE_ACTION, whose
    // values are the implicit part, one by one (a float carries the entry exactly).
    let mav = f.mav.as_ref().expect("a MAVLink field");
    assert!(mav.implicit && mav.user);
    assert_eq!(mav.entry.as_ref().map(|e| e.enum_name.as_str()), Some("PARACHUTE_ACTION"));
    let text = crate::hir::print::expr(&p, None, f.refinement.as_ref().expect("refined"));
    assert_eq!(text, "float32(action) && (action == 0 || action == 1 || action == 2) && action == PARACHUTE_RELEASE");
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

// Enum-typed fields: the entry predicate in the field's type, and E0243.

/// The printed refinement of the first field of the first message of `chor`.
fn first_refinement(chor: &str) -> (Program, Field) {
    let (p, d) = lower_mav(chor);
    assert!(d.is_empty(), "{d:?}");
    let f = first_msg(&p).payload[0].clone();
    (p, f)
}

fn printed(p: &Program, f: &Field) -> String {
    crate::hir::print::expr(p, None, f.refinement.as_ref().expect("a refinement"))
}

#[test]
fn enum_typed_fields_carry_their_entries_as_runs_or_flags() {
    // A plain enum: maximal runs of values. MAV_MISSION_RESULT is 0..=15.
    let (p, f) = first_refinement("UAV -> GCS: MISSION_ACK(type as t). end");
    assert_eq!(printed(&p, &f), "0 <= t && t <= 255 && (0 <= t && t <= 15)");
    let entry = f.mav.as_ref().and_then(|m| m.entry.as_ref()).expect("an enum field");
    assert_eq!(entry.enum_name, "MAV_MISSION_RESULT");
    // MAV_MISSION_TYPE is 0, 1, 2 and 255: two runs. A user refinement comes after.
    let (p, f) = first_refinement("GCS -> UAV: MISSION_COUNT(mission_type as m {m != 1}). end");
    assert_eq!(printed(&p, &f), "0 <= m && m <= 255 && (0 <= m && m <= 2 || m == 255) && m != 1");
    // A bitmask enum: bits no flag has are clear. ATTITUDE_TARGET_TYPEMASK has no flag 8 or 16.
    let (p, f) = first_refinement("GCS -> UAV: SET_ATTITUDE_TARGET(type_mask as k). end");
    assert_eq!(printed(&p, &f), "0 <= k && k <= 255 && (!has_flag(k, 8) && !has_flag(k, 16))");
    // POSITION_TARGET_TYPEMASK's twelve flags in a uint16_t: bits 12 to 15 are clear.
    let (p, f) = first_refinement("GCS -> UAV: SET_POSITION_TARGET_LOCAL_NED(type_mask as k). end");
    assert_eq!(printed(&p, &f), "0 <= k && k <= 65535 && k <= 4095");
    // A signed field whose sign bit no flag has: MAV_BOOL in an int8_t is 0 or 1.
    let (p, f) = first_refinement("UAV -> GCS: CAMERA_IMAGE_CAPTURED(capture_result as c). end");
    assert_eq!(printed(&p, &f), "(-128) <= c && c <= 127 && (0 <= c && c <= 1)");
    // A float parameter: the values one by one (it carries the entry exactly).
    let (p, f) = first_refinement("GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm). end");
    assert_eq!(printed(&p, &f), "float32(arm) && (arm == 0 || arm == 1)");
    // Every value of the wire type allowed: nothing to add, nothing to check. MAV_MODE_FLAG
    // has a flag for each of the eight bits of HEARTBEAT.base_mode.
    let (p, f) = first_refinement("UAV -> GCS: HEARTBEAT(base_mode as b). end");
    assert_eq!(printed(&p, &f), "0 <= b && b <= 255");
    assert!(f.mav.as_ref().is_some_and(|m| m.entry.is_none()));
    // A command fixed by the label is an entry by construction.
    let (p, f) = first_refinement("GCS -> UAV: COMMAND_LONG[MAV_CMD_DO_PARACHUTE](command). end");
    assert_eq!(printed(&p, &f), "0 <= command && command <= 65535 && command == 208");
    assert!(f.mav.as_ref().is_some_and(|m| m.entry.is_none()));
}

#[test]
fn the_refinement_without_the_entry_predicate_is_the_wire_range_and_the_users() {
    for (chor, want) in [
        ("UAV -> GCS: MISSION_ACK(type as t {t != 0}). end", Some("0 <= t && t <= 255 && t != 0")),
        ("UAV -> GCS: MISSION_ACK(type as t). end", Some("0 <= t && t <= 255")),
        (
            "GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm {arm == 1.001}). end",
            Some("float32(arm) && arm == 1.001"),
        ),
        ("GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm). end", Some("float32(arm)")),
        ("GCS -> UAV: SET_ATTITUDE_TARGET(type_mask as k {k == 15}). end", Some("0 <= k && k <= 255 && k == 15")),
    ] {
        let (p, f) = first_refinement(chor);
        let without = super::refinement_without_entry(p.dialect, &f);
        let text = without.as_ref().map(|e| crate::hir::print::expr(&p, None, e));
        assert_eq!(text.as_deref(), want, "{chor}");
    }
}

/// `entry_allows` (the shortcut for a field pinned to a constant) agrees with the predicate
/// evaluated exactly, for plain, bitmask, signed and float fields, in and around the ranges.
#[test]
fn entry_allows_agrees_with_the_entry_predicate() {
    use crate::dialect::Wire;
    use crate::exact::{holds, Tri, Value};
    let d = crate::dialect::builtin("common").expect("common");
    let cases = [
        ("MAV_MISSION_RESULT", Wire::U8),
        ("MAV_MISSION_TYPE", Wire::U8),
        ("MAV_CMD", Wire::U16),
        ("ATTITUDE_TARGET_TYPEMASK", Wire::U8),
        ("POSITION_TARGET_TYPEMASK", Wire::U16),
        ("MAV_BOOL", Wire::I8),
        ("MAV_BOOL", Wire::F32),
        ("PARACHUTE_ACTION", Wire::F32),
        ("FENCE_TYPE", Wire::F32),
        ("MAV_FRAME", Wire::F32),
        ("HIL_SENSOR_UPDATED_FLAGS", Wire::U32),
    ];
    let prog = Program { dialect: Some(d), ..Program::default() };
    for (name, wire) in cases {
        let check = crate::hir::EnumCheck { enum_name: name.into(), wire, at: Loc::default() };
        let sort = if wire.is_float() { Sort::Real } else { Sort::Int };
        let x = Expr { kind: ExprKind::Var(Var::Value(ValueId(0), "x".into())), sort, loc: Loc::default() };
        let (pred, _) = super::entry_predicate(Some(d), &check, &x);
        for v in (-300i64..=300).chain([400, 511, 4095, 4096, 65535, 1 << 20, (1 << 31) - 1]) {
            let env =
                |var: &Var| matches!(var, Var::Value(ValueId(0), _)).then(|| Value::Num(crate::exact::Num::int(v)));
            // The wire range is the field's too: compare within it.
            if wire.int_range().is_some_and(|(lo, hi)| !(lo..=hi).contains(&i128::from(v))) {
                continue;
            }
            let want = holds(&prog, &pred, &env);
            assert_ne!(want, Tri::Unknown, "{name} at {v}");
            assert_eq!(super::entry_allows(Some(d), &check, v), want == Tri::True, "{name} ({wire:?}) at {v}");
        }
    }
}

/// The predicate is never the `false` fallback with a bundled dialect: every enum a field or
/// parameter names exists, and every float parameter's enum has at most
/// `MAX_REAL_VALUES` values.
#[test]
fn every_bundled_enum_reference_can_be_checked() {
    for name in crate::dialect::builtin_names() {
        let d = crate::dialect::builtin(name).expect("bundled");
        for m in &d.messages {
            for f in m.fields.iter().filter_map(|f| f.enum_name.as_ref()) {
                assert!(d.enum_(f).is_some(), "{name}: {}.{f}", m.name);
            }
        }
        let Some(cmds) = d.enum_("MAV_CMD") else { continue };
        for c in &cmds.entries {
            for p in c.params.iter() {
                let Some(e) = p.enum_name.as_ref() else { continue };
                let e = d.enum_(e).unwrap_or_else(|| panic!("{name}: {} param{} names {e}", c.name, p.index));
                let values = if e.bitmask {
                    1u128 << e.flag_mask(64).count_ones()
                } else {
                    e.value_runs().iter().map(|(lo, hi)| (hi - lo + 1) as u128).sum()
                };
                assert!(
                    values <= super::mav::MAX_REAL_VALUES as u128,
                    "{name}: {} param{}: {}",
                    c.name,
                    p.index,
                    e.name
                );
            }
        }
    }
}

/// Σ assumes a costly entry predicate by a cheaper, weaker one; the field's refinement (what
/// a sender must establish) keeps the exact one.
#[test]
fn the_global_walk_assumes_costly_enums_by_their_hull() {
    let (p, d) = lower_mav("UAV -> GCS: COMMAND_ACK(command as c, result as r). end");
    assert!(d.is_empty(), "{d:?}");
    let m = first_msg(&p);
    let cmds = p.dialect.and_then(|d| d.enum_("MAV_CMD")).expect("MAV_CMD").value_runs();
    let (lo, hi) = (cmds[0].0, cmds[cmds.len() - 1].1);
    let assumed = super::approximate_entries(p.dialect, &m).expect("MAV_CMD is approximated");
    let text = crate::hir::print::expr(&p, None, assumed.payload[0].refinement.as_ref().expect("refined"));
    assert_eq!(text, format!("{lo} <= c && c <= {hi} && (0 <= c && c <= 65535)"));
    // The exact predicate stays in the field's own refinement; MAV_RESULT (one run) is kept.
    assert!(printed(&p, &m.payload[0]).contains("||"));
    assert_eq!(assumed.payload[1].refinement, m.payload[1].refinement);
    // A bitmask's holes (div/mod) are dropped from what is assumed.
    let (p, f) = first_refinement("GCS -> UAV: SET_ATTITUDE_TARGET(type_mask as k {k != 3}). end");
    let m = Msg { payload: vec![f], ..first_msg(&p) };
    let assumed = super::approximate_entries(p.dialect, &m).expect("holes dropped");
    let text = crate::hir::print::expr(&p, None, assumed.payload[0].refinement.as_ref().expect("refined"));
    assert_eq!(text, "0 <= k && k <= 255 && k != 3");
    // Nothing to approximate: no copy.
    let (p, _) = first_refinement("UAV -> GCS: MISSION_ACK(type as t). end");
    assert!(super::approximate_entries(p.dialect, &first_msg(&p)).is_none());
}

#[test]
fn deprecated_messages_are_warned_about_once_naming_the_replacement() {
    let warnings = |d: &[Diagnostic]| -> Vec<String> {
        d.iter().filter(|d| d.severity == crate::diag::Severity::Warning).map(|d| d.message.clone()).collect()
    };
    // Twice MISSION_REQUEST: one warning, at the first, naming MISSION_REQUEST_INT.
    let (_, d) = lower_mav(
        "UAV -> GCS: MISSION_REQUEST(seq {seq == 0}). UAV -> GCS: MISSION_REQUEST(seq {seq == 1}).
         UAV -> GCS: MISSION_REQUEST_INT(seq {seq == 2}). end",
    );
    assert!(d.iter().all(|d| !d.is_error()), "{d:?}");
    assert_eq!(warnings(&d), ["`MISSION_REQUEST` is deprecated in `common`: it is replaced by `MISSION_REQUEST_INT`"]);
    assert_eq!(codes(&d), ["E0244"]);
    assert!(d[0].help.as_deref().unwrap_or("").contains("MISSION_REQUEST_INT"), "{d:?}");
    // Superseded by a command: named as one.
    let (_, d) = lower_mav("GCS -> UAV: SET_MODE(base_mode). end");
    assert_eq!(
        warnings(&d),
        ["`SET_MODE` is deprecated in `common`: it is replaced by the command `MAV_CMD_DO_SET_MODE` (`COMMAND_LONG[MAV_CMD_DO_SET_MODE]`)"]
    );
    // "Nothing" is no replacement.
    let (_, d) = lower_mav("GCS -> UAV: PROTOCOL_VERSION(version {version == 200}). end");
    assert_eq!(warnings(&d), ["`PROTOCOL_VERSION` is deprecated in `common`, with no replacement"]);
    // Nothing deprecated: nothing said.
    let (_, d) = lower_mav("GCS -> UAV: MISSION_COUNT(count). end");
    assert!(d.is_empty(), "{d:?}");
}

fn rat(s: &str) -> num_rational::BigRational {
    crate::bounds::decimal(s).expect("a decimal")
}

/// Rounding to binary32 agrees with the hardware's `f64 as f32` (round to nearest, ties to
/// even) on values that are exact doubles, ties and subnormals included; overflow is `None`.
#[test]
fn rounding_to_float32_is_the_hardwares_and_exact() {
    use num_traits::ToPrimitive;
    let samples = [
        0.1f64,
        -0.1,
        1.0,
        16_777_217.0,          // 2^24 + 1: a tie, to the even 2^24
        16_777_219.0,          // 2^24 + 3: a tie, to the even 2^24 + 4
        3.4028234663852886e38, // the largest binary32
        3.4028235677973362e38, // just below the tie with 2^128: to the largest
        1e-45,
        7e-46,                       // above half the smallest subnormal: rounds up to it
        1.401298464324817e-45 / 2.0, // exactly half: a tie, to the even 0
        123456.789,
        -2.5e-40, // a subnormal
    ];
    for v in samples {
        let r = num_rational::BigRational::from_float(v).expect("finite");
        let got = crate::lower::round_to_float(&r, crate::lower::BINARY32).expect("finite");
        assert_eq!(got.to_f64().map(|g| g as f32), Some(v as f32), "{v}");
        assert_eq!(num_rational::BigRational::from_float(v as f32), Some(got), "{v}");
    }
    // From the largest binary32 plus half its ulp on (a tie, to the even 2^128): an
    // infinity, outside the model.
    assert_eq!(
        crate::lower::round_to_float(&rat("340282356779733661637539395458142568448"), crate::lower::BINARY32),
        None
    );
    assert_eq!(crate::lower::round_to_float(&rat("3.5e38"), crate::lower::BINARY32), None);
    assert_eq!(crate::lower::round_to_float(&rat("-1e39"), crate::lower::BINARY32), None);
    assert!(crate::lower::round_to_float(&rat("1e300"), crate::lower::BINARY64).is_some());
    // 0.1 is no binary32; its rounding is, and its decimal is exact.
    assert!(!crate::lower::is_float(&rat("0.1"), crate::lower::BINARY32));
    let r = crate::lower::round_to_float(&rat("0.1"), crate::lower::BINARY32).expect("finite");
    assert!(crate::lower::is_float(&r, crate::lower::BINARY32));
    assert_eq!(crate::lower::dyadic_decimal(&r).as_deref(), Some("0.100000001490116119384765625"));
    assert_eq!(crate::lower::dyadic_decimal(&rat("-3")).as_deref(), Some("-3.0"));
    assert!(crate::lower::is_float(&r, crate::lower::BINARY64));
    assert!(!crate::lower::is_float(&rat("0.1"), crate::lower::BINARY64));
}

/// The finite-float model is part of a float field's type: its refinement carries
/// `float32(v)` (`float64` for a `double`), the conjunct a run-time monitor must check
/// (a NaN or an infinity in such a field is outside the model: LANGUAGE.md, "Floats are
/// float32"), and the program records the field's format.
#[test]
fn a_float_field_is_refined_by_its_finite_format() {
    let (p, d) = lower_mav("GCS -> UAV: PARAM_SET(param_value as v {v < 0}). end");
    assert!(d.is_empty(), "{d:?}");
    let m = first_msg(&p);
    let v = &m.payload[0];
    assert_eq!(v.sort, Sort::Real);
    assert_eq!(printed(&p, v), "float32(v) && v < 0");
    assert_eq!(p.wire_floats.get(&v.value), Some(&Builtin::Float32));
    // An integer field gets no float conjunct.
    let (p, d) = lower_mav("GCS -> UAV: MISSION_COUNT(count). end");
    assert!(d.is_empty(), "{d:?}");
    assert!(p.wire_floats.is_empty());
}

/// A string literal is its value on the wire: the text up to its first NUL.
#[test]
fn string_literals_end_at_their_first_nul() {
    let (p, d) = lower_mav(
        "GCS -> UAV: PARAM_SET(param_id {param_id == \"AB\0C\" || param_id == \"AB\0D\" || param_id == \"AB\"}). end",
    );
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(p.strings, vec!["AB".to_string()]);
}

/// `PARAM_SET["MC_PITCH_P"]` fixes the message's one `char[N]` field to the key, as a
/// command label fixes `command`; the key is kept as the wire reads it (up to its first NUL)
/// and must fit the field.
#[test]
fn keyed_labels_fix_their_string_field_as_the_wire_reads_it() {
    let (p, f) = first_refinement("GCS -> UAV: PARAM_SET[\"MC_PITCH_P\"](param_id, param_value as v). end");
    assert_eq!(first_msg(&p).label, "PARAM_SET[\"MC_PITCH_P\"]");
    assert_eq!(printed(&p, &f), "param_id == \"MC_PITCH_P\"");
    // The user's refinement is conjoined to the key.
    let (p, f) = first_refinement("GCS -> UAV: PARAM_SET[\"MC_PITCH_P\"](param_id {param_id != \"B\"}). end");
    assert_eq!(printed(&p, &f), "param_id == \"MC_PITCH_P\" && param_id != \"B\"");
    // Without the field listed the label alone says it; a NUL ends the key.
    let (p, d) = lower_mav("GCS -> UAV: PARAM_SET[\"MC_X\0Y\"](param_value as v). end");
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(first_msg(&p).label, "PARAM_SET[\"MC_X\"]");
    // param_id is a char[16]: 16 characters fit (no NUL on the wire), 17 do not.
    let (_, d) = lower_mav("GCS -> UAV: PARAM_SET[\"ABCDEFGHIJKLMNOP\"]. end");
    assert!(d.is_empty(), "{d:?}");
    let (_, d) = lower_mav("GCS -> UAV: PARAM_SET[\"ABCDEFGHIJKLMNOPQ\"]. end");
    assert_eq!(codes(&d), ["E0236"]);
    // A key needs exactly one string field to fix: none (PARAM_REQUEST_LIST), two
    // (PARAM_EXT_SET's param_id and param_value).
    let (_, d) = lower_mav("GCS -> UAV: PARAM_REQUEST_LIST[\"X\"]. end");
    assert_eq!(codes(&d), ["E0237"]);
    assert!(d[0].message.contains("no string field"), "{d:?}");
    let (_, d) = lower_mav("GCS -> UAV: PARAM_EXT_SET[\"X\"]. end");
    assert_eq!(codes(&d), ["E0237"]);
    assert!(d[0].message.contains("`param_id`, `param_value`"), "{d:?}");
    // Every message with one string field takes a key: PARAM_REQUEST_READ, PARAM_VALUE,
    // NAMED_VALUE_FLOAT.
    let (_, d) = lower_mav(
        "GCS -> UAV: PARAM_REQUEST_READ[\"A\"]. UAV -> GCS: PARAM_VALUE[\"A\"]. UAV -> GCS: NAMED_VALUE_FLOAT[\"batt\"](value). end",
    );
    assert!(d.is_empty(), "{d:?}");
}

/// Two keys of one message are two labels (a choice may offer both); a keyed label and the
/// plain message, or the same key twice however written, are one label on the wire (E0302),
/// and a step with a streamed key is E0246 while another key of the message is not.
#[test]
fn keyed_labels_overlap_only_with_their_own_key_and_the_plain_message() {
    use crate::hir::labels_overlap;
    assert!(!labels_overlap("PARAM_SET[\"A\"]", "PARAM_SET[\"B\"]"));
    assert!(labels_overlap("PARAM_SET[\"A\"]", "PARAM_SET[\"A\"]"));
    assert!(labels_overlap("PARAM_SET[\"A\"]", "PARAM_SET"));
    assert!(!labels_overlap("PARAM_SET[\"A\"]", "PARAM_VALUE[\"A\"]"));
    // The same key written with a NUL inside is the same label text (E0302, the
    // well-formedness stage's, then sees two equal labels:
    // choreographies/mavlink/rejected/E0302-same-key-written-twice.chor).
    let (p, d) = lower_mav("( GCS -> UAV: PARAM_SET[\"A\"]. end + GCS -> UAV: PARAM_SET[\"A\0B\"]. end )");
    assert!(d.is_empty(), "{d:?}");
    let Some(Global::Choice(bs, _)) = p.choreography.as_ref().map(|c| c.body.clone()) else { panic!("a choice") };
    let labels: Vec<String> = bs
        .iter()
        .map(|b| match b {
            Global::Seq(items, _) => match &items[0] {
                Global::Msg(m) => m.label.clone(),
                other => panic!("{other:?}"),
            },
            Global::Msg(m) => m.label.clone(),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(labels, ["PARAM_SET[\"A\"]", "PARAM_SET[\"A\"]"]);
    let streamed = |step: &str| {
        lower_src(&format!(
            "dialect common;\nsystem S {{ participant GCS; participant UAV; \
             stream UAV -> GCS: PARAM_VALUE[\"A\"](param_value as a); }}\n\
             choreography G = GCS -> UAV: PARAM_REQUEST_READ[\"B\"]. UAV -> GCS: {step}. end;"
        ))
        .1
    };
    assert!(streamed("PARAM_VALUE[\"B\"]").is_empty());
    assert_eq!(codes(&streamed("PARAM_VALUE[\"A\"]")), ["E0246"]);
    assert_eq!(codes(&streamed("PARAM_VALUE")), ["E0246"]);
}
