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
//!   ([`Sigma::run`]): what held of the participant's variables now holds of their
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

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::project::{describe, motion_text, print_bounded, NOTE_NODES};
use crate::sigma::{self, instantiate, Sigma};
use crate::subtype::{
    and_all, conjuncts, mentions, not, refinement, subst_values, unfold_with, value_expr, RecEnv, RecStep,
};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

/// Checks every participant's process against its projection. Participants whose
/// projection failed are skipped (the projection error is reported already).
pub fn check_processes(prog: &Program, projections: &BTreeMap<RoleId, LocalRc>) -> (Vec<Diagnostic>, Vec<Obligation>) {
    let mut diags = Vec::new();
    let mut obligations = Vec::new();
    for role in prog.role_ids() {
        let name = prog.role_name(role);
        let Some(def) = prog.processes.iter().find(|p| p.role == role) else {
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
    // A loop checked under several contexts may meet the same goal under the same
    // hypotheses again (learnt at other places: hypotheses compare without locations,
    // in any order).
    let mut seen = HashSet::new();
    obligations.retain(|o| {
        let mut hyps = o.hyps.clone();
        hyps.sort_by_key(hash_of);
        seen.insert((o.rule, o.span, hyps, format!("{:?}", o.goal)))
    });
    (diags, obligations)
}

/// After this many different contexts for one (loop body, type) pair the context is
/// widened to the invariant.
pub const WIDEN_AFTER: usize = 8;

/// A process loop body and a type node, with the context and value map they are
/// checked under.
type LoopKey = (usize, usize, Vec<Expr>, Vec<(ValueId, Expr)>);

struct Checker<'a> {
    prog: &'a Program,
    role: RoleId,
    /// The kind's invariant over the participant's variables: true in every state.
    invariant: Vec<Expr>,
    diags: Vec<Diagnostic>,
    obligations: Vec<Obligation>,
    /// (loop body, type node, context, value map) already checked or being checked.
    assumed: HashSet<LoopKey>,
    /// How many contexts each (loop body, type node) pair has been checked under.
    contexts: HashMap<(usize, usize), usize>,
}

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
}

