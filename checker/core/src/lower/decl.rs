//! Declarations (LANGUAGE.md, Files, Robots, Systems; Sec 3.1): constants in dependency
//! order (E0213 for a cycle), sorts, robot kinds with their state and input variables
//! (X and W of Sec 3.1) and invariants, the system's participants with their initial
//! states and poses, and the connection of every input to the one participant whose
//! state feeds it (Sec 3.1). Duplicates are E0206.

use super::*;

impl Lowerer {
    /// Lowers the constants in dependency order, so that their order in the files does not
    /// matter (LANGUAGE.md), and reports each cycle once (E0213) instead of an unknown
    /// variable. A constant in a cycle is still lowered (its value then lacks the
    /// constant it depends on), so its uses elsewhere do not cascade into E0205s.
    pub(super) fn constants(&mut self, consts: &[&ast::ConstDecl]) {
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

    pub(super) fn constant(&mut self, c: &ast::ConstDecl) {
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
        if let Some((e, entry)) = self.prog.dialect.and_then(|d| d.entry(&c.name.name)) {
            let dialect = self.dialect_decl.as_ref().map(|(n, s)| (n.clone(), *s));
            let mut d = Diagnostic::error(
                Code::Duplicate,
                c.name.span,
                format!("constant `{}` is defined twice: it is an entry of the enum `{}`", c.name.name, e.name),
            )
            .with_note(format!("`{}` is {} in the dialect", c.name.name, entry.value))
            .with_help("rename the constant: in a program with a `dialect` every enum entry is an `int` constant");
            if let Some((name, span)) = dialect {
                d = d.with_label(span, format!("the dialect `{name}` defines it"));
            }
            self.diags.push(d);
            return;
        }
        let id = ConstId(self.prog.consts.len() as u32);
        self.consts.insert(c.name.name.clone(), id);
        self.const_spans.push(c.name.span);
        self.prog.consts.push(Const { name: c.name.name.clone(), sort, value, span: c.span });
    }

    pub(super) fn sort(&mut self, s: &ast::SortAst) -> Sort {
        match &s.kind {
            ast::SortKind::Unit => Sort::Unit,
            ast::SortKind::Bool => Sort::Bool,
            ast::SortKind::Int => Sort::Int,
            ast::SortKind::Real => Sort::Real,
            ast::SortKind::Point => Sort::Point,
            ast::SortKind::Vector => Sort::Vector,
            ast::SortKind::Str => Sort::Str,
            ast::SortKind::Product(parts) => {
                let parts: Vec<Sort> = parts.iter().map(|p| self.sort(p)).collect();
                if parts.contains(&Sort::Error) {
                    Sort::Error
                } else {
                    Sort::Product(parts)
                }
            }
            ast::SortKind::Named(n) => {
                self.err(
                    Code::SortMismatch,
                    s.span,
                    format!("unknown sort `{n}`"),
                    "sorts are `unit`, `bool`, `int`, `real`, `point`, `vector`, `str` and products `(S, S)`",
                );
                Sort::Error
            }
        }
    }

    pub(super) fn var_decls(
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
            self.hides_entry(&d.name);
            let sort = self.sort(&d.sort);
            out.push((d.name.name.clone(), sort));
        }
        out
    }

