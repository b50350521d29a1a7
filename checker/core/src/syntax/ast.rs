//! The syntax tree: what the parser produces, with a span on every node and no name
//! resolution. Names are plain [`Ident`]s; `lower` resolves them.
//!
//! The shapes follow the paper's grammars: [`Global`] is Def 4.1 (plus `end` and
//! parameterised recursion for refined sessions), [`Local`] is Def 4.6, [`Process`] is
//! the calculus of Sec 3.1 and [`MotionDecl`] carries the contract of Def 3.4.

use crate::source::Span;

/// A name with where it was written. Compare names with `.name`.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Clone, Debug, Default)]
pub struct File {
    pub items: Vec<Item>,
}

#[derive(Clone, Debug)]
pub enum Item {
    Import(Import),
    /// `dialect NAME;`: the MAVLink dialect whose messages are the labels.
    Dialect(DialectDecl),
    Const(ConstDecl),
    Robot(RobotDecl),
    Motion(MotionDecl),
    System(SystemDecl),
    Choreography(ChorDecl),
    Process(ProcessDecl),
    Local(LocalDecl),
}

#[derive(Clone, Debug)]
pub struct Import {
    pub path: String,
    pub span: Span,
}

/// `dialect common;`: names a bundled MAVLink dialect (LANGUAGE.md, MAVLink messages).
#[derive(Clone, Debug)]
pub struct DialectDecl {
    pub name: Ident,
    pub span: Span,
}

/// `const name: sort = value;`
#[derive(Clone, Debug)]
pub struct ConstDecl {
    pub name: Ident,
    pub sort: Option<SortAst>,
    pub value: Expr,
    pub span: Span,
}

