//! Trigonometry of parameters bound to constants, through the whole pipeline.

use crate::diag::{Code, Severity};
use crate::driver::{Config, Verdict};
use crate::fsload::check_source;

const FILE: &str = "choreographies/diagonal.chor";

fn check(name: &str, text: &str) -> (Verdict, Vec<Code>) {
    let mut db = crate::source::SourceDb::new();
    let name = crate::testing::repo(name).display().to_string();
    let r = check_source(&mut db, &name, text, &Config::default());
    let codes = r.diagnostics.iter().filter(|d| d.severity == Severity::Error).map(|d| d.code).collect();
    (r.verdict, codes)
}

fn diagonal(edit: &dyn Fn(String) -> String) -> (Verdict, Vec<Code>) {
    let text = std::fs::read_to_string(crate::testing::repo(FILE)).expect("the example exists");
    check(FILE, &edit(text))
}

/// `move_cart(0, 0, pi / 4, 1, 5)` reads cos(t), sin(t) of its parameter t = pi / 4:
/// enclosed to a few ulps, so the example verifies (it was unknown: the footprint and
/// can-end questions of [AGCOMP] saw Taylor bounds of a fresh parameter).
#[test]
fn a_direction_given_as_pi_over_4_is_enclosed_tightly() {
    assert_eq!(diagonal(&|t| t), (Verdict::Verified, vec![]));
}

/// A claim false by 2.4e-17 (cos(pi/4) = 0.70710678118654752...), less than the
/// enclosure's width, is never verified.
#[test]
fn a_claim_wrong_by_less_than_the_enclosure_is_not_verified() {
    let edit = |t: String| t.replace("0.70710678118 <= A.x <= 0.70710678119", "A.x <= 0.7071067811865475");
    let (verdict, _) = diagonal(&edit);
    assert_ne!(verdict, Verdict::Verified);
}

/// A quarter turn through a parameter is exact: `edge(pi / 2)`'s footprint ends at
/// x <= cos(pi / 2) = 0 exactly, touching q's strip x > 0 nowhere. An enclosure of
/// cos(pi / 2), however tight, would let them share a point; with the argument
/// 1.5707963267948966 (a rational just below pi / 2, whose cosine is about 6e-17)
/// they do share one.
#[test]
fn a_quarter_turn_through_a_parameter_is_exact() {
    let src = |arg: &str| {
        format!(
            // A bodiless kind: the footprints are segments, not a body's space (E0512).
            "robot Seg {{ state s: real; invariant: 0 <= s <= 1; }}
                 motion Seg.edge(t: real) {{ interruptible: true; guarantee: s == old(s); post: s == old(s);
                   footprint(px, py, pz): -0.1 <= px <= cos(t) && py == 0 && pz == 0; duration: [0, inf]; }}
                 motion Seg.strip {{ interruptible: true; guarantee: s == old(s); post: s == old(s);
                   footprint(px, py, pz): 0 < px <= 0.1 && py == 0 && pz == 0; duration: [0, inf]; }}
                 system S {{ participant p: Seg {{ init: s == 0; }} participant q: Seg {{ init: s == 0; }} }}
                 choreography S = dt<p: edge({arg}), q: strip>. end;
                 process p = dt<edge({arg})>.end;
                 process q = dt<strip>.end;"
        )
    };
    let name = "choreographies/quarter-turn-test.chor";
    assert_eq!(check(name, &src("pi / 2")), (Verdict::Verified, vec![]));
    // (They also share a point at time 0: [T-SESS] reports it too.)
    // Not a quarter turn: the footprints meet (cos(t) is 1.9e-17 > 0), but Z3's model
    // may be a point of a neighbouring cosine the enclosure admits, which is no
    // counterexample (checker/verify/src/smt/replay.rs): rejected or unknown, never verified.
    let (verdict, codes) = check(name, &src("1.5707963267948966"));
    assert_ne!(verdict, Verdict::Verified);
    assert!(verdict == Verdict::Unknown || codes.contains(&Code::FootprintsOverlap), "{codes:?}");
}
