//! Process typing (Table 1): each participant's process against its projection, with
//! [T-SUB] (Fig 5) folded into the rules so the check is algorithmic.
//!
//! The judgement is `Σ ⊢ P : T`, where Σ (a list of conjuncts) is what is known about
//! the state when `P` runs. It starts as the participant's `init` predicate and its
//! kind's invariant, and evolves as in Table 1:
//! - [T-OUT] a send matches a branch of `⊕` (with [SUB-OUT] the process may use a
//!   subset of the branches); the obligation is `Σ ⇒ P ∧ P'{e/v}`;
//! - [T-CHOICE1,2] a receive handles every label of `&` from the same sender (more are
//!   allowed, [SUB-IN]); each branch continues under `Σ ∧ P_i{x_i/v}`;
//! - [T-MOTION] a motion matches `dt<a>` (or refines it, [SUB-MOTION]); the obligation
//!   is `Σ ⇒ Pre`, and afterwards Σ is the strongest postcondition of the motion
//!   ([`Sigma::apply_motion`]): what held of the participant's variables now holds of their
//!   snapshot `old(r.x)`, and the primitive's postcondition (with its `old(x)`) and the
//!   kind's invariant are added, so `x == old(x)` keeps the position known before.
//!   Facts about other participants are forgotten: they moved too, in ways this process
//!   cannot see. The paper's rule takes Σ := Post; ours implies it and is still sound;
//! - `if e then P else Q` checks both branches against the same type under `Σ ∧ e` and
//!   `Σ ∧ ¬e`. This generalises [T-COND]: with [SUB-OUT] each branch may implement a
//!   subset of the labels of `⊕`, and the guards are checked at each send;
//! - [T-REC] is checked coinductively. Recursion of the type unfolds through an
//!   environment; a process loop body met again with the same type node and the same
//!   context is assumed well typed, so a process may unfold its loop at a different
//!   point than its type. Contexts differ between iterations, so the body is checked
//!   under each new one; after [`WIDEN_AFTER`] contexts for one pair the context is
//!   widened to the invariant (the paper's `true` context of [T-REC]);
//! - [T-REC]/[T-VAR] with parameters (DATUM): a process loop's refinement holds of its
//!   initial value (E0712) and of each jump's arguments (E0713) and is assumed in the
//!   body. The type's parameters are values the process follows in `vals`; where process
//!   and type enter or repeat their loops at the same step with as many parameters, the
//!   process's stand for the type's and must get the same values (E0714).
//!
//! Every structural error is reported and the check continues with the next branch.
//! [T-SESS] contributes one obligation: the initial geometries are disjoint.
//!
//! The files, one rule each: `walk.rs` follows process and type together and picks
//! the rule by their shapes; `out.rs` is [T-OUT], `choice.rs` [T-CHOICE1,2],
//! `motion.rs` [T-MOTION], `rec.rs` [T-REC]/[T-VAR] (coinduction and loop
//! parameters), `report.rs` the structural errors E0702/E0706; this file holds
//! [T-SESS], the checker and its state.

mod choice;
mod motion;
mod out;
mod rec;
mod report;
mod walk;

use crate::diag::{Code, Diagnostic};
use crate::hir::expr::mentions;
use crate::hir::node::NodeRef;
use crate::hir::print::{print_bounded, NOTE_NODES};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::{self, Sigma};
use crate::subtype::RecEnv;
use std::collections::{BTreeMap, HashMap, HashSet};

/// Checks every participant's process against its projection. Participants whose
/// projection failed are skipped (the projection error is reported already).
pub fn check_processes(prog: &Program, projections: &BTreeMap<RoleId, LocalArc>) -> (Vec<Obligation>, Vec<Diagnostic>) {
    let (obligations, diags, _) = check_processes_hinted(prog, projections);
    (obligations, diags)
}

