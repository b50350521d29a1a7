//! The hand-over's digest: what `mochi proxy` computes over the sources it verified is what
//! `mochi-proxy` computes over the same sources read again, and any other bytes, a missing
//! digest or a changed import are refused with E0801.

use super::*;
use std::collections::HashMap;
use std::path::PathBuf;

const LIB: &str = "const limit = 10;\n";
const SET: &str = "import \"lib.mochi\";
dialect common;
system S { participant GCS; participant UAV; }
choreography Set =
  GCS -> UAV: PARAM_SET(param_value as v {v <= limit}).
  UAV -> GCS: PARAM_VALUE(param_value {param_value == v}).
  end;";

/// A file system in memory.
fn files(pairs: &[(&str, &str)]) -> HashMap<PathBuf, String> {
    pairs.iter().map(|(p, t)| (PathBuf::from(p), t.to_string())).collect()
}

/// What `mochi proxy` does: the sources as its verification read them (a fresh database,
/// the root first, then the imports), and their digest.
fn verified(fs: &HashMap<PathBuf, String>) -> String {
    let mut db = SourceDb::new();
    let root = db.add("dir/set.chor", fs[Path::new("dir/set.chor")].clone());
    let mut read = |p: &Path| fs.get(p).cloned().ok_or_else(|| std::io::Error::other("no such file"));
    let (_, d) = syntax::parse_with_imports(&mut db, root, &mut read);
    assert!(d.is_empty(), "{d:?}");
    verified_digest(&db, root).expect("every import was read")
}

/// What `mochi-proxy` does with `digest` and the files as they are now.
fn enforce(fs: &HashMap<PathBuf, String>, digest: Option<&str>) -> Result<Automaton, Vec<Diagnostic>> {
    let mut db = SourceDb::new();
    let mut read = |p: &Path| fs.get(p).cloned().ok_or_else(|| std::io::Error::other("no such file"));
    let req = Request { path: Path::new("dir/set.chor"), verified: digest };
    load(&mut db, &req, fs[Path::new("dir/set.chor")].clone(), &mut read)
}

fn refused(r: Result<Automaton, Vec<Diagnostic>>) -> Diagnostic {
    match r {
        Ok(_) => panic!("enforced"),
        Err(d) => {
            assert_eq!(d.len(), 1, "{d:?}");
            d[0].clone()
        }
    }
}

#[test]
fn the_digest_of_the_verified_sources_is_accepted() {
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let d = verified(&fs);
    assert_eq!(d.len(), 64);
    assert!(d.bytes().all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase()));
    let a = enforce(&fs, Some(&d)).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(a.name, "Set");
}

#[test]
fn a_protocol_without_a_digest_is_refused() {
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let d = refused(enforce(&fs, None));
    assert_eq!(d.code, Code::MonitorNotVerified);
    assert!(d.message.contains("not verified"), "{}", d.message);
    assert!(d.help.as_deref().is_some_and(|h| h.contains("mochi proxy")));
}

#[test]
fn a_protocol_changed_after_its_verification_is_refused() {
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let d = verified(&fs);
    let edited = files(&[("dir/set.chor", &SET.replace("v <= limit", "v <= 1000")), ("dir/lib.mochi", LIB)]);
    assert_eq!(refused(enforce(&edited, Some(&d))).code, Code::MonitorNotVerified);
    // An import counts as much as the file itself.
    let lib = files(&[("dir/set.chor", SET), ("dir/lib.mochi", "const limit = 1000;\n")]);
    assert_eq!(refused(enforce(&lib, Some(&d))).code, Code::MonitorNotVerified);
    // So does an import that is gone.
    let gone = files(&[("dir/set.chor", SET)]);
    assert_eq!(refused(enforce(&gone, Some(&d))).code, Code::MonitorNotVerified);
    // And a digest of nothing in particular.
    assert_eq!(refused(enforce(&fs, Some(&"0".repeat(64)))).code, Code::MonitorNotVerified);
}

