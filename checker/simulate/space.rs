//! Collisions at one time of a run, on concrete states.

use super::motion::{frame_env, show_values};
use super::report::Kind;
use super::run::Runner;
use crate::exact::{self, Num, Rat, Tri, Value};
use crate::hir::Var;
use crate::smt::goals::witness::Occupant;

impl Runner<'_, '_> {
    /// Compares two footprints; false when the run must stop (a finding was made).
    pub(super) fn collide(&mut self, a: &Occupant, b: &Occupant, t: &Rat, context: &str) -> bool {
        let prog = self.prog;
        let (pa, pb) = (prog.prim(a.app.prim), prog.prim(b.app.prim));
        if pa.footprint.is_none() || pb.footprint.is_none() {
            let who = if pa.footprint.is_none() { a } else { b };
            self.report(
                Kind::Collision,
                t,
                format!(
                    "{context}: `{}` ({}) declares no footprint, so it fills all space",
                    prog.prim(who.app.prim).name,
                    prog.role_name(who.role)
                ),
            );
            return false;
        }
        match self.sess.overlap(prog, a, b) {
            Ok(None) => true,
            Ok(Some(p)) => {
                // Replay: the point must lie in both footprints, exactly (pose rotations
                // by enclosures, so a rotated point may be undecided, never wrongly false).
                let inside = [a, b].map(|o| self.in_footprint(o, &p));
                let point = format!("({}, {}, {})", p[0], p[1], p[2]);
                if inside.contains(&Tri::False) {
                    self.report(
                        Kind::Replay,
                        t,
                        format!("{context}: Z3's common point {point} of two footprints is not in both when replayed exactly"),
                    );
                } else {
                    self.report(
                        Kind::Collision,
                        t,
                        format!(
                            "{context}: the footprints of `{}` ({}: {}) and `{}` ({}: {}) share the point {point} at time {}",
                            pa.name,
                            prog.role_name(a.role),
                            show_values(prog, a.role, &a.now),
                            pb.name,
                            prog.role_name(b.role),
                            show_values(prog, b.role, &b.now),
                            exact::decimal(t)
                        ),
                    );
                }
                false
            }
            Err(why) => {
                self.undecided(t, &format!("{context}: comparing footprints"), why);
                false
            }
        }
    }

    /// Whether the world point `p` is in `o`'s footprint, evaluated exactly.
    pub(super) fn in_footprint(&self, o: &Occupant, p: &[Num; 3]) -> Tri {
        let prog = self.prog;
        let Some(fp) = &prog.prim(o.app.prim).footprint else { return Tri::True };
        let Some(local) = crate::smt::replay::to_local(prog, o.role, p) else { return Tri::Unknown };
        let args = self.arg_values(&o.app);
        let env = frame_env(&o.now, &o.start, &args, &o.clock, &[]);
        let env = |v: &Var| match v {
            Var::Point(k) => local.get(*k).cloned().map(Value::Num),
            other => env(other),
        };
        exact::holds(prog, &fp.pred, &env)
    }
}
