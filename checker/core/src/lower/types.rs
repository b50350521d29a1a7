//! Global and local types (LANGUAGE.md, Global types and Local types; Defs 4.1 and 4.6):
//! messages with guards and refined payloads, motions, sequence, choice, separation
//! `*` with its partition, and parameterised recursion. Payload fields and recursion
//! parameters become value variables (one [`ValueId`] per binding site), in scope in
//! the rest of their branch.

use super::*;

impl Lowerer {
    pub(super) fn choreography(&mut self, c: &ast::ChorDecl) {
        if let Some(first) = &self.prog.choreography {
            let d = dup(c.name.span, "choreography", &c.name.name, first.span);
            self.diags.push(d);
            return;
        }
        let mut cx = Scopes::default();
        let body = self.global(&c.body, &mut cx);
        self.jump_widths(&body, &mut Vec::new());
        self.prog.choreography = Some(Choreography { name: c.name.name.clone(), body, span: c.name.span });
        for p in &c.partitions {
            self.distinct_coordinates(&p.point);
            let names = [p.point[0].name.clone(), p.point[1].name.clone(), p.point[2].name.clone()];
            let env = Env { point: Some(&names), part: Some("a partition"), ..Env::consts_only() };
            let regions = p.regions.iter().map(|r| self.pred(r, &env, "a partition's region")).collect();
            self.prog.partitions.push(crate::hir::Partition {
                par: p.par,
                point: names.clone(),
                regions,
                span: p.span,
            });
        }
    }

    pub(super) fn global(&mut self, g: &ast::Global, cx: &mut Scopes) -> Global {
        crate::stack::deep(|| self.global_inner(g, cx))
    }

    pub(super) fn global_inner(&mut self, g: &ast::Global, cx: &mut Scopes) -> Global {
        // A choice's snapshot is for the first message of each branch only.
        let pending = cx.choice_snapshot.take();
        let head = std::mem::take(&mut cx.branch_head);
        match g {
            ast::Global::Msg(m) => {
                let from = self.role(&m.from);
                let to = self.role(&m.to);
                let (Some(from), Some(to)) = (from, to) else { return Global::End(Loc(m.span)) };
                self.streamed_step(from, to, &m.label.name, m.label.span);
                // The sender's snapshot of what it observes: the choice's, or this message's own.
                let snap = match pending {
                    Some(s) if s.iter().all(|o| matches!(self.prog.value(o.value).origin, ValueOrigin::Observed { reader, .. } if reader == from)) => s,
                    _ => self.snapshot(from),
                };
                cx.values.extend(snap.iter().map(|o| o.value));
                let outer = self.deciding.replace(from);
                let guard = m.guard.as_ref().map(|gd| {
                    let env = Env::role(from, &cx.values);
                    self.pred(gd, &env, "a guard")
                });
                let payload =
                    self.message(&m.label, &m.payload, from, ValueOrigin::Message { from, to }, &mut cx.values);
                self.deciding = outer;
                let observed = self.snapshots_read(&snap, guard.as_ref(), &payload, &mut cx.values);
                Global::Msg(Msg {
                    from,
                    to,
                    guard,
                    label: m.label.name.clone(),
                    payload,
                    loc: Loc(m.span),
                    label_loc: Loc(m.label.span),
                    observed,
                })
            }
            ast::Global::Motion { parts, span } => {
                let mut out = Vec::new();
                for (who, call) in parts {
                    let Some(r) = self.role(who) else { continue };
                    if let Some(app) = self.prim_app(r, call, &cx.values.clone()) {
                        out.push((r, app));
                    }
                }
                Global::Motion(Motion { parts: out, loc: Loc(*span) })
            }
            ast::Global::Seq(items, span) => {
                let mut pending = pending;
                let mut head = head;
                Global::Seq(
                    items
                        .iter()
                        .map(|g| {
                            cx.choice_snapshot = pending.take();
                            cx.branch_head = std::mem::take(&mut head);
                            self.global(g, cx)
                        })
                        .collect(),
                    Loc(*span),
                )
            }
            ast::Global::Choice(items, span) | ast::Global::Par(items, span) => {
                let mark = cx.values.len();
                // One decision, one snapshot: the sender of the first branch's first message
                // reads its observed values once for all branches (a choice whose branches
                // have different senders is E0303).
                let is_choice = matches!(g, ast::Global::Choice(..));
                let snap = match (g, items.iter().find_map(first_sender)) {
                    (ast::Global::Choice(..), Some(who)) => self.prog.role_by_name(&who.name).map(|r| self.snapshot(r)),
                    _ => None,
                };
                let lowered = items
                    .iter()
                    .map(|g| {
                        cx.values.truncate(mark);
                        cx.choice_snapshot = snap.clone();
                        cx.branch_head = is_choice;
                        self.global(g, cx)
                    })
                    .collect();
                cx.choice_snapshot = None;
                cx.values.truncate(mark);
                if matches!(g, ast::Global::Choice(..)) {
                    Global::Choice(lowered, Loc(*span))
                } else {
                    Global::Par(lowered, Loc(*span))
                }
            }
            ast::Global::Rec { var, params, decreases, body, span } => {
                let mark = cx.values.len();
                let params = self.rec_params(params, ValueOrigin::RecParam, Who::Nobody, &mut cx.values);
                // The measure reads the parameters, the values bound before the loop and
                // constants, none of which changes within an iteration (no participant's
                // state: a motion would change it between the head and the jump).
                let decreases = decreases.as_ref().map(|e| {
                    let env = Env { values: &cx.values.clone(), ..Env::consts_only() };
                    let m = self.expr(e, &env);
                    self.expect_sort(&m, &Sort::Int, &format!("the measure of `{}`", var.name));
                    m
                });
                cx.recs.push((var.name.clone(), params.iter().map(|p| p.sort.clone()).collect()));
                let body = self.global(body, cx);
                cx.recs.pop();
                cx.values.truncate(mark);
                Global::Rec { var: var.name.clone(), params, decreases, body: Box::new(body), loc: Loc(*span) }
            }
            ast::Global::Var { var, args, span } => {
                let args =
                    self.rec_var(var, args, *span, &cx.recs, Env { values: &cx.values.clone(), ..Env::consts_only() });
                Global::Var(RecVar { var: var.name.clone(), args, loc: Loc(*span) })
            }
            ast::Global::End(span) => Global::End(Loc(*span)),
            ast::Global::After { bound, by, span } => self.after(bound, by, *span, head, cx),
        }
    }

