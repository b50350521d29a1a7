//! Lowering: the parsed files → a resolved [`Program`]. Resolves every name (robot
//! kinds, primitives, participants, variables, recursion variables), infers the sort
//! of every expression and enforces which variables each part of a contract may read
//! (Def 3.4). Errors are E02xx; lowering reports them all and still returns a program,
//! but later stages only run on a program lowered without errors.
//!
//! Name lookup for an unqualified name, innermost first: value variables in scope
//! (payload fields, recursion parameters, process binders), primitive parameters, the
//! footprint's point coordinates, `clock`, the robot's own state and input variables,
//! constants. `Cart.x` names a participant's variable; `e.x` a component of a point.

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use crate::source::Span;
use crate::syntax::ast::{self, BinOp, UnOp};
use crate::syntax::Parsed;
use std::collections::HashMap;
use std::sync::Arc;

/// Lowers every file of `parsed` (imports first) into one program.
pub fn lower(parsed: &Parsed) -> (Program, Vec<Diagnostic>) {
    let mut l = Lowerer::default();
    let items: Vec<&ast::Item> = parsed.files.iter().flat_map(|(_, f)| f.items.iter()).collect();
    let root_span = parsed.files.last().map(|(id, _)| Span::new(*id, 0, 0)).unwrap_or_default();
    let consts: Vec<&ast::ConstDecl> =
        items.iter().filter_map(|it| if let ast::Item::Const(c) = it { Some(c) } else { None }).collect();
    l.constants(&consts);
    for it in &items {
        if let ast::Item::Robot(r) = it {
            l.robot_kind(r);
        }
    }
    for it in &items {
        if let ast::Item::Robot(r) = it {
            l.robot_invariant(r);
        }
    }
    for it in &items {
        if let ast::Item::Motion(m) = it {
            l.motion(m);
        }
    }
    for it in &items {
        if let ast::Item::System(s) = it {
            l.system(s);
        }
    }
    l.connect_inputs();
    for it in &items {
        match it {
            ast::Item::Choreography(c) => l.choreography(c),
            ast::Item::Process(p) => l.process_def(p),
            ast::Item::Local(t) => l.local_def(t),
            _ => {}
        }
    }
    if l.prog.system.is_none() || l.prog.choreography.is_none() {
        let what = match (l.prog.system.is_none(), l.prog.choreography.is_none()) {
            (true, true) => "no `system` and no `choreography`",
            (true, false) => "no `system`",
            _ => "no `choreography`",
        };
        l.diags.push(
            Diagnostic::error(Code::MissingItem, root_span, format!("{what} to check"))
                .with_help("`mochi check` reads a `.chor` file with a `system` block and a `choreography`; library files are checked through the choreographies that import them"),
        );
    }
    (l.prog, l.diags)
}

/// Lowers a local type written for `role` in the context of an already lowered
/// program; `mochi project`'s output goes back through this in the round-trip tests.
pub fn lower_local(prog: &Program, role: RoleId, t: &ast::Local) -> (LocalRc, Vec<Diagnostic>) {
    let mut l = Lowerer { prog: prog.clone(), ..Lowerer::default() };
    l.consts = prog.consts.iter().enumerate().map(|(i, c)| (c.name.clone(), ConstId(i as u32))).collect();
    l.kinds = prog.kinds.iter().enumerate().map(|(i, k)| (k.name.clone(), KindId(i as u32))).collect();
    l.prims = prog.prims.iter().enumerate().map(|(i, p)| ((p.kind, p.name.clone()), PrimId(i as u32))).collect();
    let body = l.local(t, role, &mut Scopes::default());
    (body, l.diags)
}

#[derive(Default)]
struct Lowerer {
    prog: Program,
    diags: Vec<Diagnostic>,
    consts: HashMap<String, ConstId>,
    kinds: HashMap<String, KindId>,
    prims: HashMap<(KindId, String), PrimId>,
    /// Spans of the declarations, for duplicate reports.
    const_spans: Vec<Span>,
    kind_spans: Vec<Span>,
    /// Participants whose kind is unknown: already reported, so uses stay silent.
    poisoned: std::collections::HashSet<String>,
    /// Process and local type declarations seen per role.
    process_roles: HashMap<RoleId, Span>,
    local_roles: HashMap<RoleId, Span>,
}

/// Whose variables an unqualified name may denote.
#[derive(Clone, Copy, PartialEq)]
enum Who {
    Nobody,
    /// Inside a robot kind's invariant or a primitive's contract: [`Var::Own`].
    Kind(KindId),
    /// In a participant's view: [`Var::Role`].
    Role(RoleId),
}

/// The context an expression is resolved in.
#[derive(Clone, Copy)]
struct Env<'a> {
    who: Who,
    /// Which contract part this is, for E0211 messages (`None` outside contracts).
    part: Option<&'static str>,
    params: &'a [(String, Sort)],
    point: Option<&'a [String; 3]>,
    clock: bool,
    old: bool,
    state: bool,
    input: bool,
    qualified: bool,
    values: &'a [ValueId],
}

impl<'a> Env<'a> {
    fn consts_only() -> Env<'static> {
        Env {
            who: Who::Nobody,
            part: None,
            params: &[],
            point: None,
            clock: false,
            old: false,
            state: false,
            input: false,
            qualified: false,
            values: &[],
        }
    }

    /// A participant's view: its own variables, everybody's qualified ones, `values`.
    fn role(r: RoleId, values: &'a [ValueId]) -> Env<'a> {
        Env { who: Who::Role(r), state: true, input: true, qualified: true, values, ..Env::consts_only() }
    }
}

fn dup(span: Span, what: &str, name: &str, first: Span) -> Diagnostic {
    Diagnostic::error(Code::Duplicate, span, format!("{what} `{name}` is defined twice"))
        .with_label(first, "first defined here")
        .with_help("rename or remove one of the definitions")
}

impl Lowerer {
    fn err(&mut self, code: Code, span: Span, msg: impl Into<String>, help: impl Into<String>) {
        self.diags.push(Diagnostic::error(code, span, msg).with_help(help));
    }

    // ---- declarations --------------------------------------------------------------

    /// Lowers the constants in dependency order, so that their order in the files does not
    /// matter (LANGUAGE.md), and reports each cycle once (E0213) instead of an unknown
    /// variable. A constant in a cycle is still lowered (its value then lacks the
    /// constant it depends on), so its uses elsewhere do not cascade into E0205s.
    fn constants(&mut self, consts: &[&ast::ConstDecl]) {
        let (order, cycles) = const_order(consts);
        let mut cyclic_uses = std::collections::HashSet::new();
        for cycle in &cycles {
            let names: Vec<String> = cycle.iter().map(|&i| format!("`{}`", consts[i].name.name)).collect();
            let first = consts[cycle[0]];
            let mut d = Diagnostic::error(
                Code::ConstCycle,
                first.name.span,
                format!("constants defined in a cycle: {} -> {}", names.join(" -> "), names[0]),
            )
            .with_help("give one of these constants a value that does not mention the others");
            for &i in &cycle[1..] {
                d = d.with_label(consts[i].name.span, format!("`{}` is defined here", consts[i].name.name));
            }
            self.diags.push(d);
            let members: Vec<&str> = cycle.iter().map(|&i| consts[i].name.name.as_str()).collect();
            for &i in cycle {
                for (name, span) in const_refs(&consts[i].value) {
                    if members.contains(&name) {
                        cyclic_uses.insert(span);
                    }
                }
            }
        }
        for i in order {
            let before = self.diags.len();
            self.constant(consts[i]);
            if !cyclic_uses.is_empty() {
                let mut k = before;
                while k < self.diags.len() {
                    if self.diags[k].code == Code::UnknownVariable && cyclic_uses.contains(&self.diags[k].span) {
                        self.diags.remove(k);
                    } else {
                        k += 1;
                    }
                }
            }
        }
    }

