//! MAVLink messages (LANGUAGE.md, MAVLink messages): the `dialect NAME;` item,
//! message labels resolved in the dialect (E0232), payload fields checked against the
//! message (E0233-E0235), their sorts and wire ranges, commands
//! `COMMAND_LONG[MAV_CMD_X]` with parameters by label (E0237, E0238), enum entries as
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
//! Float fields: a `float` (`double`) field's value is a finite binary32 (binary64), the
//! conjunct [`Builtin::Float32`] (`Float64`) of its refinement; [`round_to_float`] rounds a
//! constant a process sends to that format exactly ([`wire_value`]). String literals are
//! interned as their on-wire value, up to the first NUL ([`Lowerer::string`]).
//!
//! Enum-typed fields: a field or command parameter the dialect gives an enum
//! (`enum="MAV_BOOL"`) takes only the enum's entries, or for a bitmask enum combinations of
//! its flags ([`entry_predicate`]). Without a user refinement the field's type is the enum:
//! the predicate is conjoined to the implicit part like the wire range. With one, the user's
//! refinement must imply it where the message is sent: the global walk asks it
//! (`Rule::EnumEntry`, E0243; ARCHITECTURE.md, "Enum-typed fields").

use super::*;
use crate::dialect::{self, CmdParam, Dialect, Entry, Enum, Message, Wire};

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
                    Code::BadCommand,
                    label.span,
                    format!("`{}` names a MAVLink command, but this program names no dialect", label.name),
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
        let (name, cmd) = match label.name.split_once('[') {
            Some((m, c)) => (m, Some(c.trim_end_matches(']'))),
            None => (label.name.as_str(), None),
        };
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
        let command = match cmd {
            None => None,
            Some(c) => match self.command(d, msg, c, label) {
                Some(e) => Some(e),
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
            out.push(self.mav_field(f, &res, command, viewer, origin.clone(), values));
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
                Code::BadCommand,
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
                self.err(Code::BadCommand, label.span, format!("`{cmd}` is not a `MAV_CMD` of `{}`", d.name), help);
                None
            }
        }
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
    /// part (wire range, fixed command) and the user's refinement.
    fn mav_field(
        &mut self,
        f: &ast::Field,
        res: &Resolved<'static>,
        command: Option<&'static Entry>,
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
            self.str_len.insert(v, res.field.array.unwrap_or(1));
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
        let user = f.refinement.as_ref().map(|r| {
            let env = Env::role(viewer, values);
            self.pred(r, &env, "a refinement")
        });
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
            let (Some(&n), Some(text)) = (self.str_len.get(v), self.prog.string(*code)) else { continue };
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

/// How many entries or flags a diagnostic lists by name.
const LISTED: usize = 8;

/// A float field (a command parameter) holds an enum's value as a real: the predicate lists
/// the allowed values one by one, at most this many (the bundled dialects need 1,024, for
/// GIMBAL_MANAGER_FLAGS' ten flags; a test checks it). An enum with more is not checked:
/// its predicate is `false`, so the protocol is rejected with a message that says why,
/// never verified.
pub(super) const MAX_REAL_VALUES: usize = 1024;

/// The predicate "`x` is a value the enum of `check` allows", and its description for
/// diagnostics (`an entry of `MAV_BOOL`: `MAV_BOOL_FALSE` (0), `MAV_BOOL_TRUE` (1)`).
///
/// A plain enum: the union of its entries' values, as maximal runs of consecutive integers
/// ([`Enum::value_runs`]): `x == v` for a single value, `lo <= x && x <= hi` for a run (an
/// integer field), so MAV_RESULT is one range and MAV_CMD about fifty disjuncts, never one
/// per entry. A bitmask enum: a combination of its flags, i.e. every bit of `x` (within the
/// wire width, two's complement) is set by some entry ([`Enum::flag_mask`] `M`): `x <=
/// 2^a - 1` for `a` the bit length of `M` (and `0 <= x` for a signed field whose sign bit
/// no flag has), and `!has_flag(x, 2^k)` for each bit `k < a` that no flag has (encoded
/// exactly with div/mod, as `has_flag` is). A real (float) field: the allowed integers one
/// by one (`x == v`), at most [`MAX_REAL_VALUES`]. The disjunctions are balanced trees.
/// Without the dialect or the enum (no bundled file refers to a missing enum), or above the
/// limit, the predicate is `false`: the check fails and the description says why.
pub fn entry_predicate(d: Option<&Dialect>, check: &crate::hir::EnumCheck, x: &Expr) -> (Expr, String) {
    let loc = x.loc;
    let name = &check.enum_name;
    let Some(e) = d.and_then(|d| d.enum_(name)) else {
        return (Expr::bool(false, loc), format!("an entry of `{name}`, which the dialect does not define"));
    };
    let cmp =
        |op, a: Expr, b: Expr| Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Bool, loc };
    let real = x.sort == Sort::Real;
    if e.bitmask {
        let bits = check.wire.bytes() * 8;
        let mask = e.flag_mask(if real { 64 } else { bits });
        let what = describe_flags(e, mask);
        if real {
            let n = mask.count_ones();
            if n > MAX_REAL_VALUES.ilog2() {
                return (Expr::bool(false, loc), too_many(&what));
            }
            // Every subset of the mask's bits, in increasing order.
            let mut values = Vec::with_capacity(1 << n);
            let mut sub = 0u64;
            loop {
                values.push(sub as i128);
                if sub == mask {
                    break;
                }
                sub = (sub.wrapping_sub(mask)) & mask;
            }
            values.sort_unstable();
            let eqs = values.into_iter().map(|v| cmp(BinOp::Eq, x.clone(), int_literal(v, loc))).collect();
            return (any(eqs, loc), what);
        }
        let a = 64 - mask.leading_zeros();
        let mut parts = Vec::new();
        if a < bits {
            let signed = check.wire.int_range().is_some_and(|(lo, _)| lo < 0);
            if signed {
                parts.push(cmp(BinOp::Le, int_literal(0, loc), x.clone()));
            }
            parts.push(cmp(BinOp::Le, x.clone(), int_literal((1i128 << a) - 1, loc)));
        }
        for k in (0..a).filter(|k| mask >> k & 1 == 0) {
            let flag = int_literal(1i128 << k, loc);
            let has = Expr { kind: ExprKind::Call(Builtin::HasFlag, vec![x.clone(), flag]), sort: Sort::Bool, loc };
            parts.push(Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(has)), sort: Sort::Bool, loc });
        }
        return (crate::hir::expr::and_all(parts, loc), what);
    }
    let runs = e.value_runs();
    let what = describe_entries(e, &runs);
    let mut alts = Vec::new();
    if real {
        let count: i128 = runs.iter().map(|(lo, hi)| i128::from(*hi) - i128::from(*lo) + 1).sum();
        if count > MAX_REAL_VALUES as i128 {
            return (Expr::bool(false, loc), too_many(&what));
        }
        for (lo, hi) in runs {
            alts.extend((lo..=hi).map(|v| cmp(BinOp::Eq, x.clone(), int_literal(i128::from(v), loc))));
        }
    } else {
        for (lo, hi) in runs {
            alts.push(if lo == hi {
                cmp(BinOp::Eq, x.clone(), int_literal(i128::from(lo), loc))
            } else {
                let lower = cmp(BinOp::Le, int_literal(i128::from(lo), loc), x.clone());
                lower.and(cmp(BinOp::Le, x.clone(), int_literal(i128::from(hi), loc)))
            });
        }
    }
    (any(alts, loc), what)
}

