//! Diagnostics: stable error codes, their `mochi explain` texts (the table is in
//! `diag/codes.rs`), and the [`Diagnostic`] value every stage produces. Nothing here
//! renders; see `render.rs`.
//!
//! Codes are grouped by stage: E01 syntax, E02 names and sorts, E03 well-formedness of
//! the choreography (Def 4.1, Sec 4.1, Def 4.4), E04 motion contracts ([AGCOMP]), E05 the
//! geometry stage (URDF files, meshes, kinematics; `checker/verify/src/geometry/`),
//! E06 projection (Defs 4.7-4.8), E07 process typing (Fig 5, Table 1) and U00 for
//! checks that could not be decided. A code never changes meaning once released.

use crate::source::Span;
use serde::Serialize;

mod codes;

pub use codes::Code;

impl std::fmt::Display for Code {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Code {
    type Err = ();
    fn from_str(s: &str) -> Result<Code, ()> {
        let s = s.trim().to_ascii_uppercase();
        Code::ALL.iter().copied().find(|c| c.as_str() == s).ok_or(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
    Note,
}

/// The value of one variable in a counterexample, printed as the user writes it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Assignment {
    pub name: String,
    pub value: String,
}

/// Where two footprints meet: a point of the world, and the time(s) of the motions.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Overlap {
    pub point: [f64; 3],
    /// One time for a joint motion; one per motion for the sides of `*`.
    pub times: Vec<f64>,
    /// For a joint motion: a time at or before which the footprints are proved not to
    /// meet (the solver found no such meeting), so they first meet after it and at the
    /// latest at `times[0]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_before: Option<f64>,
    /// For a joint motion: why the earliest meeting was not narrowed further (a search or
    /// a query that did not decide within its budget); `None` when nothing was left open.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub earliest_open: Option<String>,
}

impl Overlap {
    /// A meeting at `point` and `times`, with nothing said about the earliest one.
    pub fn at(point: [f64; 3], times: Vec<f64>) -> Overlap {
        Overlap { point, times, not_before: None, earliest_open: None }
    }
}

/// What Z3 found when a predicate check fails, in the user's terms.
#[derive(Clone, Debug, PartialEq, Serialize, Default)]
pub struct Counterexample {
    pub values: Vec<Assignment>,
    pub overlap: Option<Overlap>,
    /// The path through the global type to the failing point, one step a line, with the
    /// values of this counterexample (`wf::trace`); empty (and left out of JSON) when the
    /// point is not in the global type.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub trace: Vec<String>,
}

/// A secondary location with a short message ("the other branch is here").
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    pub span: Span,
    pub message: String,
}

/// One finding, located in the source. Messages are lowercase without a final period.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    pub code: Code,
    pub severity: Severity,
    pub span: Span,
    pub message: String,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    pub help: Option<String>,
    /// For a failed predicate check: the model Z3 found.
    pub counterexample: Option<Box<Counterexample>>,
}

impl Diagnostic {
    pub fn error(code: Code, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            code,
            severity: Severity::Error,
            span,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
            help: None,
            counterexample: None,
        }
    }

    pub fn note_at(code: Code, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Note, ..Diagnostic::error(code, span, message) }
    }

    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label { span, message: message.into() });
        self
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Diagnostic {
        self.help = Some(help.into());
        self
    }

    pub fn with_counterexample(mut self, c: Counterexample) -> Diagnostic {
        self.counterexample = Some(Box::new(c));
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// Sorts diagnostics by file and position so output is stable whatever the stage order.
pub fn sort(diags: &mut [Diagnostic]) {
    diags.sort_by(|a, b| {
        (a.span.file, a.span.start, a.code, &a.message).cmp(&(b.span.file, b.span.start, b.code, &b.message))
    });
}

/// Drops every diagnostic that repeats an earlier one as the user reads it (the same
/// code, severity, place, message, labels, notes and help): two obligations of one send
/// (a process's [T-OUT] asked from two paths that meet) failing alike are one finding.
pub fn dedupe(diags: &mut Vec<Diagnostic>) {
    let same = |a: &Diagnostic, b: &Diagnostic| {
        a.code == b.code
            && a.severity == b.severity
            && a.span == b.span
            && a.message == b.message
            && a.labels == b.labels
            && a.notes == b.notes
            && a.help == b.help
    };
    let mut kept: Vec<Diagnostic> = Vec::with_capacity(diags.len());
    for d in diags.drain(..) {
        if !kept.iter().any(|k| same(k, &d)) {
            kept.push(d);
        }
    }
    *diags = kept;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diagnostic_repeated_as_printed_is_shown_once() {
        let f = crate::source::FileId(0);
        let d =
            |msg: &str| Diagnostic::error(Code::SendPredicate, Span::new(f, 3, 9), msg).with_note("required: x > 0");
        let mut ds = vec![d("a send"), d("another send"), d("a send")];
        dedupe(&mut ds);
        assert_eq!(ds.iter().map(|d| d.message.as_str()).collect::<Vec<_>>(), ["a send", "another send"]);
        // A different note is a different finding.
        let mut ds = vec![d("a send"), d("a send").with_note("counterexample: x = 0")];
        dedupe(&mut ds);
        assert_eq!(ds.len(), 2);
    }

    #[test]
    fn codes_are_unique_and_parse_back() {
        let mut seen = std::collections::HashSet::new();
        for &c in Code::ALL {
            assert!(seen.insert(c.as_str()), "duplicate code {c}");
            assert_eq!(c.as_str().parse::<Code>(), Ok(c));
            assert!(c.explain().len() > 80, "{c} needs a real explanation");
            assert_eq!(c.title(), c.title().to_lowercase(), "{c} title must be lowercase");
        }
        assert_eq!("e0301".parse::<Code>(), Ok(Code::SelfMessage));
        // `explain` and `explain --list` print the title and the text: a reserved code says
        // so in both, and no other code does.
        for &c in Code::ALL {
            assert_eq!(c.title().contains("(reserved"), c.is_reserved(), "{c}");
            assert_eq!(c.explain().starts_with("reserved: "), c.is_reserved(), "{c}");
        }
        assert!("E9999".parse::<Code>().is_err());
    }
}
