//! A `pose(x, y, z, roll, pitch, yaw)` frame whose arguments read the configuration,
//! compiled once per question ([`crate::bounds::compiled`]): every box evaluates each
//! argument twice, over the box and at its centre. The enclosures are those of
//! [`crate::bounds::eval`] for the same ranges, so the frame bounds
//! ([`crate::geometry::placement::FrameBound::pose`]) are unchanged.

use super::contract::Leaf;
use crate::bounds::compiled::{Compiled, VarTable};
use crate::bounds::Interval;
use crate::geometry::placement::{ArgBounds, FrameBound};
use crate::geometry::{self, Pose3};
use crate::hir::body::Pose;
use crate::hir::{Program, Var};

pub(super) struct CompiledPose {
    args: Vec<Compiled>,
    leaves: Vec<Leaf>,
}

impl CompiledPose {
    /// `leaf(v)`: where the range of variable `v` comes from.
    pub(super) fn new(prog: &Program, pose: &Pose, leaf: &dyn Fn(&Var) -> Leaf) -> CompiledPose {
        let mut table = VarTable::new();
        let args = pose.args.iter().map(|e| Compiled::new(prog, e, &mut table)).collect();
        let leaves = table.vars().iter().map(leaf).collect();
        CompiledPose { args, leaves }
    }

    /// The frame at the centre `c` of the box `[lo, hi]` and its bound over the box;
    /// `None` if an argument cannot be bounded.
    pub(super) fn frame(
        &self,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
        stack: &mut Vec<Option<Interval>>,
    ) -> Option<(Pose3, FrameBound)> {
        let env = |lo: &[f64], hi: &[f64]| -> Vec<Option<Interval>> {
            self.leaves
                .iter()
                .map(|l| match *l {
                    Leaf::Dim(i) => Some(Interval::new(lo[i], hi[i])),
                    Leaf::Fixed(iv) => iv,
                })
                .collect()
        };
        let (over, at) = (env(lo, hi), env(c, c));
        let mut ab = ArgBounds::fixed([0.0; 6]);
        for (k, e) in self.args.iter().enumerate() {
            let box_iv = e.eval(&over, stack)?;
            let mid = e.eval(&at, stack)?;
            ab.lo[k] = box_iv.lo;
            ab.hi[k] = box_iv.hi;
            ab.centre[k] = mid.lo / 2.0 + mid.hi / 2.0;
        }
        Some((geometry::pose6(ab.centre), FrameBound::pose(&ab)))
    }
}
