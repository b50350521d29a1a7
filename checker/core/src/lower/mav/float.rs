//! Float fields: a `float` (`double`) field's value is a finite binary32 (binary64), the
//! conjunct [`Builtin::Float32`] (`Float64`) of its refinement; [`wire_value`] rounds a
//! constant a process sends to that format exactly (the formats' arithmetic is
//! [`crate::float`]'s).

use super::super::*;
use crate::dialect::Wire;
use crate::float::{dyadic_decimal, float_format, round_to_float};

/// The predicate a float wire type conjoins to its field's refinement:
/// [`Builtin::Float32`] for `float`, [`Builtin::Float64`] for `double`.
pub(super) fn float_builtin(wire: Wire) -> Option<Builtin> {
    match wire {
        Wire::F32 => Some(Builtin::Float32),
        Wire::F64 => Some(Builtin::Float64),
        _ => None,
    }
}

/// The exact value of a closed numeric expression (literals, constants, arithmetic), or
/// `None` when it reads a variable or is not exact.
pub fn exact_constant(prog: &Program, e: &Expr) -> Option<num_rational::BigRational> {
    if !matches!(e.sort, Sort::Int | Sort::Real) {
        return None;
    }
    match crate::exact::eval(prog, e, &|_: &Var| None).ok()? {
        crate::exact::Value::Num(n) if n.lo == n.hi => Some(n.lo),
        _ => None,
    }
}

/// Whether the progress check may replace a field `id` defined by `id == e` by `e`
/// (`∃x. x == e ∧ P(x)` is `P(e)`): always, unless the field is a `float`/`double`, whose
/// [`Builtin::Float32`] conjunct then reads `e` and must stay decided: `e` a constant
/// (decided exactly) or a value of a field of that format or a narrower one (a float by
/// the model). Otherwise the field stays an existential whose format is encoded exactly.
pub fn float_definition_decided(prog: &Program, id: ValueId, e: &Expr) -> bool {
    let Some(f) = prog.wire_floats.get(&id) else { return true };
    if exact_constant(prog, e).is_some() {
        return true;
    }
    match &e.kind {
        ExprKind::Var(Var::Value(v, _)) => {
            prog.wire_floats.get(v).is_some_and(|w| w == f || (*w == Builtin::Float32 && *f == Builtin::Float64))
        }
        _ => false,
    }
}

/// The value a process's argument `a` for the field `field` has on the wire: for a
/// `float`/`double` field and a constant `a`, `a` rounded to the field's format (ties to
/// even), as an exact decimal literal; any other argument as it is (a non-constant one
/// keeps its `float32` conjunct undecided, so its [T-OUT] obligation is unknown unless it
/// is a value of a float field). `Err` with the rounded-away constant when it rounds to an
/// infinity, which no finite float field carries.
pub fn wire_value(prog: &Program, field: ValueId, a: &Expr) -> Result<Expr, String> {
    let Some(format) = prog.wire_floats.get(&field).and_then(|f| float_format(*f)) else { return Ok(a.clone()) };
    let Some(r) = exact_constant(prog, a) else { return Ok(a.clone()) };
    let rounded = round_to_float(&r, format).ok_or_else(|| crate::hir::print::expr(prog, None, a))?;
    match dyadic_decimal(&rounded) {
        Some(text) => Ok(Expr { kind: ExprKind::Real(text), sort: Sort::Real, loc: a.loc }),
        None => Ok(a.clone()),
    }
}
