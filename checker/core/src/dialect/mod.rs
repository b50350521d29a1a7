//! MAVLink dialects: the message and enum schema a refined session is checked against
//! (seed 000 Sec 3 and seed 004's message families).
//!
//! A dialect is read from the MAVLink XML message definitions (`common.xml`,
//! `ardupilotmega.xml` and the files they include), bundled into the binary at build
//! time under `checker/core/src/dialect/definitions/` (origin and licence in its `SOURCES.md`).
//! This module is the only one that knows the XML; the rest of mochi sees the data model
//! below: messages with typed fields, enums with entries, and the named parameters of
//! each `MAV_CMD`.
//!
//! Stage: the front end ([`crate::lower`]) resolves a file's `dialect NAME;` to a
//! [`Dialect`] and checks message labels, fields and enum names against it.
//!
//! The API: [`builtin`] and [`builtin_names`] for the bundled dialects, [`parse`] for a
//! definition tree given by a loader (its errors are [`DialectError`]s with a position),
//! the lookups [`Dialect::message`], [`Dialect::message_by_id`], [`Dialect::enum_`],
//! [`Dialect::entry`], [`Message::field`], [`Entry::param_by_name`], [`command_field`] (the
//! payload names of `COMMAND_LONG[CMD]`), the wire types' ranges ([`Wire::int_range`]) and
//! [`suggest`] for "did you mean" hints.

mod builtin;
mod xml;

pub use builtin::{builtin, builtin_names, without_descriptions};
pub use xml::{parse, DialectError};

use rustc_hash::FxHashMap;
use std::sync::OnceLock;

/// The wire type of a field (MAVLink's `uint8_t` ... `double`, `char`). An array field has
/// its length in [`Field::array`]; `char[N]` is a string.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wire {
    U8,
    U16,
    U32,
    U64,
    I8,
    I16,
    I32,
    I64,
    F32,
    F64,
    Char,
}

/// One field of a message, in the order of the XML (not the wire order).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub wire: Wire,
    /// `Some(n)` for `type[n]`.
    pub array: Option<u32>,
    /// The enum its values are taken from (`enum="MAV_CMD"`), if any.
    pub enum_name: Option<String>,
    /// `units="m"`, `"cm/s"`, ...
    pub units: Option<String>,
    /// After `<extensions/>`: MAVLink 2 only.
    pub extension: bool,
    pub description: String,
}

/// A message (`<message id=".." name="..">`).
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub id: u32,
    pub name: String,
    pub fields: Vec<Field>,
    /// `<deprecated replaced_by="...">`: the replacement's name.
    pub deprecated: Option<String>,
    pub description: String,
}

/// One `<param index="i">` of a `MAV_CMD` entry (i in 1..=7).
#[derive(Clone, Debug, PartialEq)]
pub struct CmdParam {
    pub index: u8,
    /// The `label` attribute ("Action"); mochi addresses the parameter by it in snake case
    /// (`action`), and always as `param<i>`.
    pub label: Option<String>,
    pub enum_name: Option<String>,
    pub units: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `reserved="true"`: the parameter must not be used.
    pub reserved: bool,
    pub description: String,
}

/// An enum entry (`<entry value=".." name="..">`).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub name: String,
    pub value: i64,
    /// Only for `MAV_CMD` entries: their parameters, by index.
    pub params: Vec<CmdParam>,
    pub description: String,
}

/// An enum (`<enum name="..." bitmask="true">`). Entries of one enum name may be spread
/// over several files of a dialect; they are merged.
#[derive(Clone, Debug, PartialEq)]
pub struct Enum {
    pub name: String,
    pub bitmask: bool,
    pub entries: Vec<Entry>,
    pub description: String,
}

/// A dialect: the union of a definition file and the files it includes.
///
/// Build one with [`parse`], [`builtin`] or [`Dialect::new`] (which check that names are
/// unique); a dialect built field by field (`..Default::default()`) works too, its lookups
/// then take the first of equal names. The lookups go through hash maps built on the first
/// lookup (the private `index`); do not change `messages` or `enums` after a lookup (clone
/// into a new `Dialect` instead).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dialect {
    /// The name written in `dialect NAME;` (the file name without `.xml`).
    pub name: String,
    pub messages: Vec<Message>,
    pub enums: Vec<Enum>,
    /// Name and id maps over `messages` and `enums`: a function of them, so it takes no part
    /// in equality.
    index: Index,
}

