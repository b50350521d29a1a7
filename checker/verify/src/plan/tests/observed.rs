//! Observed state (LANGUAGE.md, "Observed state"): each message reads a fresh snapshot of
//! what its sender observes, one per choice, constrained only by the stream's refinements.
//! Each case that must fail here holds when the same value is sent once and read at every
//! step (a stable value): that is the unsoundness the snapshots remove.

use crate::lower::tests::lower_src;
use crate::obligation::Rule;
use crate::smt::{discharge, Decision, SmtConfig};

/// The rules whose obligations fail (dead branches aside), or the lowering errors.
fn failing(src: &str) -> Vec<Rule> {
    let (p, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let body = &p.choreography.as_ref().expect("choreography").body;
    let side = crate::wf::side::check(&p, body);
    assert!(side.is_empty(), "{side:?}");
    let (obs, d) = super::check(&p, body);
    assert!(d.is_empty(), "{d:?}");
    let labels: Vec<String> = obs.iter().map(|o| o.rule.slug().to_string()).collect();
    let mut rules = Vec::new();
    for (ob, (dec, _)) in obs.iter().zip(discharge(&p, &obs, &labels, &SmtConfig::default())) {
        match dec {
            Decision::Holds(_) => {}
            Decision::Fails(_) if matches!(ob.goal, crate::obligation::Goal::Reachable { dead_branch: true, .. }) => {}
            Decision::Fails(_) => rules.push(ob.rule),
            Decision::Unknown { why, .. } => panic!("undecided: {} ({why})", ob.what),
        }
    }
    rules
}

/// `Q` streams `h` in [0, 100] to `P`.
fn observed(chor: &str) -> String {
    format!(
        "system S {{ participant P; participant Q; stream Q -> P: tick(h: int {{0 <= h && h <= 100}}); }}
         choreography G = {chor};"
    )
}

/// `Q` sends `h` once, at the start: every later step reads that one value.
fn stable(chor: &str) -> String {
    format!(
        "system S {{ participant P; participant Q; }}
         choreography G = Q -> P: tick(h: int {{0 <= h && h <= 100}}). {chor};"
    )
}

const LATER_CHOICE: &str = "( P -> Q: [h > 50] a.
      ( P -> Q: [h > 10] b. end + P -> Q: [h < 0] c. end )
    + P -> Q: [h <= 50] d. end )";

#[test]
fn a_later_choice_reads_a_fresh_value() {
    assert_eq!(failing(&stable(LATER_CHOICE)), vec![]);
    assert_eq!(failing(&observed(LATER_CHOICE)), vec![Rule::TotalChoice]);
}

#[test]
fn the_branches_of_one_choice_read_one_snapshot() {
    // Per-message readings would leave a gap between the two guards.
    assert_eq!(failing(&observed("( P -> Q: [h > 10] a. end + P -> Q: [h <= 10] b. end )")), vec![]);
}

#[test]
fn a_reading_satisfies_the_streams_refinement() {
    // Total only because every value of the stream is in [0, 100].
    assert_eq!(failing(&observed("( P -> Q: [h >= 0] a. end + P -> Q: [h > 100] b. end )")), vec![]);
    assert_eq!(failing(&observed("( P -> Q: [h >= 1] a. end + P -> Q: [h > 100] b. end )")), vec![Rule::TotalChoice]);
}

#[test]
fn a_guard_and_refinement_of_one_message_read_one_snapshot() {
    // The payload fits the guard's reading: `x == h` with `h > 10` gives `x > 10`.
    let g = "( P -> Q: [h > 10] a(x: int {x == h && x > 10}). end + P -> Q: [h <= 10] b. end )";
    assert_eq!(failing(&observed(g)), vec![]);
}

#[test]
fn progress_at_a_later_step_reads_a_fresh_value() {
    // Q answers below P's reading at `a`: sent in `a`, a value Q holds, so it exists.
    // Q answers below its own reading when it answers (Q streams `h`, so it reads its
    // own current value): a fresh value, which may be 41 or less: stuck.
    let sent = "( P -> Q: [h > 50] a(x: int {x == h}). Q -> P: b(y: int {y > 40 && y < x}). end
                + P -> Q: [h <= 50] c. end )";
    assert_eq!(failing(&observed(sent)), vec![]);
    let reread = "( P -> Q: [h > 50] a. Q -> P: b(y: int {y > 40 && y < h}). end
                  + P -> Q: [h <= 50] c. end )";
    assert_eq!(failing(&stable(reread)), vec![]);
    assert_eq!(failing(&observed(reread)), vec![Rule::Progress]);
}

#[test]
fn a_loop_reads_a_fresh_value_each_round() {
    let g = "mu t. ( P -> Q: [h > 50] a. ( P -> Q: [h > 10] b. t + P -> Q: [h <= 10] c. end )
                   + P -> Q: [h <= 50] d. end )";
    assert_eq!(failing(&observed(g)), vec![]);
    let g = "mu t. ( P -> Q: [h > 50] a. ( P -> Q: [h > 10] b. t + P -> Q: [h < 0] c. end )
                   + P -> Q: [h <= 50] d. end )";
    assert_eq!(failing(&stable(g)), vec![]);
    assert_eq!(failing(&observed(g)), vec![Rule::TotalChoice]);
}

/// A timeout branch counts as unguarded for total choice and makes the choice always
/// able to progress; Σ is unchanged by it.
#[test]
fn a_timeout_branch_is_always_enabled() {
    let partial = "( P -> Q: [h > 50] a. end + P -> Q: [h < 10] b. end )";
    assert_eq!(failing(&stable(partial)), vec![Rule::TotalChoice]);
    let waited = "( P -> Q: [h > 50] a. end + P -> Q: [h < 10] b. end + after 100 ms by Q. end )";
    assert_eq!(failing(&stable(waited)), vec![]);
    let stuck = "P -> Q: a(y: int {y > h && y < h}). end";
    assert_eq!(failing(&stable(stuck)), vec![Rule::Progress]);
    // The timeout keeps the choice from getting stuck, but a choice whose only message can
    // never come leaves nothing but the timeout: an error of its own (Reachable, E0410).
    let left = "( P -> Q: a(y: int {y > h && y < h}). end + after 100 ms by Q. end )";
    assert_eq!(failing(&stable(left)), vec![Rule::Reachable]);
    let some = "( P -> Q: a(y: int {y > h && y < 100}). end + after 100 ms by Q. end )";
    assert_eq!(failing(&stable(some)), vec![]);
    // What follows the timeout knows what held before the choice (`h <= 100`), no more.
    let after = "( P -> Q: a. end + after 100 ms by Q. Q -> P: b(y: int {y == h && y <= 100}). end )";
    assert_eq!(failing(&stable(after)), vec![]);
    let more = "( P -> Q: a. end + after 100 ms by Q. Q -> P: b(y: int {y == h && y > 100}). end )";
    assert_eq!(failing(&stable(more)), vec![Rule::Progress]);
}

/// A loop re-entered through a timeout branch decreases its measure there too.
#[test]
fn a_jump_through_a_timeout_decreases_the_measure() {
    let g = |jump: &str| {
        format!(
            "mu t(n: int {{0 <= n}} = 3) decreases n.
               ( P -> Q: [n > 0] ask. ( Q -> P: ok. end + after 10 ms by P. {jump} )
               + P -> Q: [n == 0] stop. end )"
        )
    };
    assert_eq!(failing(&stable(&g("t(n - 1)"))), vec![]);
    assert_eq!(failing(&stable(&g("t(n)"))), vec![Rule::MeasureDecrease]);
}
