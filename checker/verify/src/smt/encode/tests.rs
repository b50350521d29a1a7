//! Tests of the encoder: numerals read back exactly, one symbol per name.

use super::numeral::exact_decimal;
use super::*;

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(n.into(), d.into())
}

#[test]
fn negative_integers_of_a_model_read_as_written() {
    assert_eq!(int_text("(- 1)"), "-1");
    assert_eq!(int_text("(- 9223372036854775809)"), "-9223372036854775809");
    assert_eq!(int_text("42"), "42");
    // Anything else is shown as Z3 printed it, not guessed at.
    assert_eq!(int_text("(- x)"), "(- x)");
}

#[test]
fn decimals_and_doubles_become_exact_rationals() {
    // 0.65 is 13/20 exactly, not the double nearest it.
    assert_eq!(rational("0.65").and_then(|r| rational_value(&r)), Some(q(13, 20)));
    assert_eq!(rational("1e-3").and_then(|r| rational_value(&r)), Some(q(1, 1000)));
    assert_eq!(rational("12").and_then(|r| rational_value(&r)), Some(q(12, 1)));
    // A double is the dyadic rational it is: 0.1 as a double is not 1/10.
    let tenth = real_of_f64(0.1).and_then(|r| rational_value(&r)).expect("a rational");
    assert_ne!(tenth, q(1, 10));
    assert_eq!(tenth, BigRational::from_float(0.1).expect("finite"));
    assert!(real_of_f64(f64::NAN).is_none() && real_of_f64(f64::INFINITY).is_none());
    // Beyond 64 bits, through the printed numeral.
    let big = q(1, 3) * BigRational::from_integer(num_bigint::BigInt::from(10u8).pow(30));
    assert_eq!(real_of_rational(&big).and_then(|r| rational_value(&r)), Some(big.clone()));
    assert_eq!(real_of_rational(&-big.clone()).and_then(|r| rational_value(&r)), Some(-big));
    assert!(rational_value(&Real::new_const("x")).is_none());
}

#[test]
fn counterexample_numbers_are_read_in_decimals() {
    assert_eq!(decimal(&rational("0.65").expect("a literal")), "0.65");
    assert_eq!(decimal(&rational("-7").expect("a literal")), "-7");
    assert_eq!(decimal(&rational("1e-9").expect("a literal")), "1e-9");
    // Not a decimal: the fraction, never a rounding that reads as exact.
    assert_eq!(decimal(&real_of_rational(&q(1, 3)).expect("a rational")), "1/3");
    // A dyadic fraction of 40 places (Z3's arithmetic makes them): the fraction.
    assert_eq!(decimal(&real_of_rational(&q(7, 1 << 40)).expect("a rational")), "7/1099511627776");
    assert_eq!(decimal(&real_of_rational(&q(1, 1024)).expect("a rational")), "0.0009765625");
    assert_eq!(decimal(&real_of_rational(&q(-3, 8)).expect("a rational")), "-0.375");
    assert_eq!(decimal(&real_of_rational(&q(-123, 100_000_000)).expect("a rational")), "-1.23e-6");
    // π's enclosure halved: 21 places, exact.
    let half_pi = BigRational::new(
        num_bigint::BigInt::parse_bytes(b"314159265358979323846", 10).expect("digits"),
        num_bigint::BigInt::from(2u8) * num_bigint::BigInt::from(10u8).pow(20),
    );
    assert_eq!(decimal(&real_of_rational(&half_pi).expect("a rational")), "1.57079632679489661923");
    assert_eq!(exact_decimal(&q(1, 3), 30), None);
    assert_eq!(exact_decimal(&q(1200, 1), 30).as_deref(), Some("1200"));
}

#[test]
fn terms_of_one_sort_compare_and_names_are_one_symbol() {
    let (prog, _) = crate::lower::tests::first_guard(
        "robot R { state x: real; } system S { participant A: R; participant B: R; }
             choreography G = A -> B : [x >= 0] go. end;",
    );
    let mut enc = Encoder::new(&prog);
    let a = enc.named("a", &crate::hir::Sort::Real).expect("a real");
    let again = enc.named("a", &crate::hir::Sort::Real).expect("a real");
    assert!(a.equals(&again).is_some());
    assert_eq!(enc.terms().count(), 1, "one name, one symbol");
    let b = enc.named("b", &crate::hir::Sort::Bool).expect("a boolean");
    assert!(a.equals(&b).is_none(), "a real and a boolean do not compare");
    let p = enc.named("p", &crate::hir::Sort::Point).expect("a point");
    assert!(matches!(p, Term::V(_)) && p.equals(&p).is_some());
    assert!(as_real(b).is_err() && as_real(p).is_err());
}