/// [`check_processes`], with advice for obligations whose failure has a more precise fix
/// than their code's help ([`Hints`]).
pub fn check_processes_hinted(
    prog: &Program,
    projections: &BTreeMap<RoleId, LocalArc>,
) -> (Vec<Obligation>, Vec<Diagnostic>, Hints) {
    let mut hints = Hints::new();
    let mut diags = Vec::new();
    let mut obligations = Vec::new();
    if let Some(d) = observed_in_process(prog).or_else(|| timeout_in_process(prog)) {
        return (obligations, vec![d], hints);
    }
    for role in prog.role_ids() {
        let name = prog.role_name(role);
        let Some(def) = prog.processes.iter().find(|p| p.role == role) else {
            // A program with no process at all is a protocol (a MAVLink sub-protocol, or a
            // robot cell checked before its programs exist): its global type and
            // projections are checked, no process is typed (the report says so). [T-SESS]
            // below is still asked.
            if protocol_only(prog) {
                continue;
            }
            let mut d = Diagnostic::error(
                Code::MissingProcess,
                prog.role(role).span,
                format!("participant `{name}` has no process"),
            )
            .with_help(format!("add `process {name} = ...;` implementing its local type"));
            if let Some(t) = projections.get(&role) {
                d = d.with_note(format!("its local type is:\n{}", print_bounded(prog, t, NOTE_NODES)));
            }
            diags.push(d);
            continue;
        };
        let Some(ty) = projections.get(&role) else {
            continue;
        };
        let mut c = Checker::new(prog, role);
        let sigma = Sigma::from_facts(&c.initial());
        let st = State { sigma, vals: HashMap::new(), penv: Vec::new(), tenv: Vec::new(), actions: 0 };
        c.check(&def.body, ty.clone(), st);
        diags.extend(c.diags);
        obligations.extend(c.obligations);
        hints.extend(c.hints);
    }
    if protocol_only(prog) {
        if let Some((sys, span)) = &prog.system {
            let d = if prog.dialect.is_some() {
                Diagnostic::note_at(
                    Code::ProtocolOnly,
                    *span,
                    format!("protocol only: `{sys}` names a dialect and no process, so no process was typed"),
                )
                .with_note("the global type and its projections are checked; `mochi project FILE --role R` prints each participant's local type")
            } else {
                Diagnostic::note_at(
                    Code::ProtocolOnly,
                    *span,
                    format!("protocol only: `{sys}` has no process, so no process was typed"),
                )
                .with_note("the choreography is checked (well-formedness, projections, the initial states, compatibility, collisions and separation of every joint motion, the primitives' contracts); no motion's precondition is checked against the state a program reaches, which only typing a process does")
                .with_note("`mochi project FILE --role R` prints each participant's local type")
            };
            diags.push(d.with_help(
                "add a `process` for every participant to have implementations typed against their projections",
            ));
        }
    }
    // [T-SESS]: the initial states are collision free.
    let span = prog.system.as_ref().map(|(_, s)| *s).or_else(|| prog.roles.first().map(|r| r.span));
    if let Some(span) = span {
        let mut hyps = Vec::new();
        for role in prog.role_ids() {
            hyps.extend(Checker::new(prog, role).initial());
        }
        obligations.push(Obligation {
            rule: Rule::TSess,
            span,
            what: "the participants' initial geometries are pairwise disjoint".to_string(),
            hyps,
            goal: Goal::InitiallyDisjoint { firsts: prog.first_motions() },
        });
    }
    let mut seen = HashSet::new();
    diags.retain(|d| seen.insert((d.code, d.span, d.message.clone())));
    dedupe(&mut obligations);
    (obligations, diags, hints)
}

