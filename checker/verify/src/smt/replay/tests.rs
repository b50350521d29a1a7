//! Tests of the replay of counterexamples.

use super::*;
use crate::lower::tests::lower_src;
use crate::obligation::Rule;

/// An obligation `hyp ⇒ goal` over `A.x` (guards of two messages).
fn obligation(hyp: &str, goal: &str) -> (Program, Obligation) {
    let src = format!(
        "robot R {{ state x: real; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{hyp}] a. A -> B : [{goal}] b. end;"
    );
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("a sequence")
    };
    let guard = |i: usize| match &items[i] {
        crate::hir::Global::Msg(m) => m.guard.clone().expect("guard"),
        _ => panic!("a message"),
    };
    let ob = Obligation {
        rule: Rule::TOut,
        span: Default::default(),
        what: "test".into(),
        hyps: vec![guard(0)],
        goal: Goal::Valid(guard(1)),
    };
    (prog, ob)
}

fn model(x: &str) -> Valuation {
    let v = exact::parse_decimal(x).expect("number");
    [("A.x".to_string(), Value::rat(v))].into_iter().collect()
}

#[test]
fn a_real_counterexample_replays() {
    let (prog, ob) = obligation("x >= 0", "x > 0");
    assert_eq!(refutes(&prog, &ob, &Part::Valid, &model("0")), None);
}

#[test]
fn a_fake_model_that_satisfies_the_goal_is_refuted() {
    let (prog, ob) = obligation("x >= 0", "x > 0");
    let why = refutes(&prog, &ob, &Part::Valid, &model("0.5")).expect("the goal holds at 0.5");
    assert!(why.contains("goal"), "{why}");
}

#[test]
fn a_fake_model_that_breaks_a_hypothesis_is_refuted() {
    let (prog, ob) = obligation("x >= 0", "x > 0");
    let why = refutes(&prog, &ob, &Part::Valid, &model("-1")).expect("the hypothesis fails at -1");
    assert!(why.contains("hypothesis"), "{why}");
}

/// Two bots (footprint: a ball of radius 0.1) 0.15 apart in one joint motion; the
/// footprints part with a fake model whose point is `(px, 0, 0)`.
fn footprints_part(px: &str) -> Option<String> {
    let src = "robot Bot { state s: real; }
             motion Bot.hold { interruptible: true; footprint(x, y, z): x^2 + y^2 + z^2 <= 0.01; }
             system S { participant A: Bot { init: s == 0; } participant B: Bot { init: s == 0; at: pose(0.15, 0, 0, 0, 0, 0.3); } }
             choreography G = dt<A: hold, B: hold>;";
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Motion(m)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("a motion")
    };
    let ob = Obligation {
        rule: Rule::AgComp,
        span: Default::default(),
        what: "test".into(),
        hyps: vec![],
        goal: Goal::Compatible { parts: m.parts.clone() },
    };
    let num = |v: &str| Value::rat(exact::parse_decimal(v).expect("number"));
    let model: Valuation = [
        ("point.x", num(px)),
        ("point.y", num("0")),
        ("point.z", num("0")),
        ("A.s(t)", num("0")),
        ("B.s(t)", num("0")),
        ("time", num("1")),
    ]
    .into_iter()
    .map(|(n, v)| (n.to_string(), v))
    .collect();
    refutes(&prog, &ob, &Part::Disjoint(0, 1), &model)
}

#[test]
fn a_common_point_replays_and_a_fake_one_does_not() {
    // Inside both balls (B's frame is rotated by a yaw of 0.3: enclosed, decided).
    assert_eq!(footprints_part("0.07"), None);
    // Outside A's ball: not a collision.
    let why = footprints_part("0.2").expect("0.2 is outside A's footprint");
    assert!(why.contains("does not show that the point is in the footprint of `hold`"), "{why}");
}

#[test]
fn an_undecided_evaluation_does_not_refute() {
    // sqrt(2)^2 == 2 cannot be decided with enclosures; a missing variable neither.
    let (prog, ob) = obligation("x >= 0", "sqrt(x)^2 != 2");
    assert_eq!(refutes(&prog, &ob, &Part::Valid, &model("2")), None);
    assert_eq!(refutes(&prog, &ob, &Part::Valid, &Valuation::new()), None);
}
