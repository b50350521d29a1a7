//! The streams' assumption, checked: a stream's invariant admits some reading (E0410).

use super::Contexts;
use crate::hir::*;
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// The streams' assumption, checked: every reading of a stream satisfies its fields'
    /// refinements (wire range, enum, the invariant), so some message of the stream must
    /// exist. An invariant no value of the field's type satisfies would make every step that
    /// reads the stream hold vacuously (a protocol whose first step can never be taken would
    /// verify with a warning): it is E0410 at the stream, as an `init` no state satisfies is.
    /// One query per stream: a stream's refinements read its own template values and
    /// constants only (E0211), so streams are independent of each other and of Σ.
    pub(super) fn streams(&mut self) {
        for s in &self.prog.streams {
            let facts: Vec<Expr> = s.fields.iter().filter_map(|f| f.refinement.clone()).collect();
            if facts.is_empty() {
                continue;
            }
            let to: Vec<&str> = s.to.iter().map(|&r| self.prog.role_name(r)).collect();
            let what = format!(
                "the invariant of the stream `{} -> {}: {}`",
                self.prog.role_name(s.from),
                to.join(", "),
                s.label
            );
            self.reachable(s.loc.0, what, &Sigma::from_facts(&facts), Vec::new(), false);
        }
    }
}
