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
}
