//! Expressions (LANGUAGE.md, Expressions) by precedence climbing. Each operator applied,
//! each unary prefix and each `.field` counts as a level of nesting towards
//! [`MAX_DEPTH`]; comparison chains `a <= x <= b` are conjunctions of neighbours.

use super::*;

impl Parser {
    pub(super) fn expr_list(&mut self, end: &str) -> PResult<Vec<Expr>> {
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

    pub(super) fn expr(&mut self) -> PResult<Expr> {
        self.nested(|p| p.expr_bp(1))
    }

    pub(super) fn peek_binop(&self) -> Option<BinOp> {
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
    pub(super) fn expr_bp(&mut self, min: u8) -> PResult<Expr> {
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
            let rhs = match crate::stack::deep(|| self.expr_bp(if right_assoc { prec } else { prec + 1 })) {
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

    pub(super) fn expr_unary(&mut self) -> PResult<Expr> {
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

    pub(super) fn expr_atom(&mut self) -> PResult<Expr> {
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
            Tok::Str(s) => {
                self.bump();
                Ok(Expr { kind: ExprKind::Str(s), span: start })
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
