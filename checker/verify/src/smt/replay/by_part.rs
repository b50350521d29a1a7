//! Every kind of part, replayed on the exact model Z3 gives for a file of the rejected
//! corpus that fails it: the model falsifies the goal, and corrupting it is noticed.
use super::*;
use crate::driver::Config;
use crate::smt::{discharge, goals, Decision};

/// The failed parts of a file's obligations (`text`, or the file at `path` when
/// `None`), with their obligations.
fn failures(path: &str, text: Option<&str>) -> (Program, Vec<(Obligation, Part)>) {
    let path = &crate::testing::repo(path).display().to_string();
    let mut db = crate::source::SourceDb::new();
    let report = match text {
        Some(t) => crate::fsload::check_source(&mut db, path, t, &Config::patient()),
        None => crate::fsload::check_file(&mut db, std::path::Path::new(path), &Config::patient()).expect("readable"),
    };
    let Some(planned) = report.planned else { return (Program::default(), Vec::new()) };
    let labels = vec![String::new(); planned.obligations.len()];
    let results = discharge(&planned.program, &planned.obligations, &labels, &Config::patient().smt);
    let failed = planned
        .obligations
        .iter()
        .zip(results)
        .filter_map(|(ob, (d, _))| match d {
            Decision::Fails(f) => Some((ob.clone(), f.which?)),
            _ => None,
        })
        .collect();
    (planned.program, failed)
}

/// Z3's exact model of `part`'s query.
fn model(prog: &Program, ob: &Obligation, part: &Part) -> Valuation {
    let q = goals::build(prog, ob, part).expect("a query");
    let solver = super::super::solver_for(&q);
    for a in q.assertions.iter().chain(q.enc.side_conditions()) {
        solver.assert(a);
    }
    assert_eq!(solver.check(), z3::SatResult::Sat, "{part:?}");
    valuation(&q.enc, &solver.get_model().expect("a model"))
}

/// The part of `path` (or of `text` named `path`) that fails and `is` picks: Z3's model
/// falsifies it exactly, and some change of one of its values is noticed (the
/// replay is not vacuous for this kind of part).
fn falsified_and_corruption_noticed(path: &str, text: Option<&str>, is: &dyn Fn(&Part) -> bool) {
    let (prog, failed) = failures(path, text);
    let (ob, part) = failed.iter().find(|(_, p)| is(p)).unwrap_or_else(|| {
        panic!("{path}: no such failed part among {:?}", failed.iter().map(|f| &f.1).collect::<Vec<_>>())
    });
    let m = model(&prog, ob, part);
    assert_eq!(replay(&prog, ob, part, &m), Replay::Falsifies, "{path}: {part:?} under {m:?}");
    let others = ["0", "1", "-1", "0.5", "3", "1000", "-1000"];
    let noticed = m.keys().any(|k| {
        others.iter().any(|o| {
            let mut bad = m.clone();
            bad.insert(k.clone(), Value::rat(exact::parse_decimal(o).expect("a number")));
            replay(&prog, ob, part, &bad) != Replay::Falsifies
        })
    });
    assert!(noticed, "{path}: no change of {part:?}'s model is noticed");
}

const CORPUS: &[(&str, &str)] = &[
    ("Conjunct", "choreographies/rejected/E0709-sorting-target-too-close.chor"),
    ("Valid", "choreographies/rejected/E0415-countdown-below-zero.chor"),
    ("Pre", "choreographies/rejected/E0402-open-when-already-open.chor"),
    ("Assume", "choreographies/rejected/E0403-gusty-environment.chor"),
    ("Disjoint", "choreographies/rejected/E0404-target-too-close.chor"),
    ("Within", "choreographies/rejected/E0405-joint-end-outside-partner.chor"),
    ("CommonEnd", "choreographies/rejected/E0401-two-non-interruptible.chor"),
    ("Apart", "choreographies/rejected/E0406-two-carts-one-lane.chor"),
    ("Refine(Guarantee)", "choreographies/rejected/E0407-waves-instead-of-holding.chor"),
    ("Refine(Pre)", "choreographies/rejected/E0407-process-moves-to-shadowing-value.chor"),
    ("Refine(Footprint)", "choreographies/rejected/E0407-turned-footprint-refines.chor"),
    ("ClearOf", "choreographies/rejected/E0510-cart-drives-into-pillar.chor"),
    ("Contains", "choreographies/rejected/E0512-footprint-shorter-than-the-body.chor"),
];

