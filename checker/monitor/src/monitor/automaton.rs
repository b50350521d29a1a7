//! A verified MAVLink protocol compiled once into a flat automaton.
//!
//! States are the points of the global type before a message (a [`StateKind::Branch`] with
//! its outgoing edges: every first message of a choice's branches), the points where a
//! loop is entered or jumped back to (a [`StateKind::Assign`]: recursion parameters are
//! registers, assigned in parallel, their refinements checked), and `end`. An edge is a
//! message `from -> to : [guard] LABEL(fields)`: the message id, the key a keyed label
//! fixes ([`Key`]: the command of `COMMAND_LONG[MAV_CMD_X]`, the name of
//! `PARAM_VALUE["MC_PITCH_P"]`), the guard, and per listed field where it lies in
//! the payload, its register, its refinement and its enum membership. The compilation is
//! continuation-passing over the global type (`compile(g, k)` is the state from which `g`
//! runs and then goes on at `k`), so a choice in the middle of a sequence and loops nested
//! in loops need nothing special.
//!
//! The system's `stream`s are compiled beside the steps ([`StreamDef`]): their fields are
//! decoded into the stream's template registers and checked; an edge that reads observed
//! state lists its snapshots ([`ObservedRead`]), bound when its message arrives.

use super::code::{Arena, Code, RegInfo};
use super::wire::{self, Layout, Scalar, Slot};
use crate::hir::{Global, Msg, Program, RoleId, Sort, ValueId, ValueOrigin};
use crate::source::Span;

/// What a listed payload field is read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    Int,
    Float,
    Str,
}

/// A field of an edge's payload the protocol lists.
#[derive(Clone, Debug)]
pub struct FieldRead {
    pub name: String,
    pub reg: u16,
    pub slot: Slot,
    pub kind: FieldKind,
    /// The field's refinement (wire range, float format and enum as lowering conjoined them,
    /// and the user's), if any.
    pub refinement: Option<Code>,
    /// Membership of the field's enum (or bitmask), as the static type states it.
    pub entry: Option<(Code, String)>,
    pub span: Span,
}

/// What a keyed label fixes of its message: a frame of the message's id is the label's
/// only when its key field holds the key. Compared on every such frame, without allocating:
/// a command is one integer read, a name one comparison of the field's bytes up to its
/// first NUL (all N bytes when none; `wire::read_str`) with the key's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Key {
    /// `COMMAND_LONG[MAV_CMD_X]`: the `command` field's slot and the command.
    Command(Slot, i128),
    /// `PARAM_VALUE["MC_PITCH_P"]`: the key field's slot (the message's one `char[N]`
    /// field) and the key's bytes (at most N, no NUL).
    Name(Slot, Box<[u8]>),
}

impl Key {
    /// Whether `payload` holds the key.
    #[inline]
    pub fn fits(&self, payload: &[u8]) -> bool {
        match self {
            Key::Command(slot, cmd) => wire::read(payload, *slot, 0) == Scalar::Int(*cmd),
            Key::Name(slot, key) => wire::read_str(payload, *slot) == &key[..],
        }
    }
}

/// Whether a frame's payload is a label's with key `key` (any payload when there is none).
#[inline]
pub fn key_fits(key: &Option<Key>, payload: &[u8]) -> bool {
    key.as_ref().is_none_or(|k| k.fits(payload))
}

/// A message step.
#[derive(Clone, Debug)]
pub struct Edge {
    pub from: RoleId,
    pub to: RoleId,
    pub msgid: u32,
    pub label: String,
    /// What a keyed label fixes (`COMMAND_LONG[MAV_CMD_X]`, `PARAM_VALUE["MC_PITCH_P"]`).
    pub key: Option<Key>,
    pub guard: Option<Code>,
    pub fields: Vec<FieldRead>,
    /// `target_system` and `target_component`, when the message has them.
    pub target: (Option<Slot>, Option<Slot>),
    pub target_state: u32,
    /// The observed values its guard and refinements read: a snapshot register each, bound
    /// from the latest reading of a stream field when the message arrives.
    pub observed: Vec<ObservedRead>,
    pub span: Span,
}

