//! Subtyping of local types (Fig 5, Def 4.10): `sub <= sup` when a process of type
//! `sub` may stand where `sup` is expected.
//!
//! - [SUB-MOTION] `dt<a>.T <= dt<a'>.T'` if `a <= a'` (Def 3.4 in the corrected
//!   direction of the seeds README, error 1: the concrete primitive on the left) and
//!   `T <= T'`. Equal primitives need nothing; otherwise both must have the same
//!   interruptibility (E0705) and the refinement becomes an obligation.
//! - [SUB-OUT] the sub type's sends are among the super type's, with `P_i => P''_i`
//!   (guards) and `P'_i => P'''_i` (refinements) as obligations.
//! - [SUB-IN1,2,3] the sub type receives at least the super type's labels from the
//!   same sender, with `P'_i => P_i`; a default motion of the sub type may be dropped
//!   (SUB-IN2) or stand for a motion of the super type (SUB-IN3).
//! - `end <= end`.
//!
//! The relation is the largest one closed under these rules, so it is checked
//! coinductively: recursion is unfolded through an environment of the enclosing `mu`s,
//! and a pair of nodes met again (under the same renaming) is assumed to be related.
//! Payload fields of the super type are renamed to the sub type's, so the implications
//! speak about one value.
//!
//! Where the pipeline uses it: [T-SUB] (Table 1) for written local types. `local R = T;`
//! is checked as `T <= G↾R` by [`check_declared`] (E0602 when the shapes do not fit, an
//! E0711 obligation per predicate implication, decided by Z3 under the vacuity guard),
//! and `R`'s process is then typed against `T`: `P : T` and `T <= G↾R` give `P : G↾R`
//! by [T-SUB], which is what [T-SESS] asks. Process typing itself (`typeck.rs`) folds
//! [T-SUB] into its rules and does not call [`subtype`].

use crate::diag::{Code, Diagnostic};
use crate::hir::expr::{and_all, conjuncts, subst_values, value_expr};
use crate::hir::print::{describe, motion_text, print_bounded, NOTE_NODES};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::source::Span;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

/// Checks `sub <= sup` for local types of `role` (the role instantiates the refinement
/// obligations). Returns the predicate obligations, or the first structural failure.
pub fn subtype(prog: &Program, role: RoleId, sub: &LocalArc, sup: &LocalArc) -> Result<Vec<Obligation>, Diagnostic> {
    subtype_named(prog, role, sub, sup, ["the sub type", "the super type"])
}

/// [`subtype`], naming the two types in the obligations' descriptions.
fn subtype_named(
    prog: &Program,
    role: RoleId,
    sub: &LocalArc,
    sup: &LocalArc,
    names: [&str; 2],
) -> Result<Vec<Obligation>, Diagnostic> {
    let names = names.map(str::to_string);
    let mut s = Sub { prog, role, names, assumed: HashSet::new(), obligations: Vec::new() };
    s.check(sub, &mut Vec::new(), sup, &mut Vec::new(), &HashMap::new())?;
    Ok(s.obligations)
}

