//! Tests of the SMT stage: encodings decided, counterexamples named, time limits kept.

use super::*;
use crate::lower::tests::lower_src;

/// Lowers `const`s and a guard `[P]` of a message from A to B, returning it.
fn pred(consts: &str, p: &str) -> (Program, Expr) {
    let src = format!(
        "{consts} robot R {{ state x: real, n: int, m: int, k: int, b: bool; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{p}] go. end;"
    );
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("expected a sequence")
    };
    let crate::hir::Global::Msg(m) = &items[0] else { panic!("expected a message") };
    let g = m.guard.clone().expect("guard");
    (prog, g)
}

fn valid(consts: &str, p: &str) -> Validity {
    let (prog, e) = pred(consts, p);
    check_valid(&prog, &[], &e, &SmtConfig::default())
}

#[test]
fn linear_arithmetic_is_decided() {
    assert_eq!(valid("", "x > 1 => x > 0"), Validity::Holds);
    assert_eq!(valid("const lane = 0.65;", "x >= lane => x > 0.6"), Validity::Holds);
    assert_eq!(valid("", "n > 1 => 2 * n >= 4"), Validity::Holds);
    assert_eq!(valid("", "(if b then x else 0 - x) >= 0 || (b && x < 0) || (!b && x > 0)"), Validity::Holds);
    assert_eq!(valid("", "min(x, 1) <= 1 && abs(x) >= 0"), Validity::Holds);
    assert_eq!(valid("", "x == -0.5 => x < 0"), Validity::Holds);
}

/// Two payload fields named `v` are two values: two Z3 constants, shown as `v` and
/// `v#2`. (Before, both were the constant `v`, so `v == 1` and `v == 2` were
/// contradictory hypotheses and every goal held.)
#[test]
fn same_named_values_are_distinct_constants() {
    use crate::hir::expr::BinOp;
    use crate::hir::Sort;
    let src = "robot R { state x: real; }
             system S { participant A: R; participant B: R; }
             choreography G = A -> B : first(v: real {v == 1}). A -> B : second(v: real {v == 2}). end;";
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("expected a sequence")
    };
    let hyps: Vec<Expr> = items
        .iter()
        .filter_map(|g| match g {
            crate::hir::Global::Msg(m) => m.payload[0].refinement.clone(),
            _ => None,
        })
        .collect();
    assert_eq!(hyps.len(), 2);
    // Goal: first + second == 3 - 1, which fails (it is 3); read as one `v`, the
    // hypotheses contradict each other and it "holds".
    let lhs = |e: &Expr| match &e.kind {
        crate::hir::ExprKind::Binary(_, a, _) => (**a).clone(),
        _ => panic!("an equation"),
    };
    let bin = |op, a: Expr, b: Expr| Expr {
        kind: crate::hir::ExprKind::Binary(op, Box::new(a), Box::new(b)),
        sort: if op == BinOp::Eq { Sort::Bool } else { Sort::Real },
        loc: crate::hir::Loc::default(),
    };
    let two = Expr { kind: crate::hir::ExprKind::Int(2), sort: Sort::Int, loc: crate::hir::Loc::default() };
    let goal = bin(BinOp::Eq, bin(BinOp::Add, lhs(&hyps[0]), lhs(&hyps[1])), two);
    let Validity::Fails(model) = check_valid(&prog, &hyps, &goal, &SmtConfig::default()) else {
        panic!("v + v#2 == 2 does not follow from v == 1 and v#2 == 2: two values, not one")
    };
    let value = |n: &str| model.iter().find(|a| a.name == n).map(|a| a.value.clone());
    assert_eq!(value("v").as_deref(), Some("1"), "{model:?}");
    assert_eq!(value("v#2").as_deref(), Some("2"), "{model:?}");
}

#[test]
fn a_counterexample_names_the_variables() {
    let Validity::Fails(model) = valid("", "x > 0") else { panic!("x > 0 is not valid") };
    let x = model.iter().find(|a| a.name == "A.x").expect("A.x in the model");
    let v: f64 = x.value.parse().unwrap_or(1.0);
    assert!(v <= 0.0, "the counterexample must falsify x > 0: {model:?}");
}

