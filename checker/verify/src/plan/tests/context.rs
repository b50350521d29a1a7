//! The hypotheses of the obligations: Σ threaded through the type.

use crate::hir::{print, Program};
use crate::lower::tests::lower_src;
use crate::obligation::{Goal, Obligation, Rule};

/// Three robots on a line; `go` moves to a target, `hold` stays (`x == old(x)`).
const SYS: &str = "
    robot R { state x: real; invariant: 0 <= x <= 10; }
    motion R.go(to: real) { interruptible: false; post: x == to; }
    motion R.hold { interruptible: true; post: x == old(x); }
    system S {
      participant P: R { init: x == 0; }
      participant Q: R { init: x == 5; }
      participant V: R { init: x == 9; }
    }
";

fn obligations(chor: &str) -> (Program, Vec<Obligation>) {
    let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
    assert!(d.is_empty(), "{d:?}");
    let body = p.choreography.as_ref().map(|c| c.body.clone()).expect("choreography");
    let (o, d) = super::check(&p, &body);
    assert!(d.is_empty(), "{d:?}");
    (p, o)
}

fn show(prog: &Program, hyps: &[crate::hir::Expr]) -> Vec<String> {
    hyps.iter().map(|h| print::expr(prog, None, h)).collect()
}

/// The hypotheses of each obligation of `rule`, printed and sorted.
fn hyps(prog: &Program, obs: &[Obligation], rule: Rule) -> Vec<Vec<String>> {
    obs.iter().filter(|o| o.rule == rule).map(|o| sorted(show(prog, &o.hyps))).collect()
}

fn sorted<S: ToString>(v: impl IntoIterator<Item = S>) -> Vec<String> {
    let mut v: Vec<String> = v.into_iter().map(|s| s.to_string()).collect();
    v.sort();
    v
}

const INIT: [&str; 9] =
    ["P.x == 0", "0 <= P.x", "P.x <= 10", "Q.x == 5", "0 <= Q.x", "Q.x <= 10", "V.x == 9", "0 <= V.x", "V.x <= 10"];

#[test]
fn agcomp_hypotheses_follow_messages_and_motions() {
    let (p, o) = obligations(
        "P -> Q : a(n: real {n > x && n <= 10}). dt<P: go(n), Q: hold, V: hold>.
         Q -> P : b. dt<P: hold, Q: go(1), V: hold>. end",
    );
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h.len(), 2);
    // [T-SESS]'s initial state and the refinement of `a`.
    assert_eq!(h[0], sorted(INIT.iter().chain(&["P.x < n", "n <= 10"])));
    // After the motion P is at n (and `P.x < n` before it says `0 < n`); Q and V held.
    let after = ["P.x == n", "0 <= P.x", "P.x <= 10", "0 < n", "n <= 10"];
    assert_eq!(h[1], sorted(INIT[3..].iter().chain(&after)));
}

#[test]
fn choices_assume_their_guards() {
    let (p, o) = obligations(
        "P -> Q : [x >= 1] l. dt<P: go(2), Q: hold, V: hold>. end
       + P -> Q : [x < 1] r. dt<P: go(3), Q: hold, V: hold>. end",
    );
    assert_eq!(hyps(&p, &o, Rule::TotalChoice), vec![sorted(INIT)]);
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h, vec![sorted(INIT.iter().chain(&["1 <= P.x"])), sorted(INIT.iter().chain(&["P.x < 1"]))]);
}

