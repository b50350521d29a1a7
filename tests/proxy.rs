//! `mochi proxy` end to end with real MAVLink peers on loopback: pymavlink and MAVSDK as the
//! ground station and as the vehicle (tests/proxy/peers.py), through the proxy enforcing the
//! protocols of `choreographies/mavlink/`. A mission of 117 items arrives intact, a parameter
//! is set, a command is acknowledged; a vehicle that acknowledges an upload early and a
//! PARAM_SET that breaks `param-set.chor`'s dependency are dropped.
//!
//! The peers are Python packages (.ci/run installs them, pinned). When one is missing, the
//! test says so and passes when the `CI` variable is unset, and fails when it is set.

use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub(crate) const PEERS: &str = "tests/proxy/peers.py";
pub(crate) const MISSION: &str =
    "../shared/data/missions/ardupilot_autotest/ArduPlane_Tests/TerrainAvoidApplet/TopOfTheWorld.txt";

/// Whether the Python package `module` can be imported; in CI a missing one fails the test.
pub(crate) fn have(module: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        if std::env::var_os("CI").is_some() {
            panic!("the Python package `{module}` is missing in CI (.ci/run installs it)");
        }
        eprintln!("skipped: the Python package `{module}` is not installed (.ci/run installs it)");
    }
    ok
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0").and_then(|s| s.local_addr()).map(|a| a.port()).expect("a free port")
}

/// A child process whose stdout lines are collected; killed when dropped.
pub(crate) struct Running {
    child: Child,
    pub(crate) lines: Arc<Mutex<Vec<String>>>,
}

impl Running {
    pub(crate) fn spawn(cmd: &mut Command) -> Running {
        let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::null()).spawn().expect("spawns");
        let lines = Arc::new(Mutex::new(Vec::new()));
        let out = child.stdout.take().expect("stdout");
        let sink = lines.clone();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                sink.lock().unwrap().push(l);
            }
        });
        Running { child, lines }
    }

    pub(crate) fn json(&self) -> Vec<serde_json::Value> {
        self.lines.lock().unwrap().iter().filter_map(|l| serde_json::from_str(l).ok()).collect()
    }

    /// Waits until a JSON line satisfies `pred` (or `timeout` passes).
    pub(crate) fn wait_for(
        &self,
        timeout: Duration,
        pred: impl Fn(&serde_json::Value) -> bool,
    ) -> Option<serde_json::Value> {
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            if let Some(v) = self.json().into_iter().find(&pred) {
                return Some(v);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        None
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A proxy enforcing `protocols`, its ends on two free loopback ports: the ground station
/// sends to the first, the vehicle listens on the second.
pub(crate) fn proxy(protocols: &[&str], extra: &[&str]) -> (Running, u16, u16) {
    let (g, v) = (free_port(), free_port());
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mochi"));
    cmd.arg("proxy");
    for p in protocols {
        cmd.args(["--protocol", &format!("choreographies/mavlink/{p}")]);
    }
    cmd.args(["--gcs", &format!("udpin:127.0.0.1:{g}"), "--vehicle", &format!("udpout:127.0.0.1:{v}")]);
    cmd.args(extra);
    let p = Running::spawn(&mut cmd);
    assert!(
        p.wait_for(Duration::from_secs(60), |l| l["event"] == "start").is_some(),
        "the proxy did not start: {:?}",
        p.lines.lock().unwrap()
    );
    (p, g, v)
}

pub(crate) fn peer(args: &[&str]) -> Running {
    Running::spawn(Command::new("python3").arg("-u").arg(PEERS).args(args))
}

fn done(gcs: &Running, secs: u64) -> serde_json::Value {
    gcs.wait_for(Duration::from_secs(secs), |l| l.get("done").is_some())
        .unwrap_or_else(|| panic!("the ground station did not finish: {:?}", gcs.lines.lock().unwrap()))
}

pub(crate) fn violations(p: &Running) -> Vec<serde_json::Value> {
    p.json().into_iter().filter(|l| l["event"] == "violation").collect()
}

/// Two missions are the same item for item: integers exactly, reals as float32 (the wire
/// type of MISSION_ITEM_INT's params and z).
fn same_items(sent: &serde_json::Value, got: &serde_json::Value) {
    let (s, g) = (sent.as_array().expect("items"), got.as_array().expect("items"));
    assert_eq!(s.len(), g.len(), "item count");
    for (a, b) in s.iter().zip(g) {
        let (a, b) = (a.as_array().unwrap(), b.as_array().unwrap());
        for (k, (x, y)) in a.iter().zip(b).enumerate() {
            if k == 3 {
                continue; // `current`: MAVSDK keeps its own
            }
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert_eq!(x as f32, y as f32, "item {a:?} field {k} arrived as {b:?}");
        }
    }
}

#[test]
fn pymavlink_uploads_a_117_item_mission_through_the_proxy_intact() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    let gcs = peer(&["gcs-mission", &format!("udpout:127.0.0.1:{g}"), MISSION, "40"]);
    let d = done(&gcs, 60);
    assert_eq!(d["ack"], 0, "MAV_MISSION_ACCEPTED: {d}");
    assert_eq!(d["items"].as_array().unwrap().len(), 117);
    let got = vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "mission").expect("the vehicle got it");
    same_items(&d["items"], &got["items"]);
    assert_eq!(got["acked_early"], false);
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
    let end = p.wait_for(Duration::from_secs(5), |l| l["event"] == "end").expect("the session ended");
    assert_eq!(end["conformant"], true);
    let steps = p.json().iter().filter(|l| l["event"] == "step").count();
    assert!(steps >= 2 * 117, "{steps} steps");
}

