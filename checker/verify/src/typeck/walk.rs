//! The structural walk of process typing (Table 1): process and local type are followed
//! together, sequences in a loop and branches by recursion, and the shapes of the two
//! pick the rule: [T-OUT], [T-CHOICE1,2] (with [SUB-IN3] for a default the type takes),
//! [T-MOTION], [T-REC]/[T-VAR] (through `rec.rs`), `if` (a generalised [T-COND]: both
//! branches against the same type), an internal choice of sends, and `end`.

use super::{Checker, State};
use crate::diag::{Code, Diagnostic};
use crate::hir::expr::{not, subst_values};
use crate::hir::print::describe;
use crate::hir::*;
use crate::sigma::{self};
use crate::subtype::{unfold_with, RecStep};

impl<'a> Checker<'a> {
    /// Checks `p` against `t`. Sequences are followed in a loop; branches recurse.
    pub(super) fn check_inner(&mut self, mut p: &'a Process, mut t: LocalArc, mut st: State<'a>) {
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
            if looped.is_some() {
                st.forget_foreign(self.prog, self.role);
            }
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
                (Process::Send { to, label, args, cont, loc }, Local::Send { branches, loc: tloc, .. }) => {
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
                    Local::Recv { branches: tb, default: td, loc: tloc, .. },
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
