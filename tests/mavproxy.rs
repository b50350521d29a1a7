//! MAVProxy as the ground station through `mochi proxy`, headless: `mavproxy.py --daemon
//! --non-interactive`, no terminal, driven by `--cmd` alone (MAVProxy's own `wp load` and
//! `param set`; tests/proxy/mochi_when.py, a MAVProxy module loaded with `--load-module`,
//! holds a command until MAVProxy has heard the vehicle or knows a parameter, which a fixed
//! delay could not do on a loaded machine). The vehicle is the pymavlink vehicle of
//! tests/proxy/peers.py, with its 1 Hz HEARTBEAT (MAVProxy waits for one). Loopback only.
//!
//! MAVProxy 1.8.75 is pinned in .ci/run, installed without its declared dependencies
//! (matplotlib, numpy, opencv-python, vtk serve its windows and maps): headless it runs on
//! pymavlink and pyserial. When it is missing the test says so and passes when the `CI`
//! variable is unset, and fails when it is set (as tests/proxy.rs).

use super::proxy::{have, peer, proxy, violations, Running, MISSION, PEERS};
use std::process::Command;
use std::time::Duration;

/// MAVProxy connected to the proxy's ground-station end `gcs_port`, running `cmds` (each
/// through `--cmd`). It sends as 255/230 (MAVProxy's default source component).
fn mavproxy(gcs_port: u16, cmds: &[&str]) -> Running {
    let dir = std::path::Path::new(PEERS).parent().expect("tests/proxy");
    let mut cmd = Command::new("python3");
    cmd.args(["-u", "-m", "MAVProxy.mavproxy"])
        .args(["--master", &format!("udpout:127.0.0.1:{gcs_port}")])
        .args(["--daemon", "--non-interactive", "--no-state"])
        .args(["--target-system", "1", "--target-component", "1"])
        .args(["--load-module", "mochi_when"])
        .env("PYTHONPATH", dir);
    for c in cmds {
        cmd.args(["--cmd", c]);
    }
    Running::spawn(&mut cmd)
}

/// The items of a QGC WPL file: seq, frame, command, current, autocontinue, param1-4, x, y,
/// z (x and y in 1e-7 degrees, rounded).
fn wpl_items(path: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let c: Vec<f64> = l.split('\t').map(|x| x.trim().parse::<f64>().expect("a number")).collect();
            (c.len() >= 12).then(|| {
                vec![
                    c[0],
                    c[2],
                    c[3],
                    c[1],
                    c[11],
                    c[4],
                    c[5],
                    c[6],
                    c[7],
                    (c[8] * 1e7).round(),
                    (c[9] * 1e7).round(),
                    c[10],
                ]
            })
        })
        .collect()
}

/// A mission upload by MAVProxy (`wp load` of a real 117-item mission, sent as
/// MISSION_ITEM_INT) through the proxy enforcing `mission-upload-tolerant.chor` arrives
/// intact: every item as the file has it (reals as float32, MISSION_ITEM_INT's wire type;
/// latitude and longitude to the 1e-7 degree: MAVProxy truncates where the file is read
/// here rounding), and the session ends conformant with nothing dropped.
#[test]
fn mavproxy_wp_load_uploads_a_117_item_mission_through_the_proxy_intact() {
    if !have("MAVProxy") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60", "heartbeat"]);
    let gcs = mavproxy(g, &[&format!("when-target wp load {MISSION}")]);
    let ack = gcs.wait_for(Duration::from_secs(40), |l| l["mavproxy"] == "MISSION_ACK");
    assert_eq!(
        ack.as_ref().map(|a| a["type"].clone()),
        Some(0.into()),
        "MAV_MISSION_ACCEPTED: {:?}",
        gcs.lines.lock().unwrap()
    );
    let got = vehicle.wait_for(Duration::from_secs(5), |l| l["event"] == "mission").expect("the vehicle got it");
    assert_eq!(got["acked_early"], false);
    let want = wpl_items(MISSION);
    let got = got["items"].as_array().expect("items");
    assert_eq!(got.len(), 117);
    assert_eq!(want.len(), 117);
    for (w, g) in want.iter().zip(got) {
        let g: Vec<f64> = g.as_array().expect("an item").iter().map(|x| x.as_f64().expect("a number")).collect();
        for (k, (x, y)) in w.iter().zip(&g).enumerate() {
            match k {
                3 => {} // `current`: MAVProxy sets its own
                9 | 10 => assert!((x - y).abs() <= 1.0, "item {w:?} field {k} arrived as {g:?}"),
                _ => assert_eq!(*x as f32, *y as f32, "item {w:?} field {k} arrived as {g:?}"),
            }
        }
    }
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
    let end = p.wait_for(Duration::from_secs(5), |l| l["event"] == "end").expect("the session ended");
    assert_eq!(end["conformant"], true);
    assert_eq!(end["from"], "1/1", "the vehicle's MISSION_ACK ends it");
    let from_mavproxy = p.json().iter().any(|l| l["event"] == "step" && l["from"] == "255/230");
    assert!(from_mavproxy, "MAVProxy's steps are the session's");
}

