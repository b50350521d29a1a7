//! The robots' real bodies at one time of a run: each participant's `geometry:` (shapes,
//! meshes, URDF links by forward kinematics of the sampled joint values, mounted on its
//! carriers at their states) placed at its concrete state, and compared by parry distance
//! with every obstacle and with every other participant's body: those moving now, and
//! those waiting (outside `*`) at the state their last motion left them in, where the
//! model of time (README.md) says their bodies stay. A mesh is its triangles where the
//! convex hulls touch ([`super::space::meet`]).
//!
//! The checks prove the bodies apart through the footprints (a body within its footprint,
//! E0512; footprints apart, E0404/E0406/E0510): this compares what those proofs are about,
//! so a reading of a footprint that does not hold the body (a mesh's hull, a convex piece)
//! shows up as two bodies that meet.

use super::report::Kind;
use super::run::Runner;
use super::space::{attached, meet, show_point, Meet};
use crate::exact::{self, Rat, Value};
use crate::geometry::{Pose3, Solid};
use crate::hir::{RoleId, Slot, Var};
use crate::smt::goals::witness::Occupant;

/// A participant's body placed in the world.
type Placed<'p> = (RoleId, Vec<(Pose3, &'p Solid)>);

impl<'p> Runner<'_, 'p> {
    /// Obstacle `k`'s solids placed in the world (its `at:` and each part's own pose).
    pub(super) fn obstacle_solids(&self, k: usize) -> Result<Vec<(Pose3, &'p Solid)>, String> {
        let prog = self.prog;
        let Some(world) = crate::space::world::of(prog) else { return Ok(Vec::new()) };
        let base = match prog.obstacles.get(k).and_then(|o| o.pose.as_ref()) {
            Some(p) => self.pose_at(p, &|_: &Var| None)?,
            None => crate::geometry::identity(),
        };
        let mut out = Vec::new();
        for p in world.obstacles.get(k).map(|v| v.as_slice()).unwrap_or_default() {
            let pose = match &p.place {
                Some(pl) => base * self.pose_at(pl, &|_: &Var| None)?,
                None => base,
            };
            out.push((pose, &*p.solid));
        }
        Ok(out)
    }

    /// The body of participant `r` at the state `now` (empty for a kind with none).
    fn body_at(&self, r: RoleId, now: &[Value], moving: &[&Occupant]) -> Result<Vec<(Pose3, &'p Solid)>, String> {
        let prog = self.prog;
        let Some(world) = crate::space::world::of(prog) else { return Ok(Vec::new()) };
        let Some(body) = world.kinds.get(prog.role(r).kind.idx()).filter(|b| !b.is_empty()) else {
            return Ok(Vec::new());
        };
        let own = |v: &Var| match v {
            Var::Own(Slot::State(i)) => now.get(*i).cloned(),
            _ => None,
        };
        self.place(r, body, now, &own, moving)
    }

    /// The bodies of `now` (moving at time `t`), and, when `waiting`, of every other
    /// participant free by `t` at its last state, compared with the obstacles and with each
    /// other (participants attached to each other through a mount are not compared, as the
    /// checks do not compare them). False when the run must stop.
    pub(super) fn bodies_apart(&mut self, now: &[&Occupant], t: &Rat, context: &str, waiting: bool) -> bool {
        let prog = self.prog;
        if crate::space::world::of(prog).is_none_or(|w| w.kinds.iter().all(Vec::is_empty)) {
            return true;
        }
        let mut movers: Vec<Placed<'p>> = Vec::new();
        for o in now {
            match self.body_at(o.role, &o.now, now) {
                Ok(b) if !b.is_empty() => movers.push((o.role, b)),
                Ok(_) => {}
                Err(e) => {
                    let msg = format!("{context}: placing the body of `{}`: {e}", prog.role_name(o.role));
                    self.report(Kind::Undecided, t, msg);
                    return false;
                }
            }
        }
        let mut still: Vec<Placed<'p>> = Vec::new();
        if waiting {
            for (k, clock) in self.clock.iter().enumerate() {
                let r = RoleId(k as u32);
                if now.iter().any(|o| o.role == r) || clock > t || k >= prog.roles.len() {
                    continue;
                }
                let Some(state) = self.state.get(k).filter(|s| !s.is_empty()) else { continue };
                match self.body_at(r, state, now) {
                    Ok(b) if !b.is_empty() => still.push((r, b)),
                    Ok(_) => {}
                    Err(e) => {
                        let msg = format!("{context}: placing the body of `{}`, waiting: {e}", prog.role_name(r));
                        self.report(Kind::Undecided, t, msg);
                        return false;
                    }
                }
            }
        }
        for (i, (r, body)) in movers.iter().enumerate() {
            for k in 0..prog.obstacles.len() {
                let obstacle = match self.obstacle_solids(k) {
                    Ok(o) => o,
                    Err(e) => {
                        let msg = format!("{context}: placing obstacle `{}`: {e}", prog.obstacles[k].name);
                        self.report(Kind::Undecided, t, msg);
                        return false;
                    }
                };
                if let Some(contact @ Meet::Contact { .. }) = meet(body, &obstacle) {
                    let what =
                        format!("the body of `{}` meets obstacle `{}`", prog.role_name(*r), prog.obstacles[k].name);
                    self.report_contact(context, &what, contact, *r, now, t);
                    return false;
                }
            }
            let others = movers[i + 1..].iter().map(|x| (x, "")).chain(still.iter().map(|x| (x, ", waiting,")));
            for ((s, other), how) in others {
                if attached(prog, *r, *s) {
                    continue;
                }
                if let Some(contact @ Meet::Contact { .. }) = meet(body, other) {
                    let what = format!("the bodies of `{}` and `{}`{how} meet", prog.role_name(*r), prog.role_name(*s));
                    self.report_contact(context, &what, contact, *r, now, t);
                    return false;
                }
            }
        }
        true
    }

    /// Reports a contact of `r`'s body (`what` names both sides) as a collision at `t`.
    fn report_contact(&mut self, context: &str, what: &str, contact: Meet, r: RoleId, now: &[&Occupant], t: &Rat) {
        let Meet::Contact { distance, point, names } = contact else { return };
        let msg = format!(
            "{context}: {what} at {} (`{}` and `{}`, distance {distance:.3e} m) at time {}",
            show_point(&point),
            names[0],
            names[1],
            exact::decimal(t),
        );
        let msg = self.with_state(msg, r, now);
        self.report(Kind::Collision, t, msg);
    }

    /// `msg` with the state of `r` now (a mover's sampled state).
    fn with_state(&self, msg: String, r: RoleId, now: &[&Occupant]) -> String {
        match now.iter().find(|o| o.role == r) {
            Some(o) => format!("{msg}; {}", super::motion::show_values(self.prog, r, &o.now)),
            None => msg,
        }
    }
}
