//! The live proxy's cost (issue 21, Deliver 10): the latency it adds on loopback, median
//! and p99, with and without the monitor (target under 10 µs median; DATUM added 27 µs on
//! ArduPilot and 37 µs on PX4), and the resident memory of the enforcing process under a
//! flood (target under 8 MB; DATUM added 13.7 MB). Side by side, in one run: `mochi proxy`
//! as users run it (it verifies, then replaces itself with the small `mochi-proxy`, which
//! enforces: docs/proxy.md, "Two processes") and `mochi proxy --in-process` (the `mochi`
//! executable enforcing itself, with Z3 linked: what `mochi proxy` was before).
//!
//! ```text
//! cargo bench --bench proxy             # 20 uploads of 500 items per configuration
//! cargo bench --bench proxy -- --quick  # 3
//! ```
//!
//! Latency: a ground-station socket and a vehicle socket play a 500-item mission upload
//! (`mission-upload-tolerant.chor`: MISSION_COUNT, then MISSION_REQUEST_INT / MISSION_ITEM_INT
//! 500 times, MISSION_ACK, MISSION_CURRENT), one message in flight at a time; every message's
//! one-way time (send to receive, one clock) is recorded. Five configurations, each the same
//! exchange: directly (no proxy), and through each of the two processes forwarding only
//! (framing and CRC check, no protocol) and enforcing `mission-upload-tolerant.chor`,
//! `arm-command.chor` and `param-set.chor` together (UDP `udpin:`/`udpout:` ends on
//! 127.0.0.1, the event lines read from a pipe and discarded). The added latency is the
//! proxied figure minus the direct one. On a shared machine the figures move with the load;
//! the medians are stable enough to compare.
//!
//! Memory: each process enforcing one protocol (`mission-upload-tolerant.chor`) and all 15
//! of `choreographies/mavlink/`, VmRSS and VmHWM from /proc/PID/status after it started and
//! after a flood of 200,000 datagrams (telemetry, garbage, frames with bad checksums,
//! violations, session openings), with the split by mapping from /proc/PID/smaps.

use mavlink::dialects::common::*;
use mavlink::{MavHeader, MavlinkVersion};
use std::net::{SocketAddr, UdpSocket};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const ITEMS: u16 = 500;
const PROTOCOLS: [&str; 3] = [
    "choreographies/mavlink/mission-upload-tolerant.chor",
    "choreographies/mavlink/arm-command.chor",
    "choreographies/mavlink/param-set.chor",
];

fn frame(from: (u8, u8), seq: u8, m: &MavMessage) -> Vec<u8> {
    let h = MavHeader { system_id: u32::from(from.0), component_id: from.1, sequence: seq };
    let mut f = Vec::new();
    mavlink::write_versioned_msg(&mut f, MavlinkVersion::V2, h, m).expect("encodes");
    f
}

/// The upload, as (from the ground station?, frame) in order.
fn upload() -> Vec<(bool, Vec<u8>)> {
    let (gcs, uav) = ((255, 190), (1, 1));
    let mut out = Vec::new();
    let mut seq = 0u8;
    let mut put = |g: bool, m: MavMessage| {
        seq = seq.wrapping_add(1);
        out.push((g, frame(if g { gcs } else { uav }, seq, &m)));
    };
    put(
        true,
        MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: ITEMS,
            target_system: 1,
            target_component: 1,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            opaque_id: 0,
        }),
    );
    for i in 0..ITEMS {
        put(
            false,
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq: i,
                target_system: 255,
                target_component: 190,
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            }),
        );
        put(
            true,
            MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
                param1: 0.0,
                param2: 0.0,
                param3: 0.0,
                param4: 0.0,
                x: -353632620 + i32::from(i),
                y: 1491652370,
                z: 100.0,
                seq: i,
                command: MavCmd::MAV_CMD_NAV_WAYPOINT,
                target_system: 1,
                target_component: 1,
                frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
                current: 0,
                autocontinue: 1,
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            }),
        );
    }
    put(
        false,
        MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: 255,
            target_component: 190,
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            opaque_id: 0,
        }),
    );
    put(false, MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA::default()));
    out
}