    /// `after T ms by R` (LANGUAGE.md, Timeouts): `T` a positive integer constant
    /// expression (E0320), the node the head of a branch of a choice (E0321). Whether `R`
    /// waits in the choice, and what follows, is checked with the choice (`wf::side`).
    fn after(&mut self, bound: &ast::Expr, by: &ast::Ident, span: Span, head: bool, cx: &Scopes) -> Global {
        if !head {
            self.diags.push(
                Diagnostic::error(Code::TimeoutNotInChoice, span, "`after` does not start a branch of a choice")
                    .with_note("a timeout branch is the alternative of a choice's messages: its receiver takes it when none of them came in time")
                    .with_help("make it a branch of the choice whose messages it waits for: `(p -> R: a. G1 + after T ms by R. G2)`"),
            );
        }
        let (e, ms) = self.timeout_bound(bound, cx);
        let Some(r) = self.role(by) else { return Global::End(Loc(span)) };
        Global::After(crate::hir::After { ms, bound: e, by: r, loc: Loc(span) })
    }

    /// The bound `T` of `after T ms`, in a global or a local type: a positive integer
    /// constant expression (E0320). An erroneous bound counts as 1 ms, after its error.
    fn timeout_bound(&mut self, bound: &ast::Expr, cx: &Scopes) -> (Expr, i64) {
        let env = Env { values: &cx.values.clone(), ..Env::consts_only() };
        let e = self.expr(bound, &env);
        let ms = crate::hir::expr::const_int(&self.prog, &e);
        if !matches!(ms, Some(v) if v > 0) && !e.is_error() {
            let found = match ms {
                Some(v) => format!("its value is {v}"),
                None => "it is not an integer constant expression".to_string(),
            };
            self.diags.push(
                Diagnostic::error(Code::TimeoutBound, bound.span, format!("the bound of this timeout is not a positive integer constant: {found}"))
                    .with_note("the bound is a number of milliseconds known before the session starts, compared with the log's or the clock's time")
                    .with_help("write a positive integer (`after 1500 ms by R`) or a `const` holding one"),
            );
        }
        (e, ms.unwrap_or(1).max(1))
    }

