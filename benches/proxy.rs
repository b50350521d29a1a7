//! The live proxy's cost (issue 21, Deliver 10): the latency it adds on loopback, median
//! and p99, with and without the monitor (target under 10 µs median; DATUM added 27 µs on
//! ArduPilot and 37 µs on PX4), and the resident memory of `mochi proxy` under a flood
//! (target under 8 MB; DATUM added 13.7 MB).
//!
//! ```text
//! cargo bench --bench proxy             # 20 uploads of 500 items per configuration
//! cargo bench --bench proxy -- --quick  # 3
//! ```
//!
//! Latency: a ground-station socket and a vehicle socket play a 500-item mission upload
//! (`mission-upload-tolerant.chor`: MISSION_COUNT, then MISSION_REQUEST_INT / MISSION_ITEM_INT
//! 500 times, MISSION_ACK, MISSION_CURRENT), one message in flight at a time; every message's
//! one-way time (send to receive, one clock) is recorded. Three configurations, each the
//! same exchange: directly (no proxy), through the proxy forwarding only (framing and CRC
//! check, no protocol), and through the proxy enforcing `mission-upload-tolerant.chor`,
//! `arm-command.chor` and `param-set.chor` together (in process, UDP `udpin:`/`udpout:` ends,
//! events discarded). The added latency is the proxied figure minus the
//! direct one. On a shared machine the figures move with the load; the medians are stable
//! enough to compare.
//!
//! Memory: the `mochi proxy` binary with the three protocols, VmRSS and VmHWM from
//! /proc/PID/status after it started and after a flood of 200,000 datagrams (telemetry,
//! garbage, frames with bad checksums, violations, session openings).

use mavlink::dialects::common::*;
use mavlink::{MavHeader, MavlinkVersion};
use mochi::monitor::Automaton;
use mochi::proxy::{Endpoint, Event, Mode, Proxy, Sink, Totals};
use mochi::source::SourceDb;
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const ITEMS: u16 = 500;
const PROTOCOLS: [&str; 3] = [
    "choreographies/mavlink/mission-upload-tolerant.chor",
    "choreographies/mavlink/arm-command.chor",
    "choreographies/mavlink/param-set.chor",
];

fn compile(db: &mut SourceDb, path: &str) -> Automaton {
    let root = mochi::fsload::load_root(db, Path::new(path)).expect("read the protocol");
    let mut load = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(db, root, &mut load, mochi::driver::Stage::Names).expect("lowered");
    Automaton::compile(&prog).expect("compiles")
}

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

/// One-way times through an in-process proxy (with these protocols).
fn through_proxy(
    protocols: Vec<Automaton>,
    db: &SourceDb,
    msgs: &[(bool, Vec<u8>)],
    uploads: usize,
) -> (Vec<u64>, u64) {
    let (gcs, vehicle) = sockets();
    let gcs_end = Endpoint::parse("udpin:127.0.0.1:0").unwrap().open().unwrap();
    let veh_end = Endpoint::parse(&format!("udpout:{}", vehicle.local_addr().unwrap())).unwrap().open().unwrap();
    let proxy_gcs = gcs_end.local_addr().unwrap();
    let stop = AtomicBool::new(false);
    let totals = Totals::default();
    let proxy = Proxy { protocols, db: Some(db), mode: Mode::Enforce, config: Default::default(), steps: true };
    let proxy_vehicle = Mutex::new(None);
    let times = std::thread::scope(|s| {
        s.spawn(|| proxy.run(&*gcs_end, &*veh_end, &Discard, &stop, &totals));
        // The vehicle learns the proxy's address from the first message it gets (telemetry:
        // `arm-command.chor` claims HEARTBEAT, and one outside a session would be dropped).
        let mut buf = [0u8; 512];
        let hb = frame((255, 190), 0, &MavMessage::ATTITUDE(ATTITUDE_DATA::default()));
        gcs.send_to(&hb, proxy_gcs).unwrap();
        let (_, from) = vehicle.recv_from(&mut buf).expect("the proxy forwards");
        *proxy_vehicle.lock().unwrap() = Some(from);
        let times = play(&gcs, &vehicle, proxy_gcs, || from, msgs, uploads);
        stop.store(true, Ordering::Relaxed);
        times
    });
    (times, totals.violations.load(Ordering::Relaxed))
}

/// Events counted and dropped (the benchmark measures forwarding, not a terminal).
struct Discard;

impl Sink for Discard {
    fn events(&self, events: &[Event]) {
        std::hint::black_box(events.len());
    }
}

