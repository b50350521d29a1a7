//! Items (LANGUAGE.md, Files, Robots, Motion primitives, Systems): `import`, `const`,
//! `robot` blocks, `motion` blocks with their contract fields, `system` blocks with
//! participants, and the pieces they share (sorts, variable declarations, payload
//! fields, recursion parameters, primitive calls). Each block recovers inside itself, so
//! one bad entry does not hide the rest.

use super::*;

impl Parser {
    pub(super) fn file(&mut self) -> File {
        let mut items = Vec::new();
        while !self.at_eof() {
            let before = self.pos;
            match self.item() {
                Ok(item) => items.push(item),
                Err(()) => {
                    self.recover(false);
                    if self.pos == before {
                        self.bump();
                    }
                }
            }
        }
        File { items }
    }

    pub(super) fn item(&mut self) -> PResult<Item> {
        let start = self.span();
        let kw =
            match self.peek() {
                Tok::Ident(k) if ITEM_KEYWORDS.contains(&k.as_str()) => k.clone(),
                _ => return self.error_expected(
                    "an item (`import`, `dialect`, `const`, `robot`, `motion`, `system`, `choreography`, `process` or `local`)",
                ),
            };
        self.bump();
        let item = match kw.as_str() {
            "import" => {
                let path = match self.peek().clone() {
                    Tok::Str(s) => {
                        self.bump();
                        s
                    }
                    _ => return self.error_expected("a file path in double quotes"),
                };
                self.expect_punct(";")?;
                Item::Import(Import { path, span: start.to(self.prev_span()) })
            }
            "dialect" => {
                let name = self.ident("a MAVLink dialect name (`common`, `ardupilotmega`, ...)")?;
                self.expect_punct(";")?;
                Item::Dialect(DialectDecl { name, span: start.to(self.prev_span()) })
            }
            "const" => {
                let name = self.ident("a constant name")?;
                let sort = if self.eat_punct(":") { Some(self.sort()?) } else { None };
                self.expect_punct("=")?;
                let value = self.expr()?;
                self.expect_punct(";")?;
                Item::Const(ConstDecl { name, sort, value, span: start.to(self.prev_span()) })
            }
            "robot" => Item::Robot(self.robot(start)?),
            "motion" => Item::Motion(self.motion(start)?),
            "system" => Item::System(self.system(start)?),
            "choreography" => {
                let name = self.ident("a choreography name")?;
                self.expect_punct("=")?;
                self.partitions.clear();
                let body = self.global()?;
                self.expect_punct(";")?;
                let partitions = std::mem::take(&mut self.partitions);
                Item::Choreography(ChorDecl { name, body, span: start.to(self.prev_span()), partitions })
            }
            "process" => {
                let role = self.ident("a participant name")?;
                self.expect_punct("=")?;
                let body = self.process()?;
                self.expect_punct(";")?;
                Item::Process(ProcessDecl { role, body, span: start.to(self.prev_span()) })
            }
            _ => {
                let role = self.ident("a participant name")?;
                self.expect_punct("=")?;
                let body = self.local()?;
                self.expect_punct(";")?;
                Item::Local(LocalDecl { role, body, span: start.to(self.prev_span()) })
            }
        };
        Ok(item)
    }

    /// Parses `{ entry* }` calling `entry` for each, recovering inside the block.
    pub(super) fn block(&mut self, mut entry: impl FnMut(&mut Parser) -> PResult<()>) -> PResult<()> {
        self.expect_punct("{")?;
        while !self.is_punct("}") && !self.at_eof() {
            let before = self.pos;
            if entry(self).is_err() {
                self.recover(true);
                if self.pos == before {
                    self.bump();
                }
            }
        }
        self.expect_punct("}")?;
        Ok(())
    }