    /// The timeout alternative of a written local choice (LANGUAGE.md, Timeouts): in `me`'s
    /// external choice the waiting role is `me`; in its internal choice, the peer named
    /// after `by`. The continuation sees what the choice's start sees (the timeout reads
    /// and binds nothing).
    fn local_timeout(&mut self, t: &ast::LocalTimeout, me: RoleId, cx: &mut Scopes) -> Option<crate::hir::Timeout> {
        let (bound, ms) = self.timeout_bound(&t.bound, cx);
        let by = match &t.by {
            Some(r) => self.role(r)?,
            None => me,
        };
        let cont = self.local(&t.cont, me, cx);
        Some(crate::hir::Timeout { after: crate::hir::After { ms, bound, by, loc: Loc(t.span) }, cont })
    }

    /// Lowers payload fields, pushing their value variables onto `values` (each field's
    /// refinement sees the fields before it and itself).
    pub(super) fn fields(
        &mut self,
        fields: &[ast::Field],
        viewer: RoleId,
        origin: ValueOrigin,
        values: &mut Vec<ValueId>,
    ) -> Vec<Field> {
        super::distinct("payload field", fields.iter().map(|f| f.bound()), &mut self.diags);
        self.plain_fields(fields, viewer, origin, values)
    }

    /// [`Self::fields`] without the check that the names are distinct: each field bound
    /// with its written sort (`Sort::Error` when none is written) and refinement. Also the
    /// fields of a MAVLink message that could not be resolved (`lower::mav`).
    pub(super) fn plain_fields(
        &mut self,
        fields: &[ast::Field],
        viewer: RoleId,
        origin: ValueOrigin,
        values: &mut Vec<ValueId>,
    ) -> Vec<Field> {
        let mut out = Vec::new();
        for f in fields {
            // A missing sort is reported by `message` (E0241).
            let sort = f.sort.as_ref().map(|s| self.sort(s)).unwrap_or(Sort::Error);
            let v = self.new_value(f.bound(), sort.clone(), origin.clone());
            values.push(v);
            let refinement = f.refinement.as_ref().map(|r| {
                let env = Env::role(viewer, values);
                self.pred(r, &env, "a refinement")
            });
            out.push(Field { value: v, name: f.bound().name.clone(), sort, refinement, mav: None });
        }
        out
    }

    pub(super) fn new_value(&mut self, name: &ast::Ident, sort: Sort, origin: ValueOrigin) -> ValueId {
        self.hides_entry(name);
        let id = ValueId(self.prog.values.len() as u32);
        self.prog.values.push(ValueVar { name: name.name.clone(), sort, origin, span: name.span });
        id
    }

    pub(super) fn rec_params(
        &mut self,
        params: &[ast::RecParam],
        origin: ValueOrigin,
        who: Who,
        values: &mut Vec<ValueId>,
    ) -> Vec<RecParam> {
        super::distinct("recursion parameter", params.iter().map(|p| &p.name), &mut self.diags);
        let mut out = Vec::new();
        for p in params {
            let sort = self.sort(&p.sort);
            let outer = values.clone();
            let env =
                Env { who, state: who != Who::Nobody, input: who != Who::Nobody, values: &outer, ..Env::consts_only() };
            let init = self.expr(&p.init, &env);
            self.expect_sort(&init, &sort, &format!("initial value of `{}`", p.name.name));
            let v = self.new_value(&p.name, sort.clone(), origin.clone());
            values.push(v);
            // A string parameter of the choreography is as wide as its initial value (every
            // jump is checked against that width after lowering: `jump_widths`). The jumps of
            // local types and processes are not checked, so their string parameters keep an
            // unknown width, which E0236 refuses wherever a width is needed.
            if sort == Sort::Str && who == Who::Nobody {
                if let Some(n) = self.prog.str_width_of(&init, &|_| None) {
                    self.prog.str_width.insert(v, n);
                }
            }
            let refinement = p.refinement.as_ref().map(|r| {
                let env = Env { values, ..env };
                self.pred(r, &env, "a refinement")
            });
            out.push(RecParam { value: v, name: p.name.name.clone(), sort, refinement, init });
        }
        out
    }

