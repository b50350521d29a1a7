//! Mission files and the upload they imply.
//!
//! Formats read (recognised from the content, not the extension):
//!
//! - **QGroundControl `.plan`** (JSON, `"fileType": "Plan"`): `mission.items` (`SimpleItem`s,
//!   and the `Items` a `survey`/`CorridorScan` `ComplexItem` stores under
//!   `TransectStyleComplexItem`), `geoFence` (polygons and circles) and `rallyPoints`. A
//!   `null` parameter is NaN (QGroundControl writes NaN as `null`). For an ArduPilot plan
//!   (`firmwareType` 3) item 0 is the planned home position, as QGroundControl uploads it
//!   (ArduPilot keeps home in seq 0); for other firmware the items start at 0.
//!   A complex item that stores no items (`StructureScan`: QGroundControl computes its
//!   waypoints from the structure at upload time) is an error: its upload cannot be known from
//!   the file.
//! - **QGC WPL 110** (`.waypoints`, Mission Planner `.txt`): a `QGC WPL <version>` line, then
//!   one item per line, `seq current frame command p1 p2 p3 p4 x y z autocontinue`, separated
//!   by tabs or spaces; `#` lines and blank lines are skipped. The mission type follows from
//!   the commands: fence commands (5000-5004) make a fence, rally points (5100) a rally list.
//! - **Legacy ArduPilot lists**: a fence as `lat lon` lines (the first the return point, the
//!   rest a polygon whose last point repeats its first, as ArduPilot's FENCE_POINT protocol
//!   had it), read as one return point (5000) and one inclusion polygon (5001); rally points
//!   as `RALLY lat lon alt break_alt land_dir flags` lines, read as 5100 items (alt relative).
//!
//! **Coordinates.** MISSION_ITEM_INT carries x/y as int32: degrees * 1e7 in a global frame,
//! metres * 1e4 in a local one, and the parameter itself in MAV_FRAME_MISSION. The value is
//! rounded to the nearest integer, halves away from zero, from the decimal *as written in the
//! file* (exactly, digit by digit, not through a binary float): the file's decimal is what the
//! user planned, the nearest int32 is the closest the wire can carry, and `(x * 1e7) as i32`
//! (truncation, as some tools do) moves every negative coordinate whose product lands just
//! above an integer by one unit (1.1 cm) — e.g. -35.36372 becomes -353637199. A NaN x or y
//! (`null` in a .plan, a reserved parameter) is sent as 0; a value outside int32 is an error.
//!
//! **Errors** carry `file:line:column` (the line of the item in a WPL file; in a `.plan`, where
//! the offending value is), say what is wrong, and never panic.

use mavlink::dialects::ardupilotmega::{MavCmd, MavFrame};
use num_traits::FromPrimitive;
use std::fmt;

pub use super::upload::{upload_trace, Ends, UploadTrace};

/// A mission file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionFormat {
    /// QGroundControl `.plan`.
    Plan,
    /// `QGC WPL 110` text (`.waypoints`, Mission Planner `.txt`).
    Wpl,
    /// ArduPilot's legacy fence list (`lat lon` lines).
    LegacyFence,
    /// ArduPilot's legacy rally list (`RALLY ...` lines).
    LegacyRally,
}

/// The list a mission item belongs to (MAV_MISSION_TYPE).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionType {
    /// MAV_MISSION_TYPE_MISSION (0).
    Mission = 0,
    /// MAV_MISSION_TYPE_FENCE (1).
    Fence = 1,
    /// MAV_MISSION_TYPE_RALLY (2).
    Rally = 2,
}

/// One item as MISSION_ITEM_INT carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Item {
    /// Position in its list.
    pub seq: u16,
    /// The `current` flag as the file has it.
    pub current: bool,
    /// MAV_FRAME.
    pub frame: u8,
    /// MAV_CMD.
    pub command: u16,
    /// param1..param4.
    pub params: [f32; 4],
    /// param5 as int32 (see the module comment for the scaling).
    pub x: i32,
    /// param6 as int32.
    pub y: i32,
    /// param7.
    pub z: f32,
    /// Continue to the next item when this one completes.
    pub autocontinue: bool,
    /// The line of the file the item comes from (1-based; 0 for items a .plan implies).
    pub line: u32,
}

