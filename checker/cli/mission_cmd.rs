//! `mochi mission`: vet a mission file against a verified upload protocol before flying it
//! (docs/missions.md). The file is read (QGroundControl `.plan`, `QGC WPL 110` `.waypoints` /
//! Mission Planner `.txt`, ArduPilot's legacy fence and rally lists: `mavio::mission`), each
//! of its lists (mission, fence, rally) is turned into the upload a ground station and a
//! vehicle that do everything right would run (`upload_trace`), and that trace is run
//! through the monitor of each protocol: every message must be a step the protocol allows,
//! every item must satisfy the refinements of MISSION_ITEM_INT there, and the upload must
//! reach the protocol's end. A violation at an item is reported at the file's line of that
//! item.

use super::{eprintln_safe, print_safe, ColorChoice, Format, Outcome};
use clap::Args;
use mochi::mavio::mission::{parse_mission, upload_trace, Ends, MissionType};
use mochi::monitor::Monitor;
use mochi::render::{mission_json, MissionFile, MissionList, MissionViolation};
use mochi::source::SourceDb;
use std::path::PathBuf;

#[derive(Args)]
pub(crate) struct MissionArgs {
    /// Mission files: QGroundControl `.plan`, `.waypoints` / Mission Planner `.txt` (QGC WPL
    /// 110), ArduPilot legacy fence and rally lists (the format is told from the content)
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    /// A verified MAVLink upload protocol (`.chor` with a `dialect`); repeat for several: the
    /// upload must follow each
    #[arg(long = "protocol", short = 'p', required = true, value_name = "FILE")]
    protocols: Vec<PathBuf>,
    /// The ground station's system/component id in the trace
    #[arg(long, value_name = "SYS/COMP", default_value = "255/190", value_parser = parse_end)]
    gcs: (u8, u8),
    /// The vehicle's system/component id in the trace
    #[arg(long, value_name = "SYS/COMP", default_value = "1/1", value_parser = parse_end)]
    vehicle: (u8, u8),
    /// Output format
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

fn parse_end(s: &str) -> Result<(u8, u8), String> {
    let (a, b) = s.split_once('/').ok_or_else(|| format!("`{s}`: write SYSID/COMPID, e.g. 255/190"))?;
    let n = |x: &str| x.trim().parse::<u8>().map_err(|_| format!("`{x}` is not an id in 0..=255"));
    Ok((n(a)?, n(b)?))
}

/// Where in the upload a frame of the trace is: the count, the request or the item of the
/// k-th item, or the acknowledgement (the trace is COUNT, (REQUEST, ITEM) per item, ACK).
fn position(frame: u64, items: usize) -> (String, Option<usize>) {
    let f = frame as usize;
    if f == 0 {
        ("MISSION_COUNT".into(), None)
    } else if f > 2 * items {
        ("MISSION_ACK".into(), None)
    } else if f % 2 == 1 {
        (format!("MISSION_REQUEST_INT of item {}", (f - 1) / 2), Some((f - 1) / 2))
    } else {
        (format!("MISSION_ITEM_INT {}", (f - 2) / 2), Some((f - 2) / 2))
    }
}

fn type_name(t: MissionType) -> &'static str {
    match t {
        MissionType::Mission => "mission",
        MissionType::Fence => "fence",
        MissionType::Rally => "rally",
    }
}

/// Exit 0 when every list of every file uploads as each protocol allows, 1 when one does
/// not (or a file cannot be read, or a protocol is not verified).
pub(crate) fn mission(args: &MissionArgs, color: ColorChoice) -> Outcome {
    let mut db = SourceDb::new();
    let automata = match crate::verified_automata(&mut db, &args.protocols, color, "checks missions against") {
        Ok(a) => a,
        Err(o) => return o,
    };
    let ends = Ends { gcs: args.gcs, vehicle: args.vehicle };
    let mut text = String::new();
    let mut reports = Vec::new();
    let mut failed = false;
    for path in &args.files {
        let name = path.display().to_string();
        let parsed = mochi::fsload::read_bytes(path)
            .map_err(|e| format!("error: cannot read {name}: {e}"))
            .and_then(|b| String::from_utf8(b).map_err(|_| format!("error: {name}: not UTF-8 text")))
            .and_then(|t| parse_mission(&name, &t).map_err(|e| format!("error: {e}")));
        let file = match parsed {
            Ok(f) => f,
            Err(msg) => {
                failed = true;
                text += &format!("{msg}\n{name}: unreadable\n");
                reports.push(MissionFile {
                    file: name,
                    format: None,
                    verdict: "unreadable",
                    error: Some(msg),
                    lists: Vec::new(),
                });
                continue;
            }
        };
        let mut lists = Vec::new();
        let mut file_ok = true;
        for mission in &file.missions {
            let trace = upload_trace(mission, ends);
            for (a, file) in automata.iter().zip(&args.protocols) {
                let proto =
                    file.file_name().map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
                let mut m = Monitor::new(vec![a.clone()]);
                for f in trace.frames() {
                    m.on_frame(&f);
                }
                let conformant = m.finish().iter().filter(|s| s.conformant).count();
                let mut violations = Vec::new();
                for (i, v) in m.violations().iter().enumerate() {
                    let (what, item) = position(v.frame, mission.items.len());
                    let line = item.and_then(|k| mission.items.get(k)).map_or(0, |it| it.line);
                    let at = if line > 0 { format!("{name}:{line}: ") } else { format!("{name}: ") };
                    let detail = m.describe(&db, i);
                    text += &format!(
                        "{at}error: the {} upload breaks {} at {what}: {detail}\n",
                        type_name(mission.mission_type),
                        proto
                    );
                    violations.push(MissionViolation {
                        frame: v.frame,
                        message: what,
                        item,
                        line: (line > 0).then_some(line),
                        kind: v.kind.as_str(),
                        field: v.field.clone(),
                        detail,
                    });
                }
                // A trace that ends before the protocol does (no session reached `end`) is
                // not an upload the protocol accepts either.
                let verdict = if !violations.is_empty() {
                    "violation"
                } else if conformant == 0 {
                    "incomplete"
                } else {
                    "conformant"
                };
                if verdict != "conformant" {
                    file_ok = false;
                }
                if verdict == "incomplete" {
                    text += &format!(
                        "{name}: error: the {} upload of {} items does not reach the end of {}\n",
                        type_name(mission.mission_type),
                        mission.items.len(),
                        proto
                    );
                }
                lists.push(MissionList {
                    mission_type: type_name(mission.mission_type),
                    items: mission.items.len(),
                    protocol: proto,
                    verdict,
                    violations,
                });
            }
        }
        failed |= !file_ok;
        let summary: Vec<String> =
            file.missions.iter().map(|m| format!("{} {} items", type_name(m.mission_type), m.items.len())).collect();
        text += &format!("{name}: {} ({})\n", if file_ok { "accepted" } else { "rejected" }, summary.join(", "));
        reports.push(MissionFile {
            file: name,
            format: Some(format!("{:?}", file.format)),
            verdict: if file_ok { "accepted" } else { "rejected" },
            error: None,
            lists,
        });
    }
    match args.format {
        Format::Text => print_safe(&text),
        Format::Json => {
            let mut out = String::new();
            for r in &reports {
                out += &mission_json(r);
                out.push('\n');
            }
            print_safe(&out);
        }
    }
    if failed {
        eprintln_safe(&format!(
            "{} of {} mission files rejected or unreadable",
            reports.iter().filter(|r| r.verdict != "accepted").count(),
            reports.len()
        ));
        Outcome::Rejected
    } else {
        Outcome::Verified
    }
}
