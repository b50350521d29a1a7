//! Local types (LANGUAGE.md, Local types; Def 4.6): motions `dt<a /\ b>.T`, internal
//! choices `+{ ... }` of sends `[P] q!l(x: S {P}).T`, external choices `&{ ... }` of
//! receives with an optional default motion `& dt<a>.T`, `mu` and `end`.

use super::*;

impl Parser {
    pub(super) fn local(&mut self) -> PResult<Local> {
        self.nested(Parser::local_inner)
    }

    /// A sequence of prefixes `dt<a>.`, `q!l.`, `p?l.` ending in another local type, read
    /// in a loop like [`Parser::process_prefix`] (a sequence is not nesting).
    pub(super) fn local_inner(&mut self) -> PResult<Local> {
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
                heads.push(Local::Send { branches: vec![b], timeout: None, span: start.to(self.prev_span()) });
                continue;
            }
            if single && matches!(self.peek_at(1), Tok::Punct("?")) {
                let b = self.local_recv_head()?;
                heads.push(Local::Recv {
                    branches: vec![b],
                    default: None,
                    timeout: None,
                    span: start.to(self.prev_span()),
                });
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
                Local::Send { branches, span, .. } => {
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

    pub(super) fn local_atom(&mut self) -> PResult<Local> {
        let start = self.span();
        if self.eat_punct("(") {
            let t = self.local()?;
            self.expect_punct(")")?;
            return Ok(t);
        }
        if self.is_punct("+") && matches!(self.peek_at(1), Tok::Punct("{")) {
            self.bump();
            self.bump();
            let mut branches = Vec::new();
            let mut timeout = None;
            loop {
                if !self.timeout_alternative(&mut timeout, true)? {
                    branches.push(self.local_send()?);
                }
                if !self.eat_punct(",") {
                    break;
                }
            }
            self.expect_punct("}")?;
            return Ok(Local::Send { branches, timeout, span: start.to(self.prev_span()) });
        }
        if self.is_punct("&") && matches!(self.peek_at(1), Tok::Punct("{")) {
            self.bump();
            self.bump();
            let mut branches = Vec::new();
            let mut timeout = None;
            loop {
                if !self.timeout_alternative(&mut timeout, false)? {
                    branches.push(self.local_recv()?);
                }
                if !self.eat_punct(",") {
                    break;
                }
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
            return Ok(Local::Recv { branches, default, timeout, span: start.to(self.prev_span()) });
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
        if self.is_kw("after") && self.timeout_follows() {
            return self.error_expected(
                "a local type: a timeout alternative is written inside a choice, `&{ p?l.T, after N ms. T' }` or `+{ q!l.T, after N ms by q. T' }`",
            );
        }
        let var =
            self.ident("a local type (`dt<a>.T`, `q!l.T`, `p?l.T`, `+{...}`, `&{...}`, `mu t.T`, `t` or `end`)")?;
        let args = self.opt_args()?;
        Ok(Local::Var { var, args, span: start.to(self.prev_span()) })
    }

    /// The timeout alternative of a local choice, if the cursor is at one: `after T ms. T'`
    /// in an external choice (`by_peer` false: the role itself waits), `after T ms by R. T'`
    /// in an internal choice (the peer `R` waits). At most one per choice. Returns whether
    /// one was read.
    fn timeout_alternative(&mut self, slot: &mut Option<Box<LocalTimeout>>, by_peer: bool) -> PResult<bool> {
        if !(self.is_kw("after") && self.timeout_follows()) {
            return Ok(false);
        }
        if slot.is_some() {
            return self.error_expected("a branch: a choice has at most one timeout alternative `after N ms`");
        }
        let start = self.span();
        self.bump();
        let bound = self.expr()?;
        if !self.eat_kw("ms") {
            return self.error_expected("`ms` after the bound of `after` (the bound is in milliseconds)");
        }
        let by = if by_peer {
            if !self.eat_kw("by") {
                return self.error_expected(
                    "`by R` after `after T ms`: in an internal choice the timeout is the waiting peer's",
                );
            }
            Some(self.ident("the participant that waits and takes the timeout branch")?)
        } else {
            None
        };
        let span = start.to(self.prev_span());
        self.expect_punct(".")?;
        let cont = self.local()?;
        *slot = Some(Box::new(LocalTimeout { bound, by, cont, span }));
        Ok(true)
    }

    pub(super) fn local_prims(&mut self) -> PResult<Vec<PrimCall>> {
        self.expect_punct("<")?;
        let mut prims = vec![self.prim_call()?];
        while self.eat_punct("/\\") {
            prims.push(self.prim_call()?);
        }
        self.expect_punct(">")?;
        Ok(prims)
    }

    pub(super) fn local_send(&mut self) -> PResult<LocalSend> {
        let mut b = self.local_send_head()?;
        b.cont = self.local()?;
        Ok(b)
    }

    /// `[g] q!l(fields).` with an `end` placeholder for the continuation.
    pub(super) fn local_send_head(&mut self) -> PResult<LocalSend> {
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
        let label = self.label()?;
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

    pub(super) fn local_recv(&mut self) -> PResult<LocalRecv> {
        let mut b = self.local_recv_head()?;
        b.cont = self.local()?;
        Ok(b)
    }

    /// `p?l(fields).` with an `end` placeholder for the continuation.
    pub(super) fn local_recv_head(&mut self) -> PResult<LocalRecv> {
        let start = self.span();
        let from = self.ident("a sending participant")?;
        self.expect_punct("?")?;
        let label = self.label()?;
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
}