fn kind(p: &Part) -> String {
    match p {
        Part::Refine(i) => format!("Refine({i:?})"),
        other => format!("{other:?}").split(['(', ' ', '{']).next().unwrap_or_default().to_string(),
    }
}

#[test]
fn every_part_kind_of_the_corpus_replays_exactly() {
    for (k, path) in CORPUS {
        falsified_and_corruption_noticed(path, None, &|p| kind(p) == *k);
    }
}

/// A robot with a ball footprint, two primitives of given durations, for the kinds
/// of part the rejected corpus does not fail.
const BASE: &str = "
        robot Bot { state s: real; invariant: 0 <= s <= 1; geometry: sphere(0.1); }
        motion Bot.hold { interruptible: true; guarantee: s == old(s); post: s == old(s);
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [0, inf]; }
        motion Bot.early { interruptible: true; guarantee: s == old(s); post: s == old(s);
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [0, 1]; }
        motion Bot.late { interruptible: true; guarantee: s == old(s); post: s == old(s);
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [2, 3]; }
        motion Bot.stroke { interruptible: false; guarantee: 0 <= s <= 1; post: s == 1;
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [0.5, 1]; }
        motion Bot.long_stroke { interruptible: false; guarantee: 0 <= s <= 1; post: s == 1;
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [0.5, 1 + s]; }
        motion Bot.loose { interruptible: true; guarantee: s == old(s); post: 0 <= s <= 1;
          footprint(px, py, pz): px^2 + py^2 + pz^2 <= 0.01; duration: [0, inf]; }";

fn inline(name: &str, rest: &str, is: &dyn Fn(&Part) -> bool) {
    let text = format!("{BASE}\n{rest}");
    falsified_and_corruption_noticed(&format!("choreographies/rejected/{name}.chor"), Some(&text), is);
}

#[test]
fn durations_that_share_no_time_replay() {
    inline(
            "meet",
            "system S { participant a: Bot { init: s == 0; at: pose(0, 0, 0); } participant b: Bot { init: s == 0; at: pose(1, 0, 0); } }
             choreography G = a -> b: go. dt<a: early, b: late>. a -> b: stop. end;
             process a = b!go.dt<early>.b!stop.end; process b = a?go.dt<late>.a?stop.end;",
            &|p| *p == Part::Meet,
        );
}

#[test]
fn regions_of_a_written_partition_replay() {
    let sys = "system S { participant a: Bot { init: s == 0; at: pose(0, 0, 0); } participant b: Bot { init: s == 0; at: pose(2, 0, 0); } }";
    let procs = "process a = dt<hold>.end; process b = dt<hold>.end;";
    inline(
        "regions-apart",
        &format!("{sys} choreography G = dt<a: hold> * dt<b: hold> partition(x, y, z) {{ x <= 1.5; x >= 1 }}; {procs}"),
        &|p| matches!(p, Part::RegionsApart(..)),
    );
    inline(
        "in-region",
        &format!(
            "{sys} choreography G = dt<a: hold> * dt<b: hold> partition(x, y, z) {{ x <= 0.05; x >= 1 }}; {procs}"
        ),
        &|p| matches!(p, Part::InRegion { .. }),
    );
}

#[test]
fn participants_that_start_in_one_place_replay() {
    inline(
            "initially",
            "system S { participant a: Bot { init: s == 0; at: pose(0, 0, 0); } participant b: Bot { init: s == 0; at: pose(0.05, 0, 0); } }
             choreography G = dt<a: hold> * dt<b: hold>; process a = dt<hold>.end; process b = dt<hold>.end;",
            &|p| matches!(p, Part::InitiallyApart { .. }),
        );
}

