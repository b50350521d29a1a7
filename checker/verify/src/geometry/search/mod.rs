//! The geometric search: branch and bound over boxes of configurations ([`bnb`], the
//! engine, with parry's certified distances), and the collision questions of the checks
//! posed to it ([`checks`]: the scene of a joint motion's footprints, a static obstacle,
//! the runs of a separation, the initial states; the clearance report). It does not use
//! the SMT solver; it asks it for witnesses through the narrow functions of
//! `smt::goals::geo`. docs/soundness-geometry.md has the arguments.

pub mod bnb;
