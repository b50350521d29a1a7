//! `g1 * ... * gn`: the sides run from the same moment, each participant on its own
//! clock; interruptible motions that end their side early keep running ([INTERRUPT]);
//! then every pair of motions of different sides is compared at times where both run.

use super::motion::occupant;
use super::report::Kind;
use super::run::{Flow, Runner};
use crate::exact::{self, Num, Rat, Value};
use crate::hir::{Global, PrimApp, RoleId};
use crate::smt::goals::witness::{Mover, Occupant};
use num_bigint::BigInt;
use num_traits::Zero;

/// A motion run by one participant, for comparing sides of `*`.
#[derive(Clone)]
pub(super) struct Segment {
    pub(super) role: RoleId,
    pub(super) app: PrimApp,
    pub(super) start: Vec<Value>,
    /// The state at the end.
    pub(super) end: Vec<Value>,
    /// The duration as the witness chose it (an enclosure when irrational); `to - from`
    /// is its midpoint.
    pub(super) len: Num,
    /// Global start and end time.
    pub(super) from: Rat,
    pub(super) to: Rat,
    pub(super) inputs: Vec<Option<Value>>,
}

impl Runner<'_, '_> {
    /// `g1 * ... * gn`: each side from the same moment, then every pair of motions of
    /// different sides compared at times where both run.
    pub(super) fn par(&mut self, sides: &[Global]) -> Flow {
        let mut ranges = Vec::new();
        let mut order: Vec<usize> = (0..sides.len()).collect();
        // Visit the sides in a random order (they do not interact).
        for i in (1..order.len()).rev() {
            let j = self.rng.below(i + 1);
            order.swap(i, j);
        }
        let mut stop = false;
        for &k in &order {
            let from = self.segments.len();
            self.par_depth += 1;
            let flow = self.walk(&sides[k]);
            self.par_depth -= 1;
            match flow {
                Flow::Next => {}
                _ => stop = true,
            }
            ranges.push(from..self.segments.len());
            if self.over {
                return Flow::Stop;
            }
        }
        // An interruptible motion lasts until its participant's next event ([INTERRUPT]):
        // a side that finishes early keeps moving until the `*` ends.
        let end = ranges.iter().flat_map(|r| self.segments[r.clone()].iter().map(|s| s.to.clone())).max();
        if let Some(end) = end {
            for i in ranges.iter().flat_map(|r| r.clone()) {
                if !self.extend(i, &end) {
                    return Flow::Stop;
                }
            }
        }
        for a in 0..ranges.len() {
            for b in a + 1..ranges.len() {
                for i in ranges[a].clone() {
                    for j in ranges[b].clone() {
                        if !self.compare_segments(i, j) {
                            return Flow::Stop;
                        }
                    }
                }
            }
        }
        if stop {
            return Flow::Stop;
        }
        // The continuation goes on with each participant's own clock: a message waits
        // only for its sender and receiver.
        Flow::Next
    }

    /// Extends segment `i` to `end` when its motion is interruptible and is its
    /// participant's latest: a new witness ending then, if the contract allows one
    /// (otherwise it ends as first chosen). False when the run must stop.
    pub(super) fn extend(&mut self, i: usize, end: &Rat) -> bool {
        let s = self.segments[i].clone();
        if !self.prog.prim(s.app.prim).interruptible || s.to >= *end || self.clock[s.role.idx()] != s.to {
            return true;
        }
        let len = end - &s.from;
        let mover = Mover { role: s.role, app: s.app.clone(), start: s.start.clone(), inputs: s.inputs.clone() };
        let one = [Rat::from_integer(BigInt::from(1))];
        match self.sess.trajectory(self.prog, std::slice::from_ref(&mover), &one, Some(&Num::exact(len.clone()))) {
            Ok(Some(tr)) => {
                if let Some(state) = tr.samples.first().and_then(|x| x.states.first()) {
                    self.state[s.role.idx()] = state.clone();
                    self.clock[s.role.idx()] = end.clone();
                    let seg = &mut self.segments[i];
                    seg.end = state.clone();
                    seg.to = end.clone();
                    seg.len = Num::exact(len);
                    let line = format!(
                        "t = {}: `{}` ({}) kept running until then (interruptible); {}",
                        exact::decimal(end),
                        self.prog.prim(s.app.prim).name,
                        self.prog.role_name(s.role),
                        self.show_state(s.role)
                    );
                    self.trace.push(line);
                }
                true
            }
            // Not a stuck state: the participant's next message need not wait for the
            // other sides (happens-before orders it after its own side only), so running
            // this long is one possible execution, not a forced one.
            Ok(None) => true,
            Err(why) => {
                self.undecided(end, "extending an interruptible motion", why);
                false
            }
        }
    }

    /// Two motions of different sides of `*`: at a few times where both run, a state of
    /// each (a witness from its contract at that time) and their footprints compared.
    pub(super) fn compare_segments(&mut self, i: usize, j: usize) -> bool {
        let (x, y) = (self.segments[i].clone(), self.segments[j].clone());
        let lo = x.from.clone().max(y.from.clone());
        let hi = x.to.clone().min(y.to.clone());
        if lo > hi {
            return true;
        }
        let mut times = vec![lo.clone(), hi.clone()];
        let f = self.rng.fraction();
        times.push(&lo + (&hi - &lo) * f);
        times.dedup();
        for t in times {
            let mut occ = Vec::new();
            for s in [&x, &y] {
                match self.state_at(s, &t) {
                    Some(o) => occ.push(o),
                    None => return false,
                }
            }
            let context = format!(
                "`{}` ({}) and `{}` ({}) on different sides of `*`",
                self.prog.prim(x.app.prim).name,
                self.prog.role_name(x.role),
                self.prog.prim(y.app.prim).name,
                self.prog.role_name(y.role)
            );
            let both = [&occ[0], &occ[1]];
            if !self.collide(&occ[0], &occ[1], &t, &context, &both) || !self.bodies_apart(&both, &t, &context, false) {
                return false;
            }
        }
        true
    }

    /// A state of a segment's motion at global time `t` (a witness of its contract).
    pub(super) fn state_at(&mut self, s: &Segment, t: &Rat) -> Option<Occupant> {
        let len = &s.to - &s.from;
        let clock = t - &s.from;
        let mover = Mover { role: s.role, app: s.app.clone(), start: s.start.clone(), inputs: s.inputs.clone() };
        if clock.is_zero() {
            return Some(occupant(&mover, &s.start, &Num::int(0)));
        }
        if clock >= len {
            return Some(occupant(&mover, &s.end, &s.len));
        }
        let fracs = vec![&clock / &len, Rat::from_integer(BigInt::from(1))];
        match self.sess.trajectory(self.prog, std::slice::from_ref(&mover), &fracs, Some(&s.len)) {
            Ok(Some(tr)) => {
                let sample = tr.samples.first()?;
                Some(occupant(&mover, &sample.states.first()?.clone(), &sample.time))
            }
            Ok(None) => {
                self.report(
                    Kind::Stuck,
                    t,
                    format!(
                        "`{}` ({}) has no state at this time of its motion",
                        self.prog.prim(s.app.prim).name,
                        self.prog.role_name(s.role)
                    ),
                );
                None
            }
            Err(why) => {
                self.undecided(t, "a state within a side of `*`", why);
                None
            }
        }
    }
}
