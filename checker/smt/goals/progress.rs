//! Progress (E0419): the query of a [`Goal::Progress`](crate::obligation::Goal) part.
//! A branch can be taken when its guard holds and some payload satisfies its
//! refinements: `guard ∧ ∃ fields. refinement`, the fields bound by an existential over
//! the very constants the encoder gives their values (Z3 abstracts them inside the
//! body only, so a fact of Σ about the same field's earlier value, from an earlier
//! iteration of a loop, stays about that value). The part's query is Σ ∧ ¬∨ branches;
//! sat is a state of Σ in which no branch can be taken. Quantified queries go to Z3's
//! default solver (MBQI), never nlsat; undecided is unknown, never a pass.
//!
//! The guard and the refinement arrive with their definedness conjoined
//! (`wf::scope::enabled`, [`crate::hir::expr::definedness`]): the encoder makes `sqrt` of a
//! negative and a quotient by zero unconstrained values, which some payload would equal, so
//! without it "some payload exists" held where no value on the wire satisfies the refinement.

use super::super::encode::{Encoder, Term, Unsupported};
use crate::hir::expr::value_expr;
use crate::obligation::Enabled;
use z3::ast::{Ast, Bool};

/// `guard ∧ ∃ fields. refinement` as a Z3 formula.
pub fn enabled(enc: &mut Encoder, b: &Enabled) -> Result<Bool, Unsupported> {
    let guard = match &b.guard {
        Some(g) => enc.boolean(g)?,
        None => Bool::from_bool(true),
    };
    if b.fields.is_empty() {
        return Ok(Bool::and(&[guard, enc.boolean(&b.refinement)?]));
    }
    let side_before = enc.side_conditions().count();
    let mut bound: Vec<Term> = Vec::new();
    for (id, name, sort) in &b.fields {
        bound.push(enc.any(&value_expr(*id, name, sort))?);
    }
    // A chosen `float` value is a binary32 (`Encoder::choosing`): its significand is
    // bound with it.
    let ids: Vec<_> = b.fields.iter().map(|(id, _, _)| *id).collect();
    let (body, significands) = enc.choosing(&ids, |enc| enc.boolean(&b.refinement));
    let body = body?;
    if enc.side_conditions().count() != side_before {
        // A side condition (of `sqrt`, `/`, trigonometry) about a bound value would be
        // asserted outside its quantifier: refuse rather than mis-state it.
        return Err(Unsupported(format!(
            "a payload refinement of {} with `sqrt`, division or trigonometry, under \"some value exists\"",
            b.what
        )));
    }
    let mut consts: Vec<&dyn Ast> = Vec::new();
    for t in &bound {
        match t {
            Term::B(x) => consts.push(x),
            Term::I(x) => consts.push(x),
            Term::R(x) => consts.push(x),
            Term::V(xs) => xs.iter().for_each(|x| consts.push(x)),
        }
    }
    significands.iter().for_each(|m| consts.push(m));
    enc.quantified();
    let some = z3::ast::exists_const(&consts, &[], &body);
    Ok(Bool::and(&[guard, some]))
}