/// [T-SUB] (Table 1) for the written local types: each `local R = T;` must be a subtype
/// of the projection `G↾R` (Def 4.10, Fig 5), and `R`'s process is typed against `T`.
///
/// Returns the predicate side conditions of Fig 5 (E0711 and, for [SUB-MOTION], E0407
/// obligations), the local type each participant's process is to be typed against (its
/// `local` when it fits, its projection otherwise) and, last like every stage, the
/// structural failures (E0602, one per `local` item, at its role name). A role without a
/// projection (projection failed, reported already) is skipped.
///
/// Sound: typing `P` against `T` proves `P : T`; the structural part and the obligations
/// prove `T <= G↾R`; [T-SUB] gives `P : G↾R`. An undecided obligation leaves the verdict
/// `unknown` like any other.
pub fn check_declared(
    prog: &Program,
    projections: &BTreeMap<RoleId, LocalArc>,
) -> (Vec<Obligation>, BTreeMap<RoleId, LocalArc>, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut obligations = Vec::new();
    let mut types = projections.clone();
    for def in &prog.locals {
        let Some(proj) = projections.get(&def.role) else {
            continue;
        };
        let name = prog.role_name(def.role);
        let declared = format!("the declared local type of `{name}`");
        match subtype_named(prog, def.role, &def.body, proj, [&declared, "the projection"]) {
            Ok(obs) => {
                obligations.extend(obs);
                types.insert(def.role, def.body.clone());
            }
            Err(d) => {
                // The subtype's words, in this setting's: the sub type is the declared one.
                let ours = |t: &str| t.replace("super type", "projection").replace("sub type", "declared type");
                let mut e = Diagnostic::error(
                    Code::LocalMismatch,
                    def.span,
                    format!(
                        "the declared local type of `{name}` is not a subtype of the projection of the choreography"
                    ),
                )
                .with_label(d.span, ours(&d.message));
                for l in d.labels {
                    e = e.with_label(l.span, ours(&l.message));
                }
                for n in d.notes {
                    e = e.with_note(ours(&n));
                }
                let help = ours(&d.help.unwrap_or_default());
                diags.push(
                    e.with_note("[T-SUB] (Table 1): `local R = T;` needs T <= the projection onto R (Def 4.10, Fig 5), and the process is typed against T")
                        .with_note(format!("the projection onto `{name}` is:\n{}", print_bounded(prog, proj, NOTE_NODES)))
                        .with_help(format!(
                            "in the declared type: {help}; `mochi project FILE --role {name}` prints the projection"
                        )),
                );
            }
        }
    }
    (obligations, types, diags)
}

/// The enclosing `mu t. T` nodes of a local type, innermost last.
pub type RecEnv = Vec<(String, LocalArc)>;

/// How many `mu`/variable steps may follow each other before recursion counts as
/// unguarded.
const UNFOLD_LIMIT: usize = 256;

/// Unfolds `mu t. T` (binding `t`) and `t` (jumping back to the body of its `mu`) until
/// an action or `end` comes first. Returns that node and, when the last step was a
/// jump back, the variable it went through and where it is written.
pub fn unfold(t: &LocalArc, env: &mut RecEnv) -> Result<(LocalArc, Option<(String, Loc)>), Diagnostic> {
    unfold_with(t, env, &mut |_| {})
}

/// A step [`unfold_with`] took through a parameterised recursion of a local type.
pub enum RecStep<'t> {
    /// Entering `mu t(n = e)`: the parameters, with their initial values.
    Enter(&'t [RecParam]),
    /// Jumping back with `t(a)`: the loop's parameters and the arguments.
    Jump(&'t [RecParam], &'t [Expr]),
}

/// [`unfold`], telling `step` about each step through a recursion with parameters
/// (process typing follows the type's parameters' values).
pub fn unfold_with(
    t: &LocalArc,
    env: &mut RecEnv,
    step: &mut dyn FnMut(RecStep),
) -> Result<(LocalArc, Option<(String, Loc)>), Diagnostic> {
    let mut t = t.clone();
    let mut looped = None;
    for _ in 0..UNFOLD_LIMIT {
        let next = match &*t {
            Local::Rec { var, params, body, .. } => {
                if !params.is_empty() {
                    step(RecStep::Enter(params));
                }
                env.push((var.clone(), t.clone()));
                body.clone()
            }
            Local::Var { var, loc, args } => {
                let Some(i) = env.iter().rposition(|(v, _)| v == var) else {
                    return Err(Diagnostic::error(
                        Code::RecursionMismatch,
                        loc.0,
                        format!("recursion variable `{var}` of the local type is not bound"),
                    )
                    .with_help(format!("bind it with `mu {var}. ...`")));
                };
                env.truncate(i + 1);
                let Some((_, rec)) = env.get(i) else { break };
                let Local::Rec { body, params, .. } = &**rec else {
                    break;
                };
                if !params.is_empty() {
                    step(RecStep::Jump(params, args));
                }
                looped = Some((var.clone(), *loc));
                body.clone()
            }
            _ => return Ok((t, looped)),
        };
        t = next;
    }
    Err(Diagnostic::error(Code::RecursionMismatch, t.loc().0, "unguarded recursion in a local type")
        .with_help("put a message or a motion between `mu t.` and `t`"))
}

/// Renaming of the super type's value variables (by binding site) to expressions of
/// the sub type.
type Renaming = HashMap<ValueId, Expr>;

/// A pair of nodes (sub, super) and the renaming, sorted by binding site.
type Assumed = (usize, usize, Vec<(ValueId, Expr)>);

