//! Motion primitives (LANGUAGE.md, Motion primitives; Def 3.4): a primitive's contract
//! `(Pre, A, G, Post, FP, D, ‡)`, each part resolved in the environment that fixes
//! which variables it may read (E0211 otherwise), and the application of a primitive
//! `a(args)` by a participant (its kind's primitive, one argument per parameter).

use super::*;

impl Lowerer {
    pub(super) fn motion(&mut self, m: &ast::MotionDecl) {
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
            footprint: Footprint::Everywhere,
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
                    prim.footprint = Footprint::Predicate(PointPred { point: names.clone(), pred });
                }
                ("footprint", f @ (ast::FieldValue::OwnGeometry(_) | ast::FieldValue::Body(_))) => {
                    if let Some(body) = self.footprint_body(kind, &params, f) {
                        let own = matches!(f, ast::FieldValue::OwnGeometry(_));
                        prim.footprint = Footprint::Solid { body, own };
                    }
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

    /// The three coordinates of a footprint's or partition's point are three names:
    /// `partition(py, py, pz)` would read both `py`s as the first coordinate (x).
    pub(super) fn distinct_coordinates(&mut self, point: &[ast::Ident]) {
        super::distinct("coordinate", point, &mut self.diags);
        for c in point {
            self.hides_entry(c);
        }
    }

    /// Resolves `p: a(args)` (or a process's `a(args)`) for the kind of `role`.
    pub(super) fn prim_app(&mut self, role: RoleId, call: &ast::PrimCall, values: &[ValueId]) -> Option<PrimApp> {
        let kind = self.prog.role(role).kind;
        let args: Vec<Expr> = call.args.iter().map(|a| self.expr(a, &Env::role(role, values))).collect();
        let Some(&prim) = self.prims.get(&(kind, call.name.name.clone())) else {
            if self.prog.is_plain(role) {
                let who = self.prog.role_name(role).to_string();
                self.err(
                    Code::UnknownPrimitive,
                    call.name.span,
                    format!("`{who}` is a plain participant: it has no motion primitive `{}`", call.name.name),
                    format!("a participant declared `participant {who};` only sends and receives messages; give it a robot kind (`participant {who}: Kind`) to move"),
                );
                return None;
            }
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
}

pub(super) fn field_shape(key: &str) -> &'static str {
    match key {
        "footprint" => "footprint(px, py, pz): PREDICATE;` or `footprint: SHAPES;",
        "duration" => "duration: [LO, HI];",
        "interruptible" => "interruptible: true;",
        _ => "KEY: PREDICATE;",
    }
}
