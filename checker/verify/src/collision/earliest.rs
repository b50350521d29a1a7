//! The earliest contact of a joint motion, once one contact is confirmed: a window
//! `[not_before, t]` such that no configuration the contracts allow puts the two sides in
//! contact at a time at or before `not_before` (proved by the deciding search itself, run
//! again over the times `[0, mid]`), and a contact at `t` (confirmed and replayed as any
//! counterexample of that search). Sec 3.3 asks only whether a contact exists; the window is
//! what a user needs to act on it (where along the motion to change the plan).
//!
//! **Sound.** Each step asks the same question as the search that found the contact, over
//! the configurations whose time is in `[0, mid]` (a sub-box of its root): an apart answer
//! is that search's apart, restricted, so no contact at or before `mid` exists; a contact
//! answer is that search's contact, confirmed as it confirms; anything else (a budget, a
//! resolution, a contact whose time is not known) ends the bisection and is said
//! ([`Earliest::open`]). No time is claimed that a step did not prove.

use crate::geometry::search::bnb;

/// What one step of the bisection found over the times `[0, mid]`.
pub(crate) enum Step<T> {
    /// No contact at a time in `[0, mid]`.
    Apart,
    /// A confirmed contact, and its time (at most `mid`).
    Contact(T, f64),
    /// Neither, with why.
    Undecided(String),
}

/// The window of the earliest contact: none at or before `not_before` (proved); `open`:
/// why it was not narrowed further.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Earliest {
    pub not_before: Option<f64>,
    pub open: Option<String>,
}

/// Steps of the bisection at most: the window is narrowed to 1 % of the contact's time,
/// or to `1/2^(STEPS-1)` of the first contact's time.
pub(crate) const STEPS: usize = 8;

/// Bisects the time of the first contact below `found`'s (at `at` s since the motion's
/// start): first whether they meet at the motion's start (`mid = 0`), then halves of the
/// window left; `ask(from, mid)` decides the question over the times `[from, mid]`, where no
/// contact at or before `from` is already proved (`from` is 0 until a step proves more), so a
/// step never searches again the times an earlier one proved apart. `proved`: a time at or
/// before which the caller has already proved that no contact exists (the deciding search's
/// own earliest-first pass): the bisection starts there, and asks nothing about the start.
/// Returns the earliest confirmed contact found (`found` or an earlier one) with its time,
/// and the window.
pub(crate) fn bisect<T>(
    found: T,
    at: f64,
    proved: Option<f64>,
    ask: &mut dyn FnMut(f64, f64) -> Step<T>,
) -> (T, f64, Earliest) {
    if !(at.is_finite() && at >= 0.0) {
        let open = Some("the contact's time is not known".to_string());
        return (found, at, Earliest { not_before: None, open });
    }
    let proved = proved.filter(|p| p.is_finite() && *p >= 0.0 && *p <= at);
    let (mut best, mut hi, mut lo, mut open) = (found, at, proved, None);
    for step in 0..STEPS {
        if hi <= 0.0 || lo.is_some_and(|l| hi - l <= 0.01 * hi) {
            break;
        }
        let base = lo.unwrap_or(0.0);
        let mid = if step == 0 && lo.is_none() { 0.0 } else { base + (hi - base) / 2.0 };
        if mid >= hi || mid.is_nan() {
            break;
        }
        match ask(base, mid) {
            Step::Apart => lo = Some(mid),
            Step::Contact(c, t) if (0.0..=mid).contains(&t) => (best, hi) = (c, t),
            Step::Contact(..) => {
                open = Some(format!("a contact at or before {} s was found at a time outside that range", short(mid)));
                break;
            }
            Step::Undecided(why) => {
                open = Some(format!("whether they meet at or before {} s was not decided: {why}", short(mid)));
                break;
            }
        }
    }
    (best, hi, Earliest { not_before: lo, open })
}

/// Boxes the geometric search's bisection may search, over all its steps: a fifth of the
/// boxes the deciding search took (with its earliest-first pass), and at least
/// [`GEO_MIN_NODES`]. A budget of boxes, not of time, so that the window does not depend on
/// the machine's load (the query's time limit still applies); a step that meets it claims
/// nothing, and the window says so. Measured (release, `mochi check`): with 60,000 boxes a
/// step, the mounted arm's first step ran into the query's time limit without deciding, and
/// the file took 10.3 s instead of 2.6 s.
fn geo_budget(deciding: usize) -> usize {
    (deciding / 5).max(GEO_MIN_NODES)
}
const GEO_MIN_NODES: usize = 2_000;

