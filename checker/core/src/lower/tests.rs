//! Unit tests of lowering: names resolved, sorts checked, values bound by site (LANGUAGE.md "Names and scopes", "Sorts").

use super::*;
use crate::source::SourceDb;

pub(crate) use crate::testing::{first_guard, lower_src, HEADER};

fn codes(d: &[Diagnostic]) -> Vec<Code> {
    d.iter().map(|d| d.code).collect()
}

#[test]
fn a_complete_program_lowers_cleanly() {
    let src = format!(
        "{HEADER} choreography G = mu t. C -> A : [x >= 0] go(tf: real {{ tf > C.x }}). dt<C: move(tf), A: work>. A -> C: done. t;
         process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k;
         process A = mu k. C?go(y).dt<work>.C!done.k;"
    );
    let (p, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(p.roles.len(), 2);
    assert_eq!(p.roles[1].input_sources, vec![Some(RoleId(0))]);
    assert_eq!(p.processes.len(), 2);
    let Some(c) = &p.choreography else { panic!() };
    assert!(matches!(c.body, Global::Rec { .. }));
}

#[test]
fn unknown_names_are_reported_with_their_kind() {
    let src = format!(
        "{HEADER} choreography G = C -> B : go. dt<C: fly, A: work>. t;
         process C = dt<idle>.Z;"
    );
    let (_, d) = lower_src(&src);
    assert_eq!(
        codes(&d),
        vec![Code::UnknownParticipant, Code::UnknownPrimitive, Code::UnboundRecursion, Code::UnboundRecursion]
    );
}

#[test]
fn contract_parts_read_only_what_def_3_4_allows() {
    let src = "robot R { state x: real; input w: real; }
               motion R.m { interruptible: true; assume: x > 0; guarantee: w > 0; pre: clock > 0; post: old(x) == x; }";
    let (_, d) = lower_src(src);
    let d: Vec<_> = d.into_iter().filter(|d| d.code != Code::MissingItem).collect();
    assert_eq!(codes(&d), vec![Code::VariableNotAllowed; 3], "{d:?}");
    assert!(d[0].message.contains("assumption"));
}

#[test]
fn pi_is_a_reserved_real_constant_that_prints_back() {
    let src = "const half_pi: real = pi / 2; robot R { state a: real; }
               system S { participant A: R { init: a == -pi + half_pi; } } choreography G = end;";
    let (p, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let half = &p.consts[0].value;
    assert_eq!(half.sort, Sort::Real);
    assert!(matches!(&half.kind, ExprKind::Binary(_, a, _) if matches!(a.kind, ExprKind::Call(Builtin::Pi, _))));
    let init = p.roles[0].init.as_ref().expect("init");
    let text = crate::hir::print::expr(&p, None, init);
    assert_eq!(text, "A.a == -pi + half_pi");
    // The printed text reads back to the same term.
    let again = format!(
        "const half_pi: real = pi / 2; robot R {{ state a: real; }}
         system S {{ participant A: R {{ init: {}; }} }} choreography G = end;",
        text.replace("A.a", "a")
    );
    let (q, d) = lower_src(&again);
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(q.roles[0].init.as_ref().map(|e| crate::hir::print::expr(&q, None, e)), Some(text));
    // `pi` cannot be redefined or called.
    for bad in ["const pi: real = 3;", "const x = pi();", "robot R { state pi: real; }"] {
        let mut db = SourceDb::new();
        let id = db.add("t.chor", bad);
        let (_, d) = crate::syntax::parser::parse(id, bad);
        assert_eq!(codes(&d), vec![Code::UnexpectedToken], "{bad}: {d:?}");
    }
    let mut db = SourceDb::new();
    let id = db.add("t.chor", "const pi: real = 3;");
    let (_, d) = crate::syntax::parser::parse(id, "const pi: real = 3;");
    assert!(d[0].help.as_deref().is_some_and(|h| h.contains("built-in constant")), "{d:?}");
}

#[test]
fn sorts_are_checked() {
    let src = format!("{HEADER} choreography G = C -> A : [x + true] go(n: int {{ n }}). end;");
    let (_, d) = lower_src(&src);
    assert!(codes(&d).iter().all(|c| *c == Code::SortMismatch), "{d:?}");
    assert_eq!(d.len(), 3, "{d:?}"); // `x + true`, the guard is not bool, `n` is not bool
}

#[test]
fn missing_interruptible_and_duplicates() {
    let src = format!("{HEADER} motion Cart.idle {{ interruptible: true; }} motion Arm.j {{ pre: true; pre: true; }}");
    let (_, d) = lower_src(&src);
    let c = codes(&d);
    assert!(c.contains(&Code::Duplicate) && c.contains(&Code::MissingField), "{d:?}");
}

#[test]
fn unconnected_inputs_are_reported() {
    let src = "robot R { input w: real; } system S { participant P: R; } choreography G = end;";
    let (_, d) = lower_src(src);
    assert_eq!(codes(&d), vec![Code::UnconnectedInput]);
}

#[test]
fn a_library_file_has_no_system() {
    let (_, d) = lower_src("robot R { state x: real; }");
    assert_eq!(codes(&d), vec![Code::MissingItem]);
}

/// An expression with a failed part (its error reported) fails as a whole, silently: one
/// diagnostic per mistake, none about the well-sorted terms around it.
#[test]
fn a_failed_part_fails_its_whole_expression_silently() {
    for guard in [
        "norm2(ghost - point(1, 0, 0)) > 0",
        "(ghost, 1).x > 0",
        "ghost + true > 0",
        "C.nope.x > 0",
        "-old(x) > 0",
        "sqrt(ghost) > point(0, 0, 0).x",
    ] {
        let src = format!("{HEADER} choreography G = C -> A: [{guard}] go. end;");
        let (prog, d) = lower_src(&src);
        let expected = if guard.contains("old") { Code::VariableNotAllowed } else { Code::UnknownVariable };
        assert_eq!(codes(&d), vec![expected], "{guard}: {d:?}");
        let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| &c.body) else { panic!("a sequence") };
        let Global::Msg(m) = &items[0] else { panic!("a message") };
        let g = m.guard.as_ref().expect("guard");
        assert!(g.is_error(), "{guard}: {g:?}");
        // Never a proof of anything: no later stage gives the error expression a value.
        assert!(!g.is_true() && crate::exact::eval(&prog, g, &|_: &Var| None).is_err(), "{guard}");
    }
}

/// A process binder's sort is open until typing gives it the payload's (`Sort::Any`); that
/// is not the sort of a failed expression (`Sort::Error`). `p.x` of a binder is its
/// component (it used to become `true`, silently), and `p - point(...)` is no sort error.
#[test]
fn a_binder_is_not_a_failed_expression() {
    let src = format!(
        "{HEADER} choreography G = C -> A: go(q: point). dt<C: idle, A: work>. end;
         process A = C?go(p). if p.x > norm2(p - point(1, 0, 0)) then dt<work>.end else dt<work>.end;"
    );
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let Some(Process::Recv { branches, .. }) = prog.processes.first().map(|p| &p.body) else { panic!("a receive") };
    let Process::If { cond, .. } = &branches[0].cont else { panic!("a conditional") };
    let ExprKind::Binary(BinOp::Gt, a, _) = &cond.kind else { panic!("{cond:?}") };
    assert!(matches!(a.kind, ExprKind::Component(_, 0)), "{a:?}");
}

/// `after T ms by R` (LANGUAGE.md, Timeouts): a positive integer constant bound (E0320),
/// at the head of a branch of a choice only (E0321); `after` stays a name elsewhere.
#[test]
fn a_timeout_is_placed_and_bounded() {
    let lower = |chor: &str| {
        let (p, d) = lower_src(&format!("{HEADER} const N: int = 250; choreography G = {chor};"));
        (p, codes(&d))
    };
    let (p, d) = lower("C -> A: go. end + after 2 * N ms by A. A -> C: again. end");
    assert_eq!(d, vec![]);
    let Some(Global::Choice(bs, _)) = p.choreography.as_ref().map(|c| &c.body) else { panic!("a choice") };
    let a = bs[1].timeout_head().expect("the second branch times out");
    assert_eq!((a.ms, p.role_name(a.by)), (500, "A"));
    assert_eq!(lower("(C -> A: go. end + after 0 ms by A. end)").1, vec![Code::TimeoutBound]);
    assert_eq!(lower("(C -> A: go. end + after N - 300 ms by A. end)").1, vec![Code::TimeoutBound]);
    assert_eq!(lower("(C -> A: go(n: int). end + after n ms by A. end)").1, vec![Code::UnknownVariable]);
    assert_eq!(lower("C -> A: go(n: int). (A -> C: x. end + after n ms by C. end)").1, vec![Code::TimeoutBound]);
    assert_eq!(lower("C -> A: go. after 10 ms by A. end").1, vec![Code::TimeoutNotInChoice]);
    assert_eq!(lower("after 10 ms by A. end").1, vec![Code::TimeoutNotInChoice]);
    assert_eq!(lower("mu t. (after 10 ms by A. end + C -> A: go. t)").1, vec![]);
    assert_eq!(
        lower("(C -> A: go. end + (after 10 ms by A. end) * (C -> A: x. end))").1,
        vec![Code::TimeoutNotInChoice]
    );
    // `after` followed by no bound is a recursion variable's name.
    assert_eq!(lower("mu after. C -> A: go. after").1, vec![]);
    // A bracketed bound is a bound (the constants relation of the metamorphic tests writes
    // `1000` as `(999 + 1)`), and a bracket without `ms` after it is a jump.
    let (p, d) = lower("C -> A: go. end + after (2 * N + 1) ms by A. A -> C: again. end");
    assert_eq!(d, vec![]);
    let Some(Global::Choice(bs, _)) = p.choreography.as_ref().map(|c| &c.body) else { panic!("a choice") };
    assert_eq!(bs[1].timeout_head().map(|a| a.ms), Some(501));
    assert_eq!(lower("mu after(k: int = 0). C -> A: go. after(k + 1)").1, vec![]);
}

/// Written local types have the timeout alternative the printer writes (LANGUAGE.md,
/// Timeouts): `after T ms. T'` in the waiting role's external choice, `after T ms by R. T'`
/// in the sender's internal choice. A projection with timeouts prints, reads back and
/// lowers to the same type; a misplaced, doubled, unnamed or non-positive timeout is an
/// error.
#[test]
fn written_local_types_have_timeouts() {
    let src = format!(
        "{HEADER} const N: int = 500;
         choreography G = mu t. (C -> A: go. t + after 2 * N ms by A. (A -> C: again. end + after 30 ms by C. end));"
    );
    let (p, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let (locals, d) = crate::project::project_all(&p);
    assert!(d.is_empty(), "{d:?}");
    let mut texts = Vec::new();
    for (role, t) in &locals {
        let text = crate::hir::print::local(&p, t);
        let mut db = SourceDb::new();
        let file = db.add("printed", text.clone());
        let (ast, d) = crate::syntax::parser::parse_local(file, &text);
        assert!(d.is_empty(), "{text}: {d:?}");
        let (back, d) = lower_local(&p, *role, &ast.expect("parsed"));
        assert!(d.is_empty(), "{text}: {d:?}");
        assert!(crate::project::alpha_equal(&back, t), "{text}");
        assert_eq!(crate::hir::print::local(&p, &back), text);
        texts.push(text);
    }
    assert!(texts.iter().any(|t| t.contains("after 2 * N ms by A.")), "{texts:?}");
    assert!(texts.iter().any(|t| t.contains("after 2 * N ms. ")), "{texts:?}");

    // Another bound, another waiting role: not the same type.
    let c = p.role_by_name("C").expect("C");
    let written = |text: &str| {
        let mut db = SourceDb::new();
        let file = db.add("written", text.to_string());
        let (ast, d) = crate::syntax::parser::parse_local(file, text);
        if !d.is_empty() {
            return Err(d.iter().map(|d| d.code).collect::<Vec<_>>());
        }
        let (back, d) = lower_local(&p, c, &ast.expect("parsed"));
        if d.is_empty() {
            Ok(back)
        } else {
            Err(codes(&d))
        }
    };
    let projected = &locals[&c];
    let same = written("mu t. +{ A!go.t, after 1000 ms by A. &{ A?again.end, after 30 ms. end } }").expect("lowers");
    assert!(crate::project::alpha_equal(&same, projected), "{}", crate::hir::print::local(&p, projected));
    let longer = written("mu t. +{ A!go.t, after 1001 ms by A. &{ A?again.end, after 30 ms. end } }").expect("lowers");
    assert!(!crate::project::alpha_equal(&longer, projected));
    let mine = written("mu t. +{ A!go.t, after 1000 ms by C. &{ A?again.end, after 30 ms. end } }").expect("lowers");
    assert!(!crate::project::alpha_equal(&mine, projected));
    // Errors: no `by` in an internal choice, two timeouts, a timeout outside a choice, a
    // bound that is not a positive constant.
    assert_eq!(written("+{ A!go.end, after 10 ms. end }").map(|_| ()), Err(vec![Code::UnexpectedToken]));
    assert_eq!(
        written("&{ A?go.end, after 10 ms. end, after 20 ms. end }").map(|_| ()),
        Err(vec![Code::UnexpectedToken])
    );
    assert_eq!(written("after 10 ms. end").map(|_| ()), Err(vec![Code::UnexpectedToken]));
    assert_eq!(written("&{ A?go.end, after 0 ms. end }").map(|_| ()), Err(vec![Code::TimeoutBound]));
    // `after` with no bound after it is still a name.
    assert!(written("mu after. A!go.after").is_ok());
}
