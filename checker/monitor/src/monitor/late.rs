//! Late messages: a message of a choice its receiver abandoned by a timeout, arriving after
//! it (docs/monitor.md, "Late messages"). Sessions that ended by a timeout are kept for
//! theirs, within each abandoned choice's late window; a message that re-enters its choice
//! after the timeout's bound may have been late, which the waiting role's act decides.

use super::automaton::{Automaton, StateKind};
use super::code::Val;
use super::session::{ends_fit, label_fits};
use super::{Binding, Monitor};
use crate::hir::ValueOrigin;
use crate::mavio::Frame;

/// How many abandoned choices a session keeps late windows for (the oldest gives way).
const LATE_CHOICES: usize = 4;

/// The choices a session's waiting roles abandoned by their timeouts whose late messages
/// may still arrive: each state with the end of its late window (µs). Fixed room, no
/// allocation.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LateSet {
    at: [(u32, u64); LATE_CHOICES],
    n: u8,
}

impl LateSet {
    /// Adds the choice of `state`, late until `until` (replacing its earlier window; the
    /// oldest choice gives way when the room is full).
    pub(super) fn push(&mut self, state: u32, until: u64) {
        self.retain(|(l, _)| l != state);
        if self.n as usize == LATE_CHOICES {
            self.at.copy_within(1.., 0);
            self.n -= 1;
        }
        self.at[self.n as usize] = (state, until);
        self.n += 1;
    }

    pub(super) fn iter(&self) -> impl Iterator<Item = (u32, u64)> + '_ {
        self.at[..self.n as usize].iter().copied()
    }

    pub(super) fn is_empty(&self) -> bool {
        self.n == 0
    }

    pub(super) fn retain(&mut self, mut keep: impl FnMut((u32, u64)) -> bool) {
        let mut k = 0;
        for i in 0..self.n as usize {
            if keep(self.at[i]) {
                self.at[k] = self.at[i];
                k += 1;
            }
        }
        self.n = k as u8;
    }
}

/// How many sessions ended by a timeout the monitor keeps for their late messages.
pub(super) const GHOSTS: usize = 8;

/// A session that ended by a timeout: its waiting role gave up and the session reached
/// `end` by that timeout's branch (or by time). A message of a choice it abandoned may still
/// be on the wire; E0326 proves the protocol on the assumption that it reaches no session,
/// so within the choice's late window the monitor reads it as late, not as a message
/// outside any session.
pub(super) struct Ghost {
    id: u64,
    proto: usize,
    roles: Vec<Binding>,
    /// The states whose choices the ending timeouts abandoned, each with the end of its
    /// late window (µs of the frames' clock).
    late: Vec<(u32, u64)>,
}

impl Monitor {
    /// Keeps session `slot`, ending now, for its late messages: the choices its waiting
    /// roles abandoned (`late`, each within its window), and, when it ended by time (`by_time`),
    /// every choice of the chain of timeouts from its state to `end`, each late until its
    /// timeout's bound after the instant it was abandoned. The oldest kept session makes
    /// room (its buffers reused: no allocation once [`GHOSTS`] were kept).
    pub(super) fn remember(&mut self, slot: usize, by_time: bool) {
        let s = &self.slots[slot];
        let a = &self.protos[s.proto];
        let mut g = if self.ghosts.len() >= GHOSTS {
            self.ghosts.remove(0)
        } else {
            Ghost { id: 0, proto: 0, roles: Vec::with_capacity(a.roles.len()), late: Vec::with_capacity(8) }
        };
        g.id = s.id;
        g.proto = s.proto;
        g.roles.clear();
        g.roles.extend_from_slice(&s.roles);
        g.late.clear();
        g.late.extend(s.late.iter());
        if let (true, Some(mut at_us)) = (by_time, s.entered_us) {
            let mut at = s.state;
            for _ in 0..a.states.len() {
                let Some(t) = a.timeout(at) else { break };
                let bound = t.ms.saturating_mul(1000);
                at_us = at_us.saturating_add(bound);
                g.late.push((at, at_us.saturating_add(bound)));
                at = a.settle(t.next);
            }
        }
        self.ghosts.push(g);
    }