#[test]
fn pymavlink_sets_a_parameter_through_the_proxy() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["param-set.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    let gcs = peer(&["gcs-param", &format!("udpout:127.0.0.1:{g}"), "200"]);
    let d = done(&gcs, 40);
    assert_eq!(d["read"]["MC_PITCH_P"], 6.5, "{d}");
    assert_eq!(d["echo"], 200.0, "{d}");
    assert!(vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "param_set").is_some());
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
    assert!(p.wait_for(Duration::from_secs(5), |l| l["event"] == "end" && l["conformant"] == true).is_some());
}

#[test]
fn a_param_set_breaking_the_dependency_is_dropped() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["param-set.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    // MC_PITCH_P = 6.5, FF = 0: the bound is 540 / 2.3 = 234.8 deg/s; 300 breaks it.
    let gcs = peer(&["gcs-param", &format!("udpout:127.0.0.1:{g}"), "300"]);
    let d = done(&gcs, 40);
    assert_eq!(d["read"]["MC_PITCH_P"], 6.5, "the reads went through: {d}");
    assert!(d["echo"].is_null(), "the vehicle never saw the PARAM_SET: {d}");
    assert!(vehicle.json().iter().all(|l| l["event"] != "param_set"), "{:?}", vehicle.json());
    let v = violations(&p);
    assert_eq!(v.len(), 1, "{v:?}");
    assert_eq!(v[0]["msgid"], 23, "PARAM_SET");
    assert_eq!(v[0]["kind"], "refinement");
    assert_eq!(v[0]["action"], "drop");
    assert_eq!(v[0]["dir"], "gcs->vehicle");
    assert!(v[0]["detail"].as_str().unwrap().contains("param-set.chor"), "{}", v[0]);
}

#[test]
fn an_early_mission_ack_is_flagged_and_dropped() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "early-ack", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    let gcs = peer(&["gcs-mission", &format!("udpout:127.0.0.1:{g}"), MISSION, "5"]);
    let d = done(&gcs, 40);
    assert!(d["ack"].is_null(), "the ground station never saw the early ACK: {d}");
    let early = vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "mission").expect("the vehicle acked");
    assert_eq!(early["acked_early"], true);
    let acks: Vec<_> = violations(&p).into_iter().filter(|l| l["msgid"] == 47).collect();
    assert!(!acks.is_empty(), "{:?}", violations(&p));
    assert_eq!(acks[0]["dir"], "vehicle->gcs");
    assert_eq!(acks[0]["action"], "drop");
    assert_eq!(acks[0]["kind"], "refinement");
}

