//! MAVLink messages (LANGUAGE.md, MAVLink messages): the `dialect NAME;` item,
//! message labels resolved in the dialect (E0232), payload fields checked against the
//! message (E0233-E0235), their sorts and wire ranges, commands
//! `COMMAND_LONG[MAV_CMD_X]` with parameters by label (E0237, E0238), labels keyed by a
//! string field `PARAM_VALUE["MC_PITCH_P"]` (E0237, E0236), enum entries as
//! `int` constants (interned on first use), and the guard against a binder hiding an
//! entry (E0240).
//!
//! What the dialect says of a field is conjoined to the user's refinement as
//! `implicit && user` ([`MavField`]): its wire range (`0 <= count && count <= 65535` for a
//! `uint16_t`) and, for a command's `command` field, the command. So every later stage
//! (Σ, typing, the SMT stage) assumes and checks the range as part of the refinement with
//! no code of its own: a value outside it cannot be sent, and a refinement that contradicts
//! it is unsatisfiable like any other.
//!
//! Enum entries are [`entries`]'s, float fields [`float`]'s.

use super::*;
use crate::dialect::{self, CmdParam, Dialect, Entry, Message, Wire};

/// A payload field resolved in its message: the message's field and, for a command
/// parameter, the dialect's parameter.
struct Resolved<'d> {
    field: &'d crate::dialect::Field,
    param: Option<&'d CmdParam>,
}

impl Lowerer {
    /// Resolves the `dialect` items before anything else (constants and binders are
    /// checked against its entries). One dialect per program; the same name twice is fine.
    pub(super) fn dialects(&mut self, items: &[&ast::Item]) {
        for it in items {
            let ast::Item::Dialect(d) = it else { continue };
            if let Some((first, span)) = &self.dialect_decl {
                if *first != d.name.name {
                    let d = Diagnostic::error(
                        Code::DialectConflict,
                        d.name.span,
                        format!("a second dialect `{}`: this program speaks `{first}` already", d.name.name),
                    )
                    .with_label(*span, format!("`{first}` is named here"))
                    .with_help(
                        "a program speaks one MAVLink dialect: keep one `dialect` item (a dialect such as `ardupilotmega` includes `common`)",
                    );
                    self.diags.push(d);
                }
                continue;
            }
            match dialect::builtin(&d.name.name) {
                Some(found) => {
                    self.prog.dialect = Some(found);
                    self.dialect_decl = Some((d.name.name.clone(), d.name.span));
                }
                None => {
                    let names = dialect::builtin_names();
                    let close = dialect::suggest(&d.name.name, names.iter().copied());
                    let mut help = format!("the bundled dialects are {}", quoted(names.iter().copied()));
                    if !close.is_empty() {
                        help = format!("did you mean {}? {help}", quoted(close.into_iter()));
                    }
                    self.err(Code::UnknownDialect, d.name.span, format!("unknown dialect `{}`", d.name.name), help);
                    // Poison: labels are not checked against a dialect that is not there.
                    self.dialect_decl = Some((d.name.name.clone(), d.name.span));
                    self.dialect_failed = true;
                }
            }
        }
    }

    /// The constant for an enum entry of the dialect named `name`, interned on first use
    /// (a dialect has thousands of entries; a program reads a few).
    pub(super) fn entry_const(&mut self, name: &str) -> Option<ConstId> {
        if let Some(&c) = self.entry_consts.get(name) {
            return Some(c);
        }
        let d = self.prog.dialect?;
        let (_, entry) = d.entry(name)?;
        let id = ConstId(self.prog.consts.len() as u32);
        let span = self.dialect_decl.as_ref().map(|(_, s)| *s).unwrap_or_default();
        let value = Expr { kind: ExprKind::Int(entry.value), sort: Sort::Int, loc: Loc(span) };
        self.prog.consts.push(Const { name: name.to_string(), sort: Sort::Int, value, span });
        self.const_spans.push(span);
        self.entry_consts.insert(name.to_string(), id);
        Some(id)
    }

