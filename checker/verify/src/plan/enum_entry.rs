//! Enum-typed MAVLink fields (E0243): a user refinement of an enum-typed field leaves it
//! some entry of the enum.

use super::Contexts;
use crate::hir::expr::BinOp;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::Sigma;
use std::collections::HashMap;

impl<'a> Contexts<'a> {
    /// The fields of `m` that E0243 asks about: enum-typed, with a user refinement that does
    /// not settle the question by itself ([`pins_entry`]). Records the enum of every
    /// enum-typed field of `m` on the way.
    pub(super) fn enum_fields(&mut self, m: &Msg) -> Vec<usize> {
        let mut asked = Vec::new();
        for (i, f) in m.payload.iter().enumerate() {
            let Some(mav) = &f.mav else { continue };
            let Some(check) = &mav.entry else { continue };
            self.enum_of.insert(f.value, (check.enum_name.clone(), check.wire));
            let user = match (&f.refinement, mav.implicit) {
                (Some(r), true) if mav.user => match &r.kind {
                    ExprKind::Binary(BinOp::And, _, u) => Some(&**u),
                    _ => None,
                },
                (r, false) if mav.user => r.as_ref(),
                _ => None,
            };
            if user.is_some_and(|u| !pins_entry(self.prog, &self.enum_of, f.value, check, u)) {
                asked.push(i);
            }
        }
        asked
    }

    /// Enum-typed MAVLink fields (E0243; ARCHITECTURE.md, "Enum-typed fields"). A field
    /// whose values are entries of an enum has the entry predicate in its refinement (its
    /// type), so a user refinement only narrows it. This asks, for each field of `asked`,
    /// that the narrowing leaves some entry: Σ after the message (Σ `before` it, the guard
    /// and every field's refinement as `assumed`, this one's exactly) is satisfiable, and if it is not while Σ after
    /// the message *without this field's entry predicate* is, the enum is to blame
    /// (`Goal::Reachable` with that context as the one before the step). Both contexts are
    /// cut to the field's cone of influence: the facts that share no variable with it,
    /// directly or through others, cannot make the difference (and E0243 only rejects: no
    /// proof rests on it).
    pub(super) fn enum_entries(&mut self, m: &Msg, assumed: &Msg, asked: &[usize], before: &Sigma) {
        for &i in asked {
            let f = &m.payload[i];
            let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
            // The other fields as Σ will assume them; this one exactly, and without its
            // predicate.
            let mut with = assumed.clone();
            with.payload[i].refinement = f.refinement.clone();
            let mut after = before.clone();
            after.assume_message(&with);
            with.payload[i].refinement = crate::lower::refinement_without_entry(self.prog.dialect, f);
            let mut s = before.clone();
            s.assume_message(&with);
            let x =
                Expr { kind: ExprKind::Var(Var::Value(f.value, f.name.clone())), sort: f.sort.clone(), loc: check.at };
            let (_, what) = crate::lower::entry_predicate(self.prog.dialect, check, &x);
            let written = f.mav.as_ref().map_or(f.name.as_str(), |mav| mav.written.as_str());
            self.obligations.push(Obligation {
                rule: Rule::EnumEntry,
                span: check.at.0,
                what: format!("`{written}` of {}: some value its refinement admits is {what}", m.label),
                hyps: crate::sigma::cone::cone(self.prog, after.facts(), &x),
                goal: Goal::Reachable {
                    before: vec![crate::sigma::cone::cone(self.prog, s.facts(), &x)],
                    dead_branch: false,
                },
            });
        }
    }
}

/// Whether the user's refinement `u` of the enum-typed value `x` forces it to a value the
/// enum allows wherever `u` holds, syntactically: `x == c` for a constant `c` the enum
/// allows (`lower::entry_allows`), or `x == y` for a value `y` of the same enum and wire
/// type (itself an entry by its type), either way round; a conjunction when one conjunct does; a
/// disjunction when each disjunct does. Then Σ after the message is satisfiable exactly
/// when it is without `x`'s entry predicate, and E0243 needs no query.
fn pins_entry(
    prog: &Program,
    enum_of: &HashMap<ValueId, (String, crate::dialect::Wire)>,
    x: ValueId,
    check: &EnumCheck,
    u: &Expr,
) -> bool {
    match &u.kind {
        ExprKind::Binary(BinOp::And, a, b) => {
            pins_entry(prog, enum_of, x, check, a) || pins_entry(prog, enum_of, x, check, b)
        }
        ExprKind::Binary(BinOp::Or, a, b) => {
            pins_entry(prog, enum_of, x, check, a) && pins_entry(prog, enum_of, x, check, b)
        }
        ExprKind::Binary(BinOp::Eq, a, b) => [(a, b), (b, a)].into_iter().any(|(v, e)| {
            if !matches!(&v.kind, ExprKind::Var(Var::Value(id, _)) if *id == x) {
                return false;
            }
            match &e.kind {
                ExprKind::Var(Var::Value(y, _)) => enum_of.get(y) == Some(&(check.enum_name.clone(), check.wire)),
                _ => {
                    e.sort == Sort::Int
                        && crate::hir::expr::const_int(prog, e)
                            .is_some_and(|c| crate::lower::entry_allows(prog.dialect, check, c))
                }
            }
        }),
        _ => false,
    }
}