/// MAVProxy's parameter handling through the proxy, where no enforced protocol claims the
/// parameter messages (`mission-upload-tolerant.chor` and `arm-command.chor`): MAVProxy
/// fetches the list at connection (PARAM_REQUEST_LIST, then the vehicle's PARAM_VALUE per
/// parameter), and `param set` (which MAVProxy refuses for a parameter it has not seen) sends
/// PARAM_SET, answered with the value now in force. Everything passes untouched.
#[test]
fn mavproxy_param_set_passes_a_proxy_whose_protocols_claim_no_parameter() {
    if !have("MAVProxy") {
        return;
    }
    let (p, g, v) = proxy(&["mission-upload-tolerant.chor", "arm-command.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60", "heartbeat"]);
    let gcs = mavproxy(g, &["when-param MC_PITCHRATE_MAX param set MC_PITCHRATE_MAX 200"]);
    let set = vehicle.wait_for(Duration::from_secs(40), |l| l["event"] == "param_set");
    assert_eq!(
        set.as_ref().map(|s| (s["id"].clone(), s["value"].clone())),
        Some(("MC_PITCHRATE_MAX".into(), 200.0.into())),
        "{:?}",
        gcs.lines.lock().unwrap()
    );
    let echo = gcs.wait_for(Duration::from_secs(5), |l| {
        l["mavproxy"] == "PARAM_VALUE" && l["id"] == "MC_PITCHRATE_MAX" && l["value"] == 200.0
    });
    assert!(echo.is_some(), "MAVProxy sees the new value: {:?}", gcs.lines.lock().unwrap());
    assert!(violations(&p).is_empty(), "{:?}", violations(&p));
}

/// MAVProxy through `mochi proxy` enforcing `param-set.chor`, whose labels are keyed by the
/// parameter's name (docs/captures.md, its rows): MAVProxy fetches the whole list at
/// connection (PARAM_REQUEST_LIST, then the vehicle's PARAM_VALUE per parameter), and the
/// list passes: MC_PITCH_P's and MC_PITCHRATE_FF's values are readings of the protocol's
/// streams, every other parameter's are outside its alphabet. Then `param set
/// MC_PITCHRATE_MAX 200` (within the bound 540 / (1 + 0.2 * 6.5) = 234.8 the vehicle's gains
/// allow) is the protocol's one step and passes, conformant; once MAVProxy has the new value,
/// `param set MC_PITCHRATE_MAX 300` breaks the bound and is dropped, every retry of it, so
/// the vehicle keeps 200. Before the keyed labels, the list's PARAM_VALUEs were dropped as
/// `outside any session` and MAVProxy never learnt a parameter (the set never left it).
#[test]
fn mavproxy_gets_the_parameter_list_through_param_set_and_its_sets_are_checked() {
    if !have("MAVProxy") {
        return;
    }
    let (p, g, v) = proxy(&["param-set.chor"], &[]);
    let vehicle = peer(&["vehicle", &format!("udpin:127.0.0.1:{v}"), "honest", "60", "heartbeat"]);
    let gcs = mavproxy(
        g,
        &[
            "when-param MC_PITCHRATE_MAX param set MC_PITCHRATE_MAX 200",
            "when-value MC_PITCHRATE_MAX 200 param set MC_PITCHRATE_MAX 300",
        ],
    );
    assert!(
        vehicle.wait_for(Duration::from_secs(40), |l| l["event"] == "param_list").is_some(),
        "MAVProxy's PARAM_REQUEST_LIST reaches the vehicle (outside the protocol's alphabet)"
    );
    let set = vehicle.wait_for(Duration::from_secs(40), |l| l["event"] == "param_set");
    assert_eq!(
        set.as_ref().map(|s| (s["id"].clone(), s["value"].clone())),
        Some(("MC_PITCHRATE_MAX".into(), 200.0.into())),
        "{:?}",
        gcs.lines.lock().unwrap()
    );
    let end = p.wait_for(Duration::from_secs(5), |l| l["event"] == "end").expect("the set's session ended");
    assert_eq!(end["conformant"], true, "{end}");
    let dropped = p.wait_for(Duration::from_secs(20), |l| {
        l["event"] == "violation" && l["msgid"] == 23 && l["kind"] == "refinement" && l["action"] == "drop"
    });
    assert!(dropped.is_some(), "the set of 300 is dropped: {:?}", p.json());
    // MAVProxy retries an unanswered set (three attempts, a second apart): none gets through.
    std::thread::sleep(Duration::from_secs(4));
    let sets: Vec<_> = vehicle.json().into_iter().filter(|l| l["event"] == "param_set").collect();
    assert_eq!(sets.len(), 1, "{sets:?}");
    let got: std::collections::BTreeSet<String> = gcs
        .json()
        .iter()
        .filter(|l| l["mavproxy"] == "PARAM_VALUE")
        .filter_map(|l| l["id"].as_str().map(str::to_string))
        .collect();
    assert_eq!(
        got.into_iter().collect::<Vec<_>>(),
        ["MC_PITCHRATE_FF", "MC_PITCHRATE_MAX", "MC_PITCH_P"],
        "MAVProxy has the whole list"
    );
    let passed_list = p.json().iter().all(|l| !(l["event"] == "violation" && l["msgid"] == 22));
    assert!(passed_list, "no PARAM_VALUE is refused: {:?}", p.json());
}