impl Wire {
    /// Every wire type, in the order of the MAVLink specification.
    pub const ALL: [Wire; 11] = [
        Wire::U8,
        Wire::U16,
        Wire::U32,
        Wire::U64,
        Wire::I8,
        Wire::I16,
        Wire::I32,
        Wire::I64,
        Wire::F32,
        Wire::F64,
        Wire::Char,
    ];

    /// The wire type of a C type name of the XML (`"uint16_t"`, `"float"`, `"char"`), without
    /// an array suffix. `uint8_t_mavlink_version` (HEARTBEAT's version byte, filled in by the
    /// protocol) is `U8`.
    pub fn from_c_name(name: &str) -> Option<Wire> {
        Some(match name {
            "uint8_t" | "uint8_t_mavlink_version" => Wire::U8,
            "uint16_t" => Wire::U16,
            "uint32_t" => Wire::U32,
            "uint64_t" => Wire::U64,
            "int8_t" => Wire::I8,
            "int16_t" => Wire::I16,
            "int32_t" => Wire::I32,
            "int64_t" => Wire::I64,
            "float" => Wire::F32,
            "double" => Wire::F64,
            "char" => Wire::Char,
            _ => return None,
        })
    }

    /// The C name of the type as the XML writes it (`"uint16_t"`, `"float"`, `"char"`).
    pub fn c_name(self) -> &'static str {
        match self {
            Wire::U8 => "uint8_t",
            Wire::U16 => "uint16_t",
            Wire::U32 => "uint32_t",
            Wire::U64 => "uint64_t",
            Wire::I8 => "int8_t",
            Wire::I16 => "int16_t",
            Wire::I32 => "int32_t",
            Wire::I64 => "int64_t",
            Wire::F32 => "float",
            Wire::F64 => "double",
            Wire::Char => "char",
        }
    }

    /// Whether the type is one of the eight integer types (not `char`, not a float).
    pub fn is_integer(self) -> bool {
        self.int_range().is_some()
    }

    /// Whether the type is `float` or `double`.
    pub fn is_float(self) -> bool {
        matches!(self, Wire::F32 | Wire::F64)
    }

    /// The closed range of an integer type (`U16` is `(0, 65535)`); `None` for `float`,
    /// `double` and `char` (a `char` is a byte of a string, not a number to mochi).
    pub fn int_range(self) -> Option<(i128, i128)> {
        let bits = |n: u32| 1i128 << n;
        Some(match self {
            Wire::U8 => (0, bits(8) - 1),
            Wire::U16 => (0, bits(16) - 1),
            Wire::U32 => (0, bits(32) - 1),
            Wire::U64 => (0, bits(64) - 1),
            Wire::I8 => (-bits(7), bits(7) - 1),
            Wire::I16 => (-bits(15), bits(15) - 1),
            Wire::I32 => (-bits(31), bits(31) - 1),
            Wire::I64 => (-bits(63), bits(63) - 1),
            Wire::F32 | Wire::F64 | Wire::Char => return None,
        })
    }

    /// The size of one value on the wire, in bytes.
    pub fn bytes(self) -> u32 {
        match self {
            Wire::U8 | Wire::I8 | Wire::Char => 1,
            Wire::U16 | Wire::I16 => 2,
            Wire::U32 | Wire::I32 | Wire::F32 => 4,
            Wire::U64 | Wire::I64 | Wire::F64 => 8,
        }
    }
}

impl Field {
    /// Whether the field is a string: `char[N]` (mochi's sort `str`, at most N bytes).
    pub fn is_string(&self) -> bool {
        self.wire == Wire::Char && self.array.is_some()
    }

    /// The type as the XML writes it: `"uint16_t"`, `"char[16]"`, `"float[4]"`.
    pub fn c_type(&self) -> String {
        match self.array {
            Some(n) => format!("{}[{n}]", self.wire.c_name()),
            None => self.wire.c_name().to_string(),
        }
    }
}