struct Sub<'a> {
    prog: &'a Program,
    role: RoleId,
    /// How the obligations name the sub and the super type.
    names: [String; 2],
    /// The pairs of nodes assumed related, with the renaming they were met under (the
    /// predicates of the super type's node read the renamed values).
    assumed: HashSet<Assumed>,
    obligations: Vec<Obligation>,
}

impl Sub<'_> {
    fn check(
        &mut self,
        s: &LocalArc,
        senv: &mut RecEnv,
        t: &LocalArc,
        tenv: &mut RecEnv,
        ren: &Renaming,
    ) -> Result<(), Diagnostic> {
        crate::stack::deep(|| self.check_inner(s, senv, t, tenv, ren))
    }

    fn check_inner(
        &mut self,
        s: &LocalArc,
        senv: &mut RecEnv,
        t: &LocalArc,
        tenv: &mut RecEnv,
        ren: &Renaming,
    ) -> Result<(), Diagnostic> {
        let (s, _) = unfold(s, senv)?;
        let (t, _) = unfold(t, tenv)?;
        // Coinduction: a pair met again under the same renaming is assumed related. Which
        // `mu` binds a variable is lexical, so the node pointers determine the
        // environments. The renaming maps binding sites of the super type to those of the
        // sub type, finitely many, so this terminates.
        let mut key: Vec<(ValueId, Expr)> = ren.iter().map(|(k, v)| (*k, v.clone())).collect();
        key.sort_by_key(|(k, _)| *k);
        if !self.assumed.insert((Arc::as_ptr(&s) as usize, Arc::as_ptr(&t) as usize, key)) {
            return Ok(());
        }
        // A timeout alternative (LANGUAGE.md, Timeouts) is related only to the same timeout:
        // the same bound, the same waiting role, and related continuations. No process can
        // write one, so a sub type with a timeout comes from projection only.
        let timeout_of = |l: &Local| match l {
            Local::Send { timeout, .. } | Local::Recv { timeout, .. } => timeout.clone(),
            _ => None,
        };
        match (timeout_of(&s), timeout_of(&t)) {
            (None, None) => {}
            (Some(x), Some(y)) if x.after.ms == y.after.ms && x.after.by == y.after.by => {
                self.check(&x.cont, &mut senv.clone(), &y.cont, &mut tenv.clone(), ren)?;
            }
            _ => {
                return Err(self
                    .mismatch(&s, &t)
                    .with_note("a timeout alternative `after T` is related only to the same timeout, with the same bound and waiting role"))
            }
        }
        match (&*s, &*t) {
            (Local::End(_), Local::End(_)) => Ok(()),
            (Local::Motion { prims: sp, cont: sc, loc: sl }, Local::Motion { prims: tp, cont: tc, loc: tl }) => {
                self.motion(sp, *sl, tp, *tl, ren)?;
                self.check(sc, senv, tc, tenv, ren)
            }
            (Local::Send { branches: sb, .. }, Local::Send { branches: tb, loc: tloc, .. }) => {
                for x in sb {
                    let Some(y) = tb.iter().find(|y| y.to == x.to && y.label == x.label) else {
                        let allowed: Vec<String> =
                            tb.iter().map(|y| format!("`{}!{}`", self.prog.role_name(y.to), y.label)).collect();
                        return Err(Diagnostic::error(
                            Code::UnexpectedSend,
                            x.loc.0,
                            format!(
                                "`{}!{}` is not among the sends the super type allows",
                                self.prog.role_name(x.to),
                                x.label
                            ),
                        )
                        .with_label(tloc.0, format!("allowed here: {}", allowed.join(", ")))
                        .with_note("[SUB-OUT]: every send of the sub type must be a send of the super type")
                        .with_help("send one of the allowed labels to that receiver, or drop this branch"));
                    };
                    self.payload(&x.payload, x.loc, &y.payload, y.loc)?;
                    let mut inner = ren.clone();
                    rename_fields(&mut inner, &y.payload, &x.payload);
                    if let Some(g) = &y.guard {
                        let sup_guard = subst_values(g, ren);
                        let sub_guard = x.guard.clone().unwrap_or_else(|| Expr::bool(true, x.loc));
                        self.implication(sub_guard, sup_guard, x.loc.0, format!("the guard of `{}`", x.label), 0);
                    }
                    let sub_ref = and_all(x.payload.iter().filter_map(|f| f.refinement.clone()), x.loc);
                    let sup_ref = and_all(
                        y.payload.iter().filter_map(|f| f.refinement.as_ref().map(|r| subst_values(r, &inner))),
                        y.loc,
                    );
                    self.implication(sub_ref, sup_ref, x.loc.0, format!("the payload refinement of `{}`", x.label), 0);
                    self.check(&x.cont, &mut senv.clone(), &y.cont, &mut tenv.clone(), &inner)?;
                }
                Ok(())
            }
            (
                Local::Recv { branches: sb, default: sd, loc: sloc, .. },
                Local::Recv { branches: tb, default: td, loc: tloc, .. },
            ) => {
                if let (Some(x), Some(y)) = (sb.first(), tb.first()) {
                    if x.from != y.from {
                        return Err(self.mismatch(&s, &t));
                    }
                }
                for y in tb {
                    let Some(x) = sb.iter().find(|x| x.label == y.label) else {
                        return Err(Diagnostic::error(
                            Code::MissingBranch,
                            sloc.0,
                            format!(
                                "the sub type does not receive `{}?{}`, which the super type may deliver",
                                self.prog.role_name(y.from),
                                y.label
                            ),
                        )
                        .with_label(y.loc.0, "the super type receives it here")
                        .with_note("[SUB-IN]: the sub type handles every label of the super type")
                        .with_help("add a branch receiving this label"));
                    };
                    self.payload(&x.payload, x.loc, &y.payload, y.loc)?;
                    let mut inner = ren.clone();
                    rename_fields(&mut inner, &y.payload, &x.payload);
                    let sup_ref = and_all(
                        y.payload.iter().filter_map(|f| f.refinement.as_ref().map(|r| subst_values(r, &inner))),
                        y.loc,
                    );
                    let sub_ref = and_all(x.payload.iter().filter_map(|f| f.refinement.clone()), x.loc);
                    self.implication(sup_ref, sub_ref, x.loc.0, format!("the payload refinement of `{}`", x.label), 1);
                    self.check(&x.cont, &mut senv.clone(), &y.cont, &mut tenv.clone(), &inner)?;
                }
                match (sd, td) {
                    // [SUB-IN1]
                    (Some((sp, sc)), Some((tp, tc))) => {
                        let sl = sp.first().map(|a| a.loc).unwrap_or(*sloc);
                        let tl = tp.first().map(|a| a.loc).unwrap_or(*tloc);
                        self.motion(sp, sl, tp, tl, ren)?;
                        self.check(sc, senv, tc, tenv, ren)
                    }
                    // [SUB-IN2] drops the sub type's default, or neither has one.
                    (_, None) => Ok(()),
                    (None, Some((tp, _))) => Err(Diagnostic::error(
                        Code::ActionMismatch,
                        sloc.0,
                        format!(
                            "the super type may move with `{}` here, the sub type only waits",
                            motion_text(self.prog, tp)
                        ),
                    )
                    .with_label(t.loc().0, "the default motion comes from here")
                    .with_note("[SUB-IN1,2]: a default motion of the super type must be one of the sub type")
                    .with_help("add the default motion `& dt<...>.T` to the sub type's external choice")),
                }
            }
            // [SUB-IN3]
            (
                Local::Recv { default: Some((sp, sc)), loc: sloc, .. },
                Local::Motion { prims: tp, cont: tc, loc: tl },
            ) => {
                let sl = sp.first().map(|a| a.loc).unwrap_or(*sloc);
                self.motion(sp, sl, tp, *tl, ren)?;
                self.check(sc, senv, tc, tenv, ren)
            }
            _ => Err(self.mismatch(&s, &t)),
        }
    }

    fn mismatch(&self, s: &Local, t: &Local) -> Diagnostic {
        Diagnostic::error(
            Code::ActionMismatch,
            s.loc().0,
            format!("`{}` is not a subtype of `{}`", describe(self.prog, s), describe(self.prog, t)),
        )
        .with_label(t.loc().0, "the super type expects this")
        .with_note("Fig 5: a subtype performs the same kind of action (motion, send, receive or end)")
        .with_help("make the sub type perform the action the super type expects at this point")
    }

    /// [SUB-MOTION]: the sub type's motion refines the super type's.
    fn motion(
        &mut self,
        sub: &[PrimApp],
        sloc: Loc,
        sup: &[PrimApp],
        tloc: Loc,
        ren: &Renaming,
    ) -> Result<(), Diagnostic> {
        let sup: Vec<PrimApp> = sup.iter().map(|a| rename_app(a, ren)).collect();
        if let Some(ob) = refinement(self.prog, self.role, sub, sloc, &sup, tloc)? {
            self.obligations.push(ob);
        }
        Ok(())
    }

    /// Same number of payload values with compatible sorts.
    fn payload(&self, sub: &[Field], sloc: Loc, sup: &[Field], tloc: Loc) -> Result<(), Diagnostic> {
        if sub.len() != sup.len() {
            return Err(Diagnostic::error(
                Code::PayloadArity,
                sloc.0,
                format!("this message carries {} value(s), the super type's carries {}", sub.len(), sup.len()),
            )
            .with_label(tloc.0, "the super type's message")
            .with_help("carry one value per field of the super type's message"));
        }
        for (x, y) in sub.iter().zip(sup) {
            let field = |f: &Field| f.mav.as_ref().map(|m| m.field.clone());
            if field(x) != field(y) {
                let name = |f: &Field| field(f).unwrap_or_else(|| f.name.clone());
                return Err(Diagnostic::error(
                    Code::SortMismatch,
                    sloc.0,
                    format!("this value is the field `{}`, the super type's at its place is `{}`", name(x), name(y)),
                )
                .with_label(tloc.0, "the super type's message")
                .with_help("list the MAVLink message's fields in the super type's order"));
            }
            if !x.sort.fits(&y.sort) && !y.sort.fits(&x.sort) {
                return Err(Diagnostic::error(
                    Code::SortMismatch,
                    sloc.0,
                    format!(
                        "field `{}` has sort `{}`, the super type's `{}` has sort `{}`",
                        x.name, x.sort, y.name, y.sort
                    ),
                )
                .with_label(tloc.0, "the super type's message")
                .with_help("give the field the super type's sort"));
            }
        }
        Ok(())
    }

    /// Records `lhs => rhs` unless it holds syntactically: `lhs`'s conjuncts are the
    /// hypotheses, so the vacuity guard sees a predicate that can never hold (a send the
    /// sub type never makes, a reception the super type never delivers).
    fn implication(&mut self, lhs: Expr, rhs: Expr, span: Span, what: String, from: usize) {
        if rhs.is_true() || lhs == rhs {
            return;
        }
        let [a, b] = [&self.names[from], &self.names[1 - from]];
        let mut hyps = Vec::new();
        conjuncts(&lhs, &mut hyps);
        self.obligations.push(Obligation {
            rule: Rule::Subtype,
            span,
            what: format!("{what} in {a} implies the one in {b}"),
            hyps,
            goal: Goal::Valid(rhs),
        });
    }
}