/// The refinement of a field with an [`EnumCheck`] without its entry predicate: what the
/// protocol says of the value besides the enum (the wire range, the user's refinement).
/// `None` when nothing is left. Lowering puts the predicate last among the implicit
/// conjuncts, so it is the whole implicit part or its right operand.
pub fn refinement_without_entry(d: Option<&Dialect>, f: &Field) -> Option<Expr> {
    let (Some(mav), Some(r)) = (&f.mav, &f.refinement) else { return f.refinement.clone() };
    let Some(check) = &mav.entry else { return f.refinement.clone() };
    let x = Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
    let (pred, _) = entry_predicate(d, check, &x);
    let (implicit, user) = match (&r.kind, mav.user) {
        (ExprKind::Binary(BinOp::And, i, u), true) => (&**i, Some(&**u)),
        (_, true) => return f.refinement.clone(), // not built by lowering: keep it whole
        (_, false) => (r, None),
    };
    let rest = if *implicit == pred {
        None
    } else {
        match &implicit.kind {
            ExprKind::Binary(BinOp::And, rest, e) if **e == pred => Some((**rest).clone()),
            _ => return f.refinement.clone(),
        }
    };
    match (rest, user) {
        (Some(i), Some(u)) => Some(i.and(u.clone())),
        (i, u) => i.or(u.cloned()),
    }
}