    pub(super) fn robot(&mut self, start: Span) -> PResult<RobotDecl> {
        let name = self.ident("a robot kind name")?;
        let mut r = RobotDecl {
            name,
            state: vec![],
            inputs: vec![],
            geometry: vec![],
            mounts: vec![],
            invariant: None,
            span: start,
        };
        self.block(|p| {
            let key = p.ident("`state`, `input`, `geometry`, `mount` or `invariant`")?;
            match key.name.as_str() {
                "state" | "input" => {
                    let vars = p.var_decls(";")?;
                    p.expect_punct(";")?;
                    if key.name == "state" {
                        r.state.extend(vars)
                    } else {
                        r.inputs.extend(vars)
                    }
                }
                "geometry" => {
                    p.expect_punct(":")?;
                    let body = p.body()?;
                    p.expect_punct(";")?;
                    r.geometry.push(body);
                }
                "mount" => {
                    let name = p.ident("a mount name")?;
                    p.expect_punct(":")?;
                    let pose = p.pose()?;
                    p.expect_punct(";")?;
                    r.mounts.push(MountDecl { name, pose, span: key.span.to(p.prev_span()) });
                }
                "invariant" => {
                    p.expect_punct(":")?;
                    r.invariant = Some(p.expr()?);
                    p.expect_punct(";")?;
                }
                other => {
                    let d = Diagnostic::error(
                        Code::UnexpectedToken,
                        key.span,
                        format!("expected `state`, `input`, `geometry`, `mount` or `invariant`, found `{other}`"),
                    )
                    .with_help("a robot block declares its variables, geometry, mount points and invariant");
                    p.diags.push(d);
                    return Err(());
                }
            }
            Ok(())
        })?;
        r.span = start.to(self.prev_span());
        Ok(r)
    }

    /// A body: `part + part + ...`, each part `shape(args)` or `shape("file")`, optionally
    /// `at pose(...)`. Shape names and arities are checked by lowering (E0214).
    pub(super) fn body(&mut self) -> PResult<BodyAst> {
        let start = self.span();
        let mut parts = vec![self.part()?];
        while self.eat_punct("+") {
            parts.push(self.part()?);
        }
        Ok(BodyAst { parts, span: start.to(self.prev_span()) })
    }

    fn part(&mut self) -> PResult<PartAst> {
        let name =
            self.ident("a shape (`box`, `sphere`, `cylinder`, `capsule`, `urdf(\"file\")` or `mesh(\"file\")`)")?;
        self.expect_punct("(")?;
        let mut args = Vec::new();
        let mut path = None;
        if let Tok::Str(s) = self.peek().clone() {
            let span = self.bump().span;
            path = Some((s, span));
        } else {
            args = self.expr_list(")")?;
        }
        self.expect_punct(")")?;
        let shape = ShapeAst { span: name.span.to(self.prev_span()), name, args, path };
        let place = if self.eat_kw("at") { Some(self.pose()?) } else { None };
        Ok(PartAst { span: shape.span.to(self.prev_span()), shape, place })
    }

    /// `pose(e, ...)`; the number of arguments (3 or 6) is checked by lowering (E0204).
    pub(super) fn pose(&mut self) -> PResult<Pose> {
        let s = self.expect_kw("pose")?;
        self.expect_punct("(")?;
        let args = self.expr_list(")")?;
        self.expect_punct(")")?;
        Ok(Pose { args, span: s.to(self.prev_span()) })
    }

    /// `a: real, b: int` up to (not including) `end`.
    pub(super) fn var_decls(&mut self, end: &str) -> PResult<Vec<VarDecl>> {
        let mut out = Vec::new();
        if self.is_punct(end) {
            return Ok(out);
        }
        loop {
            let name = self.ident("a variable name")?;
            self.expect_punct(":")?;
            let sort = self.sort()?;
            out.push(VarDecl { name, sort });
            if !self.eat_punct(",") {
                return Ok(out);
            }
        }
    }

    pub(super) fn motion(&mut self, start: Span) -> PResult<MotionDecl> {
        let kind = self.ident("a robot kind")?;
        self.expect_punct(".")?;
        let name = self.ident("a motion primitive name")?;
        let mut params = Vec::new();
        if self.eat_punct("(") {
            params = self.var_decls(")")?;
            self.expect_punct(")")?;
        }
        let mut fields = Vec::new();
        self.block(|p| {
            let key = p.ident(
                "a contract field (`pre`, `assume`, `guarantee`, `post`, `footprint`, `duration`, `interruptible`)",
            )?;
            let value = match key.name.as_str() {
                "footprint" if p.eat_punct(":") => {
                    // A geometric footprint: the kind's own body, or shapes placed by state.
                    if p.is_kw("geometry") && !matches!(p.peek_at(1), Tok::Punct("(")) {
                        FieldValue::OwnGeometry(p.bump().span)
                    } else {
                        FieldValue::Body(p.body()?)
                    }
                }
                "footprint" => {
                    p.expect_punct("(")?;
                    let a = p.ident("a coordinate name")?;
                    p.expect_punct(",")?;
                    let b = p.ident("a coordinate name")?;
                    p.expect_punct(",")?;
                    let c = p.ident("a coordinate name")?;
                    p.expect_punct(")")?;
                    p.expect_punct(":")?;
                    FieldValue::Footprint { point: [a, b, c], pred: p.expr()? }
                }
                "duration" => {
                    p.expect_punct(":")?;
                    p.expect_punct("[")?;
                    let lo = p.expr()?;
                    p.expect_punct(",")?;
                    let hi = if p.is_kw("inf") && matches!(p.peek_at(1), Tok::Punct("]")) {
                        p.bump();
                        None
                    } else {
                        Some(p.expr()?)
                    };
                    p.expect_punct("]")?;
                    FieldValue::Duration { lo, hi }
                }
                "interruptible" => {
                    p.expect_punct(":")?;
                    if p.eat_kw("true") {
                        FieldValue::Flag(true)
                    } else if p.eat_kw("false") {
                        FieldValue::Flag(false)
                    } else {
                        return p.error_expected("`true` or `false`");
                    }
                }
                _ => {
                    p.expect_punct(":")?;
                    FieldValue::Pred(p.expr()?)
                }
            };
            p.expect_punct(";")?;
            fields.push(MotionField { span: key.span.to(p.prev_span()), key, value });
            Ok(())
        })?;
        Ok(MotionDecl { kind, name, params, fields, span: start.to(self.prev_span()) })
    }