/// Def 3.4 refinement of `sub` (a motion, possibly a merge `a ⊓ b`) by `sup`: `None`
/// when it holds syntactically (every primitive of `sup` is among `sub`'s, so the meet
/// of `sub` is below the meet of `sup`), E0705 when interruptibility or robot kind
/// differ (Def 3.4 (6)), and otherwise the obligation that the first primitive of
/// `sub` refines the meet of `sup`. For a merged `sub` this asks for more than needed
/// (the meet of `sub` is below its first primitive), which is sound.
pub fn refinement(
    prog: &Program,
    role: RoleId,
    sub: &[PrimApp],
    sloc: Loc,
    sup: &[PrimApp],
    tloc: Loc,
) -> Result<Option<Obligation>, Diagnostic> {
    if sup.iter().all(|a| sub.contains(a)) {
        return Ok(None);
    }
    let Some(concrete) = sub.first() else {
        return Err(Diagnostic::error(Code::PrimitiveMismatch, sloc.0, "this motion names no primitive")
            .with_help("write `dt<a>` with a primitive of the robot's kind"));
    };
    let c = prog.prim(concrete.prim);
    for a in sub.iter().chain(sup) {
        let p = prog.prim(a.prim);
        if p.interruptible != c.interruptible || p.kind != c.kind {
            let word = |i: bool| {
                if i {
                    "interruptible"
                } else {
                    "not interruptible"
                }
            };
            let why = if p.kind != c.kind {
                format!(
                    "`{}` is a primitive of `{}`, `{}` one of `{}`",
                    c.name,
                    prog.kind(c.kind).name,
                    p.name,
                    prog.kind(p.kind).name
                )
            } else {
                format!("`{}` is {}, `{}` is {}", c.name, word(c.interruptible), p.name, word(p.interruptible))
            };
            return Err(Diagnostic::error(
                Code::PrimitiveMismatch,
                sloc.0,
                format!("`{}` cannot refine `{}`: {why}", motion_text(prog, sub), motion_text(prog, sup)),
            )
            .with_label(tloc.0, "the motion the type expects")
            .with_note("Def 3.4 (6): a refinement has the same interruptibility (and robot kind)")
            .with_help(format!(
                "use a primitive that is {} here",
                word(prog.prim(sup.first().map(|a| a.prim).unwrap_or(concrete.prim)).interruptible)
            )));
        }
    }
    Ok(Some(Obligation {
        rule: Rule::Refinement,
        span: sloc.0,
        what: format!(
            "`{}` of `{}` refines `{}` (Def 3.4, concrete on the left)",
            crate::hir::print::prim_app(prog, concrete),
            prog.role_name(role),
            motion_text(prog, sup)
        ),
        hyps: Vec::new(),
        goal: Goal::Refines { role, concrete: concrete.clone(), abstract_: sup.to_vec() },
    }))
}