/// One list to upload.
#[derive(Clone, Debug, PartialEq)]
pub struct Mission {
    /// Which list.
    pub mission_type: MissionType,
    /// The items, seq 0 first.
    pub items: Vec<Item>,
}

/// What a mission file holds: one to three lists.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionFile {
    /// The format read.
    pub format: MissionFormat,
    /// The lists: the mission first (a `.plan` always has one, possibly empty), then fence
    /// and rally lists when the file has any.
    pub missions: Vec<Mission>,
}

/// A malformed mission file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MissionError {
    /// The file as named by the caller.
    pub file: String,
    /// 1-based line.
    pub line: u32,
    /// 1-based column.
    pub column: u32,
    /// What is wrong, and how to fix it where that is known.
    pub message: String,
}

impl fmt::Display for MissionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.column, self.message)
    }
}

impl std::error::Error for MissionError {}

/// Reads a mission file; `file` names it in errors.
pub fn parse_mission(file: &str, text: &str) -> Result<MissionFile, MissionError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let err = |line: u32, column: u32, message: String| MissionError { file: file.to_string(), line, column, message };
    let first = text.lines().map(str::trim).find(|l| !l.is_empty()).unwrap_or("");
    if first.starts_with('{') {
        plan::parse(text).map_err(|(l, c, m)| err(l, c, m))
    } else if first.starts_with("QGC WPL") {
        parse_wpl(text).map_err(|(l, c, m)| err(l, c, m))
    } else if first.starts_with("RALLY") {
        parse_legacy_rally(text).map_err(|(l, c, m)| err(l, c, m))
    } else if first.split_whitespace().count() == 2 {
        parse_legacy_fence(text).map_err(|(l, c, m)| err(l, c, m))
    } else {
        Err(err(
            1,
            1,
            "not a mission file: expected a QGroundControl .plan (JSON), a `QGC WPL 110` header, \
             `RALLY` lines or `lat lon` fence lines"
                .to_string(),
        ))
    }
}

/// A position-carrying error: line, column, message.
type At = (u32, u32, String);

/// Whether MAV_FRAME `frame` is global (x/y are degrees, sent * 1e7).
fn is_global(frame: u8) -> bool {
    matches!(frame, 0 | 3 | 5 | 6 | 10 | 11)
}

/// Whether MAV_FRAME `frame` is local (x/y are metres, sent * 1e4).
fn is_local(frame: u8) -> bool {
    matches!(frame, 1 | 4 | 7 | 8 | 9 | 12 | 13 | 14 | 15 | 16 | 17 | 18 | 19 | 20 | 21)
}

/// The decimal power x/y are scaled by in `frame`.
fn scale_digits(frame: u8) -> u32 {
    if is_global(frame) {
        7
    } else if is_local(frame) {
        4
    } else {
        0
    }
}

/// `text` (a decimal number, optionally signed, optionally with an exponent) times 10^`digits`,
/// rounded to the nearest integer with halves away from zero, computed exactly. `None` when
/// `text` is not a number or the result is not an int32. "nan" gives 0 (see the module comment).
pub fn scaled_int(text: &str, digits: u32) -> Option<i32> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("nan") {
        return Some(0);
    }
    let (neg, t) = match t.as_bytes().first()? {
        b'-' => (true, &t[1..]),
        b'+' => (false, &t[1..]),
        _ => (false, t),
    };
    let (mant, exp) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], t[i + 1..].parse::<i32>().ok()?),
        None => (t, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    if (int.is_empty() && frac.is_empty()) || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
        return None;
    }
    // digits of the mantissa, and where the decimal point falls after scaling.
    let all: Vec<u8> = int.bytes().chain(frac.bytes()).map(|b| b - b'0').collect();
    let point = int.len() as i64 + i64::from(exp) + i64::from(digits);
    let mut value: i128 = 0;
    for i in 0..point.max(0) {
        let d = all.get(i as usize).copied().unwrap_or(0);
        value = value.checked_mul(10)?.checked_add(i128::from(d))?;
        if value > i128::from(u32::MAX) {
            return None;
        }
    }
    let next = if point < 0 { 0 } else { all.get(point as usize).copied().unwrap_or(0) };
    if point >= 0 && next >= 5 {
        value += 1;
    }
    let value = if neg { -value } else { value };
    i32::try_from(value).ok()
}

