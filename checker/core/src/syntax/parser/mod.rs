//! The parser: tokens to an [`ast::File`]. Parsing never fails: it returns the items it
//! could read and a diagnostic for each error, recovering at the next `;`, `}` or
//! top-level keyword. Nesting is bounded ([`MAX_DEPTH`]) so no input overflows the stack.
//!
//! Precedence in global types, loosest first: `+` (choice), `*` (separation), `.`
//! (sequence). `mu t.` extends as far right as possible. In processes, `+` is looser
//! than prefixes, so `p?a.P + p?b.Q` is a sum of two inputs.
//!
//! This file holds the entry points, the token helpers, the nesting bound and error
//! recovery; the grammar is in `items`, `global` (Def 4.1), `local` (Def 4.6),
//! `process` (Sec 3.1) and `expr`, one `impl Parser` each.

mod expr;
mod global;
mod items;
mod local;
mod process;
#[cfg(test)]
mod tests;

use super::ast::*;
use super::lexer::{lex, Tok, Token};
use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, Span};

/// The deepest nesting of parentheses, prefixes and operators accepted.
pub const MAX_DEPTH: usize = 1000;

const ITEM_KEYWORDS: &[&str] =
    &["import", "dialect", "const", "robot", "motion", "system", "choreography", "process", "local"];
const RESERVED: &[&str] = &[
    "import",
    "const",
    "robot",
    "motion",
    "system",
    "participant",
    "choreography",
    "process",
    "local",
    "mu",
    "dt",
    "end",
    "if",
    "then",
    "else",
    "true",
    "false",
    // The constant π (LANGUAGE.md, Expressions): reserved so that no binding can shadow it.
    "pi",
];

/// Parses one file.
pub fn parse(file: FileId, text: &str) -> (File, Vec<Diagnostic>) {
    let (toks, diags) = lex(file, text);
    let mut p = Parser { toks, pos: 0, diags, depth: 0, partitions: Vec::new() };
    let f = p.file();
    (f, p.diags)
}

/// Parses a standalone global type (used by tests and the library API).
pub fn parse_global(file: FileId, text: &str) -> (Option<Global>, Vec<Diagnostic>) {
    parse_with(file, text, Parser::global)
}

/// Parses a standalone local type.
pub fn parse_local(file: FileId, text: &str) -> (Option<Local>, Vec<Diagnostic>) {
    parse_with(file, text, Parser::local)
}

/// Parses a standalone expression.
pub fn parse_expr(file: FileId, text: &str) -> (Option<Expr>, Vec<Diagnostic>) {
    parse_with(file, text, Parser::expr)
}

fn parse_with<T>(file: FileId, text: &str, f: fn(&mut Parser) -> PResult<T>) -> (Option<T>, Vec<Diagnostic>) {
    let (toks, diags) = lex(file, text);
    let mut p = Parser { toks, pos: 0, diags, depth: 0, partitions: Vec::new() };
    let res = f(&mut p).ok();
    let res = match res {
        Some(r) if p.at_eof() => Some(r),
        Some(_) => {
            let _: PResult<()> = p.error_expected("end of input");
            None
        }
        None => None,
    };
    (res, p.diags)
}

/// `Err(())` means a diagnostic has been pushed; the caller recovers.
type PResult<T> = Result<T, ()>;

struct Parser {
    toks: Vec<Token>,
    pos: usize,
    diags: Vec<Diagnostic>,
    depth: usize,
    /// Partitions met in the choreography being parsed.
    partitions: Vec<PartitionDecl>,
}

impl Parser {
    // ---- token helpers -------------------------------------------------------------

    fn peek(&self) -> &Tok {
        &self.toks[self.pos].tok
    }

    fn peek_at(&self, n: usize) -> &Tok {
        &self.toks[(self.pos + n).min(self.toks.len() - 1)].tok
    }

    fn span(&self) -> Span {
        self.toks[self.pos].span
    }

    fn prev_span(&self) -> Span {
        self.toks[self.pos.saturating_sub(1)].span
    }

    fn at_eof(&self) -> bool {
        matches!(self.peek(), Tok::Eof)
    }

    fn bump(&mut self) -> Token {
        let t = self.toks[self.pos].clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }

    fn is_punct(&self, p: &str) -> bool {
        matches!(self.peek(), Tok::Punct(q) if *q == p)
    }

    fn is_kw(&self, kw: &str) -> bool {
        matches!(self.peek(), Tok::Ident(s) if s == kw)
    }