#[test]
fn alert_only_lets_the_early_ack_through_and_reports_it() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor"], &["--alert-only"]);
    let _vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "early-ack", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    let gcs = peer(&["gcs-mission", &format!("udpout:127.0.0.1:{g}"), MISSION, "10"]);
    let d = done(&gcs, 40);
    assert_eq!(d["ack"], 0, "the early ACK went through: {d}");
    // The verdict line follows the forwarding: wait for it.
    let ack = p.wait_for(Duration::from_secs(5), |l| l["event"] == "violation" && l["msgid"] == 47);
    assert_eq!(ack.map(|a| a["action"].clone()), Some("alert".into()), "{:?}", violations(&p));
}

#[test]
fn pymavlink_arms_through_the_proxy() {
    if !have("pymavlink") {
        return;
    }
    let (p, g, v) = proxy(&["arm-command.chor"], &[]);
    let _vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60"]);
    std::thread::sleep(Duration::from_millis(500));
    let gcs = peer(&["gcs-arm", &format!("udpout:127.0.0.1:{g}")]);
    let d = done(&gcs, 40);
    assert_eq!(d["ack"], serde_json::json!([400, 0]), "{d}");
    assert_eq!(d["armed"], true, "{d}");
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
    assert!(p.wait_for(Duration::from_secs(5), |l| l["event"] == "end" && l["conformant"] == true).is_some());
}

#[test]
fn mavsdk_mission_raw_uploads_to_mission_raw_server_through_the_proxy() {
    if !have("mavsdk") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor"], &[]);
    let vehicle = peer(&["mavsdk-vehicle", &format!("udpin:127.0.0.1:{v}"), "60"]);
    std::thread::sleep(Duration::from_millis(1000));
    let gcs = peer(&["mavsdk-gcs", &format!("udpout:127.0.0.1:{g}"), "mission", MISSION]);
    let d = done(&gcs, 60);
    assert_eq!(d["result"], "ok", "{d}");
    let got = vehicle.wait_for(Duration::from_secs(10), |l| l["event"] == "mission").expect("the server got it");
    same_items(&d["items"], &got["items"]);
    let upload: Vec<_> = violations(&p).into_iter().filter(|l| l["msgid"] != 42).collect();
    assert!(upload.is_empty(), "violations other than MISSION_CURRENT telemetry: {upload:?}");
}

#[test]
fn mavsdk_param_sets_a_parameter_on_param_server_through_the_proxy() {
    if !have("mavsdk") {
        return;
    }
    let (p, g, v) = proxy(&["param-set.chor"], &[]);
    let _vehicle = peer(&["mavsdk-vehicle", &format!("udpin:127.0.0.1:{v}"), "60"]);
    std::thread::sleep(Duration::from_millis(1000));
    let gcs = peer(&["mavsdk-gcs", &format!("udpout:127.0.0.1:{g}"), "param", "200"]);
    let d = done(&gcs, 60);
    assert_eq!(d["after"], 200.0, "{d}");
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
}

/// Enforced, `arm-command.chor` carries MAVSDK's arming: the vehicle's HEARTBEAT is a stream
/// (so MAVSDK discovers the autopilot through the proxy), the acknowledgement is labelled
/// `COMMAND_ACK[MAV_CMD_COMPONENT_ARM_DISARM]` (MAVSDK's other commands and their
/// acknowledgements are not the protocol's), and `param2` (force), which MAVSDK sends as NaN
/// ("unset", as common.xml's MAV_CMD allows), is not listed. No violation, nothing dropped,
/// and the session ends conformant.
#[test]
fn mavsdk_action_arms_action_server_through_the_proxy() {
    if !have("mavsdk") {
        return;
    }
    let (p, g, v) = proxy(&["arm-command.chor"], &[]);
    let vehicle = peer(&["mavsdk-vehicle", &format!("udpin:127.0.0.1:{v}"), "60"]);
    std::thread::sleep(Duration::from_millis(1000));
    let gcs = peer(&["mavsdk-gcs", &format!("udpout:127.0.0.1:{g}"), "arm"]);
    let d = done(&gcs, 60);
    assert_eq!(d["result"], "ok", "{d}");
    assert!(vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "arm").is_some());
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
    assert!(p.wait_for(Duration::from_secs(5), |l| l["event"] == "end" && l["conformant"] == true).is_some());
}

