//! The lexer: source text to tokens. It never fails; bad characters become
//! [`Tok::Error`] tokens plus a diagnostic, and lexing goes on.

use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, Span};

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    Ident(String),
    Int(i64),
    Real(String),
    Str(String),
    /// Punctuation and operators, spelled as in the source (`->`, `&&`, `(`, ...).
    Punct(&'static str),
    Error,
    Eof,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    pub tok: Tok,
    pub span: Span,
}

/// Multi-character operators first, so the longest match wins.
const PUNCTS: &[&str] = &[
    "->", "=>", "==", "!=", "<=", ">=", "&&", "||", "/\\", "(", ")", "{", "}", "[", "]", "<", ">", ",", ";", ":", ".",
    "+", "-", "*", "/", "^", "!", "?", "=", "&",
];

pub fn lex(file: FileId, text: &str) -> (Vec<Token>, Vec<Diagnostic>) {
    let bytes = text.as_bytes();
    let mut toks = Vec::new();
    let mut diags = Vec::new();
    // A UTF-8 byte-order mark, as some Windows editors write, is not part of the text.
    let mut i = if text.starts_with('\u{feff}') { '\u{feff}'.len_utf8() } else { 0 };
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        if text[i..].starts_with("//") {
            // `\r` ends a line too: files with old Mac line endings have no `\n` at all.
            while i < bytes.len() && !matches!(bytes[i], b'\n' | b'\r') {
                i += 1;
            }
            continue;
        }
        if text[i..].starts_with("/*") {
            match text[i + 2..].find("*/") {
                Some(end) => i += 2 + end + 2,
                None => {
                    diags.push(
                        Diagnostic::error(
                            Code::Unterminated,
                            Span::new(file, start, start + 2),
                            "unterminated block comment",
                        )
                        .with_help("close the comment with `*/`"),
                    );
                    i = bytes.len();
                }
            }
            continue;
        }
        if c == b'"' {
            match text[i + 1..].find(['"', '\n', '\r']) {
                Some(end) if bytes[i + 1 + end] == b'"' => {
                    let s = text[i + 1..i + 1 + end].to_string();
                    i += end + 2;
                    toks.push(Token { tok: Tok::Str(s), span: Span::new(file, start, i) });
                }
                _ => {
                    diags.push(
                        Diagnostic::error(Code::Unterminated, Span::new(file, start, start + 1), "unterminated string")
                            .with_help("close the string with `\"` on the same line"),
                    );
                    while i < bytes.len() && !matches!(bytes[i], b'\n' | b'\r') {
                        i += 1;
                    }
                    toks.push(Token { tok: Tok::Error, span: Span::new(file, start, i) });
                }
            }
            continue;
        }
        if c.is_ascii_alphabetic() || c == b'_' {
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            toks.push(Token { tok: Tok::Ident(text[start..i].to_string()), span: Span::new(file, start, i) });
            continue;
        }
        if c.is_ascii_digit() {
            let (tok, end) = lex_number(text, start);
            i = end;
            let span = Span::new(file, start, i);
            match tok {
                Some(tok) => toks.push(Token { tok, span }),
                None => {
                    diags.push(
                        Diagnostic::error(Code::BadNumber, span, format!("malformed number `{}`", &text[start..i]))
                            .with_help("integers fit in 64 bits; reals look like `0.65` or `1.0e-3`"),
                    );
                    toks.push(Token { tok: Tok::Error, span });
                }
            }
            continue;
        }
        if let Some(p) = PUNCTS.iter().find(|p| text[i..].starts_with(**p)) {
            i += p.len();
            toks.push(Token { tok: Tok::Punct(p), span: Span::new(file, start, i) });
            continue;
        }
        // Anything else: one whole character, so spans stay on char boundaries. A run of
        // the same bad character (`~~~~~`) is one error, not one per character.
        let ch = text[i..].chars().next().unwrap_or('?');
        i += ch.len_utf8();
        let mut count = 1;
        while text[i..].starts_with(ch) {
            i += ch.len_utf8();
            count += 1;
        }
        let span = Span::new(file, start, i);
        let shown = ch.escape_debug();
        let message = if count == 1 {
            format!("unexpected character `{shown}`")
        } else {
            format!("{count} unexpected characters `{shown}`")
        };
        let mut d = Diagnostic::error(Code::UnexpectedChar, span, message);
        if let Some(ascii) = ascii_spelling(ch) {
            d = d.with_help(format!("write `{ascii}` instead"));
        } else if ch == '\u{feff}' {
            d = d.with_help("remove the byte-order mark: it is accepted only at the start of a file");
        } else {
            d = d.with_help("mochi source is ASCII; see LANGUAGE.md for the tokens");
        }
        diags.push(d);
        toks.push(Token { tok: Tok::Error, span });
    }
    toks.push(Token { tok: Tok::Eof, span: Span::new(file, text.len(), text.len()) });
    (toks, diags)
}

