//! Processes (LANGUAGE.md, Processes; Sec 3.1): sends, receives with their binders,
//! motions, conditionals and parameterised recursion. A sum is an external choice
//! (inputs from one sender, at most one default motion `dt<a>.P`) or an internal choice
//! (outputs only); anything else is E0604.

use super::*;

impl Lowerer {
    pub(super) fn process_def(&mut self, p: &ast::ProcessDecl) {
        let Some(role) = self.role(&p.role) else { return };
        if let Some(&first) = self.process_roles.get(&role) {
            let d = dup(p.role.span, "process for", &p.role.name, first);
            self.diags.push(d);
            return;
        }
        self.process_roles.insert(role, p.role.span);
        let mut cx = Scopes::default();
        self.in_process = true;
        let body = self.process(&p.body, role, &mut cx);
        self.in_process = false;
        if let Some(body) = body {
            self.prog.processes.push(ProcessDef { role, body, span: p.role.span });
        }
    }

    pub(super) fn process(&mut self, p: &ast::Process, me: RoleId, cx: &mut Scopes) -> Option<Process> {
        crate::stack::deep(|| self.process_inner(p, me, cx))
    }

    pub(super) fn process_inner(&mut self, p: &ast::Process, me: RoleId, cx: &mut Scopes) -> Option<Process> {
        let mark = cx.values.len();
        let out = match p {
            ast::Process::Send { to, label, args, cont, span } => {
                let values = cx.values.clone();
                let args: Vec<Expr> = args.iter().map(|a| self.expr(a, &Env::role(me, &values))).collect();
                let to = self.role(to);
                let cont = self.process(cont, me, cx);
                Some(Process::Send { to: to?, label: label.name.clone(), args, cont: Box::new(cont?), loc: Loc(*span) })
            }
            ast::Process::Recv { .. } => self.process_sum(std::slice::from_ref(p), p.span(), me, cx),
            ast::Process::Sum(parts, span) => {
                let mut flat = Vec::new();
                flatten_sum(parts, &mut flat);
                let flat: Vec<ast::Process> = flat.into_iter().cloned().collect();
                self.process_sum(&flat, *span, me, cx)
            }
            ast::Process::Motion { prim, cont, span } => {
                let app = self.prim_app(me, prim, &cx.values.clone());
                let cont = self.process(cont, me, cx);
                Some(Process::Motion { prim: app?, cont: Box::new(cont?), loc: Loc(*span) })
            }
            ast::Process::If { cond, then, els, span } => {
                let values = cx.values.clone();
                let cond = self.pred(cond, &Env::role(me, &values), "a condition");
                let then = self.process(then, me, cx);
                cx.values.truncate(mark);
                let els = self.process(els, me, cx);
                Some(Process::If { cond, then: Box::new(then?), els: Box::new(els?), loc: Loc(*span) })
            }
            ast::Process::Rec { var, params, body, span } => {
                let params = self.rec_params(params, ValueOrigin::Bound { role: me }, Who::Role(me), &mut cx.values);
                cx.recs.push((var.name.clone(), params.iter().map(|p| p.sort.clone()).collect()));
                let body = self.process(body, me, cx);
                cx.recs.pop();
                Some(Process::Rec { var: var.name.clone(), params, body: Box::new(body?), loc: Loc(*span) })
            }
            ast::Process::Var { var, args, span } => {
                let values = cx.values.clone();
                let args = self.rec_var(var, args, *span, &cx.recs, Env::role(me, &values));
                Some(Process::Var { var: var.name.clone(), args, loc: Loc(*span) })
            }
            ast::Process::End(span) => Some(Process::End(Loc(*span))),
        };
        cx.values.truncate(mark);
        out
    }

    /// A sum is an external choice (inputs from one sender, at most one default motion)
    /// or an internal choice (outputs only).
    pub(super) fn process_sum(
        &mut self,
        parts: &[ast::Process],
        span: Span,
        me: RoleId,
        cx: &mut Scopes,
    ) -> Option<Process> {
        let loc = Loc(span);
        let n_send = parts.iter().filter(|p| matches!(p, ast::Process::Send { .. })).count();
        if n_send == parts.len() {
            let branches: Vec<Option<Process>> = parts.iter().map(|p| self.process(p, me, cx)).collect();
            return branches.into_iter().collect::<Option<Vec<_>>>().map(|branches| Process::Choose { branches, loc });
        }
        let mut sender: Option<(RoleId, Span)> = None;
        let mut arms = Vec::new();
        let mut default: Option<(PrimApp, Box<Process>)> = None;
        let mut ok = true;
        let mark = cx.values.len();
        for part in parts {
            cx.values.truncate(mark);
            match part {
                ast::Process::Recv { from, label, binders, cont, span } => {
                    let Some(r) = self.role(from) else {
                        ok = false;
                        continue;
                    };
                    match sender {
                        Some((s, first)) if s != r => {
                            self.diags.push(
                                Diagnostic::error(
                                    Code::ChoiceMismatch,
                                    from.span,
                                    format!(
                                        "this external choice receives from `{}` and from `{}`",
                                        self.prog.role_name(s),
                                        self.prog.role_name(r)
                                    ),
                                )
                                .with_label(first, "first sender")
                                .with_help("a process waits for one sender at a time (Sec 4.3); split the choice"),
                            );
                            ok = false;
                            continue;
                        }
                        None => sender = Some((r, from.span)),
                        _ => {}
                    }
                    // One receive binds each name once: `C?grab(ty, ty, tz)` would leave the
                    // first value unreachable (the second shadows it), which is never meant.
                    ok &= super::distinct("binder", binders, &mut self.diags);
                    let binders: Vec<ValueId> =
                        binders.iter().map(|b| self.new_value(b, Sort::Any, ValueOrigin::Bound { role: me })).collect();
                    cx.values.extend(&binders);
                    let cont = self.process(cont, me, cx);
                    match cont {
                        Some(cont) => arms.push(RecvArm { label: label.name.clone(), binders, cont, loc: Loc(*span) }),
                        None => ok = false,
                    }
                }
                ast::Process::Motion { prim, cont, span } if default.is_none() => {
                    let app = self.prim_app(me, prim, &cx.values.clone());
                    let cont = self.process(cont, me, cx);
                    match (app, cont) {
                        (Some(a), Some(c)) => default = Some((a, Box::new(c))),
                        _ => ok = false,
                    }
                    let _ = span;
                }
                other => {
                    let what = match other {
                        ast::Process::Send { .. } => "an output",
                        ast::Process::Motion { .. } => "a second default motion",
                        _ => "this process",
                    };
                    self.diags.push(
                        Diagnostic::error(Code::ChoiceMismatch, other.span(), format!("{what} cannot be a branch of an external choice"))
                            .with_help("an external choice has inputs from one sender and at most one default `dt<a>.P`; an internal choice has only outputs"),
                    );
                    ok = false;
                }
            }
        }
        cx.values.truncate(mark);
        let (from, _) = sender?;
        ok.then_some(Process::Recv { from, branches: arms, default, loc })
    }
}

pub(super) fn flatten_sum<'a>(parts: &'a [ast::Process], out: &mut Vec<&'a ast::Process>) {
    for p in parts {
        match p {
            ast::Process::Sum(inner, _) => flatten_sum(inner, out),
            other => out.push(other),
        }
    }
}