/// Enforced, `compass-calibration.chor` leaves MAVSDK's connection and arming alone: it names
/// no HEARTBEAT (a refused or silent calibration ends by a timeout) and its acknowledgement
/// is `COMMAND_ACK[MAV_CMD_DO_START_MAG_CAL]`, so the acknowledgements of MAVSDK's other
/// commands pass. MAVSDK discovers the autopilot through the proxy and arms it, and nothing
/// is dropped. When the calibration ended with the vehicle's HEARTBEAT, every HEARTBEAT
/// outside a calibration was dropped and MAVSDK never saw the vehicle. (`parachute.chor` is
/// not for this vehicle: MAVSDK's server announces no ArduPilot quadrotor, which breaks the
/// parachute's HEARTBEAT stream invariant, so its heartbeats pass as no readings and a
/// release to it would be dropped.)
#[test]
fn mavsdk_arms_through_the_calibration_protocol() {
    if !have("mavsdk") {
        return;
    }
    let (p, g, v) = proxy(&["compass-calibration.chor"], &[]);
    let vehicle = peer(&["mavsdk-vehicle", &format!("udpin:127.0.0.1:{v}"), "60"]);
    std::thread::sleep(Duration::from_millis(1000));
    let gcs = peer(&["mavsdk-gcs", &format!("udpout:127.0.0.1:{g}"), "arm"]);
    let d = done(&gcs, 60);
    assert_eq!(d["result"], "ok", "{d}");
    assert!(vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "arm").is_some());
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
}

// ---- the parachute: observed state through the proxy ----------------------------------

/// A MAVLink 2 frame of `m` from `from` (common dialect; the proxy checks with
/// ardupilotmega, which includes it).
fn mav(from: (u8, u8), seq: u8, m: &mavlink::dialects::common::MavMessage) -> Vec<u8> {
    let h = mavlink::MavHeader { system_id: from.0.into(), component_id: from.1, sequence: seq };
    let mut f = Vec::new();
    mavlink::write_versioned_msg(&mut f, mavlink::MavlinkVersion::V2, h, m).expect("encodes");
    f
}

/// The vehicle's state as it streams it: HEARTBEAT of an ArduPilot quadrotor (armed or
/// not, in LOITER) and its position (50 m above home, not descending).
fn vehicle_state(armed: bool) -> [mavlink::dialects::common::MavMessage; 2] {
    use mavlink::dialects::common::*;
    [
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 5,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode: if armed { MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED } else { MavModeFlag::empty() },
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA { relative_alt: 50_000, vz: 0, ..Default::default() }),
    ]
}

fn parachute_release() -> mavlink::dialects::common::MavMessage {
    use mavlink::dialects::common::*;
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: 2.0, // PARACHUTE_RELEASE
        command: MavCmd::MAV_CMD_DO_PARACHUTE,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    })
}

