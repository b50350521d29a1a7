//! The timeout crossing (E0326, `plan/crossing.rs`): which choices with a timeout survive a
//! message on the wire when the waiting role gives up. `Q` sends the choices' messages,
//! `P` waits, except where a choice says otherwise.

use crate::diag::Code;
use crate::lower::tests::lower_src;

/// The E0326 diagnostics of `chor`, each as the text its span starts with.
fn crossings_in(system: &str, chor: &str) -> Vec<String> {
    found(system, chor).into_iter().map(|(at, _)| at).collect()
}

/// The E0326 diagnostics of `chor`: the text each span starts with, and the message.
fn found(system: &str, chor: &str) -> Vec<(String, String)> {
    let src = format!("{system} choreography G = {chor};");
    let (p, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let body = &p.choreography.as_ref().expect("choreography").body;
    let side = crate::wf::side::check(&p, body);
    assert!(side.is_empty(), "{side:?}");
    crate::plan::crossing::check(&p, body)
        .into_iter()
        .inspect(|d| assert_eq!(d.code, Code::TimeoutCrossing))
        .map(|d| (src[d.span.start as usize..].chars().take(12).collect(), d.message))
        .collect()
}

const TWO: &str = "system S { participant P; participant Q; }";

fn crossings(chor: &str) -> Vec<String> {
    crossings_in("system S { participant P; participant Q; }", chor)
}

#[test]
fn a_branch_that_goes_on_differently_from_the_timeout_is_exposed() {
    // The reproducer: Q waits for `more`, P sends `other`.
    assert_eq!(
        crossings("P -> Q: ask. ( Q -> P: val. P -> Q: more. end + after 10 ms by P. P -> Q: other. end )"),
        vec!["Q -> P: val."]
    );
    // Q ended after its answer; P's re-request reaches no one that expects it.
    assert_eq!(
        crossings("P -> Q: ask. ( Q -> P: val. end + after 10 ms by P. P -> Q: again. end )"),
        vec!["Q -> P: val."]
    );
}

#[test]
fn a_branch_that_goes_on_as_the_timeout_branch_is_safe() {
    assert_eq!(
        crossings("P -> Q: ask. ( Q -> P: val. P -> Q: again. end + after 10 ms by P. P -> Q: again. end )"),
        Vec::<String>::new()
    );
    assert_eq!(crossings("P -> Q: ask. ( Q -> P: val. end + after 10 ms by P. end )"), Vec::<String>::new());
    // The same jump with the same arguments: Q goes on as P does. Here P, back in the loop,
    // asks again and reads the late `val` as the new answer: the waiting side's rule.
    let same = "mu t(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. ( Q -> P: val. t(n - 1) + after 10 ms by P. t(n - 1) ) + P -> Q: [n <= 0] stop. end )";
    let f = found(TWO, same);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].1.contains("reach `P` late"), "{f:?}");
    // Other arguments: Q and P would disagree on `n`: the sender's rule.
    let other = "mu t(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. ( Q -> P: val. t(n - 1) + after 10 ms by P. t(0) ) + P -> Q: [n <= 0] stop. end )";
    let f = found(TWO, other);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].1.contains("goes on here"), "{f:?}");
}

#[test]
fn a_branch_that_loops_back_to_its_choice_hears_the_timeout_there() {
    // The flood: Q keeps sending, and its next choice has P's timeout among its alternatives.
    assert_eq!(crossings("mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: stop. end )"), Vec::<String>::new());
    // Back to the loop, with its parameter changed: not the same choice for Q and P.
    assert_eq!(
        crossings("mu t(n: int = 0). ( Q -> P: val. t(n + 1) + after 10 ms by P. P -> Q: stop. end )"),
        vec!["Q -> P: val."]
    );
    // Back to the loop, unchanged.
    assert_eq!(
        crossings("mu t(n: int = 0). ( Q -> P: val. t(n) + after 10 ms by P. P -> Q: stop. end )"),
        Vec::<String>::new()
    );
}

#[test]
fn a_late_message_expected_where_the_waiting_role_next_receives_is_exposed() {
    // P asks again and waits for `val`: the late `val` is read as the answer.
    let reads = "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: ask. Q -> P: val. end )";
    assert_eq!(crossings(reads), vec!["Q -> P: val."]);
    // Not expected there: P ignores it as late.
    let ignores = "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: ask. Q -> P: done. end )";
    assert_eq!(crossings(ignores), Vec::<String>::new());
    // Expected only after P's own second timeout: still before anything Q sends after.
    let later = "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: ask. ( Q -> P: done. P -> Q: ask2. Q -> P: val. end + after 10 ms by P. P -> Q: ask2. Q -> P: val. end ) )";
    assert_eq!(crossings(later), vec!["Q -> P: val."]);
}

#[test]
fn a_late_message_is_absorbed_only_by_a_loop_that_takes_any_value() {
    let with = |branch: &str| {
        format!(
            "mu t. ( Q -> P: val(x: int). t + after 10 ms by P. P -> Q: ask. mu w. ( {branch} + after 10 ms by P. end ) )"
        )
    };
    assert_eq!(crossings(&with("Q -> P: val(y: int). w")), Vec::<String>::new());
    assert_eq!(crossings(&with("Q -> P: val(y: int {y > 0}). w")), vec!["Q -> P: val("]);
    assert_eq!(crossings(&with("Q -> P: [true] val(y: int). w")), vec!["Q -> P: val("]);
    assert_eq!(crossings(&with("Q -> P: val(y: int). end")), vec!["Q -> P: val("]);
}