#[test]
fn sqrt_and_powers_are_encoded_soundly() {
    assert_eq!(valid("", "x >= 0 => sqrt(x)^2 == x"), Validity::Holds);
    assert_eq!(valid("", "x^2 >= 0"), Validity::Holds);
    // (Guarded: a model with `x < 0`, where `sqrt(x)` is undefined, falsifies nothing.)
    assert!(matches!(valid("", "x >= 0 => sqrt(x) >= 1"), Validity::Fails(_)));
}

#[test]
fn trigonometry_is_enclosed_soundly() {
    assert_eq!(valid("", "sin(x)^2 + cos(x)^2 == 1"), Validity::Holds);
    assert_eq!(valid("", "-1 <= sin(x) <= 1 && cos(x) <= 1"), Validity::Holds);
    assert_eq!(valid("", "0 <= x <= 0.1 => sin(x) >= 0 && cos(x) >= 0.99"), Validity::Holds);
    assert_eq!(valid("const yaw = 1.5708;", "cos(yaw) < 0.0001 && sin(yaw) > 0.9999"), Validity::Holds);
    // False, with a real counterexample near 0 (the enclosure is tight there).
    assert!(matches!(valid("", "0 <= x <= 0.1 => sin(x) >= 0.05"), Validity::Fails(_)));
    // True of the real functions but beyond the polynomial enclosure: never "fails".
    assert!(matches!(
        valid("", "sin(x) <= 0.999 || cos(x) <= 0.5 || cos(x) >= 0"),
        Validity::Holds | Validity::Unknown(_)
    ));
    assert!(!matches!(valid("", "cos(x) >= -0.5 || x^2 >= 4"), Validity::Fails(_)));
}

#[test]
fn trig_of_a_constant_that_is_not_written_as_one_is_enclosed() {
    // The argument mentions `x` but simplifies to the rational 0.7853981633974483,
    // whose denominator (10^16) exceeds 2^53: before, only the Taylor bounds applied
    // (cos <= 0.70745) and this was not proved; now the numeral is read exactly.
    assert_eq!(valid("", "cos(x - x + 0.7853981633974483) <= 0.7072"), Validity::Holds);
    assert_eq!(valid("", "sin(x - x + 0.7853981633974483) >= 0.7071"), Validity::Holds);
    // The enclosure stays sound: cos(pi/4) is 0.70710678..., not below 0.70710678.
    assert!(matches!(
        valid("", "cos(x - x + 0.7853981633974483) < 0.70710678"),
        Validity::Fails(_) | Validity::Unknown(_)
    ));
}

#[test]
fn points_and_vectors_are_triples() {
    assert_eq!(valid("", "norm2(vector(x, 0, 0)) == x^2"), Validity::Holds);
    assert_eq!(valid("", "dot(point(1, 2, 3), vector(x, x, x)) == 6 * x"), Validity::Holds);
    assert_eq!(valid("", "(point(x, 1, 2) - point(0, 1, 2)).x == x"), Validity::Holds);
}

/// [T-SESS] on two bots (radius 0.1, footprint the ball) placed `gap` apart.
fn initially_apart(gap: &str) -> Decision {
    let src = format!(
            "robot Bot {{ state s: real; }}
             motion Bot.hold {{ interruptible: true; footprint(x, y, z): x^2 + y^2 + z^2 <= 0.01; }}
             system S {{ participant A: Bot {{ init: s == 0; }} participant B: Bot {{ init: s == 0; at: pose({gap}, 0, 0); }} }}
             choreography G = dt<A: hold> * dt<B: hold>;"
        );
    initial_states(&src)
}

