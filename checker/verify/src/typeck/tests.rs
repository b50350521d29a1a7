//! Unit tests of process typing, rule by rule of Table 1 (with Fig 5 folded in).

use super::*;
use crate::hir::print::motion_text;
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
    let (obs, diags) = check_processes(&prog, &map);
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
    obs.iter().filter(|o| o.rule == rule).map(|o| o.hyps.iter().map(|h| print::expr(prog, None, h)).collect()).collect()
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
    let bad =
        src.replace("Cart?ready.dt<pick>.Cart!ok.dt<work>.k + Cart?free", "Cart?ready.dt<pick>.dt<work>.k + Cart?free");
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
    let chor = "choreography G = C -> A : go(tf: real { tf > 0 }). A -> C : [tf > 0] ack(u: real { u == tf }). end;";
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
    let (_, d, _) = check_with(chor, "process C = A!a.A?x.end + A!b.end; process A = C?a.C!z.end + C?b.dt<work>.end;");
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
    let (_, d, _) =
        check("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k; process A = mu k. C?go(y).dt<grab>.C!done.k;");
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

/// Obligations are the same when their rule, span, hypotheses (as a set) and goal are,
/// terms compared as `Expr` compares them: without locations. (Before, goals compared
/// by their `Debug` text, which prints locations, and a goal met twice with its terms
/// written at other places was kept twice.)
#[test]
fn the_same_obligation_met_twice_is_kept_once() {
    use crate::source::{FileId, Span};
    let at = |start: usize| Loc(Span::new(FileId(0), start, start + 1));
    let v = |id: u32, start: usize| Expr {
        kind: ExprKind::Var(Var::Value(ValueId(id), "v".into())),
        sort: Sort::Real,
        loc: at(start),
    };
    let zero = |start: usize| Expr { kind: ExprKind::Real("0.5".into()), sort: Sort::Real, loc: at(start) };
    let gt = |a: Expr, b: Expr| Expr {
        kind: ExprKind::Binary(crate::hir::expr::BinOp::Gt, Box::new(a), Box::new(b)),
        sort: Sort::Bool,
        loc: Loc::default(),
    };
    let ob = |hyps: Vec<Expr>, goal: Goal| Obligation {
        rule: Rule::TOut,
        span: Span::new(FileId(0), 3, 4),
        what: String::new(),
        hyps,
        goal,
    };
    let app = |start: usize| PrimApp { prim: PrimId(0), args: vec![v(0, start)], loc: at(start) };
    let refines =
        |start: usize| Goal::Refines { role: RoleId(0), concrete: app(start), abstract_: vec![app(start + 1)] };
    let mut obs = vec![
        ob(vec![gt(v(0, 1), zero(2)), gt(v(1, 1), zero(2))], Goal::Valid(gt(v(0, 5), zero(6)))),
        // The same, written elsewhere, hypotheses in another order.
        ob(vec![gt(v(1, 7), zero(8)), gt(v(0, 9), zero(10))], Goal::Valid(gt(v(0, 11), zero(12)))),
        // Another value of the same name: another goal.
        ob(vec![gt(v(0, 1), zero(2)), gt(v(1, 1), zero(2))], Goal::Valid(gt(v(1, 5), zero(6)))),
        // Another literal text: kept (reals compare by their text, never rounded).
        ob(
            vec![gt(v(0, 1), zero(2)), gt(v(1, 1), zero(2))],
            Goal::Valid(gt(v(0, 5), Expr { kind: ExprKind::Real("0.50000000000000001".into()), ..zero(6) })),
        ),
        ob(vec![], refines(20)),
        ob(vec![], refines(30)),
    ];
    super::dedupe(&mut obs);
    assert_eq!(obs.len(), 4, "{obs:#?}");
    assert!(matches!(obs[3].goal, Goal::Refines { .. }));
}

/// With some but not all processes, each missing one is still E0701 (a partial set is most
/// likely an omission; a cell without any process is a protocol, `checker/cli/protocol_tests.rs`).
#[test]
fn a_partial_set_of_processes_still_needs_every_process() {
    let (_, d, _) = check("process C = mu k. A!go(x + 1).dt<move(x + 1)>.A?done.k;");
    assert_eq!(codes(&d), vec![Code::MissingProcess], "{d:?}");
}