    pub(super) fn system(&mut self, start: Span) -> PResult<SystemDecl> {
        let name = self.ident("a system name")?;
        let mut participants = Vec::new();
        let mut obstacles = Vec::new();
        let mut streams = Vec::new();
        self.block(|p| {
            if p.is_kw("obstacle") {
                obstacles.push(p.obstacle()?);
                return Ok(());
            }
            if p.is_kw("stream") {
                streams.push(p.stream()?);
                return Ok(());
            }
            if !p.is_kw("participant") {
                return p.error_expected("`participant`, `stream` or `obstacle`");
            }
            let pstart = p.bump().span;
            let name = p.ident("a participant name")?;
            // `participant GCS;` is a plain participant: no kind, nothing else to say.
            if p.eat_punct(";") {
                let span = pstart.to(p.prev_span());
                participants.push(ParticipantDecl { name, kind: None, init: None, at: None, on: Vec::new(), span });
                return Ok(());
            }
            if !p.is_punct(":") {
                return p.error_expected("`:` and a robot kind, or `;` for a plain participant");
            }
            p.bump();
            let kind = Some(p.ident("a robot kind")?);
            let mut part = ParticipantDecl { name, kind, init: None, at: None, on: Vec::new(), span: pstart };
            if !p.eat_punct(";") {
                p.block(|p| {
                    let key = p.ident("`init`, `at` or `on`")?;
                    p.expect_punct(":")?;
                    match key.name.as_str() {
                        "init" => part.init = Some(p.expr()?),
                        "at" => part.at = Some(p.pose()?),
                        "on" => {
                            let carrier = p.ident("a participant name (`on: Carrier.mount`)")?;
                            p.expect_punct(".")?;
                            let mount = p.ident("a mount name (`on: Carrier.mount`)")?;
                            part.on.push(OnDecl { span: key.span.to(mount.span), carrier, mount });
                        }
                        other => {
                            let d = Diagnostic::error(
                                Code::UnexpectedToken,
                                key.span,
                                format!("expected `init`, `at` or `on`, found `{other}`"),
                            )
                            .with_help(
                                "a participant block holds `init: PREDICATE;`, `at: pose(x, y, z);` and `on: Carrier.mount;`",
                            );
                            p.diags.push(d);
                            return Err(());
                        }
                    }
                    p.expect_punct(";")?;
                    Ok(())
                })?;
            }
            part.span = pstart.to(p.prev_span());
            participants.push(part);
            Ok(())
        })?;
        Ok(SystemDecl { name, participants, obstacles, streams, span: start.to(self.prev_span()) })
    }

    /// `stream FROM -> TO, ...: LABEL(fields);` (the keyword is next).
    fn stream(&mut self) -> PResult<StreamDecl> {
        let start = self.expect_kw("stream")?;
        let from = self.ident("the participant that sends the stream")?;
        self.expect_punct("->")?;
        let mut to = vec![self.ident("a participant that receives the stream")?];
        while self.eat_punct(",") {
            to.push(self.ident("a participant that receives the stream")?);
        }
        self.expect_punct(":")?;
        let label = self.label()?;
        let payload = if self.eat_punct("(") {
            let f = self.fields()?;
            self.expect_punct(")")?;
            f
        } else {
            Vec::new()
        };
        self.expect_punct(";")?;
        Ok(StreamDecl { from, to, label, payload, span: start.to(self.prev_span()) })
    }