/// `parachute.chor` through the proxy: a DO_PARACHUTE release while the vehicle streams that
/// it is disarmed is dropped (the guard reads the observed `base_mode`); once it streams that
/// it is armed, 50 m up and not descending, the same command goes through.
#[test]
fn a_parachute_release_in_a_wrong_vehicle_state_is_dropped() {
    use mavlink::dialects::common::*;
    let (p, g, v) = proxy(&["parachute.chor"], &[]);
    let vehicle = UdpSocket::bind(("127.0.0.1", v)).expect("the vehicle's port");
    vehicle.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let gcs = UdpSocket::bind("127.0.0.1:0").unwrap();
    gcs.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    gcs.connect(("127.0.0.1", g)).unwrap();
    let mut b = [0u8; 2048];
    // A message outside the protocol's alphabet opens the path to the vehicle.
    let ping = MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA { target_system: 1, target_component: 1 });
    gcs.send(&mav((255, 190), 0, &ping)).unwrap();
    let (_, at) = vehicle.recv_from(&mut b).expect("the proxy forwards outside the alphabet");
    let mut seq = 1;
    let mut stream = |armed: bool| {
        for m in vehicle_state(armed) {
            vehicle.send_to(&mav((1, 1), seq, &m), at).unwrap();
            seq += 1;
            let mut b = [0u8; 2048];
            gcs.recv(&mut b).expect("the vehicle's stream reaches the ground station");
        }
    };
    stream(false);
    let release = mav((255, 190), 1, &parachute_release());
    gcs.send(&release).unwrap();
    gcs.send(&mav((255, 190), 2, &ping)).unwrap();
    let (n, _) = vehicle.recv_from(&mut b).unwrap();
    assert_eq!(&b[..n], &mav((255, 190), 2, &ping)[..], "the release was forwarded while disarmed");
    let dropped = p.wait_for(Duration::from_secs(5), |l| l["event"] == "violation").expect("a violation line");
    assert_eq!(
        (dropped["kind"].as_str(), dropped["action"].as_str(), dropped["msgid"].as_u64()),
        (Some("guard"), Some("drop"), Some(76))
    );
    // The ground station's own HEARTBEAT, while the vehicle is safe to release: forwarded
    // (no step, and no reading of the vehicle's HEARTBEAT stream, whose invariant a ground
    // station's `MAV_TYPE_GCS` breaks). Dropping it would starve the vehicle of the ground
    // station's heartbeats (ArduPilot's GCS failsafe).
    stream(true);
    let gcs_heartbeat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        ..Default::default()
    });
    let hb = mav((255, 190), 3, &gcs_heartbeat);
    gcs.send(&hb).unwrap();
    let (n, _) = vehicle.recv_from(&mut b).unwrap();
    assert_eq!(&b[..n], &hb[..], "the ground station's HEARTBEAT is forwarded");
    gcs.send(&release).unwrap();
    let (n, _) = vehicle.recv_from(&mut b).unwrap();
    assert_eq!(&b[..n], &release[..], "the release in the right state is forwarded");
    // The vehicle acknowledges it (`COMMAND_ACK[MAV_CMD_DO_PARACHUTE]`): the session ends.
    let ack = MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
        command: MavCmd::MAV_CMD_DO_PARACHUTE,
        result: MavResult::MAV_RESULT_ACCEPTED,
        target_system: 255,
        target_component: 190,
        ..Default::default()
    });
    vehicle.send_to(&mav((1, 1), 9, &ack), at).unwrap();
    gcs.recv(&mut b).expect("the acknowledgement reaches the ground station");
    let end = p.wait_for(Duration::from_secs(5), |l| l["event"] == "end").expect("the session ended");
    assert_eq!(end["conformant"], true);
    assert_eq!(violations(&p).len(), 1, "only the early release: {:?}", violations(&p));
}

