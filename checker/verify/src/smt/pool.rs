//! The worker pool of the SMT stage and the hard limit on a query's time.
//!
//! Each worker is a thread with its own Z3 context (the `z3` crate's thread-local
//! context) and a [`Watchdog`] that interrupts the context when a query runs past its
//! limit. That is the first guard; Z3's own `timeout` parameter is not used (it deadlocks
//! on 4.8.12, see [`Watchdog`]).
//!
//! `Z3_interrupt` only sets a flag that Z3 polls, and some of its procedures (nonlinear
//! real arithmetic on turned boxes was seen) go for minutes without polling. The second
//! guard does not depend on Z3: the thread that called [`run`] watches every worker, and
//! when a query is still running [`grace`] after its limit, it *abandons* the worker: the
//! obligation the worker was deciding becomes unknown ([`Why::Abandoned`]), a replacement
//! worker takes over the remaining obligations, and the abandoned thread is detached. It
//! owns its Z3 context and everything it reads (the pool is reference-counted), so nothing
//! it touches is freed under it; if Z3 ever returns, the worker sees it was abandoned,
//! drops its answer and ends. Otherwise it runs until the process exits (the binary
//! never joins it).
//!
//! Soundness: an abandoned obligation is unknown, and unknown is never a pass; the answer
//! it would have given is never used. Costs: the abandoned context's memory and the CPU
//! the runaway thread takes until the process exits. So at most [`MAX_ABANDONED`] workers
//! are abandoned in one run; after that the obligations not yet started are unknown
//! without running ([`Why::NotRun`]).

use super::{Decision, SmtConfig, Stats, Why};
use crate::hir::Program;
use crate::obligation::Obligation;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Abandoned workers still running (in Z3) at once, in one [`run`], before the rest of its
/// obligations are given up. One that stops later (Z3 noticed the interrupt after all)
/// no longer counts.
pub const MAX_ABANDONED: usize = 2;

/// How long past its limit a query may run before its worker is abandoned: a fifth of the
/// limit, between 1 and 10 s. Z3 normally notices an interrupt within milliseconds, but a
/// separation query between two turning boxes (ARCHITECTURE.md, "The time limit holds")
/// took 2.9 s to stop after a 30 s limit: the grace leaves room for that.
pub fn grace(limit: Duration) -> Duration {
    (limit / 5).clamp(Duration::from_secs(1), Duration::from_secs(10))
}

/// Interrupts the worker's Z3 context when a query runs past its deadline.
///
/// Z3's own `timeout` parameter is not used: in Z3 4.8.10-4.8.12 (Debian's libz3 is
/// 4.8.12) its thread-pool `scoped_timer` can deadlock (Z3Prover/z3 PR #5371, fixed
/// after 4.8.12); we saw `check()` hang forever with a 1 ms timeout. `Z3_interrupt` on
/// the context needs no timer thread of Z3's. One watchdog thread serves all of a
/// worker's queries (starting a thread per query cost more than most queries).
#[derive(Default)]
pub struct Watchdog {
    state: Mutex<WatchState>,
    wake: Condvar,
}

#[derive(Default)]
struct WatchState {
    /// The running query's number and when to interrupt it next.
    armed: Option<(u64, Instant)>,
    /// The running query's limit (unlike `armed`, not moved on by re-interrupts).
    limit_at: Option<Instant>,
    /// Queries that were interrupted.
    fired: Option<u64>,
    seq: u64,
    stop: bool,
}

impl Watchdog {
    pub fn run(&self, handle: z3::ContextHandle) {
        let Ok(mut st) = self.state.lock() else { return };
        loop {
            if st.stop {
                return;
            }
            match st.armed {
                None => {
                    st = match self.wake.wait(st) {
                        Ok(g) => g,
                        Err(_) => return,
                    };
                }
                Some((seq, deadline)) => {
                    let now = Instant::now();
                    if now >= deadline {
                        // An interrupt that lands before Z3 has entered the check is
                        // lost (Z3 clears the flag when a check starts), so keep
                        // interrupting every 10 ms until the worker disarms.
                        handle.interrupt();
                        st.fired = Some(seq);
                        st.armed = Some((seq, now + Duration::from_millis(10)));
                        continue;
                    }
                    st = match self.wake.wait_timeout(st, deadline - now) {
                        Ok((g, _)) => g,
                        Err(_) => return,
                    };
                }
            }
        }
    }

