//! The MAVLink readers (`checker/monitor/src/mavio/`) against the real captures, pymavlink, random
//! frames and random bytes; the mission files of `../shared/data/missions/`; and the census of
//! what the captures contain (docs/captures.md).
//!
//! The differential test needs pymavlink (`.ci/run` installs the pinned version): without it
//! the test says so and passes when the `CI` variable is unset, and fails when it is set.

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MavHeader, MavlinkVersion, Message, SigningConfig, SigningData};
use mochi::mavio::census::{census, render_table};
use mochi::mavio::log::{detect, read_log, read_log_as, Format};
use mochi::mavio::mission::{parse_mission, upload_trace, Ends, MissionType};
use mochi::mavio::parse::{Config, RawReader, Stream, MAX_FRAME};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn shared(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(dir)
}

/// The capture files (sorted), without SOURCES.md.
fn captures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(shared("mavlink_captures"))
        .expect("../shared/data/mavlink_captures")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    v.sort();
    assert!(v.len() >= 7, "captures missing: {v:?}");
    v
}

/// One frame as both readers print it: time, sysid, compid, msgid.
type Row = (Option<u64>, u8, u8, u32);

fn ours(bytes: &[u8]) -> (Format, Vec<Row>, mochi::mavio::parse::Counts) {
    let mut rows = Vec::new();
    let s = read_log(bytes, Config::default(), |f| rows.push((f.time_us, f.sysid, f.compid, f.msgid)));
    (s.format, rows, s.counts)
}

/// pymavlink's reading: the frames, the ids of the frames its dialect does not have, and the
/// count of BAD_DATA; or why it cannot be had.
fn pymavlink(format: Format, path: &Path) -> Result<(Vec<Row>, Vec<u32>, u64), String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mavio/pymavlink_frames.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(format.name())
        .arg(path)
        .output()
        .map_err(|e| format!("python3 not runnable: {e}"))?;
    if !out.status.success() {
        return Err(format!("pymavlink script failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut rows = Vec::new();
    let mut unknown = Vec::new();
    let mut bad = 0;
    let num = |s: &str| s.parse::<u64>().map_err(|e| format!("`{s}` from the script: {e}"));
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["bad", n] => bad = num(n)?,
            ["unknown", id] => unknown.push(num(id)? as u32),
            ["garbage", _] => {}
            [t, s, c, m] => rows.push((t.parse().ok(), num(s)? as u8, num(c)? as u8, num(m)? as u32)),
            _ => return Err(format!("unexpected line from the script: {line}")),
        }
    }
    Ok((rows, unknown, bad))
}

fn pymavlink_available() -> Result<(), String> {
    let out = Command::new("python3").args(["-c", "import pymavlink"]).output().map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).trim().to_string())
    }
}

