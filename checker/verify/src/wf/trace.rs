//! Counterexample traces: the path through the global type that reaches the
//! point of a failing obligation, in the user's terms. A global type is a tree, so the
//! point (the obligation's span: a message, a jump, a choice's first message, a
//! parameter's initial value) determines its path from the start: the messages and
//! motions before it in each enclosing sequence, the branch taken at each enclosing
//! choice, and the head of each enclosing loop. One iteration of each loop is shown: the
//! loop head with the parameters' values of the iteration that reaches the point. The
//! values come from the counterexample's model (by each value's symbol there); a value
//! the model does not mention is shown by its name alone.

use crate::diag::Assignment;
use crate::hir::*;
use crate::source::Span;

/// One step of a path.
#[derive(Debug)]
pub enum Step<'g> {
    /// A message sent on the way; `branch` when it is the first of a choice's branch
    /// (its index and the number of branches).
    Msg { m: &'g Msg, branch: Option<(usize, usize)> },
    /// The head of a loop the point is in.
    Loop { var: &'g str, params: &'g [RecParam] },
    /// A joint motion on the way.
    Motion(&'g Motion),
    /// A choice passed before the point: some branch that continues was taken.
    Choice,
    /// The point is on side `k` of `n` of a `*`.
    Side(usize, usize),
}

/// The path from the start of `g` to the node at `span`, or `None` when no node of `g`
/// is there (an obligation of a process, of a contract).
pub fn path_to(g: &Global, span: Span) -> Option<Vec<Step<'_>>> {
    let mut out = Vec::new();
    find(g, span, None, &mut out).then_some(out)
}

fn within(outer: Span, inner: Span) -> bool {
    outer.file == inner.file && outer.start <= inner.start && inner.end <= outer.end
}

fn find<'g>(g: &'g Global, span: Span, branch: Option<(usize, usize)>, out: &mut Vec<Step<'g>>) -> bool {
    if !within(g.loc().0, span) {
        return false;
    }
    match g {
        Global::Msg(_) | Global::Motion(_) | Global::Var(_) | Global::End(_) | Global::After(_) => true,
        Global::Seq(items, _) => {
            let mut branch = branch;
            for it in items {
                if crate::stack::deep(|| find(it, span, branch, out)) {
                    return true;
                }
                match it {
                    Global::Msg(m) => out.push(Step::Msg { m, branch }),
                    Global::Motion(m) => out.push(Step::Motion(m)),
                    Global::Choice(..) => out.push(Step::Choice),
                    _ => {}
                }
                branch = None;
            }
            false
        }
        Global::Choice(bs, _) => {
            let n = bs.len();
            bs.iter().enumerate().any(|(k, b)| crate::stack::deep(|| find(b, span, Some((k + 1, n)), out)))
        }
        Global::Par(sides, _) => {
            let n = sides.len();
            for (k, s) in sides.iter().enumerate() {
                if within(s.loc().0, span) {
                    out.push(Step::Side(k + 1, n));
                    return crate::stack::deep(|| find(s, span, None, out));
                }
            }
            false
        }
        Global::Rec { var, params, body, .. } => {
            // A parameter's initial value: the point is the loop's entry.
            if params.iter().any(|p| within(p.init.loc.0, span)) {
                return true;
            }
            out.push(Step::Loop { var, params });
            crate::stack::deep(|| find(body, span, None, out)) || {
                out.pop();
                true // the loop head itself (its measure, its parameters' refinements)
            }
        }
    }
}

/// The steps as lines: `GCS -> UAV: MISSION_COUNT(count = 3)`, `loop t: i = 0`. `values`
/// are the counterexample's; `bound` says which symbol each of two same-named values has
/// (`smt::Failure::bound`).
pub fn lines(prog: &Program, steps: &[Step], values: &[Assignment], bound: &[(String, String, Span)]) -> Vec<String> {
    // `shown` is the name the user reads (a MAVLink field as written, `seq` of
    // `seq as s`); `name` the value's own, by which the model knows it.
    let value = |id: ValueId, name: &str, shown: &str| -> String {
        let shared: Vec<&(String, String, Span)> = bound.iter().filter(|(_, n, _)| n == name).collect();
        let symbol = if shared.is_empty() {
            Some(name.to_string())
        } else {
            shared.iter().find(|(_, _, s)| *s == prog.value(id).span).map(|(sym, _, _)| sym.clone())
        };
        match symbol.and_then(|sym| values.iter().find(|a| a.name == sym)) {
            Some(a) => format!("{shown} = {}", a.value),
            None => shown.to_string(),
        }
    };
    let mut out = Vec::new();
    for step in steps {
        match step {
            Step::Msg { m, branch } => {
                let guard = m.guard.as_ref().map(|g| format!("[{}] ", print::expr(prog, None, g))).unwrap_or_default();
                let fields: Vec<String> = m
                    .payload
                    .iter()
                    .map(|f| {
                        let text = value(f.value, &f.name, f.mav.as_ref().map_or(&f.name, |m| &m.written));
                        match f.mav.as_ref().and_then(|m| m.entry.as_ref()) {
                            Some(check) => entry_named(prog, &check.enum_name, text),
                            None => text,
                        }
                    })
                    .collect();
                let payload = if fields.is_empty() { String::new() } else { format!("({})", fields.join(", ")) };
                let which = branch.map(|(k, n)| format!("   (branch {k} of {n})")).unwrap_or_default();
                out.push(format!(
                    "{} -> {}: {guard}{}{payload}{which}",
                    prog.role_name(m.from),
                    prog.role_name(m.to),
                    m.label
                ));
            }
            Step::Loop { var, params } => {
                let ps: Vec<String> = params.iter().map(|p| value(p.value, &p.name, &p.name)).collect();
                if ps.is_empty() {
                    out.push(format!("mu {var}   (loop head)"));
                } else {
                    out.push(format!("mu {var}: {}   (loop head: this iteration's parameters)", ps.join(", ")));
                }
            }
            Step::Motion(m) => {
                let parts: Vec<String> = m
                    .parts
                    .iter()
                    .map(|(r, a)| format!("{}: {}", prog.role_name(*r), print::prim_app(prog, a)))
                    .collect();
                out.push(format!("dt<{}>", parts.join(", ")));
            }
            Step::Choice => out.push("(a choice: one of its branches)".into()),
            Step::Side(k, n) => out.push(format!("(side {k} of {n} of `*`)")),
        }
    }
    out
}