/// Plays `uploads` uploads between `gcs` (sending to `to_vehicle`) and `vehicle` (sending to
/// `to_gcs`); one-way times in nanoseconds.
fn play(
    gcs: &UdpSocket,
    vehicle: &UdpSocket,
    to_vehicle: std::net::SocketAddr,
    to_gcs: impl Fn() -> std::net::SocketAddr,
    msgs: &[(bool, Vec<u8>)],
    uploads: usize,
) -> Vec<u64> {
    let mut times = Vec::with_capacity(msgs.len() * uploads);
    let mut buf = [0u8; 512];
    for _ in 0..uploads {
        for (from_gcs, f) in msgs {
            let t = Instant::now();
            if *from_gcs {
                gcs.send_to(f, to_vehicle).expect("send");
                let n = vehicle.recv(&mut buf).expect("the vehicle receives within 2 s");
                assert_eq!(&buf[..n], &f[..], "forwarded byte for byte");
            } else {
                vehicle.send_to(f, to_gcs()).expect("send");
                let n = gcs.recv(&mut buf).expect("the ground station receives within 2 s");
                assert_eq!(&buf[..n], &f[..], "forwarded byte for byte");
            }
            times.push(t.elapsed().as_nanos() as u64);
        }
    }
    times
}

fn quantiles(mut v: Vec<u64>) -> (f64, f64) {
    v.sort_unstable();
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize] as f64 / 1000.0;
    (q(0.5), q(0.99))
}

fn sockets() -> (UdpSocket, UdpSocket) {
    let g = UdpSocket::bind("127.0.0.1:0").unwrap();
    let v = UdpSocket::bind("127.0.0.1:0").unwrap();
    g.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    v.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    (g, v)
}

/// The two ways to run the proxy: `mochi proxy` (which replaces itself with `mochi-proxy`)
/// and `mochi proxy --in-process`.
#[derive(Clone, Copy)]
enum Process {
    Small,
    InProcess,
}

impl Process {
    fn name(self) -> &'static str {
        match self {
            Process::Small => "mochi proxy (mochi-proxy enforces)",
            Process::InProcess => "mochi proxy --in-process",
        }
    }
}

/// A proxy process between a ground station sending to `gcs_port` and a vehicle at
/// `vehicle`, enforcing `protocols`; its event lines are read and discarded, as a log
/// collector would.
fn spawn(how: Process, protocols: &[String], gcs_port: u16, vehicle: SocketAddr) -> Child {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mochi"));
    cmd.arg("proxy");
    if let Process::InProcess = how {
        cmd.arg("--in-process");
    }
    for p in protocols {
        cmd.args(["--protocol", p]);
    }
    cmd.args(["--gcs", &format!("udpin:127.0.0.1:{gcs_port}"), "--vehicle", &format!("udpout:{vehicle}")]);
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::inherit()).spawn().expect("mochi proxy");
    let out = child.stdout.take().unwrap();
    std::thread::spawn(move || {
        let _ = std::io::copy(&mut std::io::BufReader::new(out), &mut std::io::sink());
    });
    child
}

/// Sends telemetry from `gcs` to the proxy until `vehicle` receives it (the proxy verifies
/// first, which takes seconds): the proxy's address on the vehicle's side.
fn wait_started(gcs: &UdpSocket, gcs_port: u16, vehicle: &UdpSocket) -> SocketAddr {
    let hb = frame((255, 190), 0, &MavMessage::ATTITUDE(ATTITUDE_DATA::default()));
    let mut buf = [0u8; 2048];
    let started = Instant::now();
    vehicle.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    loop {
        let _ = gcs.send_to(&hb, ("127.0.0.1", gcs_port));
        if let Ok((_, from)) = vehicle.recv_from(&mut buf) {
            // Whatever else was sent while it started.
            while vehicle.recv_from(&mut buf).is_ok() {}
            vehicle.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
            return from;
        }
        assert!(started.elapsed() < Duration::from_secs(600), "the proxy did not start in 10 minutes");
    }
}