impl Message {
    /// The field of this name (`"count"` of MISSION_COUNT), extension fields included.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// The field a name key `MSG["KEY"]` fixes: the message's one `char[N]` field
    /// (PARAM_VALUE's, PARAM_SET's and PARAM_REQUEST_READ's `param_id`, NAMED_VALUE_FLOAT's
    /// `name`). `None` when the message has no string field or several (the key would not
    /// say which).
    pub fn key_field(&self) -> Option<&Field> {
        let mut strings = self.fields.iter().filter(|f| f.is_string());
        match (strings.next(), strings.next()) {
            (Some(f), None) => Some(f),
            _ => None,
        }
    }
}

/// What a label's `[...]` fixes (LANGUAGE.md, "Commands" and "Keyed labels").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabelKey<'a> {
    /// `COMMAND_LONG[MAV_CMD_X]`: the `command` field is the entry `MAV_CMD_X`.
    Command(&'a str),
    /// `PARAM_VALUE["MC_PITCH_P"]`: the message's one `char[N]` field
    /// ([`Message::key_field`]) holds this string, compared as on the wire (up to its first
    /// NUL byte: the parser keeps the key up to it).
    Name(&'a str),
}

/// A label split into its message's name and its key: `COMMAND_LONG[MAV_CMD_X]`,
/// `PARAM_VALUE["MC_PITCH_P"]` or a plain `HEARTBEAT` (no key). The one reader of the
/// label's text form, for lowering, the monitor and the tests.
pub fn split_label(label: &str) -> (&str, Option<LabelKey<'_>>) {
    let Some((name, rest)) = label.split_once('[') else { return (label, None) };
    let inner = rest.strip_suffix(']').unwrap_or(rest);
    match inner.strip_prefix('"').and_then(|k| k.strip_suffix('"')) {
        Some(key) => (name, Some(LabelKey::Name(key))),
        None => (name, Some(LabelKey::Command(inner))),
    }
}

impl CmdParam {
    /// The parameter's label in snake case, the name mochi addresses it by besides
    /// `param<i>`: `"Action"` is `action`, `"Yaw Angle"` is `yaw_angle`, `"Latitude/X"` is
    /// `latitude_x`, `"speed rate-of-change"` is `speed_rate_of_change`, `"SwitchPosition"`
    /// is `switch_position`, `"ROI Mode"` is `roi_mode`. `None` without a label, or when the
    /// label has no letter or digit, or starts with a digit (not an identifier). Whether the
    /// name is usable within its command is [`Entry::param_by_name`]'s business.
    pub fn snake_name(&self) -> Option<String> {
        self.label.as_deref().and_then(snake_case)
    }
}

/// `label` in snake case (see [`CmdParam::snake_name`]): words are split at every run of
/// characters that are not ASCII letters or digits, and inside a word before an upper-case
/// letter that follows a lower-case letter or digit, or that starts a capitalised word after
/// upper-case letters (`ROIMode` is `roi_mode`); the words are lower-cased and joined by `_`.
pub fn snake_case(label: &str) -> Option<String> {
    let mut out = String::new();
    for word in label.split(|c: char| !c.is_ascii_alphanumeric()).filter(|w| !w.is_empty()) {
        if !out.is_empty() {
            out.push('_');
        }
        let cs: Vec<char> = word.chars().collect();
        for (i, &c) in cs.iter().enumerate() {
            if i > 0 && c.is_ascii_uppercase() {
                let prev = cs[i - 1];
                let next_lower = cs.get(i + 1).is_some_and(|n| n.is_ascii_lowercase());
                if prev.is_ascii_lowercase() || prev.is_ascii_digit() || (prev.is_ascii_uppercase() && next_lower) {
                    out.push('_');
                }
            }
            out.push(c.to_ascii_lowercase());
        }
    }
    match out.chars().next() {
        Some(c) if c.is_ascii_alphabetic() => Some(out),
        _ => None,
    }
}

impl Entry {
    /// The parameter `name` addresses in this command (a `MAV_CMD` entry): `param<i>` (i in
    /// 1..=7) is the parameter of index i, and otherwise `name` is compared with each
    /// parameter's [`CmdParam::snake_name`]. A snake name two parameters of the command share,
    /// or one that is itself `param<j>`, addresses nothing (use `param<i>`). `None` also for
    /// `param<i>` when the XML lists no parameter i (COMMAND_LONG still has the field
    /// `param<i>`: the front end reads it as a plain field then). A reserved parameter is
    /// returned like any other: refusing it is the caller's rule.
    pub fn param_by_name(&self, name: &str) -> Option<&CmdParam> {
        if let Some(i) = positional_param(name) {
            return self.params.iter().find(|p| p.index == i);
        }
        let mut found = None;
        for p in &self.params {
            if p.snake_name().as_deref() == Some(name) {
                if found.is_some() {
                    return None;
                }
                found = Some(p);
            }
        }
        found
    }

    /// The names the parameters can be addressed by besides `param<i>` (see
    /// [`Entry::param_by_name`]), in index order: for "did you mean" hints and listings.
    pub fn param_names(&self) -> Vec<(String, &CmdParam)> {
        self.params
            .iter()
            .filter_map(|p| p.snake_name().map(|n| (n, p)))
            .filter(|(n, p)| self.param_by_name(n).is_some_and(|q| std::ptr::eq(q, *p)))
            .collect()
    }

    /// Whether the value is a single bit (a positive power of two): the entries of a bitmask
    /// enum that `has_flag` tests one bit of. (Some bitmask enums also list 0 or a mask of
    /// several bits; those are not single bits.)
    pub fn is_single_bit(&self) -> bool {
        self.value > 0 && (self.value & (self.value - 1)) == 0
    }
}

/// `Some(i)` when `name` is `param<i>` with i in 1..=7.
fn positional_param(name: &str) -> Option<u8> {
    let digits = name.strip_prefix("param")?;
    match digits.as_bytes() {
        [d @ b'1'..=b'7'] => Some(d - b'0'),
        _ => None,
    }
}

impl Enum {
    /// The entry of this name in this enum.
    pub fn entry(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.name == name)
    }

    /// The entries' values as maximal runs of consecutive integers `(lo, hi)`, ascending
    /// and disjoint (equal values once): MAV_RESULT's 0..=9 is one run, MAV_CMD's values
    /// some fifty. What a value of a plain (not bitmask) enum may be is their union.
    pub fn value_runs(&self) -> Vec<(i64, i64)> {
        let mut values: Vec<i64> = self.entries.iter().map(|e| e.value).collect();
        values.sort_unstable();
        values.dedup();
        let mut runs: Vec<(i64, i64)> = Vec::new();
        for v in values {
            match runs.last_mut() {
                Some((_, hi)) if hi.checked_add(1) == Some(v) => *hi = v,
                _ => runs.push((v, v)),
            }
        }
        runs
    }

    /// The bits of the low `bits` (1..=64) that some entry's value sets, its value read in
    /// two's complement: what a value of a bitmask enum may set (a combination of its flags;
    /// MAV_MODE_FLAG's eight flags make `0xff`, MAV_BOOL's FALSE = 0 and TRUE = 1 make `1`).
    pub fn flag_mask(&self, bits: u32) -> u64 {
        let keep = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        self.entries.iter().fold(0u64, |m, e| m | (e.value as u64 & keep))
    }
}