    pub fn arm(&self, timeout: Duration) -> u64 {
        let Ok(mut st) = self.state.lock() else { return 0 };
        st.seq += 1;
        let at = Instant::now() + timeout;
        st.armed = Some((st.seq, at));
        st.limit_at = Some(at);
        self.wake.notify_all();
        st.seq
    }

    /// Disarms; whether the query `seq` was interrupted.
    pub fn disarm(&self, seq: u64) -> bool {
        let Ok(mut st) = self.state.lock() else { return false };
        st.armed = None;
        st.limit_at = None;
        st.fired == Some(seq)
    }

    pub fn stop(&self) {
        if let Ok(mut st) = self.state.lock() {
            st.stop = true;
        }
        self.wake.notify_all();
    }

    /// The limit of the query running now, if one is.
    fn limit_at(&self) -> Option<Instant> {
        self.state.lock().ok().and_then(|st| st.limit_at)
    }
}

/// What [`run`] hands to each worker thread: everything it reads, owned, so that an
/// abandoned worker never reads freed memory.
pub struct Shared<W> {
    pub prog: Program,
    pub obligations: Vec<Obligation>,
    pub labels: Vec<String>,
    pub cfg: SmtConfig,
    /// State the workers share (caches), beside the pool's own.
    pub extra: W,
    /// Whether [`run`] reports each decision (it is then woken for each).
    each: bool,
    pool: Mutex<PoolState>,
    changed: Condvar,
}

struct PoolState {
    results: Vec<Option<(Decision, Stats)>>,
    decided: usize,
    /// The next obligation no worker has taken.
    next: usize,
    slots: Vec<Slot>,
    abandoned: usize,
    /// Set once [`MAX_ABANDONED`] workers were abandoned: no obligation is started after.
    given_up: bool,
}

struct Slot {
    watchdog: Arc<Watchdog>,
    /// The obligation the worker is deciding.
    current: Option<usize>,
    abandoned: bool,
    /// The thread (`None` if it could not start). An abandoned one is never joined; its
    /// handle only says whether it still runs.
    thread: Option<std::thread::JoinHandle<()>>,
}

/// One worker's view of the pool.
pub struct Lease<'a, W> {
    pub shared: &'a Shared<W>,
    pub watchdog: &'a Watchdog,
    slot: usize,
}

impl<W> Lease<'_, W> {
    /// The next obligation to decide, or `None` when there is none or this worker was
    /// abandoned.
    pub fn take(&self) -> Option<usize> {
        let mut st = self.shared.lock();
        if st.slots[self.slot].abandoned || st.given_up || st.next >= st.results.len() {
            return None;
        }
        let i = st.next;
        st.next += 1;
        st.slots[self.slot].current = Some(i);
        Some(i)
    }

    /// Records the decision on obligation `i` (dropped if this worker was abandoned: the
    /// obligation is already unknown).
    pub fn finish(&self, i: usize, result: (Decision, Stats)) {
        let mut st = self.shared.lock();
        let abandoned = st.slots[self.slot].abandoned;
        st.slots[self.slot].current = None;
        if !abandoned && st.results[i].is_none() {
            st.results[i] = Some(result);
            st.decided += 1;
        }
        // The pool needs waking for progress, and when all are decided; otherwise it
        // wakes on its own for the next limit (a wake per obligation costs on big runs).
        let wake = self.shared.each || st.decided == st.results.len();
        drop(st);
        if wake {
            self.shared.changed.notify_all();
        }
    }
}

