//! The reader of MAVLink XML message definitions (`common.xml` and the files it includes)
//! into a [`Dialect`], with roxmltree (which knows the position of every element, so every
//! error has a file, line and column).
//!
//! What is read: `<include>` (resolved through the caller's loader, relative to the
//! including file's folder, each file once, so include cycles are harmless), `<enum>` (name,
//! `bitmask`, description; entries with `value` and name, `MAV_CMD` parameters with index,
//! label, enum, units, minValue, maxValue, reserved), `<message>` (id, name, description,
//! `<deprecated>`/`<superseded>` with `replaced_by`, fields with type, name, enum, units and
//! whether they follow `<extensions/>`). Enums of one name in several files are merged (their
//! entries appended, `bitmask` if any part says so).
//!
//! What is ignored: `<version>`, `<dialect>`, `<wip/>`, deprecation of enums and entries, the
//! field attributes `display`, `print_format`, `default`, `invalid`, `instance`,
//! `multiplier`, `increment`, the parameter attributes `default`, `increment`, `decimalPlaces`,
//! `hasLocation`/`isDestination`/`missionOnly` of commands, and any element or attribute this
//! reader does not know (later schema versions add some: ignoring them cannot change a
//! message's fields or an entry's value, which is all mochi checks against).
//!
//! What is refused (a [`DialectError`]): malformed XML (and any DTD: no entity expansion),
//! elements nested deeper than [`MAX_NESTING`] (roxmltree recurses per level), an element of
//! more than 64 attributes or more than 64 namespace declarations ([`crate::xmlscan`]), a root other
//! than `<mavlink>`, a missing required attribute, an unknown wire type, an array
//! length outside 1..=255, a message id outside MAVLink 2's 24 bits, a message name or id
//! defined twice with different content, two fields of one name, an entry value that is not
//! an integer (decimal, `0x` hex or `2**k`, optionally negative), an entry without a value
//! (pymavlink numbers such entries implicitly; mochi does not guess a constant), an entry
//! name defined twice with different content or in two enums, a parameter index outside
//! 1..=7 or given twice, a min/max that is not a finite number, a `bitmask` or `reserved`
//! other than `true`/`false`, a file the loader does not have, includes nested deeper than
//! [`MAX_INCLUDE_DEPTH`].

use super::{CmdParam, Dialect, Entry, Enum, Field, Message, Wire};
use rustc_hash::{FxHashMap, FxHashSet};
use std::borrow::Cow;
use std::fmt;

/// How deep includes may nest (the bundled tree is 4 deep: ardupilotmega, common, standard,
/// minimal). A bound, so that a loader that makes up files forever cannot exhaust the stack.
pub const MAX_INCLUDE_DEPTH: usize = 32;

/// How deep elements may nest: the shared pre-scan's limit ([`crate::xmlscan`]), which
/// runs before roxmltree (it parses elements by recursion) sees a document.
pub use crate::xmlscan::MAX_NESTING;

/// Why a definition tree could not be read: the file (as the loader was asked for it), the
/// 1-based line and column of the offending element or attribute, and what is wrong. `line`
/// is 0 when the error is about the file as a whole (the loader does not have the root file)
/// or about no file (from [`Dialect::new`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DialectError {
    pub file: String,
    pub line: u32,
    pub col: u32,
    pub message: String,
}

impl fmt::Display for DialectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}:{}:{}: {}", self.file, self.line, self.col, self.message)
        }
    }
}

impl std::error::Error for DialectError {}

/// Reads the dialect whose root definition file is `root` (`"common.xml"`); `load` returns
/// the text of a file by the name it is included by (joined to the including file's folder
/// when that has one: `"v1.0/common.xml"` includes `"v1.0/standard.xml"`), or `None` if there
/// is none. Each file is asked for once. The dialect's name is `root`'s file name without
/// folder and `.xml`. Never panics, whatever the files hold.
pub fn parse(root: &str, load: &mut dyn FnMut(&str) -> Option<String>) -> Result<Dialect, DialectError> {
    parse_texts(root, &mut |name| load(name).map(Cow::Owned), true)
}