/// A snapshot an edge takes: register `reg` is bound to field `field` of stream `stream`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObservedRead {
    pub reg: u16,
    pub stream: u32,
    pub field: u32,
}

/// A `stream` of the system: messages `from -> to` at any time, never a step. Its fields
/// are decoded into the template registers and checked against their refinements (wire
/// range, enum, the stream's invariant); an accepted message is the latest reading.
#[derive(Clone, Debug)]
pub struct StreamDef {
    pub from: RoleId,
    pub to: Vec<RoleId>,
    pub msgid: u32,
    pub label: String,
    pub key: Option<Key>,
    pub fields: Vec<FieldRead>,
    pub target: (Option<Slot>, Option<Slot>),
    pub span: Span,
}

/// The timeout branch of a branch state, `after T ms by R. G`: when `ms` milliseconds
/// passed since the state was entered and no edge of it was taken, `by` (the waiting role)
/// may go on at `next` (the state from which `G` runs, before its assignments).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timeout {
    pub ms: u64,
    pub by: RoleId,
    pub next: u32,
    pub span: Span,
}

/// A state of the automaton.
#[derive(Clone, Debug)]
pub enum StateKind {
    /// Waiting for one of these edges.
    Branch(Vec<u32>),
    /// Assign the registers in parallel, check the refinements, go on at `next`.
    Assign {
        assigns: Vec<(u16, Code)>,
        checks: Vec<(u16, Code)>,
        next: u32,
        span: Span,
    },
    End,
}

/// What a MAVLink end is, as its HEARTBEAT says, and what a role must be played by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EndKind {
    /// Not known (no HEARTBEAT seen from the end; a role of no conventional name).
    #[default]
    Unknown,
    /// A ground station: HEARTBEAT `type == MAV_TYPE_GCS`; a role named `GCS`.
    GroundStation,
    /// A vehicle's autopilot: HEARTBEAT `autopilot != MAV_AUTOPILOT_INVALID` and a type
    /// other than `MAV_TYPE_GCS`; a role named `UAV`, `Vehicle`, `Autopilot`, ...
    Vehicle,
}

impl EndKind {
    /// Whether an end of kind `end` may play a role of kind `self`: either is unknown, or
    /// they are the same.
    #[inline]
    pub fn admits(self, end: EndKind) -> bool {
        self == EndKind::Unknown || end == EndKind::Unknown || self == end
    }

    /// The kind a role's name declares (case-insensitive): `GCS`, `GroundStation`,
    /// `Ground_Station`, `Ground` a ground station; `UAV`, `UAS`, `Vehicle`, `Autopilot`,
    /// `Drone`, `Copter`, `Plane`, `Rover`, `Sub`, `Boat` a vehicle; any other name is played
    /// by any end (docs/monitor.md, "Which end plays which role").
    pub fn of_role(name: &str) -> EndKind {
        let n = name.to_ascii_lowercase();
        match n.as_str() {
            "gcs" | "groundstation" | "ground_station" | "ground" => EndKind::GroundStation,
            "uav" | "uas" | "vehicle" | "autopilot" | "drone" | "copter" | "plane" | "rover" | "sub" | "boat" => {
                EndKind::Vehicle
            }
            _ => EndKind::Unknown,
        }
    }

    /// The kind a HEARTBEAT payload declares (`type` at byte 4, `autopilot` at byte 5; a
    /// MAVLink 2 payload truncated before them reads zeros, as the wire format says). A
    /// HEARTBEAT of `MAV_TYPE_GENERIC` and `MAV_AUTOPILOT_GENERIC` (all zeros: a default or
    /// truncated one) claims nothing: unknown.
    pub fn of_heartbeat(payload: &[u8]) -> EndKind {
        let ty = payload.get(4).copied().unwrap_or(0);
        let autopilot = payload.get(5).copied().unwrap_or(0);
        if ty == MAV_TYPE_GCS {
            EndKind::GroundStation
        } else if ty == 0 && autopilot == 0 {
            EndKind::Unknown
        } else if autopilot != MAV_AUTOPILOT_INVALID {
            EndKind::Vehicle
        } else {
            EndKind::Unknown
        }
    }
}