/// Whether `prog` is a protocol only: it has no `process` item (a MAVLink sub-protocol,
/// or a robot cell whose choreography is checked before its programs are written). Then
/// no process is typed and E0701 is not asked. With one process, every participant needs
/// one: a partial set of processes is most likely an omission, and a cell half typed
/// would read as typed, so each missing one is E0701.
/// E0715: processes typed against a protocol that reads observed values (LANGUAGE.md,
/// "Observed state"). The typing rules do not know snapshots yet, so such a program is
/// refused here rather than typed as if the readings were ordinary values.
fn observed_in_process(prog: &Program) -> Option<Diagnostic> {
    if prog.processes.is_empty() {
        return None;
    }
    let chor = prog.choreography.as_ref()?;
    let m = first_observing(&chor.body)?;
    let o = &m.observed[0];
    Some(
        Diagnostic::error(
            Code::ObservedInProcess,
            m.loc.0,
            format!(
                "not supported yet: this message reads the observed value `{}`, and processes are typed against this protocol",
                o.name
            ),
        )
        .with_label(prog.role(m.from).span, "a process is typed for this participant")
        .with_note("process typing does not know snapshots of observed state yet; the protocol alone is checked over fresh readings")
        .with_help("remove the `process` items to check the protocol alone, or send the reading in a payload field and guard on that field"),
    )
}

/// E0325: processes typed against a protocol with a timeout branch (LANGUAGE.md,
/// Timeouts). The process language has no timeout, and a process of the choice's sender
/// would have to expect the waiting role's message after the timeout at every point of
/// the branch it chose: such a program is refused rather than typed without the timeout.
fn timeout_in_process(prog: &Program) -> Option<Diagnostic> {
    if prog.processes.is_empty() {
        return None;
    }
    let a = first_timeout(&prog.choreography.as_ref()?.body)?;
    Some(
        Diagnostic::error(
            Code::TimeoutInProcess,
            a.loc.0,
            "not supported yet: this choice has a timeout branch, and processes are typed against this protocol",
        )
        .with_label(prog.role(a.by).span, "a process is typed for this participant")
        .with_note("the process language has no timeout; the protocol alone is checked (well-formedness, total choice, progress, termination)")
        .with_help("remove the `process` items to check the protocol alone"),
    )
}

/// The first timeout head, in the order of the type.
pub fn first_timeout(g: &Global) -> Option<&After> {
    match g {
        Global::After(a) => Some(a),
        Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => gs.iter().find_map(first_timeout),
        Global::Rec { body, .. } => crate::stack::deep(|| first_timeout(body)),
        Global::Msg(_) | Global::Motion(_) | Global::Var(_) | Global::End(_) => None,
    }
}

/// The first message, in the order of the type, that reads an observed value.
fn first_observing(g: &Global) -> Option<&Msg> {
    match g {
        Global::Msg(m) => (!m.observed.is_empty()).then_some(m),
        Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => gs.iter().find_map(first_observing),
        Global::Rec { body, .. } => crate::stack::deep(|| first_observing(body)),
        Global::Motion(_) | Global::Var(_) | Global::End(_) | Global::After(_) => None,
    }
}

pub fn protocol_only(prog: &Program) -> bool {
    prog.processes.is_empty()
}

/// A loop checked under several contexts may meet the same goal under the same
/// hypotheses again (learnt at other places): each is kept once. Obligations are the
/// same when their rule, span, hypotheses (in any order) and goal are, terms compared
/// as [`Expr`] compares them: by value, without locations, reals by their literal text
/// (so `0.5` and `0.50` are kept apart: harmless, only fewer duplicates are found).
/// Keeping one of two such obligations is sound: the solver is asked the same question.
fn dedupe(obligations: &mut Vec<Obligation>) {
    let mut seen = HashSet::new();
    let keys: Vec<bool> = obligations
        .iter()
        .map(|o| {
            let mut hyps: Vec<&Expr> = o.hyps.iter().collect();
            hyps.sort_by_key(|e| hash_of(e));
            seen.insert((o.rule, o.span, hyps, GoalKey::of(&o.goal)))
        })
        .collect();
    let mut keep = keys.into_iter();
    obligations.retain(|_| keep.next().unwrap_or(true));
}