#[test]
fn loops_get_a_syntactic_invariant_and_one_obligation_per_motion() {
    // P moves one further each round: `P.x == 0` is not invariant; Q and V hold.
    let (p, o) = obligations("mu t. P -> Q : a. dt<P: go(x + 1), Q: hold, V: hold>. Q -> P : b. t");
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h, vec![sorted(&INIT[1..])]);
    // A jump from an inner loop to the outer one weakens the outer invariant too.
    let (p, o) = obligations(
        "mu t. P -> Q : a. dt<P: hold, Q: hold, V: hold>.
           mu s. ( Q -> P : b. dt<P: hold, Q: hold, V: hold>. s
                 + Q -> P : c. dt<P: hold, Q: go(3), V: hold>. t )",
    );
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h.len(), 3, "one obligation per joint motion: {h:?}");
    // Q is at 5 or 3: the interval join keeps `3 <= Q.x <= 5` of `Q.x == 5`.
    let without_q = sorted(INIT.iter().filter(|f| **f != "Q.x == 5").chain(&["3 <= Q.x", "Q.x <= 5"]));
    assert_eq!(h[0], without_q);
    assert_eq!(h[1], without_q, "the inner loop's invariant");
    assert_eq!(h[2], without_q);
}

#[test]
fn recursion_parameters_are_new_values_at_each_round() {
    let (p, o) = obligations(
        "mu t(k: int = 0). P -> Q : a(n: int {n == k && k >= 0}). dt<P: go(n), Q: hold, V: hold>. Q -> P : b. t(k + 1)",
    );
    let h = hyps(&p, &o, Rule::AgComp);
    // `n == k` holds at the motion; nothing about `k` survives the jump back (the
    // parameter is unrefined: its `0 <= k` is not checked, so not assumed either).
    assert_eq!(h, vec![sorted(INIT[1..].iter().chain(&["n == k", "0 <= k"]))]);
}

#[test]
fn separation_lists_the_runs_of_each_side_with_their_contexts() {
    let (p, o) = obligations(
        "mu t. P -> Q : a. ((dt<P: go(2), Q: hold>. Q -> P : b. (dt<P: hold> * dt<Q: hold>)) * dt<V: hold>). t",
    );
    let seps: Vec<&Obligation> = o.iter().filter(|o| o.rule == Rule::FullSeparation).collect();
    assert_eq!(seps.len(), 2);
    assert_eq!(o.iter().filter(|o| o.rule == Rule::AgComp).count(), 4);
    let runs = |ob: &Obligation| -> Vec<Vec<(String, Vec<String>)>> {
        let Goal::Separated { sides } = &ob.goal else { panic!("separation") };
        sides
            .iter()
            .map(|s| {
                s.runs
                    .iter()
                    .map(|r| {
                        let who = format!("{}: {}", p.role_name(r.role), print::prim_app(&p, &r.app));
                        (who, sorted(show(&p, &r.hyps)))
                    })
                    .collect()
            })
            .collect()
    };
    // P is at 2 after a round, so `P.x == 0` is not part of the loop's invariant;
    // the interval join of 0 and 2 keeps `P.x <= 2`.
    let pq = sorted(["0 <= P.x", "P.x <= 10", "P.x <= 2", "Q.x == 5", "0 <= Q.x", "Q.x <= 10"]);
    let outer = runs(seps[0]);
    // The P/Q side sees nothing of V, and its runs include the nested `*`'s.
    assert_eq!(
        outer[0],
        vec![
            ("P: go(2)".to_string(), pq.clone()),
            ("Q: hold".to_string(), pq),
            ("P: hold".to_string(), sorted(["P.x == 2", "0 <= P.x", "P.x <= 10"])),
            ("Q: hold".to_string(), sorted(["Q.x == 5", "0 <= Q.x", "Q.x <= 10"])),
        ]
    );
    assert_eq!(outer[1], vec![("V: hold".to_string(), sorted(&INIT[6..]))]);
    let inner = runs(seps[1]);
    assert_eq!(inner.len(), 2);
    assert_eq!(inner[0], vec![outer[0][2].clone()]);
    assert_eq!(inner[1], vec![outer[0][3].clone()]);
    // The obligation's own hypotheses: Σ at the `*`.
    assert_eq!(sorted(show(&p, &seps[0].hyps)), sorted(INIT.iter().filter(|f| **f != "P.x == 0").chain(&["P.x <= 2"])));
}