    /// E0240: `name`, about to be bound (a payload binder, a recursion parameter, a received
    /// value, a primitive's parameter, a robot variable), is an enum entry of the dialect,
    /// which it would hide from every expression in its scope.
    pub(super) fn hides_entry(&mut self, name: &ast::Ident) {
        let Some(d) = self.prog.dialect else { return };
        if let Some((e, _)) = d.entry(&name.name) {
            let msg = format!("`{}` would hide the enum entry `{}` of `{}`", name.name, name.name, e.name);
            self.diags.push(
                Diagnostic::error(Code::ShadowsEntry, name.span, msg)
                    .with_help("choose another name: in a program with a `dialect` every enum entry is a constant"),
            );
        }
    }

    /// Lowers a message's label and payload: a MAVLink message in a program with a
    /// dialect, an ordinary label otherwise. Pushes the fields' values onto `values`.
    pub(super) fn message(
        &mut self,
        label: &ast::Ident,
        fields: &[ast::Field],
        viewer: RoleId,
        origin: ValueOrigin,
        values: &mut Vec<ValueId>,
    ) -> Vec<Field> {
        if self.dialect_failed {
            // The dialect was not found (E0230): bind the names, check nothing against it.
            return self.plain_fields(fields, viewer, origin, values);
        }
        let Some(d) = self.prog.dialect else {
            if label.name.contains('[') {
                self.err(
                    Code::BadKey,
                    label.span,
                    format!("`{}` names a MAVLink command or key, but this program names no dialect", label.name),
                    "add `dialect common;` (or the dialect your autopilot speaks) to the file",
                );
            }
            for f in fields {
                let what = if f.binder.is_some() { "`FIELD as NAME`" } else { "a field without a sort" };
                if f.binder.is_some() || f.sort.is_none() {
                    self.err(
                        Code::MissingSort,
                        f.name.span,
                        format!("{what} is only for MAVLink messages, and `{}` is not one", label.name),
                        format!(
                            "write `{}: SORT` (e.g. `{}: real`), or name a `dialect` for MAVLink messages",
                            f.name.name, f.name.name
                        ),
                    );
                }
            }
            return self.fields(fields, viewer, origin, values);
        };
        let (name, key) = dialect::split_label(&label.name);
        let Some(msg) = d.message(name) else {
            let close = dialect::suggest(name, d.messages.iter().map(|m| m.name.as_str()));
            let help = if close.is_empty() {
                format!("the messages of `{}` are MAVLink's, by their XML names (`HEARTBEAT`, `MISSION_COUNT`)", d.name)
            } else {
                format!("did you mean {}?", quoted(close.into_iter()))
            };
            self.err(
                Code::UnknownMessage,
                label.span,
                format!("`{name}` is not a message of the dialect `{}`", d.name),
                help,
            );
            return self.plain_fields(fields, viewer, origin, values);
        };
        self.deprecated(d, msg, label);
        let (command, key) = match key {
            None => (None, None),
            Some(dialect::LabelKey::Command(c)) => match self.command(d, msg, c, label) {
                Some(e) => (Some(e), None),
                None => return self.plain_fields(fields, viewer, origin, values),
            },
            Some(dialect::LabelKey::Name(k)) => match self.key(msg, k, label) {
                Some(f) => (None, Some((f.name.as_str(), k))),
                None => return self.plain_fields(fields, viewer, origin, values),
            },
        };
        super::distinct("payload field", fields.iter().map(|f| f.bound()), &mut self.diags);
        let mut seen: Vec<(&str, Span)> = Vec::new();
        let mut out = Vec::new();
        for f in fields {
            let Some(res) = self.resolve_field(d, msg, command, f) else {
                out.extend(self.plain_fields(std::slice::from_ref(f), viewer, origin.clone(), values));
                continue;
            };
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == res.field.name) {
                let d = dup(f.name.span, "payload field", &res.field.name, *first);
                self.diags.push(d);
            }
            seen.push((res.field.name.as_str(), f.name.span));
            let key = key.filter(|(field, _)| *field == res.field.name).map(|(_, k)| k);
            out.push(self.mav_field(f, &res, command, key, viewer, origin.clone(), values));
        }
        out
    }

    /// E0244 (a warning): `msg` is marked `<deprecated>` or `<superseded>` in the dialect.
    /// Once per message per program, at its first use, naming the replacement the XML gives
    /// (a message, or a command sent with COMMAND_LONG). Not an error: autopilots still send
    /// some (MISSION_REQUEST, MISSION_ITEM), and a protocol that must accept them says so.
    fn deprecated(&mut self, d: &'static Dialect, msg: &'static Message, label: &ast::Ident) {
        let Some(by) = &msg.deprecated else { return };
        if !self.deprecated_seen.insert(msg.name.clone()) {
            return;
        }
        let by = by.trim();
        let replacement = match (by, d.entry(by)) {
            ("" | "Nothing", _) => None,
            (_, Some((e, _))) if e.name == "MAV_CMD" => Some(format!("the command `{by}` (`COMMAND_LONG[{by}]`)")),
            _ => Some(format!("`{by}`")),
        };
        let (what, help) = match &replacement {
            Some(r) => (
                format!("`{}` is deprecated in `{}`: it is replaced by {r}", msg.name, d.name),
                format!("use {r} where the autopilots this protocol talks to support it; keep `{}` only where one still sends or expects it", msg.name),
            ),
            None => (
                format!("`{}` is deprecated in `{}`, with no replacement", msg.name, d.name),
                format!("keep `{}` only where an autopilot still sends or expects it", msg.name),
            ),
        };
        self.diags.push(Diagnostic {
            severity: crate::diag::Severity::Warning,
            ..Diagnostic::error(Code::DeprecatedMessage, label.span, what)
                .with_note("said once per message, at its first use; the protocol is checked as written")
                .with_help(help)
        });
    }

    /// `COMMAND_LONG[MAV_CMD_X]`: the message has a `command` field of enum `MAV_CMD` and
    /// `MAV_CMD_X` is an entry of it (E0237 otherwise).
    fn command(&mut self, d: &'static Dialect, msg: &Message, cmd: &str, label: &ast::Ident) -> Option<&'static Entry> {
        let takes = msg.field("command").is_some_and(|f| f.enum_name.as_deref() == Some("MAV_CMD"));
        if !takes {
            self.err(
                Code::BadKey,
                label.span,
                format!("`{}` has no `command` field: `{}[...]` names no command", msg.name, msg.name),
                "only command messages (`COMMAND_LONG`, `COMMAND_INT`) take a `[MAV_CMD_...]`",
            );
            return None;
        }
        match d.entry(cmd) {
            Some((e, entry)) if e.name == "MAV_CMD" => Some(entry),
            _ => {
                let cmds = d.enum_("MAV_CMD").map(|e| e.entries.iter().map(|x| x.name.as_str()).collect::<Vec<_>>());
                let close = dialect::suggest(cmd, cmds.unwrap_or_default().into_iter());
                let mut help = "write an entry of the enum `MAV_CMD` (`MAV_CMD_DO_PARACHUTE`)".to_string();
                if !close.is_empty() {
                    help = format!("did you mean {}?", quoted(close.into_iter()));
                }
                self.err(Code::BadKey, label.span, format!("`{cmd}` is not a `MAV_CMD` of `{}`", d.name), help);
                None
            }
        }
    }

    /// `PARAM_VALUE["MC_PITCH_P"]`: the message has one `char[N]` field (its key field,
    /// `Message::key_field`; E0237 otherwise) and the key fits in it (E0236 otherwise).
    fn key(&mut self, msg: &'static Message, key: &str, label: &ast::Ident) -> Option<&'static crate::dialect::Field> {
        let Some(field) = msg.key_field() else {
            let strings: Vec<&str> = msg.fields.iter().filter(|f| f.is_string()).map(|f| f.name.as_str()).collect();
            let what = match strings.len() {
                0 => format!("`{}` has no string field: `{}[\"{key}\"]` names no key", msg.name, msg.name),
                _ => format!(
                    "`{}` has several string fields ({}): `{}[\"{key}\"]` does not say which it fixes",
                    msg.name,
                    quoted(strings.into_iter()),
                    msg.name
                ),
            };
            self.err(
                Code::BadKey,
                label.span,
                what,
                "a key names a message with one `char[N]` field (`PARAM_VALUE[\"MC_PITCH_P\"]` fixes `param_id`); refine the field in the payload instead",
            );
            return None;
        };
        let n = field.array.unwrap_or(1) as usize;
        if key.len() > n {
            self.err(
                Code::StringTooLong,
                label.span,
                format!("the key \"{key}\" has {} characters, `{}` holds at most {n}", key.len(), field.name),
                "a `char[N]` field holds N characters: write the name as the autopilot spells it",
            );
            return None;
        }
        Some(field)
    }

    /// The message's field (or command parameter) a payload field names (E0233, E0235,
    /// E0238 otherwise, reported here).
    fn resolve_field(
        &mut self,
        d: &'static Dialect,
        msg: &'static Message,
        command: Option<&'static Entry>,
        f: &ast::Field,
    ) -> Option<Resolved<'static>> {
        let name = f.name.name.as_str();
        // A name that is a field of the message and the label of a parameter carried by
        // another field (COMMAND_INT's `frame`, MAV_CMD_DO_CHANGE_ALTITUDE's param2 "Frame")
        // is neither: the two differ in type and meaning, so the writer must say which.
        if let Some(c) = command {
            if let dialect::CommandField::Ambiguous { field, param } = dialect::command_field(msg, c, name) {
                self.err(
                    Code::UnknownField,
                    f.name.span,
                    format!(
                        "`{name}` names both the field `{}` of `{}` and parameter {} of `{}` (carried in `param{}`)",
                        field.name, msg.name, param.index, c.name, param.index
                    ),
                    format!("write `param{}` for the command's parameter; the message's own `{}` cannot be refined in a `{}[...]` payload that names it so", param.index, field.name, msg.name),
                );
                return None;
            }
        }
        // A command parameter by its label or `param<i>`: the message's field for index i.
        let by_param = command.and_then(|c| c.param_by_name(name)).map(|p| (param_field(msg, p.index), p));
        let res = match by_param {
            Some((Some(field), p)) => Resolved { field, param: Some(p) },
            _ => match msg.field(name) {
                Some(field) => {
                    let param = command.and_then(|c| {
                        let i = param_index(msg, &field.name)?;
                        c.params.iter().find(|p| p.index == i)
                    });
                    Resolved { field, param }
                }
                None => {
                    let mut names: Vec<&str> = msg.fields.iter().map(|x| x.name.as_str()).collect();
                    let labels: Vec<String> = command
                        .map(|c| c.param_names().into_iter().filter(|(_, p)| !p.reserved).map(|(n, _)| n).collect())
                        .unwrap_or_default();
                    names.extend(labels.iter().map(String::as_str));
                    let close = dialect::suggest(name, names.iter().copied());
                    let help = if close.is_empty() {
                        format!("its fields are {}", quoted(msg.fields.iter().map(|x| x.name.as_str())))
                    } else {
                        format!("did you mean {}?", quoted(close.into_iter()))
                    };
                    let what = match command {
                        Some(c) => format!("`{}[{}]`", msg.name, c.name),
                        None => format!("`{}`", msg.name),
                    };
                    self.err(Code::UnknownField, f.name.span, format!("{what} has no field `{name}`"), help);
                    let _ = d;
                    return None;
                }
            },
        };
        if let (Some(p), Some(c)) = (res.param, command) {
            if p.reserved {
                self.err(
                    Code::ReservedParam,
                    f.name.span,
                    format!("parameter {} of `{}` is reserved", p.index, c.name),
                    "remove it from the payload: a reserved parameter carries no value",
                );
                return None;
            }
        }
        if res.field.array.is_some() && res.field.wire != Wire::Char {
            self.err(
                Code::ArrayField,
                f.name.span,
                format!(
                    "`{}` is an array (`{}[{}]`), which mochi cannot read yet",
                    res.field.name,
                    wire_name(res.field.wire),
                    res.field.array.unwrap_or(0)
                ),
                "leave it out of the payload: a field not listed may have any value of its wire type",
            );
            return None;
        }
        Some(res)
    }

    /// Lowers one resolved MAVLink field: its value (sort from the wire type), the implicit
    /// part (wire range, fixed command, the key a keyed label fixes when `key` is this
    /// field's) and the user's refinement.
    #[allow(clippy::too_many_arguments)]
    fn mav_field(
        &mut self,
        f: &ast::Field,
        res: &Resolved<'static>,
        command: Option<&'static Entry>,
        key: Option<&str>,
        viewer: RoleId,
        origin: ValueOrigin,
        values: &mut Vec<ValueId>,
    ) -> Field {
        let wire = res.field.wire;
        let sort = match (wire, res.field.array) {
            (Wire::Char, _) => Sort::Str,
            (Wire::F32 | Wire::F64, _) => Sort::Real,
            _ => Sort::Int,
        };
        if let Some(written) = &f.sort {
            let want = self.sort(written);
            if want != sort && want != Sort::Error {
                self.err(
                    Code::WireSort,
                    written.span,
                    format!(
                        "`{}` is a `{}` on the wire, so its sort is `{sort}`, not `{want}`",
                        res.field.name,
                        wire_name(wire)
                    ),
                    format!("write `{}: {sort}` or leave the sort out", f.name.name),
                );
            }
        }
        let binder = f.bound();
        let v = self.new_value(binder, sort.clone(), origin);
        values.push(v);
        if sort == Sort::Str {
            self.prog.str_width.insert(v, res.field.array.unwrap_or(1));
        }
        let loc = Loc(f.name.span);
        let var = || Expr { kind: ExprKind::Var(Var::Value(v, binder.name.clone())), sort: sort.clone(), loc };
        let mut implicit = Vec::new();
        if let Some((lo, hi)) = wire.int_range() {
            let cmp = |op, a: Expr, b: Expr| Expr {
                kind: ExprKind::Binary(op, Box::new(a), Box::new(b)),
                sort: Sort::Bool,
                loc,
            };
            implicit.push(cmp(BinOp::Le, int_literal(lo, loc), var()));
            implicit.push(cmp(BinOp::Le, var(), int_literal(hi, loc)));
        }
        if let Some(format) = float_builtin(wire) {
            // A `float` field's value is a finite binary32 (a `double`'s a binary64): part
            // of its type, as the wire range is of an integer's. The receiver assumes it
            // (the encoder knows it of every value of the field), the progress check asks
            // for a payload of that format, and a process's [T-OUT] sends its literal
            // rounded to it (`typeck::out`).
            self.prog.wire_floats.insert(v, format);
            implicit.push(Expr { kind: ExprKind::Call(format, vec![var()]), sort: Sort::Bool, loc });
        }
        let fixed = matches!((command, res.field.name.as_str()), (Some(_), "command"));
        if let (Some(c), true) = (command, fixed) {
            let value = Expr { kind: ExprKind::Int(c.value), sort: Sort::Int, loc };
            implicit.push(Expr {
                kind: ExprKind::Binary(BinOp::Eq, Box::new(var()), Box::new(value)),
                sort: Sort::Bool,
                loc,
            });
        }
        if let Some(k) = key {
            // `PARAM_VALUE["MC_PITCH_P"]`: the key field is the key, as a fixed command's
            // `command` field is the command.
            let value = self.string(k, loc);
            implicit.push(Expr {
                kind: ExprKind::Binary(BinOp::Eq, Box::new(var()), Box::new(value)),
                sort: Sort::Bool,
                loc,
            });
        }
        let user = f.refinement.as_ref().map(|r| {
            let env = Env::role(viewer, values);
            self.pred(r, &env, "a refinement")
        });
        if let (Some(u), Some(n)) = (&user, self.prog.str_width.get(&v).copied()) {
            self.string_widths(v, &binder.name, n, u);
        }
        // The enum of the field, or of the command parameter it carries (COMMAND_LONG's
        // `param1` has none of its own; MAV_CMD_COMPONENT_ARM_DISARM's param1 is a MAV_BOOL).
        // A fixed command is an entry by construction.
        let enum_name = match res.param {
            Some(p) => p.enum_name.clone(),
            None => res.field.enum_name.clone(),
        };
        let mut entry = enum_name.filter(|_| !fixed && sort != Sort::Str).map(|enum_name| crate::hir::EnumCheck {
            enum_name,
            wire,
            at: loc,
        });
        if let Some(check) = &entry {
            // The field's type is the enum, as it is its wire type: the predicate is part of
            // the refinement (assumed by the receiver, proved by a process's [T-OUT]), last
            // of the implicit conjuncts (`refinement_without_entry` relies on it). One that
            // every value of the wire type satisfies (MAV_MODE_FLAG's eight flags in a
            // uint8_t) is left out, and the field has nothing to check.
            let (pred, _) = entry_predicate(d_of(self), check, &var());
            if pred.is_true() {
                entry = None;
            } else {
                implicit.push(pred);
            }
        }
        let implicit = (!implicit.is_empty()).then(|| crate::hir::expr::and_all(implicit, loc));
        let mav = MavField {
            field: res.field.name.clone(),
            written: f.name.name.clone(),
            implicit: implicit.is_some(),
            user: user.is_some(),
            entry,
        };
        let refinement = match (implicit, user) {
            (Some(i), Some(u)) => {
                Some(Expr { kind: ExprKind::Binary(BinOp::And, Box::new(i), Box::new(u)), sort: Sort::Bool, loc })
            }
            (i, u) => i.or(u),
        };
        Field { value: v, name: binder.name.clone(), sort, refinement, mav: Some(mav) }
    }

    /// E0236: a string literal compared with a `char[N]` field is longer than N.
    pub(super) fn string_fits(&mut self, a: &Expr, b: &Expr) {
        for (var, lit) in [(a, b), (b, a)] {
            let (ExprKind::Var(Var::Value(v, name)), ExprKind::Int(code)) = (&var.kind, &lit.kind) else { continue };
            if lit.sort != Sort::Str {
                continue;
            }
            let (Some(&n), Some(text)) = (self.prog.str_width.get(v), self.prog.string(*code)) else { continue };
            if text.len() > n as usize {
                let text = text.to_string();
                self.err(
                    Code::StringTooLong,
                    lit.loc.0,
                    format!("\"{text}\" has {} characters, `{name}` holds at most {n}", text.len()),
                    "a `char[N]` field holds N characters: write the name as the autopilot spells it",
                );
            }
        }
    }

    /// E0236: `f == e` in the refinement of a `char[N]` field `f`, where `e` may hold a
    /// longer string (a wider field's value, a loop parameter whose initial value is). No value of `f`
    /// equals a longer `e`, while the checks, to which a string is one value without a
    /// length, would find one: progress would hold of a stuck state, and a process that
    /// sends `e` in `f` would be typed as sending `e`, where the wire carries its first N
    /// characters. A literal longer than N is [`Self::string_fits`]'s.
    fn string_widths(&mut self, v: ValueId, name: &str, n: u32, refinement: &Expr) {
        let width = |e: &Expr| self.prog.str_width_of(e, &|_| None);
        let is_field = |e: &Expr| matches!(&e.kind, ExprKind::Var(Var::Value(w, _)) if *w == v);
        let mut wide = Vec::new();
        refinement.visit(|e| {
            let ExprKind::Binary(BinOp::Eq, a, b) = &e.kind else { return };
            if a.sort != Sort::Str {
                return;
            }
            for (x, other) in [(a, b), (b, a)] {
                if is_field(x) && !matches!(other.kind, ExprKind::Int(_)) && width(other).is_none_or(|w| w > n) {
                    wide.push((other.loc, width(other)));
                }
            }
        });
        for (at, w) in wide {
            let held = match w {
                Some(w) => format!("a string of up to {w} characters"),
                None => "a string of any length (mochi does not know its width)".to_string(),
            };
            self.err(
                Code::StringTooLong,
                at.0,
                format!("`{name}` holds at most {n} characters, and this is {held}: a longer one has no equal `{name}`"),
                format!(
                    "mochi reads a string as one value without a length, so it cannot tell when no `{name}` exists: compare `{name}` with a value of a field at most {n} wide, or with literals"
                ),
            );
        }
    }

    /// A string literal: its code in [`Program::strings`].
    ///
    /// A literal is interned as the value a `char[N]` field carries on the wire: the text
    /// up to its first NUL byte (MAVLink pads a shorter string with NULs, and a reader
    /// stops at the first), so `"AB\0C"`, `"AB\0D"` and `"AB"` are one string, never
    /// three that `==` would tell apart.
    pub(super) fn string(&mut self, s: &str, loc: Loc) -> Expr {
        let s = s.split('\0').next().unwrap_or_default();
        let code = match self.prog.strings.iter().position(|x| x == s) {
            Some(i) => i,
            None => {
                self.prog.strings.push(s.to_string());
                self.prog.strings.len() - 1
            }
        };
        Expr { kind: ExprKind::Int(code as i64), sort: Sort::Str, loc }
    }

    /// `has_flag(x, F)`: `x` an `int`, `F` a constant positive integer (E0239).
    pub(super) fn has_flag(&mut self, args: &[Expr], span: Span) -> bool {
        let x_ok = matches!(args[0].sort, Sort::Int | Sort::Any | Sort::Error);
        let flag = crate::hir::expr::const_int(&self.prog, &args[1]);
        if !x_ok {
            self.err(
                Code::BadFlag,
                args[0].loc.0,
                format!("`has_flag` tests the bits of an integer, this is `{}`", args[0].sort),
                "pass an `int` field such as HEARTBEAT's `base_mode`",
            );
        }
        if flag.is_none_or(|f| f <= 0) {
            self.err(
                Code::BadFlag,
                args[1].loc.0,
                "the flag of `has_flag` must be a constant positive integer",
                "pass an entry of a bitmask enum (`MAV_MODE_FLAG_SAFETY_ARMED`) or a positive integer constant",
            );
        }
        let _ = span;
        x_ok && flag.is_some_and(|f| f > 0)
    }
}

