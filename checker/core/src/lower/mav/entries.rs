//! Enum-typed fields: a field or command parameter the dialect gives an enum
//! (`enum="MAV_BOOL"`) takes only the enum's entries, or for a bitmask enum combinations of
//! its flags ([`entry_predicate`]). Without a user refinement the field's type is the enum:
//! the predicate is conjoined to the implicit part like the wire range. With one, the user's
//! refinement must imply it where the message is sent: the global walk asks it
//! (`Rule::EnumEntry`, E0243; docs/soundness-mavlink.md, "Enum-typed fields").

use super::super::*;
use super::int_literal;
use crate::dialect::{Dialect, Enum};

/// How many entries or flags a diagnostic lists by name.
const LISTED: usize = 8;

/// A float field (a command parameter) holds an enum's value as a real: the predicate lists
/// the allowed values one by one, at most this many (the bundled dialects need 1,024, for
/// GIMBAL_MANAGER_FLAGS' ten flags; a test checks it). An enum with more is not checked:
/// its predicate is `false`, so the protocol is rejected with a message that says why,
/// never verified.
pub(crate) const MAX_REAL_VALUES: usize = 1024;

/// The predicate "`x` is a value the enum of `check` allows", and its description for
/// diagnostics (`an entry of `MAV_BOOL`: `MAV_BOOL_FALSE` (0), `MAV_BOOL_TRUE` (1)`).
///
/// A plain enum: the union of its entries' values, as maximal runs of consecutive integers
/// ([`Enum::value_runs`]): `x == v` for a single value, `lo <= x && x <= hi` for a run (an
/// integer field), so MAV_RESULT is one range and MAV_CMD about fifty disjuncts, never one
/// per entry. A bitmask enum: a combination of its flags, i.e. every bit of `x` (within the
/// wire width, two's complement) is set by some entry ([`Enum::flag_mask`] `M`): `x <=
/// 2^a - 1` for `a` the bit length of `M` (and `0 <= x` for a signed field whose sign bit
/// no flag has), and `!has_flag(x, 2^k)` for each bit `k < a` that no flag has (encoded
/// exactly with div/mod, as `has_flag` is). A real (float) field: the allowed integers one
/// by one (`x == v`), at most [`MAX_REAL_VALUES`]. The disjunctions are balanced trees.
/// Without the dialect or the enum (no bundled file refers to a missing enum), or above the
/// limit, the predicate is `false`: the check fails and the description says why.
pub fn entry_predicate(d: Option<&Dialect>, check: &crate::hir::EnumCheck, x: &Expr) -> (Expr, String) {
    let loc = x.loc;
    let name = &check.enum_name;
    let Some(e) = d.and_then(|d| d.enum_(name)) else {
        return (Expr::bool(false, loc), format!("an entry of `{name}`, which the dialect does not define"));
    };
    let cmp =
        |op, a: Expr, b: Expr| Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Bool, loc };
    let real = x.sort == Sort::Real;
    if e.bitmask {
        let bits = check.wire.bytes() * 8;
        let mask = e.flag_mask(if real { 64 } else { bits });
        let what = describe_flags(e, mask);
        if real {
            let n = mask.count_ones();
            if n > MAX_REAL_VALUES.ilog2() {
                return (Expr::bool(false, loc), too_many(&what));
            }
            // Every subset of the mask's bits, in increasing order.
            let mut values = Vec::with_capacity(1 << n);
            let mut sub = 0u64;
            loop {
                values.push(sub as i128);
                if sub == mask {
                    break;
                }
                sub = (sub.wrapping_sub(mask)) & mask;
            }
            values.sort_unstable();
            let eqs = values.into_iter().map(|v| cmp(BinOp::Eq, x.clone(), int_literal(v, loc))).collect();
            return (any(eqs, loc), what);
        }
        let a = 64 - mask.leading_zeros();
        let mut parts = Vec::new();
        if a < bits {
            let signed = check.wire.int_range().is_some_and(|(lo, _)| lo < 0);
            if signed {
                parts.push(cmp(BinOp::Le, int_literal(0, loc), x.clone()));
            }
            parts.push(cmp(BinOp::Le, x.clone(), int_literal((1i128 << a) - 1, loc)));
        }
        for k in (0..a).filter(|k| mask >> k & 1 == 0) {
            let flag = int_literal(1i128 << k, loc);
            let has = Expr { kind: ExprKind::Call(Builtin::HasFlag, vec![x.clone(), flag]), sort: Sort::Bool, loc };
            parts.push(Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(has)), sort: Sort::Bool, loc });
        }
        return (crate::hir::expr::and_all(parts, loc), what);
    }
    let runs = e.value_runs();
    let what = describe_entries(e, &runs);
    let mut alts = Vec::new();
    if real {
        let count: i128 = runs.iter().map(|(lo, hi)| i128::from(*hi) - i128::from(*lo) + 1).sum();
        if count > MAX_REAL_VALUES as i128 {
            return (Expr::bool(false, loc), too_many(&what));
        }
        for (lo, hi) in runs {
            alts.extend((lo..=hi).map(|v| cmp(BinOp::Eq, x.clone(), int_literal(i128::from(v), loc))));
        }
    } else {
        for (lo, hi) in runs {
            alts.push(if lo == hi {
                cmp(BinOp::Eq, x.clone(), int_literal(i128::from(lo), loc))
            } else {
                let lower = cmp(BinOp::Le, int_literal(i128::from(lo), loc), x.clone());
                lower.and(cmp(BinOp::Le, x.clone(), int_literal(i128::from(hi), loc)))
            });
        }
    }
    (any(alts, loc), what)
}

