//! Printing the HIR in mochi's ASCII notation (LANGUAGE.md). What is printed parses back
//! to an equal term, so projections can be golden-tested and pasted into `local` items.
//! Participants' variables are always qualified (`Cart.x`). The end of the file has the
//! helpers diagnostics use to show local types: [`describe`] (the first action),
//! [`motion_text`], and [`print_bounded`] (whole types, summarised when too large).

use super::node::NodeRef;
use super::*;
use crate::syntax::ast::{BinOp, UnOp};
use std::collections::{HashMap, HashSet};
use std::fmt::Write;

/// Prints a local type over several lines, choices indented by two spaces.
///
/// Two passes: the first finds the binders that hide a value the type still reads (a
/// second `v` received before a guard on the first), the second prints those under fresh
/// names. A binder that hides nothing read is printed as written.
pub fn local(prog: &Program, t: &Local) -> String {
    let mut find = Printer { prog, prim: None, out: String::new(), indent: 0, scope: Vec::new(), rename: None };
    find.rename = Some(Rename { pass: Pass::Find, hiding: HashSet::new(), renamed: HashSet::new() });
    find.local(t);
    let hiding = find.rename.map(|r| r.hiding).unwrap_or_default();
    let mut p = Printer { prog, prim: None, out: String::new(), indent: 0, scope: Vec::new(), rename: None };
    p.rename = Some(Rename { pass: Pass::Print, hiding, renamed: HashSet::new() });
    p.local(t);
    p.out
}

/// Which pass of [`local`] a printer is in.
#[derive(Clone, Copy, PartialEq)]
enum Pass {
    /// Binders print as written; a read of a value hidden by a later binder of the same
    /// name marks that binder.
    Find,
    /// Marked binders, and binders whose name a renamed binder now takes, print fresh.
    Print,
}

/// The renaming state of [`local`]'s two passes.
struct Rename {
    pass: Pass,
    /// The binders that hide a value read in their scope.
    hiding: HashSet<ValueId>,
    /// The binders printed under a fresh name (second pass): a later binder written with
    /// that name must not capture it.
    renamed: HashSet<ValueId>,
}

/// Prints a global type on several lines, choices and separations indented.
pub fn global(prog: &Program, g: &Global) -> String {
    let mut p = Printer { prog, prim: None, out: String::new(), indent: 0, scope: Vec::new(), rename: None };
    p.global(g);
    p.out
}

/// Prints an expression; `prim` names the primitive whose parameters and kind variables
/// it may mention.
pub fn expr(prog: &Program, prim: Option<PrimId>, e: &Expr) -> String {
    let mut p = Printer { prog, prim, out: String::new(), indent: 0, scope: Vec::new(), rename: None };
    p.expr(e, 0);
    p.out
}

/// `a(args)`
pub fn prim_app(prog: &Program, a: &PrimApp) -> String {
    let mut p = Printer { prog, prim: None, out: String::new(), indent: 0, scope: Vec::new(), rename: None };
    p.prim_app(a);
    p.out
}

struct Printer<'a> {
    prog: &'a Program,
    prim: Option<PrimId>,
    out: String,
    indent: usize,
    /// The values bound on the way to what is being printed (a local type's message
    /// fields and recursion parameters), innermost last, each with the name it is printed
    /// as. A value's identity is its binding site, not its name (LANGUAGE.md, "Names and
    /// scopes"): when a binder's name is already in scope for another value, the binder is
    /// printed under a fresh name (`v_2`), so that what is printed reads back to the same
    /// type (a guard on the first `v` after a second `v` was received stays on the first).
    scope: Vec<(ValueId, String)>,
    /// `Some` while printing a whole local type ([`local`]): which binders to rename.
    /// Without it (expressions, global types) binders print as written.
    rename: Option<Rename>,
}

