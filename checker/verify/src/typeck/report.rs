//! The structural errors of process typing (Table 1): no rule applies because the
//! process and its local type disagree on the kind of the next action (E0702) or on
//! where a loop goes back ([T-REC]/[T-VAR], E0706).

use super::Checker;
use crate::diag::{Code, Diagnostic};
use crate::hir::print::{describe, print_bounded, NOTE_NODES};
use crate::hir::*;

impl Checker<'_> {
    /// E0702: the process and the type disagree on the kind of the next action.
    pub(super) fn mismatch(&mut self, p: &Process, t: &LocalArc, looped: Option<&(String, Loc)>) {
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
    pub(super) fn loop_mismatch(&mut self, var: &str, loc: Loc, body: &Process, t: &LocalArc) {
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
