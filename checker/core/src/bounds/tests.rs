//! Tests of the interval bounds.

use super::*;
use crate::lower::tests::lower_src;

fn guard(p: &str) -> (Program, Expr) {
    let src = format!(
        "const r = 0.5; robot R {{ state x: real, y: real, z: real; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{p}] go. end;"
    );
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("expected a sequence")
    };
    let crate::hir::Global::Msg(m) = &items[0] else { panic!("expected a message") };
    (prog, m.guard.clone().expect("guard"))
}

fn slot(v: &Var) -> Option<usize> {
    match v {
        Var::Role(_, crate::hir::Slot::State(i)) => Some(*i),
        _ => None,
    }
}

#[test]
fn pi_is_enclosed_never_exact() {
    let (prog, e) = guard("x == pi");
    let ExprKind::Binary(_, _, p) = &e.kind else { panic!("a comparison") };
    let i = eval(&prog, p, &closed).expect("bounded");
    // π = 3.14159265358979323846...: strictly inside, one ulp wide.
    let pi = BigRational::new(BigInt::from(314159265358979323846u128), BigInt::from(10u128.pow(20)));
    assert!(BigRational::from_float(i.lo).unwrap() < pi && pi < BigRational::from_float(i.hi).unwrap(), "{i:?}");
    assert_eq!(i.hi, i.lo.next_up());
    assert_eq!(exact(&prog, p), None);
}

#[test]
fn quarter_turns_are_recognised_exactly() {
    let angle = |src: &str| {
        let (p, e) = guard(&format!("x == {src}"));
        let ExprKind::Binary(_, _, a) = e.kind else { panic!("a comparison") };
        (quarter_turn(&p, &a), pi_multiple(&p, &a))
    };
    let q = |n: i64, d: i64| Some(BigRational::new(n.into(), d.into()));
    assert_eq!(angle("pi / 2"), (Some((0, 1)), q(1, 2)));
    assert_eq!(angle("pi"), (Some((-1, 0)), q(1, 1)));
    assert_eq!(angle("-pi / 2"), (Some((0, -1)), q(-1, 2)));
    assert_eq!(angle("3 * pi / 2 + 2 * pi"), (Some((0, -1)), q(7, 2)));
    assert_eq!(angle("r * pi"), (Some((0, 1)), q(1, 2))); // r = 0.5, a constant
    assert_eq!(angle("pi - pi"), (Some((1, 0)), q(0, 1)));
    assert_eq!(angle("0 * pi"), (Some((1, 0)), q(0, 1)));
    // Not quarter turns, or not multiples of π at all.
    assert_eq!(angle("pi / 4"), (None, q(1, 4)));
    assert_eq!(angle("1.5708"), (None, None));
    assert_eq!(angle("1.5707963267948966"), (None, None));
    assert_eq!(angle("pi * pi"), (None, None));
    assert_eq!(angle("pi / 0"), (None, None));
    assert_eq!(angle("x * pi"), (None, None));
    assert_eq!(angle("pi + 1"), (None, None));
    // sin and cos of a quarter turn are exact rationals; of anything else, enclosed.
    let (p, e) = guard("x == sin(pi / 2) + cos(-pi)");
    let ExprKind::Binary(_, _, a) = e.kind else { panic!("a comparison") };
    assert_eq!(exact(&p, &a), Some(BigRational::zero()));
    let (p, e) = guard("x == cos(1.5708)");
    let ExprKind::Binary(_, _, a) = e.kind else { panic!("a comparison") };
    assert_eq!(exact(&p, &a), None);
}

#[test]
fn boxes_enclose_linear_bounds_and_spheres() {
    let (prog, e) = guard("0 <= x <= 2 * r && (y^2 + z^2 <= r^2 || y == 3)");
    let b = point_box(&prog, &e, &slot, &closed);
    assert!(b[0].lo <= 0.0 && b[0].hi >= 1.0 && b[0].hi < 1.0 + 1e-9, "{b:?}");
    assert!(b[1].lo <= -0.5 && b[1].hi >= 3.0 && b[1].hi < 3.0 + 1e-9, "{b:?}");
    // `y == 3` leaves z free, so the hull over the disjunction is unbounded in z.
    assert!(!b[2].is_finite(), "{b:?}");
    let (prog, e) = guard("x^2 + y^2 + z^2 <= r^2 && z >= 0");
    let b = point_box(&prog, &e, &slot, &closed);
    assert!(b[2].lo == 0.0 && b[2].hi >= 0.5 && b[2].hi < 0.5 + 1e-9, "{b:?}");
    assert!(b[0].lo <= -0.5 && b[0].lo > -0.5 - 1e-9, "{b:?}");
}

#[test]
fn unbounded_coordinates_stay_unbounded() {
    let (prog, e) = guard("x >= 0 || y > 1");
    let b = point_box(&prog, &e, &slot, &closed);
    assert!(!b[0].is_finite() && !b[1].is_finite() && !b[2].is_finite());
}

#[test]
fn intervals_contain_the_true_value() {
    let (prog, e) = guard("x == sqrt(2) * sqrt(2) - 2 + r / 3");
    let ExprKind::Binary(_, _, rhs) = &e.kind else { panic!() };
    let iv = eval(&prog, rhs, &closed).expect("closed term");
    let v = 2f64.sqrt() * 2f64.sqrt() - 2.0 + 0.5 / 3.0;
    assert!(iv.lo <= v && v <= iv.hi && iv.hi - iv.lo < 1e-9, "{iv:?}");
    let s = trig(Builtin::Sin, Some(Interval::point(1.2)));
    assert!(s.lo <= 1.2f64.sin() && 1.2f64.sin() <= s.hi && s.hi <= 1.0);
}

