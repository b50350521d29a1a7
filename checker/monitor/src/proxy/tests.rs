//! The proxy on loopback UDP, in process: forwarding both ways, byte for byte (signed frames
//! too), violations dropped or only reported, garbage and floods.

use super::*;
use crate::monitor::{Automaton, Kind};
use mavlink::dialects::common::{MavMessage, PARAM_SET_DATA};
use mavlink::{MavHeader, MavlinkVersion, SigningConfig, SigningData};
use std::net::UdpSocket;

/// A protocol small enough to read at a glance: the GCS sets a value of at most 10, the
/// vehicle echoes it.
const SET: &str = "dialect common;
system S { participant GCS; participant UAV; }
choreography Set =
  GCS -> UAV: PARAM_SET(param_value as v {v <= 10}).
  UAV -> GCS: PARAM_VALUE(param_value {param_value == v}).
  end;";

fn automaton(db: &mut SourceDb) -> Automaton {
    let file = db.add("set.chor", SET);
    let mut no_imports = |_: &std::path::Path| Err(std::io::Error::other("no imports"));
    let prog = match mochi_verify::driver::prepare(db, file, &mut no_imports, mochi_verify::driver::Stage::Names) {
        Ok(p) => p,
        Err(d) => panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()),
    };
    Automaton::compile(&prog).expect("compiles")
}

fn encode(from: (u8, u8), seq: u8, m: &MavMessage, signing: Option<&SigningData>) -> Vec<u8> {
    let h = MavHeader { system_id: u32::from(from.0), component_id: from.1, sequence: seq };
    let mut f = Vec::new();
    mavlink::write_versioned_msg_signed(&mut f, MavlinkVersion::V2, h, m, signing).expect("encodes");
    f
}

fn param_set(v: f32) -> MavMessage {
    MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: v,
        target_system: 1,
        target_component: 1,
        param_id: [0; 16].into(),
        param_type: mavlink::dialects::common::MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(mavlink::dialects::common::HEARTBEAT_DATA::default())
}

/// The events, kept for the test.
#[derive(Default)]
struct Events(Mutex<Vec<Event>>);

impl Sink for Events {
    fn events(&self, events: &[Event]) {
        self.0.lock().unwrap().extend_from_slice(events);
    }
}

impl Events {
    fn all(&self) -> Vec<Event> {
        self.0.lock().unwrap().clone()
    }
}

/// A proxy between a GCS socket and a vehicle socket, run in `body`.
fn with_proxy(monitored: bool, mode: Mode, body: impl FnOnce(&UdpSocket, &UdpSocket, &Events, &Totals)) {
    let mut db = SourceDb::new();
    let protocols = if monitored { vec![automaton(&mut db)] } else { Vec::new() };
    let vehicle = UdpSocket::bind("127.0.0.1:0").unwrap();
    vehicle.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let gcs_end = Endpoint::parse("udpin:127.0.0.1:0").unwrap().open().unwrap();
    let veh_end = Endpoint::parse(&format!("udpout:{}", vehicle.local_addr().unwrap())).unwrap().open().unwrap();
    let gcs = UdpSocket::bind("127.0.0.1:0").unwrap();
    gcs.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    gcs.connect(gcs_end.local_addr().unwrap()).unwrap();
    let lines = Events::default();
    let stop = AtomicBool::new(false);
    let totals = Totals::default();
    let proxy = Proxy { protocols, db: Some(&db), mode, config: Config::default(), steps: true };
    /// Stops the proxy even when the body panics (else the scope would wait forever).
    struct Stop<'a>(&'a AtomicBool);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    std::thread::scope(|s| {
        s.spawn(|| proxy.run(&*gcs_end, &*veh_end, &lines, &stop, &totals));
        let _stop = Stop(&stop);
        body(&gcs, &vehicle, &lines, &totals);
    });
}

fn recv(s: &UdpSocket) -> Vec<u8> {
    let mut b = [0u8; 2048];
    let (n, _) = s.recv_from(&mut b).expect("a datagram within 5 s");
    b[..n].to_vec()
}

