//! What a simulation found, in the user's terms.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Two footprints (or bodies, or a body and an obstacle) share a point.
    Collision,
    /// No step is possible and the protocol has not ended.
    Stuck,
    /// A guard, refinement or precondition is false where the type says it holds; a
    /// robot's body outside its footprint; a participant reading a value it does not know.
    Violation,
    /// A model that does not satisfy its own constraints when replayed exactly: a bug.
    Replay,
    /// Something the simulator could not decide (a timeout, an unsupported construct, an
    /// enclosure on both sides of a boundary); the run stops there. Not a failure of the
    /// choreography, and not a clean run either.
    Undecided,
}

/// One thing found, in the user's terms.
#[derive(Clone, Debug, Serialize)]
pub struct Finding {
    pub kind: Kind,
    pub run: usize,
    pub step: usize,
    /// Global time (seconds since the start), as a decimal.
    pub time: String,
    pub message: String,
    /// The events of the run up to the finding, one per line.
    pub trace: Vec<String>,
}

/// A message a run of a protocol without motion sent: for tests that replay runs elsewhere
/// (the run-time monitor's agreement with the static checks, `tests/monitor.rs`).
#[derive(Clone, Debug)]
pub struct SimMessage {
    pub from: crate::hir::RoleId,
    pub to: crate::hir::RoleId,
    pub label: String,
    /// Per payload field: its value id, its MAVLink field (`None` without a dialect), its
    /// refinement as the sender's local type states it, and the value sent.
    pub fields: Vec<(crate::hir::ValueId, Option<String>, Option<crate::hir::Expr>, crate::exact::Value)>,
    /// The values the sender had when it sent (recursion parameters included).
    pub known: Vec<(crate::hir::ValueId, crate::exact::Value)>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct SimReport {
    pub runs: usize,
    /// Messages and motions simulated, over all runs.
    pub steps: usize,
    pub queries: usize,
    pub findings: Vec<Finding>,
    /// Per run, the messages sent (protocols without motion only; not part of the output).
    #[serde(skip)]
    pub messages: Vec<Vec<SimMessage>>,
}

impl SimReport {
    /// Collisions, stuck states, violations and replay failures (not undecided runs).
    pub fn failures(&self) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(|f| f.kind != Kind::Undecided)
    }

    /// Runs that stopped undecided.
    pub fn undecided(&self) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(|f| f.kind == Kind::Undecided)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn finding(kind: Kind) -> Finding {
        Finding { kind, run: 0, step: 1, time: "0".into(), message: String::new(), trace: Vec::new() }
    }

    #[test]
    fn undecided_runs_are_not_failures_and_not_hidden() {
        let r = SimReport {
            runs: 2,
            steps: 3,
            queries: 0,
            findings: vec![finding(Kind::Undecided), finding(Kind::Collision)],
            messages: Vec::new(),
        };
        assert_eq!(r.failures().count(), 1);
        assert_eq!(r.failures().next().map(|f| f.kind), Some(Kind::Collision));
        assert_eq!(r.undecided().count(), 1);
    }
}