/// [`parse`] over texts that may be borrowed (the bundled files are read in place, not
/// copied), keeping the description texts only if `descriptions` (without them every
/// `description` is empty: nothing but a reader of the definitions looks at them, and they are
/// a fifth of a dialect's memory).
pub(super) fn parse_texts(
    root: &str,
    load: &mut dyn FnMut(&str) -> Option<Cow<'static, str>>,
    descriptions: bool,
) -> Result<Dialect, DialectError> {
    let mut r = Reader {
        load,
        descriptions,
        seen: FxHashSet::default(),
        messages: Vec::new(),
        by_name: FxHashMap::default(),
        by_id: FxHashMap::default(),
        enums: Vec::new(),
        enum_at: FxHashMap::default(),
        entry_at: FxHashMap::default(),
    };
    r.file(root, None, 0)?;
    let name = root.rsplit('/').next().unwrap_or(root);
    let name = name.strip_suffix(".xml").unwrap_or(name);
    let messages = r.messages.into_iter().map(|(m, _)| m).collect();
    let enums = r.enums.into_iter().map(|(e, _)| e).collect();
    Dialect::new(name, messages, enums)
}

/// Where something was defined: for "first defined at" in duplicate errors.
#[derive(Clone, Debug)]
struct Origin {
    file: String,
    line: u32,
    col: u32,
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

struct Reader<'l> {
    load: &'l mut dyn FnMut(&str) -> Option<Cow<'static, str>>,
    /// Whether description texts are kept ([`parse_texts`]).
    descriptions: bool,
    seen: FxHashSet<String>,
    messages: Vec<(Message, Origin)>,
    by_name: FxHashMap<String, usize>,
    by_id: FxHashMap<u32, usize>,
    enums: Vec<(Enum, Origin)>,
    enum_at: FxHashMap<String, usize>,
    /// Entry name -> (enum index, entry index, where).
    entry_at: FxHashMap<String, (usize, usize, Origin)>,
}

/// One file being read: its name, text and where its lines start, for positions.
struct File<'a> {
    name: &'a str,
    text: &'a str,
    /// The byte offset of each line's start.
    lines: Vec<usize>,
    /// Whether description texts are kept ([`parse_texts`]).
    descriptions: bool,
}

impl File<'_> {
    /// The 1-based line and column (in characters, as roxmltree counts them) of a byte
    /// offset: a binary search over the line starts (roxmltree's `text_pos_at` scans from
    /// the start of the text, which made reading common.xml quadratic).
    fn origin(&self, at: usize) -> Origin {
        let at = at.min(self.text.len());
        let line = self.lines.partition_point(|&s| s <= at).max(1);
        let start = self.lines[line - 1];
        let col = self.text.get(start..at).map_or(0, |t| t.chars().count()) + 1;
        Origin { file: self.name.to_string(), line: line as u32, col: col as u32 }
    }

    fn err<T>(&self, at: usize, message: String) -> Result<T, DialectError> {
        let o = self.origin(at);
        Err(DialectError { file: o.file, line: o.line, col: o.col, message })
    }

    /// The value of a required attribute.
    fn required<'n>(&self, node: roxmltree::Node<'n, '_>, attr: &str) -> Result<&'n str, DialectError> {
        match node.attribute(attr) {
            Some(v) => Ok(v),
            None => self.err(node.range().start, format!("<{}> has no `{attr}` attribute", node.tag_name().name())),
        }
    }

    /// Where an attribute's value starts (the element's start if it has none).
    fn attr_at(&self, node: roxmltree::Node<'_, '_>, attr: &str) -> usize {
        node.attribute_node(attr).map_or(node.range().start, |a| a.range_value().start)
    }

    /// A `true`/`false` attribute; absent is false.
    fn flag(&self, node: roxmltree::Node<'_, '_>, attr: &str) -> Result<bool, DialectError> {
        match node.attribute(attr) {
            None | Some("false") => Ok(false),
            Some("true") => Ok(true),
            Some(v) => self.err(self.attr_at(node, attr), format!("`{attr}` is `{v}`, not `true` or `false`")),
        }
    }
}