    /// `obstacle Name { geometry: BODY; at: pose(...); }`.
    fn obstacle(&mut self) -> PResult<ObstacleDecl> {
        let start = self.expect_kw("obstacle")?;
        let name = self.ident("an obstacle name")?;
        let mut o = ObstacleDecl { name, geometry: Vec::new(), at: Vec::new(), span: start };
        self.block(|p| {
            let key = p.ident("`geometry` or `at`")?;
            p.expect_punct(":")?;
            match key.name.as_str() {
                "geometry" => o.geometry.push(p.body()?),
                "at" => o.at.push(p.pose()?),
                other => {
                    let d = Diagnostic::error(
                        Code::UnexpectedToken,
                        key.span,
                        format!("expected `geometry` or `at`, found `{other}`"),
                    )
                    .with_help("an obstacle block holds `geometry: SHAPES;` and `at: pose(x, y, z);`");
                    p.diags.push(d);
                    return Err(());
                }
            }
            p.expect_punct(";")?;
            Ok(())
        })?;
        o.span = start.to(self.prev_span());
        Ok(o)
    }

    pub(super) fn sort(&mut self) -> PResult<SortAst> {
        let start = self.span();
        if self.eat_punct("(") {
            let mut parts = vec![self.nested(Parser::sort)?];
            while self.eat_punct(",") {
                parts.push(self.nested(Parser::sort)?);
            }
            self.expect_punct(")")?;
            let span = start.to(self.prev_span());
            if parts.len() == 1 {
                return Ok(parts.pop().unwrap_or(SortAst { kind: SortKind::Unit, span }));
            }
            return Ok(SortAst { kind: SortKind::Product(parts), span });
        }
        let id = self.ident("a sort (`unit`, `bool`, `int`, `real`, `point`, `vector` or a product `(S, S)`)")?;
        let kind = match id.name.as_str() {
            "unit" => SortKind::Unit,
            "bool" => SortKind::Bool,
            "int" => SortKind::Int,
            "real" => SortKind::Real,
            "point" => SortKind::Point,
            "vector" => SortKind::Vector,
            "str" => SortKind::Str,
            other => SortKind::Named(other.to_string()),
        };
        Ok(SortAst { kind, span: id.span })
    }

    /// `(f: S {P}, g: S)` payload fields; the opening `(` is already consumed. The sort
    /// is optional and `f as b` renames the value: both are for MAVLink messages, whose
    /// fields have their sorts from the dialect (lowering reports a missing sort elsewhere).
    pub(super) fn fields(&mut self) -> PResult<Vec<Field>> {
        let mut out = Vec::new();
        if self.is_punct(")") {
            return Ok(out);
        }
        loop {
            let name = self.ident("a field name")?;
            let binder = if self.eat_kw("as") { Some(self.ident("a name for the field's value")?) } else { None };
            let sort = if self.eat_punct(":") { Some(self.sort()?) } else { None };
            let refinement = if self.eat_punct("{") {
                let e = self.expr()?;
                self.expect_punct("}")?;
                Some(e)
            } else {
                None
            };
            out.push(Field { name, binder, sort, refinement });
            if !self.eat_punct(",") {
                return Ok(out);
            }
        }
    }

    pub(super) fn rec_params(&mut self) -> PResult<Vec<RecParam>> {
        let mut out = Vec::new();
        if !self.eat_punct("(") {
            return Ok(out);
        }
        loop {
            let name = self.ident("a recursion parameter")?;
            self.expect_punct(":")?;
            let sort = self.sort()?;
            let refinement = if self.eat_punct("{") {
                let e = self.expr()?;
                self.expect_punct("}")?;
                Some(e)
            } else {
                None
            };
            self.expect_punct("=")?;
            let init = self.expr()?;
            out.push(RecParam { name, sort, refinement, init });
            if !self.eat_punct(",") {
                break;
            }
        }
        self.expect_punct(")")?;
        Ok(out)
    }

    pub(super) fn prim_call(&mut self) -> PResult<PrimCall> {
        let name = self.ident("a motion primitive")?;
        let mut args = Vec::new();
        if self.eat_punct("(") {
            args = self.expr_list(")")?;
            self.expect_punct(")")?;
        }
        Ok(PrimCall { span: name.span.to(self.prev_span()), name, args })
    }

    /// Optional `(e, ...)` after a name.
    pub(super) fn opt_args(&mut self) -> PResult<Vec<Expr>> {
        if self.eat_punct("(") {
            let args = self.expr_list(")")?;
            self.expect_punct(")")?;
            Ok(args)
        } else {
            Ok(Vec::new())
        }
    }
}