/// The digest is of the bytes the verification read, not of a later read of the same path
/// (the command line reads the root file again to compile it, after the verification).
#[test]
fn the_digest_is_of_the_first_read() {
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let mut db = SourceDb::new();
    let root = db.add("dir/set.chor", SET);
    db.add("dir/lib.mochi", LIB);
    db.add("dir/set.chor", "changed later");
    db.add("dir/lib.mochi", "changed later");
    assert_eq!(verified_digest(&db, root), Some(verified(&fs)));
    // An import the verification did not read: no digest.
    let mut alone = SourceDb::new();
    let root = alone.add("dir/set.chor", SET);
    assert_eq!(verified_digest(&alone, root), None);
}

#[test]
fn a_refusal_reads_as_plain_text_with_its_place() {
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let mut db = SourceDb::new();
    let mut read = |p: &Path| fs.get(p).cloned().ok_or_else(|| std::io::Error::other("no such file"));
    let req = Request { path: Path::new("dir/set.chor"), verified: None };
    let Err(d) = load(&mut db, &req, SET.to_string(), &mut read) else { panic!("enforced") };
    let text = plain(&db, &d[0]);
    assert!(text.starts_with("error[E0801]: dir/set.chor:1:1: dir/set.chor was not verified"), "{text}");
    assert!(text.contains("= help: mochi-proxy enforces only protocols"), "{text}");
}

/// What `mochi-proxy` keeps of a loaded protocol (the automaton, and of its program the
/// names, constants and strings, not the choreography's body) monitors as the whole compiled
/// program does: the same outcomes, and the same explanations of its violations.
#[test]
fn a_loaded_protocol_monitors_as_the_whole_program_does() {
    use crate::mavio::Frame;
    use crate::monitor::{Monitor, Outcome};
    use mavlink::dialects::common::{MavMessage, MavParamType, PARAM_SET_DATA, PARAM_VALUE_DATA};
    use mavlink::{MavlinkVersion, Message};
    let fs = files(&[("dir/set.chor", SET), ("dir/lib.mochi", LIB)]);
    let loaded = enforce(&fs, Some(&verified(&fs))).unwrap_or_else(|e| panic!("{e:?}"));
    assert!(matches!(loaded.prog.choreography.as_ref().map(|c| &c.body), Some(Global::End(_))));
    let mut db = SourceDb::new();
    let root = db.add("dir/set.chor", SET);
    let mut read = |p: &Path| fs.get(p).cloned().ok_or_else(|| std::io::Error::other("no such file"));
    let (parsed, d) = syntax::parse_with_imports(&mut db, root, &mut read);
    assert!(d.is_empty(), "{d:?}");
    let whole = Automaton::compile(&crate::lower::lower(&parsed).0).expect("compiles");
    let set = |v: f32| {
        MavMessage::PARAM_SET(PARAM_SET_DATA {
            param_value: v,
            target_system: 1,
            target_component: 1,
            param_id: [0; 16].into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        })
    };
    let value = |v: f32| MavMessage::PARAM_VALUE(PARAM_VALUE_DATA { param_value: v, ..Default::default() });
    // Conforming, then a value above the limit, then a wrong echo.
    let trace = [(true, set(5.0)), (false, value(5.0)), (true, set(50.0)), (true, set(3.0)), (false, value(4.0))];
    let run = |a: &Automaton| {
        let mut m = Monitor::new(vec![a.clone()]);
        let mut out = Vec::new();
        for (from_gcs, msg) in &trace {
            let mut payload = [0u8; 255];
            let n = msg.ser(MavlinkVersion::V2, &mut payload);
            let (sysid, compid) = if *from_gcs { (255, 190) } else { (1, 1) };
            let f = Frame {
                time_us: Some(1000),
                version: 2,
                sysid,
                compid,
                msgid: msg.message_id(),
                payload: &payload[..n],
                signed: false,
                raw: &[],
            };
            out.push(match m.on_frame(&f) {
                Outcome::Violation(v) => format!("violation: {}", m.describe(&db, v)),
                o => format!("{o:?}"),
            });
        }
        out
    };
    let (a, b) = (run(&loaded), run(&whole));
    assert_eq!(a, b);
    assert_eq!(a.iter().filter(|o| o.starts_with("violation")).count(), 2, "{a:?}");
}