fn vm(pid: u32, key: &str) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let l = s.lines().find(|l| l.starts_with(key))?;
    l.split_whitespace().nth(1)?.parse().ok()
}

fn memory() {
    let gport = UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let sink = UdpSocket::bind("127.0.0.1:0").unwrap();
    sink.set_nonblocking(true).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mochi"));
    cmd.arg("proxy");
    for p in PROTOCOLS {
        cmd.args(["--protocol", p]);
    }
    cmd.args([
        "--gcs",
        &format!("udpin:127.0.0.1:{gport}"),
        "--vehicle",
        &format!("udpout:{}", sink.local_addr().unwrap()),
    ]);
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::null()).spawn().expect("mochi proxy");
    // Read (and discard) its verdict lines, as a log collector would.
    let out = child.stdout.take().unwrap();
    std::thread::spawn(move || {
        let _ = std::io::copy(&mut std::io::BufReader::new(out), &mut std::io::sink());
    });
    let pid = child.id();
    // Started once it forwards.
    let g = UdpSocket::bind("127.0.0.1:0").unwrap();
    let hb = frame((255, 190), 0, &MavMessage::ATTITUDE(ATTITUDE_DATA::default()));
    let mut buf = [0u8; 2048];
    let started = Instant::now();
    loop {
        let _ = g.send_to(&hb, ("127.0.0.1", gport));
        std::thread::sleep(Duration::from_millis(20));
        if sink.recv(&mut buf).is_ok() || started.elapsed() > Duration::from_secs(120) {
            break;
        }
    }
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
    let rss1 = vm(pid, "VmRSS:").unwrap_or(0);
    let hwm = vm(pid, "VmHWM:").unwrap_or(0);
    let (anon, file) = (vm(pid, "RssAnon:").unwrap_or(0), vm(pid, "RssFile:").unwrap_or(0));
    let pss = rollup(pid, "Pss:").unwrap_or(0);
    let maps = mappings(pid);
    let _ = child.kill();
    let _ = child.wait();
    let mb = |k: u64| k as f64 / 1024.0;
    println!(
        "proxy memory: mochi proxy (3 protocols) VmRSS {:.1} MB after start, {:.1} MB after 200,000 datagrams of flood; peak VmHWM {:.1} MB (target < 8 MB)",
        mb(rss0),
        mb(rss1),
        mb(hwm)
    );
    println!(
        "  after the flood: RssAnon {:.1} MB (heap, stacks), RssFile {:.1} MB (the executable and the shared libraries' pages), Pss {:.1} MB (shared pages divided among the processes that map them)",
        mb(anon),
        mb(file),
        mb(pss)
    );
    let top: Vec<String> = maps.iter().take(6).map(|(k, name)| format!("{} {:.1} MB", name, mb(*k))).collect();
    println!("  resident by mapping: {}", top.join(", "));
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

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let uploads = if quick { 3 } else { 20 };
    let msgs = upload();
    let mut db = SourceDb::new();
    let protocols: Vec<Automaton> = PROTOCOLS.iter().map(|p| compile(&mut db, p)).collect();

    let (gcs, vehicle) = sockets();
    let (ga, va) = (gcs.local_addr().unwrap(), vehicle.local_addr().unwrap());
    let _ = play(&gcs, &vehicle, va, || ga, &msgs, 1);
    let direct = play(&gcs, &vehicle, va, || ga, &msgs, uploads);
    let (forward, _) = through_proxy(Vec::new(), &db, &msgs, uploads);
    let (monitored, violations) = through_proxy(protocols, &db, &msgs, uploads);
    assert_eq!(violations, 0, "the conforming upload raised violations");

    let n = direct.len();
    let (d50, d99) = quantiles(direct);
    let (f50, f99) = quantiles(forward);
    let (m50, m99) = quantiles(monitored);
    println!(
        "proxy latency, one way on loopback UDP, {n} messages per configuration ({uploads} uploads of {ITEMS} items):"
    );
    println!("  {:<44} {:>10} {:>10}", "", "median µs", "p99 µs");
    println!("  {:<44} {:>10.2} {:>10.2}", "direct (no proxy)", d50, d99);
    println!("  {:<44} {:>10.2} {:>10.2}", "through the proxy, forwarding only", f50, f99);
    println!("  {:<44} {:>10.2} {:>10.2}", "through the proxy, enforcing 3 protocols", m50, m99);
    println!(
        "  added by the proxy: {:.2} µs median ({:.2} µs p99) forwarding only, {:.2} µs median ({:.2} µs p99) enforcing (target < 10 µs median)",
        f50 - d50,
        f99 - d99,
        m50 - d50,
        m99 - d99
    );
    memory();
}