#[test]
fn frames_are_forwarded_both_ways_byte_for_byte_signed_ones_too() {
    with_proxy(false, Mode::Enforce, |gcs, vehicle, _, _| {
        let signing = SigningData::from_config(SigningConfig::new([7; 32], 1, true, false));
        let f = encode((255, 190), 3, &param_set(42.0), Some(&signing));
        assert_eq!(f[2] & 1, 1, "the frame is signed");
        gcs.send(&f).unwrap();
        assert_eq!(recv(vehicle), f);
        // The vehicle answers the address the proxy sent from.
        let back = encode((1, 1), 9, &heartbeat(), None);
        let mut b = [0u8; 64];
        let (_, proxy_addr) = {
            gcs.send(&encode((255, 190), 4, &heartbeat(), None)).unwrap();
            vehicle.recv_from(&mut b).unwrap()
        };
        vehicle.send_to(&back, proxy_addr).unwrap();
        assert_eq!(recv(gcs), back);
    });
}

#[test]
fn a_violating_message_is_dropped_and_reported() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, lines, totals| {
        // 11 > 10: dropped; the vehicle sees the conforming set that follows, and nothing else.
        gcs.send(&encode((255, 190), 0, &param_set(11.0), None)).unwrap();
        let ok = encode((255, 190), 1, &param_set(5.0), None);
        gcs.send(&ok).unwrap();
        assert_eq!(recv(vehicle), ok);
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(totals.dropped.load(Ordering::Relaxed), 1);
        let all = lines.all();
        let Some(Event::Violation { at, kind, detail, forwarded, .. }) =
            all.iter().find(|e| matches!(e, Event::Violation { .. }))
        else {
            panic!("no violation: {all:?}")
        };
        assert!(!forwarded);
        assert_eq!(*kind, Kind::Refinement);
        assert_eq!(at.dir, Dir::GcsToVehicle);
        assert!(detail.as_deref().unwrap_or("").contains("set.chor:4:"), "{detail:?}");
        assert!(all.iter().any(|e| matches!(e, Event::Step { .. })), "{all:?}");
    });
}

#[test]
fn alert_only_forwards_the_violation_and_reports_it() {
    with_proxy(true, Mode::AlertOnly, |gcs, vehicle, lines, _| {
        let bad = encode((255, 190), 0, &param_set(11.0), None);
        gcs.send(&bad).unwrap();
        assert_eq!(recv(vehicle), bad);
        std::thread::sleep(Duration::from_millis(50));
        let all = lines.all();
        assert!(all.iter().any(|e| matches!(e, Event::Violation { forwarded: true, .. })), "{all:?}");
    });
}

#[test]
fn garbage_and_floods_neither_stop_it_nor_grow_its_record() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, lines, totals| {
        let mut noise = vec![0u8; 1400];
        let mut x = 0x1234_5678u32;
        let bad = encode((255, 190), 0, &param_set(11.0), None);
        let mut crc = bad.clone();
        let n = crc.len();
        crc[n - 3] ^= 0xff;
        // Garbage, frames with bad checksums, truncated frames, and violations, two thousand
        // times.
        for k in 0..2304 {
            for b in noise.iter_mut() {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                *b = x as u8;
            }
            gcs.send(&noise).unwrap();
            gcs.send(&crc).unwrap();
            gcs.send(&bad[..bad.len() / 2]).unwrap();
            gcs.send(&bad).unwrap();
            if k % 32 == 0 {
                // Let the proxy keep up (loopback drops datagrams a slow reader has no room for).
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        // Still forwarding: a conforming message gets through.
        let ok = encode((255, 190), 1, &param_set(5.0), None);
        let mut got = None;
        for _ in 0..50 {
            gcs.send(&ok).unwrap();
            let f = recv(vehicle);
            if f == ok {
                got = Some(f);
                break;
            }
        }
        assert_eq!(got.as_deref(), Some(&ok[..]), "the proxy forwards after the flood");
        assert!(totals.violations.load(Ordering::Relaxed) > 1024);
        // The record of violations is not kept (no session open: no session lost).
        assert!(totals.resets.load(Ordering::Relaxed) == 0, "no lossy reset without open sessions");
        assert!(lines.all().iter().any(|e| matches!(e, Event::Violation { .. })));
    });
}

#[test]
fn a_flood_of_session_openings_is_bounded() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, lines, totals| {
        // Each PARAM_SET opens a session that waits for the vehicle's echo.
        for k in 0..(SESSION_CAP as usize + 64) {
            gcs.send(&encode((255, 190), k as u8, &param_set(1.0), None)).unwrap();
            let _ = recv(vehicle);
        }
        std::thread::sleep(Duration::from_millis(50));
        assert!(totals.resets.load(Ordering::Relaxed) >= 1);
        let all = lines.all();
        assert!(
            all.iter().any(|e| matches!(e, Event::Reset { reason: "too many open sessions", .. })),
            "{:?}",
            all.iter().filter(|e| matches!(e, Event::Reset { .. })).collect::<Vec<_>>()
        );
    });
}

