//! Refined sessions: termination, progress and recursion parameters, decided
//! end to end (the global walk's obligations through the SMT stage), on global types with
//! no processes. The nested-loop cases are those nuscr got wrong (nuscr/nuscr#155: a
//! recursion variable missing from the progress check's environment; #158: several
//! variables under one label): shadowed parameter names, a jump to an outer loop from an
//! inner one, parameters read after an inner loop.

use crate::lower::tests::lower_src;
use crate::obligation::Rule;
use crate::smt::{discharge, Decision, SmtConfig};

const SYS: &str = "robot R { state x: real; } system S { participant P: R; participant Q: R; }";

/// The rules whose obligations fail, in order, and the first failure's counterexample
/// as `name = value` pairs. Panics on an undecided obligation: each case is decidable.
fn failing(chor: &str) -> (Vec<Rule>, Vec<String>) {
    let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
    assert!(d.is_empty(), "{d:?}");
    let body = &p.choreography.as_ref().expect("choreography").body;
    let side = crate::wf::side::check(&p, body);
    assert!(side.is_empty(), "{side:?}");
    let (obs, d) = super::check(&p, body);
    assert!(d.is_empty(), "{d:?}");
    let labels: Vec<String> = obs.iter().map(|o| o.rule.slug().to_string()).collect();
    let results = discharge(&p, &obs, &labels, &SmtConfig::default());
    let mut rules = Vec::new();
    let mut values = Vec::new();
    for (ob, (dec, _)) in obs.iter().zip(results) {
        match dec {
            Decision::Holds(_) => {}
            Decision::Fails(f) => {
                // A dead branch is a warning, not a failure of the protocol.
                if matches!(ob.goal, crate::obligation::Goal::Reachable { dead_branch: true, .. }) {
                    continue;
                }
                if rules.is_empty() {
                    values = f.values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                }
                rules.push(ob.rule);
            }
            Decision::Unknown { why, .. } => panic!("undecided: {} ({why})", ob.what),
        }
    }
    (rules, values)
}

const UPLOAD: &str = "P -> Q: count(c: int {1 <= c && c <= 5}).
    mu t(i: int {0 <= i && i <= c} = 0) decreases c - i.
      ( Q -> P: [i < c] req(seq: int {seq == i}). P -> Q: item(s: int {s == i}). JUMP
      + Q -> P: [ACK] ack. end )";

fn upload(jump: &str, ack: &str) -> String {
    UPLOAD.replace("JUMP", jump).replace("ACK", ack)
}

#[test]
fn the_upload_terminates_and_a_counter_never_incremented_does_not() {
    assert_eq!(failing(&upload("t(i + 1)", "i == c")).0, vec![]);
    let (rules, values) = failing(&upload("t(i)", "i == c"));
    assert_eq!(rules, vec![Rule::MeasureDecrease]);
    assert!(values.iter().any(|v| v.starts_with("i = ")), "{values:?}");
    // A measure that may go negative: no refinement bounds i by c.
    let unbounded = "P -> Q: count(c: int {1 <= c && c <= 5}).
        mu t(i: int = 0) decreases c - i.
          ( Q -> P: req. t(i + 1) + Q -> P: ack. end )";
    assert_eq!(failing(unbounded).0, vec![Rule::MeasureBound]);
}

/// The acknowledgement's guard `i > c` is never true where the loop must end (i == c):
/// the choice is not total there (stuck), with i == c in the counterexample.
#[test]
fn an_acknowledgement_that_is_never_taken_leaves_the_upload_stuck() {
    let (rules, values) = failing(&upload("t(i + 1)", "i > c"));
    assert_eq!(rules, vec![Rule::TotalChoice]);
    let get = |n: &str| values.iter().find_map(|v| v.strip_prefix(&format!("{n} = ")).map(str::to_string));
    assert_eq!(get("i"), get("c"), "stuck at i == c: {values:?}");
}

/// Progress with payloads: a refinement no value satisfies is stuck (a lone message),
/// or leaves a choice with no branch to take once the guards alone are total.
#[test]
fn a_payload_no_value_satisfies_is_stuck() {
    assert_eq!(failing("P -> Q: m(x: int {x > 0 && x < 0}). end").0, vec![Rule::Progress]);
    // Against an earlier received value: for c == 2 no r has c < r < 3.
    let (rules, values) = failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r > c && r < 3}). end");
    assert_eq!(rules, vec![Rule::Progress]);
    assert!(values.iter().any(|v| v.starts_with("c = ") && v != "c = 1"), "{values:?}");
    // Satisfiable for every c: no failure (and no quantifier: r == c + 1 defines r).
    assert_eq!(failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r == c + 1}). end").0, vec![]);
    assert_eq!(failing("P -> Q: cnt(c: int {1 <= c && c <= 5}). Q -> P: ack(r: int {r > c}). end").0, vec![]);
    // Guards total, but the branch for c >= 3 admits no payload.
    let choice = "P -> Q: cnt(c: int {1 <= c && c <= 5}).
        ( Q -> P: [c < 3] ok(r: int {r == c}). end + Q -> P: [c >= 3] big(r: int {r > c && r < 3}). end )";
    assert_eq!(failing(choice).0, vec![Rule::Progress]);
    let fine = choice.replace("r > c && r < 3", "r > c && r < 9");
    assert_eq!(failing(&fine).0, vec![]);
}