impl super::Geo<'_> {
    /// The window of the first contact below `c`'s ([`bisect`]): each step is the
    /// geometric search ([`bnb::decide`]) over the root box with its time dimension `t`
    /// capped at `mid`, within what is left of `opts`' deadline.
    pub(super) fn earliest_contact(
        &self,
        c: bnb::Contact,
        t: usize,
        opts: &bnb::Options,
        deciding: usize,
    ) -> (bnb::Contact, Earliest) {
        let at = c.q.get(t).copied().unwrap_or(f64::NAN);
        let mut step_opts = opts.clone();
        step_opts.time_dim = None;
        let budget = geo_budget(deciding);
        let mut left = budget;
        // The search's own earliest-first pass proved every configuration with a time below
        // `clear_before` apart: at or before the double below it, none touches.
        let proved = c.clear_before.filter(|cb| cb.is_finite() && *cb > self.root.lo[t]).map(f64::next_down);
        let (best, _, window) = bisect(c, at, proved, &mut |from, mid| {
            let mut capped = self.root.clone();
            if mid < capped.lo[t] || mid.is_nan() {
                return Step::Undecided("the time asked about is before the motion's start".to_string());
            }
            capped.hi[t] = mid.min(capped.hi[t]);
            // Only the times after those already proved apart: `[from, mid]`.
            capped.lo[t] = from.clamp(capped.lo[t], capped.hi[t]);
            if left == 0 {
                return Step::Undecided(format!("the window's budget of {budget} boxes was spent"));
            }
            step_opts.max_nodes = left;
            let v = bnb::decide(self, &capped, &step_opts);
            left = left.saturating_sub(v.stats.nodes);
            match v.outcome {
                // Every box proved apart or infeasible: no contact the constraints allow.
                bnb::Outcome::Apart { .. } => Step::Apart,
                bnb::Outcome::Contact(c) => {
                    let at = c.q.get(t).copied().unwrap_or(f64::NAN);
                    Step::Contact(c, at)
                }
                bnb::Outcome::Unknown { why, .. } => Step::Undecided(match why {
                    bnb::UnknownWhy::Resolution => {
                        "boxes at the search's resolution touch or are too close to call".into()
                    }
                    bnb::UnknownWhy::Nodes(_) => format!("the window's budget of {budget} boxes was spent"),
                    bnb::UnknownWhy::Deadline => "the time limit was reached (raise it with --timeout)".into(),
                    bnb::UnknownWhy::BadBox => "the search box is malformed".into(),
                }),
            }
        });
        (best, window)
    }
}