/// `MAV_TYPE_GCS` and `MAV_AUTOPILOT_INVALID` (common.xml).
const MAV_TYPE_GCS: u8 = 6;
const MAV_AUTOPILOT_INVALID: u8 = 8;

/// A protocol compiled for the monitor.
#[derive(Clone, Debug)]
pub struct Automaton {
    pub name: String,
    pub prog: Program,
    pub roles: Vec<String>,
    /// The kind of end each role must be played by ([`EndKind::of_role`]).
    pub role_kinds: Vec<EndKind>,
    pub states: Vec<StateKind>,
    pub edges: Vec<Edge>,
    pub arena: Arena,
    pub start: u32,
    /// The timeout branch of each state (indexed by state; `None` for most).
    pub timeouts: Vec<Option<Timeout>>,
    /// The message ids of every edge (sorted, deduplicated).
    pub alphabet: Vec<u32>,
    /// The edges of each message id of the alphabet (sorted by id; each list in edge
    /// order): the candidates for a frame, without a look at the other edges.
    pub edges_by_id: Vec<(u32, Box<[u32]>)>,
    /// The system's streams, and their message ids (sorted, deduplicated).
    pub streams: Vec<StreamDef>,
    pub stream_alphabet: Vec<u32>,
    /// Predicates compiled (guards, refinements, enum memberships, parameter refinements),
    /// each with an index for coverage: `(edge or state, what)`.
    pub preds: usize,
}

/// Why a program cannot be monitored.
#[derive(Clone, Debug, PartialEq)]
pub struct CompileError {
    pub message: String,
    pub span: Option<Span>,
}

impl CompileError {
    /// The refusal as a diagnostic (E0802) at the construct, or at `fallback` (the file)
    /// when it has no position, with what to do about it.
    pub fn diagnostic(&self, fallback: Span) -> crate::diag::Diagnostic {
        crate::diag::Diagnostic::error(
            crate::diag::Code::MonitorUnsupported,
            self.span.unwrap_or(fallback),
            format!("the monitor cannot run this protocol: {}", self.message),
        )
        .with_help(
            "the monitor runs MAVLink protocols (`dialect ...;`, messages only) whose loops send a message on \
             every path back, whose messages reach the link in the protocol's order and which start with a \
             message; write the construct so, or check the protocol statically only (`mochi check`)",
        )
    }
}

fn err<T>(message: impl Into<String>, span: Option<Span>) -> Result<T, CompileError> {
    Err(CompileError { message: message.into(), span })
}

/// A label resolved: its message, the message's layout, and the command it fixes.
type Label = (&'static crate::dialect::Message, Layout, Option<Key>);

struct Loop {
    var: String,
    regs: Vec<u16>,
    checks: Vec<(u16, Code)>,
    head: u32,
}

struct Builder<'p> {
    prog: &'p Program,
    dialect: &'static crate::dialect::Dialect,
    a: Automaton,
    loops: Vec<Loop>,
}

impl Automaton {
    /// Compiles the choreography of `prog` (a lowered program with a dialect, one that
    /// `mochi check` verifies: the monitor trusts what the static checks proved, such as
    /// that guards and refinements read only what their participant knows).
    pub fn compile(prog: &Program) -> Result<Automaton, CompileError> {
        Self::compile_with(prog, false)
    }

    /// [`Automaton::compile`] with every guard and refinement left a tree of operators
    /// (`Arena::tree_only`): the evaluator before comparisons were compiled, which the
    /// benchmark and the differential test run beside the default.
    #[doc(hidden)]
    pub fn compile_tree(prog: &Program) -> Result<Automaton, CompileError> {
        Self::compile_with(prog, true)
    }