/// The text of an element and its descendants, whitespace runs collapsed to one space.
fn text_of(node: roxmltree::Node<'_, '_>) -> String {
    let mut out = String::new();
    for t in node.descendants().filter(|n| n.is_text()).filter_map(|n| n.text()) {
        for w in t.split_whitespace() {
            if !out.is_empty() {
                out.push(' ');
            }
            out.push_str(w);
        }
    }
    out
}

/// The `<description>` child's text, or "" (always "" when `f` keeps no descriptions).
fn description(f: &File<'_>, node: roxmltree::Node<'_, '_>) -> String {
    if !f.descriptions {
        return String::new();
    }
    node.children().find(|c| c.has_tag_name("description")).map(text_of).unwrap_or_default()
}

/// The text of a field or parameter element (its description), or "" when `f` keeps no
/// descriptions.
fn own_text(f: &File<'_>, node: roxmltree::Node<'_, '_>) -> String {
    if f.descriptions {
        text_of(node)
    } else {
        String::new()
    }
}

/// `"2**k"`, `"0x.."`, decimal, each optionally with a leading `-`; `None` if not an `i64`.
fn entry_value(s: &str) -> Option<i64> {
    let s = s.trim();
    let (neg, body) = match s.strip_prefix('-') {
        Some(b) => (true, b.trim_start()),
        None => (false, s),
    };
    let digits = |d: &str, radix: u32| -> Option<i128> {
        if d.is_empty() || !d.chars().all(|c| c.is_digit(radix)) {
            return None;
        }
        i128::from_str_radix(d, radix).ok()
    };
    let v: i128 = if let Some(h) = body.strip_prefix("0x").or_else(|| body.strip_prefix("0X")) {
        digits(h, 16)?
    } else if let Some((b, k)) = body.split_once("**") {
        let (b, k) = (digits(b.trim(), 10)?, digits(k.trim(), 10)?);
        b.checked_pow(u32::try_from(k).ok()?)?
    } else {
        digits(body, 10)?
    };
    i64::try_from(if neg { -v } else { v }).ok()
}

/// The wire type and array length of a field's `type` attribute (`"uint8_t[4]"`).
fn wire_type(ty: &str) -> Result<(Wire, Option<u32>), String> {
    let (base, array) = match ty.strip_suffix(']').and_then(|t| t.split_once('[')) {
        Some((b, n)) => {
            let n: u32 = match n.parse::<u32>() {
                // Written plainly: `[04]` or `[+4]` are not MAVLink's.
                Ok(k) if (1..=255).contains(&k) && k.to_string() == n => k,
                _ => return Err(format!("the array length in `{ty}` is not a number in 1..=255")),
            };
            (b, Some(n))
        }
        None => (ty, None),
    };
    let wire = Wire::from_c_name(base).ok_or_else(|| {
        format!(
            "unknown wire type `{base}` (MAVLink's types are uint8_t..uint64_t, int8_t..int64_t, float, \
             double, char, and arrays of them)"
        )
    })?;
    if base == "uint8_t_mavlink_version" && array.is_some() {
        return Err(format!("`{ty}`: uint8_t_mavlink_version is a single byte"));
    }
    Ok((wire, array))
}

/// Joins an include to the including file's folder.
fn resolve(from: &str, include: &str) -> String {
    match from.rfind('/') {
        Some(i) if !include.starts_with('/') => format!("{}/{}", &from[..i], include),
        _ => include.to_string(),
    }
}