/// Maps the super type's payload fields to the sub type's value variables (the two
/// binding sites describe one message).
fn rename_fields(ren: &mut Renaming, sup: &[Field], sub: &[Field]) {
    for (y, x) in sup.iter().zip(sub) {
        if x.value == y.value {
            ren.remove(&y.value);
        } else {
            ren.insert(y.value, value_expr(x.value, &x.name, &x.sort));
        }
    }
}

fn rename_app(a: &PrimApp, ren: &Renaming) -> PrimApp {
    PrimApp { prim: a.prim, args: a.args.iter().map(|e| subst_values(e, ren)).collect(), loc: a.loc }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;

    /// Two carts of one kind, so `local P = ...; local Q = ...;` give a sub and a
    /// super type over the same primitives.
    const PAIR: &str = "
        robot Cart { state x: real; }
        motion Cart.idle { interruptible: true; }
        motion Cart.creep { interruptible: true; }
        motion Cart.rush(xf: real) { interruptible: false; }
        system S { participant P: Cart; participant Q: Cart; participant O: Cart; }
        choreography G = end;
    ";

    fn run(sub: &str, sup: &str) -> (Program, Result<Vec<Obligation>, Diagnostic>) {
        let src = format!("{PAIR} local P = {sub}; local Q = {sup};");
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let (Some(s), Some(t)) = (prog.locals.first(), prog.locals.get(1)) else { panic!("two local types") };
        let r = subtype(&prog, RoleId(0), &s.body, &t.body);
        (prog, r)
    }

    fn obligations(sub: &str, sup: &str) -> Vec<Obligation> {
        match run(sub, sup).1 {
            Ok(o) => o,
            Err(d) => panic!("{sub} <= {sup} failed: {d:?}"),
        }
    }

    fn fails(sub: &str, sup: &str) -> Diagnostic {
        match run(sub, sup).1 {
            Ok(o) => panic!("{sub} <= {sup} holds: {o:?}"),
            Err(d) => d,
        }
    }

    #[test]
    fn end_is_a_subtype_of_end_only() {
        assert!(obligations("end", "end").is_empty());
        assert_eq!(fails("end", "dt<idle>.end").code, Code::ActionMismatch);
    }

    #[test]
    fn sub_motion_equal_primitives_need_nothing() {
        assert!(obligations("dt<idle>.end", "dt<idle>.end").is_empty());
        // A merged motion of the sub type already contains the super type's.
        assert!(obligations("dt<idle /\\ creep>.end", "dt<creep>.end").is_empty());
    }

    #[test]
    fn sub_motion_different_primitives_is_a_refinement_obligation() {
        let obs = obligations("dt<creep>.end", "dt<idle /\\ creep>.end");
        assert_eq!(obs.len(), 1);
        assert_eq!(obs[0].rule, Rule::Refinement);
        let Goal::Refines { role, concrete, abstract_ } = &obs[0].goal else { panic!() };
        assert_eq!((*role, concrete.prim, abstract_.len()), (RoleId(0), PrimId(1), 2));
    }

    #[test]
    fn sub_motion_fails_on_interruptibility() {
        let d = fails("dt<rush(1.0)>.end", "dt<idle>.end");
        assert_eq!(d.code, Code::PrimitiveMismatch);
        assert!(d.message.contains("interruptible"), "{}", d.message);
    }

    #[test]
    fn sub_out_fewer_sends_with_implied_predicates() {
        let obs =
            obligations("[x > 1] O!a(v: real { v > 2 }).end", "+{ [P.x > 0] O!a(w: real { w > 0 }).end, O!b.end }");
        assert_eq!(obs.len(), 2, "{obs:?}");
        assert!(obs.iter().all(|o| o.rule == Rule::Subtype));
        let prog = run("end", "end").0;
        let texts: Vec<String> = obs
            .iter()
            .map(|o| match &o.goal {
                Goal::Valid(e) => implication(&prog, o, e),
                _ => String::new(),
            })
            .collect();
        // The super type's field `w` is renamed to the sub type's `v`.
        assert_eq!(texts, vec!["P.x > 1 => P.x > 0", "v > 2 => v > 0"]);
    }

    #[test]
    fn sub_out_fails_on_a_send_the_super_type_lacks() {
        let d = fails("+{ O!a.end, O!c.end }", "+{ O!a.end, O!b.end }");
        assert_eq!(d.code, Code::UnexpectedSend);
        assert!(d.message.contains("O!c"));
        assert_eq!(fails("O!a(v: real).end", "O!a.end").code, Code::PayloadArity);
    }

    #[test]
    fn sub_in_more_receptions_with_reversed_implication() {
        let obs = obligations("&{ O?a(v: real { v > 0 }).end, O?b.end }", "O?a(w: real { w > 1 }).end");
        assert_eq!(obs.len(), 1);
        let Goal::Valid(e) = &obs[0].goal else { panic!() };
        let prog = run("end", "end").0;
        assert_eq!(implication(&prog, &obs[0], e), "v > 1 => v > 0");
    }

    /// `hyps => goal` as text: the left side of a Fig 5 implication is the obligation's
    /// hypotheses (so that the vacuity guard sees it), the right side its goal.
    fn implication(prog: &Program, o: &Obligation, goal: &Expr) -> String {
        let hyps: Vec<String> = o.hyps.iter().map(|h| print::expr(prog, None, h)).collect();
        format!("{} => {}", hyps.join(" && "), print::expr(prog, None, goal))
    }

    #[test]
    fn sub_in_fails_on_a_missing_label_or_sender() {
        assert_eq!(fails("O?a.end", "&{ O?a.end, O?b.end }").code, Code::MissingBranch);
        assert_eq!(fails("Q?a.end", "O?a.end").code, Code::ActionMismatch);
    }

    #[test]
    fn sub_in_defaults() {
        // [SUB-IN1]: both have defaults, the motions are compared.
        assert!(obligations("&{ O?a.end } & dt<idle>.end", "&{ O?a.end } & dt<idle>.end").is_empty());
        // [SUB-IN2]: the sub type's default may be dropped.
        assert!(obligations("&{ O?a.end } & dt<idle>.end", "O?a.end").is_empty());
        // [SUB-IN3]: receptions with a default may stand for the motion alone.
        assert_eq!(obligations("&{ O?a.end } & dt<creep>.end", "dt<idle>.end").len(), 1);
        // A default of the super type the sub type lacks fails.
        assert_eq!(fails("O?a.end", "&{ O?a.end } & dt<idle>.end").code, Code::ActionMismatch);
        assert_eq!(
            fails("&{ O?a.end } & dt<rush(1.0)>.end", "&{ O?a.end } & dt<idle>.end").code,
            Code::PrimitiveMismatch
        );
    }

    #[test]
    fn recursion_is_coinductive_and_may_unfold_at_different_points() {
        assert!(obligations("mu t. O!a.O?b.t", "O!a.mu s. O?b.O!a.s").is_empty());
        assert!(obligations("mu t. O!a.O?b.O!a.O?b.t", "mu s. O!a.O?b.s").is_empty());
        assert_eq!(fails("mu t. O!a.O?b.t", "mu s. O!a.O?b.end").code, Code::ActionMismatch);
    }
}