/// The hash maps over a dialect's names, built on the first lookup.
#[derive(Clone, Default)]
struct Index(OnceLock<Tables>);

#[derive(Clone, Default)]
struct Tables {
    message: FxHashMap<String, usize>,
    message_id: FxHashMap<u32, usize>,
    enum_: FxHashMap<String, usize>,
    entry: FxHashMap<String, (usize, usize)>,
}

impl PartialEq for Index {
    /// The index is a function of the dialect's messages and enums, which `Dialect`'s
    /// equality compares: two indexes never make two dialects differ.
    fn eq(&self, _: &Index) -> bool {
        true
    }
}

impl std::fmt::Debug for Index {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Index")
    }
}

impl Tables {
    /// The maps of `d`; of equal names the first wins (`Dialect::new` and `parse` refuse
    /// them).
    fn of(d: &Dialect) -> Tables {
        let mut t = Tables::default();
        for (i, m) in d.messages.iter().enumerate() {
            t.message.entry(m.name.clone()).or_insert(i);
            t.message_id.entry(m.id).or_insert(i);
        }
        for (i, e) in d.enums.iter().enumerate() {
            t.enum_.entry(e.name.clone()).or_insert(i);
            for (j, x) in e.entries.iter().enumerate() {
                t.entry.entry(x.name.clone()).or_insert((i, j));
            }
        }
        t
    }
}