/// nuscr#155's protocol: the parameter `n` must be in the progress check's
/// environment. At n == 0 no v has v == n && v > 0: stuck.
#[test]
fn nuscr_155_the_recursion_parameter_is_in_the_progress_check() {
    let g = "P -> Q: init(x: int {x >= 0}).
        mu t(n: int {n >= 0 && n <= x} = 0).
          ( Q -> P: [n < x] step(v: int {v == n && v > 0}). t(n + 1)
          + Q -> P: [n == x] stop. end )";
    let (rules, values) = failing(g);
    assert_eq!(rules, vec![Rule::Progress]);
    assert!(values.contains(&"n = 0".to_string()), "{values:?}");
    assert_eq!(failing(&g.replace("v > 0", "v >= 0")).0, vec![]);
}

/// nuscr#158: several parameters under one label, substituted simultaneously.
#[test]
fn several_parameters_are_substituted_together() {
    let g = "mu t(a: int {a >= 0} = 0, b: int {b >= a} = 0) decreases 10 - b.
          ( P -> Q: [b < 10] more. t(ARGS) + P -> Q: [b >= 10] stop. end )";
    assert_eq!(failing(&g.replace("ARGS", "a + 1, b + 1")).0, vec![]);
    assert_eq!(failing(&g.replace("ARGS", "a + 1, b")).0, vec![Rule::MeasureDecrease, Rule::RecJump]);
    // b's refinement reads the new a (a + 1 <= b + 1), not the old one.
    assert_eq!(failing(&g.replace("ARGS", "b + 1, b + 1")).0, vec![]);
}

const NESTED: &str = "P -> Q: cnt(c: int {2 <= c && c <= 4}).
    mu t(n: int {0 <= n && n <= c} = 0) decreases c - n.
      ( P -> Q: [n < c] outer.
        (mu s(INNER: int {0 <= INNER && INNER <= 3} = 0) decreases 3 - INNER.
          ( P -> Q: [INNER < 3] inner. s(INNER + 1)
          + P -> Q: [INNER == 3] done(v: int {READ}). t(OUTER) ))
      + P -> Q: [n == c] stop. end )";

fn nested(inner: &str, read: &str, outer: &str) -> String {
    NESTED.replace("INNER", inner).replace("READ", read).replace("OUTER", outer)
}

/// A jump from the inner loop to the outer one with the outer's parameter: `n < c` of
/// the outer iteration still holds inside the inner loop, so `t(n + 1)` keeps
/// `n <= c` and the outer measure drops; `t(n)` does not make progress.
#[test]
fn a_jump_to_the_outer_loop_from_the_inner_one_uses_the_outer_parameters() {
    assert_eq!(failing(&nested("m", "v == n", "n + 1")).0, vec![]);
    assert_eq!(failing(&nested("m", "v == n", "n")).0, vec![Rule::MeasureDecrease]);
    // `n + 2` may pass c (n == c - 1): the outer refinement fails at the inner jump.
    assert_eq!(failing(&nested("m", "v == n", "n + 2")).0, vec![Rule::RecJump]);
}

/// The inner loop's parameter shadows the outer's name: inside it, `n` is the inner
/// one (3 at `done`). `t(n - 3)` is then `t(0)`, which keeps `0 <= n <= c`; read as
/// the outer `n` (names confused) it would be negative and break it. (The outer loop's
/// `decreases c - n` is dropped here: restarting at 0 does not terminate.)
#[test]
fn a_shadowed_parameter_name_means_the_inner_parameter() {
    let g = nested("n", "v == n && v == 3", "n - 3").replace(" decreases c - n", "");
    assert_eq!(failing(&g).0, vec![]);
    // `t(n + 1)` with the inner n == 3 gives the outer 4 > c for c < 4.
    let g = nested("n", "v == n", "n + 1").replace(" decreases c - n", "");
    let (rules, values) = failing(&g);
    assert_eq!(rules, vec![Rule::RecJump]);
    assert!(values.iter().any(|v| v.starts_with("c = ") && v != "c = 4"), "{values:?}");
}

/// A parameter of the outer loop read after the inner loop's iterations (in its exit
/// message): what held of it before the inner loop still holds.
#[test]
fn an_outer_parameter_read_after_the_inner_loop_keeps_its_facts() {
    assert_eq!(failing(&nested("m", "v == n && v < c", "n + 1")).0, vec![]);
    let (rules, _) = failing(&nested("m", "v == n && v >= c", "n + 1"));
    assert_eq!(rules, vec![Rule::Progress]);
}