impl Printer<'_> {
    fn newline(&mut self) {
        self.out.push('\n');
        for _ in 0..self.indent {
            self.out.push(' ');
        }
    }

    fn local(&mut self, t: &Local) {
        crate::stack::deep(|| self.local_inner(t))
    }

    fn local_inner(&mut self, t: &Local) {
        match t {
            Local::Motion { prims, cont, .. } => {
                self.motion(prims);
                self.out.push('.');
                self.local(cont);
            }
            Local::Send { branches, timeout: None, .. } if branches.len() == 1 => self.send(&branches[0]),
            Local::Send { branches, timeout, .. } => {
                self.out.push_str("+{");
                self.indent += 2;
                for (i, b) in branches.iter().enumerate() {
                    if i > 0 {
                        self.out.push(',');
                    }
                    self.newline();
                    self.send(b);
                }
                if let Some(t) = timeout {
                    self.timeout(t, true, !branches.is_empty());
                }
                self.indent -= 2;
                self.newline();
                self.out.push('}');
            }
            Local::Recv { branches, default: None, timeout: None, .. } if branches.len() == 1 => {
                self.recv(&branches[0])
            }
            Local::Recv { branches, default, timeout, .. } => {
                self.out.push_str("&{");
                self.indent += 2;
                for (i, b) in branches.iter().enumerate() {
                    if i > 0 {
                        self.out.push(',');
                    }
                    self.newline();
                    self.recv(b);
                }
                if let Some(t) = timeout {
                    self.timeout(t, false, !branches.is_empty());
                }
                self.indent -= 2;
                self.newline();
                self.out.push('}');
                if let Some((prims, cont)) = default {
                    self.out.push_str(" & ");
                    self.motion(prims);
                    self.out.push('.');
                    self.local(cont);
                }
            }
            Local::Rec { var, params, body, .. } => {
                let _ = write!(self.out, "mu {var}");
                let outer = self.scope.len();
                self.rec_params(params);
                self.out.push_str(". ");
                self.local(body);
                self.scope.truncate(outer);
            }
            Local::Var { var, args, .. } => {
                self.out.push_str(var);
                self.args(args);
            }
            Local::End(_) => self.out.push_str("end"),
        }
    }

    fn send(&mut self, b: &SendBranch) {
        if let Some(g) = &b.guard {
            self.out.push('[');
            self.expr(g, 0);
            self.out.push_str("] ");
        }
        let _ = write!(self.out, "{}!{}", self.prog.role_name(b.to), b.label);
        let outer = self.scope.len();
        self.fields(&b.payload);
        self.out.push('.');
        self.local(&b.cont);
        self.scope.truncate(outer);
    }

    fn recv(&mut self, b: &RecvBranch) {
        let _ = write!(self.out, "{}?{}", self.prog.role_name(b.from), b.label);
        let outer = self.scope.len();
        self.fields(&b.payload);
        self.out.push('.');
        self.local(&b.cont);
        self.scope.truncate(outer);
    }

    /// Binds `value` (written `name`) for what follows and returns the name it is printed
    /// as: `name` itself unless another value of that name is in scope, then the first of
    /// `name_2`, `name_3`, ... that names neither a value in scope nor a constant.
    fn bind(&mut self, value: ValueId, name: &str) -> String {
        let taken = |n: &str, scope: &[(ValueId, String)]| {
            scope.iter().any(|(v, m)| m == n && *v != value) || self.prog.consts.iter().any(|c| c.name == n)
        };
        let fresh = match &self.rename {
            None | Some(Rename { pass: Pass::Find, .. }) => false,
            Some(Rename { hiding, renamed, .. }) => {
                hiding.contains(&value)
                    || self.scope.iter().any(|(v, m)| m == name && *v != value && renamed.contains(v))
            }
        };
        let printed = if fresh {
            (2..).map(|k| format!("{name}_{k}")).find(|n| !taken(n, &self.scope)).unwrap_or_default()
        } else {
            name.to_string()
        };
        if fresh {
            if let Some(r) = &mut self.rename {
                r.renamed.insert(value);
            }
        }
        self.scope.push((value, printed.clone()));
        printed
    }

    fn motion(&mut self, prims: &[PrimApp]) {
        self.out.push_str("dt<");
        for (i, a) in prims.iter().enumerate() {
            if i > 0 {
                self.out.push_str(" /\\ ");
            }
            self.prim_app(a);
        }
        self.out.push('>');
    }

    fn prim_app(&mut self, a: &PrimApp) {
        self.out.push_str(&self.prog.prim(a.prim).name);
        self.args(&a.args);
    }

    fn args(&mut self, args: &[Expr]) {
        if args.is_empty() {
            return;
        }
        self.out.push('(');
        for (i, e) in args.iter().enumerate() {
            if i > 0 {
                self.out.push_str(", ");
            }
            self.expr(e, 0);
        }
        self.out.push(')');
    }

    fn fields(&mut self, fields: &[Field]) {
        if fields.is_empty() {
            return;
        }
        self.out.push('(');
        for (i, f) in fields.iter().enumerate() {
            if i > 0 {
                self.out.push_str(", ");
            }
            let name = self.bind(f.value, &f.name);
            // A MAVLink field: `FIELD` or `FIELD as NAME`, and only the user's part of the
            // refinement (lowering adds the wire range again; `MavField`).
            let written = match &f.mav {
                Some(m) if m.written != name => format!("{} as {name}", m.written),
                _ => name,
            };
            let _ = write!(self.out, "{}: {}", written, f.sort);
            let user = match (&f.mav, &f.refinement) {
                (Some(m), Some(r)) if m.implicit => match &r.kind {
                    ExprKind::Binary(BinOp::And, _, u) if m.user => Some(&**u),
                    _ => None,
                },
                (_, r) => r.as_ref(),
            };
            if let Some(r) = user {
                self.out.push_str(" { ");
                self.expr(r, 0);
                self.out.push_str(" }");
            }
        }
        self.out.push(')');
    }

    fn rec_params(&mut self, params: &[RecParam]) {
        if params.is_empty() {
            return;
        }
        self.out.push('(');
        for (i, p) in params.iter().enumerate() {
            if i > 0 {
                self.out.push_str(", ");
            }
            let name = self.bind(p.value, &p.name);
            let _ = write!(self.out, "{}: {}", name, p.sort);
            if let Some(r) = &p.refinement {
                self.out.push_str(" { ");
                self.expr(r, 0);
                self.out.push_str(" }");
            }
            self.out.push_str(" = ");
            self.expr(&p.init, 0);
        }
        self.out.push(')');
    }

    fn global(&mut self, g: &Global) {
        crate::stack::deep(|| self.global_inner(g))
    }

    fn global_inner(&mut self, g: &Global) {
        match g {
            Global::Msg(m) => {
                let _ = write!(self.out, "{} -> {} : ", self.prog.role_name(m.from), self.prog.role_name(m.to));
                if let Some(gd) = &m.guard {
                    self.out.push('[');
                    self.expr(gd, 0);
                    self.out.push_str("] ");
                }
                self.out.push_str(&m.label);
                // A global type's binders are printed as written: their scopes follow the
                // sequence and `*` structure, which this printer does not track.
                let outer = self.scope.len();
                self.fields(&m.payload);
                self.scope.truncate(outer);
            }
            Global::Motion(m) => {
                self.out.push_str("dt<");
                for (i, (r, a)) in m.parts.iter().enumerate() {
                    if i > 0 {
                        self.out.push_str(", ");
                    }
                    let _ = write!(self.out, "{}: ", self.prog.role_name(*r));
                    self.prim_app(a);
                }
                self.out.push('>');
            }
            Global::Seq(gs, _) => {
                for (i, g) in gs.iter().enumerate() {
                    if i > 0 {
                        self.out.push_str(". ");
                    }
                    self.global_atom(g);
                }
            }
            Global::After(a) => {
                self.out.push_str("after ");
                self.expr(&a.bound, 0);
                let _ = write!(self.out, " ms by {}", self.prog.role_name(a.by));
            }
            Global::Choice(gs, _) | Global::Par(gs, _) => {
                let op = if matches!(g, Global::Choice(..)) { "+ " } else { "* " };
                self.out.push('(');
                self.indent += 2;
                for (i, g) in gs.iter().enumerate() {
                    self.newline();
                    if i > 0 {
                        self.out.push_str(op);
                    }
                    self.global_atom(g);
                }
                self.indent -= 2;
                self.newline();
                self.out.push(')');
            }
            Global::Rec { var, params, decreases, body, .. } => {
                let _ = write!(self.out, "mu {var}");
                let outer = self.scope.len();
                self.rec_params(params);
                if let Some(m) = decreases {
                    self.out.push_str(" decreases (");
                    self.expr(m, 0);
                    self.out.push(')');
                }
                self.scope.truncate(outer);
                self.out.push_str(". ");
                self.global(body);
            }
            Global::Var(v) => {
                self.out.push_str(&v.var);
                self.args(&v.args);
            }
            Global::End(_) => self.out.push_str("end"),
        }
    }

    /// A global type in a position where `.`, `*` or `+` would capture too much.
    fn global_atom(&mut self, g: &Global) {
        if matches!(g, Global::Seq(..) | Global::Rec { .. }) {
            self.out.push('(');
            self.global(g);
            self.out.push(')');
        } else {
            self.global(g);
        }
    }

    /// In the first pass of [`local`], a read of `id` marks the binders after its own in
    /// scope that print under the same name (they hide it).
    fn note_read(&mut self, id: ValueId) {
        let Some(Rename { pass: Pass::Find, hiding, .. }) = &mut self.rename else { return };
        let Some(at) = self.scope.iter().rposition(|(v, _)| *v == id) else { return };
        let name = &self.scope[at].1;
        for (v, n) in &self.scope[at + 1..] {
            if n == name && *v != id {
                hiding.insert(*v);
            }
        }
    }

    fn var_name(&self, v: &Var) -> String {
        let prim = self.prim.map(|p| self.prog.prim(p));
        let own = |slot: Slot| match prim {
            Some(pr) => self.prog.slot_name(pr.kind, slot).to_string(),
            None => "?".to_string(),
        };
        match v {
            Var::Const(c) => self.prog.consts[c.idx()].name.clone(),
            Var::Own(slot) => own(*slot),
            Var::Old(i) => format!("old({})", own(Slot::State(*i))),
            Var::Param(i) => prim.map(|p| p.params[*i].0.clone()).unwrap_or_else(|| format!("param{i}")),
            Var::Point(i) => match prim.and_then(|p| p.footprint.predicate()) {
                Some(fp) => fp.point[*i].clone(),
                None => ["px", "py", "pz"][*i].to_string(),
            },
            Var::Clock => "clock".to_string(),
            Var::Role(r, slot) => {
                let kind = self.prog.role(*r).kind;
                format!("{}.{}", self.prog.role_name(*r), self.prog.slot_name(kind, *slot))
            }
            Var::Value(id, name) => match self.scope.iter().rposition(|(v, _)| v == id) {
                Some(at) => self.scope[at].1.clone(),
                None => name.clone(),
            },
            Var::Snap(r, slot) => {
                let kind = self.prog.role(*r).kind;
                format!("old({}.{})", self.prog.role_name(*r), self.prog.slot_name(kind, *slot))
            }
        }
    }

    /// Prints `e`, parenthesised when it binds looser than `ctx`.
    fn expr(&mut self, e: &Expr, ctx: u8) {
        crate::stack::deep(|| self.expr_inner(e, ctx))
    }

    fn expr_inner(&mut self, e: &Expr, ctx: u8) {
        if e.is_error() {
            // Never printed for a program that lowered cleanly; visible if it ever is.
            self.out.push_str("{error}");
            return;
        }
        match &e.kind {
            // A string literal is its code (`Program::strings`).
            ExprKind::Int(i) if e.sort == Sort::Str => match self.prog.string(*i) {
                Some(text) => {
                    let _ = write!(self.out, "\"{text}\"");
                }
                None => {
                    let _ = write!(self.out, "{{string {i}}}");
                }
            },
            ExprKind::Int(i) => {
                if *i < 0 && ctx > 0 {
                    let _ = write!(self.out, "({i})");
                } else {
                    let _ = write!(self.out, "{i}");
                }
            }
            ExprKind::Real(r) => self.out.push_str(r),
            ExprKind::Bool(b) => self.out.push_str(if *b { "true" } else { "false" }),
            ExprKind::Var(v) => {
                if let Var::Value(id, _) = v {
                    self.note_read(*id);
                }
                let s = self.var_name(v);
                self.out.push_str(&s);
            }
            ExprKind::Unary(op, a) => {
                let (sym, prec) = match op {
                    UnOp::Neg => ("-", 7),
                    UnOp::Not => ("!", 4),
                };
                let paren = prec < ctx;
                if paren {
                    self.out.push('(');
                }
                self.out.push_str(sym);
                self.expr(a, if *op == UnOp::Neg { BinOp::Pow.precedence() } else { 4 });
                if paren {
                    self.out.push(')');
                }
            }
            ExprKind::Binary(op, a, b) => {
                let prec = op.precedence();
                let paren = prec < ctx;
                if paren {
                    self.out.push('(');
                }
                // Comparisons do not associate (`a < b < c` is a chain), so both operands
                // of one bind tighter; `=>` and `^` associate to the right.
                let (left, right) = if op.is_comparison() {
                    (prec + 1, prec + 1)
                } else if matches!(op, BinOp::Implies | BinOp::Pow) {
                    (prec + 1, prec)
                } else {
                    (prec, prec + 1)
                };
                self.expr(a, left);
                let _ = write!(self.out, " {} ", op.symbol());
                self.expr(b, right);
                if paren {
                    self.out.push(')');
                }
            }
            ExprKind::Call(Builtin::Pi, _) => self.out.push_str("pi"),
            ExprKind::Call(f, args) => {
                self.out.push_str(f.name());
                self.out.push('(');
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        self.out.push_str(", ");
                    }
                    self.expr(a, 0);
                }
                self.out.push(')');
            }
            ExprKind::If(c, a, b) => {
                let paren = ctx > 0;
                if paren {
                    self.out.push('(');
                }
                self.out.push_str("if ");
                self.expr(c, 0);
                self.out.push_str(" then ");
                self.expr(a, 0);
                self.out.push_str(" else ");
                self.expr(b, 0);
                if paren {
                    self.out.push(')');
                }
            }
            ExprKind::Tuple(items) => {
                self.out.push('(');
                for (i, a) in items.iter().enumerate() {
                    if i > 0 {
                        self.out.push_str(", ");
                    }
                    self.expr(a, 0);
                }
                self.out.push(')');
            }
            ExprKind::Component(a, i) => {
                self.expr(a, 10);
                let _ = write!(self.out, ".{}", ["x", "y", "z"][*i]);
            }
        }
    }
}