/// Variables whose value changes when time passes.
fn is_physical(v: &Var) -> bool {
    matches!(v, Var::Role(..) | Var::Snap(..) | Var::Own(_) | Var::Old(_) | Var::Clock | Var::Point(_))
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

    fn check<'p>(&mut self, p: &'p Process, t: LocalRc, st: State<'p>) {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.check_inner(p, t, st))
    }

    /// Checks `p` against `t`. Sequences are followed in a loop; branches recurse.
    fn check_inner<'p>(&mut self, mut p: &'p Process, mut t: LocalRc, mut st: State<'p>) {
        loop {
            // The type's loop steps, with the new values of its parameters (type terms).
            let mut steps: Vec<(bool, Vec<RecParam>, Vec<Expr>)> = Vec::new();
            let looped = match unfold_with(&t, &mut st.tenv, &mut |s| {
                steps.push(match s {
                    RecStep::Enter(ps) => (false, ps.to_vec(), sigma::initial_values(ps)),
                    RecStep::Jump(ps, args) => (true, ps.to_vec(), args.to_vec()),
                })
            }) {
                Ok((u, looped)) => {
                    t = u;
                    looped
                }
                Err(d) => return self.diags.push(d),
            };
            // The type's parameters are ghost values the process follows in `vals`.
            let mut last = None;
            for (jump, params, values) in steps {
                let values: Vec<Expr> = values.iter().map(|e| subst_values(e, &st.vals)).collect();
                // What Σ knows of a parameter the process did not follow speaks of its
                // old value: forgotten. A followed one appears in Σ only through `vals`.
                let unmapped: Vec<ValueId> =
                    params.iter().map(|p| p.value).filter(|id| !st.vals.contains_key(id)).collect();
                st.forget(&unmapped);
                for (p, v) in params.iter().zip(&values) {
                    st.vals.insert(p.value, v.clone());
                }
                last = Some((jump, params));
            }
            match p {
                Process::Rec { var, params, body, .. } => {
                    let inits = sigma::initial_values(params);
                    let ty = last.filter(|(jump, tp)| !jump && tp.len() == params.len());
                    self.loop_params(
                        params,
                        &inits,
                        params.iter().map(|p| p.init.loc).collect(),
                        ty.map(|t| t.1),
                        &mut st,
                        false,
                    );
                    st.penv.push((var, p, st.actions));
                    if !self.enter(body, &t, &mut st) {
                        return;
                    }
                    p = body;
                    continue;
                }
                Process::Var { var, args, loc } => {
                    let Some(i) = st.penv.iter().rposition(|(v, _, _)| *v == var) else {
                        return self.diags.push(
                            Diagnostic::error(
                                Code::RecursionMismatch,
                                loc.0,
                                format!("process variable `{var}` is not bound"),
                            )
                            .with_help(format!("bind it with `mu {var}. ...`")),
                        );
                    };
                    let Some(&(_, rec, mark)) = st.penv.get(i) else {
                        return;
                    };
                    let Process::Rec { params, body, loc: rec_loc, .. } = rec else {
                        return;
                    };
                    if mark == st.actions {
                        return self.diags.push(
                            Diagnostic::error(
                                Code::RecursionMismatch,
                                loc.0,
                                format!("the process loops back to `{var}` without performing an action"),
                            )
                            .with_label(rec_loc.0, "the loop starts here")
                            .with_help("put a message or a motion between `mu` and the variable (recursion is guarded, Def 4.1)"),
                        );
                    }
                    if shape_clash(body, &t) {
                        return self.loop_mismatch(var, *loc, body, &t);
                    }
                    st.penv.truncate(i + 1);
                    if let Some(last) = st.penv.last_mut() {
                        last.2 = st.actions;
                    }
                    if args.len() == params.len() {
                        let ty = last.filter(|(jump, tp)| *jump && tp.len() == params.len());
                        self.loop_params(params, args, vec![*loc; args.len()], ty.map(|t| t.1), &mut st, true);
                    } else {
                        let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
                        st.forget(&ids);
                    }
                    if !self.enter(body, &t, &mut st) {
                        return;
                    }
                    p = body;
                    continue;
                }
                Process::If { cond, then, els, .. } => {
                    let mut yes = st.clone();
                    yes.assume(cond.clone());
                    self.check(then, t.clone(), yes);
                    st.assume(not(cond.clone()));
                    p = els;
                    continue;
                }
                Process::Choose { branches, .. } => {
                    for b in branches {
                        self.check(b, t.clone(), st.clone());
                    }
                    return;
                }
                _ => {}
            }
            match (p, &*t) {
                (Process::End(_), Local::End(_)) => return,
                (Process::Send { to, label, args, cont, loc }, Local::Send { branches, loc: tloc }) => {
                    let Some(b) = branches.iter().find(|b| b.to == *to && b.label == *label) else {
                        return self.unexpected_send(*to, label, *loc, branches, *tloc);
                    };
                    if !self.send(args, *loc, b, &mut st) {
                        return;
                    }
                    p = cont;
                    t = b.cont.clone();
                }
                (
                    Process::Recv { from, branches, default, loc },
                    Local::Recv { branches: tb, default: td, loc: tloc },
                ) => {
                    if let Some(b) = tb.first().filter(|b| b.from != *from) {
                        return self.diags.push(
                            Diagnostic::error(
                                Code::ActionMismatch,
                                loc.0,
                                format!(
                                    "the local type expects a message from `{}` here, the process receives from `{}`",
                                    self.prog.role_name(b.from),
                                    self.prog.role_name(*from)
                                ),
                            )
                            .with_label(
                                tloc.0,
                                format!("the local type comes from here: `{}`", describe(self.prog, &t)),
                            )
                            .with_help(format!("receive from `{}` at this point", self.prog.role_name(b.from))),
                        );
                    }
                    return self.receive(branches, default.as_ref(), *loc, tb, td.as_ref(), &t, &st);
                }
                // [SUB-IN3]: receptions with a default motion where the type only moves.
                (Process::Recv { default: Some((a, q)), .. }, Local::Motion { prims, cont, loc: tloc }) => {
                    if !self.motion(a, a.loc, prims, *tloc, &mut st) {
                        return;
                    }
                    p = q;
                    t = cont.clone();
                }
                (Process::Motion { prim, cont, loc }, Local::Motion { prims, cont: tc, loc: tloc }) => {
                    if !self.motion(prim, *loc, prims, *tloc, &mut st) {
                        return;
                    }
                    p = cont;
                    t = tc.clone();
                }
                _ => return self.mismatch(p, &t, looped.as_ref()),
            }
        }
    }

    /// The process's loop parameters get `values` (process terms, evaluated now), at
    /// entry (`jump` false) or at a jump back: [T-REC]/[T-VAR] with parameters.
    /// - Their refinements must hold of the values (E0712 at entry, E0713 at a jump),
    ///   and the loop body assumes them of the (fresh) parameters.
    /// - When the local type enters or repeats a loop with as many parameters at the
    ///   same step (`ty`: its parameters, whose new values are in `vals` already), the
    ///   process's parameters stand for the type's: each value must equal the type's
    ///   (E0714), and afterwards the type's parameter is the process's in `vals`.
    fn loop_params(
        &mut self,
        params: &[RecParam],
        values: &[Expr],
        locs: Vec<Loc>,
        ty: Option<Vec<RecParam>>,
        st: &mut State,
        jump: bool,
    ) {
        let (rule, when) = if jump { (Rule::TRecJump, "the argument") } else { (Rule::TRecInit, "the initial value") };
        for ((p, v), loc) in params.iter().zip(values).zip(&locs) {
            if let Some(r) = &p.refinement {
                self.obligations.push(Obligation {
                    rule,
                    span: loc.0,
                    what: format!(
                        "the refinement `{}` of `{}`'s loop parameter `{}` holds of {when} `{}`",
                        print::expr(self.prog, None, r),
                        self.name(),
                        p.name,
                        print::expr(self.prog, None, v)
                    ),
                    hyps: st.sigma.facts().to_vec(),
                    goal: Goal::Valid(sigma::subst_params(r, params, values)),
                });
            }
        }
        if let Some(tp) = &ty {
            for (((p, v), t), loc) in params.iter().zip(values).zip(tp).zip(&locs) {
                let Some(want) = st.vals.get(&t.value) else { continue };
                let goal = Expr {
                    kind: ExprKind::Binary(crate::hir::expr::BinOp::Eq, Box::new(v.clone()), Box::new(want.clone())),
                    sort: Sort::Bool,
                    loc: *loc,
                };
                self.obligations.push(Obligation {
                    rule: Rule::TRecArgs,
                    span: loc.0,
                    what: format!(
                        "{when} `{}` of `{}`'s loop parameter `{}` equals the local type's `{}` for its parameter `{}`",
                        print::expr(self.prog, None, v),
                        self.name(),
                        p.name,
                        print::expr(self.prog, None, want),
                        t.name
                    ),
                    hyps: st.sigma.facts().to_vec(),
                    goal: Goal::Valid(goal),
                });
            }
        }
        let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
        st.forget(&ids);
        for r in params.iter().filter_map(|p| p.refinement.as_ref()) {
            st.assume(r.clone());
        }
        if let Some(tp) = ty {
            for (p, t) in params.iter().zip(tp) {
                st.vals.insert(t.value, value_expr(p.value, &p.name, &p.sort));
            }
        }
    }

    /// Coinduction for process loops: whether `body` still needs checking against `t`
    /// under the current context. Widens the context after [`WIDEN_AFTER`] variants.
    fn enter(&mut self, body: &Process, t: &LocalRc, st: &mut State) -> bool {
        let pair = (body as *const Process as usize, Arc::as_ptr(t) as usize);
        let n = self.contexts.get(&pair).copied().unwrap_or(0);
        if n >= WIDEN_AFTER {
            st.sigma = Sigma::from_facts(&self.invariant);
            st.vals.clear();
        }
        let mut sigma = st.sigma.facts().to_vec();
        sigma.sort_by_key(hash_of);
        let mut vals: Vec<(ValueId, Expr)> = st.vals.iter().map(|(k, v)| (*k, v.clone())).collect();
        vals.sort_by_key(|a| a.0);
        if !self.assumed.insert((pair.0, pair.1, sigma, vals)) {
            return false;
        }
        self.contexts.insert(pair, n + 1);
        true
    }

    /// [T-OUT]: arity, sorts, and the obligation `Σ ⇒ guard ∧ refinement{args/fields}`.
    fn send(&mut self, args: &[Expr], loc: Loc, b: &SendBranch, st: &mut State) -> bool {
        let to = self.prog.role_name(b.to);
        if args.len() != b.payload.len() {
            self.diags.push(
                Diagnostic::error(
                    Code::PayloadArity,
                    loc.0,
                    format!(
                        "`{to}!{}` sends {} value(s), the local type's message carries {}",
                        b.label,
                        args.len(),
                        b.payload.len()
                    ),
                )
                .with_label(b.loc.0, format!("the message is declared here with {}", fields_text(&b.payload)))
                .with_help("pass one value per payload field"),
            );
            return false;
        }
        for (a, f) in args.iter().zip(&b.payload) {
            if !a.sort.fits(&f.sort) {
                self.diags.push(
                    Diagnostic::error(
                        Code::SortMismatch,
                        a.loc.0,
                        format!("the value for field `{}` must be of sort `{}`, this is `{}`", f.name, f.sort, a.sort),
                    )
                    .with_label(b.loc.0, "the field is declared here")
                    .with_help(format!("send a `{}` value", f.sort)),
                );
            }
        }
        // The type's fields get new values (a binding site met again in a loop): what
        // was known of their earlier values goes. The guard reads only older values.
        let fields: Vec<ValueId> = b.payload.iter().map(|f| f.value).collect();
        st.forget(&fields);
        let mut vals = st.vals.clone();
        for (a, f) in args.iter().zip(&b.payload) {
            vals.insert(f.value, a.clone());
        }
        let mut goal = Vec::new();
        if let Some(g) = &b.guard {
            conjuncts(&subst_values(g, &st.vals), &mut goal);
        }
        for f in &b.payload {
            if let Some(r) = &f.refinement {
                conjuncts(&subst_values(r, &vals), &mut goal);
            }
        }
        if !goal.is_empty() {
            self.obligations.push(Obligation {
                rule: Rule::TOut,
                span: loc.0,
                what: format!("`{}` may send `{to}!{}`: the guard and payload refinement hold", self.name(), b.label),
                hyps: st.sigma.facts().to_vec(),
                goal: Goal::Valid(and_all(goal, loc)),
            });
        }
        st.vals = vals;
        st.actions += 1;
        true
    }

    /// [T-CHOICE1,2] with [SUB-IN1,2]: every label of the type is handled; each branch
    /// continues under the refinement of what it received.
    #[allow(clippy::too_many_arguments)]
    fn receive<'p>(
        &mut self,
        arms: &'p [RecvArm],
        default: Option<&'p (PrimApp, Box<Process>)>,
        loc: Loc,
        tb: &[RecvBranch],
        td: Option<&(Vec<PrimApp>, LocalRc)>,
        t: &LocalRc,
        st: &State<'p>,
    ) {
        let missing: Vec<&RecvBranch> = tb.iter().filter(|b| !arms.iter().any(|a| a.label == b.label)).collect();
        if !missing.is_empty() {
            let names: Vec<String> =
                missing.iter().map(|b| format!("`{}?{}`", self.prog.role_name(b.from), b.label)).collect();
            let mut d = Diagnostic::error(
                Code::MissingBranch,
                loc.0,
                format!("the process does not handle {}, which the local type may deliver here", names.join(", ")),
            );
            for b in &missing {
                d = d.with_label(b.loc.0, "the choreography may send this");
            }
            self.diags.push(
                d.with_note("[T-CHOICE1,2] with [SUB-IN]: an external choice handles every label of the type and may handle more")
                    .with_help(format!("add a branch for {}", names.join(", "))),
            );
        }
        for b in tb {
            let Some(arm) = arms.iter().find(|a| a.label == b.label) else {
                continue;
            };
            if arm.binders.len() != b.payload.len() {
                self.diags.push(
                    Diagnostic::error(
                        Code::PayloadArity,
                        arm.loc.0,
                        format!(
                            "`{}?{}` binds {} value(s), the local type's message carries {}",
                            self.prog.role_name(b.from),
                            b.label,
                            arm.binders.len(),
                            b.payload.len()
                        ),
                    )
                    .with_label(b.loc.0, format!("the message is declared here with {}", fields_text(&b.payload)))
                    .with_help("bind one variable per payload field"),
                );
                continue;
            }
            let mut s = st.clone();
            s.forget(&arm.binders);
            // The type's fields get new values too (see `send`).
            s.forget(&b.payload.iter().map(|f| f.value).collect::<Vec<_>>());
            for (v, f) in arm.binders.iter().zip(&b.payload) {
                // The type's field is the process's binder from here on; the binder takes
                // the field's sort.
                s.vals.insert(f.value, value_expr(*v, &self.prog.value(*v).name, &f.sort));
            }
            for f in &b.payload {
                if let Some(r) = &f.refinement {
                    let r = subst_values(r, &s.vals);
                    s.assume(r);
                }
            }
            s.actions += 1;
            self.check(&arm.cont, b.cont.clone(), s);
        }
        match (default, td) {
            // [T-CHOICE2] / [SUB-IN1]
            (Some((a, q)), Some((prims, tc))) => {
                let mut s = st.clone();
                let tloc = prims.first().map(|p| p.loc).unwrap_or(t.loc());
                if self.motion(a, a.loc, prims, tloc, &mut s) {
                    self.check(q, tc.clone(), s);
                }
            }
            (None, Some((prims, _))) => self.diags.push(
                Diagnostic::error(
                    Code::ActionMismatch,
                    loc.0,
                    format!(
                        "the local type may move with the default motion `{}` here, the process only waits for a message",
                        motion_text(self.prog, prims)
                    ),
                )
                .with_label(t.loc().0, format!("the local type comes from here: `{}`", describe(self.prog, t)))
                .with_help(format!("add a default branch `+ {}.P` to the external choice", motion_text(self.prog, prims))),
            ),
            // [SUB-IN2]: a default the type does not have is never taken.
            (_, None) => {}
        }
    }

    /// [T-MOTION] with [SUB-MOTION]: refinement, `Σ ⇒ Pre`, then Σ := Post.
    fn motion(&mut self, a: &PrimApp, loc: Loc, prims: &[PrimApp], tloc: Loc, st: &mut State) -> bool {
        let abstract_: Vec<PrimApp> = prims
            .iter()
            .map(|b| PrimApp {
                prim: b.prim,
                args: b.args.iter().map(|e| subst_values(e, &st.vals)).collect(),
                loc: b.loc,
            })
            .collect();
        match refinement(self.prog, self.role, std::slice::from_ref(a), loc, &abstract_, tloc) {
            Err(d) => {
                self.diags.push(d);
                return false;
            }
            // Refinement (Def 3.4) constrains whole trajectories, not the state the
            // motion starts in, so it gets no hypotheses from Σ.
            Ok(Some(ob)) => self.obligations.push(ob),
            Ok(None) => {}
        }
        let prim = self.prog.prim(a.prim);
        // Received values in the arguments take the sorts of their payload fields.
        let args: Vec<Expr> = a.args.iter().map(|e| subst_values(e, &st.vals)).collect();
        let mut pre = Vec::new();
        conjuncts(&instantiate(&prim.pre, self.role, &args), &mut pre);
        if !pre.is_empty() {
            self.obligations.push(Obligation {
                rule: Rule::TMotion,
                span: loc.0,
                what: format!(
                    "the precondition of `{}` holds when `{}` starts it",
                    print::prim_app(self.prog, a),
                    self.name()
                ),
                hyps: st.sigma.facts().to_vec(),
                goal: Goal::Valid(and_all(pre, loc)),
            });
        }
        // Σ := the strongest postcondition; the others moved meanwhile.
        st.sigma.run(self.prog, self.role, a.prim, &args);
        let me = self.role;
        st.sigma.forget(&|v| matches!(v, Var::Role(r, _) | Var::Snap(r, _) if *r != me));
        st.vals.retain(|_, e| !mentions(e, &is_physical));
        st.actions += 1;
        true
    }

    fn name(&self) -> &'a str {
        self.prog.role_name(self.role)
    }

    fn unexpected_send(&mut self, to: RoleId, label: &str, loc: Loc, branches: &[SendBranch], tloc: Loc) {
        let allowed: Vec<String> =
            branches.iter().map(|b| format!("`{}!{}`", self.prog.role_name(b.to), b.label)).collect();
        let allowed = allowed.join(", ");
        self.diags.push(
            Diagnostic::error(
                Code::UnexpectedSend,
                loc.0,
                format!("the process sends `{}!{label}`, which the local type does not allow here", self.prog.role_name(to)),
            )
            .with_label(tloc.0, format!("the local type allows {allowed}"))
            .with_note("[T-OUT] with [SUB-OUT]: each send matches a branch of the internal choice, with the same receiver and label")
            .with_help(format!("send one of {allowed}")),
        );
    }

    /// E0702: the process and the type disagree on the kind of the next action.
    fn mismatch(&mut self, p: &Process, t: &LocalRc, looped: Option<&(String, Loc)>) {
        let expected = describe(self.prog, t);
        if let (Process::End(loc), Some((var, var_loc))) = (p, looped) {
            return self.diags.push(
                Diagnostic::error(
                    Code::RecursionMismatch,
                    loc.0,
                    format!("the process ends here, but the local type loops back to `{var}` and expects `{expected}`"),
                )
                .with_label(var_loc.0, "the local type loops back here")
                .with_label(t.loc().0, format!("and continues with `{expected}`"))
                .with_help(format!(
                    "loop back with a process variable instead of `end` (the choreography repeats with `{var}`)"
                )),
            );
        }
        let performs = describe_process(self.prog, p);
        let help = match &**t {
            Local::End(_) => "the choreography ends here for this participant; end the process with `end`".to_string(),
            _ => format!("perform `{expected}` at this point, as the projection of the choreography prescribes"),
        };
        self.diags.push(
            Diagnostic::error(
                Code::ActionMismatch,
                p.loc().0,
                format!("the local type expects `{expected}` here, the process performs `{performs}`"),
            )
            .with_label(t.loc().0, format!("`{expected}` comes from here"))
            .with_note(format!(
                "the local type of `{}` from here on is:\n{}",
                self.name(),
                print_bounded(self.prog, t, NOTE_NODES)
            ))
            .with_help(help),
        );
    }

    /// E0706: looping back to `var` does not fit the type at this point.
    fn loop_mismatch(&mut self, var: &str, loc: Loc, body: &Process, t: &LocalRc) {
        let msg = match &**t {
            Local::End(_) => format!("the process loops back to `{var}` here, but the local type ends"),
            _ => format!(
                "the process loops back to `{var}` and then performs `{}`, but the local type expects `{}`",
                describe_process(self.prog, body),
                describe(self.prog, t)
            ),
        };
        self.diags.push(
            Diagnostic::error(Code::RecursionMismatch, loc.0, msg)
                .with_label(t.loc().0, "the local type at this point")
                .with_label(body.loc().0, "the loop body starts here")
                .with_help("loop back where the local type loops (or end where it ends)"),
        );
    }
}

