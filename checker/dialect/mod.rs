//! MAVLink dialects: the message and enum schema a refined session is checked against
//! (issue 10, seed 000 Sec 3 and seed 004's message families).
//!
//! A dialect is read from the MAVLink XML message definitions (`common.xml`,
//! `ardupilotmega.xml` and the files they include), bundled into the binary at build
//! time under `checker/dialect/definitions/` (origin and licence in its `SOURCES.md`).
//! This module is the only one that knows the XML; the rest of mochi sees the data model
//! below: messages with typed fields, enums with entries, and the named parameters of
//! each `MAV_CMD`.
//!
//! Stage: the front end ([`crate::lower`]) resolves a file's `dialect NAME;` to a
//! [`Dialect`] and checks message labels, fields and enum names against it.

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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dialect {
    /// The name written in `dialect NAME;` (the file name without `.xml`).
    pub name: String,
    pub messages: Vec<Message>,
    pub enums: Vec<Enum>,
}