/// Up to this many alternatives, the entry predicate is assumed exactly in the contexts of
/// the global walk; above, its convex hull (see [`approximate_entries`]).
const ASSUMED_EXACTLY: usize = 4;

/// A sound over-approximation of the entry predicate, cheaper for the solver, when the exact
/// one is costly: the hull `lo <= x && x <= hi` of a plain enum of more than
/// [`ASSUMED_EXACTLY`] runs (MAV_CMD's fifty) or of a float field of more values; a
/// bitmask's range without its `!has_flag` holes (div/mod). `None` when the exact predicate
/// is cheap enough to keep. (`true`, when nothing is left.)
fn entry_approximation(d: Option<&Dialect>, check: &crate::hir::EnumCheck, x: &Expr) -> Option<Expr> {
    let e = d.and_then(|d| d.enum_(&check.enum_name))?;
    let loc = x.loc;
    let cmp =
        |op, a: Expr, b: Expr| Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Bool, loc };
    let hull = |lo: i128, hi: i128| {
        cmp(BinOp::Le, int_literal(lo, loc), x.clone()).and(cmp(BinOp::Le, x.clone(), int_literal(hi, loc)))
    };
    let real = x.sort == Sort::Real;
    if e.bitmask {
        let (pred, _) = entry_predicate(d, check, x);
        if real {
            let mask = e.flag_mask(64);
            return (mask.count_ones() > ASSUMED_EXACTLY.ilog2() && mask <= i64::MAX as u64)
                .then(|| hull(0, i128::from(mask)));
        }
        let has_holes = pred.conjuncts().iter().any(|c| matches!(c.kind, ExprKind::Unary(UnOp::Not, _)));
        if !has_holes {
            return None;
        }
        let kept = pred.conjuncts().into_iter().filter(|c| !matches!(c.kind, ExprKind::Unary(UnOp::Not, _))).cloned();
        return Some(crate::hir::expr::and_all(kept, loc));
    }
    let runs = e.value_runs();
    let (lo, hi) = (runs.first()?.0, runs.last()?.1);
    let many = if real {
        runs.iter().map(|(a, b)| i128::from(*b) - i128::from(*a) + 1).sum::<i128>() > ASSUMED_EXACTLY as i128
    } else {
        runs.len() > ASSUMED_EXACTLY
    };
    many.then(|| hull(i128::from(lo), i128::from(hi)))
}

/// `m` with each enum-typed field whose entry predicate is costly ([`entry_approximation`])
/// refined by the approximation instead: what the global walk *assumes* after the message
/// (Σ). Sound, as a weaker fact: the exact predicate stays in the field's refinement, which
/// every check that must *establish* it reads (a process's [T-OUT], the progress check's
/// payload, E0243). `None` when no field changes.
pub fn approximate_entries(d: Option<&Dialect>, m: &Msg) -> Option<Msg> {
    let mut out: Option<Msg> = None;
    for (i, f) in m.payload.iter().enumerate() {
        let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
        let x = Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
        let Some(approx) = entry_approximation(d, check, &x) else { continue };
        let rest = refinement_without_entry(d, f);
        let new = match rest {
            Some(r) => approx.and(r),
            None => approx,
        };
        out.get_or_insert_with(|| m.clone()).payload[i].refinement = (!new.is_true()).then_some(new);
    }
    out
}