    fn eat_punct(&mut self, p: &str) -> bool {
        if self.is_punct(p) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn eat_kw(&mut self, kw: &str) -> bool {
        if self.is_kw(kw) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn expect_punct(&mut self, p: &str) -> PResult<Span> {
        if self.is_punct(p) {
            Ok(self.bump().span)
        } else {
            self.error_expected(&format!("`{p}`"))
        }
    }

    fn expect_kw(&mut self, kw: &str) -> PResult<Span> {
        if self.is_kw(kw) {
            Ok(self.bump().span)
        } else {
            self.error_expected(&format!("`{kw}`"))
        }
    }

    fn ident(&mut self, what: &str) -> PResult<Ident> {
        match self.peek().clone() {
            Tok::Ident(name) if !RESERVED.contains(&name.as_str()) => {
                let span = self.bump().span;
                Ok(Ident { name, span })
            }
            _ => self.error_expected(what),
        }
    }

    /// A message label: a name, a MAVLink command `COMMAND_LONG[MAV_CMD_X]` or a keyed
    /// label `PARAM_VALUE["MC_PITCH_P"]`, returned as one [`Ident`] named
    /// `COMMAND_LONG[MAV_CMD_X]` (`PARAM_VALUE["MC_PITCH_P"]`) whose span runs to the `]`. In
    /// a global type the guard's `[` comes before the label, so a `[` after it is the key.
    /// A key is kept as the wire reads it, up to its first NUL byte (as a string literal
    /// is: `lower::mav`'s `string`), so the same key is the same label however it is written.
    fn label(&mut self) -> PResult<Ident> {
        let mut label = self.ident("a message label")?;
        if self.eat_punct("[") {
            let key = match self.peek().clone() {
                Tok::Str(s) => {
                    self.bump();
                    format!("\"{}\"", s.split('\0').next().unwrap_or_default())
                }
                _ => {
                    self.ident("a command (`COMMAND_LONG[MAV_CMD_NAME]`) or a key (`PARAM_VALUE[\"MC_PITCH_P\"]`)")?
                        .name
                }
            };
            self.expect_punct("]")?;
            label = Ident { name: format!("{}[{key}]", label.name), span: label.span.to(self.prev_span()) };
        }
        Ok(label)
    }

    fn describe(tok: &Tok) -> String {
        match tok {
            Tok::Ident(s) if RESERVED.contains(&s.as_str()) => format!("keyword `{s}`"),
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Int(i) => format!("number `{i}`"),
            Tok::Real(r) => format!("number `{r}`"),
            Tok::Str(s) => format!("string {s:?}"),
            Tok::Punct(p) => format!("`{p}`"),
            Tok::Error => "an invalid token".into(),
            Tok::Eof => "end of file".into(),
        }
    }

    fn error_expected<T>(&mut self, what: &str) -> PResult<T> {
        // A lexer error already explains an Error token; do not pile a second one on it.
        if !matches!(self.peek(), Tok::Error) {
            let found = Self::describe(self.peek());
            let help = if matches!(self.peek(), Tok::Ident(s) if s == "pi") {
                "`pi` is the built-in constant π and cannot be redefined or bound: choose another name".to_string()
            } else {
                format!("write {what} here; LANGUAGE.md gives the grammar")
            };
            let d = Diagnostic::error(Code::UnexpectedToken, self.span(), format!("expected {what}, found {found}"))
                .with_help(help);
            self.diags.push(d);
        }
        Err(())
    }

    /// Runs `f` one level deeper, growing the stack on demand ([`crate::stack::deep`]), and
    /// refuses input nested deeper than [`MAX_DEPTH`].
    fn nested<T>(&mut self, f: impl FnOnce(&mut Parser) -> PResult<T>) -> PResult<T> {
        self.enter()?;
        let r = crate::stack::deep(|| f(self));
        self.leave();
        r
    }

    fn enter(&mut self) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let d = Diagnostic::error(Code::TooDeep, self.span(), format!("nesting deeper than {MAX_DEPTH} levels"))
                .with_help("split the term with named constants (long sequences `a. b. c` are fine)");
            self.diags.push(d);
            // Jump to the end so the caller does not report the same limit again.
            self.pos = self.toks.len() - 1;
            return Err(());
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    /// Skips to just after the next `;` at this nesting level, or to a `}` or a keyword
    /// that starts an item, whichever comes first.
    fn recover(&mut self, stop_at_brace: bool) {
        let mut depth = 0i32;
        loop {
            match self.peek() {
                Tok::Eof => return,
                Tok::Punct("(" | "[" | "{") => depth += 1,
                Tok::Punct(")" | "]") => depth -= 1,
                Tok::Punct("}") => {
                    if depth <= 0 && stop_at_brace {
                        return;
                    }
                    depth -= 1;
                }
                Tok::Punct(";") if depth <= 0 => {
                    self.bump();
                    return;
                }
                Tok::Ident(k) if depth <= 0 && ITEM_KEYWORDS.contains(&k.as_str()) && self.pos > 0 => {
                    if matches!(self.toks[self.pos - 1].tok, Tok::Punct(";" | "}")) {
                        return;
                    }
                }
                _ => {}
            }
            self.bump();
        }
    }
}