    fn compile_with(prog: &Program, tree_only: bool) -> Result<Automaton, CompileError> {
        let Some(chor) = &prog.choreography else { return err("the program has no choreography", None) };
        let Some(dialect) = prog.dialect else {
            return err("the program names no MAVLink dialect (`dialect common;`)", Some(chor.span));
        };
        if prog.roles.len() > 64 {
            return err("more than 64 participants", Some(chor.span));
        }
        let mut arena = Arena { tree_only, ..Arena::default() };
        for (i, v) in prog.values.iter().enumerate() {
            let knowers = match &v.origin {
                ValueOrigin::Message { from, to } => (1u64 << from.idx()) | (1u64 << to.idx()),
                ValueOrigin::RecParam => (1u64 << prog.roles.len()) - 1,
                ValueOrigin::Bound { role } => 1u64 << role.idx(),
                // A stream's template fields are read only by the stream's own invariant; a
                // snapshot is its reader's.
                ValueOrigin::Stream { .. } => 0,
                ValueOrigin::Observed { reader, .. } => 1u64 << reader.idx(),
            };
            let id = ValueId(i as u32);
            let r = arena.regs.len() as u16;
            arena.reg_of.insert(id, r);
            if let Some(f) = prog.wire_floats.get(&id) {
                arena.float_regs.insert(r, *f);
            }
            arena.regs.push(RegInfo {
                value: id,
                name: v.name.clone(),
                sort: v.sort.clone(),
                str_at: 0,
                str_cap: 0,
                knowers,
            });
        }
        let mut b = Builder {
            prog,
            dialect,
            a: Automaton {
                name: chor.name.clone(),
                prog: prog.clone(),
                roles: prog.roles.iter().map(|r| r.name.clone()).collect(),
                role_kinds: prog.roles.iter().map(|r| EndKind::of_role(&r.name)).collect(),
                states: vec![StateKind::End],
                edges: Vec::new(),
                arena,
                start: 0,
                timeouts: Vec::new(),
                alphabet: Vec::new(),
                edges_by_id: Vec::new(),
                streams: Vec::new(),
                stream_alphabet: Vec::new(),
                preds: 0,
            },
            loops: Vec::new(),
        };
        for st in &prog.streams {
            let s = b.stream(st)?;
            b.a.streams.push(s);
        }
        let start = b.compile(&chor.body, 0)?;
        b.a.start = start;
        b.a.timeouts.resize(b.a.states.len(), None);
        b.check_guarded()?;
        super::order::check(&b.a)?;
        let mut alphabet: Vec<u32> = b.a.edges.iter().map(|e| e.msgid).collect();
        alphabet.sort_unstable();
        alphabet.dedup();
        b.a.edges_by_id = alphabet
            .iter()
            .map(|&id| {
                let es: Vec<u32> = (0..b.a.edges.len() as u32).filter(|&e| b.a.edges[e as usize].msgid == id).collect();
                (id, es.into_boxed_slice())
            })
            .collect();
        b.a.alphabet = alphabet;
        let mut streams: Vec<u32> = b.a.streams.iter().map(|s| s.msgid).collect();
        streams.sort_unstable();
        streams.dedup();
        b.a.stream_alphabet = streams;
        Ok(b.a)
    }

    /// Whether message `msgid` is some stream's message.
    #[inline]
    pub fn in_streams(&self, msgid: u32) -> bool {
        self.stream_alphabet.binary_search(&msgid).is_ok()
    }

    /// Whether message `msgid` is a step of some edge.
    #[inline]
    pub fn in_alphabet(&self, msgid: u32) -> bool {
        self.alphabet.binary_search(&msgid).is_ok()
    }

    /// The edges whose message is `msgid` (none when it is outside the alphabet).
    #[inline]
    pub fn edges_with(&self, msgid: u32) -> &[u32] {
        match self.edges_by_id.binary_search_by_key(&msgid, |(id, _)| *id) {
            Ok(k) => &self.edges_by_id[k].1,
            Err(_) => &[],
        }
    }

    /// The edges of `state` (empty unless it is a branch).
    pub fn edges_of(&self, state: u32) -> &[u32] {
        match &self.states[state as usize] {
            StateKind::Branch(es) => es,
            _ => &[],
        }
    }

    /// The timeout branch of `state`, if it has one.
    #[inline]
    pub fn timeout(&self, state: u32) -> Option<&Timeout> {
        self.timeouts.get(state as usize).and_then(Option::as_ref)
    }