/// Robots without an invariant, so that only the loop invariant bounds them.
const FREE: &str = "
    robot F { state x: real; }
    motion F.go(to: real) { interruptible: false; post: x == to; }
    motion F.hold { interruptible: true; post: x == old(x); }
    system S { participant P: F { init: x >= 0; } participant Q: F { init: x == 0; } }
";

fn free_obligations(chor: &str) -> (Program, Vec<Obligation>) {
    let (p, d) = lower_src(&format!("{FREE} choreography G = {chor};"));
    assert!(d.is_empty(), "{d:?}");
    let body = p.choreography.as_ref().map(|c| c.body.clone()).expect("choreography");
    let (o, d) = super::check(&p, &body);
    assert!(d.is_empty(), "{d:?}");
    (p, o)
}

#[test]
fn a_weaker_bound_every_jump_keeps_survives() {
    // `P.x >= 0` at entry; one branch leaves P at 1, the other at 2. Neither jump
    // holds `0 <= P.x` literally, but both imply it: the invariant keeps it (it
    // was dropped before the interval join, a false alarm for any motion needing it).
    let (p, o) = free_obligations(
        "mu t. P -> Q : a. dt<P: hold, Q: hold>.
           ( P -> Q : l. dt<P: go(1), Q: hold>. t
           + P -> Q : r. dt<P: go(2), Q: hold>. t )",
    );
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h.len(), 3);
    assert_eq!(h[0], sorted(["0 <= P.x", "Q.x == 0"]));
    // The choice's join weakens too: after it, P is between 1 and 2.
    let (p, o) = free_obligations(
        "mu t. P -> Q : a. dt<P: hold, Q: hold>.
           ( P -> Q : l. dt<P: go(1), Q: hold>. Q -> P : m. dt<P: hold, Q: hold>. t
           + P -> Q : r. dt<P: go(2), Q: hold>. Q -> P : m. dt<P: hold, Q: hold>. t )",
    );
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h[0], sorted(["0 <= P.x", "Q.x == 0"]));
}

#[test]
fn bounds_that_keep_weakening_are_widened_away() {
    // Q steps down by one each round: -1, -2, ... The join would weaken the lower
    // bound forever; after WEAKEN_WALKS walks only literal facts are kept.
    let (p, o) = free_obligations("mu t. P -> Q : a. dt<P: hold, Q: go(x - 1)>. Q -> P : b. t");
    let h = hyps(&p, &o, Rule::AgComp);
    assert_eq!(h, vec![sorted(["0 <= P.x"])]);
    let (_, o) = free_obligations("mu t. P -> Q : a. dt<P: hold, Q: go(x - 1)>. Q -> P : b. t");
    let motions = o.iter().filter(|ob| ob.rule == Rule::AgComp).count();
    assert_eq!(motions, 1, "one obligation per motion, from the last walk only");
}

#[test]
fn recursion_parameters_are_checked_at_entry_and_jumps_and_assumed() {
    let (p, o) = free_obligations(
        "mu t(n: int {n >= 0} = 2). ( P -> Q : [n > 0] more. dt<P: hold, Q: hold>. t(n - 1)
                                    + P -> Q : [n == 0] stop. dt<P: hold, Q: hold>. end )",
    );
    let goals = |rule: Rule| -> Vec<String> {
        o.iter()
            .filter(|ob| ob.rule == rule)
            .map(|ob| match &ob.goal {
                Goal::Valid(e) => print::expr(&p, None, e),
                _ => panic!("a predicate"),
            })
            .collect()
    };
    assert_eq!(goals(Rule::RecInit), vec!["2 >= 0"]);
    assert_eq!(goals(Rule::RecJump), vec!["n - 1 >= 0"]);
    // The body assumes the refinement: total choice and the jump see `0 <= n`.
    assert!(hyps(&p, &o, Rule::TotalChoice)[0].contains(&"0 <= n".to_string()));
    assert_eq!(hyps(&p, &o, Rule::RecJump), vec![sorted(["0 <= P.x", "Q.x == 0", "0 <= n", "0 < n"])]);
}