fn param_value(v: f32) -> MavMessage {
    MavMessage::PARAM_VALUE(mavlink::dialects::common::PARAM_VALUE_DATA {
        param_value: v,
        param_count: 1,
        param_index: 0,
        param_id: [0; 16].into(),
        param_type: mavlink::dialects::common::MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

#[test]
fn a_flood_of_violations_inside_an_open_session_loses_nothing() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, lines, totals| {
        // A session opens: the set of 5 waits for the vehicle's echo.
        gcs.send(&encode((255, 190), 0, &param_set(5.0), None)).unwrap();
        let mut b = [0u8; 512];
        let (_, proxy) = vehicle.recv_from(&mut b).expect("the set is forwarded");
        // Nine thousand wrong echoes: each is dropped, reported, and forgotten; the session
        // stays open in its state.
        let wrong = encode((1, 1), 0, &param_value(6.0), None);
        let flood = 9000;
        for k in 0..flood {
            vehicle.send_to(&wrong, proxy).unwrap();
            if k % 32 == 0 {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        let right = encode((1, 1), 1, &param_value(5.0), None);
        let mut got = None;
        for _ in 0..50 {
            vehicle.send_to(&right, proxy).unwrap();
            let f = recv(gcs);
            if f == right {
                got = Some(f);
                break;
            }
        }
        assert_eq!(got.as_deref(), Some(&right[..]), "the echo that fits the session is forwarded");
        std::thread::sleep(Duration::from_millis(50));
        assert!(totals.violations.load(Ordering::Relaxed) > 8000, "{totals:?}");
        assert_eq!(totals.resets.load(Ordering::Relaxed), 0, "the open session was lost in a reset");
        assert!(lines.all().iter().any(|e| matches!(e, Event::End { conformant: true, .. })), "the session ended");
    });
}

/// A MAVLink 2 frame of message id 42424 (no dialect has it): its checksum is arbitrary,
/// since nobody here knows its CRC_EXTRA.
fn unknown_frame(payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xFD, payload.len() as u8, 0, 0, 7, 255, 190, 0xB8, 0xA5, 0x00];
    f.extend_from_slice(payload);
    f.extend_from_slice(&[0x12, 0x34]);
    f
}

#[test]
fn unknown_message_ids_are_forwarded_whole_unless_they_hide_a_frame() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, _, totals| {
        // An unknown message, then telemetry outside the protocol: both pass, byte for byte.
        let unknown = unknown_frame(&[1, 2, 3, 4, 5, 6, 7, 8]);
        let hb = encode((255, 190), 1, &heartbeat(), None);
        gcs.send(&[unknown.clone(), hb.clone()].concat()).unwrap();
        assert_eq!(recv(vehicle), [unknown, hb.clone()].concat());
        // An "unknown message" whose payload is a violating PARAM_SET: not forwarded whole;
        // the PARAM_SET inside is found, judged and dropped; the heartbeat after it passes.
        let bad = encode((255, 190), 2, &param_set(11.0), None);
        let wrapper = unknown_frame(&bad);
        gcs.send(&[wrapper, hb.clone()].concat()).unwrap();
        assert_eq!(recv(vehicle), hb);
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(totals.dropped.load(Ordering::Relaxed), 1);
    });
}

#[test]
fn a_ground_station_claiming_to_be_an_autopilot_is_still_judged_as_the_ground_station() {
    with_proxy(true, Mode::Enforce, |gcs, vehicle, lines, totals| {
        // A HEARTBEAT from the ground-station side that claims an ArduPilot quadrotor: the
        // monitor would read the end as a vehicle, which cannot play `GCS`, and the set would
        // pass as outside the protocol. The proxy knows the side: it is the ground station.
        use mavlink::dialects::common::{MavAutopilot, MavType, HEARTBEAT_DATA};
        let claim = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            ..HEARTBEAT_DATA::default()
        });
        let hb = encode((255, 190), 0, &claim, None);
        gcs.send(&hb).unwrap();
        assert_eq!(recv(vehicle), hb);
        gcs.send(&encode((255, 190), 1, &param_set(11.0), None)).unwrap();
        let ok = encode((255, 190), 2, &param_set(5.0), None);
        gcs.send(&ok).unwrap();
        assert_eq!(recv(vehicle), ok, "the violating set was forwarded");
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(totals.dropped.load(Ordering::Relaxed), 1, "{:?}", lines.all());
    });
}