impl Dialect {
    /// A dialect of these messages and enums, checked: message names, message ids, enum
    /// names and entry names (across all enums) are each unique, and field names within a
    /// message. The error names the first duplicate (its position is the dialect's name,
    /// line 0: there is no file).
    pub fn new(name: &str, messages: Vec<Message>, enums: Vec<Enum>) -> Result<Dialect, DialectError> {
        let d = Dialect { name: name.to_string(), messages, enums, index: Index::default() };
        let dup = |what: String| Err(DialectError { file: name.to_string(), line: 0, col: 0, message: what });
        let t = d.tables();
        if t.message.len() != d.messages.len() {
            return dup("two messages have the same name".into());
        }
        if t.message_id.len() != d.messages.len() {
            return dup("two messages have the same id".into());
        }
        if t.enum_.len() != d.enums.len() {
            return dup("two enums have the same name".into());
        }
        if t.entry.len() != d.enums.iter().map(|e| e.entries.len()).sum::<usize>() {
            return dup("two enum entries have the same name".into());
        }
        for m in &d.messages {
            for (i, f) in m.fields.iter().enumerate() {
                if m.fields[..i].iter().any(|g| g.name == f.name) {
                    return dup(format!("message {} has two fields named {}", m.name, f.name));
                }
            }
        }
        Ok(d)
    }

    fn tables(&self) -> &Tables {
        self.index.0.get_or_init(|| Tables::of(self))
    }

    /// The message of this name (`"MISSION_COUNT"`).
    pub fn message(&self, name: &str) -> Option<&Message> {
        self.tables().message.get(name).map(|&i| &self.messages[i])
    }

    /// The message of this id (44 is MISSION_COUNT).
    pub fn message_by_id(&self, id: u32) -> Option<&Message> {
        self.tables().message_id.get(&id).map(|&i| &self.messages[i])
    }

    /// The enum of this name (`"MAV_CMD"`), with the entries of every file of the dialect.
    pub fn enum_(&self, name: &str) -> Option<&Enum> {
        self.tables().enum_.get(name).map(|&i| &self.enums[i])
    }

    /// The entry of this name and its enum (`"PARACHUTE_RELEASE"` is of PARACHUTE_ACTION).
    /// Entry names are unique across a dialect's enums ([`parse`] checks it), so an entry
    /// name is a constant of the dialect.
    pub fn entry(&self, name: &str) -> Option<(&Enum, &Entry)> {
        self.tables().entry.get(name).map(|&(i, j)| (&self.enums[i], &self.enums[i].entries[j]))
    }

    /// Every entry of every enum with its enum, in file order: the dialect's constants.
    pub fn entries(&self) -> impl Iterator<Item = (&Enum, &Entry)> {
        self.enums.iter().flat_map(|e| e.entries.iter().map(move |x| (e, x)))
    }

    /// Whether `entry` is a single-bit flag of a bitmask enum (`MAV_MODE_FLAG_SAFETY_ARMED`):
    /// the constants `has_flag` is meant for.
    pub fn is_flag(&self, entry: &str) -> bool {
        self.entry(entry).is_some_and(|(e, x)| e.bitmask && x.is_single_bit())
    }
}