/// A parameter as f32: the nearest float to the decimal (NaN for "nan").
fn param(text: &str) -> Option<f32> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("nan") {
        return Some(f32::NAN);
    }
    t.parse::<f32>().ok()
}

/// Splits a line into its fields with their 1-based columns.
fn fields(line: &str) -> Vec<(u32, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices() {
        if c.is_whitespace() {
            if let Some(s) = start.take() {
                out.push((s as u32 + 1, &line[s..i]));
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        out.push((s as u32 + 1, &line[s..]));
    }
    out
}

/// The mission type a command puts its item in.
fn type_of(command: u16) -> MissionType {
    match command {
        5000..=5004 => MissionType::Fence,
        5100 => MissionType::Rally,
        _ => MissionType::Mission,
    }
}

fn parse_wpl(text: &str) -> Result<MissionFile, At> {
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.by_ref().find(|(_, l)| !l.trim().is_empty()) else {
        return Err((1, 1, "empty file".into()));
    };
    let version = header.trim().strip_prefix("QGC WPL").map(str::trim).unwrap_or("");
    if version != "110" {
        return Err((
            1,
            1,
            format!("`QGC WPL {version}`: only version 110 is read (the one QGroundControl and Mission Planner write)"),
        ));
    }
    let mut items: Vec<Item> = Vec::new();
    let mut kind: Option<(MissionType, u32)> = None;
    for (n, line) in lines {
        let ln = n as u32 + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f = fields(line);
        if f.len() != 12 {
            let col = f.get(12).map_or(line.len() as u32 + 1, |x| x.0);
            return Err((
                ln,
                col,
                format!("{} fields, expected 12: seq current frame command p1 p2 p3 p4 x y z autocontinue", f.len()),
            ));
        }
        let int = |i: usize, what: &str, max: u32| -> Result<u32, At> {
            f[i].1
                .parse::<u32>()
                .ok()
                .filter(|v| *v <= max)
                .ok_or_else(|| (ln, f[i].0, format!("{what} `{}` is not an integer from 0 to {max}", f[i].1)))
        };
        let seq = int(0, "seq", u32::from(u16::MAX))?;
        if seq as usize != items.len() {
            return Err((ln, f[0].0, format!("seq {seq} out of order: expected {}", items.len())));
        }
        let current = int(1, "current", 1)? == 1;
        let frame = int(2, "frame", 255)? as u8;
        let command = int(3, "command", u32::from(u16::MAX))? as u16;
        let mut params = [0f32; 4];
        for (k, p) in params.iter_mut().enumerate() {
            *p = param(f[4 + k].1)
                .ok_or_else(|| (ln, f[4 + k].0, format!("param{} `{}` is not a number", k + 1, f[4 + k].1)))?;
        }
        let digits = scale_digits(frame);
        let x = scaled_int(f[8].1, digits).ok_or_else(|| (ln, f[8].0, coord_msg("x", f[8].1, digits)))?;
        let y = scaled_int(f[9].1, digits).ok_or_else(|| (ln, f[9].0, coord_msg("y", f[9].1, digits)))?;
        let z = param(f[10].1).ok_or_else(|| (ln, f[10].0, format!("z `{}` is not a number", f[10].1)))?;
        let autocontinue = int(11, "autocontinue", 1)? == 1;
        check_enums(frame, command).map_err(|(which, m)| (ln, f[if which == 0 { 2 } else { 3 }].0, m))?;
        let t = type_of(command);
        match kind {
            None => kind = Some((t, ln)),
            Some((k, first)) if k != t && !(k == MissionType::Mission && items.len() == 1) => {
                return Err((
                    ln,
                    f[3].0,
                    format!("command {command} belongs to the {t:?} list but line {first} began a {k:?} list: one file holds one list"),
                ));
            }
            Some((k, _)) if k != t => kind = Some((t, ln)),
            _ => {}
        }
        items.push(Item { seq: seq as u16, current, frame, command, params, x, y, z, autocontinue, line: ln });
    }
    let mission_type = kind.map_or(MissionType::Mission, |k| k.0);
    Ok(MissionFile { format: MissionFormat::Wpl, missions: vec![Mission { mission_type, items }] })
}

fn coord_msg(which: &str, text: &str, digits: u32) -> String {
    format!("{which} `{text}` is not a number whose value * 1e{digits} fits MISSION_ITEM_INT's int32")
}

/// Checks that the frame and command are values the dialect has (0: the frame is wrong, 1:
/// the command).
fn check_enums(frame: u8, command: u16) -> Result<(), (u8, String)> {
    if MavFrame::from_u8(frame).is_none() {
        return Err((0, format!("frame {frame} is not a MAV_FRAME of the ardupilotmega dialect")));
    }
    if MavCmd::from_u16(command).is_none() {
        return Err((1, format!("command {command} is not a MAV_CMD of the ardupilotmega dialect")));
    }
    Ok(())
}

fn parse_legacy_fence(text: &str) -> Result<MissionFile, At> {
    let mut pts: Vec<(u32, i32, i32)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let ln = n as u32 + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f = fields(line);
        if f.len() != 2 {
            return Err((ln, f.get(2).map_or(1, |x| x.0), format!("{} fields, expected `lat lon`", f.len())));
        }
        let lat = scaled_int(f[0].1, 7).ok_or_else(|| (ln, f[0].0, coord_msg("latitude", f[0].1, 7)))?;
        let lon = scaled_int(f[1].1, 7).ok_or_else(|| (ln, f[1].0, coord_msg("longitude", f[1].1, 7)))?;
        pts.push((ln, lat, lon));
    }
    if pts.len() < 4 {
        return Err((
            1,
            1,
            format!(
                "{} points: a legacy fence is a return point and a closed polygon of at least 3 vertices",
                pts.len()
            ),
        ));
    }
    let mut poly = &pts[1..];
    if poly.len() > 3 && poly.first().map(|p| (p.1, p.2)) == poly.last().map(|p| (p.1, p.2)) {
        poly = &poly[..poly.len() - 1];
    }
    let mut items = vec![fence_item(0, 5000, 0.0, pts[0])];
    for p in poly {
        items.push(fence_item(items.len() as u16, 5001, poly.len() as f32, *p));
    }
    Ok(MissionFile {
        format: MissionFormat::LegacyFence,
        missions: vec![Mission { mission_type: MissionType::Fence, items }],
    })
}

fn fence_item(seq: u16, command: u16, p1: f32, (line, x, y): (u32, i32, i32)) -> Item {
    Item {
        seq,
        current: false,
        frame: 0,
        command,
        params: [p1, 0.0, 0.0, 0.0],
        x,
        y,
        z: 0.0,
        autocontinue: false,
        line,
    }
}

fn parse_legacy_rally(text: &str) -> Result<MissionFile, At> {
    let mut items = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let ln = n as u32 + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f = fields(line);
        if f[0].1 != "RALLY" || f.len() != 7 {
            return Err((ln, 1, "expected `RALLY lat lon alt break_alt land_dir flags`".into()));
        }
        let lat = scaled_int(f[1].1, 7).ok_or_else(|| (ln, f[1].0, coord_msg("latitude", f[1].1, 7)))?;
        let lon = scaled_int(f[2].1, 7).ok_or_else(|| (ln, f[2].0, coord_msg("longitude", f[2].1, 7)))?;
        let mut v = [0f32; 4];
        for (k, slot) in v.iter_mut().enumerate() {
            *slot = param(f[3 + k].1).ok_or_else(|| (ln, f[3 + k].0, format!("`{}` is not a number", f[3 + k].1)))?;
        }
        items.push(Item {
            seq: items.len() as u16,
            current: false,
            frame: 3,
            command: 5100,
            params: [0.0; 4],
            x: lat,
            y: lon,
            z: v[0],
            autocontinue: false,
            line: ln,
        });
    }
    Ok(MissionFile {
        format: MissionFormat::LegacyRally,
        missions: vec![Mission { mission_type: MissionType::Rally, items }],
    })
}

