//! [T-CHOICE1,2] of Table 1 with [SUB-IN1,2] (Fig 5): a receive handles every label of
//! the type's external choice (E0703 otherwise); each branch continues under the
//! refinement of what it received, and a default motion of the type must be matched.

use super::out::fields_text;
use super::{Checker, State};
use crate::diag::{Code, Diagnostic};
use crate::hir::expr::{subst_values, value_expr};
use crate::hir::print::{describe, motion_text};
use crate::hir::*;

impl<'a> Checker<'a> {
    /// [T-CHOICE1,2] with [SUB-IN1,2]: every label of the type is handled; each branch
    /// continues under the refinement of what it received.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn receive(
        &mut self,
        arms: &'a [RecvArm],
        default: Option<&'a (PrimApp, Box<Process>)>,
        loc: Loc,
        tb: &[RecvBranch],
        td: Option<&(Vec<PrimApp>, LocalArc)>,
        t: &LocalArc,
        st: &State<'a>,
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
                if let Some(&n) = self.prog.str_width.get(&f.value) {
                    self.bound_width.insert(*v, n);
                }
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
}