/// Lowers `src` (which must be clean) and decides its [T-SESS] obligation: the first
/// footprints of the participants, from their initial states, are disjoint.
pub(crate) fn initial_states(src: &str) -> Decision {
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let hyps = prog.roles.iter().filter_map(|r| r.init.clone()).collect();
    let ob = Obligation {
        rule: crate::obligation::Rule::TSess,
        span: Default::default(),
        what: "initial states".into(),
        hyps,
        goal: Goal::InitiallyDisjoint { firsts: prog.first_motions() },
    };
    discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0
}

#[test]
fn initially_apart_holds_for_distant_bots_and_fails_for_touching_ones() {
    assert!(matches!(initially_apart("0.5"), Decision::Holds(_)));
    let Decision::Fails(f) = initially_apart("0.15") else { panic!("the balls overlap") };
    let o = f.overlap.expect("a point");
    assert!(o.point[0] >= 0.05 - 1e-9 && o.point[0] <= 0.1 + 1e-9, "{o:?}");
}

#[test]
fn an_input_is_its_source_state() {
    // `C.d` is an input connected to `E.d` (Sec 3.1): knowing one is knowing the other.
    let src = "robot Car { state x: real; input d: real; } robot Env { state d: real; }
             system S { participant C: Car; participant E: Env; }
             choreography G = C -> E : [d == 0] go. E -> C : [d == 0] back. end;";
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("expected a sequence")
    };
    let guard = |i: usize| match &items[i] {
        crate::hir::Global::Msg(m) => m.guard.clone().expect("guard"),
        _ => panic!("expected a message"),
    };
    let (car_d, env_d) = (guard(0), guard(1));
    assert_eq!(check_valid(&prog, std::slice::from_ref(&car_d), &env_d, &SmtConfig::default()), Validity::Holds);
    assert_eq!(check_valid(&prog, &[env_d], &car_d, &SmtConfig::default()), Validity::Holds);
}

/// The vacuity guard's witness point never calls an unsatisfiable context
/// satisfiable, and finds the common satisfiable ones without Z3.
#[test]
fn witness_boxes_are_models() {
    let cases = [
        ("const dy = 0.65;", "x == dy * 3.0 && 0 <= x <= 10 && n == 2 && m >= n + 1", true),
        ("", "x == 0.1 + 0.2 && x > 0.29", true),
        ("", "x == 0 && x == 1", false),
        ("", "x >= 1 && x <= 0", false),
        ("", "x == 0.1 + 0.2 && x == 0.3", true), // exact rationals, not doubles
        ("", "x == 0.1 && x >= 0.1000000000000000001", false), // equal as doubles only
        ("", "x == 1.0 / 3 && 3 * x == 1 && (x < 0 => n >= 1)", true),
        ("", "x > 1 && x < 1.5 && n > 0 && n < 1", false),
        ("", "x * x == 2 && x > 0", false),
    ];
    for (consts, p, expected) in cases {
        let (prog, e) = pred(consts, p);
        let facts: Vec<Expr> = e.conjuncts().into_iter().cloned().collect();
        let shown = goals::witnessed(&prog, &facts);
        assert_eq!(shown, expected, "{p}");
        if shown {
            // A witness is a model: Z3 agrees the facts are satisfiable.
            let none = Expr::bool(false, crate::hir::Loc::default());
            assert!(matches!(check_valid(&prog, &facts, &none, &SmtConfig::default()), Validity::Fails(_)), "{p}");
        }
    }
}

