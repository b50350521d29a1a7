//! The parser: tokens to an [`ast::File`]. Parsing never fails: it returns the items it
//! could read and a diagnostic for each error, recovering at the next `;`, `}` or
//! top-level keyword. Nesting is bounded ([`MAX_DEPTH`]) so no input overflows the stack.
//!
//! Precedence in global types, loosest first: `+` (choice), `*` (separation), `.`
//! (sequence). `mu t.` extends as far right as possible. In processes, `+` is looser
//! than prefixes, so `p?a.P + p?b.Q` is a sum of two inputs.

use super::ast::*;
use super::lexer::{lex, Tok, Token};
use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, Span};

/// The deepest nesting of parentheses, prefixes and operators accepted.
pub const MAX_DEPTH: usize = 1000;

/// When less than this much stack is left, a new segment is allocated...
pub const STACK_RED_ZONE: usize = 64 * 1024;
/// ...of this size.
pub const STACK_GROWTH: usize = 4 * 1024 * 1024;

const ITEM_KEYWORDS: &[&str] = &["import", "const", "robot", "motion", "system", "choreography", "process", "local"];
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

    /// Runs `f` one level deeper, growing the stack on demand (the `stacker` crate, as
    /// rustc does) and refusing input nested deeper than [`MAX_DEPTH`].
    fn nested<T>(&mut self, f: impl FnOnce(&mut Parser) -> PResult<T>) -> PResult<T> {
        self.enter()?;
        let r = stacker::maybe_grow(STACK_RED_ZONE, STACK_GROWTH, || f(self));
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

    // ---- items ---------------------------------------------------------------------

    fn file(&mut self) -> File {
        let mut items = Vec::new();
        while !self.at_eof() {
            let before = self.pos;
            match self.item() {
                Ok(item) => items.push(item),
                Err(()) => {
                    self.recover(false);
                    if self.pos == before {
                        self.bump();
                    }
                }
            }
        }
        File { items }
    }

    fn item(&mut self) -> PResult<Item> {
        let start = self.span();
        let kw =
            match self.peek() {
                Tok::Ident(k) if ITEM_KEYWORDS.contains(&k.as_str()) => k.clone(),
                _ => return self.error_expected(
                    "an item (`import`, `const`, `robot`, `motion`, `system`, `choreography`, `process` or `local`)",
                ),
            };
        self.bump();
        let item = match kw.as_str() {
            "import" => {
                let path = match self.peek().clone() {
                    Tok::Str(s) => {
                        self.bump();
                        s
                    }
                    _ => return self.error_expected("a file path in double quotes"),
                };
                self.expect_punct(";")?;
                Item::Import(Import { path, span: start.to(self.prev_span()) })
            }
            "const" => {
                let name = self.ident("a constant name")?;
                let sort = if self.eat_punct(":") { Some(self.sort()?) } else { None };
                self.expect_punct("=")?;
                let value = self.expr()?;
                self.expect_punct(";")?;
                Item::Const(ConstDecl { name, sort, value, span: start.to(self.prev_span()) })
            }
            "robot" => Item::Robot(self.robot(start)?),
            "motion" => Item::Motion(self.motion(start)?),
            "system" => Item::System(self.system(start)?),
            "choreography" => {
                let name = self.ident("a choreography name")?;
                self.expect_punct("=")?;
                self.partitions.clear();
                let body = self.global()?;
                self.expect_punct(";")?;
                let partitions = std::mem::take(&mut self.partitions);
                Item::Choreography(ChorDecl { name, body, span: start.to(self.prev_span()), partitions })
            }
            "process" => {
                let role = self.ident("a participant name")?;
                self.expect_punct("=")?;
                let body = self.process()?;
                self.expect_punct(";")?;
                Item::Process(ProcessDecl { role, body, span: start.to(self.prev_span()) })
            }
            _ => {
                let role = self.ident("a participant name")?;
                self.expect_punct("=")?;
                let body = self.local()?;
                self.expect_punct(";")?;
                Item::Local(LocalDecl { role, body, span: start.to(self.prev_span()) })
            }
        };
        Ok(item)
    }

    /// Parses `{ entry* }` calling `entry` for each, recovering inside the block.
    fn block(&mut self, mut entry: impl FnMut(&mut Parser) -> PResult<()>) -> PResult<()> {
        self.expect_punct("{")?;
        while !self.is_punct("}") && !self.at_eof() {
            let before = self.pos;
            if entry(self).is_err() {
                self.recover(true);
                if self.pos == before {
                    self.bump();
                }
            }
        }
        self.expect_punct("}")?;
        Ok(())
    }

    fn robot(&mut self, start: Span) -> PResult<RobotDecl> {
        let name = self.ident("a robot kind name")?;
        let mut r = RobotDecl { name, state: vec![], inputs: vec![], geometry: None, invariant: None, span: start };
        self.block(|p| {
            let key = p.ident("`state`, `input`, `geometry` or `invariant`")?;
            match key.name.as_str() {
                "state" | "input" => {
                    let vars = p.var_decls(";")?;
                    p.expect_punct(";")?;
                    if key.name == "state" {
                        r.state.extend(vars)
                    } else {
                        r.inputs.extend(vars)
                    }
                }
                "geometry" => {
                    p.expect_punct(":")?;
                    let shape = p.ident("a shape (`box`, `sphere`, `cylinder` or `urdf`)")?;
                    let mut g = Geometry { shape, args: vec![], path: None, span: key.span };
                    p.expect_punct("(")?;
                    if let Tok::Str(s) = p.peek().clone() {
                        p.bump();
                        g.path = Some(s);
                    } else if !p.is_punct(")") {
                        g.args = p.expr_list(")")?;
                    }
                    p.expect_punct(")")?;
                    g.span = key.span.to(p.prev_span());
                    p.expect_punct(";")?;
                    r.geometry = Some(g);
                }
                "invariant" => {
                    p.expect_punct(":")?;
                    r.invariant = Some(p.expr()?);
                    p.expect_punct(";")?;
                }
                other => {
                    let d = Diagnostic::error(
                        Code::UnexpectedToken,
                        key.span,
                        format!("expected `state`, `input`, `geometry` or `invariant`, found `{other}`"),
                    )
                    .with_help("a robot block declares its variables, geometry and invariant");
                    p.diags.push(d);
                    return Err(());
                }
            }
            Ok(())
        })?;
        r.span = start.to(self.prev_span());
        Ok(r)
    }

    /// `a: real, b: int` up to (not including) `end`.
    fn var_decls(&mut self, end: &str) -> PResult<Vec<VarDecl>> {
        let mut out = Vec::new();
        if self.is_punct(end) {
            return Ok(out);
        }
        loop {
            let name = self.ident("a variable name")?;
            self.expect_punct(":")?;
            let sort = self.sort()?;
            out.push(VarDecl { name, sort });
            if !self.eat_punct(",") {
                return Ok(out);
            }
        }
    }

    fn motion(&mut self, start: Span) -> PResult<MotionDecl> {
        let kind = self.ident("a robot kind")?;
        self.expect_punct(".")?;
        let name = self.ident("a motion primitive name")?;
        let mut params = Vec::new();
        if self.eat_punct("(") {
            params = self.var_decls(")")?;
            self.expect_punct(")")?;
        }
        let mut fields = Vec::new();
        self.block(|p| {
            let key = p.ident(
                "a contract field (`pre`, `assume`, `guarantee`, `post`, `footprint`, `duration`, `interruptible`)",
            )?;
            let value = match key.name.as_str() {
                "footprint" => {
                    p.expect_punct("(")?;
                    let a = p.ident("a coordinate name")?;
                    p.expect_punct(",")?;
                    let b = p.ident("a coordinate name")?;
                    p.expect_punct(",")?;
                    let c = p.ident("a coordinate name")?;
                    p.expect_punct(")")?;
                    p.expect_punct(":")?;
                    FieldValue::Footprint { point: [a, b, c], pred: p.expr()? }
                }
                "duration" => {
                    p.expect_punct(":")?;
                    p.expect_punct("[")?;
                    let lo = p.expr()?;
                    p.expect_punct(",")?;
                    let hi = if p.is_kw("inf") && matches!(p.peek_at(1), Tok::Punct("]")) {
                        p.bump();
                        None
                    } else {
                        Some(p.expr()?)
                    };
                    p.expect_punct("]")?;
                    FieldValue::Duration { lo, hi }
                }
                "interruptible" => {
                    p.expect_punct(":")?;
                    if p.eat_kw("true") {
                        FieldValue::Flag(true)
                    } else if p.eat_kw("false") {
                        FieldValue::Flag(false)
                    } else {
                        return p.error_expected("`true` or `false`");
                    }
                }
                _ => {
                    p.expect_punct(":")?;
                    FieldValue::Pred(p.expr()?)
                }
            };
            p.expect_punct(";")?;
            fields.push(MotionField { span: key.span.to(p.prev_span()), key, value });
            Ok(())
        })?;
        Ok(MotionDecl { kind, name, params, fields, span: start.to(self.prev_span()) })
    }

    fn system(&mut self, start: Span) -> PResult<SystemDecl> {
        let name = self.ident("a system name")?;
        let mut participants = Vec::new();
        self.block(|p| {
            let pstart = p.expect_kw("participant")?;
            let name = p.ident("a participant name")?;
            p.expect_punct(":")?;
            let kind = p.ident("a robot kind")?;
            let mut part = ParticipantDecl { name, kind, init: None, at: None, span: pstart };
            if !p.eat_punct(";") {
                p.block(|p| {
                    let key = p.ident("`init` or `at`")?;
                    p.expect_punct(":")?;
                    match key.name.as_str() {
                        "init" => part.init = Some(p.expr()?),
                        "at" => {
                            let s = p.expect_kw("pose")?;
                            p.expect_punct("(")?;
                            let args = p.expr_list(")")?;
                            p.expect_punct(")")?;
                            part.at = Some(Pose { args, span: s.to(p.prev_span()) });
                        }
                        other => {
                            let d = Diagnostic::error(
                                Code::UnexpectedToken,
                                key.span,
                                format!("expected `init` or `at`, found `{other}`"),
                            )
                            .with_help("a participant block holds `init: PREDICATE;` and `at: pose(x, y, z);`");
                            p.diags.push(d);
                            return Err(());
                        }
                    }
                    p.expect_punct(";")?;
                    Ok(())
                })?;
            }
            part.span = pstart.to(p.prev_span());
            participants.push(part);
            Ok(())
        })?;
        Ok(SystemDecl { name, participants, span: start.to(self.prev_span()) })
    }

    fn sort(&mut self) -> PResult<SortAst> {
        let start = self.span();
        if self.eat_punct("(") {
            let mut parts = vec![self.nested(Parser::sort)?];
            while self.eat_punct(",") {
                parts.push(self.nested(Parser::sort)?);
            }
            self.expect_punct(")")?;
            let span = start.to(self.prev_span());
            if parts.len() == 1 {
                return Ok(parts.pop().unwrap_or(SortAst { kind: SortKind::Unit, span }));
            }
            return Ok(SortAst { kind: SortKind::Product(parts), span });
        }
        let id = self.ident("a sort (`unit`, `bool`, `int`, `real`, `point`, `vector` or a product `(S, S)`)")?;
        let kind = match id.name.as_str() {
            "unit" => SortKind::Unit,
            "bool" => SortKind::Bool,
            "int" => SortKind::Int,
            "real" => SortKind::Real,
            "point" => SortKind::Point,
            "vector" => SortKind::Vector,
            other => SortKind::Named(other.to_string()),
        };
        Ok(SortAst { kind, span: id.span })
    }

    /// `(f: S {P}, g: S)` payload fields; the opening `(` is already consumed.
    fn fields(&mut self) -> PResult<Vec<Field>> {
        let mut out = Vec::new();
        if self.is_punct(")") {
            return Ok(out);
        }
        loop {
            let name = self.ident("a field name")?;
            self.expect_punct(":")?;
            let sort = self.sort()?;
            let refinement = if self.eat_punct("{") {
                let e = self.expr()?;
                self.expect_punct("}")?;
                Some(e)
            } else {
                None
            };
            out.push(Field { name, sort, refinement });
            if !self.eat_punct(",") {
                return Ok(out);
            }
        }
    }

    fn rec_params(&mut self) -> PResult<Vec<RecParam>> {
        let mut out = Vec::new();
        if !self.eat_punct("(") {
            return Ok(out);
        }
        loop {
            let name = self.ident("a recursion parameter")?;
            self.expect_punct(":")?;
            let sort = self.sort()?;
            let refinement = if self.eat_punct("{") {
                let e = self.expr()?;
                self.expect_punct("}")?;
                Some(e)
            } else {
                None
            };
            self.expect_punct("=")?;
            let init = self.expr()?;
            out.push(RecParam { name, sort, refinement, init });
            if !self.eat_punct(",") {
                break;
            }
        }
        self.expect_punct(")")?;
        Ok(out)
    }

    fn prim_call(&mut self) -> PResult<PrimCall> {
        let name = self.ident("a motion primitive")?;
        let mut args = Vec::new();
        if self.eat_punct("(") {
            args = self.expr_list(")")?;
            self.expect_punct(")")?;
        }
        Ok(PrimCall { span: name.span.to(self.prev_span()), name, args })
    }

    /// Optional `(e, ...)` after a name.
    fn opt_args(&mut self) -> PResult<Vec<Expr>> {
        if self.eat_punct("(") {
            let args = self.expr_list(")")?;
            self.expect_punct(")")?;
            Ok(args)
        } else {
            Ok(Vec::new())
        }
    }

    // ---- global types (Def 4.1) ----------------------------------------------------

    fn global(&mut self) -> PResult<Global> {
        self.nested(Parser::global_choice)
    }

    fn global_choice(&mut self) -> PResult<Global> {
        self.global_nary("+", Parser::global_par, Global::Choice)
    }

    fn global_par(&mut self) -> PResult<Global> {
        let g = self.global_nary("*", Parser::global_seq, Global::Par)?;
        if let (Global::Par(_, par), true) = (&g, self.is_kw("partition")) {
            let par = *par;
            let start = self.bump().span;
            self.expect_punct("(")?;
            let a = self.ident("a coordinate name")?;
            self.expect_punct(",")?;
            let b = self.ident("a coordinate name")?;
            self.expect_punct(",")?;
            let c = self.ident("a coordinate name")?;
            self.expect_punct(")")?;
            self.expect_punct("{")?;
            let mut regions = vec![self.expr()?];
            while self.eat_punct(";") {
                if self.is_punct("}") {
                    break;
                }
                regions.push(self.expr()?);
            }
            self.expect_punct("}")?;
            let span = start.to(self.prev_span());
            if let Global::Par(sides, _) = &g {
                if sides.len() != regions.len() {
                    self.diags.push(
                        Diagnostic::error(
                            Code::ArityMismatch,
                            span,
                            format!(
                                "this partition has {} region(s), the `*` before it has {} sides",
                                regions.len(),
                                sides.len()
                            ),
                        )
                        .with_label(par, "the sides")
                        .with_help("write one region per side, in the order of the sides, separated by `;`"),
                    );
                }
            }
            self.partitions.push(PartitionDecl { par, point: [a, b, c], regions, span });
        }
        Ok(g)
    }

    fn global_seq(&mut self) -> PResult<Global> {
        self.global_nary(".", Parser::global_atom, Global::Seq)
    }

    /// `operand (op operand)*`, flattened into one n-ary node when `op` occurs.
    fn global_nary(
        &mut self,
        op: &str,
        operand: fn(&mut Parser) -> PResult<Global>,
        node: fn(Vec<Global>, Span) -> Global,
    ) -> PResult<Global> {
        let first = operand(self)?;
        if !self.is_punct(op) {
            return Ok(first);
        }
        let mut parts = vec![first];
        while self.eat_punct(op) {
            parts.push(operand(self)?);
        }
        let span = parts[0].span().to(self.prev_span());
        Ok(node(parts, span))
    }

    fn global_atom(&mut self) -> PResult<Global> {
        let start = self.span();
        if self.eat_punct("(") {
            let g = self.global()?;
            self.expect_punct(")")?;
            return Ok(g);
        }
        if self.eat_kw("dt") {
            self.expect_punct("<")?;
            let mut parts = Vec::new();
            loop {
                let who = self.ident("a participant")?;
                self.expect_punct(":")?;
                let call = self.prim_call()?;
                parts.push((who, call));
                if !self.eat_punct(",") {
                    break;
                }
            }
            self.expect_punct(">")?;
            return Ok(Global::Motion { parts, span: start.to(self.prev_span()) });
        }
        if self.eat_kw("mu") {
            let var = self.ident("a recursion variable")?;
            let params = self.rec_params()?;
            self.expect_punct(".")?;
            let body = self.global()?;
            return Ok(Global::Rec { var, params, body: Box::new(body), span: start.to(self.prev_span()) });
        }
        if self.eat_kw("end") {
            return Ok(Global::End(start));
        }
        let from = self.ident("a message `p -> q : l`, a motion `dt<...>`, `mu`, `end` or `(`")?;
        if !self.eat_punct("->") {
            let args = self.opt_args()?;
            return Ok(Global::Var { var: from, args, span: start.to(self.prev_span()) });
        }
        let to = self.ident("the receiving participant")?;
        self.expect_punct(":")?;
        let guard = if self.eat_punct("[") {
            let g = self.expr()?;
            self.expect_punct("]")?;
            Some(g)
        } else {
            None
        };
        let label = self.ident("a message label")?;
        let payload = if self.eat_punct("(") {
            let f = self.fields()?;
            self.expect_punct(")")?;
            f
        } else {
            Vec::new()
        };
        Ok(Global::Msg(Msg { from, to, guard, label, payload, span: start.to(self.prev_span()) }))
    }

    // ---- local types (Def 4.6) -----------------------------------------------------

    fn local(&mut self) -> PResult<Local> {
        self.nested(Parser::local_inner)
    }

    /// A sequence of prefixes `dt<a>.`, `q!l.`, `p?l.` ending in another local type, read
    /// in a loop like [`Parser::process_prefix`] (a sequence is not nesting).
    fn local_inner(&mut self) -> PResult<Local> {
        let mut heads: Vec<Local> = Vec::new();
        let last = loop {
            let start = self.span();
            if self.eat_kw("dt") {
                let prims = self.local_prims()?;
                self.expect_punct(".")?;
                let cont = Box::new(Local::End(start));
                heads.push(Local::Motion { prims, cont, span: start.to(self.prev_span()) });
                continue;
            }
            let single = !(self.is_punct("+") || self.is_punct("&") || self.is_punct("("));
            if single && (self.is_punct("[") || matches!(self.peek_at(1), Tok::Punct("!"))) {
                let b = self.local_send_head()?;
                heads.push(Local::Send { branches: vec![b], span: start.to(self.prev_span()) });
                continue;
            }
            if single && matches!(self.peek_at(1), Tok::Punct("?")) {
                let b = self.local_recv_head()?;
                heads.push(Local::Recv { branches: vec![b], default: None, span: start.to(self.prev_span()) });
                continue;
            }
            break self.local_atom()?;
        };
        // Each prefix's span runs to the end of the whole sequence, as a recursive parse gives.
        let end = self.prev_span();
        let mut acc = last;
        while let Some(mut head) = heads.pop() {
            match &mut head {
                Local::Motion { cont, span, .. } => {
                    **cont = acc;
                    *span = span.to(end);
                }
                Local::Send { branches, span } => {
                    if let Some(b) = branches.first_mut() {
                        b.cont = acc;
                    }
                    *span = span.to(end);
                }
                Local::Recv { branches, span, .. } => {
                    if let Some(b) = branches.first_mut() {
                        b.cont = acc;
                    }
                    *span = span.to(end);
                }
                _ => {}
            }
            acc = head;
        }
        Ok(acc)
    }

    fn local_atom(&mut self) -> PResult<Local> {
        let start = self.span();
        if self.eat_punct("(") {
            let t = self.local()?;
            self.expect_punct(")")?;
            return Ok(t);
        }
        if self.is_punct("+") && matches!(self.peek_at(1), Tok::Punct("{")) {
            self.bump();
            self.bump();
            let mut branches = vec![self.local_send()?];
            while self.eat_punct(",") {
                branches.push(self.local_send()?);
            }
            self.expect_punct("}")?;
            return Ok(Local::Send { branches, span: start.to(self.prev_span()) });
        }
        if self.is_punct("&") && matches!(self.peek_at(1), Tok::Punct("{")) {
            self.bump();
            self.bump();
            let mut branches = vec![self.local_recv()?];
            while self.eat_punct(",") {
                branches.push(self.local_recv()?);
            }
            self.expect_punct("}")?;
            let mut default = None;
            if self.eat_punct("&") {
                self.expect_kw("dt")?;
                let prims = self.local_prims()?;
                self.expect_punct(".")?;
                let cont = self.local()?;
                default = Some((prims, Box::new(cont)));
            }
            return Ok(Local::Recv { branches, default, span: start.to(self.prev_span()) });
        }
        if self.eat_kw("mu") {
            let var = self.ident("a recursion variable")?;
            let params = self.rec_params()?;
            self.expect_punct(".")?;
            let body = self.local()?;
            return Ok(Local::Rec { var, params, body: Box::new(body), span: start.to(self.prev_span()) });
        }
        if self.eat_kw("end") {
            return Ok(Local::End(start));
        }
        let var =
            self.ident("a local type (`dt<a>.T`, `q!l.T`, `p?l.T`, `+{...}`, `&{...}`, `mu t.T`, `t` or `end`)")?;
        let args = self.opt_args()?;
        Ok(Local::Var { var, args, span: start.to(self.prev_span()) })
    }

    fn local_prims(&mut self) -> PResult<Vec<PrimCall>> {
        self.expect_punct("<")?;
        let mut prims = vec![self.prim_call()?];
        while self.eat_punct("/\\") {
            prims.push(self.prim_call()?);
        }
        self.expect_punct(">")?;
        Ok(prims)
    }

    fn local_send(&mut self) -> PResult<LocalSend> {
        let mut b = self.local_send_head()?;
        b.cont = self.local()?;
        Ok(b)
    }

    /// `[g] q!l(fields).` with an `end` placeholder for the continuation.
    fn local_send_head(&mut self) -> PResult<LocalSend> {
        let start = self.span();
        let guard = if self.eat_punct("[") {
            let g = self.expr()?;
            self.expect_punct("]")?;
            Some(g)
        } else {
            None
        };
        let to = self.ident("a receiving participant")?;
        self.expect_punct("!")?;
        let label = self.ident("a message label")?;
        let payload = if self.eat_punct("(") {
            let f = self.fields()?;
            self.expect_punct(")")?;
            f
        } else {
            Vec::new()
        };
        let span = start.to(self.prev_span());
        self.expect_punct(".")?;
        Ok(LocalSend { guard, to, label, payload, cont: Local::End(span), span })
    }

    fn local_recv(&mut self) -> PResult<LocalRecv> {
        let mut b = self.local_recv_head()?;
        b.cont = self.local()?;
        Ok(b)
    }

    /// `p?l(fields).` with an `end` placeholder for the continuation.
    fn local_recv_head(&mut self) -> PResult<LocalRecv> {
        let start = self.span();
        let from = self.ident("a sending participant")?;
        self.expect_punct("?")?;
        let label = self.ident("a message label")?;
        let payload = if self.eat_punct("(") {
            let f = self.fields()?;
            self.expect_punct(")")?;
            f
        } else {
            Vec::new()
        };
        let span = start.to(self.prev_span());
        self.expect_punct(".")?;
        Ok(LocalRecv { from, label, payload, cont: Local::End(span), span })
    }

    // ---- processes (Sec 3.1) -------------------------------------------------------

    fn process(&mut self) -> PResult<Process> {
        self.nested(Parser::process_sum)
    }

    fn process_sum(&mut self) -> PResult<Process> {
        let first = self.process_prefix()?;
        if !self.is_punct("+") {
            return Ok(first);
        }
        let mut parts = vec![first];
        while self.eat_punct("+") {
            parts.push(self.process_prefix()?);
        }
        let span = parts[0].span().to(self.prev_span());
        Ok(Process::Sum(parts, span))
    }

    /// A sequence of prefixes `a.b.c. ... .P` (the continuation of a prefix is another
    /// prefix: parenthesise sums). Read in a loop, not by recursion: a sequence is not
    /// nesting, and a process of 100,000 steps must parse. The tree is built from the end.
    fn process_prefix(&mut self) -> PResult<Process> {
        let mut heads: Vec<Process> = Vec::new();
        let last = loop {
            let start = self.span();
            let placeholder = || Box::new(Process::End(start));
            if self.eat_kw("dt") {
                self.expect_punct("<")?;
                let prim = self.prim_call()?;
                self.expect_punct(">")?;
                let span = start.to(self.prev_span());
                self.expect_punct(".")?;
                heads.push(Process::Motion { prim, cont: placeholder(), span });
                continue;
            }
            let is_comm = matches!(self.peek(), Tok::Ident(s) if !RESERVED.contains(&s.as_str()))
                && matches!(self.peek_at(1), Tok::Punct("!" | "?"));
            if !is_comm {
                break self.process_atom()?;
            }
            let who = self.ident("a participant")?;
            if self.eat_punct("!") {
                let label = self.ident("a message label")?;
                let args = self.opt_args()?;
                let span = start.to(self.prev_span());
                self.expect_punct(".")?;
                heads.push(Process::Send { to: who, label, args, cont: placeholder(), span });
            } else {
                self.expect_punct("?")?;
                let label = self.ident("a message label")?;
                let mut binders = Vec::new();
                if self.eat_punct("(") {
                    if !self.is_punct(")") {
                        loop {
                            binders.push(self.ident("a variable to bind the received value")?);
                            if !self.eat_punct(",") {
                                break;
                            }
                        }
                    }
                    self.expect_punct(")")?;
                }
                let span = start.to(self.prev_span());
                self.expect_punct(".")?;
                heads.push(Process::Recv { from: who, label, binders, cont: placeholder(), span });
            }
        };
        let mut acc = last;
        while let Some(mut head) = heads.pop() {
            if let Process::Motion { cont, .. } | Process::Send { cont, .. } | Process::Recv { cont, .. } = &mut head {
                **cont = acc;
            }
            acc = head;
        }
        Ok(acc)
    }

    /// A process that is not a prefix: `( P )`, `if`, `mu`, `end` or a variable.
    fn process_atom(&mut self) -> PResult<Process> {
        let start = self.span();
        if self.eat_punct("(") {
            let p = self.process()?;
            self.expect_punct(")")?;
            return Ok(p);
        }
        if self.eat_kw("if") {
            let cond = self.expr()?;
            self.expect_kw("then")?;
            let then = self.nested(Parser::process_prefix)?;
            self.expect_kw("else")?;
            let els = self.nested(Parser::process_prefix)?;
            return Ok(Process::If {
                cond,
                then: Box::new(then),
                els: Box::new(els),
                span: start.to(self.prev_span()),
            });
        }
        if self.eat_kw("mu") {
            let var = self.ident("a process variable")?;
            let params = self.rec_params()?;
            self.expect_punct(".")?;
            let body = self.process()?;
            return Ok(Process::Rec { var, params, body: Box::new(body), span: start.to(self.prev_span()) });
        }
        if self.eat_kw("end") {
            return Ok(Process::End(start));
        }
        let var = self.ident("a process (`q!l(e).P`, `p?l(x).P`, `dt<a>.P`, `if`, `mu x.P`, `x` or `end`)")?;
        let args = self.opt_args()?;
        Ok(Process::Var { var, args, span: start.to(self.prev_span()) })
    }

    // ---- expressions ---------------------------------------------------------------

    fn expr_list(&mut self, end: &str) -> PResult<Vec<Expr>> {
        let mut out = Vec::new();
        if self.is_punct(end) {
            return Ok(out);
        }
        loop {
            out.push(self.expr()?);
            if !self.eat_punct(",") {
                return Ok(out);
            }
        }
    }

    fn expr(&mut self) -> PResult<Expr> {
        self.nested(|p| p.expr_bp(1))
    }

    fn peek_binop(&self) -> Option<BinOp> {
        Some(match self.peek() {
            Tok::Punct("=>") => BinOp::Implies,
            Tok::Punct("||") => BinOp::Or,
            Tok::Punct("&&") => BinOp::And,
            Tok::Punct("==") => BinOp::Eq,
            Tok::Punct("!=") => BinOp::Ne,
            Tok::Punct("<") => BinOp::Lt,
            Tok::Punct("<=") => BinOp::Le,
            Tok::Punct(">") => BinOp::Gt,
            Tok::Punct(">=") => BinOp::Ge,
            Tok::Punct("+") => BinOp::Add,
            Tok::Punct("-") => BinOp::Sub,
            Tok::Punct("*") => BinOp::Mul,
            Tok::Punct("/") => BinOp::Div,
            Tok::Punct("^") => BinOp::Pow,
            _ => return None,
        })
    }

    /// Precedence climbing. `=>` and `^` associate to the right; comparison chains
    /// `a <= x <= b` mean `a <= x && x <= b`, as written in the paper.
    ///
    /// Every operator applied is a level of nesting (the tree `((a + b) + c) + ...` is as
    /// deep as it is long, and later stages recurse over it), so a chain of operators
    /// counts towards [`MAX_DEPTH`] like parentheses do. A chain is left-nested, so any
    /// length of comparisons `a < b < c < d` is the conjunction of its neighbours; a
    /// parenthesised comparison `(a < b) == c` starts no chain.
    fn expr_bp(&mut self, min: u8) -> PResult<Expr> {
        let mut lhs = self.expr_unary()?;
        let mut levels = 0;
        // The right operand of the last comparison of this chain, if the last operator was one.
        let mut chain: Option<Expr> = None;
        let res = loop {
            let Some(op) = self.peek_binop() else { break Ok(lhs) };
            let prec = op.precedence();
            if prec < min {
                break Ok(lhs);
            }
            if self.enter().is_err() {
                break Err(());
            }
            levels += 1;
            self.bump();
            let right_assoc = matches!(op, BinOp::Implies | BinOp::Pow);
            let rhs = match stacker::maybe_grow(STACK_RED_ZONE, STACK_GROWTH, || {
                self.expr_bp(if right_assoc { prec } else { prec + 1 })
            }) {
                Ok(rhs) => rhs,
                Err(()) => break Err(()),
            };
            let span = lhs.span.to(rhs.span);
            let next_chain = op.is_comparison().then(|| rhs.clone());
            lhs = match chain.take() {
                Some(mid) if op.is_comparison() => {
                    let right =
                        Expr { span: mid.span.to(rhs.span), kind: ExprKind::Binary(op, Box::new(mid), Box::new(rhs)) };
                    Expr { kind: ExprKind::Binary(BinOp::And, Box::new(lhs), Box::new(right)), span }
                }
                _ => Expr { kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)), span },
            };
            chain = next_chain;
        };
        for _ in 0..levels {
            self.leave();
        }
        res
    }

    fn expr_unary(&mut self) -> PResult<Expr> {
        let start = self.span();
        let op = if self.is_punct("-") {
            Some(UnOp::Neg)
        } else if self.is_punct("!") {
            Some(UnOp::Not)
        } else {
            None
        };
        if let Some(op) = op {
            self.bump();
            // `-x^2` is `-(x^2)`; `!a && b` is `(!a) && b`.
            let inner =
                self.nested(|p| if op == UnOp::Neg { p.expr_bp(BinOp::Pow.precedence()) } else { p.expr_unary() })?;
            return Ok(Expr { span: start.to(inner.span), kind: ExprKind::Unary(op, Box::new(inner)) });
        }
        let mut e = self.expr_atom()?;
        // `a.b.c` is a tree as deep as the chain is long: each `.` is a level.
        let mut levels = 0;
        let mut res = Ok(());
        while self.is_punct(".") && matches!(self.peek_at(1), Tok::Ident(_)) {
            res = self.enter();
            if res.is_err() {
                break;
            }
            levels += 1;
            self.bump();
            match self.ident("a field name") {
                Ok(field) => e = Expr { span: e.span.to(field.span), kind: ExprKind::Dot(Box::new(e), field) },
                Err(()) => {
                    res = Err(());
                    break;
                }
            }
        }
        for _ in 0..levels {
            self.leave();
        }
        res.map(|()| e)
    }

    fn expr_atom(&mut self) -> PResult<Expr> {
        let start = self.span();
        match self.peek().clone() {
            Tok::Int(i) => {
                self.bump();
                Ok(Expr { kind: ExprKind::Int(i), span: start })
            }
            Tok::Real(r) => {
                self.bump();
                Ok(Expr { kind: ExprKind::Real(r), span: start })
            }
            Tok::Punct("(") => {
                self.bump();
                let mut items = vec![self.expr()?];
                while self.eat_punct(",") {
                    items.push(self.expr()?);
                }
                self.expect_punct(")")?;
                let span = start.to(self.prev_span());
                if items.len() == 1 {
                    let mut e = items.pop().ok_or(())?;
                    e.span = span;
                    Ok(e)
                } else {
                    Ok(Expr { kind: ExprKind::Tuple(items), span })
                }
            }
            Tok::Ident(k) if k == "true" || k == "false" => {
                self.bump();
                Ok(Expr { kind: ExprKind::Bool(k == "true"), span: start })
            }
            Tok::Ident(k) if k == "pi" => {
                let span = self.bump().span;
                Ok(Expr { kind: ExprKind::Call(Ident { name: k, span }, Vec::new()), span: start })
            }
            Tok::Ident(k) if k == "if" => {
                self.bump();
                let c = self.expr()?;
                self.expect_kw("then")?;
                let a = self.expr()?;
                self.expect_kw("else")?;
                let b = self.expr()?;
                Ok(Expr { span: start.to(b.span), kind: ExprKind::If(Box::new(c), Box::new(a), Box::new(b)) })
            }
            Tok::Ident(_) => {
                let name = self.ident("an expression")?;
                if self.eat_punct("(") {
                    let args = self.expr_list(")")?;
                    self.expect_punct(")")?;
                    Ok(Expr { span: start.to(self.prev_span()), kind: ExprKind::Call(name, args) })
                } else {
                    Ok(Expr { kind: ExprKind::Var(name.name), span: start })
                }
            }
            _ => self.error_expected("an expression"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn global(src: &str) -> Global {
        let (g, d) = parse_global(FileId(0), src);
        assert!(d.is_empty(), "{d:?}");
        g.expect("parses")
    }

    #[test]
    fn sequence_binds_tighter_than_star_and_choice() {
        let g = global("p -> q : a. dt<p: m> * dt<r: n> + p -> q : b. t");
        let Global::Choice(branches, _) = g else { panic!("expected a choice") };
        assert_eq!(branches.len(), 2);
        let Global::Par(sides, _) = &branches[0] else { panic!("expected `*` in the first branch") };
        assert!(matches!(&sides[0], Global::Seq(items, _) if items.len() == 2));
    }

    #[test]
    fn mu_extends_to_the_right() {
        let g = global("mu t. p -> q : a. t");
        let Global::Rec { body, .. } = g else { panic!("expected mu") };
        assert!(matches!(*body, Global::Seq(ref v, _) if v.len() == 2));
    }

    #[test]
    fn message_with_guard_and_refined_payload() {
        let g = global("Cart -> Arm : [x > 0] arrive(t: real { t >= 1.5 }, y: int)");
        let Global::Msg(m) = g else { panic!("expected a message") };
        assert!(m.guard.is_some());
        assert_eq!(m.payload.len(), 2);
        assert!(m.payload[0].refinement.is_some());
    }

    #[test]
    fn comparison_chains_are_conjunctions() {
        let (e, d) = parse_expr(FileId(0), "a <= x <= b");
        assert!(d.is_empty());
        assert!(matches!(e.unwrap().kind, ExprKind::Binary(BinOp::And, _, _)));
    }

    #[test]
    fn comparison_chains_of_any_length_are_conjunctions_of_neighbours() {
        let (e, d) = parse_expr(FileId(0), "1 < 2 < 3 < 4");
        assert!(d.is_empty(), "{d:?}");
        // ((1 < 2 && 2 < 3) && 3 < 4)
        let ExprKind::Binary(BinOp::And, l, r) = e.unwrap().kind else { panic!("expected &&") };
        assert!(matches!(l.kind, ExprKind::Binary(BinOp::And, _, _)));
        let ExprKind::Binary(BinOp::Lt, a, b) = r.kind else { panic!("expected 3 < 4") };
        assert!(matches!((a.kind, b.kind), (ExprKind::Int(3), ExprKind::Int(4))));
        // A parenthesised comparison is an operand, not the start of a chain.
        let (e, _) = parse_expr(FileId(0), "(x < y) == b");
        assert!(matches!(e.unwrap().kind, ExprKind::Binary(BinOp::Eq, _, _)));
    }

    #[test]
    fn operator_chains_count_as_nesting() {
        for src in [format!("{}1", "2 ^ ".repeat(10_000)), format!("1{}", " + 1".repeat(10_000))] {
            let (_, d) = parse_expr(FileId(0), &src);
            assert_eq!(d.len(), 1, "{d:?}");
            assert_eq!(d[0].code, Code::TooDeep);
        }
        let (_, d) = parse_expr(FileId(0), &format!("1{}", " + 1".repeat(900)));
        assert!(d.is_empty(), "{d:?}");
    }

    #[test]
    fn sorts_and_field_chains_count_as_nesting() {
        // Before: a sort nested a million deep overflowed the stack (a crash, not an error).
        on_big_stack(|| {
            let deep_sort = format!("const a: {}int{} = 1;", "(".repeat(1_000_000), ")".repeat(1_000_000));
            let dots = format!("const a = x{};", ".y".repeat(100_000));
            for src in [deep_sort, dots] {
                let (_, d) = parse(FileId(0), &src);
                assert_eq!(d.len(), 1, "{d:?}");
                assert_eq!(d[0].code, Code::TooDeep);
            }
        });
    }

    #[test]
    fn process_sum_of_inputs_with_default_motion() {
        let (f, d) = parse(FileId(0), "process A = p?a(x).dt<m>.X + p?b.end + dt<idle>.X;");
        assert!(d.is_empty(), "{d:?}");
        let Item::Process(p) = &f.items[0] else { panic!() };
        assert!(matches!(&p.body, Process::Sum(v, _) if v.len() == 3));
    }

    #[test]
    fn local_types_parse() {
        let (t, d) = parse_local(FileId(0), "mu t. +{ [x > 0] B!a(v: real).dt<m /\\ n>.t, B!b.end }");
        assert!(d.is_empty(), "{d:?}");
        assert!(matches!(t, Some(Local::Rec { .. })));
        let (t, d) = parse_local(FileId(0), "&{ A?a.t, A?b.end } & dt<idle>.t");
        assert!(d.is_empty(), "{d:?}");
        assert!(matches!(t, Some(Local::Recv { default: Some(_), .. })));
    }

    /// Runs `f` on a thread with a large stack: dropping (and later stages walking) a
    /// 100,000-step process recurses once per step, beyond a test thread's 2 MiB.
    fn on_big_stack(f: impl FnOnce() + Send + 'static) {
        std::thread::Builder::new().stack_size(256 << 20).spawn(f).expect("thread").join().expect("no panic");
    }

    #[test]
    fn long_sequences_are_not_nesting() {
        on_big_stack(|| {
            let n = 100_000;
            let src = format!(
                "choreography C = {}end;\nprocess A = {}end;\nlocal A = {}end;\nlocal B = {}end;",
                "A -> B : m.\n".repeat(n),
                "dt<w>.B!m(1).B?r(x).".repeat(n / 2),
                "dt<w>.B!m.".repeat(n / 2),
                "A?m(x: real).".repeat(n)
            );
            let (f, d) = parse(FileId(0), &src);
            assert!(d.is_empty(), "{:?}", &d[..d.len().min(3)]);
            let Item::Process(p) = &f.items[1] else { panic!("a process") };
            let (mut steps, mut cur) = (0, &p.body);
            while let Process::Motion { cont, .. } | Process::Send { cont, .. } | Process::Recv { cont, .. } = cur {
                steps += 1;
                cur = cont;
            }
            assert_eq!(steps, 3 * n / 2);
            assert!(matches!(cur, Process::End(_)));
            let Item::Local(l) = &f.items[2] else { panic!("a local type") };
            let Local::Motion { span, .. } = &l.body else { panic!("a motion") };
            assert_eq!(span.end, l.span.end - 1, "the span covers the sequence up to its `end`");
        });
    }

    #[test]
    fn errors_recover_at_the_next_item() {
        let (f, d) = parse(FileId(0), "const a = ;\nconst b = 2;\nrobot R { state x: real; bogus; }\nconst c = 3;");
        assert_eq!(f.items.len(), 3, "{:?}", f.items);
        assert_eq!(d.len(), 2, "{d:?}");
        assert!(d.iter().all(|d| d.code == Code::UnexpectedToken));
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let src = format!("const a = {}1{};", "(".repeat(5000), ")".repeat(5000));
        let (_, d) = parse(FileId(0), &src);
        assert!(d.iter().any(|d| d.message.contains("nesting deeper") && d.code == Code::TooDeep));
    }
}