/// What a payload name of `COMMAND_LONG[CMD](...)` / `COMMAND_INT[CMD](...)` addresses: see
/// [`command_field`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CommandField<'a> {
    /// A field of the message; `param` is the command's parameter it carries, if the field
    /// is one of the message's parameter fields and the XML describes that parameter (its
    /// label, enum, units, range, `reserved`).
    Field { field: &'a Field, param: Option<&'a CmdParam> },
    /// The name is both a field of the message and the label of a parameter carried by
    /// another field (`frame` of COMMAND_INT and param2 "Frame" of MAV_CMD_DO_CHANGE_ALTITUDE;
    /// `command` of COMMAND_LONG and param1 "command" of ardupilotmega's
    /// MAV_CMD_NAV_SCRIPT_TIME): the writer must say `param<i>` or use another name.
    Ambiguous { field: &'a Field, param: &'a CmdParam },
    /// Neither a field of the message nor a parameter of the command.
    Unknown,
}

/// The field of `message` (COMMAND_LONG, COMMAND_INT) that carries parameter `index` (1..=7)
/// of a command: `param<i>`, and in COMMAND_INT, whose parameters 5 to 7 are the integer
/// fields `x`, `y`, `z`, those.
pub fn param_field(message: &Message, index: u8) -> Option<&Field> {
    message.field(&format!("param{index}")).or_else(|| match index {
        5..=7 => message.field(["x", "y", "z"][usize::from(index - 5)]),
        _ => None,
    })
}

/// Resolves `name` in the payload of `message` sent as command `command` (a `MAV_CMD`
/// entry), as `COMMAND_LONG[MAV_CMD_DO_PARACHUTE](action {...})` reads: a field of the
/// message by its own name (`target_system`, `param1`, `x`), or a parameter by
/// [`Entry::param_by_name`] (its label in snake case, or `param<i>`) mapped to the field that
/// carries it ([`param_field`]). A name that is a field and also another parameter's label is
/// [`CommandField::Ambiguous`], never silently one of them (the two differ in type and
/// meaning: COMMAND_INT's `frame` is a MAV_FRAME byte, DO_CHANGE_ALTITUDE's param2 a float).
pub fn command_field<'a>(message: &'a Message, command: &'a Entry, name: &str) -> CommandField<'a> {
    let carried = |field: &Field| (1..=7).find(|&i| param_field(message, i).is_some_and(|f| std::ptr::eq(f, field)));
    match (message.field(name), command.param_by_name(name)) {
        (Some(field), Some(param)) => {
            if carried(field) == Some(param.index) {
                CommandField::Field { field, param: Some(param) }
            } else {
                CommandField::Ambiguous { field, param }
            }
        }
        (Some(field), None) => {
            let param = carried(field).and_then(|i| command.params.iter().find(|p| p.index == i));
            CommandField::Field { field, param }
        }
        (None, Some(param)) => match param_field(message, param.index) {
            Some(field) => CommandField::Field { field, param: Some(param) },
            None => CommandField::Unknown,
        },
        (None, None) => CommandField::Unknown,
    }
}

/// Up to three names of `candidates` closest to `name`, closest first, for "did you mean"
/// hints: by edit distance (Levenshtein, ignoring case), within a third of the name's length
/// (at least 1, at most 6 edits), or, for names of four characters or more, candidates that
/// contain `name` ignoring case (`PARACHUTE` finds `MAV_CMD_DO_PARACHUTE`). Ties are broken by
/// name, so the hint is deterministic; a candidate equal to `name` is left out (the caller
/// asks because `name` was not found). Duplicates among the candidates are reported once.
pub fn suggest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let lower = name.to_lowercase();
    let limit = (name.chars().count() / 3).clamp(1, 6);
    let mut scored: Vec<(usize, &'a str)> = candidates
        .filter(|c| *c != name)
        .filter_map(|c| {
            let cl = c.to_lowercase();
            let d = strsim::levenshtein(&lower, &cl);
            if d <= limit {
                Some((d, c))
            } else if lower.chars().count() >= 4 && cl.contains(&lower) {
                Some((d.max(limit + 1), c))
            } else {
                None
            }
        })
        .collect();
    scored.sort();
    scored.dedup_by(|a, b| a.1 == b.1);
    scored.into_iter().take(3).map(|(_, c)| c).collect()
}

#[cfg(test)]
mod tests;
