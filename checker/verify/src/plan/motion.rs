//! [AGCOMP] of each joint motion under Σ (Sec 3.4, Def 4.4 (3)), the runs for the
//! enclosing `*`s, and the motion's effect on Σ.

use super::Contexts;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, RoleMotion, Rule};
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// [AGCOMP] under Σ, the runs for enclosing `*`s, then the motion's effect.
    pub(super) fn motion(&mut self, m: &Motion, sigma: &mut Sigma) {
        // Every dt gets one: even a lone primitive must be able to end (see smt::goals).
        let who: Vec<RoleId> = m.parts.iter().map(|(r, _)| *r).collect();
        self.obligations.push(Obligation {
            rule: Rule::AgComp,
            span: m.loc.0,
            what: format!("joint motion of {}", crate::wf::scope::names(self.prog, &who)),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Compatible { parts: m.parts.clone() },
        });
        if self.in_par > 0 {
            for (role, app) in &m.parts {
                self.runs.push(RoleMotion { role: *role, app: app.clone(), hyps: sigma.facts().to_vec() });
            }
        }
        sigma.apply_joint_motion(self.prog, &m.parts);
    }
}