/// Whether the enum of `check` allows the integer `v` (an entry's value, or for a bitmask
/// enum a combination of its flags): [`entry_predicate`] on a constant, without a solver.
pub fn entry_allows(d: Option<&Dialect>, check: &crate::hir::EnumCheck, v: i64) -> bool {
    let Some(e) = d.and_then(|d| d.enum_(&check.enum_name)) else { return false };
    let real = check.wire.is_float();
    if e.bitmask {
        let bits = if real { 64 } else { check.wire.bytes() * 8 };
        let mask = e.flag_mask(bits);
        if real {
            // Listed value by value: the non-negative combinations, up to the limit.
            return mask.count_ones() <= MAX_REAL_VALUES.ilog2() && v >= 0 && (v as u64) & !mask == 0;
        }
        let keep = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let fits = check.wire.int_range().is_none_or(|(lo, hi)| (lo..=hi).contains(&i128::from(v)));
        return fits && (v as u64 & keep) & !mask == 0;
    }
    if real {
        let count: i128 = e.value_runs().iter().map(|(lo, hi)| i128::from(*hi) - i128::from(*lo) + 1).sum();
        if count > MAX_REAL_VALUES as i128 {
            return false;
        }
    }
    e.entries.iter().any(|x| x.value == v)
}

/// The disjunction of `alts` as a balanced tree (so no stage recurses as deep as there are
/// alternatives); `false` when there are none (an enum without entries).
fn any(mut alts: Vec<Expr>, loc: Loc) -> Expr {
    match alts.len() {
        0 => Expr::bool(false, loc),
        1 => alts.pop().unwrap_or_else(|| Expr::bool(false, loc)),
        n => {
            let right = alts.split_off(n.div_ceil(2));
            let (a, b) = (any(alts, loc), any(right, loc));
            Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(a), Box::new(b)), sort: Sort::Bool, loc }
        }
    }
}

fn too_many(what: &str) -> String {
    format!("{what}; a float field is checked value by value and this enum has more than {MAX_REAL_VALUES} values, so mochi cannot check it (the check fails rather than pass unchecked)")
}

/// `an entry of `MAV_RESULT`: `MAV_RESULT_ACCEPTED` (0), ...`: the entries by name when
/// few, else their count and values.
fn describe_entries(e: &Enum, runs: &[(i64, i64)]) -> String {
    if e.entries.is_empty() {
        return format!("an entry of `{}`, which has none", e.name);
    }
    if e.entries.len() <= LISTED {
        let names: Vec<String> = e.entries.iter().map(|x| format!("`{}` ({})", x.name, x.value)).collect();
        return format!("an entry of `{}`: {}", e.name, names.join(", "));
    }
    let values = if runs.len() <= 6 {
        let r: Vec<String> =
            runs.iter().map(|(lo, hi)| if lo == hi { lo.to_string() } else { format!("{lo}..={hi}") }).collect();
        format!(": values {}", r.join(", "))
    } else {
        String::new()
    };
    format!("an entry of `{}` ({} entries{values})", e.name, e.entries.len())
}

/// `a combination of the flags of `X`: `A` (1), `B` (2)`: the entries by name when few (a
/// 0 entry such as MAV_BOOL_FALSE included), else the mask of the bits they set.
fn describe_flags(e: &Enum, mask: u64) -> String {
    if e.entries.is_empty() {
        return format!("a combination of the flags of `{}`, which has none: 0", e.name);
    }
    if e.entries.len() <= LISTED {
        let names: Vec<String> = e.entries.iter().map(|x| format!("`{}` ({})", x.name, x.value)).collect();
        return format!("a combination of the flags of `{}`: {}", e.name, names.join(", "));
    }
    format!("a combination of the flags of `{}` ({} entries, bits {mask:#x})", e.name, e.entries.len())
}