    fn constant(&mut self, c: &ast::ConstDecl) {
        let value = self.expr(&c.value, &Env::consts_only());
        let sort = match &c.sort {
            Some(s) => {
                let want = self.sort(s);
                self.expect_sort(&value, &want, "constant");
                want
            }
            None => value.sort.clone(),
        };
        if let Some(&first) = self.consts.get(&c.name.name) {
            let d = dup(c.name.span, "constant", &c.name.name, self.const_spans[first.idx()]);
            self.diags.push(d);
            return;
        }
        let id = ConstId(self.prog.consts.len() as u32);
        self.consts.insert(c.name.name.clone(), id);
        self.const_spans.push(c.name.span);
        self.prog.consts.push(Const { name: c.name.name.clone(), sort, value, span: c.span });
    }

    fn sort(&mut self, s: &ast::SortAst) -> Sort {
        match &s.kind {
            ast::SortKind::Unit => Sort::Unit,
            ast::SortKind::Bool => Sort::Bool,
            ast::SortKind::Int => Sort::Int,
            ast::SortKind::Real => Sort::Real,
            ast::SortKind::Point => Sort::Point,
            ast::SortKind::Vector => Sort::Vector,
            ast::SortKind::Product(parts) => Sort::Product(parts.iter().map(|p| self.sort(p)).collect()),
            ast::SortKind::Named(n) => {
                self.err(
                    Code::SortMismatch,
                    s.span,
                    format!("unknown sort `{n}`"),
                    "sorts are `unit`, `bool`, `int`, `real`, `point`, `vector` and products `(S, S)`",
                );
                Sort::Any
            }
        }
    }

    fn var_decls(
        &mut self,
        decls: &[ast::VarDecl],
        what: &str,
        seen: &mut HashMap<String, Span>,
    ) -> Vec<(String, Sort)> {
        let mut out = Vec::new();
        for d in decls {
            if let Some(&first) = seen.get(&d.name.name) {
                let diag = dup(d.name.span, what, &d.name.name, first);
                self.diags.push(diag);
                continue;
            }
            seen.insert(d.name.name.clone(), d.name.span);
            let sort = self.sort(&d.sort);
            out.push((d.name.name.clone(), sort));
        }
        out
    }

    fn robot_kind(&mut self, r: &ast::RobotDecl) {
        if let Some(&first) = self.kinds.get(&r.name.name) {
            let d = dup(r.name.span, "robot kind", &r.name.name, self.kind_spans[first.idx()]);
            self.diags.push(d);
            return;
        }
        let mut seen = HashMap::new();
        let state = self.var_decls(&r.state, "variable", &mut seen);
        let inputs = self.var_decls(&r.inputs, "variable", &mut seen);
        let id = KindId(self.prog.kinds.len() as u32);
        self.kinds.insert(r.name.name.clone(), id);
        self.kind_spans.push(r.name.span);
        self.prog.kinds.push(RobotKind {
            name: r.name.name.clone(),
            state,
            inputs,
            geometry: r.geometry.clone(),
            invariant: None,
            span: r.span,
        });
    }

    fn robot_invariant(&mut self, r: &ast::RobotDecl) {
        let Some(inv) = &r.invariant else { return };
        let Some(&kind) = self.kinds.get(&r.name.name) else { return };
        if self.kind_spans[kind.idx()] != r.name.span {
            return; // a duplicate, already reported
        }
        let env = Env { who: Who::Kind(kind), state: true, input: true, ..Env::consts_only() };
        let e = self.pred(inv, &env, "an invariant");
        self.prog.kinds[kind.idx()].invariant = Some(e);
    }

    fn kind_of_name(&mut self, name: &ast::Ident) -> Option<KindId> {
        match self.kinds.get(&name.name) {
            Some(&k) => Some(k),
            None => {
                let mut help = "declare it with `robot NAME { ... }` or import the file that does".to_string();
                if !self.prog.kinds.is_empty() {
                    let names: Vec<_> = self.prog.kinds.iter().map(|k| format!("`{}`", k.name)).collect();
                    help = format!("known robot kinds: {}", names.join(", "));
                }
                self.err(Code::UnknownRobot, name.span, format!("unknown robot kind `{}`", name.name), help);
                None
            }
        }
    }