/// Whether the first action of `p` (after its own `mu`s) certainly cannot match `t`.
fn shape_clash(p: &Process, t: &Local) -> bool {
    let mut p = p;
    while let Process::Rec { body, .. } = p {
        p = body;
    }
    !matches!(
        (p, t),
        (Process::Var { .. } | Process::If { .. }, _)
            | (Process::Send { .. } | Process::Choose { .. }, Local::Send { .. })
            | (Process::Recv { .. }, Local::Recv { .. })
            | (Process::Recv { default: Some(_), .. }, Local::Motion { .. })
            | (Process::Motion { .. }, Local::Motion { .. })
            | (Process::End(_), Local::End(_))
    )
}

fn hash_of(e: &Expr) -> u64 {
    sigma::fact_hash(e)
}

fn fields_text(fields: &[Field]) -> String {
    if fields.is_empty() {
        return "no payload".to_string();
    }
    let items: Vec<String> = fields.iter().map(|f| format!("{}: {}", f.name, f.sort)).collect();
    format!("payload ({})", items.join(", "))
}

/// A short description of the first action of a process, for messages.
fn describe_process(prog: &Program, p: &Process) -> String {
    let args_text = |args: &[Expr]| {
        if args.is_empty() {
            String::new()
        } else {
            let a: Vec<String> = args.iter().map(|e| print::expr(prog, None, e)).collect();
            format!("({})", a.join(", "))
        }
    };
    match p {
        Process::Send { to, label, args, .. } => format!("{}!{label}{}", prog.role_name(*to), args_text(args)),
        Process::Recv { from, branches, default, .. } => {
            let mut items: Vec<String> =
                branches.iter().map(|b| format!("{}?{}", prog.role_name(*from), b.label)).collect();
            if let Some((a, _)) = default {
                items.push(format!("dt<{}>", print::prim_app(prog, a)));
            }
            items.join(" + ")
        }
        Process::Choose { branches, .. } => {
            let items: Vec<String> = branches.iter().map(|b| describe_process(prog, b)).collect();
            items.join(" + ")
        }
        Process::If { cond, .. } => {
            format!("if {} then ... else ...", print::expr(prog, None, cond))
        }
        Process::Motion { prim, .. } => format!("dt<{}>", print::prim_app(prog, prim)),
        Process::Rec { var, body, .. } => format!("mu {var}. {}", describe_process(prog, body)),
        Process::Var { var, args, .. } => format!("{var}{}", args_text(args)),
        Process::End(_) => "end".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::{lower_src, HEADER};
    use crate::project::project_all;

    /// HEADER's cart `C` and arm `A`, and a loop: the cart tells the arm where it goes,
    /// both move, the arm reports back.
    const LOOP: &str = "
        motion Cart.creep { interruptible: true; }
        motion Arm.grab { interruptible: false; }
        choreography G = mu t. C -> A : go(tf: real { tf > C.x }). dt<C: move(tf), A: work>. A -> C : done. t;
    ";

    fn check(procs: &str) -> (Program, Vec<Diagnostic>, Vec<Obligation>) {
        check_with(LOOP, procs)
    }

    fn check_with(chor: &str, procs: &str) -> (Program, Vec<Diagnostic>, Vec<Obligation>) {
        check_src(&format!("{HEADER} {chor} {procs}"))
    }

    fn check_src(src: &str) -> (Program, Vec<Diagnostic>, Vec<Obligation>) {
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let (map, d) = project_all(&prog);
        assert!(d.is_empty(), "{d:?}");
        let (diags, obs) = check_processes(&prog, &map);
        (prog, diags, obs)
    }

    /// A watcher `W` that is not told of `P`'s choice: its projection has a default.
    const WATCH: &str = "
        robot K { state x: real; }
        motion K.m { interruptible: true; }
        motion K.w { interruptible: true; }
        system S { participant P: K; participant Q: K; participant W: K; }
        choreography G = P -> Q : a. dt<P: m, Q: m, W: w>. P -> W : stop. end
                       + P -> Q : b. P -> W : go. end;
        process P = Q!a.dt<m>.W!stop.end + Q!b.W!go.end;
        process Q = P?a.dt<m>.end + P?b.end;
    ";

    fn codes(d: &[Diagnostic]) -> Vec<Code> {
        d.iter().map(|d| d.code).collect()
    }

    fn goals(prog: &Program, obs: &[Obligation], rule: Rule) -> Vec<String> {
        obs.iter()
            .filter(|o| o.rule == rule)
            .map(|o| match &o.goal {
                Goal::Valid(e) => print::expr(prog, None, e),
                Goal::Refines { concrete, abstract_, .. } => {
                    format!("{} <= {}", print::prim_app(prog, concrete), motion_text(prog, abstract_))
                }
                other => format!("{other:?}"),
            })
            .collect()
    }

    const GOOD_A: &str = "process A = mu k. C?go(y).dt<work>.C!done.k;";

    /// The hypotheses of each obligation of `rule`, printed.
    fn hyps_of(prog: &Program, obs: &[Obligation], rule: Rule) -> Vec<Vec<String>> {
        obs.iter()
            .filter(|o| o.rule == rule)
            .map(|o| o.hyps.iter().map(|h| print::expr(prog, None, h)).collect())
            .collect()
    }

    /// A shuttle in the style of Fig 2: forward, stay (`x == old(x)`), back, and again.
    const SHUTTLE: &str = "
        motion Cart.stay { interruptible: true; pre: v == 0; post: x == old(x) && v == 0; }
        motion Cart.fwd(xf: real) { interruptible: false; pre: xf > x && v == 0; post: x == xf && v == 0; }
        motion Cart.back(xf: real) { interruptible: false; pre: xf < x && v == 0; post: x == xf && v == 0; }
        choreography G = mu t. C -> A : go. dt<C: fwd(1.0), A: work>. C -> A : at. dt<C: stay, A: work>.
                               A -> C : done. dt<C: back(0), A: work>. C -> A : home. t;
        process C = mu k. A!go.dt<fwd(1.0)>.A!at.dt<stay>.A?done.dt<back(0)>.A!home.k;
        process A = mu k. C?go.dt<work>.C?at.dt<work>.C!done.dt<work>.C?home.k;
    ";

    #[test]
    fn t_motion_keeps_what_a_post_with_old_preserves() {
        let (prog, d, obs) = check_with(SHUTTLE, "");
        assert!(d.is_empty(), "{d:?}");
        // [T-MOTION]: after `stay` (post `x == old(x)`) the cart is still where `fwd`
        // left it, so `back(0)`'s precondition `0 < C.x` follows. The loop closes after
        // one iteration: `back(0)` leaves the context the loop started in.
        assert_eq!(goals(&prog, &obs, Rule::TMotion), vec!["1.0 > C.x && C.v == 0", "C.v == 0", "0 < C.x && C.v == 0"]);
        assert_eq!(
            hyps_of(&prog, &obs, Rule::TMotion),
            vec![
                vec!["C.x == 0", "C.v == 0", "0 <= C.v"],
                vec!["C.x == 1.0", "C.v == 0", "0 <= C.v"],
                vec!["C.x == 1.0", "C.v == 0", "0 <= C.v"],
            ]
        );
        assert!(obs.iter().filter(|o| o.rule == Rule::TMotion).nth(1).is_some_and(Obligation::trivially_holds));
    }

    #[test]
    fn a_well_typed_system_has_only_obligations() {
        let (prog, d, obs) = check(&format!("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; {GOOD_A}"));
        assert!(d.is_empty(), "{d:?}");
        // `move`'s postcondition `x == xf` with `xf` the `x + 1` computed before the
        // motion: each iteration knows the cart one further, `C.x == 1`, `C.x == 2`, ...,
        // so the contexts never repeat. After WIDEN_AFTER of them the context is widened
        // to the invariant, and the iteration after that meets it again.
        assert_eq!(goals(&prog, &obs, Rule::TOut), vec!["C.x + 1 > C.x"; WIDEN_AFTER + 1]);
        assert_eq!(goals(&prog, &obs, Rule::TMotion), vec!["C.x + 1 > C.x && C.v == 0"; WIDEN_AFTER + 1]);
        let hyps = hyps_of(&prog, &obs, Rule::TMotion);
        assert_eq!(hyps[0], vec!["C.x == 0", "C.v == 0", "0 <= C.v"]);
        assert_eq!(hyps[1], vec!["C.x == 1", "0 <= C.v"]);
        assert_eq!(hyps[2], vec!["C.x == 2", "0 <= C.v"]);
        assert_eq!(hyps[WIDEN_AFTER], vec!["0 <= C.v"]);
        assert_eq!(obs.iter().filter(|o| o.rule == Rule::TSess).count(), 1);
        assert!(goals(&prog, &obs, Rule::Refinement).is_empty());
        let _ = prog;
    }

    #[test]
    fn example_3_1_processes_implement_the_cart_and_arms_choreography() {
        let src = format!(
            "{} process Cart = mu k. (G!arrive.R!free.dt<m_move(1.0)>.G!ready.dt<m_idle>.G?ok.dt<m_move(0.0)>.k
                                   + G!free.R!arrive.dt<m_move(2.0)>.R!ready.dt<m_idle>.R?ok.dt<m_move(0.0)>.k);
                process G = mu k. Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.k + Cart?free.dt<work>.k;
                process R = mu k. Cart?free.dt<work>.k + Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.k;",
            crate::project::tests::CART_ARMS
        );
        let (_, d, obs) = check_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let rules: Vec<Rule> = obs.iter().map(|o| o.rule).collect();
        assert_eq!(rules, vec![Rule::TSess]);
        // The green arm forgets to report back in its loop.
        let bad = src.replace(
            "Cart?ready.dt<pick>.Cart!ok.dt<work>.k + Cart?free",
            "Cart?ready.dt<pick>.dt<work>.k + Cart?free",
        );
        let (_, d, _) = check_src(&bad);
        assert_eq!(codes(&d), vec![Code::ActionMismatch]);
        assert_eq!(d[0].message, "the local type expects `Cart!ok` here, the process performs `dt<work>`");
    }

    #[test]
    fn a_process_may_unfold_its_loop_later_or_twice() {
        let later = "process C = A!go(x + 1).dt<move(x + 1)>.mu k. A?done.A!go(x + 1).dt<move(x + 1)>.k;";
        let (_, d, _) = check(&format!("{later} {GOOD_A}"));
        assert!(d.is_empty(), "{d:?}");
        let twice = "process A = mu k. C?go(y).dt<work>.C!done.C?go(z).dt<work>.C!done.k;";
        let (_, d, _) = check(&format!("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; {twice}"));
        assert!(d.is_empty(), "{d:?}");
    }

    #[test]
    fn nested_loops_and_conditionals_in_loops() {
        for c in [
            "process C = mu k. mu j. A!go(x + 1).dt<move(x + 1)>.A?done.k;",
            "process C = mu k. A!go(x + 1).dt<move(x + 1)>.mu j. A?done.k;",
            "process C = mu k. if x > 0 then A!go(1.0).dt<move(1.0)>.A?done.k else A!go(2.0).dt<move(2.0)>.A?done.k;",
            "process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.mu j. A!go(x + 2).dt<move(x + 2)>.A?done.j;",
        ] {
            let (_, d, _) = check(&format!("{c} {GOOD_A}"));
            assert!(d.is_empty(), "{c}: {d:?}");
        }
        // Jumping to an outer loop from an inner one at the wrong point.
        let (_, d, _) = check(&format!("process C = mu k. A!go(x + 1).mu j. dt<move(x + 1)>.A?done.j; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::RecursionMismatch], "{d:?}");
    }

    #[test]
    fn long_sequences_are_checked_without_deep_recursion() {
        let n = 400;
        let msgs: Vec<String> = (0..n).map(|i| format!("C -> A : m{i}")).collect();
        let sends: Vec<String> = (0..n).map(|i| format!("A!m{i}")).collect();
        let recvs: Vec<String> = (0..n).map(|i| format!("C?m{i}")).collect();
        let chor = format!("choreography G = {}. end;", msgs.join(". "));
        let procs = format!("process C = {}.end; process A = {}.end;", sends.join("."), recvs.join("."));
        let (_, d, _) = check_with(&chor, &procs);
        assert!(d.is_empty(), "{d:?}");
    }

    #[test]
    fn facts_about_others_are_forgotten_when_the_participant_moves() {
        // The arm learns `tf > C.x` with `go`; once it has moved, so has the cart.
        let chor = "choreography G = C -> A : go(tf: real { tf > C.x }). dt<C: idle, A: work>.
                                     A -> C : [tf > 0] ack(u: real { u == tf }). end;";
        let (prog, d, obs) =
            check_with(chor, "process C = A!go(1.0).dt<idle>.A?ack(w).end; process A = C?go(y).dt<work>.C!ack(y).end;");
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(goals(&prog, &obs, Rule::TOut), vec!["1.0 > C.x", "y > 0 && y == y"]);
        let hyps = hyps_of(&prog, &obs, Rule::TOut);
        assert_eq!(hyps[0], vec!["C.x == 0", "C.v == 0", "0 <= C.v"]);
        assert_eq!(hyps[1], Vec::<String>::new(), "`C.x < y` went stale when the arm moved");
    }

    #[test]
    fn received_refinements_enter_the_context() {
        let chor =
            "choreography G = C -> A : go(tf: real { tf > 0 }). A -> C : [tf > 0] ack(u: real { u == tf }). end;";
        let (prog, d, obs) = check_with(chor, "process C = A!go(1.0).A?ack(w).end; process A = C?go(y).C!ack(y).end;");
        assert!(d.is_empty(), "{d:?}");
        let outs: Vec<&Obligation> = obs.iter().filter(|o| o.rule == Rule::TOut).collect();
        assert_eq!(goals(&prog, &obs, Rule::TOut), vec!["1.0 > 0", "y > 0 && y == y"]);
        assert!(outs[1].hyps.iter().any(|h| print::expr(&prog, None, h) == "0 < y"));
    }

    #[test]
    fn conditionals_check_both_branches_under_the_condition() {
        let chor = "choreography G = C -> A : left. end + C -> A : [x > 0] right. end;";
        let (prog, d, obs) = check_with(
            chor,
            "process C = if x > 1 then A!right.end else A!left.end; process A = C?left.end + C?right.end;",
        );
        assert!(d.is_empty(), "{d:?}");
        let out: Vec<&Obligation> = obs.iter().filter(|o| o.rule == Rule::TOut).collect();
        assert_eq!(out.len(), 1);
        assert!(out[0].hyps.iter().any(|h| print::expr(&prog, None, h) == "1 < C.x"));
    }

    #[test]
    fn e0701_participant_without_process() {
        let (_, d, _) = check("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k;");
        assert_eq!(codes(&d), vec![Code::MissingProcess]);
        assert!(d[0].notes[0].contains("C?go"), "{:?}", d[0].notes);
    }

    #[test]
    fn e0702_wrong_kind_of_action() {
        let (prog, d, _) = check(&format!("process C = mu k. dt<idle>.A?done.k; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::ActionMismatch]);
        assert_eq!(d[0].message, "the local type expects `A!go` here, the process performs `dt<idle>`");
        let _ = prog;
        // The process ends where the type continues.
        let (_, d, _) = check(&format!("process C = mu k. A!go(x + 1).end; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::ActionMismatch]);
        assert!(d[0].message.contains("performs `end`"), "{}", d[0].message);
    }

    #[test]
    fn defaults_follow_t_choice2() {
        let (prog, d, _) = check_src(&format!("{WATCH} process W = P?go.end + dt<w>.P?stop.end;"));
        assert!(d.is_empty(), "{d:?}");
        let w = prog.role_by_name("W").expect("W");
        let (map, _) = project_all(&prog);
        assert_eq!(print::local(&prog, &map[&w]), "&{\n  P?go.end\n} & dt<w>.P?stop.end");
        // The type may move by default; a process that only waits lacks that branch.
        let (_, d, _) = check_src(&format!("{WATCH} process W = P?go.end;"));
        assert_eq!(codes(&d), vec![Code::ActionMismatch]);
        assert!(d[0].message.contains("default motion `dt<w>`"), "{}", d[0].message);
        // The default continues like the type's.
        let (_, d, _) = check_src(&format!("{WATCH} process W = P?go.end + dt<w>.P?go.end;"));
        assert_eq!(codes(&d), vec![Code::MissingBranch], "{d:?}");
    }

    #[test]
    fn all_errors_are_collected() {
        let chor = "choreography G = C -> A : a. A -> C : x. end + C -> A : b. A -> C : y. end;";
        let (_, d, _) =
            check_with(chor, "process C = A!a.A?x.end + A!b.end; process A = C?a.C!z.end + C?b.dt<work>.end;");
        assert_eq!(codes(&d), vec![Code::ActionMismatch, Code::UnexpectedSend, Code::ActionMismatch], "{d:?}");
    }

    #[test]
    fn e0703_missing_branch() {
        let (_, d, _) =
            check("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; process A = mu k. C?stop.end + C?other.k;");
        assert_eq!(codes(&d), vec![Code::MissingBranch]);
        assert!(d[0].message.contains("`C?go`"), "{}", d[0].message);
    }

    #[test]
    fn e0704_unexpected_send() {
        let (_, d, _) = check(&format!("process C = mu k. A!stop.k; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::UnexpectedSend]);
        assert!(d[0].labels[0].message.contains("`A!go`"));
    }

    #[test]
    fn e0705_interruptibility_and_refinement_obligations() {
        let (_, d, _) = check(&format!("process C = mu k. A!go(x + 1).dt<idle>.A?done.k; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::PrimitiveMismatch]);
        let (_, d, _) = check(
            "process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; process A = mu k. C?go(y).dt<grab>.C!done.k;",
        );
        assert_eq!(codes(&d), vec![Code::PrimitiveMismatch], "work is interruptible, grab is not");
        // Same interruptibility: a refinement obligation instead.
        let (prog, d, obs) = check_with(
            "motion Cart.creep { interruptible: true; }
             choreography G = mu t. C -> A : go. dt<C: idle, A: work>. A -> C : done. t;",
            "process C = mu k. A!go.dt<creep>.A?done.k; process A = mu k. C?go.dt<work>.C!done.k;",
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(goals(&prog, &obs, Rule::Refinement), vec!["creep <= dt<idle>"]);
    }

    #[test]
    fn e0706_loops_that_do_not_match() {
        // The process stops where the type loops.
        let (_, d, _) = check(&format!("process C = A!go(x + 1).dt<move(x + 1)>.A?done.end; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::RecursionMismatch]);
        assert!(d[0].message.contains("loops back to `t`"), "{}", d[0].message);
        // The process loops where the type ends.
        let chor = "choreography G = C -> A : go. end;";
        let (_, d, _) = check_with(chor, "process C = mu k. A!go.k; process A = C?go.end;");
        assert_eq!(codes(&d), vec![Code::RecursionMismatch]);
        assert!(d[0].message.contains("the local type ends"), "{}", d[0].message);
        // An unguarded process loop.
        let (_, d, _) = check_with(chor, "process C = mu k. k; process A = C?go.end;");
        assert_eq!(codes(&d), vec![Code::RecursionMismatch]);
    }

    #[test]
    fn e0707_payload_arity() {
        let (_, d, _) = check(&format!("process C = mu k. A!go.dt<move(x + 1)>.A?done.k; {GOOD_A}"));
        assert_eq!(codes(&d), vec![Code::PayloadArity]);
        let (_, d, _) =
            check("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; process A = mu k. C?go.dt<work>.C!done.k;");
        assert_eq!(codes(&d), vec![Code::PayloadArity]);
    }

    #[test]
    fn e0208_argument_sorts() {
        let (_, d, _) = check(&format!("process C = mu k. A!go(true).dt<move(1.0)>.A?done.k; {GOOD_A}"));
        assert!(codes(&d).contains(&Code::SortMismatch), "{d:?}");
    }

    #[test]
    fn the_types_loop_parameters_are_followed_in_the_process() {
        let chor = "choreography G = mu t(n: int {n >= 0} = 1).
                      C -> A : [n > 0] go. dt<C: idle, A: work>. A -> C : done. t(n - 1);";
        // C does not keep a counter: the type's `n` is 1, then 1 - 1, ... The second
        // `A!go` must show `1 - 1 > 0`, which fails: C may not say `go` forever.
        let (prog, d, obs) =
            check_with(chor, "process C = mu k. A!go.dt<idle>.A?done.k; process A = mu k. C?go.dt<work>.C!done.k;");
        assert!(d.is_empty(), "{d:?}");
        let outs = goals(&prog, &obs, Rule::TOut);
        assert_eq!(outs[..2], ["1 > 0", "1 - 1 > 0"]);
        assert!(goals(&prog, &obs, Rule::TRecArgs).is_empty(), "C's loop has no parameter to align");
        // C mirrors the parameter: `j` stands for `n`, so the guard is `j > 0`, known
        // from the `if`; the arguments must agree with the type's, the refinement hold.
        let (prog, d, obs) = check_with(
            chor,
            "process C = mu k(j: int {j >= 0} = 1). if j > 0 then A!go.dt<idle>.A?done.k(j - 1) else A!go.dt<idle>.A?done.k(j);
             process A = mu k. C?go.dt<work>.C!done.k;",
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(goals(&prog, &obs, Rule::TRecInit), vec!["1 >= 0"]);
        assert_eq!(goals(&prog, &obs, Rule::TRecArgs), vec!["1 == 1", "j - 1 == j - 1", "j == j - 1"]);
        assert_eq!(goals(&prog, &obs, Rule::TRecJump), vec!["j - 1 >= 0", "j >= 0"]);
        // (The `else` branch sends `go` at j == 0: its `j > 0` fails, as it should.)
        let outs = goals(&prog, &obs, Rule::TOut);
        assert!(!outs.is_empty() && outs.iter().all(|g| g == "j > 0"), "{outs:?}");
        let hyps = hyps_of(&prog, &obs, Rule::TRecJump);
        assert!(hyps[0].contains(&"0 <= j".to_string()) && hyps[0].contains(&"0 < j".to_string()), "{hyps:?}");
    }

    #[test]
    fn defaults_and_internal_choice() {
        // [T-CHOICE2] with a default; an internal sum of sends where each branch is
        // one label of the type.
        let chor = "choreography G = mu t. (C -> A : a. dt<C: idle, A: work>. A -> C : ok. t
                                         + C -> A : b. A -> C : ok. t);";
        let (_, d, _) = check_with(
            chor,
            "process C = mu k. (A!a.dt<idle>.A?ok.k + A!b.A?ok.k); process A = mu k. C?a.dt<work>.C!ok.k + C?b.C!ok.k;",
        );
        assert!(d.is_empty(), "{d:?}");
    }
}