/// Every capture, frame by frame, against pymavlink. Where the two differ the test asserts
/// the difference that docs/mavio.md explains, so a new difference fails.
#[test]
fn captures_match_pymavlink_frame_by_frame() {
    if let Err(why) = pymavlink_available() {
        if std::env::var_os("CI").is_some() {
            panic!("pymavlink is missing in CI (.ci/run installs it): {why}");
        }
        eprintln!(
            "SKIPPED captures_match_pymavlink_frame_by_frame: pymavlink not installed ({why}); .ci/run installs it"
        );
        return;
    }
    let mut report = Vec::new();
    for path in captures() {
        let bytes = std::fs::read(&path).unwrap();
        let (format, mine, counts) = ours(&bytes);
        let (theirs, unknown, bad) = pymavlink(format, &path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        report.push(format!(
            "{name}: {format:?}, ours {} frames {counts:?}; pymavlink {} frames, {} of ids its dialect lacks {:?}, {bad} bad",
            mine.len(),
            theirs.len(),
            unknown.len(),
            unknown.iter().collect::<std::collections::BTreeSet<_>>()
        ));
        // Frames of ids pymavlink 2.4.50's dialect lacks: the mavlink crate's newer dialect may
        // have them (then they are ours to yield), else they are our unknown ids too.
        let (mine, newer): (Vec<Row>, Vec<Row>) = mine.into_iter().partition(|r| !unknown.contains(&r.3));
        assert_eq!(
            newer.len() as u64 + counts.unknown_id,
            unknown.len() as u64,
            "{name}: unknown ids\n{}",
            report.join("\n")
        );
        assert_eq!(counts.bad_crc, bad, "{name}: bad frames\n{}", report.join("\n"));
        if mine == theirs {
            continue;
        }
        let first = mine.iter().zip(&theirs).position(|(a, b)| a != b).unwrap_or(mine.len().min(theirs.len()));
        panic!(
            "{name}: readers differ at frame {first}: ours {:?}, pymavlink {:?} (ours {} frames, pymavlink {})\n{}",
            mine.get(first),
            theirs.get(first),
            mine.len(),
            theirs.len(),
            report.join("\n")
        );
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn formats_are_detected_from_content() {
    for path in captures() {
        let bytes = std::fs::read(&path).unwrap();
        let want = match path.extension().unwrap().to_str().unwrap() {
            "tlog" => Format::Tlog,
            "bin" => Format::Raw,
            "pcapng" => Format::Pcapng,
            e => panic!("unexpected capture extension {e}"),
        };
        assert_eq!(detect(&bytes), want, "{}", path.display());
    }
}

#[test]
fn the_captures_read_cleanly() {
    for path in captures() {
        let bytes = std::fs::read(&path).unwrap();
        let (_, rows, c) = ours(&bytes);
        assert!(!rows.is_empty(), "{}", path.display());
        // Chunked reading of the raw streams gives the same frames as reading them whole.
        if detect(&bytes) == Format::Raw {
            for chunk in [1usize, 7, 64, 1500] {
                let mut st = Stream::new(Config::default());
                let mut got = Vec::new();
                for piece in bytes.chunks(chunk) {
                    st.push(piece, None);
                    while let Some(f) = st.next_frame() {
                        got.push((f.time_us, f.sysid, f.compid, f.msgid));
                    }
                    assert!(st.buffered() <= chunk + MAX_FRAME);
                }
                let end = st.finish(|f| got.push((f.time_us, f.sysid, f.compid, f.msgid)));
                assert_eq!(got, rows, "{} in chunks of {chunk}", path.display());
                assert_eq!(end, c, "{} in chunks of {chunk}", path.display());
            }
        }
    }
}

/// A message of id `id` from the dialect with fields drawn from `seed` bytes (the default
/// message where the bytes make an invalid enum value).
fn message(id: u32, seed: &[u8]) -> Option<MavMessage> {
    MavMessage::parse(MavlinkVersion::V2, id, seed).ok().or_else(|| MavMessage::default_message_from_id(id))
}

/// The ids the dialect knows, to draw from.
fn known_ids() -> Vec<u32> {
    (0..65536).filter(|&id| MavMessage::default_message_from_id(id).is_some()).collect()
}

#[derive(Clone, Debug)]
struct Spec {
    id_index: usize,
    seed: Vec<u8>,
    v2: bool,
    signed: bool,
    sysid: u8,
    compid: u8,
    garbage: Vec<u8>,
}

fn spec() -> impl Strategy<Value = Spec> {
    (
        any::<usize>(),
        proptest::collection::vec(any::<u8>(), 0..255),
        any::<bool>(),
        any::<bool>(),
        any::<u8>(),
        any::<u8>(),
        // Garbage without start bytes, or a cut frame prefix (built below).
        proptest::collection::vec(any::<u8>().prop_filter("no start byte", |b| *b != 0xfe && *b != 0xfd), 0..40),
    )
        .prop_map(|(id_index, seed, v2, signed, sysid, compid, garbage)| Spec {
            id_index,
            seed,
            v2,
            signed,
            sysid,
            compid,
            garbage,
        })
}

const KEY: [u8; 32] = [7; 32];

/// Encodes the frames with the mavlink crate; returns the stream and the frames' bytes.
fn encode(specs: &[Spec], ids: &[u32], cut_prefixes: bool) -> (Vec<u8>, Vec<Vec<u8>>) {
    let signing = SigningData::from_config(SigningConfig::new(KEY, 3, true, false));
    let mut stream = Vec::new();
    let mut frames = Vec::new();
    for (k, s) in specs.iter().enumerate() {
        let id = ids[s.id_index % ids.len()];
        let version = if s.v2 || id > 255 { MavlinkVersion::V2 } else { MavlinkVersion::V1 };
        let Some(m) = message(id, &s.seed) else { continue };
        let h = MavHeader { system_id: u32::from(s.sysid), component_id: s.compid, sequence: k as u8 };
        let mut f = Vec::new();
        let sign = (s.signed && version == MavlinkVersion::V2).then_some(&signing);
        mavlink::write_versioned_msg_signed(&mut f, version, h, &m, sign).unwrap();
        stream.extend(&s.garbage);
        if cut_prefixes && s.seed.first().is_some_and(|b| b % 3 == 0) && f.len() > 3 {
            // A cut frame (a dropout) before the real one.
            stream.extend(&f[..f.len() / 2]);
        }
        stream.extend(&f);
        frames.push(f);
    }
    (stream, frames)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Random frames from the mavlink crate (v1/v2, signed or not, MAVLink 2's truncated
    /// payloads, garbage and cut frames between them) read back exactly, whole or in
    /// arbitrary chunks.
    #[test]
    fn encoded_frames_read_back(specs in proptest::collection::vec(spec(), 1..12), cuts in proptest::collection::vec(1usize..64, 1..20), cut_prefixes in any::<bool>()) {
        let ids = known_ids();
        let (stream, frames) = encode(&specs, &ids, cut_prefixes);
        let cfg = Config { key: Some(KEY), ..Config::default() };
        let whole: Vec<Vec<u8>> = RawReader::new(&stream, cfg).map(|f| f.raw.to_vec()).collect();
        prop_assert_eq!(&whole, &frames);
        // Each frame's fields are the header's.
        for f in RawReader::new(&stream, cfg) {
            let m = MavMessage::parse(if f.version == 1 { MavlinkVersion::V1 } else { MavlinkVersion::V2 }, f.msgid, f.payload);
            prop_assert!(m.is_ok(), "payload of {} does not parse", f.msgid);
        }
        let mut st = Stream::new(cfg);
        let mut got = Vec::new();
        let mut at = 0;
        let mut i = 0;
        while at < stream.len() {
            let n = cuts[i % cuts.len()].min(stream.len() - at);
            st.push(&stream[at..at + n], None);
            at += n;
            i += 1;
            while let Some(f) = st.next_frame() {
                got.push(f.raw.to_vec());
            }
        }
        st.finish(|f| got.push(f.raw.to_vec()));
        prop_assert_eq!(&got, &frames);
    }

    /// A wrong key rejects every signed frame and keeps every unsigned one.
    #[test]
    fn a_wrong_key_rejects_signed_frames(specs in proptest::collection::vec(spec(), 1..8)) {
        let ids = known_ids();
        let (stream, frames) = encode(&specs, &ids, false);
        let cfg = Config { key: Some([8; 32]), ..Config::default() };
        let mut r = RawReader::new(&stream, cfg);
        let got: Vec<Vec<u8>> = r.by_ref().map(|f| f.raw.to_vec()).collect();
        let unsigned: Vec<Vec<u8>> = frames.iter().filter(|f| !(f[0] == 0xfd && f[2] & 1 == 1)).cloned().collect();
        prop_assert_eq!(got, unsigned);
        prop_assert_eq!(r.counts().bad_signature as usize, frames.len() - r.counts().frames as usize);
    }

    /// Arbitrary bytes: no panic, every byte accounted for, in every format.
    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..4096)) {
        for format in [Format::Tlog, Format::Raw, Format::Pcapng, Format::Pcap] {
            let mut n = 0u64;
            let s = read_log_as(format, &bytes, Config::default(), |_| n += 1);
            prop_assert_eq!(s.counts.frames, n);
        }
        let mut framed = 0usize;
        let mut r = RawReader::new(&bytes, Config::default());
        for f in r.by_ref() {
            framed += f.raw.len();
        }
        prop_assert_eq!(framed as u64 + r.counts().garbage_bytes, bytes.len() as u64);
    }

    /// Arbitrary bytes after the header of a capture: the capture readers are exercised past
    /// the magic.
    #[test]
    fn arbitrary_captures_never_panic(body in proptest::collection::vec(any::<u8>(), 0..2048), ng in any::<bool>()) {
        let mut bytes = if ng {
            let mut h = vec![0x0a, 0x0d, 0x0d, 0x0a, 28, 0, 0, 0, 0x4d, 0x3c, 0x2b, 0x1a, 1, 0, 0, 0];
            h.extend([0xff; 8]);
            h.extend([28, 0, 0, 0]);
            h.extend([1, 0, 0, 0, 20, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 20, 0, 0, 0]);
            h
        } else {
            let mut h = vec![0xd4, 0xc3, 0xb2, 0xa1, 2, 0, 4, 0];
            h.extend([0; 12]);
            h.extend([1, 0, 0, 0]);
            h
        };
        bytes.extend(&body);
        let _ = read_log(&bytes, Config::default(), |_| {});
    }
}

/// The worst input for the framer: start bytes whose headers name a known message and a
/// full-length payload, so every byte begins a candidate whose checksum is computed. The
/// time per byte must not grow with the input (linear time): 4 MiB within 8 times the time of
/// 512 KiB, plus slack for timer noise.
#[test]
fn adversarial_input_takes_linear_time() {
    let pattern = [0xfd, 0xff, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00];
    let make = |n: usize| pattern.iter().copied().cycle().take(n).collect::<Vec<u8>>();
    let time = |b: &[u8]| {
        let t = Instant::now();
        let mut r = RawReader::new(b, Config::default());
        assert_eq!(r.by_ref().count(), 0);
        assert_eq!(r.counts().garbage_bytes, b.len() as u64);
        t.elapsed().as_secs_f64()
    };
    let small = make(512 << 10);
    let big = make(4 << 20);
    let ts = time(&small);
    let tb = time(&big);
    assert!(tb < ts * 8.0 * 3.0 + 0.05, "4 MiB took {tb:.3} s, 512 KiB {ts:.3} s: not linear");
    assert!(tb < 20.0, "4 MiB of adversarial input took {tb:.1} s");
}

/// Every mission file in ../shared/data/missions: read, or refused with a located error; the
/// upload trace of each list reads back as COUNT, REQUEST_INT/ITEM_INT per item, ACK.
#[test]
fn every_mission_file_is_read() {
    let mut files = Vec::new();
    let mut stack = vec![shared("missions")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().unwrap() != "SOURCES.md" {
                files.push(p);
            }
        }
    }
    files.sort();
    assert_eq!(files.len(), 28, "{files:?}");
    let mut refused = Vec::new();
    for p in &files {
        let name = p.strip_prefix(shared("missions")).unwrap().display().to_string();
        let text = std::fs::read_to_string(p).unwrap();
        let mf = match parse_mission(&name, &text) {
            Ok(m) => m,
            Err(e) => {
                refused.push(e.to_string());
                continue;
            }
        };
        for m in &mf.missions {
            let t = upload_trace(m, Ends::default());
            let ids: Vec<(u8, u8, u32)> = t.frames().map(|f| (f.sysid, f.compid, f.msgid)).collect();
            let n = m.items.len();
            assert_eq!(ids.len(), 2 * n + 2, "{name}");
            assert_eq!(ids[0], (255, 190, 44));
            assert_eq!(ids[ids.len() - 1], (1, 1, 47));
            for k in 0..n {
                assert_eq!(ids[1 + 2 * k], (1, 1, 51));
                assert_eq!(ids[2 + 2 * k], (255, 190, 73));
            }
            for (k, f) in t.frames().filter(|f| f.msgid == 73).enumerate() {
                let MavMessage::MISSION_ITEM_INT(d) = MavMessage::parse(MavlinkVersion::V2, 73, f.payload).unwrap()
                else {
                    panic!()
                };
                let it = &m.items[k];
                assert_eq!(
                    (d.seq, d.x, d.y, d.command as u16, d.frame as u8),
                    (k as u16, it.x, it.y, it.command, it.frame)
                );
                assert_eq!(d.mission_type as u8, m.mission_type as u8);
                assert!(d.z.to_bits() == it.z.to_bits() || (d.z.is_nan() && it.z.is_nan()));
            }
        }
        if name.contains("Kingaroy") {
            assert_eq!(mf.missions[0].items.len(), 529);
        }
        if name.ends_with("fence.txt") && !name.contains("110") {
            assert_eq!(mf.missions[0].mission_type, MissionType::Fence);
        }
    }
    // The one file whose upload cannot be known from it: a StructureScan stores no items.
    assert_eq!(refused.len(), 1, "{refused:#?}");
    assert!(
        refused[0].contains("qgroundcontrol_sample_with_structured_scan.plan:") && refused[0].contains("StructureScan"),
        "{}",
        refused[0]
    );
}

#[test]
fn malformed_mission_files_are_located_errors() {
    let cases: &[(&str, &str, (u32, u32))] = &[
        ("{\"fileType\": \"Plan\",\n  \"mission\": {\"items\": [}\n}", "not valid JSON", (2, 25)),
        ("QGC WPL 110\n0 1 0 16 0 0 0 0 1 2 3 1\n2 0 0 16 0 0 0 0 1 2 3 1\n", "out of order", (3, 1)),
        ("QGC WPL 110\n0 1 0 16 0 0 0 0 91x 2 3 1\n", "x `91x`", (2, 18)),
        ("QGC WPL 110\n0 1 0 16 0 0 0 0 300 2 3 1\n", "fits", (2, 18)),
        ("QGC WPL 120\n", "version 110", (1, 1)),
        ("RALLY 1 2\n", "RALLY lat lon", (1, 1)),
        ("1 2\n3 4\n", "points", (1, 1)),
        ("garbage", "not a mission file", (1, 1)),
        ("{\"fileType\": \"Plan\", \"mission\": {\"items\": [{\"type\": \"SimpleItem\", \"command\": 16, \"frame\": 3, \"params\": [0]}]}}", "7 numbers", (1, 53)),
    ];
    for (text, what, (l, c)) in cases {
        let e = parse_mission("f", text).unwrap_err();
        assert!(e.message.contains(what), "{text:?}: {e}");
        assert_eq!((e.line, e.column), (*l, *c), "{text:?}: {e}");
    }
}

/// docs/captures.md holds the census of every capture; `MAVIO_BLESS=1` rewrites it.
#[test]
fn the_census_in_the_docs_is_current() {
    let mut out = String::new();
    for path in captures() {
        let bytes = std::fs::read(&path).unwrap();
        let c = census(&bytes, Config::default());
        out.push_str(&render_table(&path.file_name().unwrap().to_string_lossy(), &c));
        out.push('\n');
    }
    let doc = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/captures.md");
    let text = std::fs::read_to_string(&doc).unwrap_or_default();
    const BEGIN: &str = "<!-- census: begin (generated by tests/mavio.rs, MAVIO_BLESS=1 to update) -->\n";
    const END: &str = "<!-- census: end -->";
    if std::env::var_os("MAVIO_BLESS").is_some() {
        let (head, tail) = match (text.find(BEGIN), text.find(END)) {
            (Some(b), Some(e)) => (text[..b].to_string(), text[e + END.len()..].to_string()),
            _ => (text.clone(), String::from("\n")),
        };
        std::fs::write(&doc, format!("{head}{BEGIN}{out}{END}{tail}")).unwrap();
        return;
    }
    let b = text.find(BEGIN).expect("docs/captures.md has no census markers: run with MAVIO_BLESS=1");
    let e = text.find(END).unwrap();
    assert_eq!(
        &text[b + BEGIN.len()..e],
        out,
        "docs/captures.md is stale: run `MAVIO_BLESS=1 cargo test --test suite -- mavio::the_census`"
    );
}
