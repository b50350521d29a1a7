//! What the monitor cannot read, refused when a protocol is compiled (E0802, at the
//! construct): the monitor reads a session's messages in the order of the global type, on
//! one link, and opens a session at its first message.
//!
//! - **A message whose sender is causally unordered with the message before it.** After
//!   `p -> q: a`, a message `r -> s: b` with `r` neither `p` nor `q` may be sent before `a`
//!   (nothing tells `r` that `a` was sent), so the link may carry `b` first, which the
//!   monitor would report unexpected, or outside any session when `a` is the session's
//!   first message (a third role that speaks before the session's first message). After a
//!   timeout by `R`, only `R` knows the choice was left: the next message must be `R`'s
//!   (E0324 asks it already). Likewise the waiting role of a timeout must be an end of the
//!   message that entered its choice: the monitor starts the wait at that message's frame,
//!   which another role does not see (after another timeout, the wait starts when that one
//!   could fire, which the monitor computes).
//! - **A protocol that starts by waiting**: a first choice with a timeout branch in which a
//!   message follows. The session would be opened by the waiting role's message after its
//!   timeout, whose start, the instant the waiting began, no frame shows: the timeout's
//!   bound could never be checked. A first choice whose timeout branch ends at once is read
//!   (the session starts at a message, or never).

use super::automaton::{Automaton, CompileError, StateKind};

/// Refuses a protocol whose messages could reach the link in another order than the global
/// type's, or that starts by waiting (module docs).
pub(super) fn check(a: &Automaton) -> Result<(), CompileError> {
    let start = a.settle(a.start);
    if let Some(t) = a.timeout(start) {
        if !matches!(a.states[a.settle(t.next) as usize], StateKind::End) {
            let by = &a.roles[t.by.idx()];
            return Err(CompileError {
                message: format!(
                    "the protocol starts by waiting: `{by}`'s first act is after this timeout, and no frame shows when \
                     its waiting began, so its bound cannot be checked; start the protocol with the message the wait \
                     follows (a request), or end the timeout branch at once"
                ),
                span: Some(t.span),
            });
        }
    }
    // For each state reached, the roles that may send next without racing the event before
    // (the last message's two ends, or the role whose timeout was taken): the intersection
    // over every way in. `u64::MAX` at the start: any role opens the session.
    // With it, the roles that may wait by a timeout there: the ends of the message that
    // entered the state (any role, when a timeout entered it: the wait then starts at the
    // instant that timeout could fire, which the monitor computes).
    let mut may: Vec<Option<(u64, u64)>> = vec![None; a.states.len()];
    may[start as usize] = Some((u64::MAX, u64::MAX));
    let mut work = vec![start];
    while let Some(s) = work.pop() {
        let Some((m, wait)) = may[s as usize] else { continue };
        let mut next: Vec<(u32, u64, u64)> = Vec::new();
        for &e in a.edges_of(s) {
            let edge = &a.edges[e as usize];
            if m & (1u64 << edge.from.idx()) == 0 {
                let from = &a.roles[edge.from.idx()];
                return Err(CompileError {
                    message: format!(
                        "`{from}`'s `{}` may reach the link before the message it follows in the protocol: `{from}` \
                         neither sent nor received that message, so nothing orders the two, and the monitor reads a \
                         session's messages in the protocol's order; let `{from}` learn of the message before (it \
                         sends or receives it, or hears of it in a message of its own)",
                        edge.label
                    ),
                    span: Some(edge.span),
                });
            }
            let ends = (1u64 << edge.from.idx()) | (1u64 << edge.to.idx());
            next.push((a.settle(edge.target_state), ends, ends));
        }
        if let Some(t) = a.timeout(s) {
            if wait & (1u64 << t.by.idx()) == 0 {
                let by = &a.roles[t.by.idx()];
                return Err(CompileError {
                    message: format!(
                        "`{by}` cannot know when this wait began: it neither sent nor received the message before \
                         the choice, whose time is the wait's start for the monitor; let `{by}` take part in that \
                         message, or move the choice after one it takes part in"
                    ),
                    span: Some(t.span),
                });
            }
            next.push((a.settle(t.next), 1u64 << t.by.idx(), u64::MAX));
        }
        for (t, bits, waits) in next {
            let new = may[t as usize].map_or((bits, waits), |(old, w)| (old & bits, w & waits));
            if may[t as usize] != Some(new) {
                may[t as usize] = Some(new);
                work.push(t);
            }
        }
    }
    Ok(())
}