fn wire_name(w: Wire) -> &'static str {
    w.c_name()
}

/// An integer bound as a literal: `Int` where it fits, else the exact decimal (a `real`
/// literal: `uint64_t`'s 18446744073709551615 is compared exactly, never rounded).
fn int_literal(n: i128, loc: Loc) -> Expr {
    match i64::try_from(n) {
        Ok(i) => Expr { kind: ExprKind::Int(i), sort: Sort::Int, loc },
        Err(_) => Expr { kind: ExprKind::Real(n.to_string()), sort: Sort::Real, loc },
    }
}

fn quoted<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names.map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

/// The predicate a float wire type conjoins to its field's refinement:
/// [`Builtin::Float32`] for `float`, [`Builtin::Float64`] for `double`.
pub(crate) fn float_builtin(wire: Wire) -> Option<Builtin> {
    match wire {
        Wire::F32 => Some(Builtin::Float32),
        Wire::F64 => Some(Builtin::Float64),
        _ => None,
    }
}

/// A binary floating-point format as a set of rationals: its finite values are exactly
/// `m * 2^q` for integers `|m| <= 2^p - 1` and `qmin <= q <= qmax` (`q` the exponent of
/// the last significand bit: binary32 has `p = 24`, subnormals down to `2^-149`, and its
/// largest value `(2^24 - 1) * 2^104`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FloatFormat {
    pub p: u32,
    pub qmin: i64,
    pub qmax: i64,
}

pub const BINARY32: FloatFormat = FloatFormat { p: 24, qmin: -149, qmax: 104 };
pub const BINARY64: FloatFormat = FloatFormat { p: 53, qmin: -1074, qmax: 971 };

/// The format [`Builtin::Float32`] or [`Builtin::Float64`] stands for.
pub fn float_format(f: Builtin) -> Option<FloatFormat> {
    match f {
        Builtin::Float32 => Some(BINARY32),
        Builtin::Float64 => Some(BINARY64),
        _ => None,
    }
}

/// `2^k` as an exact rational.
pub fn pow2(k: i64) -> num_rational::BigRational {
    use num_bigint::BigInt;
    let one = BigInt::from(1);
    if k >= 0 {
        num_rational::BigRational::from_integer(one << (k as usize))
    } else {
        num_rational::BigRational::new(one.clone(), one << (k.unsigned_abs() as usize))
    }
}

/// `r` rounded to the nearest value of `f`, ties to even (IEEE 754's default, what an
/// autopilot's `(float)0.1` does), exactly. `None` when it rounds to an infinity (its
/// magnitude is at least the largest finite value plus half its ulp), which the
/// finite-float model excludes.
pub fn round_to_float(r: &num_rational::BigRational, f: FloatFormat) -> Option<num_rational::BigRational> {
    use num_traits::{One, Signed, Zero};
    if r.is_zero() {
        return Some(r.clone());
    }
    let a = r.abs();
    // e = floor(log2 a): 2^e <= a < 2^(e+1).
    let mut e = a.numer().bits() as i64 - a.denom().bits() as i64;
    if a < pow2(e) {
        e -= 1;
    }
    let q = (e - (i64::from(f.p) - 1)).max(f.qmin);
    let scaled = &a / pow2(q);
    let mut n = scaled.floor();
    let twice = (&scaled - &n) * num_rational::BigRational::from_integer(2.into());
    let odd = !(n.to_integer() % num_bigint::BigInt::from(2)).is_zero();
    if twice > num_rational::BigRational::one() || (twice.is_one() && odd) {
        n += num_rational::BigRational::one();
    }
    let v = n * pow2(q);
    let max = num_rational::BigRational::from_integer((num_bigint::BigInt::from(1) << f.p as usize) - 1) * pow2(f.qmax);
    if v > max {
        return None;
    }
    Some(if r.is_negative() { -v } else { v })
}

