//! Tests of the dialect reader against the bundled MAVLink definitions, of its errors and
//! of the lookups; a proptest that no input panics the reader.

use super::*;
use proptest::prelude::*;

fn common() -> &'static Dialect {
    builtin("common").expect("common is bundled")
}

fn apm() -> &'static Dialect {
    builtin("ardupilotmega").expect("ardupilotmega is bundled")
}

/// A loader over a few files given as text.
fn files<'a>(fs: &'a [(&'a str, &'a str)]) -> impl FnMut(&str) -> Option<String> + 'a {
    move |name| fs.iter().find(|(n, _)| *n == name).map(|(_, t)| t.to_string())
}

fn parse_files(root: &str, fs: &[(&str, &str)]) -> Result<Dialect, DialectError> {
    parse(root, &mut files(fs))
}

fn err(root: &str, fs: &[(&str, &str)]) -> DialectError {
    match parse_files(root, fs) {
        Ok(_) => panic!("{root} was read, an error was expected"),
        Err(e) => e,
    }
}

mod bundled;
mod reader;