#[test]
fn refinement_items_without_a_corpus_file_replay() {
    let sys = "system S { participant a: Bot { init: s == 0; at: pose(0, 0, 0); } }";
    inline("refine-post", &format!("{sys} choreography G = dt<a: hold>. end; process a = dt<loose>.end;"), &|p| {
        *p == Part::Refine(super::super::goals::RefineItem::Post)
    });
    inline(
        "refine-duration",
        &format!("{sys} choreography G = dt<a: stroke>. end; process a = dt<long_stroke>.end;"),
        &|p| *p == Part::Refine(super::super::goals::RefineItem::Duration),
    );
    falsified_and_corruption_noticed(
        "choreographies/rejected/refine-assume.chor",
        Some(
            "import \"common.mochi\";
                 motion DCart.careful { interruptible: true; assume: -0.01 <= d <= 0.01;
                   guarantee: old(x) <= x <= old(x) + 2 * v_cruise * clock && 0 <= v <= 2 * v_cruise;
                   post: x >= old(x);
                   footprint(px, py, pz): old(x) - cart_l / 2 <= px <= old(x) + 2 * v_cruise * clock + cart_l / 2
                     && -cart_w / 2 <= py <= cart_w / 2 && 0 <= pz <= cart_h;
                   duration: [0, inf]; }
                 system D { participant c: DCart { init: x == 0 && v == 0; at: pose(0, 0, 0); } participant e: Env; }
                 choreography D = c -> e: go. dt<c: drive, e: disturb>. end;
                 process c = e!go.dt<careful>.end; process e = c?go.dt<disturb>.end;",
        ),
        &|p| *p == Part::Refine(super::super::goals::RefineItem::Assume),
    );
}

/// The identical footprint of another primitive, at a pose turned by `1.5708` (not an
/// exact quarter turn): both footprints read one local point, so it refines.
#[test]
fn a_turned_footprint_refines_its_copy() {
    let text =
        std::fs::read_to_string(crate::testing::repo("choreographies/rejected/E0407-turned-footprint-refines.chor"))
            .expect("readable");
    let same = text.replace("-0.5 <= px <= 0.51", "-0.5 <= px <= 0.5");
    assert_ne!(text, same);
    let (_, failed) = failures("choreographies/rejected/same.chor", Some(&same));
    assert!(failed.is_empty(), "{failed:?}");
}

/// A fake model of the turned footprint's refinement: a point on the boundary of the
/// abstract footprint, which the rotation's enclosure cannot place inside or outside
/// it, is not a counterexample (undecided), and one inside both is refuted.
#[test]
fn a_point_the_enclosure_cannot_place_is_undecided() {
    let path = "choreographies/rejected/E0407-turned-footprint-refines.chor";
    let (prog, failed) = failures(path, None);
    let (ob, part) = failed.iter().find(|(_, p)| kind(p) == "Refine(Footprint)").expect("the footprint item");
    let mut m = model(&prog, ob, part);
    let num = |v: &str| Value::rat(exact::parse_decimal(v).expect("a number"));
    // Local (0.5, -0.125, 0), within 1e-55, in the world (cos and sin of 1.5708 to 70
    // digits); the enclosure of the rotation (1e-40) is wider than that.
    m.insert("point.x".into(), num("2.125"));
    m.insert("point.y".into(), num("0.9500004591540110335939995402907007796268995926470878425714"));
    m.insert("point.z".into(), num("0"));
    let r = replay(&prog, ob, part, &m);
    assert!(matches!(&r, Replay::Undecided(why) if why.contains("not decided exactly")), "{r:?}");
    // Local (0, 0, 0): in both footprints.
    m.insert("point.x".into(), num("2"));
    m.insert("point.y".into(), num("0.45"));
    let r = replay(&prog, ob, part, &m);
    assert!(matches!(&r, Replay::Refuted(why) if why.contains("outside the footprint of `reach`")), "{r:?}");
}

/// Footprints that meet only at irrational points (a flat segment turned by an
/// angle 1.9e-17 short of π/2, far from its origin): no exact counterexample exists
/// in rationals, Z3's model (a neighbouring rotation's) does not falsify the goal, and
/// the verdict is unknown with why: never verified (the rounding it guards against
/// verified it), never rejected on a point that is not in both footprints.
#[test]
fn footprints_that_meet_only_at_irrational_points_are_unknown() {
    let mut db = crate::source::SourceDb::new();
    let path = &crate::testing::repo("tests/data/rotation-far-from-origin.chor");
    let report = crate::fsload::check_file(&mut db, path, &Config::patient()).expect("readable");
    assert_eq!(report.verdict, crate::driver::Verdict::Unknown, "{:?}", report.diagnostics);
    assert!(
        report
            .diagnostics
            .iter()
            .any(|d| d.notes.iter().any(|n| n.contains("does not falsify the goal in exact arithmetic"))),
        "{:?}",
        report.diagnostics
    );
}