/// The message field that carries command parameter `i`: `param<i>`, or for
/// `COMMAND_INT` (whose parameters 5-7 are `x`, `y`, `z`) those.
fn param_field(msg: &'static Message, i: u8) -> Option<&'static crate::dialect::Field> {
    msg.field(&format!("param{i}")).or_else(|| match i {
        5 => msg.field("x"),
        6 => msg.field("y"),
        7 => msg.field("z"),
        _ => None,
    })
}

/// The parameter index a command message's field carries, if any.
fn param_index(msg: &Message, field: &str) -> Option<u8> {
    if let Some(i) = field.strip_prefix("param").and_then(|i| i.parse::<u8>().ok()) {
        return (1..=7).contains(&i).then_some(i);
    }
    match field {
        "x" | "y" | "z" if msg.field("param5").is_none() => Some(match field {
            "x" => 5,
            "y" => 6,
            _ => 7,
        }),
        _ => None,
    }
}

/// The dialect of a program being lowered; only called on MAVLink fields, which exist only
/// with one.
fn d_of(l: &Lowerer) -> Option<&'static Dialect> {
    l.prog.dialect
}

fn wire_name(w: Wire) -> &'static str {
    w.c_name()
}

/// An integer bound as a literal: `Int` where it fits, else the exact decimal (a `real`
/// literal: `uint64_t`'s 18446744073709551615 is compared exactly, never rounded).
pub(super) fn int_literal(n: i128, loc: Loc) -> Expr {
    match i64::try_from(n) {
        Ok(i) => Expr { kind: ExprKind::Int(i), sort: Sort::Int, loc },
        Err(_) => Expr { kind: ExprKind::Real(n.to_string()), sort: Sort::Real, loc },
    }
}

fn quoted<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names.map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

mod entries;
mod float;

#[cfg(test)]
pub(crate) use entries::MAX_REAL_VALUES;
pub use entries::{approximate_entries, entry_allows, entry_predicate, refinement_without_entry};
use float::float_builtin;
pub use float::{exact_constant, float_definition_decided, wire_value};