impl Printer<'_> {
    /// The timeout alternative of a choice: `after T ms. T_R` in the waiting role's
    /// external choice, `after T ms by R. T_p` in the sender's internal choice.
    fn timeout(&mut self, t: &crate::hir::Timeout, by: bool, comma: bool) {
        if comma {
            self.out.push(',');
        }
        self.newline();
        self.out.push_str("after ");
        self.expr(&t.after.bound, 0);
        self.out.push_str(" ms");
        if by {
            let _ = write!(self.out, " by {}", self.prog.role_name(t.after.by));
        }
        self.out.push_str(". ");
        self.local(&t.cont);
    }
}

/// A short description of the first action of a local type, for messages:
/// `GRobot!ready`, `&{Cart?ok, Cart?ko} & dt<m_idle>`, `dt<a /\ b>`, `end`.
pub fn describe(prog: &Program, t: &Local) -> String {
    match t {
        Local::Motion { prims, .. } => motion_text(prog, prims),
        Local::Send { branches, timeout, .. } => {
            let mut items: Vec<String> =
                branches.iter().map(|b| format!("{}!{}", prog.role_name(b.to), b.label)).collect();
            if let Some(t) = timeout {
                items.push(format!("after {} ms by {}", t.after.ms, prog.role_name(t.after.by)));
            }
            if items.len() == 1 {
                items.join("")
            } else {
                format!("+{{{}}}", items.join(", "))
            }
        }
        Local::Recv { branches, default, timeout, .. } => {
            let mut items: Vec<String> =
                branches.iter().map(|b| format!("{}?{}", prog.role_name(b.from), b.label)).collect();
            if let Some(t) = timeout {
                items.push(format!("after {} ms", t.after.ms));
            }
            let mut s = if items.len() == 1 && default.is_none() {
                items.join("")
            } else {
                format!("&{{{}}}", items.join(", "))
            };
            if let Some((prims, _)) = default {
                s.push_str(" & ");
                s.push_str(&motion_text(prog, prims));
            }
            s
        }
        Local::Rec { var, body, .. } => format!("mu {var}. {}", describe(prog, body)),
        Local::Var { var, args, .. } => {
            if args.is_empty() {
                var.clone()
            } else {
                let args: Vec<String> = args.iter().map(|a| expr(prog, None, a)).collect();
                format!("{var}({})", args.join(", "))
            }
        }
        Local::End(_) => "end".to_string(),
    }
}