/// One-way times through a proxy process (with these protocols).
fn through(how: Process, protocols: &[String], msgs: &[(bool, Vec<u8>)], uploads: usize) -> Vec<u64> {
    let (gcs, vehicle) = sockets();
    let gcs_port = free_port();
    let mut child = spawn(how, protocols, gcs_port, vehicle.local_addr().unwrap());
    let from = wait_started(&gcs, gcs_port, &vehicle);
    let to_vehicle: SocketAddr = format!("127.0.0.1:{gcs_port}").parse().unwrap();
    let _ = play(&gcs, &vehicle, to_vehicle, || from, msgs, 1);
    let times = play(&gcs, &vehicle, to_vehicle, || from, msgs, uploads);
    let _ = child.kill();
    let _ = child.wait();
    times
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn vm(pid: u32, key: &str) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let l = s.lines().find(|l| l.starts_with(key))?;
    l.split_whitespace().nth(1)?.parse().ok()
}

fn memory(how: Process, protocols: &[String]) {
    let gport = free_port();
    let sink = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut child = spawn(how, protocols, gport, sink.local_addr().unwrap());
    let pid = child.id();
    let g = UdpSocket::bind("127.0.0.1:0").unwrap();
    wait_started(&g, gport, &sink);
    sink.set_nonblocking(true).unwrap();
    let mut buf = [0u8; 2048];
    let rss0 = vm(pid, "VmRSS:").unwrap_or(0);
    let mut x = 0x9e37_79b9u32;
    let telemetry = frame((1, 1), 0, &MavMessage::ATTITUDE(ATTITUDE_DATA::default()));
    let count = |k: u16| {
        frame(
            (255, (k % 200) as u8),
            0,
            &MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                count: 3,
                target_system: 1,
                target_component: 1,
                mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
                opaque_id: 0,
            }),
        )
    };
    let bad = frame(
        (1, 1),
        0,
        &MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: 255,
            target_component: 190,
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            opaque_id: 0,
        }),
    );
    let mut noise = [0u8; 1024];
    for k in 0..200_000u32 {
        let d: Vec<u8> = match k % 5 {
            0 => telemetry.clone(),
            1 => {
                for b in noise.iter_mut() {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    *b = x as u8;
                }
                noise.to_vec()
            }
            2 => {
                let mut c = telemetry.clone();
                let n = c.len();
                c[n - 1] ^= 0x55;
                c
            }
            3 => bad.clone(),
            _ => count(k as u16),
        };
        let _ = g.send_to(&d, ("127.0.0.1", gport));
        if k % 64 == 0 {
            while sink.recv(&mut buf).is_ok() {}
            std::thread::sleep(Duration::from_micros(200));
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    let exe = std::fs::read_link(format!("/proc/{pid}/exe")).ok();
    let exe = exe.as_ref().and_then(|e| e.file_name()).map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let rss1 = vm(pid, "VmRSS:").unwrap_or(0);
    let hwm = vm(pid, "VmHWM:").unwrap_or(0);
    let (anon, file) = (vm(pid, "RssAnon:").unwrap_or(0), vm(pid, "RssFile:").unwrap_or(0));
    let pss = rollup(pid, "Pss:").unwrap_or(0);
    let maps = mappings(pid);
    let _ = child.kill();
    let _ = child.wait();
    let mb = |k: u64| k as f64 / 1024.0;
    println!(
        "  {} [{exe}], {} protocol(s): VmRSS {:.1} MB after start, {:.1} MB after the flood; peak VmHWM {:.1} MB (target < 8 MB)",
        how.name(),
        protocols.len(),
        mb(rss0),
        mb(rss1),
        mb(hwm)
    );
    println!(
        "    after the flood: RssAnon {:.1} MB (heap, stacks), RssFile {:.1} MB (executable and shared libraries), Pss {:.1} MB",
        mb(anon),
        mb(file),
        mb(pss)
    );
    let top: Vec<String> = maps.iter().take(7).map(|(k, name)| format!("{} {:.1} MB", name, mb(*k))).collect();
    println!("    resident by mapping: {}", top.join(", "));
}

/// A field of /proc/PID/smaps_rollup, in kB.
fn rollup(pid: u32, key: &str) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/smaps_rollup")).ok()?;
    let l = s.lines().find(|l| l.starts_with(key))?;
    l.split_whitespace().nth(1)?.parse().ok()
}

