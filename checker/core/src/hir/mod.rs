//! The HIR: the program after name resolution. Names are ids into the tables of
//! [`Program`]; every node keeps a [`Loc`] for diagnostics. Equality ignores locations,
//! so two local types written in different places compare equal when they say the same
//! thing (the merge of Def 4.7 relies on this).
//!
//! Submodules follow the paper: [`expr`] (predicates and sorts), [`global`] (Def 4.1),
//! [`local`] (Def 4.6), [`process`] (Sec 3.1), [`print`] (mochi's ASCII notation).

pub mod body;
pub mod expr;
pub mod global;
pub mod local;
pub mod node;
pub mod print;
pub mod process;

pub use expr::{Builtin, Expr, ExprKind, Slot, Sort, Var};
pub use global::{labels_overlap, After, EnumCheck, Field, Global, MavField, Motion, Msg, PrimApp, RecParam, RecVar};
pub use local::{Local, LocalArc, RecvBranch, SendBranch, Timeout};
pub use process::{Process, RecvArm};

use crate::source::Span;
use std::fmt;

/// A source location that never takes part in equality or hashing.
#[derive(Clone, Copy, Default)]
pub struct Loc(pub Span);

impl PartialEq for Loc {
    fn eq(&self, _: &Loc) -> bool {
        true
    }
}
impl Eq for Loc {}
impl std::hash::Hash for Loc {
    fn hash<H: std::hash::Hasher>(&self, _: &mut H) {}
}
impl fmt::Debug for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "@{:?}", self.0)
    }
}