    /// The kept session of protocol `p` of which the frame is a late message: a first
    /// message of a choice it abandoned, between its ends, within that choice's window.
    /// Its sender goes on past it alone (its receiver's session is over, E0326's third
    /// case): the states its own messages and timeouts lead to are late within the same
    /// window, lengthened by each of its own timeouts on the way (in the ghost's reserved
    /// room: no allocation).
    pub(super) fn late_of_ended(&mut self, p: usize, f: &Frame) -> Option<u64> {
        let t = f.time_us?;
        let a = &self.protos[p];
        let mut hit = None;
        'ghosts: for (gi, g) in self.ghosts.iter().enumerate().rev() {
            if g.proto != p {
                continue;
            }
            for &(l, until) in &g.late {
                if t > until {
                    continue;
                }
                let fits = a.edges_of(l).iter().find(|&&e| {
                    let e = &a.edges[e as usize];
                    label_fits(e, f) && ends_fit(a, e, &g.roles, &self.kinds, f)
                });
                if let Some(&e) = fits {
                    hit = Some((gi, e, until));
                    break 'ghosts;
                }
            }
        }
        let (gi, e, until) = hit?;
        let by = a.edges[e as usize].from;
        let mut at = a.settle(a.edges[e as usize].target_state);
        let mut until = until;
        let g = &mut self.ghosts[gi];
        for _ in 0..a.states.len() {
            if matches!(a.states[at as usize], StateKind::End) {
                break;
            }
            let senders = !a.edges_of(at).is_empty() && a.edges_of(at).iter().all(|&x| a.edges[x as usize].from == by);
            if senders && g.late.len() < g.late.capacity() && !g.late.iter().any(|&(l, _)| l == at) {
                g.late.push((at, until));
            }
            // The sender's own timeout (it waits for the ended role in vain): what it sends
            // after comes that much later.
            match a.timeout(at) {
                Some(t) if t.by == by => {
                    until = until.saturating_add(t.ms.saturating_mul(1000));
                    at = a.settle(t.next);
                }
                _ => break,
            }
        }
        Some(g.id)
    }

    /// A step of protocol `p`: the kept sessions whose late messages its sender could send
    /// are over (FIFO puts every late message of that end before it), unless the step's
    /// message may itself be one of them (a first message of the protocol that is also a
    /// late message of the ended session: it starts a session, and the ended one's sender
    /// went on past it).
    pub(super) fn forget_late_of(&mut self, p: usize, f: &Frame) {
        if self.ghosts.is_empty() {
            return;
        }
        let a = &self.protos[p];
        let kinds = &self.kinds;
        self.ghosts.retain(|g| {
            if g.proto != p {
                return true;
            }
            let sent_by = |l: u32| {
                a.edges_of(l).iter().any(|&e| {
                    let b = g.roles.get(a.edges[e as usize].from.idx());
                    b.is_some_and(|b| b.sys == Some(f.sysid) && b.comp == Some(f.compid))
                })
            };
            let late_itself = |&(l, until): &(u32, u64)| {
                f.time_us.is_some_and(|t| t <= until)
                    && a.edges_of(l).iter().any(|&e| {
                        let e = &a.edges[e as usize];
                        label_fits(e, f) && ends_fit(a, e, &g.roles, kinds, f)
                    })
            };
            !g.late.iter().any(|&(l, _)| sent_by(l)) || g.late.iter().any(late_itself)
        });
    }
}

/// Whether a step left every recursion parameter as it was (its old values in `undo`): a
/// message that re-enters its choice so is one the waiting role may have ignored as late.
pub(super) fn params_unchanged(a: &Automaton, regs: &[Val], undo: &[(u16, Val)]) -> bool {
    undo.iter().all(|&(r, old)| {
        let param = a.arena.regs.get(r as usize).is_some_and(|info| {
            a.prog.values.get(info.value.0 as usize).is_some_and(|v| matches!(v.origin, ValueOrigin::RecParam))
        });
        !param || regs[r as usize] == old
    })
}
