//! Global types (LANGUAGE.md, Global types; Def 4.1). Precedence, loosest first: `+`
//! (choice), `*` (separation, optionally followed by its `partition`), `.` (sequence);
//! each is one n-ary node. `mu t.` extends as far right as possible.

use super::*;

impl Parser {
    pub(super) fn global(&mut self) -> PResult<Global> {
        self.nested(Parser::global_choice)
    }

    pub(super) fn global_choice(&mut self) -> PResult<Global> {
        self.global_nary("+", Parser::global_par, Global::Choice)
    }

    pub(super) fn global_par(&mut self) -> PResult<Global> {
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

    pub(super) fn global_seq(&mut self) -> PResult<Global> {
        self.global_nary(".", Parser::global_atom, Global::Seq)
    }

    /// `operand (op operand)*`, flattened into one n-ary node when `op` occurs.
    pub(super) fn global_nary(
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

    pub(super) fn global_atom(&mut self) -> PResult<Global> {
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
            let decreases = if self.eat_kw("decreases") { Some(self.measure()?) } else { None };
            self.expect_punct(".")?;
            let body = self.global()?;
            return Ok(Global::Rec { var, params, decreases, body: Box::new(body), span: start.to(self.prev_span()) });
        }
        if self.eat_kw("end") {
            return Ok(Global::End(start));
        }
        // `after` is a keyword only where a bound follows it (a number, a name that does
        // not start a message, or a bracketed expression followed by `ms`): elsewhere it
        // stays a name (`after -> q: l`, the jump `after(n)`).
        if self.is_kw("after") && self.timeout_follows() {
            self.bump();
            let bound = self.expr()?;
            if !self.eat_kw("ms") {
                return self.error_expected("`ms` after the bound of `after` (the bound is in milliseconds)");
            }
            if !self.eat_kw("by") {
                return self.error_expected("`by R` after `after T ms`, naming the waiting participant");
            }
            let by = self.ident("the participant that waits and takes the timeout branch")?;
            return Ok(Global::After { bound, by, span: start.to(self.prev_span()) });
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
        let label = self.label()?;
        let payload = if self.eat_punct("(") {
            let f = self.fields()?;
            self.expect_punct(")")?;
            f
        } else {
            Vec::new()
        };
        Ok(Global::Msg(Msg { from, to, guard, label, payload, span: start.to(self.prev_span()) }))
    }

    /// Whether the `after` at the cursor starts a timeout branch: a bound follows it, that
    /// is a number, a name, or a bracketed expression whose closing bracket is followed by
    /// `ms` (`after (2 * N) ms by R`; without `ms` it is the jump `after(n)`).
    pub(super) fn timeout_follows(&self) -> bool {
        match self.peek_at(1) {
            Tok::Int(_) | Tok::Real(_) | Tok::Ident(_) => true,
            Tok::Punct("(") => {
                let mut depth = 0usize;
                let mut k = 1;
                loop {
                    match self.peek_at(k) {
                        Tok::Punct("(") => depth += 1,
                        Tok::Punct(")") => {
                            depth -= 1;
                            if depth == 0 {
                                return matches!(self.peek_at(k + 1), Tok::Ident(s) if s == "ms");
                            }
                        }
                        Tok::Eof => return false,
                        _ => {}
                    }
                    k += 1;
                }
            }
            _ => false,
        }
    }

    /// The measure of `mu t(...) decreases E. G`. It ends at the first `.` outside
    /// brackets: a measure is an integer, which has no components, so `decreases n. p -> q`
    /// is the measure `n` and the body `p -> q`, not the component `n.p` (the expression
    /// grammar would read `.` followed by a name as a component).
    fn measure(&mut self) -> PResult<Expr> {
        let mut depth = 0i32;
        let mut end = None;
        for k in self.pos..self.toks.len() {
            match &self.toks[k].tok {
                Tok::Punct("(" | "[" | "{") => depth += 1,
                Tok::Punct(")" | "]" | "}") => {
                    depth -= 1;
                    if depth < 0 {
                        break;
                    }
                }
                Tok::Punct(".") if depth == 0 => {
                    end = Some(k);
                    break;
                }
                Tok::Punct(";") | Tok::Eof => break,
                _ => {}
            }
        }
        let Some(end) = end else { return self.expr() };
        // The `.` is hidden while the measure is read, so that it cannot continue it.
        let dot = std::mem::replace(&mut self.toks[end].tok, Tok::Punct(";"));
        let e = self.expr();
        self.toks[end].tok = dot;
        let e = e?;
        if self.pos != end {
            return self.error_expected("`.` after the measure of `decreases`");
        }
        Ok(e)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{parse_global, FileId};
    use crate::syntax::ast::{ExprKind, Global};

    fn rec(src: &str) -> (Option<crate::syntax::ast::Expr>, Global) {
        let (g, d) = parse_global(FileId(0), src);
        assert!(d.is_empty(), "{d:?}");
        let Some(Global::Rec { decreases, body, .. }) = g else { panic!("expected mu") };
        (decreases, *body)
    }

    /// `decreases n. p -> q` is the measure `n` and a body starting with `p -> q`, not the
    /// component `n.p` of the expression grammar.
    #[test]
    fn the_measure_ends_at_the_first_dot() {
        let (m, body) = rec("mu t(n: int = 3) decreases n. p -> q: a. t(n - 1)");
        assert!(matches!(m.map(|m| m.kind), Some(ExprKind::Var(..))), "the measure is `n`");
        assert!(matches!(body, Global::Seq(ref v, _) if v.len() == 2));
        let (m, _) = rec("mu t(i: int = 0) decreases (c - i) * 2. (p -> q: a. t(i + 1) + p -> q: b. end)");
        assert!(matches!(m.map(|m| m.kind), Some(ExprKind::Binary(..))));
        let (m, _) = rec("mu t. p -> q: a. t");
        assert!(m.is_none());
    }

    #[test]
    fn a_measure_not_followed_by_a_dot_is_an_error() {
        let (_, d) = parse_global(FileId(0), "mu t(n: int = 3) decreases n");
        assert!(!d.is_empty());
        let (_, d) = parse_global(FileId(0), "mu t(n: int = 3) decreases. p -> q: a. t(n)");
        assert!(!d.is_empty());
    }
}
