//! The dialects bundled with mochi: the MAVLink XML definitions under
//! `checker/core/src/dialect/definitions/` (origin, commit and licence in its `SOURCES.md`),
//! embedded in the binary at build time, each parsed once on first use.

use super::{xml, Dialect};
use std::borrow::Cow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

/// The bundled definition files: the name a protocol writes in `dialect NAME;` (the file
/// name without `.xml`) and the file's text.
const FILES: [(&str, &str); 9] = [
    ("ardupilotmega", include_str!("definitions/ardupilotmega.xml")),
    ("common", include_str!("definitions/common.xml")),
    ("csAirLink", include_str!("definitions/csAirLink.xml")),
    ("cubepilot", include_str!("definitions/cubepilot.xml")),
    ("icarous", include_str!("definitions/icarous.xml")),
    ("loweheiser", include_str!("definitions/loweheiser.xml")),
    ("minimal", include_str!("definitions/minimal.xml")),
    ("standard", include_str!("definitions/standard.xml")),
    ("uAvionix", include_str!("definitions/uAvionix.xml")),
];

const NAMES: [&str; 9] = {
    let mut names = [""; 9];
    let mut i = 0;
    while i < FILES.len() {
        names[i] = FILES[i].0;
        i += 1;
    }
    names
};

/// The names of the bundled dialects, sorted as the files are (`"ardupilotmega"`,
/// `"common"`, ..., `"minimal"`, `"standard"`, `"uAvionix"`): for `dialect NAME;` and its
/// "did you mean" hint.
pub fn builtin_names() -> &'static [&'static str] {
    &NAMES
}

/// The bundled dialect `name` (`"common"`, `"ardupilotmega"`, see [`builtin_names`]; the
/// name is matched exactly), read from the embedded XML on the first call for that name and
/// shared afterwards (a `OnceLock` per name). `None` for a name that is not bundled. Every
/// bundled file reads without error (a unit test checks each): a failure to read one would
/// be a defect of the bundle and also gives `None`, never a panic.
///
/// Cost of the first call, measured in a release build on the (shared, loaded) development
/// machine, best of 20: `common` 5.5 ms, `ardupilotmega` (common's tree and six more files)
/// 6.7 ms; a cold first read 20-40 ms (`tests::builtin_parse_time_common_and_ardupilotmega_well_under_50ms`
/// bounds it).
///
/// The embedded texts are read in place (not copied), and without their description texts
/// after [`without_descriptions`].
pub fn builtin(name: &str) -> Option<&'static Dialect> {
    static CELLS: [OnceLock<Option<Dialect>>; 9] = [const { OnceLock::new() }; 9];
    let i = FILES.iter().position(|(n, _)| *n == name)?;
    let descriptions = DESCRIPTIONS.load(Ordering::Relaxed);
    let mut load = |file: &str| embedded(file).map(Cow::Borrowed);
    CELLS[i].get_or_init(|| xml::parse_texts(&format!("{name}.xml"), &mut load, descriptions).ok()).as_ref()
}

/// Whether the bundled dialects keep their description texts ([`without_descriptions`]).
static DESCRIPTIONS: AtomicBool = AtomicBool::new(true);

/// From now on, a bundled dialect read for the first time keeps no description texts: every
/// `description` of its messages, fields, enums, entries and command parameters is empty. The
/// names, ids, wire types, enums, units, labels and bounds, everything a program is checked and
/// lowered against, are the same. For a process that only lowers and enforces protocols
/// (`mochi-proxy`): nothing but a reader of the definitions looks at the descriptions, and
/// they are a fifth of a parsed dialect's memory (common and ardupilotmega together: 2.5 MB
/// of heap with them, 2.0 MB without). A dialect already read keeps what it has.
pub fn without_descriptions() {
    DESCRIPTIONS.store(false, Ordering::Relaxed);
}

/// The embedded text of a file (by file name, `common.xml`).
fn embedded(file: &str) -> Option<&'static str> {
    let stem = file.strip_suffix(".xml")?;
    FILES.iter().find(|(n, _)| *n == stem).map(|(_, t)| *t)
}

/// The loader over the embedded files, a copy of the text (for the tests' loaders).
#[cfg(test)]
pub(super) fn bundled(file: &str) -> Option<String> {
    embedded(file).map(str::to_string)
}