/// `parachute.chor` is for ArduPilot quadrotors, yet the HEARTBEATs of a PX4 quadrotor and of
/// a camera (which break its HEARTBEAT stream's invariant) reach the ground station through
/// the proxy: dropping them hid every other vehicle and component from it. They are no
/// readings, and the PX4's erases the safe reading its end streamed before, so a release to
/// the PX4 vehicle is dropped (no reading).
#[test]
fn heartbeats_of_other_autopilots_and_components_pass_the_parachute_protocol() {
    use mavlink::dialects::common::*;
    let (p, g, v) = proxy(&["parachute.chor"], &[]);
    let vehicle = UdpSocket::bind(("127.0.0.1", v)).expect("the vehicle's port");
    vehicle.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let gcs = UdpSocket::bind("127.0.0.1:0").unwrap();
    gcs.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    gcs.connect(("127.0.0.1", g)).unwrap();
    let mut b = [0u8; 2048];
    let ping = MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA { target_system: 1, target_component: 1 });
    gcs.send(&mav((255, 190), 0, &ping)).unwrap();
    let (_, at) = vehicle.recv_from(&mut b).expect("the proxy forwards outside the alphabet");
    let heartbeat = |mavtype, autopilot| {
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype,
            autopilot,
            base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
            ..Default::default()
        })
    };
    let [ardupilot, position] = vehicle_state(true);
    let px4 = heartbeat(MavType::MAV_TYPE_QUADROTOR, MavAutopilot::MAV_AUTOPILOT_PX4);
    let camera = heartbeat(MavType::MAV_TYPE_CAMERA, MavAutopilot::MAV_AUTOPILOT_INVALID);
    let sent = [((1, 1), &ardupilot), ((1, 1), &position), ((1, 100), &camera), ((1, 1), &px4)];
    for (seq, (from, m)) in (1..).zip(sent) {
        let f = mav(from, seq, m);
        vehicle.send_to(&f, at).unwrap();
        let n = gcs.recv(&mut b).expect("every HEARTBEAT and reading reaches the ground station");
        assert_eq!(&b[..n], &f[..]);
    }
    gcs.send(&mav((255, 190), 1, &parachute_release())).unwrap();
    gcs.send(&mav((255, 190), 2, &ping)).unwrap();
    let (n, _) = vehicle.recv_from(&mut b).unwrap();
    assert_eq!(&b[..n], &mav((255, 190), 2, &ping)[..], "the release to the PX4 vehicle was forwarded");
    let dropped = p.wait_for(Duration::from_secs(5), |l| l["event"] == "violation").expect("a violation line");
    assert_eq!(
        (dropped["kind"].as_str(), dropped["action"].as_str(), dropped["msgid"].as_u64()),
        (Some("no reading"), Some("drop"), Some(76))
    );
    assert_eq!(violations(&p).len(), 1, "only the release: {:?}", violations(&p));
}

// ---- the two processes: `mochi proxy` verifies, `mochi-proxy` enforces -----------------

/// The enforcing process is `mochi-proxy` (`mochi proxy` replaced itself with it) and maps
/// no libz3 and no libstdc++: the solver is not in the process that stands on the link.
#[cfg(target_os = "linux")]
#[test]
fn the_enforcing_process_is_mochi_proxy_without_z3() {
    let (p, _, _) = proxy(&["param-set.chor", "mission-upload-tolerant.chor"], &[]);
    let pid = p.child.id();
    let exe = std::fs::read_link(format!("/proc/{pid}/exe")).expect("the process's executable");
    assert_eq!(exe.file_name().and_then(|n| n.to_str()), Some("mochi-proxy"), "{}", exe.display());
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).expect("its mappings");
    for lib in ["libz3", "libstdc++"] {
        assert!(!maps.contains(lib), "the enforcing process maps {lib}:\n{maps}");
    }
}

/// `mochi-proxy` on `path` with these extra arguments: its exit code and stderr (it must
/// refuse before opening an end, so the ends are never used).
fn small(path: &str, extra: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mochi-proxy"))
        .args(["--protocol", path])
        .args(extra)
        .args(["--gcs", &format!("udpin:127.0.0.1:{}", free_port()), "--vehicle", "udpout:127.0.0.1:9"])
        .stdin(Stdio::null())
        .output()
        .expect("runs mochi-proxy");
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// The digest `mochi proxy` hands over for the protocol at `path` (its sources as read now).
fn digest_of(path: &str) -> String {
    let mut db = mochi::source::SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, std::path::Path::new(path)).expect("reads");
    let mut load = |p: &std::path::Path| mochi::fsload::read_bytes(p);
    mochi::driver::prepare(&mut db, root, &mut load, mochi::driver::Stage::Names).expect("lowers");
    mochi::proxy::handoff::verified_digest(&db, root).expect("a digest")
}

