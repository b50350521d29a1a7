//! [T-OUT] of Table 1 with [SUB-OUT] (Fig 5): a send matches a branch of the type's
//! internal choice (E0704 otherwise), with one value per field of the right sort (E0707,
//! E0208), and the obligation `Σ ⇒ P ∧ P'{e/v}` for its guard and refinements.

use super::{Checker, State};
use crate::diag::{Code, Diagnostic};
use crate::hir::expr::{and_all, conjuncts, subst_values};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};

impl Checker<'_> {
    /// [T-OUT]: arity, sorts, and the obligation `Σ ⇒ guard ∧ refinement{args/fields}`.
    pub(super) fn send(&mut self, args: &[Expr], loc: Loc, b: &SendBranch, st: &mut State) -> bool {
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
        for (a, f) in args.iter().zip(&b.payload) {
            self.sent_string_fits(a, f, b.loc);
        }
        // The type's fields get new values (a binding site met again in a loop): what
        // was known of their earlier values goes. The guard reads only older values.
        let fields: Vec<ValueId> = b.payload.iter().map(|f| f.value).collect();
        st.forget(&fields);
        let mut vals = st.vals.clone();
        for (a, f) in args.iter().zip(&b.payload) {
            // The value the receiver gets: a literal sent in a MAVLink float field rounded
            // to the field's format (`lower::wire_value`).
            let a = match crate::lower::wire_value(self.prog, f.value, a) {
                Ok(w) => w,
                Err(text) => {
                    self.diags.push(
                        Diagnostic::error(
                            Code::SendPredicate,
                            a.loc.0,
                            format!("`{text}` sent in the float field `{}` rounds to an infinity on the wire", f.name),
                        )
                        .with_label(b.loc.0, "the field is declared here")
                        .with_note(
                            "a MAVLink float field carries finite values only (LANGUAGE.md, \"Floats are float32\")",
                        )
                        .with_help("send a value within the field's format"),
                    );
                    a.clone()
                }
            };
            vals.insert(f.value, a);
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
            let goal = crate::hir::expr::defined_and(and_all(goal, loc));
            if let Some(hint) = self.loop_hint(&goal) {
                self.hints.insert((Rule::TOut, loc.0), hint);
            }
            self.obligations.push(Obligation {
                rule: Rule::TOut,
                span: loc.0,
                what: format!("`{}` may send `{to}!{}`: the guard and payload refinement hold", self.name(), b.label),
                hyps: st.sigma.facts().to_vec(),
                // The guard and refinements hold of the values sent, and can be evaluated.
                goal: Goal::Valid(goal),
            });
        }
        st.vals = vals;
        st.actions += 1;
        true
    }

    /// E0236: a string sent in a `char[N]` field that may be longer than N. The wire keeps
    /// its first N characters, while [T-OUT] types the send as carrying the whole value (a
    /// string is one code to the checks, without a length): a received STATUSTEXT.text
    /// (char[50]) echoed as a PARAM_SET.param_id (char[16]) would be typed as the text.
    fn sent_string_fits(&mut self, a: &Expr, f: &Field, decl: Loc) {
        let Some(&n) = self.prog.str_width.get(&f.value) else { return };
        let w = self.prog.str_width_of(a, &|v| self.bound_width.get(&v).copied());
        if w.is_some_and(|w| w <= n) {
            return;
        }
        let what = match w {
            Some(w) => format!("a string of up to {w} characters"),
            None => "a string of a width mochi does not know".to_string(),
        };
        self.diags.push(
            Diagnostic::error(
                Code::StringTooLong,
                a.loc.0,
                format!("this sends {what} in `{}`, which holds at most {n}: the wire keeps its first {n}", f.name),
            )
            .with_label(decl.0, "the field is declared here")
            .with_help(format!(
                "send a value received in a field at most {n} wide, or a literal of at most {n} characters"
            )),
        );
    }

    pub(super) fn unexpected_send(&mut self, to: RoleId, label: &str, loc: Loc, branches: &[SendBranch], tloc: Loc) {
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
}

pub(super) fn fields_text(fields: &[Field]) -> String {
    if fields.is_empty() {
        return "no payload".to_string();
    }
    let items: Vec<String> = fields.iter().map(|f| format!("{}: {}", f.name, f.sort)).collect();
    format!("payload ({})", items.join(", "))
}