/// Reads `123`, `1.5`, `2e3`, `1.0e-3`. Returns `None` for an out-of-range integer or
/// a dangling exponent. A `.` not followed by a digit is left alone (it is sequencing).
fn lex_number(text: &str, start: usize) -> (Option<Tok>, usize) {
    let b = text.as_bytes();
    let mut i = start;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    let mut real = false;
    if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
        real = true;
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            real = true;
            i = j;
        } else {
            // `2e` or `2e+`: swallow the letters so the error covers them.
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_') {
                j += 1;
            }
            return (None, j);
        }
    }
    // Trailing identifier characters glued to a number (`12abc`) are an error.
    if i < b.len() && (b[i].is_ascii_alphabetic() || b[i] == b'_') {
        let mut j = i;
        while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_') {
            j += 1;
        }
        return (None, j);
    }
    let s = &text[start..i];
    if real {
        (Some(Tok::Real(s.to_string())), i)
    } else {
        (s.parse::<i64>().ok().map(Tok::Int), i)
    }
}

/// Helps users who paste the paper's notation.
fn ascii_spelling(ch: char) -> Option<&'static str> {
    Some(match ch {
        '→' => "->",
        '⇒' => "=>",
        '∧' => "&&",
        '∨' => "||",
        '¬' => "!",
        '≤' => "<=",
        '≥' => ">=",
        '≠' => "!=",
        'μ' => "mu",
        '⊕' => "+{ ... }",
        '⊓' => "/\\",
        '⟨' => "<",
        '⟩' => ">",
        '∞' => "inf",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &str) -> Vec<Tok> {
        lex(FileId(0), src).0.into_iter().map(|t| t.tok).collect()
    }

    #[test]
    fn operators_take_the_longest_match() {
        assert_eq!(
            kinds("p->q <= a/\\b"),
            vec![
                Tok::Ident("p".into()),
                Tok::Punct("->"),
                Tok::Ident("q".into()),
                Tok::Punct("<="),
                Tok::Ident("a".into()),
                Tok::Punct("/\\"),
                Tok::Ident("b".into()),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn numbers_and_sequencing_dots() {
        assert_eq!(kinds("1.5"), vec![Tok::Real("1.5".into()), Tok::Eof]);
        assert_eq!(kinds("1e-3"), vec![Tok::Real("1e-3".into()), Tok::Eof]);
        assert_eq!(kinds("t.1"), vec![Tok::Ident("t".into()), Tok::Punct("."), Tok::Int(1), Tok::Eof]);
        assert_eq!(kinds("ok."), vec![Tok::Ident("ok".into()), Tok::Punct("."), Tok::Eof]);
    }

    #[test]
    fn a_byte_order_mark_is_skipped_and_cr_ends_a_comment() {
        let (toks, diags) = lex(FileId(0), "\u{feff}a // c\rb");
        assert!(diags.is_empty(), "{diags:?}");
        let names: Vec<Tok> = toks.into_iter().map(|t| t.tok).collect();
        assert_eq!(names, vec![Tok::Ident("a".into()), Tok::Ident("b".into()), Tok::Eof]);
    }

    #[test]
    fn control_characters_are_escaped_and_runs_are_one_error() {
        let (_, diags) = lex(FileId(0), "a \0 ~~~~~ b");
        assert_eq!(diags.len(), 2, "{diags:?}");
        assert_eq!(diags[0].message, "unexpected character `\\0`");
        assert_eq!(diags[1].message, "5 unexpected characters `~`");
        assert_eq!(diags[1].span.range(), 4..9);
    }

    #[test]
    fn errors_are_reported_and_lexing_continues() {
        let (toks, diags) = lex(FileId(0), "a → b 99999999999999999999 /* x");
        assert_eq!(diags.len(), 3);
        assert_eq!(diags[0].code, Code::UnexpectedChar);
        assert_eq!(diags[0].help.as_deref(), Some("write `->` instead"));
        assert_eq!(diags[1].code, Code::BadNumber);
        assert_eq!(diags[2].code, Code::Unterminated);
        assert_eq!(toks.last().unwrap().tok, Tok::Eof);
    }
}