/// Whether `r` is a finite value of `f`.
pub fn is_float(r: &num_rational::BigRational, f: FloatFormat) -> bool {
    round_to_float(r, f).as_ref() == Some(r)
}

/// The exact value of a closed numeric expression (literals, constants, arithmetic), or
/// `None` when it reads a variable or is not exact.
pub fn exact_constant(prog: &Program, e: &Expr) -> Option<num_rational::BigRational> {
    if !matches!(e.sort, Sort::Int | Sort::Real) {
        return None;
    }
    match crate::exact::eval(prog, e, &|_: &Var| None).ok()? {
        crate::exact::Value::Num(n) if n.lo == n.hi => Some(n.lo),
        _ => None,
    }
}

/// Whether the progress check may replace a field `id` defined by `id == e` by `e`
/// (`∃x. x == e ∧ P(x)` is `P(e)`): always, unless the field is a `float`/`double`, whose
/// [`Builtin::Float32`] conjunct then reads `e` and must stay decided: `e` a constant
/// (decided exactly) or a value of a field of that format or a narrower one (a float by
/// the model). Otherwise the field stays an existential whose format is encoded exactly.
pub fn float_definition_decided(prog: &Program, id: ValueId, e: &Expr) -> bool {
    let Some(f) = prog.wire_floats.get(&id) else { return true };
    if exact_constant(prog, e).is_some() {
        return true;
    }
    match &e.kind {
        ExprKind::Var(Var::Value(v, _)) => {
            prog.wire_floats.get(v).is_some_and(|w| w == f || (*w == Builtin::Float32 && *f == Builtin::Float64))
        }
        _ => false,
    }
}

/// A rational whose denominator is a power of two (every float) as its exact decimal,
/// `-0.100000001490116119384765625`.
pub fn dyadic_decimal(r: &num_rational::BigRational) -> Option<String> {
    use num_traits::{One, Signed, Zero};
    let d = r.denom();
    let k = d.bits().checked_sub(1)?;
    if (num_bigint::BigInt::one() << k as usize) != *d {
        return None;
    }
    let n = r.numer().abs() * num_traits::pow(num_bigint::BigInt::from(5), k as usize);
    let mut digits = n.to_string();
    let k = k as usize;
    if k > 0 {
        if digits.len() <= k {
            digits = format!("{}{digits}", "0".repeat(k + 1 - digits.len()));
        }
        digits.insert(digits.len() - k, '.');
    } else {
        digits.push_str(".0");
    }
    let sign = if r.is_negative() && !r.is_zero() { "-" } else { "" };
    Some(format!("{sign}{digits}"))
}

/// The value a process's argument `a` for the field `field` has on the wire: for a
/// `float`/`double` field and a constant `a`, `a` rounded to the field's format (ties to
/// even), as an exact decimal literal; any other argument as it is (a non-constant one
/// keeps its `float32` conjunct undecided, so its [T-OUT] obligation is unknown unless it
/// is a value of a float field). `Err` with the rounded-away constant when it rounds to an
/// infinity, which no finite float field carries.
pub fn wire_value(prog: &Program, field: ValueId, a: &Expr) -> Result<Expr, String> {
    let Some(format) = prog.wire_floats.get(&field).and_then(|f| float_format(*f)) else { return Ok(a.clone()) };
    let Some(r) = exact_constant(prog, a) else { return Ok(a.clone()) };
    let rounded = round_to_float(&r, format).ok_or_else(|| crate::hir::print::expr(prog, None, a))?;
    match dyadic_decimal(&rounded) {
        Some(text) => Ok(Expr { kind: ExprKind::Real(text), sort: Sort::Real, loc: a.loc }),
        None => Ok(a.clone()),
    }
}