/// A time as the report shows it (five significant digits).
fn short(t: f64) -> String {
    let s = format!("{t:.5}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contact exists exactly from `first` s on: a step is apart below it and finds a
    /// contact at `mid` otherwise (the least time it may show).
    fn from(first: f64) -> impl FnMut(f64, f64) -> Step<f64> {
        move |_, mid| if mid < first { Step::Apart } else { Step::Contact(mid, first.max(mid / 2.0)) }
    }

    #[test]
    fn the_window_holds_the_first_contact_and_narrows_to_one_percent() {
        let (_, t, w) = bisect(10.0, 10.0, None, &mut from(3.45));
        let lo = w.not_before.expect("a proved bound");
        assert!(lo < 3.45 && 3.45 <= t, "[{lo}, {t}]");
        assert!(w.open.is_none());
        // Eight steps from 10 s: the window is at most 10 / 2^7 wide.
        assert!(t - lo <= 10.0 / 128.0, "[{lo}, {t}]");
    }

    /// Each step searches only the times after those proved apart (the window's lower end,
    /// or the deciding search's own bound), never the start again: the steps' slabs
    /// `[from, mid]` do not overlap, and with a proved bound nothing before it is asked.
    #[test]
    fn a_step_never_searches_times_already_proved_apart() {
        let mut asked = Vec::new();
        let (_, t, w) = bisect(10.0, 10.0, None, &mut |a, mid| {
            asked.push((a, mid));
            from(3.45)(a, mid)
        });
        assert!(w.not_before.is_some_and(|lo| lo < 3.45 && 3.45 <= t), "{w:?}");
        assert_eq!(asked[0], (0.0, 0.0));
        // Each slab starts where the latest apart step ended (here: apart below 3.45 s), so
        // no time proved apart is searched again.
        for k in 1..asked.len() {
            let proved = asked[..k].iter().map(|(_, m)| *m).filter(|m| *m < 3.45).fold(0.0, f64::max);
            assert_eq!(asked[k].0, proved, "{asked:?}");
        }
        let mut asked = Vec::new();
        let (_, t, w) = bisect(10.0, 10.0, Some(3.0), &mut |a, mid| {
            asked.push((a, mid));
            from(3.45)(a, mid)
        });
        assert!(asked.iter().all(|(a, mid)| *a >= 3.0 && *mid > 3.0), "{asked:?}");
        assert!(w.not_before.is_some_and(|lo| (3.0..3.45).contains(&lo)) && 3.45 <= t, "{w:?}");
        assert!(t - w.not_before.unwrap_or(0.0) <= 0.01 * t + 7.0 / 128.0, "{w:?}");
    }

    #[test]
    fn an_undecided_step_keeps_what_was_proved_and_says_why() {
        let mut calls = 0;
        let (_, t, w) = bisect(8.0, 8.0, None, &mut |_, mid| {
            calls += 1;
            if mid == 0.0 {
                Step::<f64>::Apart
            } else {
                Step::Undecided("out of boxes".into())
            }
        });
        assert_eq!((t, w.not_before, calls), (8.0, Some(0.0), 2));
        assert!(w.open.as_deref().is_some_and(|o| o.contains("4 s") && o.contains("out of boxes")), "{w:?}");
        // Nothing proved: no bound, and why.
        let (_, _, w) = bisect(8.0, 8.0, None, &mut |_, _| Step::<f64>::Undecided("time limit".into()));
        assert!(w.not_before.is_none() && w.open.is_some());
    }

    /// choreographies/rejected/geometry/E0510-bridge-lowered.chor: by hand (its header),
    /// the cart's front face first reaches the lowered deck at t = (1.0 - 0.31) / 0.2 =
    /// 3.45 s; the geometric search's first contact is later (6 s, where it meets the deck
    /// best first), and the window must hold 3.45 s and be narrow.
    #[test]
    fn the_geometric_window_holds_the_bridges_first_contact_by_hand() {
        use crate::driver::Config;
        let src = include_str!("../../../../choreographies/rejected/geometry/E0510-bridge-lowered.chor");
        let path = crate::testing::repo("choreographies/rejected/geometry/E0510-bridge-lowered.chor");
        let mut db = crate::source::SourceDb::new();
        let r = crate::fsload::check_source(&mut db, &path.display().to_string(), src, &Config::patient());
        let d = r.diagnostics.iter().find(|d| d.code == crate::diag::Code::ObstacleHit).expect("E0510");
        let o = d.counterexample.as_deref().and_then(|c| c.overlap.clone()).expect("a contact");
        let (lo, t) = (o.not_before.expect("a proved bound"), o.times[0]);
        assert!(lo < 3.45 && 3.45 <= t + 1e-9, "window [{lo}, {t}]: {o:?}");
        assert!(t - lo <= 0.05 * t, "window [{lo}, {t}] wider than 5 %: {o:?}");
    }

    #[test]
    fn a_contact_at_the_start_is_the_earliest_and_a_bad_time_is_never_taken() {
        let (_, t, w) = bisect(5.0, 5.0, None, &mut |_, _| Step::Contact(0.0, 0.0));
        assert_eq!((t, w.not_before, w.open), (0.0, None, None));
        let (_, t, w) = bisect(5.0, 5.0, None, &mut |_, mid| Step::Contact(mid + 1.0, mid + 1.0));
        assert_eq!(t, 5.0);
        assert!(w.open.is_some());
        let (_, _, w) = bisect(5.0, f64::NAN, None, &mut |_, _| -> Step<f64> { panic!("not asked") });
        assert!(w.open.is_some());
    }
}