/// `field = 2` of a field whose values are entries of enum `enum_name` (not a bitmask),
/// as `field = NAME` when 2 is the value of entry `NAME`; otherwise as it is.
fn entry_named(prog: &Program, enum_name: &str, text: String) -> String {
    let Some((field, value)) = text.split_once(" = ") else { return text };
    let Ok(v) = value.parse::<i64>() else { return text };
    let entry = prog
        .dialect
        .and_then(|d| d.enums.iter().find(|e| e.name == enum_name && !e.bitmask))
        .and_then(|e| e.entries.iter().find(|x| x.value == v));
    match entry {
        Some(x) => format!("{field} = {}", x.name),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use crate::lower::tests::lower_src;

    const SRC: &str = "
        robot R { state x: real; }
        system S { participant P: R; participant Q: R; }
        choreography G =
          P -> Q: count(c: int {1 <= c && c <= 5}).
          mu t(i: int {0 <= i && i <= c} = 0).
            ( Q -> P: [i < c] req(seq: int {seq == i}). P -> Q: item(s: int {s == i}). t(i + 1)
            + Q -> P: [i == c] ack. end );";

    /// The path to the jump: the count, the loop head, the branch's messages.
    #[test]
    fn the_path_to_a_jump_lists_the_messages_and_the_loop_head() {
        let (p, d) = lower_src(SRC);
        assert!(d.is_empty(), "{d:?}");
        let g = &p.choreography.as_ref().unwrap().body;
        let mut jump = None;
        fn find_var(g: &crate::hir::Global, out: &mut Option<crate::source::Span>) {
            use crate::hir::Global;
            match g {
                Global::Var(v) => *out = Some(v.loc.0),
                Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
                    gs.iter().for_each(|g| find_var(g, out))
                }
                Global::Rec { body, .. } => find_var(body, out),
                _ => {}
            }
        }
        find_var(g, &mut jump);
        let steps = super::path_to(g, jump.unwrap()).expect("the jump is in the type");
        let values = [("c", "3"), ("i", "2"), ("seq", "2")]
            .map(|(n, v)| crate::diag::Assignment { name: n.into(), value: v.into() });
        let lines = super::lines(&p, &steps, &values, &[]);
        assert_eq!(
            lines,
            vec![
                "P -> Q: count(c = 3)".to_string(),
                "mu t: i = 2   (loop head: this iteration's parameters)".into(),
                "Q -> P: [i < c] req(seq = 2)   (branch 1 of 2)".into(),
                "P -> Q: item(s)".into(),
            ]
        );
        assert!(super::path_to(g, crate::source::Span::default()).is_none() || g.loc().0 == Default::default());
    }

    /// An enum-typed field's value is shown as its entry's name (`MAV_MISSION_TYPE_FENCE`,
    /// not `1`); a value no entry has stays a number.
    #[test]
    fn an_enum_field_shows_its_entry_name() {
        let (p, d) = lower_src(
            "dialect common;\nsystem S { participant GCS; participant UAV; }\n
             choreography G = GCS -> UAV: MISSION_REQUEST_LIST(mission_type). end;",
        );
        assert!(d.is_empty(), "{d:?}");
        let g = &p.choreography.as_ref().unwrap().body;
        let crate::hir::Global::Seq(items, _) = g else { panic!("a sequence: {g:?}") };
        let steps = super::path_to(g, items[1].loc().0).expect("the end is in the type");
        let shown = |v: &str| {
            let values = [crate::diag::Assignment { name: "mission_type".into(), value: v.into() }];
            super::lines(&p, &steps, &values, &[])
        };
        assert_eq!(shown("1"), vec!["GCS -> UAV: MISSION_REQUEST_LIST(mission_type = MAV_MISSION_TYPE_FENCE)"]);
        assert_eq!(shown("77"), vec!["GCS -> UAV: MISSION_REQUEST_LIST(mission_type = 77)"]);
    }
}