/// The value of a closed term: exact rational and enclosure.
fn closed_term(t: &str) -> (Option<BigRational>, Interval) {
    let (prog, e) = guard(&format!("x == {t}"));
    let ExprKind::Binary(_, _, rhs) = &e.kind else { panic!() };
    (exact(&prog, rhs), eval(&prog, rhs, &closed).expect("closed term"))
}

fn contains(iv: Interval, q: &BigRational) -> bool {
    let le = |f: f64, q: &BigRational| f == f64::NEG_INFINITY || BigRational::from_float(f).is_some_and(|r| r <= *q);
    let ge = |f: f64, q: &BigRational| f == f64::INFINITY || BigRational::from_float(f).is_some_and(|r| r >= *q);
    le(iv.lo, q) && ge(iv.hi, q)
}

#[test]
fn literals_and_sums_that_round_to_integers_stay_exact() {
    // Each failed before: the double nearest the value is an integer (or 0), and it
    // was taken as exact.
    for (t, num, den) in [
        ("1e-400", "1", &format!("1{}", "0".repeat(400))[..]),
        ("3.0000000000000001", "30000000000000001", "10000000000000000"),
        ("1 - 1e-20 - 1", "-1", "100000000000000000000"),
        ("0.1 + 0.2 - 0.3", "0", "1"),
        ("(1 + 1e-17) * (1 - 1e-17) - 1", "-1", &format!("1{}", "0".repeat(34))[..]),
    ] {
        let want = BigRational::new(num.parse().unwrap(), den.parse().unwrap());
        let (q, iv) = closed_term(t);
        assert_eq!(q.as_ref(), Some(&want), "{t}");
        assert!(contains(iv, &want), "{t}: {iv:?}");
        assert_eq!(iv.is_exactly(0.0), want.is_zero(), "{t}: {iv:?}");
    }
    // Powers (the language allows exponents up to 64) stay exact and enclosed.
    let (q, iv) = closed_term("(1 - 1e-30) ^ 64");
    let want = num_traits::pow(decimal("0.999999999999999999999999999999").unwrap(), 64);
    assert_eq!(q, Some(want.clone()));
    assert!(contains(iv, &want) && iv.lo < 1.0 && iv.hi <= 1.0, "{iv:?}");
    // Interval powers take O(log n) products and overflow soundly.
    let big = Interval::point(1.5).pow(1_000_000_000);
    assert!(big.lo == f64::MAX && big.hi == f64::INFINITY, "{big:?}");
    // sin of a tiny constant is not 0.
    let (_, iv) = closed_term("sin(1e-400)");
    assert!(!iv.is_exactly(0.0), "{iv:?}");
}

#[test]
fn variable_sums_are_widened_when_inexact() {
    // x in [1, 1], y in [1e-20, 1e-20]: x + y must not be the point 1.
    let x = Interval::point(1.0);
    let y = Interval::of_rational(&decimal("1e-20").unwrap());
    let s = x + y;
    assert!(s.lo <= 1.0 && s.hi > 1.0, "{s:?}");
    let want = decimal("1.00000000000000000001").unwrap();
    assert!(contains(s, &want), "{s:?}");
    let p = Interval::point(0.1) * Interval::point(3.0);
    assert!(contains(p, &(BigRational::from_float(0.1).unwrap() * BigRational::from_integer(3.into()))), "{p:?}");
}

use proptest::prelude::*;

/// A decimal literal with up to 17 digits and an exponent in [-30, 30].
fn lit() -> impl Strategy<Value = String> {
    (any::<bool>(), 0u64..100_000_000_000_000_000, -30i32..30)
        .prop_map(|(neg, m, e)| format!("{}{m}e{e}", if neg { "-" } else { "" }))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn enclosures_contain_the_exact_rational(a in lit(), b in lit(), c in lit()) {
        let (qa, qb, qc) = (decimal(&a).unwrap(), decimal(&b).unwrap(), decimal(&c).unwrap());
        let cases = [
            (format!("({a}) + ({b}) - ({c})"), &qa + &qb - &qc),
            (format!("({a}) * ({b}) + ({c})"), &qa * &qb + &qc),
            (format!("({a}) ^ 2 - {b}"), &qa * &qa - &qb),
        ];
        for (t, want) in cases {
            let (q, iv) = closed_term(&t);
            prop_assert_eq!(q.as_ref(), Some(&want), "{}", t);
            prop_assert!(contains(iv, &want), "{}: {:?}", t, iv);
        }
        // The same through double-ended intervals (variables), without the rationals.
        let (ia, ib, ic) = (Interval::of_rational(&qa), Interval::of_rational(&qb), Interval::of_rational(&qc));
        prop_assert!(contains(ia + ib + -ic, &(&qa + &qb - &qc)));
        prop_assert!(contains(ia * ib + ic, &(&qa * &qb + &qc)));
        prop_assert!(contains(ia.pow(3), &(&qa * &qa * &qa)));
        if !qb.is_zero() {
            prop_assert!(contains(ia.div(ib).unwrap(), &(&qa / &qb)));
        }
    }
}

#[test]
fn ranges_are_read_off_facts() {
    let (prog, e) = guard("y == 2 && x <= y + 1 && 0 <= x && z > 1");
    let rs = ranges_from(&prog, &[&e], &closed);
    let get = |i| rs.iter().find(|(v, _)| slot(v) == Some(i)).map(|(_, r)| *r);
    assert_eq!(get(1), Some(Interval::point(2.0)));
    let x = get(0).expect("x bounded");
    assert!(x.lo == 0.0 && (3.0..3.0 + 1e-9).contains(&x.hi), "{x:?}");
    assert_eq!(get(2).map(|r| r.hi), Some(f64::INFINITY));
}
