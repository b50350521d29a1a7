//! Lowering: the parsed files → a resolved [`Program`]. Resolves every name (robot
//! kinds, primitives, participants, variables, recursion variables), infers the sort
//! of every expression and enforces which variables each part of a contract may read
//! (Def 3.4). Errors are E02xx; lowering reports them all and still returns a program,
//! but later stages only run on a program lowered without errors. An expression that
//! fails becomes [`Expr::error`]: its sort fits everywhere and an expression with a failed
//! part fails with it, silently, so each mistake is reported once.
//!
//! Name lookup for an unqualified name, innermost first: value variables in scope
//! (payload fields, recursion parameters, process binders), primitive parameters, the
//! footprint's point coordinates, `clock`, the robot's own state and input variables,
//! constants. `Cart.x` names a participant's variable; `e.x` a component of a point.
//!
//! The pass structure: [`lower`] runs over all items in a fixed order, so that every
//! name is declared before anything resolves it, whatever the order of the files:
//! constants (`decl`, in dependency order), robot kinds, then their invariants (which
//! may read constants) and bodies and mounts (`body`), primitives (`contract`), the system and its input connections
//! (`decl`; obstacles and mounts in `body`), and last the choreography, local types (`types`) and processes
//! (`process`). Expressions (`expr`) resolve names through `names` in an `Env`
//! that says which variables the current position may read.

mod body;
mod contract;
mod decl;
mod expr;
mod mav;
pub use crate::float::{dyadic_decimal, float_format, is_float, pow2, round_to_float, FloatFormat, BINARY32, BINARY64};
pub use mav::{approximate_entries, entry_allows, entry_predicate, float_definition_decided, refinement_without_entry};
pub use mav::{exact_constant, wire_value};
#[cfg(test)]
mod mav_tests;
mod names;
mod observed;
mod process;
#[cfg(test)]
pub(crate) mod tests;
mod types;

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
    l.dialects(&items);
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
            l.robot_body(r);
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
    if l.prog.system.is_some() {
        // The first system's streams (a second system is E0206, reported above).
        if let Some(ast::Item::System(s)) = items.iter().find(|it| matches!(it, ast::Item::System(_))) {
            l.streams(s);
        }
    }
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
pub fn lower_local(prog: &Program, role: RoleId, t: &ast::Local) -> (LocalArc, Vec<Diagnostic>) {
    let mut l = Lowerer { prog: prog.clone(), ..Lowerer::default() };
    l.consts = prog.consts.iter().enumerate().map(|(i, c)| (c.name.clone(), ConstId(i as u32))).collect();
    l.kinds = prog.kinds.iter().enumerate().map(|(i, k)| (k.name.clone(), KindId(i as u32))).collect();
    // Enum entries the program interned already keep their constants (and ids).
    if let Some(d) = prog.dialect {
        l.entry_consts = l.consts.iter().filter(|(n, _)| d.entry(n).is_some()).map(|(n, c)| (n.clone(), *c)).collect();
        l.dialect_decl = Some((d.name.clone(), Span::default()));
    }
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
    /// Kinds that wrote a `geometry:`, lowered or not (a malformed one is reported at the
    /// kind, so `footprint: geometry` in its primitives is not E0215 on top).
    kinds_with_geometry: std::collections::HashSet<KindId>,
    /// Participants whose kind is unknown: already reported, so uses stay silent.
    poisoned: std::collections::HashSet<String>,
    /// Process and local type declarations seen per role.
    process_roles: HashMap<RoleId, Span>,
    local_roles: HashMap<RoleId, Span>,
    /// The first `dialect` item: its name and span.
    dialect_decl: Option<(String, Span)>,
    /// The dialect named could not be found (E0230): messages are not checked.
    dialect_failed: bool,
    /// Enum entries of the dialect interned as constants so far ([`Lowerer::entry_const`]).
    entry_consts: HashMap<String, ConstId>,
    /// The kind of plain participants ([`PLAIN_KIND`]), made on first use.
    plain_kind: Option<KindId>,
    /// Deprecated MAVLink messages warned about (E0244, once each).
    deprecated_seen: std::collections::HashSet<String>,
    /// The participant deciding at the message being lowered (its guard and payload), where
    /// observed values are read: for the diagnostic of a read of a stream it does not see.
    deciding: Option<RoleId>,
    /// Lowering a process body: an observed value read there is E0715 (not supported yet).
    in_process: bool,
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

/// E0206 for each name of one binder list (a receive's binders, a message's fields, a
/// `mu`'s parameters, a point's coordinates) that repeats an earlier one: the second would
/// hide the first from everything after it. Returns whether the names are distinct.
fn distinct<'i>(what: &str, names: impl IntoIterator<Item = &'i ast::Ident>, diags: &mut Vec<Diagnostic>) -> bool {
    let mut seen: Vec<&ast::Ident> = Vec::new();
    let mut ok = true;
    for b in names {
        if let Some(first) = seen.iter().find(|f| f.name == b.name) {
            diags.push(dup(b.span, what, &b.name, first.span));
            ok = false;
        }
        seen.push(b);
    }
    ok
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
}

/// Value variables and recursion variables in scope while lowering a type or process.
#[derive(Default)]
struct Scopes {
    values: Vec<ValueId>,
    /// The recursion variables in scope, innermost last, with their parameters' sorts.
    recs: Vec<(String, Vec<Sort>)>,
    /// The snapshot of observed values taken at a choice, for its branches' first messages
    /// (taken by the first message lowered; see `lower::observed`).
    choice_snapshot: Option<Vec<Observed>>,
    /// Whether the node being lowered starts a branch of a choice: the one place a timeout
    /// head `after T ms by R` may stand (E0321 elsewhere).
    branch_head: bool,
}
