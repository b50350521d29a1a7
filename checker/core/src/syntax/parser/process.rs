//! Processes (LANGUAGE.md, Processes; Sec 3.1): prefixes `q!l(e)`, `q?l(x)` and
//! `dt<a>` read in a loop (a sequence is not nesting), sums `P + Q` (looser than the
//! prefixes, so `p?a.P + p?b.Q` is a sum of two inputs), conditionals, `mu` and `end`.

use super::*;

impl Parser {
    pub(super) fn process(&mut self) -> PResult<Process> {
        self.nested(Parser::process_sum)
    }

    pub(super) fn process_sum(&mut self) -> PResult<Process> {
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
    pub(super) fn process_prefix(&mut self) -> PResult<Process> {
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
                let label = self.label()?;
                let args = self.opt_args()?;
                let span = start.to(self.prev_span());
                self.expect_punct(".")?;
                heads.push(Process::Send { to: who, label, args, cont: placeholder(), span });
            } else {
                self.expect_punct("?")?;
                let label = self.label()?;
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
    pub(super) fn process_atom(&mut self) -> PResult<Process> {
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
}