#[test]
fn after_the_waiting_role_ended_the_sender_must_not_wait_for_it_for_ever() {
    // P re-requests; Q may have ended by its own timeout when the request arrives.
    let waits =
        "mu r(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. Q -> P: val. r(n - 1) + after 30 ms by Q. end )";
    assert_eq!(crossings(waits), vec!["P -> Q: [n >"]);
    let gives_up = "mu r(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. ( mu w. ( Q -> P: val. w + after 10 ms by P. r(n - 1) ) ) + after 30 ms by Q. end )";
    assert_eq!(crossings(gives_up), Vec::<String>::new());
}

#[test]
fn a_third_role_is_accepted_where_both_ends_go_on_as_the_timeout_branch() {
    let three = "system S { participant P; participant Q; participant B; }";
    // The branch goes on as the timeout branch does: B is told the same either way.
    assert_eq!(
        crossings_in(
            three,
            "P -> Q: ask. ( Q -> P: val. P -> Q: again. P -> B: log. end + after 10 ms by P. P -> Q: again. P -> B: log. end )"
        ),
        Vec::<String>::new()
    );
    // The branch jumps back to the choice: B takes part in the timeout branch only.
    assert_eq!(
        crossings_in(three, "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: stop. P -> B: log. end )"),
        Vec::<String>::new()
    );
    // The waiting role ended: Q goes on alone with B, undecided, so rejected.
    assert_eq!(
        crossings_in(three, "P -> Q: ask. ( Q -> P: val. Q -> B: log. end + after 10 ms by P. end )"),
        vec!["Q -> P: val."]
    );
}

#[test]
fn a_sender_that_can_always_send_never_waits_for_the_ended_role() {
    // After Q gave up and ended, P's next choice has an unguarded branch: P never waits
    // there for Q's message of Q's own timeout branch (Q sends nothing any more).
    let free =
        "( P -> Q: ask. ( mu w. ( P -> Q: more. w + after 10 ms by Q. Q -> P: ack. end ) ) + after 5 ms by Q. end )";
    assert_eq!(crossings(free), Vec::<String>::new());
    // With a guard on its only branch, P may have to wait for Q's `ack` there, for ever.
    let guarded = "mu r(n: int {0 <= n} = 1) decreases n. ( P -> Q: ask. ( mu w. ( P -> Q: [n > 0] more. w + after 10 ms by Q. Q -> P: ack. end ) ) + after 5 ms by Q. end )";
    assert_eq!(crossings(guarded), vec!["P -> Q: ask."]);
}

#[test]
fn a_jump_to_an_outer_loop_restarts_the_inner_loops_parameters() {
    // The choice is the first step of both loops, but `outer(a)` enters `inner` again with
    // `b = a`: after a crossing of `again`, Q is back at the choice with b = 0 while P, who
    // took the timeout, has its own b (2 after two rounds) and sends go(v = 2), which Q's
    // `v == b` refuses. Not a jump straight back to the choice.
    let reset = "mu outer(a: int {a == 0} = 0). mu inner(b: int {0 <= b} = a). \
                 ( Q -> P: again. outer(a) + after 10 ms by P. P -> Q: go(v: int {v == b}). Q -> P: ok. inner(b + 1) )";
    assert_eq!(crossings(reset), vec!["Q -> P: agai"]);
    // An inner loop without parameters restarts nothing: straight back.
    let plain = "mu outer(a: int {a == 0} = 0). mu inner. \
                 ( Q -> P: again. outer(a) + after 10 ms by P. P -> Q: go(v: int {v == a}). Q -> P: ok. inner )";
    assert_eq!(crossings(plain), Vec::<String>::new());
    // The same for the waiting side: a late `more` absorbed by a branch that jumps to the
    // outer loop restarts the inner loop's count.
    let absorb = "( P -> Q: ask. ( mu o(a: int {a == 0} = 0). mu w(k: int {0 <= k} = a). \
                  ( P -> Q: more. o(a) + after 10 ms by Q. Q -> P: ack(v: int {v == k}). w(k + 1) ) ) \
                  + after 5 ms by Q. end )";
    let f = found(TWO, absorb);
    assert!(!f.is_empty(), "{f:?}");
}

#[test]
fn a_sender_left_at_a_timeout_that_ends_it_too_is_not_waiting_for_the_ended_role() {
    // compass-calibration.chor's shape: Q's refused `ack` (res == 1) crosses P's first
    // timeout and P ends; Q then has no branch at the next choice, whose only way out is P's
    // timeout. Q's part of it is `end`: Q learns nothing from it, and once P's session is
    // over (or the bound passed) so is Q's. Not a wait for ever.
    let silence = "P -> Q: start. ( Q -> P: ack(res: int {0 <= res && res <= 1}). ( Q -> P: [res == 0] progress. end + after 10 ms by P. end ) + after 10 ms by P. end )";
    assert_eq!(crossings(silence), Vec::<String>::new());
    // Q waits for a message from P in both branches of the next choice, which never comes.
    let waits = "P -> Q: start. ( Q -> P: ack(res: int {0 <= res && res <= 1}). ( Q -> P: [res == 0] progress. P -> Q: bye. end + after 10 ms by P. P -> Q: bye. end ) + after 10 ms by P. end )";
    let f = found(TWO, waits);
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].0, "Q -> P: ack(");
    assert!(f[0].1.contains("waits for it for ever"), "{f:?}");
}