    pub(super) fn robot_kind(&mut self, r: &ast::RobotDecl) {
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
            body: None,
            mounts: Vec::new(),
            invariant: None,
            speed: None,
            span: r.span,
        });
    }

    pub(super) fn robot_invariant(&mut self, r: &ast::RobotDecl) {
        let Some(inv) = &r.invariant else { return };
        let Some(&kind) = self.kinds.get(&r.name.name) else { return };
        if self.kind_spans[kind.idx()] != r.name.span {
            return; // a duplicate, already reported
        }
        let env = Env { who: Who::Kind(kind), state: true, input: true, ..Env::consts_only() };
        let e = self.pred(inv, &env, "an invariant");
        self.prog.kinds[kind.idx()].invariant = Some(e);
    }

    /// The kind of plain participants (`participant GCS;`): no state, inputs, body, mounts,
    /// invariant or primitives. One for all of them, made on first use; its name
    /// ([`PLAIN_KIND`]) is not an identifier, so nothing written can name it.
    pub(super) fn plain_kind(&mut self) -> KindId {
        if let Some(k) = self.plain_kind {
            return k;
        }
        let id = KindId(self.prog.kinds.len() as u32);
        self.kind_spans.push(Span::default());
        self.prog.kinds.push(RobotKind {
            name: PLAIN_KIND.to_string(),
            state: Vec::new(),
            inputs: Vec::new(),
            body: None,
            mounts: Vec::new(),
            invariant: None,
            speed: None,
            span: Span::default(),
        });
        self.plain_kind = Some(id);
        id
    }

    pub(super) fn kind_of_name(&mut self, name: &ast::Ident) -> Option<KindId> {
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

    pub(super) fn system(&mut self, s: &ast::SystemDecl) {
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
            let kind = match &p.kind {
                Some(k) => self.kind_of_name(k),
                None => Some(self.plain_kind()),
            };
            let Some(kind) = kind else {
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
                mounted_on: None,
                span: p.name.span,
            });
            ok.push((RoleId(self.prog.roles.len() as u32 - 1), p));
        }
        // Obstacles before anything resolves participants, so that naming one is E0217.
        self.obstacles(s);
        for &(r, p) in &ok {
            if let Some(init) = &p.init {
                let env = Env { qualified: false, ..Env::role(r, &[]) };
                let e = self.pred(init, &env, "an initial-state predicate");
                self.prog.roles[r.idx()].init = Some(e);
            }
            if let Some(pose) = &p.at {
                self.pose_arity(pose);
                let args: Vec<Expr> = pose.args.iter().map(|a| self.expr(a, &Env::consts_only())).collect();
                for a in &args {
                    self.expect_sort(a, &Sort::Real, "pose coordinate");
                }
                self.prog.roles[r.idx()].pose = args;
            }
        }
        self.mounts(&ok);
    }

    /// Sec 3.1: each input variable is fed by the unique other participant that has a
    /// state variable of the same name.
    pub(super) fn connect_inputs(&mut self) {
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

    pub(super) fn role(&mut self, name: &ast::Ident) -> Option<RoleId> {
        match self.prog.role_by_name(&name.name) {
            Some(r) => Some(r),
            None if self.poisoned.contains(&name.name) => None,
            None if self.obstacle_as_role(&name.name, name.span) => None,
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
}

/// The variable names an expression mentions, with their spans (an explicit stack: the
/// expression may be up to the parser's nesting limit deep).
pub(super) fn const_refs(e: &ast::Expr) -> Vec<(&str, Span)> {
    let mut out = Vec::new();
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        match &e.kind {
            ast::ExprKind::Var(name) => out.push((name.as_str(), e.span)),
            ast::ExprKind::Dot(a, _) | ast::ExprKind::Unary(_, a) => stack.push(a),
            ast::ExprKind::Binary(_, a, b) => stack.extend([&**a, &**b]),
            ast::ExprKind::If(a, b, c) => stack.extend([&**a, &**b, &**c]),
            ast::ExprKind::Call(_, args) | ast::ExprKind::Tuple(args) => stack.extend(args.iter()),
            ast::ExprKind::Int(_)
            | ast::ExprKind::Real(_)
            | ast::ExprKind::Bool(_)
            | ast::ExprKind::Str(_)
            | ast::ExprKind::Error => {}
        }
    }
    out
}

/// The constants in an order where each comes after those its value mentions (a depth-first
/// post-order, otherwise the order of the files), and the cycles found, each as the
/// indices along it. A name declared twice refers to its first declaration.
pub(super) fn const_order(consts: &[&ast::ConstDecl]) -> (Vec<usize>, Vec<Vec<usize>>) {
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