impl<W> Shared<W> {
    fn lock(&self) -> MutexGuard<'_, PoolState> {
        // A worker that panicked while holding the lock leaves the state consistent
        // (every update is a single step): keep using it.
        self.pool.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Test hook: a query whose dump label contains this text makes its worker hang inside
/// its armed query, as if Z3 ignored the interrupt, until [`release_hung`] is called.
#[cfg(test)]
pub static HANG: Mutex<Option<String>> = Mutex::new(None);
#[cfg(test)]
static RELEASED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

#[cfg(test)]
pub fn release_hung() {
    RELEASED.store(true, std::sync::atomic::Ordering::SeqCst);
}

/// Called by a worker between arming its watchdog and asking Z3 (tests only): hangs,
/// deaf to the watchdog, if the hook names this query.
#[cfg(test)]
pub fn maybe_hang(label: &str) {
    let hang = HANG.lock().ok().and_then(|h| h.clone()).is_some_and(|h| label.contains(&h));
    while hang && !RELEASED.load(std::sync::atomic::Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Decides every obligation on `jobs` worker threads, each running `work` (which takes
/// obligations from its [`Lease`] until there are none), and abandons any worker whose
/// query outlives its limit by [`grace`]. Returns one result per obligation.
pub fn run<W: Send + Sync + 'static>(
    shared: Shared<W>,
    jobs: usize,
    work: fn(&Lease<W>),
    on_decided: &dyn Fn(usize, usize),
) -> Vec<(Decision, Stats)> {
    let n = shared.obligations.len();
    let limit = shared.cfg.timeout;
    let grace = grace(limit);
    let shared = Arc::new(shared);
    let mut st = shared.lock();
    for _ in 0..jobs {
        spawn(&shared, &mut st, work);
    }
    let mut reported = 0;
    loop {
        if st.decided > reported {
            reported = st.decided;
            // Progress is reported without the lock held.
            drop(st);
            on_decided(reported, n);
            st = shared.lock();
            continue;
        }
        if st.decided == n {
            break;
        }
        // A worker that died (a panic: a bug) leaves its obligation unknown; another
        // takes its place, within the same cap as abandoned ones.
        for k in 0..st.slots.len() {
            let dead = !st.slots[k].abandoned && st.slots[k].thread.as_ref().is_some_and(|t| t.is_finished());
            let Some(i) = st.slots[k].current.filter(|_| dead) else { continue };
            st.slots[k].current = None;
            if st.results[i].is_none() {
                let why = Why::Incomplete(
                    "its worker thread stopped (please report this as a bug in mochi)".into(),
                    Default::default(),
                );
                st.results[i] = Some((Decision::Unknown { part: String::new(), why }, Stats::default()));
                st.decided += 1;
            }
            st.abandoned += 1;
            if st.abandoned >= MAX_ABANDONED {
                st.given_up = true;
            } else {
                spawn(&shared, &mut st, work);
            }
        }
        let live =
            st.slots.iter().filter(|s| !s.abandoned && s.thread.as_ref().is_some_and(|t| !t.is_finished())).count();
        // Obligations nobody will take: after the cap, or with no worker left.
        if (st.given_up || live == 0) && st.decided < n {
            let why = if st.given_up {
                Why::NotRun(format!(
                    "{} worker thread(s) were abandoned after Z3 did not stop when interrupted",
                    st.abandoned
                ))
            } else {
                Why::NotRun("no worker thread could be started".into())
            };
            let from = if live == 0 { 0 } else { st.next };
            let mut filled = 0;
            for r in st.results[from..].iter_mut().filter(|r| r.is_none()) {
                *r = Some((Decision::Unknown { part: String::new(), why: why.clone() }, Stats::default()));
                filled += 1;
            }
            st.decided += filled;
            st.next = n;
            if filled > 0 {
                continue;
            }
        }
        // Abandon the workers whose query is past its limit and grace.
        let now = Instant::now();
        let mut wake = now + limit + grace;
        for k in 0..st.slots.len() {
            let slot = &st.slots[k];
            let (Some(i), false) = (slot.current, slot.abandoned) else { continue };
            let Some(at) = slot.watchdog.limit_at() else { continue };
            if now < at + grace {
                wake = wake.min(at + grace);
                continue;
            }
            let slot = &mut st.slots[k];
            slot.abandoned = true;
            slot.current = None;
            st.abandoned += 1;
            let after = now.saturating_duration_since(at) + limit;
            if st.results[i].is_none() {
                st.results[i] = Some((
                    Decision::Unknown { part: String::new(), why: Why::Abandoned(after) },
                    Stats { millis: after.as_secs_f64() * 1000.0, ..Stats::default() },
                ));
                st.decided += 1;
            }
            // The thread is never joined; it counts against the cap while it runs.
            let runaway =
                st.slots.iter().filter(|s| s.abandoned && s.thread.as_ref().is_some_and(|t| !t.is_finished())).count();
            if runaway >= MAX_ABANDONED {
                st.given_up = true;
            } else {
                spawn(&shared, &mut st, work);
            }
        }
        if st.decided > reported || (st.given_up && st.next < n) {
            continue;
        }
        let wait = wake.saturating_duration_since(Instant::now()).max(Duration::from_millis(1));
        st = match shared.changed.wait_timeout(st, wait) {
            Ok((g, _)) => g,
            Err(e) => e.into_inner().0,
        };
    }
    // Every obligation is decided: the live workers are idle or leaving; join them so
    // that their Z3 contexts are freed now. Abandoned ones stay detached.
    let threads: Vec<_> = st.slots.iter_mut().filter(|s| !s.abandoned).filter_map(|s| s.thread.take()).collect();
    let results = std::mem::take(&mut st.results);
    drop(st);
    for t in threads {
        let _ = t.join();
    }
    results
        .into_iter()
        .map(|r| {
            r.unwrap_or((
                Decision::Unknown {
                    part: String::new(),
                    why: Why::Incomplete("a worker thread stopped".into(), Default::default()),
                },
                Stats::default(),
            ))
        })
        .collect()
}

/// Starts a worker on a new slot (if the thread cannot start, the slot stays empty).
fn spawn<W: Send + Sync + 'static>(shared: &Arc<Shared<W>>, st: &mut PoolState, work: fn(&Lease<W>)) {
    let slot = st.slots.len();
    let watchdog = Arc::new(Watchdog::default());
    let (sh, wd) = (Arc::clone(shared), Arc::clone(&watchdog));
    let thread = std::thread::Builder::new().name(format!("mochi-smt-{slot}")).spawn(move || {
        let ctx = z3::Context::thread_local();
        let handle = ctx.handle();
        // However the worker ends (normally or by a panic), its watchdog stops and the
        // pool wakes up to see it.
        struct Leave<'w, W>(&'w Watchdog, &'w Shared<W>);
        impl<W> Drop for Leave<'_, W> {
            fn drop(&mut self) {
                self.0.stop();
                self.1.changed.notify_all();
            }
        }
        std::thread::scope(|s| {
            s.spawn(|| wd.run(handle));
            let _leave = Leave(&wd, &sh);
            work(&Lease { shared: &sh, watchdog: &wd, slot });
        });
    });
    st.slots.push(Slot { watchdog, current: None, abandoned: false, thread: thread.ok() });
}

impl<W> Shared<W> {
    pub fn new(prog: Program, obligations: Vec<Obligation>, labels: Vec<String>, cfg: SmtConfig, extra: W) -> Self {
        let n = obligations.len();
        Shared {
            each: cfg.on_progress.is_some(),
            prog,
            obligations,
            labels,
            cfg,
            extra,
            pool: Mutex::new(PoolState {
                results: vec![None; n],
                decided: 0,
                next: 0,
                slots: Vec::new(),
                abandoned: 0,
                given_up: false,
            }),
            changed: Condvar::new(),
        }
    }
}