/// A goal as a value that compares and hashes by its terms ([`Goal`] holds primitive
/// applications, whose locations must not count). Exhaustive over [`Goal`]: a new kind
/// of goal must say what makes two of it the same.
#[derive(PartialEq, Eq, Hash)]
enum GoalKey<'o> {
    Valid(&'o Expr),
    Compatible(Vec<(RoleId, AppKey<'o>)>),
    Refines(RoleId, AppKey<'o>, Vec<AppKey<'o>>),
    Separated(Vec<(&'o [RoleId], Vec<RunKey<'o>>)>),
    InitiallyDisjoint(Vec<(RoleId, Vec<AppKey<'o>>)>),
    CanEnd(PrimId),
    Occupies(PrimId),
    Contains(PrimId),
    Reachable(&'o [Vec<Expr>], bool),
    /// Each branch's guard, fields (by binding site and sort) and refinement.
    Progress(Vec<BranchKey<'o>>),
}

/// A progress branch: its guard, its fields (by binding site and sort), its refinement.
type BranchKey<'o> = (Option<&'o Expr>, Vec<(ValueId, &'o Sort)>, &'o Expr);

/// A primitive application without its location.
type AppKey<'o> = (PrimId, &'o [Expr]);

/// A run of a side of `*`: who, what, and the context it starts in.
type RunKey<'o> = (RoleId, AppKey<'o>, &'o [Expr]);

impl<'o> GoalKey<'o> {
    fn of(g: &'o Goal) -> GoalKey<'o> {
        let app = |a: &'o PrimApp| (a.prim, &a.args[..]);
        match g {
            Goal::Valid(e) => GoalKey::Valid(e),
            Goal::Compatible { parts } => GoalKey::Compatible(parts.iter().map(|(r, a)| (*r, app(a))).collect()),
            Goal::Refines { role, concrete, abstract_ } => {
                GoalKey::Refines(*role, app(concrete), abstract_.iter().map(app).collect())
            }
            Goal::Separated { sides } => GoalKey::Separated(
                sides
                    .iter()
                    .map(|s| (&s.roles[..], s.runs.iter().map(|r| (r.role, app(&r.app), &r.hyps[..])).collect()))
                    .collect(),
            ),
            Goal::InitiallyDisjoint { firsts } => GoalKey::InitiallyDisjoint(
                firsts.iter().map(|(r, apps)| (*r, apps.iter().map(app).collect())).collect(),
            ),
            Goal::CanEnd { prim } => GoalKey::CanEnd(*prim),
            Goal::Occupies { prim } => GoalKey::Occupies(*prim),
            Goal::Contains { prim } => GoalKey::Contains(*prim),
            Goal::Reachable { before, dead_branch } => GoalKey::Reachable(before, *dead_branch),
            Goal::Progress { branches } => GoalKey::Progress(
                branches
                    .iter()
                    .map(|b| (b.guard.as_ref(), b.fields.iter().map(|(v, _, s)| (*v, s)).collect(), &b.refinement))
                    .collect(),
            ),
        }
    }
}

/// After this many different contexts for one (loop body, type) pair the context is
/// widened to the invariant.
pub const WIDEN_AFTER: usize = 8;

/// A process loop body and a type node, with the context and value map they are
/// checked under.
type LoopKey<'a> = (NodeRef<&'a Process>, NodeRef<LocalArc>, Vec<Expr>, Vec<(ValueId, Expr)>);

struct Checker<'a> {
    prog: &'a Program,
    role: RoleId,
    /// The kind's invariant over the participant's variables: true in every state.
    invariant: Vec<Expr>,
    diags: Vec<Diagnostic>,
    obligations: Vec<Obligation>,
    /// (loop body, type node, context, value map) already checked or being checked.
    assumed: HashSet<LoopKey<'a>>,
    /// How many contexts each (loop body, type node) pair has been checked under.
    contexts: HashMap<(NodeRef<&'a Process>, NodeRef<LocalArc>), usize>,
    /// Process loop parameters that stand for a refined parameter of the local type's
    /// loop (process parameter, type parameter): where an obligation reading one fails
    /// and the process's loop does not keep the type's refinement, the advice is to add it.
    stands_for: HashMap<ValueId, (RecParam, RecParam)>,
    /// Advice for an obligation, by its rule and span, more precise than its code's.
    hints: Hints,
    /// The width N of each process binder that received a `char[N]` field (the field's
    /// [`Program::str_width`]), for [T-OUT]'s width check.
    bound_width: HashMap<ValueId, u32>,
}

/// Advice for obligations (by rule and span) that applies better than their code's
/// generic help: e.g. a loop parameter that lacks its type's refinement.
pub type Hints = HashMap<(Rule, crate::source::Span), String>;

/// What the checker knows at a point of the process.
#[derive(Clone)]
struct State<'p> {
    /// Σ, as conjuncts.
    sigma: Sigma,
    /// The type's value variables (payload fields, by binding site) as process
    /// expressions: a receive substitutes the process's binder for the type's field, a
    /// send the sent expression. The type's binder and the process's are different
    /// binding sites linked only through this map, never through their names.
    vals: HashMap<ValueId, Expr>,
    /// Enclosing process loops: variable, `mu` node, actions performed when entered.
    penv: Vec<(&'p str, &'p Process, usize)>,
    /// Enclosing `mu`s of the local type.
    tenv: RecEnv,
    /// Actions performed so far on this path (for guardedness of process loops).
    actions: usize,
}

impl State<'_> {
    fn assume(&mut self, e: Expr) {
        self.sigma.assume(&e);
    }

    /// Forgets what is known about the value variables `ids` (they get new values): the
    /// facts about them and the type's values that stood for them (or were them).
    fn forget(&mut self, ids: &[ValueId]) {
        if ids.is_empty() {
            return;
        }
        let hit = |v: &Var| matches!(v, Var::Value(id, _) if ids.contains(id));
        self.sigma.forget_values(ids);
        self.vals.retain(|k, e| !ids.contains(k) && !mentions(e, &hit));
    }

    /// Forgets every fact about values `role` never holds: payload fields of messages
    /// between two other participants. A received refinement may mention one (`B -> C:
    /// now(n {n == b})` with `b` sent by `A` to `B`), and the receiver assumes it with
    /// that value unknown, i.e. existentially. The value gets a new binding each time
    /// the global type passes its message again, which the receiver cannot see: once its
    /// local type steps through a loop, facts from two rounds would otherwise speak of one
    /// `b` and relate payloads of different rounds (`n == b` and `m == b` give `n == m`).
    fn forget_foreign(&mut self, prog: &Program, role: RoleId) {
        let foreign = |v: &Var| match v {
            Var::Value(id, _) => prog.value(*id).origin.unheld_by(role),
            _ => false,
        };
        self.sigma.forget(&foreign);
        self.vals.retain(|_, e| !mentions(e, &foreign));
    }
}

impl<'a> Checker<'a> {
    fn new(prog: &'a Program, role: RoleId) -> Checker<'a> {
        Checker {
            prog,
            role,
            invariant: sigma::invariant(prog, role),
            diags: Vec::new(),
            obligations: Vec::new(),
            assumed: HashSet::new(),
            contexts: HashMap::new(),
            stands_for: HashMap::new(),
            hints: HashMap::new(),
            bound_width: HashMap::new(),
        }
    }

    /// The initial context: `init` and the invariant, and those of the participants
    /// feeding this one's inputs ([T-SESS] assumes every participant starts in its
    /// `init`, and an input *is* its source's state): a precondition over an input that
    /// the source's initial state proves holds.
    fn initial(&self) -> Vec<Expr> {
        let mut out = sigma::init(self.prog, self.role);
        out.extend(self.invariant.iter().cloned());
        let mut sources: Vec<RoleId> = self.prog.role(self.role).input_sources.iter().flatten().copied().collect();
        sources.sort();
        sources.dedup();
        for src in sources.into_iter().filter(|s| *s != self.role) {
            out.extend(sigma::init(self.prog, src));
            out.extend(sigma::invariant(self.prog, src));
        }
        out
    }

    fn check(&mut self, p: &'a Process, t: LocalArc, st: State<'a>) {
        crate::stack::deep(|| self.check_inner(p, t, st))
    }

    fn name(&self) -> &'a str {
        self.prog.role_name(self.role)
    }
}

fn hash_of(e: &Expr) -> u64 {
    sigma::fact_hash(e)
}

#[cfg(test)]
mod tests;