impl Reader<'_> {
    /// Reads the file `name` (once) and, first, the files it includes. `from` is the include
    /// element that asked for it.
    fn file(&mut self, name: &str, from: Option<Origin>, depth: usize) -> Result<(), DialectError> {
        if !self.seen.insert(name.to_string()) {
            return Ok(());
        }
        let missing = |message: String| match &from {
            Some(o) => DialectError { file: o.file.clone(), line: o.line, col: o.col, message },
            None => DialectError { file: name.to_string(), line: 0, col: 0, message },
        };
        if depth > MAX_INCLUDE_DEPTH {
            return Err(missing(format!("includes nest deeper than {MAX_INCLUDE_DEPTH} files at `{name}`")));
        }
        let text = match (self.load)(name) {
            Some(t) => t,
            None => {
                return Err(missing(match from {
                    Some(_) => format!("the included file `{name}` is not there"),
                    None => "no such definition file".to_string(),
                }))
            }
        };
        let lines = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        let f = File { name, text: &text, lines, descriptions: self.descriptions };
        if let Some(e) = crate::xmlscan::excess(&text) {
            use crate::xmlscan::{Excess, MAX_ATTRIBUTES, MAX_NAMESPACES};
            return match e {
                Excess::Depth(at) => f.err(at, format!("elements nest deeper than {MAX_NESTING}")),
                Excess::Attributes(at) => f.err(at, format!("an element has more than {MAX_ATTRIBUTES} attributes")),
                Excess::Namespaces(at) => f.err(at, format!("more than {MAX_NAMESPACES} namespace declarations")),
            };
        }
        let doc = match roxmltree::Document::parse(&text) {
            Ok(d) => d,
            Err(e) => {
                let p = e.pos();
                return Err(DialectError {
                    file: name.to_string(),
                    line: p.row,
                    col: p.col,
                    message: format!("malformed XML: {e}"),
                });
            }
        };
        let root = doc.root_element();
        if !root.has_tag_name("mavlink") {
            return f
                .err(root.range().start, format!("the root element is <{}>, not <mavlink>", root.tag_name().name()));
        }
        for inc in root.children().filter(|c| c.has_tag_name("include")) {
            let target = text_of(inc);
            if target.is_empty() {
                return f.err(inc.range().start, "an empty <include>".to_string());
            }
            self.file(&resolve(name, &target), Some(f.origin(inc.range().start)), depth + 1)?;
        }
        for section in root.children() {
            if section.has_tag_name("enums") {
                for e in section.children().filter(|c| c.has_tag_name("enum")) {
                    self.enum_(&f, e)?;
                }
            } else if section.has_tag_name("messages") {
                for m in section.children().filter(|c| c.has_tag_name("message")) {
                    self.message(&f, m)?;
                }
            }
        }
        Ok(())
    }

    fn enum_(&mut self, f: &File<'_>, node: roxmltree::Node<'_, '_>) -> Result<(), DialectError> {
        let name = f.required(node, "name")?;
        let bitmask = f.flag(node, "bitmask")?;
        let at = f.origin(node.range().start);
        let ei = match self.enum_at.get(name) {
            Some(&i) => {
                let e = &mut self.enums[i].0;
                e.bitmask |= bitmask;
                if e.description.is_empty() {
                    e.description = description(f, node);
                }
                i
            }
            None => {
                let e =
                    Enum { name: name.to_string(), bitmask, entries: Vec::new(), description: description(f, node) };
                self.enums.push((e, at));
                self.enum_at.insert(name.to_string(), self.enums.len() - 1);
                self.enums.len() - 1
            }
        };
        for x in node.children().filter(|c| c.has_tag_name("entry")) {
            let entry = entry(f, x)?;
            let here = f.origin(x.range().start);
            if let Some((i, j, first)) = self.entry_at.get(&entry.name) {
                let (i, j) = (*i, *j);
                if i == ei && self.enums[i].0.entries[j] == entry {
                    continue; // the same entry again (a file read through two paths)
                }
                let other = &self.enums[i].0;
                return f.err(
                    x.range().start,
                    if i == ei {
                        format!("enum entry {} is defined again with different content (first at {first})", entry.name)
                    } else {
                        format!(
                            "enum entry {} of {name} is also an entry of {} (at {first}): entry names must be \
                             unique in a dialect",
                            entry.name, other.name
                        )
                    },
                );
            }
            let e = &mut self.enums[ei].0;
            self.entry_at.insert(entry.name.clone(), (ei, e.entries.len(), here));
            e.entries.push(entry);
        }
        Ok(())
    }

    fn message(&mut self, f: &File<'_>, node: roxmltree::Node<'_, '_>) -> Result<(), DialectError> {
        let name = f.required(node, "name")?;
        let id_text = f.required(node, "id")?;
        let id = match id_text.trim().parse::<u32>() {
            Ok(id) if id < 1 << 24 => id,
            _ => {
                return f.err(
                    f.attr_at(node, "id"),
                    format!("message {name}: id `{id_text}` is not a number in 0..=16777215 (24 bits)"),
                )
            }
        };
        let mut fields: Vec<Field> = Vec::new();
        let mut extension = false;
        let mut deprecated = None;
        for c in node.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "extensions" => extension = true,
                "deprecated" | "superseded" => {
                    deprecated = Some(c.attribute("replaced_by").unwrap_or("").to_string());
                }
                "field" => {
                    let fname = f.required(c, "name")?;
                    let ty = f.required(c, "type")?;
                    let (wire, array) = match wire_type(ty.trim()) {
                        Ok(t) => t,
                        Err(m) => return f.err(f.attr_at(c, "type"), format!("field {name}.{fname}: {m}")),
                    };
                    if fields.iter().any(|g| g.name == fname) {
                        return f.err(c.range().start, format!("message {name} has two fields named {fname}"));
                    }
                    fields.push(Field {
                        name: fname.to_string(),
                        wire,
                        array,
                        enum_name: c.attribute("enum").map(str::to_string),
                        units: c.attribute("units").map(str::to_string),
                        extension,
                        description: own_text(f, c),
                    });
                }
                _ => {}
            }
        }
        let m = Message { id, name: name.to_string(), fields, deprecated, description: description(f, node) };
        let here = f.origin(node.range().start);
        let same_name = self.by_name.get(name).copied();
        let same_id = self.by_id.get(&id).copied();
        for k in [same_name, same_id].into_iter().flatten() {
            let (first, at) = &self.messages[k];
            if *first != m {
                let what = if first.name == m.name {
                    format!("message {name} is defined again with different content")
                } else {
                    format!("message {name} has id {id}, the id of {}", first.name)
                };
                return f.err(node.range().start, format!("{what} (first at {at})"));
            }
        }
        if same_name.is_none() {
            self.messages.push((m, here));
            self.by_name.insert(name.to_string(), self.messages.len() - 1);
            self.by_id.insert(id, self.messages.len() - 1);
        }
        Ok(())
    }
}