    /// E0236: a jump passes a string parameter a value that may be wider than the
    /// parameter's initial value, the width every message of the loop was checked with.
    fn jump_widths(&mut self, g: &Global, loops: &mut Vec<(String, StrParams)>) {
        match g {
            Global::Seq(items, _) | Global::Choice(items, _) | Global::Par(items, _) => {
                items.iter().for_each(|i| self.jump_widths(i, loops))
            }
            Global::Rec { var, params, body, .. } => {
                let strs = params
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.sort == Sort::Str)
                    .map(|(i, p)| (i, p.value, p.name.clone()))
                    .collect();
                loops.push((var.clone(), strs));
                self.jump_widths(body, loops);
                loops.pop();
            }
            Global::Var(j) => {
                let Some((_, strs)) = loops.iter().rev().find(|(n, _)| *n == j.var) else { return };
                for (i, v, name) in strs.clone() {
                    let Some(a) = j.args.get(i) else { continue };
                    let (n, w) = (self.prog.str_width.get(&v).copied(), self.prog.str_width_of(a, &|_| None));
                    if n.is_some() && (w.is_none() || w > n) {
                        let n = n.unwrap_or_default();
                        let held = w.map_or("a string of a width mochi does not know".to_string(), |w| {
                            format!("a string of up to {w} characters")
                        });
                        self.err(
                            Code::StringTooLong,
                            a.loc.0,
                            format!("this passes {held} to `{name}`, which its initial value makes at most {n} wide"),
                            format!("pass `{name}` values at most {n} wide: the loop's messages were checked with that width"),
                        );
                    }
                }
            }
            Global::Msg(_) | Global::Motion(_) | Global::End(_) | Global::After(_) => {}
        }
    }

    pub(super) fn rec_var(
        &mut self,
        var: &ast::Ident,
        args: &[ast::Expr],
        span: Span,
        recs: &[(String, Vec<Sort>)],
        env: Env,
    ) -> Vec<Expr> {
        let args: Vec<Expr> = args.iter().map(|a| self.expr(a, &env)).collect();
        match recs.iter().rev().find(|(n, _)| *n == var.name).map(|(n, sorts)| (n, sorts.len(), sorts)) {
            None => self.err(
                Code::UnboundRecursion,
                var.span,
                format!("recursion variable `{}` is not bound here", var.name),
                format!("bind it with `mu {}. ...` around this occurrence", var.name),
            ),
            Some((_, n, _)) if n != args.len() => self.err(
                Code::ArityMismatch,
                span,
                format!("`{}` takes {n} argument(s), found {}", var.name, args.len()),
                "pass one argument per recursion parameter",
            ),
            // Each argument has its parameter's sort (an `int` parameter given `i + 0.5`
            // would be a real the next iteration's refinements and guards read as an int).
            Some((_, _, sorts)) => {
                for (i, (a, s)) in args.iter().zip(sorts).enumerate() {
                    self.expect_sort(a, s, &format!("argument {} of `{}`", i + 1, var.name));
                }
            }
        }
        args
    }

    pub(super) fn local_def(&mut self, t: &ast::LocalDecl) {
        let Some(role) = self.role(&t.role) else { return };
        if let Some(&first) = self.local_roles.get(&role) {
            let d = dup(t.role.span, "local type for", &t.role.name, first);
            self.diags.push(d);
            return;
        }
        self.local_roles.insert(role, t.role.span);
        let mut cx = Scopes::default();
        let body = self.local(&t.body, role, &mut cx);
        self.prog.locals.push(LocalDef { role, body, span: t.role.span });
    }

    pub(super) fn local(&mut self, t: &ast::Local, me: RoleId, cx: &mut Scopes) -> LocalArc {
        crate::stack::deep(|| Arc::new(self.local_inner(t, me, cx)))
    }

    pub(super) fn local_inner(&mut self, t: &ast::Local, me: RoleId, cx: &mut Scopes) -> Local {
        let mark = cx.values.len();
        let out = match t {
            ast::Local::Motion { prims, cont, span } => {
                let prims: Vec<PrimApp> =
                    prims.iter().filter_map(|c| self.prim_app(me, c, &cx.values.clone())).collect();
                let cont = self.local(cont, me, cx);
                Local::Motion { prims, cont, loc: Loc(*span) }
            }
            ast::Local::Send { branches, timeout, span } => {
                let mut out = Vec::new();
                // One decision, one snapshot of what `me` observes, for every branch.
                let snap = self.snapshot(me);
                for b in branches {
                    cx.values.truncate(mark);
                    cx.values.extend(snap.iter().map(|o| o.value));
                    let outer = self.deciding.replace(me);
                    let guard = b.guard.as_ref().map(|g| {
                        let env = Env::role(me, &cx.values);
                        self.pred(g, &env, "a guard")
                    });
                    let Some(to) = self.role(&b.to) else {
                        self.deciding = outer;
                        continue;
                    };
                    let origin = ValueOrigin::Message { from: me, to };
                    let payload = self.message(&b.label, &b.payload, me, origin, &mut cx.values);
                    self.deciding = outer;
                    let observed = self.snapshots_read(&snap, guard.as_ref(), &payload, &mut cx.values);
                    let cont = self.local(&b.cont, me, cx);
                    out.push(SendBranch {
                        observed,
                        guard,
                        to,
                        label: b.label.name.clone(),
                        payload,
                        cont,
                        loc: Loc(b.span),
                    });
                }
                cx.values.truncate(mark);
                let timeout = timeout.as_ref().and_then(|t| self.local_timeout(t, me, cx));
                Local::Send { branches: out, timeout, loc: Loc(*span) }
            }
            ast::Local::Recv { branches, default, timeout, span } => {
                let mut out = Vec::new();
                for b in branches {
                    cx.values.truncate(mark);
                    let Some(from) = self.role(&b.from) else { continue };
                    let origin = ValueOrigin::Message { from, to: me };
                    let payload = self.message(&b.label, &b.payload, me, origin, &mut cx.values);
                    let cont = self.local(&b.cont, me, cx);
                    out.push(RecvBranch { from, label: b.label.name.clone(), payload, cont, loc: Loc(b.span) });
                }
                cx.values.truncate(mark);
                let default = default.as_ref().map(|(prims, cont)| {
                    let prims: Vec<PrimApp> =
                        prims.iter().filter_map(|c| self.prim_app(me, c, &cx.values.clone())).collect();
                    (prims, self.local(cont, me, cx))
                });
                cx.values.truncate(mark);
                let timeout = timeout.as_ref().and_then(|t| self.local_timeout(t, me, cx));
                Local::Recv { branches: out, default, timeout, loc: Loc(*span) }
            }
            ast::Local::Rec { var, params, body, span } => {
                let params = self.rec_params(params, ValueOrigin::RecParam, Who::Role(me), &mut cx.values);
                cx.recs.push((var.name.clone(), params.iter().map(|p| p.sort.clone()).collect()));
                let body = self.local(body, me, cx);
                cx.recs.pop();
                Local::Rec { var: var.name.clone(), params, body, loc: Loc(*span) }
            }
            ast::Local::Var { var, args, span } => {
                let values = cx.values.clone();
                let args = self.rec_var(var, args, *span, &cx.recs, Env::role(me, &values));
                Local::Var { var: var.name.clone(), args, loc: Loc(*span) }
            }
            ast::Local::End(span) => Local::End(Loc(*span)),
        };
        cx.values.truncate(mark);
        out
    }
}

/// The sender of the first message of `g`, if it starts with one (as written).
fn first_sender(g: &ast::Global) -> Option<&ast::Ident> {
    match g {
        ast::Global::Msg(m) => Some(&m.from),
        ast::Global::Seq(items, _) => items.first().and_then(first_sender),
        _ => None,
    }
}

/// A loop's string parameters: position, value and name ([`Lowerer::jump_widths`]).
type StrParams = Vec<(usize, ValueId, String)>;