macro_rules! id {
    ($(#[$m:meta])* $name:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub u32);
        impl $name {
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }
    };
}

id!(/// A named constant.
    ConstId);
id!(/// A robot kind (`robot K { ... }`).
    KindId);
id!(/// A motion primitive of some kind.
    PrimId);
id!(/// A participant (role) of the system.
    RoleId);
id!(/// A value variable: a payload field, a recursion parameter or a process binder.
    ValueId);

#[derive(Clone, Debug)]
pub struct Const {
    pub name: String,
    pub sort: Sort,
    pub value: Expr,
    pub span: Span,
}

/// The name of the kind of plain participants (`participant GCS;`): no state, no inputs,
/// no body, no primitives. It cannot be written (it is not an identifier), so no `robot`
/// item and no `participant P: Kind` can name it.
pub const PLAIN_KIND: &str = "<plain>";

/// A robot kind: state variables X, input variables W (Sec 3.1), geometry, invariant.
#[derive(Clone, Debug)]
pub struct RobotKind {
    pub name: String,
    pub state: Vec<(String, Sort)>,
    pub inputs: Vec<(String, Sort)>,
    /// The robot's body as a function of its state (`geom(p)` of Sec 3.1), in its frame:
    /// `geometry:`, whose poses read the kind's state variables ([`Var::Own`]) and
    /// constants. A kind with no body may be bodiless (E0412).
    pub body: Option<body::Body>,
    /// Frames other participants can be mounted on (`on: Carrier.mount`).
    pub mounts: Vec<body::Mount>,
    pub invariant: Option<Expr>,
    /// What every motion of the robot satisfies at every time, from its URDF's velocity
    /// limits: `J - old(J) <= v * clock && old(J) - J <= v * clock` for each joint `J` with
    /// `<limit velocity="v">` (checker/verify/src/space/world.rs, `add_joint_limits`). Used where a
    /// motion must be able to end (E0408, E0409): a contract whose postcondition needs a
    /// joint to move faster than that cannot end. `None`: no such limit.
    pub speed: Option<Expr>,
    pub span: Span,
}

impl RobotKind {
    /// The state or input variable called `name`, with its sort.
    pub fn slot(&self, name: &str) -> Option<(Slot, &Sort)> {
        let find = |vars: &[(String, Sort)]| vars.iter().position(|(n, _)| n == name);
        find(&self.state)
            .map(Slot::State)
            .or_else(|| find(&self.inputs).map(Slot::Input))
            .map(|slot| (slot, &self.var(slot).1))
    }

    /// The name and sort of a variable.
    pub fn var(&self, slot: Slot) -> &(String, Sort) {
        match slot {
            Slot::State(i) => &self.state[i],
            Slot::Input(i) => &self.inputs[i],
        }
    }
}

/// A footprint predicate over the point `(x, y, z)` named by the user (or `x, y, z` for
/// one derived from shapes), the state, `old(X)`, parameters and `clock` (Def 3.4's FP).
#[derive(Clone, Debug)]
pub struct PointPred {
    pub point: [String; 3],
    pub pred: Expr,
}

/// The footprint of a primitive (Def 3.4's FP), one value per way of writing it. Every
/// check that reads a footprint matches on it exhaustively: a geometric footprint with no
/// predicate ([`Footprint::Solid`]) is decided by the geometric procedure or reported
/// unknown, never read as all space where that would let a check pass.
#[derive(Clone, Debug)]
pub enum Footprint {
    /// No `footprint` field: the primitive may occupy all space (Def 3.4 with FP = R³).
    /// Exact, not an approximation: a check for which all space is the worst case
    /// (collision, containment of the body, the abstract side of a refinement) reads it so.
    Everywhere,
    /// `footprint(px, py, pz): P;`.
    Predicate(PointPred),
    /// A geometric footprint (`footprint: geometry;` when `own`, else `footprint: SHAPES;`)
    /// all of whose parts are boxes, spheres, cylinders or capsules: at time `t` the body
    /// placed by the state at `t`, with its exact predicate (`space::region`, filled by
    /// `space::prepare`).
    Shapes { body: body::Body, own: bool, region: PointPred },
    /// A geometric footprint with a URDF or mesh part: a body only the geometric decision
    /// procedure can place; it has no predicate. Lowering makes every geometric footprint
    /// one of these; `space::prepare` turns those it can write as a predicate into
    /// [`Footprint::Shapes`].
    Solid { body: body::Body, own: bool },
}

impl Footprint {
    /// The exact predicate of the footprint, if it has one. `None` for
    /// [`Footprint::Everywhere`] (all space) and [`Footprint::Solid`] (no predicate): a
    /// caller must tell the two apart.
    pub fn predicate(&self) -> Option<&PointPred> {
        match self {
            Footprint::Predicate(p) | Footprint::Shapes { region: p, .. } => Some(p),
            Footprint::Everywhere | Footprint::Solid { .. } => None,
        }
    }

    /// The body of a geometric footprint.
    pub fn body(&self) -> Option<&body::Body> {
        match self {
            Footprint::Shapes { body, .. } | Footprint::Solid { body, .. } => Some(body),
            Footprint::Everywhere | Footprint::Predicate(_) => None,
        }
    }

    /// Whether the primitive declares a footprint (anything but all space).
    pub fn is_declared(&self) -> bool {
        !matches!(self, Footprint::Everywhere)
    }

    /// Whether the footprint is `footprint: geometry;`, the kind's own body.
    pub fn is_own_geometry(&self) -> bool {
        match self {
            Footprint::Shapes { own, .. } | Footprint::Solid { own, .. } => *own,
            Footprint::Everywhere | Footprint::Predicate(_) => false,
        }
    }

    /// Where the footprint is written, if it is.
    pub fn span(&self) -> Option<Span> {
        match self {
            Footprint::Everywhere => None,
            Footprint::Predicate(p) => Some(p.pred.loc.0),
            Footprint::Shapes { body, .. } | Footprint::Solid { body, .. } => Some(body.span),
        }
    }
}

/// `[lo, hi]`, `hi = None` for infinity (Def 3.4's `D`).
#[derive(Clone, Debug)]
pub struct Duration {
    pub lo: Expr,
    pub hi: Option<Expr>,
}

/// A motion primitive `a ⊢ (Pre, A, G, Post, FP, D, ‡)` (Def 3.4). Predicates read the
/// kind's variables through [`Var::Own`], parameters through [`Var::Param`].
#[derive(Clone, Debug)]
pub struct Primitive {
    pub name: String,
    pub kind: KindId,
    pub params: Vec<(String, Sort)>,
    pub pre: Expr,
    pub assume: Expr,
    pub guarantee: Expr,
    pub post: Expr,
    /// A geometric footprint's body is placed at time `t` by the state at `t` (poses may
    /// read X, `old(X)`, parameters and `clock`).
    pub footprint: Footprint,
    pub duration: Duration,
    pub interruptible: bool,
    pub span: Span,
    pub name_span: Span,
}

/// A participant: an instance of a robot kind with an initial-state predicate and a pose.
#[derive(Clone, Debug)]
pub struct Participant {
    pub name: String,
    pub kind: KindId,
    /// Over the participant's own variables ([`Var::Role`]).
    pub init: Option<Expr>,
    /// `x, y, z[, roll, pitch, yaw]`, constants only.
    pub pose: Vec<Expr>,
    /// For each input variable of the kind, the participant whose state feeds it.
    pub input_sources: Vec<Option<RoleId>>,
    /// `on: Carrier.mount`: the participant rides on another; its `pose` is then relative
    /// to the mount's frame, which moves with the carrier's state.
    pub mounted_on: Option<body::MountedOn>,
    pub span: Span,
}

/// Where a value variable comes from, which decides who knows it.
#[derive(Clone, Debug, PartialEq)]
pub enum ValueOrigin {
    /// A payload field of `from -> to`: known to both.
    Message { from: RoleId, to: RoleId },
    /// A recursion parameter: protocol state known to every participant.
    RecParam,
    /// A variable bound by a receive (or a recursion) in `role`'s process or local type.
    Bound { role: RoleId },
    /// A field of a stream declaration ([`Stream`]) as declared: the template each snapshot
    /// copies. No expression outside the stream's own invariant reads it.
    Stream { stream: u32 },
    /// A snapshot of an observed value: the latest value of a field of stream `stream` that
    /// `reader` had received when it evaluated one message's guard and refinements (or one
    /// choice's). Known to `reader` only; a fresh value at every step (LANGUAGE.md,
    /// "Observed state").
    Observed { reader: RoleId, stream: u32 },
}

impl ValueOrigin {
    /// Whether `role` never holds a value of this origin: a payload field of a message
    /// between two other participants, a snapshot another participant took, or a stream's
    /// template field (which only its own invariant reads).
    pub fn unheld_by(&self, role: RoleId) -> bool {
        match self {
            ValueOrigin::Message { from, to } => *from != role && *to != role,
            ValueOrigin::Observed { reader, .. } => *reader != role,
            ValueOrigin::Stream { .. } => true,
            ValueOrigin::RecParam | ValueOrigin::Bound { .. } => false,
        }
    }
}

#[derive(Clone, Debug)]
pub struct ValueVar {
    pub name: String,
    pub sort: Sort,
    pub origin: ValueOrigin,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct Choreography {
    pub name: String,
    pub body: Global,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct ProcessDef {
    pub role: RoleId,
    pub body: Process,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct LocalDef {
    pub role: RoleId,
    pub body: LocalArc,
    pub span: Span,
}

/// A partition written after a `*` (span `par`): the region of the world, a predicate
/// over the point named `point` ([`Var::Point`]), that each side keeps to.
#[derive(Clone, Debug)]
pub struct Partition {
    pub par: Span,
    pub point: [String; 3],
    pub regions: Vec<Expr>,
    pub span: Span,
}

/// A whole resolved program: the tables every later stage reads.
#[derive(Clone, Debug, Default)]
pub struct Program {
    pub consts: Vec<Const>,
    pub kinds: Vec<RobotKind>,
    pub prims: Vec<Primitive>,
    pub roles: Vec<Participant>,
    pub values: Vec<ValueVar>,
    pub system: Option<(String, Span)>,
    pub choreography: Option<Choreography>,
    pub processes: Vec<ProcessDef>,
    pub locals: Vec<LocalDef>,
    pub partitions: Vec<Partition>,
    /// The system's static obstacles.
    pub obstacles: Vec<body::Obstacle>,
    /// Every body as solids, set by the verifier's geometry stage (`space::world::World`
    /// in `mochi-verify`, read back with `space::world::of`). The core does not depend on
    /// the geometry engine, so it holds the solids without knowing their type.
    pub world: Option<std::sync::Arc<dyn std::any::Any + Send + Sync>>,
    /// The MAVLink dialect named by `dialect NAME;`: message labels are its
    /// messages, its enum entries are `int` constants.
    pub dialect: Option<&'static crate::dialect::Dialect>,
    /// The string literals of the program, each once: a literal of sort `str` is
    /// `ExprKind::Int(code)` with `code` its index here ([`Sort::Str`]).
    pub strings: Vec<String>,
    /// The values of MAVLink `float` and `double` fields, with [`Builtin::Float32`] or
    /// [`Builtin::Float64`]: every such value is a finite float of that format (the
    /// model of LANGUAGE.md, "Floats are float32"), a fact the encoder may use anywhere.
    pub wire_floats: std::collections::HashMap<ValueId, Builtin>,
    /// The values of MAVLink `char[N]` fields (and streams' snapshots of them), with N:
    /// the wire carries at most N characters of such a value, a length the checks do not
    /// otherwise see (a string is one code to them). Read by E0236 (a refinement comparing
    /// a field with a wider value) and [T-OUT] (a process sending a wider string).
    pub str_width: std::collections::HashMap<ValueId, u32>,
    /// The system's streams (`stream UAV -> GCS: HEARTBEAT(base_mode);`), in declaration order.
    pub streams: Vec<Stream>,
}

/// `stream from -> to, ...: LABEL(fields)`: `from` sends `LABEL` at any time, any number of
/// times, to each of `to`; it is no step of the session. Each field is observed: a guard or
/// refinement of a message sent by a participant that receives the stream (or by `from`)
/// reads the latest value it has seen, a fresh snapshot at each message ([`Observed`]).
/// The fields' refinements (the wire range and the user's invariant) are what every value
/// of the stream satisfies: an assumption, enforced by a monitor at run time.
#[derive(Clone, Debug)]
pub struct Stream {
    pub from: RoleId,
    pub to: Vec<RoleId>,
    pub label: String,
    /// The template fields (values of origin [`ValueOrigin::Stream`]).
    pub fields: Vec<global::Field>,
    pub loc: Loc,
}

impl Stream {
    /// Whether `r` sees the stream's values: its sender or one of its receivers.
    pub fn seen_by(&self, r: RoleId) -> bool {
        self.from == r || self.to.contains(&r)
    }
}

/// A snapshot of an observed field read by one message (or one choice: the branches' first
/// messages share it): a fresh value of the stream field `field` of stream `stream`, with
/// `refinement` (the field's wire range and the stream's invariant, over the snapshots of
/// the same stream message taken at the same step) assumed, and nothing else.
#[derive(Clone, Debug, PartialEq)]
pub struct Observed {
    pub value: ValueId,
    pub name: String,
    pub sort: Sort,
    pub stream: u32,
    pub field: u32,
    pub refinement: Option<Expr>,
}

impl Program {
    pub fn role(&self, r: RoleId) -> &Participant {
        &self.roles[r.idx()]
    }
    pub fn role_name(&self, r: RoleId) -> &str {
        &self.roles[r.idx()].name
    }
    pub fn role_by_name(&self, name: &str) -> Option<RoleId> {
        self.roles.iter().position(|p| p.name == name).map(|i| RoleId(i as u32))
    }
    pub fn role_ids(&self) -> impl Iterator<Item = RoleId> {
        (0..self.roles.len() as u32).map(RoleId)
    }
    pub fn prim(&self, p: PrimId) -> &Primitive {
        &self.prims[p.idx()]
    }
    pub fn kind(&self, k: KindId) -> &RobotKind {
        &self.kinds[k.idx()]
    }
    pub fn kind_of(&self, r: RoleId) -> &RobotKind {
        self.kind(self.role(r).kind)
    }
    /// Whether `r` is a plain participant (`participant GCS;`): its kind is the synthetic
    /// empty one lowering gives every plain participant, [`PLAIN_KIND`].
    pub fn is_plain(&self, r: RoleId) -> bool {
        self.kind_of(r).name == PLAIN_KIND
    }
    /// The text of a string literal's code ([`Sort::Str`]).
    pub fn string(&self, code: i64) -> Option<&str> {
        usize::try_from(code).ok().and_then(|i| self.strings.get(i)).map(String::as_str)
    }

    /// How many characters string `e` may hold at most ([`Program::str_width`]): a
    /// literal's length, a value's width (or `bound(v)`'s, for values this table does not
    /// hold: a process's binders), the wider branch of an `if`; `None` when unknown.
    pub fn str_width_of(&self, e: &Expr, bound: &dyn Fn(ValueId) -> Option<u32>) -> Option<u32> {
        match &e.kind {
            ExprKind::Var(Var::Value(v, _)) => self.str_width.get(v).copied().or_else(|| bound(*v)),
            ExprKind::Int(code) if e.sort == Sort::Str => self.string(*code).map(|t| t.len() as u32),
            ExprKind::If(_, a, b) => Some(self.str_width_of(a, bound)?.max(self.str_width_of(b, bound)?)),
            _ => None,
        }
    }
    /// For [T-SESS]: each participant's possible first primitives, in role order.
    /// Participants that never move are left out (they have no footprint to place).
    pub fn first_motions(&self) -> Vec<(RoleId, Vec<PrimApp>)> {
        let Some(chor) = &self.choreography else { return Vec::new() };
        self.role_ids()
            .filter_map(|r| {
                let mut apps = Vec::new();
                chor.body.first_primitives(r, &mut apps);
                (!apps.is_empty()).then_some((r, apps))
            })
            .collect()
    }

    /// The variable a participant's input stands for: the connected participant's state
    /// variable of the same name (Sec 3.1). Other variables are themselves.
    pub fn source_of(&self, v: &Var) -> Var {
        if let Var::Role(r, Slot::Input(i)) = v {
            let name = &self.kind_of(*r).inputs[*i].0;
            let src = self.role(*r).input_sources.get(*i).copied().flatten();
            if let Some((s, slot @ Slot::State(_))) = src.and_then(|s| Some((s, self.kind_of(s).slot(name)?.0))) {
                return Var::Role(s, slot);
            }
        }
        v.clone()
    }

    /// The partition written for the `*` at `par`, if any.
    pub fn partition(&self, par: Span) -> Option<&Partition> {
        self.partitions.iter().find(|p| p.par == par)
    }

    pub fn value(&self, v: ValueId) -> &ValueVar {
        &self.values[v.idx()]
    }
    /// The name of a participant's variable, qualified: `Cart.x`.
    pub fn slot_name(&self, kind: KindId, slot: Slot) -> &str {
        &self.kind(kind).var(slot).0
    }
}