/// Run by hand, the small executable enforces no protocol `mochi proxy` did not verify: one
/// without a digest (here a protocol `mochi check` rejects) is refused with E0801, and so is
/// a verified protocol changed after its digest was computed. The same file with the right
/// digest starts.
#[test]
fn mochi_proxy_refuses_a_protocol_without_the_digest_of_its_verification() {
    let rejected = "choreographies/mavlink/rejected/E0316-rally-count-beyond-storage.chor";
    let (code, err) = small(rejected, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("error[E0801]") && err.contains("was not verified by `mochi proxy`"), "{err}");
    // A digest of other bytes is refused too.
    let (code, err) = small(rejected, &["--verified", &digest_of("choreographies/mavlink/param-set.chor")]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("error[E0801]") && err.contains("is not what `mochi proxy` verified"), "{err}");

    // A verified protocol, copied with the profiles it imports: with its digest it starts;
    // with an import changed afterwards, it is refused.
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("handoff-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("profiles")).unwrap();
    let copy = dir.join("param-set.chor");
    std::fs::copy("choreographies/mavlink/param-set.chor", &copy).unwrap();
    for e in std::fs::read_dir("choreographies/mavlink/profiles").unwrap() {
        let e = e.unwrap().path();
        std::fs::copy(&e, dir.join("profiles").join(e.file_name().unwrap())).unwrap();
    }
    let copy = copy.to_str().unwrap().to_string();
    let digest = digest_of(&copy);
    let (g, v) = (free_port(), free_port());
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mochi-proxy"));
    cmd.args(["--protocol", &copy, "--verified", &digest]);
    cmd.args(["--gcs", &format!("udpin:127.0.0.1:{g}"), "--vehicle", &format!("udpout:127.0.0.1:{v}")]);
    let p = Running::spawn(&mut cmd);
    let start = p.wait_for(Duration::from_secs(30), |l| l["event"] == "start").expect("it starts with the digest");
    assert_eq!(start["protocols"], serde_json::json!(["SetPitchRateMax"]), "{start}");
    drop(p);
    let import = dir.join("profiles/px4.mochi");
    let text = std::fs::read_to_string(&import).unwrap();
    std::fs::write(&import, text + "// edited after the verification\n").unwrap();
    let (code, err) = small(&copy, &["--verified", &digest]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("error[E0801]") && err.contains("changed since it was verified"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without `mochi-proxy` next to it, `mochi proxy` says so and stops (exit 1) rather than
/// enforcing in a process with Z3 unasked; `--in-process` enforces there.
#[cfg(unix)]
#[test]
fn mochi_proxy_missing_is_an_error_that_says_what_to_do() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("alone-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let alone = dir.join("mochi");
    let _ = std::fs::remove_file(&alone);
    // A hard link: the same executable under another directory, no copy.
    if std::fs::hard_link(env!("CARGO_BIN_EXE_mochi"), &alone).is_err() {
        eprintln!("skipped: cannot link the mochi executable into {}", dir.display());
        return;
    }
    let args = |extra: &[&str]| {
        let mut c = Command::new(&alone);
        c.args(["proxy", "--protocol", "choreographies/mavlink/param-set.chor"]);
        c.args(["--gcs", &format!("udpin:127.0.0.1:{}", free_port())]);
        c.args(["--vehicle", &format!("udpout:127.0.0.1:{}", free_port())]).args(extra);
        c
    };
    let out = args(&[]).stdin(Stdio::null()).output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("mochi-proxy") && err.contains("--in-process") && err.contains("cargo build"), "{err}");
    let p = Running::spawn(&mut args(&["--in-process"]));
    let start = p.wait_for(Duration::from_secs(60), |l| l["event"] == "start");
    assert!(start.is_some(), "--in-process starts without mochi-proxy: {:?}", p.lines.lock().unwrap());
    drop(p);
    let _ = std::fs::remove_dir_all(&dir);
}