/// The hard limit: a query during which Z3 ignores the watchdog (the test hook hangs
/// the worker inside its armed query) is abandoned at its limit plus the grace, its
/// obligation is unknown with a note saying so, and a replacement worker decides the
/// rest. Once [`pool::MAX_ABANDONED`] workers are abandoned, the obligations not yet
/// started are unknown without running. (Before the pool, `discharge` never returned.)
#[test]
fn a_query_that_ignores_the_interrupt_is_abandoned_at_the_limit() {
    use std::time::Instant;
    let (prog, e) = pred("", "x > 1 => x > 0");
    let ob = Obligation {
        rule: crate::obligation::Rule::TOut,
        span: Default::default(),
        what: "a guard".into(),
        hyps: Vec::new(),
        goal: Goal::Valid(e),
    };
    if let Ok(mut h) = pool::HANG.lock() {
        *h = Some("hang-me".into());
    }
    let limit = Duration::from_millis(300);
    let cfg = SmtConfig { timeout: limit, jobs: 1, ..SmtConfig::default() };
    let bound = limit + pool::grace(limit);
    // Slack for a loaded machine: the pool wakes at the bound, then reports.
    let slack = Duration::from_millis(1500);
    let abandoned = |d: &Decision| match d {
        Decision::Unknown { why: w @ Why::Abandoned(after), .. } => {
            assert!(*after >= bound && *after < bound + slack, "{after:?}");
            assert!(w.to_string().contains("did not stop when asked"), "{w}");
            true
        }
        _ => false,
    };
    // One hung query among good ones: abandoned; the others still decided.
    let labels: Vec<String> = ["hang-me-1", "fine-1", "fine-2"].map(String::from).to_vec();
    let t = Instant::now();
    let r = discharge(&prog, &[ob.clone(), ob.clone(), ob.clone()], &labels, &cfg);
    let took = t.elapsed();
    assert!(took >= bound && took < bound + slack, "{took:?}");
    assert!(abandoned(&r[0].0), "{:?}", r[0].0);
    assert!(matches!(r[1].0, Decision::Holds(_)) && matches!(r[2].0, Decision::Holds(_)), "{r:?}");
    // As many hung queries as the cap: the rest is not run.
    let mut labels: Vec<String> = (0..pool::MAX_ABANDONED).map(|i| format!("hang-me-{i}")).collect();
    labels.extend(["fine-1".to_string(), "fine-2".to_string()]);
    let obs = vec![ob; labels.len()];
    let t = Instant::now();
    let r = discharge(&prog, &obs, &labels, &cfg);
    let took = t.elapsed();
    pool::release_hung();
    assert!(took < (bound + slack) * pool::MAX_ABANDONED as u32, "{took:?}");
    for d in &r[..pool::MAX_ABANDONED] {
        assert!(abandoned(&d.0), "{d:?}");
    }
    for d in &r[pool::MAX_ABANDONED..] {
        assert!(matches!(&d.0, Decision::Unknown { why: Why::NotRun(s), .. } if s.contains("abandoned")), "{d:?}");
    }
}

/// The solver is chosen from the variables the encoder declared (an `Int`: the default
/// solver; reals only: nlsat), and agrees with what the query's text declares.
#[test]
fn the_logic_is_the_encoders_decision() {
    for (p, ints) in [("x > 1 => x > 0", false), ("n > 1 => 2 * n >= 4", true), ("x > 0 || n >= 0 || b", true)] {
        let (prog, e) = pred("", p);
        let ob = Obligation {
            rule: crate::obligation::Rule::TOut,
            span: Default::default(),
            what: String::new(),
            hyps: Vec::new(),
            goal: Goal::Valid(e),
        };
        let q = goals::build(&prog, &ob, &Part::Valid).unwrap_or_else(|_| panic!("{p} encodes"));
        let logic = q.enc.logic();
        assert_eq!(logic == Logic::WithIntegers, ints, "{p}");
        let solver = solver_for(&q);
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            solver.assert(a);
        }
        assert_eq!(solver.to_string().contains(" () Int)"), ints, "{p}");
    }
}

#[test]
fn a_timeout_is_unknown() {
    // Fermat's last theorem for cubes: true, but beyond Z3's nonlinear integer
    // reasoning, and given 1 ms. Whatever Z3 says, it must not be "holds" or "fails".
    let (prog, e) = pred("", "n > 0 && m > 0 && k > 0 => n^3 + m^3 != k^3");
    let cfg = SmtConfig { timeout: Duration::from_millis(1), ..SmtConfig::default() };
    match check_valid(&prog, &[], &e, &cfg) {
        Validity::Unknown(_) => {}
        other => panic!("expected unknown, got {other:?}"),
    }
}