/// Resident kB per mapped file (anonymous mappings as `[anon]`), largest first.
fn mappings(pid: u32) -> Vec<(u64, String)> {
    let Ok(s) = std::fs::read_to_string(format!("/proc/{pid}/smaps")) else { return Vec::new() };
    let mut by: std::collections::BTreeMap<String, u64> = Default::default();
    let mut name = String::new();
    for l in s.lines() {
        let mut w = l.split_whitespace();
        let first = w.next().unwrap_or("");
        if first.contains('-') && first.chars().all(|c| c.is_ascii_hexdigit() || c == '-') {
            let path = l.split_whitespace().nth(5).unwrap_or("[anon]");
            name = path.rsplit('/').next().unwrap_or(path).to_string();
        } else if first == "Rss:" {
            *by.entry(name.clone()).or_default() += w.next().and_then(|k| k.parse::<u64>().ok()).unwrap_or(0);
        }
    }
    let mut v: Vec<(u64, String)> = by.into_iter().map(|(n, k)| (k, n)).collect();
    v.sort_by(|a, b| b.cmp(a));
    v
}

/// Every protocol of `choreographies/mavlink/`, sorted.
fn all_protocols() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir("choreographies/mavlink")
        .expect("choreographies/mavlink")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "chor"))
        .map(|p| p.display().to_string())
        .collect();
    v.sort();
    v
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let uploads = if quick { 3 } else { 20 };
    let msgs = upload();
    let three: Vec<String> = PROTOCOLS.iter().map(|p| p.to_string()).collect();

    let (gcs, vehicle) = sockets();
    let (ga, va) = (gcs.local_addr().unwrap(), vehicle.local_addr().unwrap());
    let _ = play(&gcs, &vehicle, va, || ga, &msgs, 1);
    let direct = play(&gcs, &vehicle, va, || ga, &msgs, uploads);
    let n = direct.len();
    let (d50, d99) = quantiles(direct);
    println!(
        "proxy latency, one way on loopback UDP, {n} messages per configuration ({uploads} uploads of {ITEMS} items):"
    );
    println!("  {:<66} {:>10} {:>10} {:>22}", "", "median µs", "p99 µs", "added median (p99) µs");
    println!("  {:<66} {:>10.2} {:>10.2}", "direct (no proxy)", d50, d99);
    for how in [Process::Small, Process::InProcess] {
        for (what, protocols) in [("forwarding only", &Vec::new()), ("enforcing 3 protocols", &three)] {
            let (m50, m99) = quantiles(through(how, protocols, &msgs, uploads));
            let label = format!("{}, {what}", how.name());
            println!("  {label:<66} {m50:>10.2} {m99:>10.2} {:>12.2} ({:.2})", m50 - d50, m99 - d99);
        }
    }
    println!("proxy memory, the enforcing process, under a flood of 200,000 datagrams:");
    let all = all_protocols();
    let one = vec![PROTOCOLS[0].to_string()];
    for how in [Process::Small, Process::InProcess] {
        memory(how, &one);
        memory(how, &all);
    }
}