    /// The states reached from `s` by assignments only: the branch or end a step lands on.
    pub fn settle(&self, mut s: u32) -> u32 {
        for _ in 0..=self.states.len() {
            match &self.states[s as usize] {
                StateKind::Assign { next, .. } => s = *next,
                _ => return s,
            }
        }
        s
    }
}

/// The items of a sequence, nested sequences spliced in.
fn flatten<'g>(g: &'g Global, out: &mut Vec<&'g Global>) {
    match g {
        Global::Seq(items, _) => items.iter().for_each(|i| flatten(i, out)),
        _ => out.push(g),
    }
}

impl Builder<'_> {
    fn state(&mut self, k: StateKind) -> u32 {
        self.a.states.push(k);
        (self.a.states.len() - 1) as u32
    }

    fn code(&mut self, e: &crate::hir::Expr) -> Result<Code, CompileError> {
        let mut c = self.a.arena.compile(self.prog, e).map_err(|m| CompileError { message: m, span: Some(e.loc.0) })?;
        c.id = self.a.preds as u32;
        self.a.preds += 1;
        Ok(c)
    }

    fn compile(&mut self, g: &Global, k: u32) -> Result<u32, CompileError> {
        match g {
            Global::Msg(m) => {
                let e = self.edge(m, k)?;
                Ok(self.state(StateKind::Branch(vec![e])))
            }
            Global::Seq(items, _) => {
                let mut cur = k;
                for item in items.iter().rev() {
                    cur = self.compile(item, cur)?;
                }
                Ok(cur)
            }
            Global::Choice(bs, loc) => {
                let mut edges = Vec::new();
                let mut timeout = None;
                for b in bs {
                    if let Some(after) = b.timeout_head() {
                        // `after T ms by R. G`: `G` compiled as any branch; the branch
                        // state keeps where it goes and after how long.
                        let mut items = Vec::new();
                        flatten(b, &mut items);
                        let mut next = k;
                        for item in items.iter().skip(1).rev() {
                            next = self.compile(item, next)?;
                        }
                        if timeout.is_some() {
                            return err("a second timeout branch in one choice", Some(after.loc.0));
                        }
                        let Ok(ms) = u64::try_from(after.ms) else {
                            return err("a timeout bound that is not positive", Some(after.loc.0));
                        };
                        timeout = Some(Timeout { ms, by: after.by, next, span: after.loc.0 });
                        continue;
                    }
                    let s = self.compile(b, k)?;
                    match &self.a.states[s as usize] {
                        StateKind::Branch(es) => edges.extend(es.iter().copied()),
                        _ => return err("a branch of a choice that does not start with a message", Some(loc.0)),
                    }
                }
                let s = self.state(StateKind::Branch(edges));
                if let Some(t) = timeout {
                    self.a.timeouts.resize(self.a.states.len(), None);
                    self.a.timeouts[s as usize] = Some(t);
                }
                Ok(s)
            }
            Global::Rec { var, params, body, loc, .. } => {
                let head = self.state(StateKind::End);
                let mut regs = Vec::new();
                let mut checks = Vec::new();
                let mut assigns = Vec::new();
                for p in params {
                    if p.sort == Sort::Str {
                        return err(
                            format!("the recursion parameter `{}` is a string: the monitor holds strings only in payload fields", p.name),
                            Some(loc.0),
                        );
                    }
                    let r = self.reg(p.value, loc.0)?;
                    regs.push(r);
                    assigns.push((r, self.code(&p.init)?));
                    if let Some(rf) = &p.refinement {
                        checks.push((r, self.code(rf)?));
                    }
                }
                self.loops.push(Loop { var: var.clone(), regs, checks: checks.clone(), head });
                let b = self.compile(body, k);
                self.loops.pop();
                let b = b?;
                self.a.states[head as usize] =
                    StateKind::Assign { assigns: Vec::new(), checks: Vec::new(), next: b, span: loc.0 };
                Ok(self.state(StateKind::Assign { assigns, checks, next: head, span: loc.0 }))
            }
            Global::Var(v) => {
                let Some(l) = self.loops.iter().rev().find(|l| l.var == v.var) else {
                    return err(format!("`{}` is not a loop around this jump", v.var), Some(v.loc.0));
                };
                if l.regs.len() != v.args.len() {
                    return err(format!("`{}` takes {} arguments", v.var, l.regs.len()), Some(v.loc.0));
                }
                let (regs, checks, head) = (l.regs.clone(), l.checks.clone(), l.head);
                let mut assigns = Vec::new();
                for (r, a) in regs.into_iter().zip(&v.args) {
                    assigns.push((r, self.code(a)?));
                }
                Ok(self.state(StateKind::Assign { assigns, checks, next: head, span: v.loc.0 }))
            }
            Global::End(_) => Ok(0),
            // Lowering admits `after` only at the head of a branch of a choice (E0321),
            // which the choice above splits off.
            Global::After(a) => err("`after` that does not start a branch of a choice", Some(a.loc.0)),
            Global::Motion(m) => err("a motion: the monitor runs MAVLink protocols only", Some(m.loc.0)),
            Global::Par(_, loc) => err("a `*`: the monitor runs MAVLink protocols only", Some(loc.0)),
        }
    }

    fn reg(&self, v: ValueId, span: Span) -> Result<u16, CompileError> {
        match self.a.arena.reg_of.get(&v) {
            Some(r) => Ok(*r),
            None => err("a value that is not a register", Some(span)),
        }
    }

    /// The message id, the decoder layout's slots and the key a keyed label fixes.
    fn label(&self, label: &str, span: Span) -> Result<Label, CompileError> {
        let (name, key) = crate::dialect::split_label(label);
        let Some(msg) = self.dialect.message(name) else {
            return err(format!("`{name}` is not a message of `{}`", self.dialect.name), Some(span));
        };
        let layout = Layout::of(msg);
        let key = match key {
            Some(crate::dialect::LabelKey::Command(c)) => {
                let Some((_, entry)) = self.dialect.entry(c) else {
                    return err(format!("`{c}` is not an entry of the dialect"), Some(span));
                };
                let Some(slot) = layout.slot(msg, "command") else {
                    return err(format!("`{name}` has no `command` field"), Some(span));
                };
                Some(Key::Command(slot, i128::from(entry.value)))
            }
            Some(crate::dialect::LabelKey::Name(k)) => {
                let Some(slot) = msg.key_field().and_then(|f| layout.slot(msg, &f.name)) else {
                    return err(format!("`{name}` has no one string field to key by"), Some(span));
                };
                if k.len() > usize::from(slot.len) || k.as_bytes().contains(&0) {
                    return err(format!("the key \"{k}\" does not fit `{name}`'s key field"), Some(span));
                }
                Some(Key::Name(slot, k.as_bytes().into()))
            }
            None => None,
        };
        Ok((msg, layout, key))
    }

    /// The listed fields of a payload: where each lies, its register, its checks.
    fn fields(
        &mut self,
        msg: &'static crate::dialect::Message,
        layout: &Layout,
        payload: &[crate::hir::global::Field],
        span: Span,
        strings: bool,
    ) -> Result<Vec<FieldRead>, CompileError> {
        let name = &msg.name;
        let mut fields = Vec::new();
        for f in payload {
            let Some(mav) = &f.mav else {
                return err(format!("the field `{}` is not a MAVLink field", f.name), Some(span));
            };
            let Some(df) = msg.field(&mav.field) else {
                return err(format!("`{}` is not a field of `{name}`", mav.field), Some(span));
            };
            let Some(slot) = layout.slot(msg, &mav.field) else {
                return err(format!("`{}` is not a field of `{name}`", mav.field), Some(span));
            };
            let kind = if df.is_string() {
                FieldKind::Str
            } else if df.array.is_some() {
                return err(format!("the array field `{}` (the language cannot list one)", mav.field), Some(span));
            } else if df.wire.is_float() {
                FieldKind::Float
            } else {
                FieldKind::Int
            };
            if kind == FieldKind::Str && !strings {
                return err(
                    format!("the string field `{}` of a stream: the monitor keeps numeric readings only", mav.field),
                    Some(span),
                );
            }
            let reg = self.reg(f.value, span)?;
            if kind == FieldKind::Str {
                let info = &mut self.a.arena.regs[reg as usize];
                info.str_at = self.a.arena.str_size;
                info.str_cap = slot.len;
                self.a.arena.str_size += u32::from(slot.len);
            }
            let refinement = match &f.refinement {
                Some(r) => Some(self.code(r)?),
                None => None,
            };
            let entry = match &mav.entry {
                Some(check) => {
                    let x = crate::hir::expr::value_expr(f.value, &f.name, &f.sort);
                    let (pred, what) = crate::lower::entry_predicate(Some(self.dialect), check, &x);
                    Some((self.code(&pred)?, what))
                }
                None => None,
            };
            fields.push(FieldRead { name: f.name.clone(), reg, slot, kind, refinement, entry, span });
        }
        Ok(fields)
    }

    fn stream(&mut self, st: &crate::hir::Stream) -> Result<StreamDef, CompileError> {
        let span = st.loc.0;
        let (msg, layout, key) = self.label(&st.label, span)?;
        let fields = self.fields(msg, &layout, &st.fields, span, false)?;
        let target = (layout.slot(msg, "target_system"), layout.slot(msg, "target_component"));
        Ok(StreamDef {
            from: st.from,
            to: st.to.clone(),
            msgid: msg.id,
            label: st.label.clone(),
            key,
            fields,
            target,
            span,
        })
    }

    fn edge(&mut self, m: &Msg, k: u32) -> Result<u32, CompileError> {
        let span = m.loc.0;
        let (msg, layout, key) = self.label(&m.label, span)?;
        let guard = match &m.guard {
            Some(g) => Some(self.code(g)?),
            None => None,
        };
        let fields = self.fields(msg, &layout, &m.payload, span, true)?;
        let mut observed = Vec::new();
        for o in &m.observed {
            if self.prog.streams.get(o.stream as usize).is_none_or(|s| s.fields.get(o.field as usize).is_none()) {
                return err(format!("`{}` reads a stream field that does not exist", m.label), Some(span));
            }
            observed.push(ObservedRead { reg: self.reg(o.value, span)?, stream: o.stream, field: o.field });
        }
        // Each participant is monitored with only what it knows: the message is its sender's
        // obligation, so its guard and refinements may read only registers the sender
        // knows (E0305 proves it of a verified protocol; checked again here so that the
        // monitor's single register file is never read beyond a role's knowledge).
        let from_bit = 1u64 << m.from.idx();
        let codes = guard.iter().chain(fields.iter().flat_map(|f: &FieldRead| f.refinement.iter()));
        for c in codes {
            let mut bad = None;
            let arena = &self.a.arena;
            c.expr.visit_vars(&mut |v, _| {
                if let crate::hir::Var::Value(id, name) = v {
                    let known = arena.reg_of.get(id).is_some_and(|r| arena.regs[*r as usize].knowers & from_bit != 0);
                    if !known {
                        bad = Some(name.clone());
                    }
                }
            });
            if let Some(name) = bad {
                return err(
                    format!(
                        "`{}` reads `{name}`, which its sender `{}` does not know",
                        m.label,
                        self.prog.role_name(m.from)
                    ),
                    Some(c.expr.loc.0),
                );
            }
        }
        let target = (layout.slot(msg, "target_system"), layout.slot(msg, "target_component"));
        self.a.edges.push(Edge {
            from: m.from,
            to: m.to,
            msgid: msg.id,
            label: m.label.clone(),
            key,
            guard,
            fields,
            target,
            target_state: k,
            observed,
            span,
        });
        Ok((self.a.edges.len() - 1) as u32)
    }

    /// Refuses a loop that can jump back to itself without a message (the run would
    /// assign forever): well-formed protocols are guarded, this keeps the monitor total.
    fn check_guarded(&self) -> Result<(), CompileError> {
        for s in 0..self.a.states.len() {
            let mut at = s;
            for _ in 0..=self.a.states.len() {
                match &self.a.states[at] {
                    StateKind::Assign { next, .. } => at = *next as usize,
                    _ => break,
                }
            }
            if let StateKind::Assign { span, .. } = &self.a.states[at] {
                return err("a loop that jumps back without a message", Some(*span));
            }
        }
        Ok(())
    }
}