mod plan {
    //! The QGroundControl `.plan` reader (JSON).
    use super::*;
    use serde_json::Value;

    /// The line and column of the `nth` occurrence of `needle` in `text` (1, 1 when absent).
    fn locate(text: &str, needle: &str, nth: usize) -> (u32, u32) {
        let Some((at, _)) = text.match_indices(needle).nth(nth) else { return (1, 1) };
        let before = &text[..at];
        let line = before.matches('\n').count() as u32 + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) as u32 + 1;
        (line, col)
    }

    /// A number's decimal text (serde_json keeps the shortest text that reads back as the same
    /// f64, which is the decimal the file wrote whenever that has 17 digits or fewer).
    fn num_text(v: &Value) -> Option<String> {
        match v {
            Value::Null => Some("nan".into()),
            Value::Number(n) => Some(n.to_string()),
            _ => None,
        }
    }

    pub(super) fn parse(text: &str) -> Result<MissionFile, At> {
        let doc: Value = serde_json::from_str(text)
            .map_err(|e| (e.line() as u32, e.column() as u32, format!("not valid JSON: {e}")))?;
        let here = |needle: &str, nth: usize, m: String| {
            let (l, c) = locate(text, needle, nth);
            (l, c, m)
        };
        if doc.get("fileType").and_then(Value::as_str) != Some("Plan") {
            return Err(here("fileType", 0, "not a QGroundControl plan: `\"fileType\": \"Plan\"` missing".into()));
        }
        let mission = doc.get("mission").ok_or_else(|| here("{", 0, "no `mission` object".into()))?;
        let ardupilot = mission.get("firmwareType").and_then(Value::as_u64) == Some(3);
        let mut out = Vec::new();
        let mut items = Vec::new();
        if ardupilot {
            let home = mission.get("plannedHomePosition").and_then(Value::as_array);
            let Some(home) = home.filter(|h| h.len() == 3) else {
                return Err(here(
                    "plannedHomePosition",
                    0,
                    "an ArduPilot plan needs `plannedHomePosition` [lat, lon, alt] (uploaded as item 0)".into(),
                ));
            };
            let get = |i: usize| num_text(&home[i]);
            let (lat, lon, alt) = (get(0), get(1), get(2));
            let (Some(lat), Some(lon), Some(alt)) = (lat, lon, alt) else {
                return Err(here("plannedHomePosition", 0, "`plannedHomePosition` must hold three numbers".into()));
            };
            items.push(Item {
                seq: 0,
                current: false,
                frame: 0,
                command: 16,
                params: [0.0; 4],
                x: scaled_int(&lat, 7).ok_or_else(|| here("plannedHomePosition", 0, coord_msg("latitude", &lat, 7)))?,
                y: scaled_int(&lon, 7)
                    .ok_or_else(|| here("plannedHomePosition", 0, coord_msg("longitude", &lon, 7)))?,
                z: param(&alt).unwrap_or(f32::NAN),
                autocontinue: true,
                line: 0,
            });
        }
        let list = mission
            .get("items")
            .and_then(Value::as_array)
            .ok_or_else(|| here("\"mission\"", 0, "`mission.items` is not a list".into()))?;
        let mut simple_seen = 0usize;
        let mut complex_seen = 0usize;
        for it in list {
            match it.get("type").and_then(Value::as_str) {
                Some("SimpleItem") => {
                    simple_seen += 1;
                    push_simple(text, it, &mut items, simple_seen - 1)?;
                }
                Some("ComplexItem") => {
                    let kind = it.get("complexItemType").and_then(Value::as_str).unwrap_or("?");
                    complex_seen += 1;
                    let inner =
                        it.get("TransectStyleComplexItem").and_then(|t| t.get("Items")).and_then(Value::as_array);
                    let Some(inner) = inner else {
                        return Err(here(
                            "\"ComplexItem\"",
                            complex_seen - 1,
                            format!(
                                "complex item `{kind}` stores no mission items (QGroundControl computes them from its \
                                 geometry when it uploads): export the mission from QGroundControl as .waypoints to vet it"
                            ),
                        ));
                    };
                    for sub in inner {
                        simple_seen += 1;
                        push_simple(text, sub, &mut items, simple_seen - 1)?;
                    }
                }
                other => {
                    return Err(here(
                        "\"type\"",
                        simple_seen + complex_seen,
                        format!("unknown mission item type {other:?}"),
                    ));
                }
            }
        }
        out.push(Mission { mission_type: MissionType::Mission, items });
        let fence = fence_items(text, doc.get("geoFence"))?;
        if !fence.is_empty() {
            out.push(Mission { mission_type: MissionType::Fence, items: fence });
        }
        let mut rally = Vec::new();
        if let Some(points) = doc.get("rallyPoints").and_then(|r| r.get("points")).and_then(Value::as_array) {
            for (k, p) in points.iter().enumerate() {
                let (lat, lon, alt) = triple(p)
                    .ok_or_else(|| here("\"points\"", 0, format!("rally point {k} is not [lat, lon, alt]")))?;
                rally.push(Item {
                    seq: k as u16,
                    current: false,
                    frame: 3,
                    command: 5100,
                    params: [0.0; 4],
                    x: scaled_int(&lat, 7).ok_or_else(|| here("\"points\"", 0, coord_msg("latitude", &lat, 7)))?,
                    y: scaled_int(&lon, 7).ok_or_else(|| here("\"points\"", 0, coord_msg("longitude", &lon, 7)))?,
                    z: param(&alt).unwrap_or(f32::NAN),
                    autocontinue: false,
                    line: 0,
                });
            }
        }
        if !rally.is_empty() {
            out.push(Mission { mission_type: MissionType::Rally, items: rally });
        }
        Ok(MissionFile { format: MissionFormat::Plan, missions: out })
    }

    fn triple(p: &Value) -> Option<(String, String, String)> {
        let a = p.as_array()?;
        Some((num_text(a.first()?)?, num_text(a.get(1)?)?, num_text(a.get(2).unwrap_or(&Value::Null))?))
    }

    /// Appends the `SimpleItem` `it` (the `nth` in the file).
    fn push_simple(text: &str, it: &Value, items: &mut Vec<Item>, nth: usize) -> Result<(), At> {
        let (line, col) = locate(text, "\"SimpleItem\"", nth);
        let bad = |m: String| (line, col, m);
        let command = it.get("command").and_then(Value::as_u64).and_then(|c| u16::try_from(c).ok());
        let command = command.ok_or_else(|| bad("`command` is not a MAV_CMD number".into()))?;
        let frame = it.get("frame").and_then(Value::as_u64).and_then(|c| u8::try_from(c).ok());
        let frame = frame.ok_or_else(|| bad("`frame` is not a MAV_FRAME number".into()))?;
        check_enums(frame, command).map_err(|(_, m)| bad(m))?;
        let params = it.get("params").and_then(Value::as_array).filter(|p| p.len() == 7);
        let params = params.ok_or_else(|| bad("`params` is not a list of 7 numbers (null for NaN)".into()))?;
        let texts: Option<Vec<String>> = params.iter().map(num_text).collect();
        let texts = texts.ok_or_else(|| bad("`params` holds something other than numbers and null".into()))?;
        let mut p = [0f32; 4];
        for (k, slot) in p.iter_mut().enumerate() {
            *slot = param(&texts[k]).ok_or_else(|| bad(format!("param{} is not a number", k + 1)))?;
        }
        let digits = scale_digits(frame);
        let x = scaled_int(&texts[4], digits).ok_or_else(|| bad(coord_msg("x", &texts[4], digits)))?;
        let y = scaled_int(&texts[5], digits).ok_or_else(|| bad(coord_msg("y", &texts[5], digits)))?;
        let z = param(&texts[6]).ok_or_else(|| bad("param7 is not a number".into()))?;
        let autocontinue = it.get("autoContinue").and_then(Value::as_bool).unwrap_or(true);
        items.push(Item {
            seq: items.len() as u16,
            current: false,
            frame,
            command,
            params: p,
            x,
            y,
            z,
            autocontinue,
            line,
        });
        Ok(())
    }

    fn fence_items(text: &str, fence: Option<&Value>) -> Result<Vec<Item>, At> {
        let mut items = Vec::new();
        let Some(fence) = fence else { return Ok(items) };
        let (line, col) = locate(text, "\"geoFence\"", 0);
        let bad = |m: String| (line, col, m);
        let push = |items: &mut Vec<Item>, command: u16, p1: f32, lat: &str, lon: &str| -> Result<(), At> {
            let x = scaled_int(lat, 7).ok_or_else(|| bad(coord_msg("latitude", lat, 7)))?;
            let y = scaled_int(lon, 7).ok_or_else(|| bad(coord_msg("longitude", lon, 7)))?;
            let seq = items.len() as u16;
            items.push(Item {
                seq,
                current: false,
                frame: 0,
                command,
                params: [p1, 0.0, 0.0, 0.0],
                x,
                y,
                z: 0.0,
                autocontinue: false,
                line,
            });
            Ok(())
        };
        if let Some(polys) = fence.get("polygons").and_then(Value::as_array) {
            for poly in polys {
                let inclusion = poly.get("inclusion").and_then(Value::as_bool).unwrap_or(true);
                let pts = poly
                    .get("polygon")
                    .and_then(Value::as_array)
                    .ok_or_else(|| bad("a fence polygon has no `polygon` list".into()))?;
                for pt in pts {
                    let (lat, lon, _) = triple(pt).ok_or_else(|| bad("a fence vertex is not [lat, lon]".into()))?;
                    push(&mut items, if inclusion { 5001 } else { 5002 }, pts.len() as f32, &lat, &lon)?;
                }
            }
        }
        if let Some(circles) = fence.get("circles").and_then(Value::as_array) {
            for c in circles {
                let inclusion = c.get("inclusion").and_then(Value::as_bool).unwrap_or(true);
                let circle = c.get("circle").ok_or_else(|| bad("a fence circle has no `circle`".into()))?;
                let centre = circle.get("center").and_then(triple);
                let radius = circle.get("radius").and_then(Value::as_f64);
                let (Some((lat, lon, _)), Some(r)) = (centre, radius) else {
                    return Err(bad("a fence circle needs `center` [lat, lon] and `radius`".into()));
                };
                push(&mut items, if inclusion { 5003 } else { 5004 }, r as f32, &lat, &lon)?;
            }
        }
        if let Some(ret) = fence.get("breachReturn").and_then(triple) {
            push(&mut items, 5000, 0.0, &ret.0, &ret.1)?;
        }
        Ok(items)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_round_to_nearest_from_the_decimal() {
        assert_eq!(scaled_int("-35.363720", 7), Some(-353_637_200));
        assert_eq!(scaled_int("149.1652300", 7), Some(1_491_652_300));
        assert_eq!(scaled_int("-35.36372", 7), Some(-353_637_200));
        assert_eq!(scaled_int("1.00000005", 7), Some(10_000_001));
        assert_eq!(scaled_int("-1.00000005", 7), Some(-10_000_001));
        assert_eq!(scaled_int("1.00000004999", 7), Some(10_000_000));
        assert_eq!(scaled_int("1e-7", 7), Some(1));
        assert_eq!(scaled_int("4.7e1", 7), Some(470_000_000));
        assert_eq!(scaled_int("215", 7), None);
        assert_eq!(scaled_int("-214.7483648", 7), Some(i32::MIN));
        assert_eq!(scaled_int("12a", 7), None);
        assert_eq!(scaled_int("", 7), None);
        assert_eq!(scaled_int(".", 7), None);
        assert_eq!(scaled_int("0.4", 0), Some(0));
        assert_eq!(scaled_int("0.5", 0), Some(1));
        assert_eq!(scaled_int("1e-30", 7), Some(0));
        assert_eq!(scaled_int("9e99999", 7), None);
    }

    #[test]
    fn a_short_wpl_line_is_an_error_at_its_line() {
        let e =
            parse_mission("m.txt", "QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n1\t0\t3\t16\t0\n").unwrap_err();
        assert_eq!((e.line, e.column), (3, 11));
        assert!(e.to_string().starts_with("m.txt:3:11: 5 fields"), "{e}");
    }

    #[test]
    fn an_unknown_command_is_an_error_at_its_column() {
        let e = parse_mission("m.txt", "QGC WPL 110\n0 1 0 61234 0 0 0 0 1 2 3 1\n").unwrap_err();
        assert_eq!((e.line, e.column), (2, 7), "{e}");
    }
}
