//! Full separation (Sec 4.1): one obligation per `*` listing what each side may run, each
//! side walked from the facts of Σ over its own participants.

use super::Contexts;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule, Side};
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// `g1 * ... * gn`: each side from the facts over its own participants; one
    /// separation obligation listing what each side may run.
    pub(super) fn par(&mut self, sides: &'a [Global], loc: Loc, sigma: Sigma) -> Option<Sigma> {
        let pts: Vec<Vec<RoleId>> = sides.iter().map(Global::participant_list).collect();
        // Pushed now so that obligations keep the order of the type; the sides are
        // filled in once they have been walked.
        let slot = (sides.len() > 1).then(|| {
            self.obligations.push(Obligation {
                rule: Rule::FullSeparation,
                span: loc.0,
                what: format!("footprints of the {} sides of `*`", sides.len()),
                hyps: sigma.facts().to_vec(),
                goal: Goal::Separated { sides: Vec::new() },
            });
            self.obligations.len() - 1
        });
        let starts = sigma.split(&pts);
        let mut out = Some(Sigma::new());
        let mut done = Vec::with_capacity(sides.len());
        self.in_par += 1;
        for ((side, roles), start) in sides.iter().zip(pts).zip(starts) {
            let from = self.runs.len();
            let end = self.walk(side, start);
            done.push(Side { roles, runs: self.runs[from..].to_vec() });

            out = match (out, end) {
                (Some(mut o), Some(e)) => {
                    o.meet(e);
                    Some(o)
                }
                _ => None,
            };
        }
        self.in_par -= 1;
        if self.in_par == 0 {
            self.runs.clear();
        }

        if let Some(i) = slot {
            if let Some(Obligation { goal: Goal::Separated { sides }, .. }) = self.obligations.get_mut(i) {
                *sides = done;
            }
        }
        out
    }
}