/// The refinement of a field with an [`EnumCheck`] without its entry predicate: what the
/// protocol says of the value besides the enum (the wire range, the user's refinement).
/// `None` when nothing is left. Lowering puts the predicate last among the implicit
/// conjuncts, so it is the whole implicit part or its right operand.
pub fn refinement_without_entry(d: Option<&Dialect>, f: &Field) -> Option<Expr> {
    let (Some(mav), Some(r)) = (&f.mav, &f.refinement) else { return f.refinement.clone() };
    let Some(check) = &mav.entry else { return f.refinement.clone() };
    let x = Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
    let (pred, _) = entry_predicate(d, check, &x);
    let (implicit, user) = match (&r.kind, mav.user) {
        (ExprKind::Binary(BinOp::And, i, u), true) => (&**i, Some(&**u)),
        (_, true) => return f.refinement.clone(), // not built by lowering: keep it whole
        (_, false) => (r, None),
    };
    let rest = if *implicit == pred {
        None
    } else {
        match &implicit.kind {
            ExprKind::Binary(BinOp::And, rest, e) if **e == pred => Some((**rest).clone()),
            _ => return f.refinement.clone(),
        }
    };
    match (rest, user) {
        (Some(i), Some(u)) => Some(i.and(u.clone())),
        (i, u) => i.or(u.cloned()),
    }
}

/// Up to this many alternatives, the entry predicate is assumed exactly in the contexts of
/// the global walk; above, its convex hull (see [`approximate_entries`]).
const ASSUMED_EXACTLY: usize = 4;

/// A sound over-approximation of the entry predicate, cheaper for the solver, when the exact
/// one is costly: the hull `lo <= x && x <= hi` of a plain enum of more than
/// [`ASSUMED_EXACTLY`] runs (MAV_CMD's fifty) or of a float field of more values; a
/// bitmask's range without its `!has_flag` holes (div/mod). `None` when the exact predicate
/// is cheap enough to keep. (`true`, when nothing is left.)
fn entry_approximation(d: Option<&Dialect>, check: &crate::hir::EnumCheck, x: &Expr) -> Option<Expr> {
    let e = d.and_then(|d| d.enum_(&check.enum_name))?;
    let loc = x.loc;
    let cmp =
        |op, a: Expr, b: Expr| Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Bool, loc };
    let hull = |lo: i128, hi: i128| {
        cmp(BinOp::Le, int_literal(lo, loc), x.clone()).and(cmp(BinOp::Le, x.clone(), int_literal(hi, loc)))
    };
    let real = x.sort == Sort::Real;
    if e.bitmask {
        let (pred, _) = entry_predicate(d, check, x);
        if real {
            let mask = e.flag_mask(64);
            return (mask.count_ones() > ASSUMED_EXACTLY.ilog2() && mask <= i64::MAX as u64)
                .then(|| hull(0, i128::from(mask)));
        }
        let has_holes = pred.conjuncts().iter().any(|c| matches!(c.kind, ExprKind::Unary(UnOp::Not, _)));
        if !has_holes {
            return None;
        }
        let kept = pred.conjuncts().into_iter().filter(|c| !matches!(c.kind, ExprKind::Unary(UnOp::Not, _))).cloned();
        return Some(crate::hir::expr::and_all(kept, loc));
    }
    let runs = e.value_runs();
    let (lo, hi) = (runs.first()?.0, runs.last()?.1);
    let many = if real {
        runs.iter().map(|(a, b)| i128::from(*b) - i128::from(*a) + 1).sum::<i128>() > ASSUMED_EXACTLY as i128
    } else {
        runs.len() > ASSUMED_EXACTLY
    };
    many.then(|| hull(i128::from(lo), i128::from(hi)))
}