/// Prints a local type for a diagnostic. Shared tails make a local type a DAG whose
/// printed tree can be exponentially larger, so a type that would print more than
/// `max_nodes` nodes is summarised by its first action.
pub fn print_bounded(prog: &Program, t: &LocalArc, max_nodes: usize) -> String {
    if tree_size(t, max_nodes + 1, &mut HashMap::new()) <= max_nodes {
        local(prog, t)
    } else {
        format!("{}. ... (too large to print here; use `mochi project`)", describe(prog, t))
    }
}

/// The number of nodes of `t` printed as a tree, saturating at `cap`.
fn tree_size<'t>(t: &'t LocalArc, cap: usize, memo: &mut HashMap<NodeRef<&'t Local>, usize>) -> usize {
    let key = NodeRef::new(&**t);
    if let Some(&n) = memo.get(&key) {
        return n;
    }
    let n = crate::stack::deep(|| {
        let mut n = 1usize;
        let mut add = |c: &'t LocalArc, memo: &mut HashMap<NodeRef<&'t Local>, usize>| {
            n = n.saturating_add(tree_size(c, cap, memo)).min(cap);
        };
        match &**t {
            Local::Motion { cont, .. } => add(cont, memo),
            Local::Send { branches, timeout, .. } => {
                branches.iter().for_each(|b| add(&b.cont, memo));
                if let Some(t) = timeout {
                    add(&t.cont, memo);
                }
            }
            Local::Recv { branches, default, timeout, .. } => {
                branches.iter().for_each(|b| add(&b.cont, memo));
                if let Some(t) = timeout {
                    add(&t.cont, memo);
                }
                if let Some((_, c)) = default {
                    add(c, memo);
                }
            }
            Local::Rec { body, .. } => add(body, memo),
            Local::Var { .. } | Local::End(_) => {}
        }
        n
    });
    memo.insert(key, n);
    n
}

/// `dt<a>` or `dt<a /\ b>`.
pub fn motion_text(prog: &Program, prims: &[PrimApp]) -> String {
    let items: Vec<String> = prims.iter().map(|a| prim_app(prog, a)).collect();
    format!("dt<{}>", items.join(" /\\ "))
}

/// How many nodes a local type printed in a note may have.
pub const NOTE_NODES: usize = 400;