/// `name: sort`
#[derive(Clone, Debug)]
pub struct VarDecl {
    pub name: Ident,
    pub sort: SortAst,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SortAst {
    pub kind: SortKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum SortKind {
    Unit,
    Bool,
    Int,
    Real,
    Point,
    Vector,
    /// `str`: a MAVLink `char[N]` field's sort.
    Str,
    Product(Vec<SortAst>),
    /// A name the parser does not know (reported by lowering).
    Named(String),
}

/// `robot Kind { state ...; input ...; geometry: ...; mount m: pose(...); invariant: ...; }`
/// (Sec 3.1: X, W, `geom(p)`).
#[derive(Clone, Debug)]
pub struct RobotDecl {
    pub name: Ident,
    pub state: Vec<VarDecl>,
    pub inputs: Vec<VarDecl>,
    /// Every `geometry:` written (more than one is E0206, reported by lowering).
    pub geometry: Vec<BodyAst>,
    pub mounts: Vec<MountDecl>,
    pub invariant: Option<Expr>,
    pub span: Span,
}

/// A body: `part + part + ...` (LANGUAGE.md, Robots).
#[derive(Clone, Debug)]
pub struct BodyAst {
    pub parts: Vec<PartAst>,
    pub span: Span,
}

/// `shape(args)` optionally followed by `at pose(...)`.
#[derive(Clone, Debug)]
pub struct PartAst {
    pub shape: ShapeAst,
    pub place: Option<Pose>,
    pub span: Span,
}

/// A shape as written: its name and either numeric arguments or one file path (a string).
/// Which names exist and how many arguments each takes is checked by lowering (E0214),
/// so a misspelt shape does not cascade into parse errors.
#[derive(Clone, Debug)]
pub struct ShapeAst {
    pub name: Ident,
    pub args: Vec<Expr>,
    /// The string argument of `urdf("...")` or `mesh("...")` and its span. After
    /// [`crate::syntax::parse_with_imports`] the path is resolved against the directory of
    /// the file that names it (as imports are).
    pub path: Option<(String, Span)>,
    pub span: Span,
}

/// `mount name: pose(...);` in a robot.
#[derive(Clone, Debug)]
pub struct MountDecl {
    pub name: Ident,
    pub pose: Pose,
    pub span: Span,
}

/// `motion Kind.name(params) { fields }` (Def 3.4).
#[derive(Clone, Debug)]
pub struct MotionDecl {
    pub kind: Ident,
    pub name: Ident,
    pub params: Vec<VarDecl>,
    pub fields: Vec<MotionField>,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct MotionField {
    pub key: Ident,
    pub value: FieldValue,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub enum FieldValue {
    /// `pre`, `assume`, `guarantee`, `post`.
    Pred(Expr),
    /// `footprint(px, py, pz): pred`.
    Footprint { point: [Ident; 3], pred: Expr },
    /// `duration: [lo, hi]`, `hi` is `None` for `inf`.
    Duration { lo: Expr, hi: Option<Expr> },
    /// `interruptible: true|false`.
    Flag(bool),
    /// `footprint: geometry;`: the kind's own body (the span is `geometry`'s).
    OwnGeometry(Span),
    /// `footprint: box(...) at pose(...) + ...;`: a geometric footprint.
    Body(BodyAst),
}

/// `system Name { participant P: Kind { init: ...; at: pose(...); } obstacle O { ... } ... }`.
#[derive(Clone, Debug)]
pub struct SystemDecl {
    pub name: Ident,
    pub participants: Vec<ParticipantDecl>,
    pub obstacles: Vec<ObstacleDecl>,
    pub streams: Vec<StreamDecl>,
    pub span: Span,
}

/// `stream FROM -> TO, ...: LABEL(fields);` in a system: a message `FROM` sends to each `TO`
/// at any time, whose fields are observed state (LANGUAGE.md, "Observed state").
#[derive(Clone, Debug)]
pub struct StreamDecl {
    pub from: Ident,
    pub to: Vec<Ident>,
    pub label: Ident,
    pub payload: Vec<Field>,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct ParticipantDecl {
    pub name: Ident,
    /// `None` for a plain participant (`participant GCS;`): no state, no geometry, no
    /// motion primitives (a MAVLink ground station, an autopilot).
    pub kind: Option<Ident>,
    pub init: Option<Expr>,
    pub at: Option<Pose>,
    /// Every `on: Carrier.mount` written (more than one is E0206, reported by lowering).
    pub on: Vec<OnDecl>,
    pub span: Span,
}

/// `on: Carrier.mount` in a participant.
#[derive(Clone, Debug)]
pub struct OnDecl {
    pub carrier: Ident,
    pub mount: Ident,
    pub span: Span,
}

/// `obstacle Name { geometry: BODY; at: pose(...); }` in a system. Fields written twice are
/// kept so that lowering reports them (E0206).
#[derive(Clone, Debug)]
pub struct ObstacleDecl {
    pub name: Ident,
    pub geometry: Vec<BodyAst>,
    pub at: Vec<Pose>,
    pub span: Span,
}

/// `pose(x, y, z)` or `pose(x, y, z, roll, pitch, yaw)`.
#[derive(Clone, Debug)]
pub struct Pose {
    pub args: Vec<Expr>,
    pub span: Span,
}

/// `choreography Name = G;`
#[derive(Clone, Debug)]
pub struct ChorDecl {
    pub name: Ident,
    pub body: Global,
    pub span: Span,
    /// The partitions written after `*`s (`g1 * g2 partition(x, y, z) { P1; P2 }`).
    pub partitions: Vec<PartitionDecl>,
}

/// `partition(x, y, z) { P1; ...; Pn }` after the last side of an n-ary `*` whose span
/// is `par`: the region (a predicate over a world point) each side keeps to, the
/// `∃ FP1, FP2` of [AGCOMP] written out as PGCD requires.
#[derive(Clone, Debug)]
pub struct PartitionDecl {
    pub par: Span,
    pub point: [Ident; 3],
    pub regions: Vec<Expr>,
    pub span: Span,
}

/// `process Role = P;`
#[derive(Clone, Debug)]
pub struct ProcessDecl {
    pub role: Ident,
    pub body: Process,
    pub span: Span,
}

/// `local Role = T;` — the projection onto `Role` must equal `T`.
#[derive(Clone, Debug)]
pub struct LocalDecl {
    pub role: Ident,
    pub body: Local,
    pub span: Span,
}

/// A message payload field `x: sort { refinement }`. Of a MAVLink message (a program
/// with a `dialect`), `FIELD`, `FIELD as BINDER`, each with an optional `: sort` and
/// `{refinement}`: `name` is then the message's field (or a `MAV_CMD` parameter's label)
/// and `binder` the value's name when it differs.
#[derive(Clone, Debug)]
pub struct Field {
    pub name: Ident,
    pub binder: Option<Ident>,
    pub sort: Option<SortAst>,
    pub refinement: Option<Expr>,
}

impl Field {
    /// The name the field's value is bound to: the binder after `as`, else the field's.
    pub fn bound(&self) -> &Ident {
        self.binder.as_ref().unwrap_or(&self.name)
    }
}

/// A primitive applied to arguments: `m_move(x_G)`, or `work` with no arguments.
#[derive(Clone, Debug)]
pub struct PrimCall {
    pub name: Ident,
    pub args: Vec<Expr>,
    pub span: Span,
}

/// A parameter of a parameterised recursion `mu t(x: int { 0 <= x } = 0). G`.
#[derive(Clone, Debug)]
pub struct RecParam {
    pub name: Ident,
    pub sort: SortAst,
    pub refinement: Option<Expr>,
    pub init: Expr,
}

/// Global types (Def 4.1), with `+` and `*` n-ary and `.` as a flat sequence.
#[derive(Clone, Debug)]
pub enum Global {
    /// `p -> q : [guard] label(fields)`
    Msg(Msg),
    /// `dt<p: a(args), q: b>`
    Motion {
        parts: Vec<(Ident, PrimCall)>,
        span: Span,
    },
    /// `g1 . g2 . ...`
    Seq(Vec<Global>, Span),
    /// `g1 + g2 + ...`
    Choice(Vec<Global>, Span),
    /// `g1 * g2 * ...`
    Par(Vec<Global>, Span),
    /// `mu t. G` or `mu t(params). G`, optionally `mu t(params) decreases E. G`
    Rec {
        var: Ident,
        params: Vec<RecParam>,
        /// The termination measure `decreases E` (refined sessions).
        decreases: Option<Expr>,
        body: Box<Global>,
        span: Span,
    },
    /// `t` or `t(args)`
    Var {
        var: Ident,
        args: Vec<Expr>,
        span: Span,
    },
    End(Span),
    /// `after T ms by R`: the head of a choice's timeout branch (LANGUAGE.md, Timeouts).
    /// `R` takes the branch when no message of the other branches has reached it within
    /// `T` milliseconds of the choice being entered.
    After {
        bound: Expr,
        by: Ident,
        span: Span,
    },
}

#[derive(Clone, Debug)]
pub struct Msg {
    pub from: Ident,
    pub to: Ident,
    pub guard: Option<Expr>,
    /// The label; a MAVLink command is one label `COMMAND_LONG[MAV_CMD_X]` (written with
    /// any spacing, stored without), its span from the message name to the `]`.
    pub label: Ident,
    pub payload: Vec<Field>,
    pub span: Span,
}

impl Global {
    pub fn span(&self) -> Span {
        match self {
            Global::Msg(m) => m.span,
            Global::Motion { span, .. }
            | Global::Seq(_, span)
            | Global::Choice(_, span)
            | Global::Par(_, span)
            | Global::Rec { span, .. }
            | Global::Var { span, .. }
            | Global::After { span, .. }
            | Global::End(span) => *span,
        }
    }
}

/// Local types (Def 4.6), with `end` and parameterised recursion.
#[derive(Clone, Debug)]
pub enum Local {
    /// `dt<a>.T`, or `dt<a /\ b>.T` for a merged motion (Def 4.7).
    Motion {
        prims: Vec<PrimCall>,
        cont: Box<Local>,
        span: Span,
    },
    /// `+{ [g] q!l(fields).T, ... }` or a single `[g] q!l(fields).T`; the choice may end
    /// with the peer's timeout alternative `after T ms by R. T'`.
    Send {
        branches: Vec<LocalSend>,
        timeout: Option<Box<LocalTimeout>>,
        span: Span,
    },
    /// `&{ p?l(fields).T, ... }` optionally `& dt<a>.T`; the choice may end with this
    /// role's own timeout alternative `after T ms. T'`.
    Recv {
        branches: Vec<LocalRecv>,
        default: Option<(Vec<PrimCall>, Box<Local>)>,
        timeout: Option<Box<LocalTimeout>>,
        span: Span,
    },
    Rec {
        var: Ident,
        params: Vec<RecParam>,
        body: Box<Local>,
        span: Span,
    },
    Var {
        var: Ident,
        args: Vec<Expr>,
        span: Span,
    },
    End(Span),
}

#[derive(Clone, Debug)]
pub struct LocalSend {
    pub guard: Option<Expr>,
    pub to: Ident,
    pub label: Ident,
    pub payload: Vec<Field>,
    pub cont: Local,
    pub span: Span,
}

/// The timeout alternative of a local choice (LANGUAGE.md, Timeouts): `after T ms. T'` in
/// the waiting role's external choice (`by` is `None`: the role itself), `after T ms by R. T'`
/// in the sender's internal choice.
#[derive(Clone, Debug)]
pub struct LocalTimeout {
    pub bound: Expr,
    pub by: Option<Ident>,
    pub cont: Local,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct LocalRecv {
    pub from: Ident,
    pub label: Ident,
    pub payload: Vec<Field>,
    pub cont: Local,
    pub span: Span,
}

/// Processes (Sec 3.1).
#[derive(Clone, Debug)]
pub enum Process {
    /// `q!l(e, ...).P`
    Send {
        to: Ident,
        label: Ident,
        args: Vec<Expr>,
        cont: Box<Process>,
        span: Span,
    },
    /// `p?l(x, ...).P`
    Recv {
        from: Ident,
        label: Ident,
        binders: Vec<Ident>,
        cont: Box<Process>,
        span: Span,
    },
    /// `dt<a(e)>.P`
    Motion {
        prim: PrimCall,
        cont: Box<Process>,
        span: Span,
    },
    /// `P + Q + ...`: inputs (with at most one default motion) or outputs (Example 3.1).
    Sum(Vec<Process>, Span),
    /// `if e then P else Q`
    If {
        cond: Expr,
        then: Box<Process>,
        els: Box<Process>,
        span: Span,
    },
    /// `mu x. P` or `mu x(params). P`
    Rec {
        var: Ident,
        params: Vec<RecParam>,
        body: Box<Process>,
        span: Span,
    },
    /// `x` or `x(args)`
    Var {
        var: Ident,
        args: Vec<Expr>,
        span: Span,
    },
    End(Span),
}

impl Process {
    pub fn span(&self) -> Span {
        match self {
            Process::Send { span, .. }
            | Process::Recv { span, .. }
            | Process::Motion { span, .. }
            | Process::Sum(_, span)
            | Process::If { span, .. }
            | Process::Rec { span, .. }
            | Process::Var { span, .. }
            | Process::End(span) => *span,
        }
    }
}

/// Predicates and terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Int(i64),
    /// A real literal kept as written, so no precision is lost before the solver.
    Real(String),
    Bool(bool),
    /// A string literal `"MC_PITCH_P"` (compared with `char[N]` MAVLink fields).
    Str(String),
    Var(String),
    /// `e.name`: a participant's variable (`Cart.x`) or a component (`p.x`).
    Dot(Box<Expr>, Ident),
    Call(Ident, Vec<Expr>),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    If(Box<Expr>, Box<Expr>, Box<Expr>),
    Tuple(Vec<Expr>),
    /// A parse error placeholder; never reaches lowering without a diagnostic.
    Error,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnOp {
    Neg,
    Not,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    And,
    Or,
    Implies,
}

impl BinOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Pow => "^",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::And => "&&",
            BinOp::Or => "||",
            BinOp::Implies => "=>",
        }
    }

    /// Binding strength, higher binds tighter.
    pub fn precedence(self) -> u8 {
        match self {
            BinOp::Implies => 1,
            BinOp::Or => 2,
            BinOp::And => 3,
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 4,
            BinOp::Add | BinOp::Sub => 5,
            BinOp::Mul | BinOp::Div => 6,
            BinOp::Pow => 8,
        }
    }

    pub fn is_comparison(self) -> bool {
        self.precedence() == 4
    }
}