/// `m` with each enum-typed field whose entry predicate is costly ([`entry_approximation`])
/// refined by the approximation instead: what the global walk *assumes* after the message
/// (Σ). Sound, as a weaker fact: the exact predicate stays in the field's refinement, which
/// every check that must *establish* it reads (a process's [T-OUT], the progress check's
/// payload, E0243). `None` when no field changes.
pub fn approximate_entries(d: Option<&Dialect>, m: &Msg) -> Option<Msg> {
    let mut out: Option<Msg> = None;
    for (i, f) in m.payload.iter().enumerate() {
        let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
        let x = Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
        let Some(approx) = entry_approximation(d, check, &x) else { continue };
        let rest = refinement_without_entry(d, f);
        let new = match rest {
            Some(r) => approx.and(r),
            None => approx,
        };
        out.get_or_insert_with(|| m.clone()).payload[i].refinement = (!new.is_true()).then_some(new);
    }
    out
}

/// Whether the enum of `check` allows the integer `v` (an entry's value, or for a bitmask
/// enum a combination of its flags): [`entry_predicate`] on a constant, without a solver.
pub fn entry_allows(d: Option<&Dialect>, check: &crate::hir::EnumCheck, v: i64) -> bool {
    let Some(e) = d.and_then(|d| d.enum_(&check.enum_name)) else { return false };
    let real = check.wire.is_float();
    if e.bitmask {
        let bits = if real { 64 } else { check.wire.bytes() * 8 };
        let mask = e.flag_mask(bits);
        if real {
            // Listed value by value: the non-negative combinations, up to the limit.
            return mask.count_ones() <= MAX_REAL_VALUES.ilog2() && v >= 0 && (v as u64) & !mask == 0;
        }
        let keep = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let fits = check.wire.int_range().is_none_or(|(lo, hi)| (lo..=hi).contains(&i128::from(v)));
        return fits && (v as u64 & keep) & !mask == 0;
    }
    if real {
        let count: i128 = e.value_runs().iter().map(|(lo, hi)| i128::from(*hi) - i128::from(*lo) + 1).sum();
        if count > MAX_REAL_VALUES as i128 {
            return false;
        }
    }
    e.entries.iter().any(|x| x.value == v)
}

/// The disjunction of `alts` as a balanced tree (so no stage recurses as deep as there are
/// alternatives); `false` when there are none (an enum without entries).
fn any(mut alts: Vec<Expr>, loc: Loc) -> Expr {
    match alts.len() {
        0 => Expr::bool(false, loc),
        1 => alts.pop().unwrap_or_else(|| Expr::bool(false, loc)),
        n => {
            let right = alts.split_off(n.div_ceil(2));
            let (a, b) = (any(alts, loc), any(right, loc));
            Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(a), Box::new(b)), sort: Sort::Bool, loc }
        }
    }
}

fn too_many(what: &str) -> String {
    format!("{what}; a float field is checked value by value and this enum has more than {MAX_REAL_VALUES} values, so mochi cannot check it (the check fails rather than pass unchecked)")
}

/// `an entry of `MAV_RESULT`: `MAV_RESULT_ACCEPTED` (0), ...`: the entries by name when
/// few, else their count and values.
fn describe_entries(e: &Enum, runs: &[(i64, i64)]) -> String {
    if e.entries.is_empty() {
        return format!("an entry of `{}`, which has none", e.name);
    }
    if e.entries.len() <= LISTED {
        let names: Vec<String> = e.entries.iter().map(|x| format!("`{}` ({})", x.name, x.value)).collect();
        return format!("an entry of `{}`: {}", e.name, names.join(", "));
    }
    let values = if runs.len() <= 6 {
        let r: Vec<String> =
            runs.iter().map(|(lo, hi)| if lo == hi { lo.to_string() } else { format!("{lo}..={hi}") }).collect();
        format!(": values {}", r.join(", "))
    } else {
        String::new()
    };
    format!("an entry of `{}` ({} entries{values})", e.name, e.entries.len())
}

/// `a combination of the flags of `X`: `A` (1), `B` (2)`: the entries by name when few (a
/// 0 entry such as MAV_BOOL_FALSE included), else the mask of the bits they set.
fn describe_flags(e: &Enum, mask: u64) -> String {
    if e.entries.is_empty() {
        return format!("a combination of the flags of `{}`, which has none: 0", e.name);
    }
    if e.entries.len() <= LISTED {
        let names: Vec<String> = e.entries.iter().map(|x| format!("`{}` ({})", x.name, x.value)).collect();
        return format!("a combination of the flags of `{}`: {}", e.name, names.join(", "));
    }
    format!("a combination of the flags of `{}` ({} entries, bits {mask:#x})", e.name, e.entries.len())
}