    fn motion(&mut self, m: &ast::MotionDecl) {
        let Some(kind) = self.kind_of_name(&m.kind) else { return };
        if let Some(&first) = self.prims.get(&(kind, m.name.name.clone())) {
            let d = dup(m.name.span, "motion primitive", &m.name.name, self.prog.prim(first).name_span);
            self.diags.push(d);
            return;
        }
        let mut seen = HashMap::new();
        let params = self.var_decls(&m.params, "parameter", &mut seen);
        let loc = Loc(m.span);
        let mut prim = Primitive {
            name: m.name.name.clone(),
            kind,
            params: params.clone(),
            pre: Expr::bool(true, loc),
            assume: Expr::bool(true, loc),
            guarantee: Expr::bool(true, loc),
            post: Expr::bool(true, loc),
            footprint: None,
            duration: Duration { lo: Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc }, hi: None },
            interruptible: false,
            span: m.span,
            name_span: m.name.span,
        };
        let mut interruptible_seen = false;
        let mut fields_seen: HashMap<String, Span> = HashMap::new();
        let base = Env { who: Who::Kind(kind), params: &params, ..Env::consts_only() };
        for f in &m.fields {
            if let Some(&first) = fields_seen.get(&f.key.name) {
                let d = dup(f.key.span, "field", &f.key.name, first);
                self.diags.push(d);
                continue;
            }
            fields_seen.insert(f.key.name.clone(), f.key.span);
            match (f.key.name.as_str(), &f.value) {
                ("pre", ast::FieldValue::Pred(e)) => {
                    let env = Env { state: true, input: true, part: Some("the precondition"), ..base };
                    prim.pre = self.pred(e, &env, "a precondition");
                }
                ("assume", ast::FieldValue::Pred(e)) => {
                    let env = Env { input: true, clock: true, part: Some("the assumption"), ..base };
                    prim.assume = self.pred(e, &env, "an assumption");
                }
                ("guarantee", ast::FieldValue::Pred(e)) => {
                    let env = Env { state: true, clock: true, old: true, part: Some("the guarantee"), ..base };
                    prim.guarantee = self.pred(e, &env, "a guarantee");
                }
                ("post", ast::FieldValue::Pred(e)) => {
                    let env = Env { state: true, input: true, old: true, part: Some("the postcondition"), ..base };
                    prim.post = self.pred(e, &env, "a postcondition");
                }
                ("footprint", ast::FieldValue::Footprint { point, pred }) => {
                    self.distinct_coordinates(point);
                    let names = [point[0].name.clone(), point[1].name.clone(), point[2].name.clone()];
                    let env = Env {
                        state: true,
                        clock: true,
                        old: true,
                        point: Some(&names),
                        part: Some("the footprint"),
                        ..base
                    };
                    let pred = self.pred(pred, &env, "a footprint");
                    prim.footprint = Some(Footprint { point: names.clone(), pred });
                }
                ("duration", ast::FieldValue::Duration { lo, hi }) => {
                    let env = Env { state: true, old: true, part: Some("the duration"), ..base };
                    let lo = self.expr(lo, &env);
                    self.expect_sort(&lo, &Sort::Real, "duration bound");
                    let hi = hi.as_ref().map(|h| self.expr(h, &env));
                    if let Some(h) = &hi {
                        self.expect_sort(h, &Sort::Real, "duration bound");
                    }
                    prim.duration = Duration { lo, hi };
                }
                ("interruptible", ast::FieldValue::Flag(b)) => {
                    prim.interruptible = *b;
                    interruptible_seen = true;
                }
                (key, _) => {
                    let known = ["pre", "assume", "guarantee", "post", "footprint", "duration", "interruptible"];
                    let help = if known.contains(&key) {
                        format!("write `{}`", field_shape(key))
                    } else {
                        "the fields are `pre`, `assume`, `guarantee`, `post`, `footprint(x, y, z)`, `duration` and `interruptible`".into()
                    };
                    self.err(Code::UnexpectedToken, f.key.span, format!("`{key}` is not a field of this form"), help);
                }
            }
        }
        if !interruptible_seen {
            self.err(
                Code::MissingField,
                m.name.span,
                format!("motion primitive `{}` does not say whether it is interruptible", m.name.name),
                "add `interruptible: true;` (a message may interrupt it) or `interruptible: false;`",
            );
        }
        let id = PrimId(self.prog.prims.len() as u32);
        self.prims.insert((kind, m.name.name.clone()), id);
        self.prog.prims.push(prim);
    }

    fn system(&mut self, s: &ast::SystemDecl) {
        if let Some((first, span)) = &self.prog.system {
            let d = dup(s.name.span, "system", &s.name.name, *span).with_note(format!("`{first}` is the first system"));
            self.diags.push(d);
            return;
        }
        self.prog.system = Some((s.name.name.clone(), s.name.span));
        // Names first, so qualified variables may name any participant.
        let mut ok = Vec::new();
        for p in &s.participants {
            if let Some(first) = self.prog.role_by_name(&p.name.name) {
                let d = dup(p.name.span, "participant", &p.name.name, self.prog.role(first).span);
                self.diags.push(d);
                continue;
            }
            let Some(kind) = self.kind_of_name(&p.kind) else {
                self.poisoned.insert(p.name.name.clone());
                continue;
            };
            let n_inputs = self.prog.kind(kind).inputs.len();
            self.prog.roles.push(Participant {
                name: p.name.name.clone(),
                kind,
                init: None,
                pose: Vec::new(),
                input_sources: vec![None; n_inputs],
                span: p.name.span,
            });
            ok.push((RoleId(self.prog.roles.len() as u32 - 1), p));
        }
        for (r, p) in ok {
            if let Some(init) = &p.init {
                let env = Env { qualified: false, ..Env::role(r, &[]) };
                let e = self.pred(init, &env, "an initial-state predicate");
                self.prog.roles[r.idx()].init = Some(e);
            }
            if let Some(pose) = &p.at {
                if pose.args.len() != 3 && pose.args.len() != 6 {
                    self.err(
                        Code::ArityMismatch,
                        pose.span,
                        format!("`pose` takes 3 or 6 arguments, found {}", pose.args.len()),
                        "write `pose(x, y, z)` or `pose(x, y, z, roll, pitch, yaw)` in metres and radians",
                    );
                }
                let args: Vec<Expr> = pose.args.iter().map(|a| self.expr(a, &Env::consts_only())).collect();
                for a in &args {
                    self.expect_sort(a, &Sort::Real, "pose coordinate");
                }
                self.prog.roles[r.idx()].pose = args;
            }
        }
    }

    /// Sec 3.1: each input variable is fed by the unique other participant that has a
    /// state variable of the same name.
    fn connect_inputs(&mut self) {
        for r in self.prog.role_ids().collect::<Vec<_>>() {
            let kind = self.prog.role(r).kind;
            let inputs = self.prog.kind(kind).inputs.clone();
            for (i, (w, _)) in inputs.iter().enumerate() {
                let sources: Vec<RoleId> = self
                    .prog
                    .role_ids()
                    .filter(|&q| q != r && self.prog.kind_of(q).state.iter().any(|(x, _)| x == w))
                    .collect();
                if sources.len() == 1 {
                    self.prog.roles[r.idx()].input_sources[i] = Some(sources[0]);
                    continue;
                }
                let name = self.prog.role_name(r).to_string();
                let span = self.prog.role(r).span;
                let msg = if sources.is_empty() {
                    format!("input `{w}` of `{name}` is not connected: no other participant has a state variable `{w}`")
                } else {
                    let names: Vec<_> = sources.iter().map(|q| format!("`{}`", self.prog.role_name(*q))).collect();
                    format!(
                        "input `{w}` of `{name}` is ambiguous: {} all have a state variable `{w}`",
                        names.join(", ")
                    )
                };
                self.err(
                    Code::UnconnectedInput,
                    span,
                    msg,
                    "make exactly one other participant's kind declare the state variable",
                );
            }
        }
    }

    fn role(&mut self, name: &ast::Ident) -> Option<RoleId> {
        match self.prog.role_by_name(&name.name) {
            Some(r) => Some(r),
            None if self.poisoned.contains(&name.name) => None,
            None => {
                let names: Vec<_> = self.prog.roles.iter().map(|p| format!("`{}`", p.name)).collect();
                let help = if names.is_empty() {
                    "declare participants in the `system` block".to_string()
                } else {
                    format!("the participants are {}", names.join(", "))
                };
                self.err(Code::UnknownParticipant, name.span, format!("unknown participant `{}`", name.name), help);
                None
            }
        }
    }

    /// Resolves `p: a(args)` (or a process's `a(args)`) for the kind of `role`.
    fn prim_app(&mut self, role: RoleId, call: &ast::PrimCall, values: &[ValueId]) -> Option<PrimApp> {
        let kind = self.prog.role(role).kind;
        let args: Vec<Expr> = call.args.iter().map(|a| self.expr(a, &Env::role(role, values))).collect();
        let Some(&prim) = self.prims.get(&(kind, call.name.name.clone())) else {
            let kname = self.prog.kind(kind).name.clone();
            let avail: Vec<_> =
                self.prog.prims.iter().filter(|p| p.kind == kind).map(|p| format!("`{}`", p.name)).collect();
            let help = if avail.is_empty() {
                format!(
                    "robot kind `{kname}` has no motion primitives; declare `motion {kname}.{}(...) {{ ... }}`",
                    call.name.name
                )
            } else {
                format!("`{kname}` has {}", avail.join(", "))
            };
            self.err(
                Code::UnknownPrimitive,
                call.name.span,
                format!("`{}` (a `{kname}`) has no motion primitive `{}`", self.prog.role_name(role), call.name.name),
                help,
            );
            return None;
        };
        let params = self.prog.prim(prim).params.clone();
        if params.len() != args.len() {
            let sig: Vec<_> = params.iter().map(|(n, s)| format!("{n}: {s}")).collect();
            self.err(
                Code::ArityMismatch,
                call.span,
                format!("`{}` takes {} argument(s), found {}", call.name.name, params.len(), args.len()),
                format!("its signature is `{}({})`", call.name.name, sig.join(", ")),
            );
            return None;
        }
        for (a, (n, s)) in args.iter().zip(&params) {
            self.expect_sort(a, s, &format!("argument `{n}`"));
        }
        Some(PrimApp { prim, args, loc: Loc(call.span) })
    }

    // ---- global types --------------------------------------------------------------

    fn choreography(&mut self, c: &ast::ChorDecl) {
        if let Some(first) = &self.prog.choreography {
            let d = dup(c.name.span, "choreography", &c.name.name, first.span);
            self.diags.push(d);
            return;
        }
        let mut cx = Scopes::default();
        let body = self.global(&c.body, &mut cx);
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

    /// The three coordinates of a footprint's or partition's point are three names:
    /// `partition(py, py, pz)` would read both `py`s as the first coordinate (x).
    fn distinct_coordinates(&mut self, point: &[ast::Ident]) {
        for (i, b) in point.iter().enumerate() {
            if let Some(first) = point[..i].iter().find(|f| f.name == b.name) {
                self.diags.push(dup(b.span, "coordinate", &b.name, first.span));
            }
        }
    }

    fn global(&mut self, g: &ast::Global, cx: &mut Scopes) -> Global {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.global_inner(g, cx))
    }

    fn global_inner(&mut self, g: &ast::Global, cx: &mut Scopes) -> Global {
        match g {
            ast::Global::Msg(m) => {
                let from = self.role(&m.from);
                let to = self.role(&m.to);
                let (Some(from), Some(to)) = (from, to) else { return Global::End(Loc(m.span)) };
                let guard = m.guard.as_ref().map(|gd| {
                    let env = Env::role(from, &cx.values);
                    self.pred(gd, &env, "a guard")
                });
                let payload = self.fields(&m.payload, from, ValueOrigin::Message { from, to }, &mut cx.values);
                Global::Msg(Msg {
                    from,
                    to,
                    guard,
                    label: m.label.name.clone(),
                    payload,
                    loc: Loc(m.span),
                    label_loc: Loc(m.label.span),
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
                Global::Seq(items.iter().map(|g| self.global(g, cx)).collect(), Loc(*span))
            }
            ast::Global::Choice(items, span) | ast::Global::Par(items, span) => {
                let mark = cx.values.len();
                let lowered = items
                    .iter()
                    .map(|g| {
                        cx.values.truncate(mark);
                        self.global(g, cx)
                    })
                    .collect();
                cx.values.truncate(mark);
                if matches!(g, ast::Global::Choice(..)) {
                    Global::Choice(lowered, Loc(*span))
                } else {
                    Global::Par(lowered, Loc(*span))
                }
            }
            ast::Global::Rec { var, params, body, span } => {
                let mark = cx.values.len();
                let params = self.rec_params(params, ValueOrigin::RecParam, Who::Nobody, &mut cx.values);
                cx.recs.push((var.name.clone(), params.len()));
                let body = self.global(body, cx);
                cx.recs.pop();
                cx.values.truncate(mark);
                Global::Rec { var: var.name.clone(), params, body: Box::new(body), loc: Loc(*span) }
            }
            ast::Global::Var { var, args, span } => {
                let args =
                    self.rec_var(var, args, *span, &cx.recs, Env { values: &cx.values.clone(), ..Env::consts_only() });
                Global::Var(RecVar { var: var.name.clone(), args, loc: Loc(*span) })
            }
            ast::Global::End(span) => Global::End(Loc(*span)),
        }
    }

    /// Lowers payload fields, pushing their value variables onto `values` (each field's
    /// refinement sees the fields before it and itself).
    fn fields(
        &mut self,
        fields: &[ast::Field],
        viewer: RoleId,
        origin: ValueOrigin,
        values: &mut Vec<ValueId>,
    ) -> Vec<Field> {
        let mut out = Vec::new();
        for f in fields {
            let sort = self.sort(&f.sort);
            let v = self.new_value(&f.name, sort.clone(), origin.clone());
            values.push(v);
            let refinement = f.refinement.as_ref().map(|r| {
                let env = Env::role(viewer, values);
                self.pred(r, &env, "a refinement")
            });
            out.push(Field { value: v, name: f.name.name.clone(), sort, refinement });
        }
        out
    }

    fn new_value(&mut self, name: &ast::Ident, sort: Sort, origin: ValueOrigin) -> ValueId {
        let id = ValueId(self.prog.values.len() as u32);
        self.prog.values.push(ValueVar { name: name.name.clone(), sort, origin, span: name.span });
        id
    }

    fn rec_params(
        &mut self,
        params: &[ast::RecParam],
        origin: ValueOrigin,
        who: Who,
        values: &mut Vec<ValueId>,
    ) -> Vec<RecParam> {
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
            let refinement = p.refinement.as_ref().map(|r| {
                let env = Env { values, ..env };
                self.pred(r, &env, "a refinement")
            });
            out.push(RecParam { value: v, name: p.name.name.clone(), sort, refinement, init });
        }
        out
    }

    fn rec_var(
        &mut self,
        var: &ast::Ident,
        args: &[ast::Expr],
        span: Span,
        recs: &[(String, usize)],
        env: Env,
    ) -> Vec<Expr> {
        let args: Vec<Expr> = args.iter().map(|a| self.expr(a, &env)).collect();
        match recs.iter().rev().find(|(n, _)| *n == var.name) {
            None => self.err(
                Code::UnboundRecursion,
                var.span,
                format!("recursion variable `{}` is not bound here", var.name),
                format!("bind it with `mu {}. ...` around this occurrence", var.name),
            ),
            Some((_, n)) if *n != args.len() => self.err(
                Code::ArityMismatch,
                span,
                format!("`{}` takes {n} argument(s), found {}", var.name, args.len()),
                "pass one argument per recursion parameter",
            ),
            _ => {}
        }
        args
    }

    // ---- local types ---------------------------------------------------------------

    fn local_def(&mut self, t: &ast::LocalDecl) {
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

    fn local(&mut self, t: &ast::Local, me: RoleId, cx: &mut Scopes) -> LocalRc {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || Arc::new(self.local_inner(t, me, cx)))
    }

    fn local_inner(&mut self, t: &ast::Local, me: RoleId, cx: &mut Scopes) -> Local {
        let mark = cx.values.len();
        let out = match t {
            ast::Local::Motion { prims, cont, span } => {
                let prims: Vec<PrimApp> =
                    prims.iter().filter_map(|c| self.prim_app(me, c, &cx.values.clone())).collect();
                let cont = self.local(cont, me, cx);
                Local::Motion { prims, cont, loc: Loc(*span) }
            }
            ast::Local::Send { branches, span } => {
                let mut out = Vec::new();
                for b in branches {
                    cx.values.truncate(mark);
                    let guard = b.guard.as_ref().map(|g| {
                        let env = Env::role(me, &cx.values);
                        self.pred(g, &env, "a guard")
                    });
                    let Some(to) = self.role(&b.to) else { continue };
                    let payload = self.fields(&b.payload, me, ValueOrigin::Message { from: me, to }, &mut cx.values);
                    let cont = self.local(&b.cont, me, cx);
                    out.push(SendBranch { guard, to, label: b.label.name.clone(), payload, cont, loc: Loc(b.span) });
                }
                Local::Send { branches: out, loc: Loc(*span) }
            }
            ast::Local::Recv { branches, default, span } => {
                let mut out = Vec::new();
                for b in branches {
                    cx.values.truncate(mark);
                    let Some(from) = self.role(&b.from) else { continue };
                    let payload = self.fields(&b.payload, me, ValueOrigin::Message { from, to: me }, &mut cx.values);
                    let cont = self.local(&b.cont, me, cx);
                    out.push(RecvBranch { from, label: b.label.name.clone(), payload, cont, loc: Loc(b.span) });
                }
                cx.values.truncate(mark);
                let default = default.as_ref().map(|(prims, cont)| {
                    let prims: Vec<PrimApp> =
                        prims.iter().filter_map(|c| self.prim_app(me, c, &cx.values.clone())).collect();
                    (prims, self.local(cont, me, cx))
                });
                Local::Recv { branches: out, default, loc: Loc(*span) }
            }
            ast::Local::Rec { var, params, body, span } => {
                let params = self.rec_params(params, ValueOrigin::RecParam, Who::Role(me), &mut cx.values);
                cx.recs.push((var.name.clone(), params.len()));
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

    // ---- processes -----------------------------------------------------------------

    fn process_def(&mut self, p: &ast::ProcessDecl) {
        let Some(role) = self.role(&p.role) else { return };
        if let Some(&first) = self.process_roles.get(&role) {
            let d = dup(p.role.span, "process for", &p.role.name, first);
            self.diags.push(d);
            return;
        }
        self.process_roles.insert(role, p.role.span);
        let mut cx = Scopes::default();
        if let Some(body) = self.process(&p.body, role, &mut cx) {
            self.prog.processes.push(ProcessDef { role, body, span: p.role.span });
        }
    }

    fn process(&mut self, p: &ast::Process, me: RoleId, cx: &mut Scopes) -> Option<Process> {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.process_inner(p, me, cx))
    }

    fn process_inner(&mut self, p: &ast::Process, me: RoleId, cx: &mut Scopes) -> Option<Process> {
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
                cx.recs.push((var.name.clone(), params.len()));
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
    fn process_sum(&mut self, parts: &[ast::Process], span: Span, me: RoleId, cx: &mut Scopes) -> Option<Process> {
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
                    for (i, b) in binders.iter().enumerate() {
                        if let Some(first) = binders[..i].iter().find(|f| f.name == b.name) {
                            self.diags.push(dup(b.span, "binder", &b.name, first.span));
                            ok = false;
                        }
                    }
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

    // ---- expressions ---------------------------------------------------------------

    /// Resolves a predicate and checks that it is boolean.
    fn pred(&mut self, e: &ast::Expr, env: &Env, what: &str) -> Expr {
        let r = self.expr(e, env);
        self.expect_sort(&r, &Sort::Bool, what);
        r
    }

    fn expect_sort(&mut self, e: &Expr, want: &Sort, what: &str) {
        if !e.sort.fits(want) {
            self.err(
                Code::SortMismatch,
                e.loc.0,
                format!("{what} must be of sort `{want}`, this is `{}`", e.sort),
                match want {
                    Sort::Bool => "write a comparison or a boolean combination".to_string(),
                    Sort::Real | Sort::Int => "write a numeric term".to_string(),
                    _ => format!("write a term of sort `{want}`"),
                },
            );
        }
    }

    fn expr(&mut self, e: &ast::Expr, env: &Env) -> Expr {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.expr_inner(e, env))
    }

    fn expr_inner(&mut self, e: &ast::Expr, env: &Env) -> Expr {
        let loc = Loc(e.span);
        let mk = |kind, sort| Expr { kind, sort, loc };
        match &e.kind {
            ast::ExprKind::Int(i) => mk(ExprKind::Int(*i), Sort::Int),
            ast::ExprKind::Real(r) => mk(ExprKind::Real(r.clone()), Sort::Real),
            ast::ExprKind::Bool(b) => mk(ExprKind::Bool(*b), Sort::Bool),
            ast::ExprKind::Error => mk(ExprKind::Bool(true), Sort::Any),
            ast::ExprKind::Var(name) => self.var(name, e.span, env),
            ast::ExprKind::Dot(base, field) => {
                if let ast::ExprKind::Var(b) = &base.kind {
                    if !self.is_local_name(b, env) {
                        if let Some(r) = self.prog.role_by_name(b) {
                            return self.role_var(r, field, e.span, env);
                        }
                        if !self.resolves(b, env) {
                            if !self.poisoned.contains(b) {
                                let names: Vec<_> = self.prog.roles.iter().map(|p| format!("`{}`", p.name)).collect();
                                self.err(
                                    Code::UnknownParticipant,
                                    base.span,
                                    format!("unknown participant `{b}` in `{b}.{}`", field.name),
                                    if names.is_empty() {
                                        "declare participants in the `system` block".to_string()
                                    } else {
                                        format!("the participants are {}", names.join(", "))
                                    },
                                );
                            }
                            return mk(ExprKind::Bool(true), Sort::Any);
                        }
                    }
                }
                let b = self.expr(base, env);
                if b.sort == Sort::Any {
                    return mk(ExprKind::Bool(true), Sort::Any);
                }
                let axis = match field.name.as_str() {
                    "x" => Some(0),
                    "y" => Some(1),
                    "z" => Some(2),
                    _ => None,
                };
                match axis {
                    Some(i) if b.sort.is_spatial() => mk(ExprKind::Component(Box::new(b), i), Sort::Real),
                    _ => {
                        self.err(
                            Code::SortMismatch,
                            field.span,
                            format!("`.{}` needs a point or a vector, this is `{}`", field.name, b.sort),
                            "components are `.x`, `.y`, `.z` of a `point` or `vector`; `Name.var` reads a participant's variable",
                        );
                        mk(ExprKind::Bool(true), Sort::Any)
                    }
                }
            }
            ast::ExprKind::Call(f, args) if f.name == "old" => self.old(f, args, e.span, env),
            ast::ExprKind::Call(f, args) => {
                let args: Vec<Expr> = args.iter().map(|a| self.expr(a, env)).collect();
                let Some(b) = Builtin::from_name(&f.name) else {
                    self.err(
                        Code::UnknownVariable,
                        f.span,
                        format!("unknown function `{}`", f.name),
                        "functions are sqrt, min, max, abs, sin, cos, old, point, vector, dot, norm2",
                    );
                    return mk(ExprKind::Bool(true), Sort::Any);
                };
                if args.len() != b.arity() {
                    self.err(
                        Code::ArityMismatch,
                        e.span,
                        format!("`{}` takes {} argument(s), found {}", f.name, b.arity(), args.len()),
                        "see LANGUAGE.md, Expressions",
                    );
                    return mk(ExprKind::Bool(true), Sort::Any);
                }
                let sort = match b {
                    Builtin::Dot | Builtin::Norm2 => {
                        for a in &args {
                            self.expect_sort_spatial(a);
                        }
                        Sort::Real
                    }
                    Builtin::Point | Builtin::Vector => {
                        for a in &args {
                            self.expect_sort(a, &Sort::Real, "a coordinate");
                        }
                        if b == Builtin::Point {
                            Sort::Point
                        } else {
                            Sort::Vector
                        }
                    }
                    Builtin::Abs | Builtin::Min | Builtin::Max => {
                        for a in &args {
                            self.expect_sort(a, &Sort::Real, &format!("an argument of `{}`", f.name));
                        }
                        if args.iter().all(|a| a.sort == Sort::Int) {
                            Sort::Int
                        } else {
                            Sort::Real
                        }
                    }
                    Builtin::Sqrt | Builtin::Sin | Builtin::Cos => {
                        self.expect_sort(&args[0], &Sort::Real, &format!("the argument of `{}`", f.name));
                        Sort::Real
                    }
                    // Only the parser makes this call (`pi` is reserved, `pi()` does not parse).
                    Builtin::Pi => Sort::Real,
                };
                mk(ExprKind::Call(b, args), sort)
            }
            ast::ExprKind::Unary(op, a) => {
                let a = self.expr(a, env);
                let sort = match op {
                    UnOp::Not => {
                        self.expect_sort(&a, &Sort::Bool, "the operand of `!`");
                        Sort::Bool
                    }
                    UnOp::Neg if a.sort == Sort::Vector => Sort::Vector,
                    UnOp::Neg => {
                        self.expect_sort(&a, &Sort::Real, "the operand of `-`");
                        a.sort.clone()
                    }
                };
                mk(ExprKind::Unary(*op, Box::new(a)), sort)
            }
            ast::ExprKind::Binary(op, a, b) => {
                let a = self.expr(a, env);
                let b = self.expr(b, env);
                let sort = self.binary_sort(*op, &a, &b);
                mk(ExprKind::Binary(*op, Box::new(a), Box::new(b)), sort)
            }
            ast::ExprKind::If(c, a, b) => {
                let c = self.pred(c, env, "a condition");
                let a = self.expr(a, env);
                let b = self.expr(b, env);
                let sort = if a.sort.fits(&b.sort) {
                    b.sort.clone()
                } else if b.sort.fits(&a.sort) {
                    a.sort.clone()
                } else {
                    self.err(
                        Code::SortMismatch,
                        b.loc.0,
                        format!("the branches of `if` have sorts `{}` and `{}`", a.sort, b.sort),
                        "both branches must have the same sort",
                    );
                    Sort::Any
                };
                mk(ExprKind::If(Box::new(c), Box::new(a), Box::new(b)), sort)
            }
            ast::ExprKind::Tuple(items) => {
                let items: Vec<Expr> = items.iter().map(|a| self.expr(a, env)).collect();
                let sort = Sort::Product(items.iter().map(|i| i.sort.clone()).collect());
                mk(ExprKind::Tuple(items), sort)
            }
        }
    }

    fn expect_sort_spatial(&mut self, a: &Expr) {
        if !a.sort.is_spatial() {
            self.err(
                Code::SortMismatch,
                a.loc.0,
                format!("expected a `point` or `vector`, this is `{}`", a.sort),
                "build one with `point(x, y, z)` or `vector(x, y, z)`",
            );
        }
    }

    fn binary_sort(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Sort {
        use BinOp::*;
        match op {
            And | Or | Implies => {
                self.expect_sort(a, &Sort::Bool, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Bool, &format!("the right operand of `{}`", op.symbol()));
                Sort::Bool
            }
            Eq | Ne => {
                if !a.sort.fits(&b.sort) && !b.sort.fits(&a.sort) {
                    self.err(
                        Code::SortMismatch,
                        b.loc.0,
                        format!("cannot compare `{}` with `{}`", a.sort, b.sort),
                        "both sides of `==` must have the same sort",
                    );
                }
                Sort::Bool
            }
            Lt | Le | Gt | Ge => {
                self.expect_sort(a, &Sort::Real, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Real, &format!("the right operand of `{}`", op.symbol()));
                Sort::Bool
            }
            Pow => {
                self.expect_sort(a, &Sort::Real, "the base of `^`");
                if !matches!(b.kind, ExprKind::Int(n) if (0..=64).contains(&n)) {
                    self.err(
                        Code::SortMismatch,
                        b.loc.0,
                        "the exponent of `^` must be an integer literal between 0 and 64",
                        "use `sqrt` for square roots; other powers are not supported",
                    );
                }
                a.sort.clone()
            }
            Add | Sub if a.sort.is_spatial() && b.sort.is_spatial() && a.sort != Sort::Any => {
                match (op, &a.sort, &b.sort) {
                    (Sub, Sort::Point, Sort::Point) => Sort::Vector,
                    (_, Sort::Point, Sort::Vector) => Sort::Point,
                    (_, Sort::Vector, Sort::Vector) => Sort::Vector,
                    _ => {
                        self.err(
                            Code::SortMismatch,
                            b.loc.0,
                            format!("cannot apply `{}` to `{}` and `{}`", op.symbol(), a.sort, b.sort),
                            "point - point is a vector; point + vector is a point; vectors add",
                        );
                        Sort::Any
                    }
                }
            }
            Mul if a.sort.is_numeric() && b.sort == Sort::Vector => Sort::Vector,
            Mul if a.sort == Sort::Vector && b.sort.is_numeric() => Sort::Vector,
            Add | Sub | Mul | Div => {
                self.expect_sort(a, &Sort::Real, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Real, &format!("the right operand of `{}`", op.symbol()));
                if op == Div || a.sort == Sort::Real || b.sort == Sort::Real {
                    Sort::Real
                } else if a.sort == Sort::Any || b.sort == Sort::Any {
                    Sort::Any
                } else {
                    Sort::Int
                }
            }
        }
    }

    /// Whether `name` denotes something other than a participant in this environment.
    fn is_local_name(&self, name: &str, env: &Env) -> bool {
        env.values.iter().any(|v| self.prog.value(*v).name == name)
            || env.params.iter().any(|(n, _)| n == name)
            || env.point.is_some_and(|p| p.iter().any(|n| n == name))
    }

    /// Whether an unqualified name resolves to anything in `env`.
    fn resolves(&self, name: &str, env: &Env) -> bool {
        if self.is_local_name(name, env) || self.consts.contains_key(name) || (name == "clock" && env.part.is_some()) {
            return true;
        }
        self.own_kind(env).is_some_and(|k| self.prog.kind(k).slot(name).is_some())
    }

    fn own_kind(&self, env: &Env) -> Option<KindId> {
        match env.who {
            Who::Kind(k) => Some(k),
            Who::Role(r) => Some(self.prog.role(r).kind),
            Who::Nobody => None,
        }
    }

    fn var(&mut self, name: &str, span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let mk = |v: Var, sort: Sort| Expr { kind: ExprKind::Var(v), sort, loc };
        if let Some(v) = env.values.iter().rev().find(|v| self.prog.value(**v).name == name) {
            let vv = self.prog.value(*v);
            return mk(Var::Value(*v, vv.name.clone()), vv.sort.clone());
        }
        if let Some(i) = env.params.iter().position(|(n, _)| n == name) {
            return mk(Var::Param(i), env.params[i].1.clone());
        }
        if let Some(i) = env.point.and_then(|p| p.iter().position(|n| n == name)) {
            return mk(Var::Point(i), Sort::Real);
        }
        if name == "clock" && env.part.is_some() {
            if !env.clock {
                self.not_allowed(span, "`clock`", env);
            }
            return mk(Var::Clock, Sort::Real);
        }
        if let Some(kind) = self.own_kind(env) {
            if let Some((slot, sort)) = self.prog.kind(kind).slot(name) {
                let sort = sort.clone();
                let allowed = match slot {
                    Slot::State(_) => env.state,
                    Slot::Input(_) => env.input,
                };
                if !allowed {
                    let what = match slot {
                        Slot::State(_) => format!("state variable `{name}`"),
                        Slot::Input(_) => format!("input variable `{name}`"),
                    };
                    self.not_allowed(span, &what, env);
                }
                return match env.who {
                    Who::Role(r) => mk(Var::Role(r, slot), sort),
                    _ => mk(Var::Own(slot), sort),
                };
            }
        }
        if let Some(&c) = self.consts.get(name) {
            return mk(Var::Const(c), self.prog.consts[c.idx()].sort.clone());
        }
        let mut help = "declare it as a `const`, a parameter, a robot variable, or bind it in a message".to_string();
        if self.prog.role_by_name(name).is_some() {
            help = format!("`{name}` is a participant; write `{name}.var` for one of its variables");
        } else if let Who::Role(r) = env.who {
            let owners: Vec<_> = self
                .prog
                .role_ids()
                .filter(|q| {
                    self.prog.kind_of(*q).state.iter().chain(&self.prog.kind_of(*q).inputs).any(|(n, _)| n == name)
                })
                .map(|q| format!("`{}.{name}`", self.prog.role_name(q)))
                .collect();
            if !owners.is_empty() {
                help = format!(
                    "`{}` has no variable `{name}`; did you mean {}?",
                    self.prog.role_name(r),
                    owners.join(" or ")
                );
            }
        }
        self.err(Code::UnknownVariable, span, format!("unknown variable `{name}`"), help);
        Expr { kind: ExprKind::Bool(true), sort: Sort::Any, loc }
    }

    fn not_allowed(&mut self, span: Span, what: &str, env: &Env) {
        let part = env.part.unwrap_or("this expression");
        if part == "a partition" {
            return self.err(
                Code::VariableNotAllowed,
                span,
                format!("a partition's region cannot read {what}"),
                "a region is a fixed part of the world: it reads its point and constants only (Sec 3.4, ∃ FP1, FP2)",
            );
        }
        let reads = match part {
            "the precondition" => "state and input variables",
            "the assumption" => "input variables and `clock`",
            "the guarantee" => "state variables, `old(x)` and `clock`",
            "the postcondition" => "state and input variables and `old(x)`",
            "the footprint" => "state variables, `old(x)`, its point and `clock`",
            "the duration" => "parameters, constants and the initial state",
            _ => "parameters and constants",
        };
        self.err(
            Code::VariableNotAllowed,
            span,
            format!("{part} of a motion primitive cannot read {what}"),
            format!("Def 3.4: {part} reads {reads} (besides parameters and constants)"),
        );
    }

    fn role_var(&mut self, r: RoleId, field: &ast::Ident, span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        if !env.qualified {
            self.err(
                Code::UnknownVariable,
                span,
                format!(
                    "`{}.{}` names a participant's variable, which is not visible here",
                    self.prog.role_name(r),
                    field.name
                ),
                "contracts and initial states read their own robot's variables unqualified",
            );
            return Expr { kind: ExprKind::Bool(true), sort: Sort::Any, loc };
        }
        let k = self.prog.kind_of(r);
        match k.slot(&field.name) {
            Some((slot, sort)) => Expr { kind: ExprKind::Var(Var::Role(r, slot)), sort: sort.clone(), loc },
            None => {
                let vars: Vec<_> = k.state.iter().chain(&k.inputs).map(|(n, _)| format!("`{n}`")).collect();
                let kname = k.name.clone();
                self.err(
                    Code::UnknownVariable,
                    field.span,
                    format!("`{}` (a `{kname}`) has no variable `{}`", self.prog.role_name(r), field.name),
                    if vars.is_empty() {
                        format!("`{kname}` declares no variables")
                    } else {
                        format!("its variables are {}", vars.join(", "))
                    },
                );
                Expr { kind: ExprKind::Bool(true), sort: Sort::Any, loc }
            }
        }
    }

    fn old(&mut self, f: &ast::Ident, args: &[ast::Expr], span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let bad = Expr { kind: ExprKind::Bool(true), sort: Sort::Any, loc };
        if !env.old {
            self.not_allowed(f.span, "`old(...)`", env);
            return bad;
        }
        let name = match args {
            [ast::Expr { kind: ast::ExprKind::Var(n), .. }] => n,
            _ => {
                self.err(
                    Code::ArityMismatch,
                    span,
                    "`old` takes one state variable",
                    "write `old(x)` for a state variable `x`",
                );
                return bad;
            }
        };
        let Some(kind) = self.own_kind(env) else { return bad };
        match self.prog.kind(kind).state.iter().position(|(n, _)| n == name) {
            Some(i) => Expr { kind: ExprKind::Var(Var::Old(i)), sort: self.prog.kind(kind).state[i].1.clone(), loc },
            None => {
                self.err(
                    Code::UnknownVariable,
                    args[0].span,
                    format!("`old({name})`: `{name}` is not a state variable of `{}`", self.prog.kind(kind).name),
                    "`old` reads the value a state variable had when the motion started",
                );
                bad
            }
        }
    }
}

fn field_shape(key: &str) -> &'static str {
    match key {
        "footprint" => "footprint(px, py, pz): PREDICATE;",
        "duration" => "duration: [LO, HI];",
        "interruptible" => "interruptible: true;",
        _ => "KEY: PREDICATE;",
    }
}

fn flatten_sum<'a>(parts: &'a [ast::Process], out: &mut Vec<&'a ast::Process>) {
    for p in parts {
        match p {
            ast::Process::Sum(inner, _) => flatten_sum(inner, out),
            other => out.push(other),
        }
    }
}

/// Value variables and recursion variables in scope while lowering a type or process.
#[derive(Default)]
struct Scopes {
    values: Vec<ValueId>,
    recs: Vec<(String, usize)>,
}

/// The variable names an expression mentions, with their spans (an explicit stack: the
/// expression may be up to the parser's nesting limit deep).
fn const_refs(e: &ast::Expr) -> Vec<(&str, Span)> {
    let mut out = Vec::new();
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        match &e.kind {
            ast::ExprKind::Var(name) => out.push((name.as_str(), e.span)),
            ast::ExprKind::Dot(a, _) | ast::ExprKind::Unary(_, a) => stack.push(a),
            ast::ExprKind::Binary(_, a, b) => stack.extend([&**a, &**b]),
            ast::ExprKind::If(a, b, c) => stack.extend([&**a, &**b, &**c]),
            ast::ExprKind::Call(_, args) | ast::ExprKind::Tuple(args) => stack.extend(args.iter()),
            ast::ExprKind::Int(_) | ast::ExprKind::Real(_) | ast::ExprKind::Bool(_) | ast::ExprKind::Error => {}
        }
    }
    out
}

/// The constants in an order where each comes after those its value mentions (a depth-first
/// post-order, otherwise the order of the files), and the cycles found, each as the
/// indices along it. A name declared twice refers to its first declaration.
fn const_order(consts: &[&ast::ConstDecl]) -> (Vec<usize>, Vec<Vec<usize>>) {
    let mut first: HashMap<&str, usize> = HashMap::new();
    for (i, c) in consts.iter().enumerate() {
        first.entry(c.name.name.as_str()).or_insert(i);
    }
    let deps: Vec<Vec<usize>> = consts
        .iter()
        .map(|c| {
            let mut d: Vec<usize> = const_refs(&c.value).iter().filter_map(|(n, _)| first.get(n).copied()).collect();
            d.sort_unstable();
            d.dedup();
            d
        })
        .collect();
    // 0 = not visited, 1 = on the current path, 2 = done.
    let mut state = vec![0u8; consts.len()];
    let mut order = Vec::with_capacity(consts.len());
    let mut cycles = Vec::new();
    for root in 0..consts.len() {
        if state[root] != 0 {
            continue;
        }
        let mut path: Vec<(usize, usize)> = vec![(root, 0)];
        state[root] = 1;
        while let Some((node, next)) = path.last_mut().map(|(n, k)| (*n, k)) {
            if let Some(&dep) = deps[node].get(*next) {
                *next += 1;
                match state[dep] {
                    0 => {
                        state[dep] = 1;
                        path.push((dep, 0));
                    }
                    1 => {
                        let at = path.iter().position(|&(n, _)| n == dep).unwrap_or(0);
                        cycles.push(path[at..].iter().map(|&(n, _)| n).collect());
                    }
                    _ => {}
                }
            } else {
                state[node] = 2;
                order.push(node);
                path.pop();
            }
        }
    }
    (order, cycles)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::source::{FileId, SourceDb};

    /// Parses and lowers one source text; for tests of later stages too.
    /// Lowers `src` (which must be clean) and returns the guard of the choreography's first
    /// message, which must be a sequence starting with a guarded message.
    pub(crate) fn first_guard(src: &str) -> (Program, crate::hir::Expr) {
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("a sequence")
        };
        let crate::hir::Global::Msg(m) = &items[0] else { panic!("a message") };
        let g = m.guard.clone().expect("guard");
        (prog, g)
    }

    pub(crate) fn lower_src(src: &str) -> (Program, Vec<Diagnostic>) {
        let mut db = SourceDb::new();
        let id = db.add("test.chor", src);
        let (f, mut d) = crate::syntax::parser::parse(id, src);
        assert!(d.is_empty(), "parse errors: {d:?}");
        let (p, d2) = lower(&Parsed { files: vec![(FileId(id.0), f)] });
        d.extend(d2);
        (p, d)
    }

    pub(crate) const HEADER: &str = "
        const amax = 0.5;
        robot Cart { state x: real, v: real; invariant: v >= 0; }
        robot Arm { state h: real; input x: real; }
        motion Cart.move(xf: real) { interruptible: false; pre: xf > x && v == 0; post: x == xf; duration: [2 * sqrt(xf / amax), inf]; }
        motion Cart.idle { interruptible: true; guarantee: x == old(x); }
        motion Arm.work { interruptible: true; assume: x <= 1.0; footprint(px, py, pz): pz >= 0 && clock >= 0; }
        system S {
          participant C: Cart { init: x == 0 && v == 0; at: pose(0, 0, 0); }
          participant A: Arm { at: pose(2, 1, 0); }
        }
    ";

    fn codes(d: &[Diagnostic]) -> Vec<Code> {
        d.iter().map(|d| d.code).collect()
    }

    #[test]
    fn a_complete_program_lowers_cleanly() {
        let src = format!(
            "{HEADER} choreography G = mu t. C -> A : [x >= 0] go(tf: real {{ tf > C.x }}). dt<C: move(tf), A: work>. A -> C: done. t;
             process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k;
             process A = mu k. C?go(y).dt<work>.C!done.k;"
        );
        let (p, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(p.roles.len(), 2);
        assert_eq!(p.roles[1].input_sources, vec![Some(RoleId(0))]);
        assert_eq!(p.processes.len(), 2);
        let Some(c) = &p.choreography else { panic!() };
        assert!(matches!(c.body, Global::Rec { .. }));
    }

    #[test]
    fn unknown_names_are_reported_with_their_kind() {
        let src = format!(
            "{HEADER} choreography G = C -> B : go. dt<C: fly, A: work>. t;
             process C = dt<idle>.Z;"
        );
        let (_, d) = lower_src(&src);
        assert_eq!(
            codes(&d),
            vec![Code::UnknownParticipant, Code::UnknownPrimitive, Code::UnboundRecursion, Code::UnboundRecursion]
        );
    }

    #[test]
    fn contract_parts_read_only_what_def_3_4_allows() {
        let src = "robot R { state x: real; input w: real; }
                   motion R.m { interruptible: true; assume: x > 0; guarantee: w > 0; pre: clock > 0; post: old(x) == x; }";
        let (_, d) = lower_src(src);
        let d: Vec<_> = d.into_iter().filter(|d| d.code != Code::MissingItem).collect();
        assert_eq!(codes(&d), vec![Code::VariableNotAllowed; 3], "{d:?}");
        assert!(d[0].message.contains("assumption"));
    }

    #[test]
    fn pi_is_a_reserved_real_constant_that_prints_back() {
        let src = "const half_pi: real = pi / 2; robot R { state a: real; }
                   system S { participant A: R { init: a == -pi + half_pi; } } choreography G = end;";
        let (p, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let half = &p.consts[0].value;
        assert_eq!(half.sort, Sort::Real);
        assert!(matches!(&half.kind, ExprKind::Binary(_, a, _) if matches!(a.kind, ExprKind::Call(Builtin::Pi, _))));
        let init = p.roles[0].init.as_ref().expect("init");
        let text = crate::hir::print::expr(&p, None, init);
        assert_eq!(text, "A.a == -pi + half_pi");
        // The printed text reads back to the same term.
        let again = format!(
            "const half_pi: real = pi / 2; robot R {{ state a: real; }}
             system S {{ participant A: R {{ init: {}; }} }} choreography G = end;",
            text.replace("A.a", "a")
        );
        let (q, d) = lower_src(&again);
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(q.roles[0].init.as_ref().map(|e| crate::hir::print::expr(&q, None, e)), Some(text));
        // `pi` cannot be redefined or called.
        for bad in ["const pi: real = 3;", "const x = pi();", "robot R { state pi: real; }"] {
            let mut db = SourceDb::new();
            let id = db.add("t.chor", bad);
            let (_, d) = crate::syntax::parser::parse(id, bad);
            assert_eq!(codes(&d), vec![Code::UnexpectedToken], "{bad}: {d:?}");
        }
        let mut db = SourceDb::new();
        let id = db.add("t.chor", "const pi: real = 3;");
        let (_, d) = crate::syntax::parser::parse(id, "const pi: real = 3;");
        assert!(d[0].help.as_deref().is_some_and(|h| h.contains("built-in constant")), "{d:?}");
    }

    #[test]
    fn sorts_are_checked() {
        let src = format!("{HEADER} choreography G = C -> A : [x + true] go(n: int {{ n }}). end;");
        let (_, d) = lower_src(&src);
        assert!(codes(&d).iter().all(|c| *c == Code::SortMismatch), "{d:?}");
        assert_eq!(d.len(), 3, "{d:?}"); // `x + true`, the guard is not bool, `n` is not bool
    }

    #[test]
    fn missing_interruptible_and_duplicates() {
        let src =
            format!("{HEADER} motion Cart.idle {{ interruptible: true; }} motion Arm.j {{ pre: true; pre: true; }}");
        let (_, d) = lower_src(&src);
        let c = codes(&d);
        assert!(c.contains(&Code::Duplicate) && c.contains(&Code::MissingField), "{d:?}");
    }

    #[test]
    fn unconnected_inputs_are_reported() {
        let src = "robot R { input w: real; } system S { participant P: R; } choreography G = end;";
        let (_, d) = lower_src(src);
        assert_eq!(codes(&d), vec![Code::UnconnectedInput]);
    }

    #[test]
    fn a_library_file_has_no_system() {
        let (_, d) = lower_src("robot R { state x: real; }");
        assert_eq!(codes(&d), vec![Code::MissingItem]);
    }
}