/// One `<entry>`.
fn entry(f: &File<'_>, node: roxmltree::Node<'_, '_>) -> Result<Entry, DialectError> {
    let name = f.required(node, "name")?;
    let value = match node.attribute("value") {
        None => {
            return f.err(
                node.range().start,
                format!("enum entry {name} has no value (mochi does not number entries implicitly)"),
            )
        }
        Some(v) => match entry_value(v) {
            Some(v) => v,
            None => {
                return f.err(
                    f.attr_at(node, "value"),
                    format!(
                        "the value `{v}` of enum entry {name} is not an integer (decimal, 0x hex or 2**k) \
                         within 64 signed bits"
                    ),
                )
            }
        },
    };
    let mut params: Vec<CmdParam> = Vec::new();
    for p in node.children().filter(|c| c.has_tag_name("param")) {
        let index_text = f.required(p, "index")?;
        let index = match index_text.trim().parse::<u8>() {
            Ok(i) if (1..=7).contains(&i) => i,
            _ => {
                return f.err(f.attr_at(p, "index"), format!("{name}: param index `{index_text}` is not one of 1..=7"))
            }
        };
        if params.iter().any(|q| q.index == index) {
            return f.err(p.range().start, format!("{name} has two params of index {index}"));
        }
        let bound = |attr: &str| -> Result<Option<f64>, DialectError> {
            match p.attribute(attr) {
                None => Ok(None),
                Some(v) => match v.trim().parse::<f64>() {
                    Ok(x) if x.is_finite() => Ok(Some(x)),
                    _ => f.err(f.attr_at(p, attr), format!("{name} param{index}: {attr} `{v}` is not a finite number")),
                },
            }
        };
        let (min, max) = (bound("minValue")?, bound("maxValue")?);
        params.push(CmdParam {
            index,
            label: p.attribute("label").map(str::to_string),
            enum_name: p.attribute("enum").map(str::to_string),
            units: p.attribute("units").map(str::to_string),
            min,
            max,
            reserved: f.flag(p, "reserved")?,
            description: own_text(f, p),
        });
    }
    params.sort_by_key(|p| p.index);
    Ok(Entry { name: name.to_string(), value, params, description: description(f, node) })
}
