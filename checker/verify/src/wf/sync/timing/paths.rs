//! The paths of the once-unfolded tree through a segment, read one at a time, and the
//! points where a path may be cut into segments.

use super::*;

/// Past this many paths through the choices of one segment (see [`Checker::timing`]) the
/// timing checks give up with an error.
pub(super) const MAX_PATHS: usize = 4096;

/// The paths of the once-unfolded tree through the events `range`, one after the other:
/// `visit` gets, for each, the events on it in tree order and the branch it takes at each
/// choice it meets. Returns `false` (before visiting any) if there are more than `limit`.
///
/// A first pass only counts (the decision depends on the counts alone), so that the paths
/// are then visited as they are found rather than all held at once (4,096 copies of a long
/// sequence took gigabytes).
pub(super) fn paths(
    ev: &[Event],
    range: std::ops::Range<usize>,
    branches: &HashMap<u32, u32>,
    limit: usize,
    mut visit: impl FnMut(&[usize], &HashMap<u32, u32>),
) -> bool {
    walk_paths(ev, range.clone(), branches, limit, None) && walk_paths(ev, range, branches, limit, Some(&mut visit))
}

/// What [`paths`] calls on each path.
pub(super) type Visit<'v> = &'v mut dyn FnMut(&[usize], &HashMap<u32, u32>);

#[cfg(test)]
thread_local! {
    /// Events stepped over by [`walk_paths`] on this thread: the tests' measure of the work
    /// the timing checks do, which no machine's load changes.
    pub(in crate::wf::sync) static STEPS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// One pass of [`paths`]; without `visit`, only the count is checked.
pub(super) fn walk_paths(
    ev: &[Event],
    range: std::ops::Range<usize>,
    branches: &HashMap<u32, u32>,
    limit: usize,
    mut visit: Option<Visit>,
) -> bool {
    let keep = visit.is_some();
    let mut done = 0usize;
    let mut work: Vec<(HashMap<u32, u32>, Vec<usize>, usize)> = vec![(HashMap::new(), Vec::new(), range.start)];
    while let Some((mut assign, mut list, mut i)) = work.pop() {
        'ev: while i < range.end {
            #[cfg(test)]
            STEPS.with(|s| s.set(s.get() + 1));
            for &(node, b, choice) in &ev[i].path {
                if !choice {
                    continue;
                }
                let taken = match assign.get(&node) {
                    Some(&x) => x,
                    None => {
                        let n = branches.get(&node).copied().unwrap_or(1);
                        if done + work.len() + n as usize > limit {
                            return false;
                        }
                        for k in 1..n {
                            let mut a = assign.clone();
                            a.insert(node, k);
                            work.push((a, if keep { list.clone() } else { Vec::new() }, i));
                        }
                        assign.insert(node, 0);
                        0
                    }
                };
                if taken != b {
                    i += 1;
                    continue 'ev;
                }
            }
            if keep {
                list.push(i);
            }
            i += 1;
        }
        done += 1;
        if let Some(f) = visit.as_mut() {
            f(&list, &assign);
        }
    }
    true
}

/// What the timing checks need of the tree besides its events (from [`Builder`]).
pub(in crate::wf::sync) struct Layout<'b> {
    /// Number of branches of each choice node.
    pub(in crate::wf::sync) branches: &'b HashMap<u32, u32>,
    /// The internal nodes above each `end`.
    pub(in crate::wf::sync) ends: &'b [Vec<(u32, u32, bool)>],
    /// The `*` nodes.
    pub(in crate::wf::sync) pars: &'b HashSet<u32>,
    /// How many events precede the first `end`.
    pub(in crate::wf::sync) first_end: usize,
}

/// Where the paths may be cut: before the first event of a choice whose enclosing nodes are
/// all sequences (no choice or `*` has events on both sides of the cut), and before any
/// `end` (a path goes on past the cut). Ascending, each in `1..ev.len()`.
pub(super) fn cut_points(ev: &[Event], layout: &Layout) -> Vec<usize> {
    let mut cuts = Vec::new();
    for (i, e) in ev.iter().enumerate().skip(1) {
        if i >= layout.first_end {
            break;
        }
        // The outermost choice or `*` above the event, if any.
        let Some(k) = e.path.iter().position(|(n, _, choice)| *choice || layout.pars.contains(n)) else {
            continue;
        };
        let (node, _, choice) = e.path[k];
        let first_of_node = !ev[i - 1].path.iter().any(|(n, _, _)| *n == node);
        if choice && first_of_node {
            cuts.push(i);
        }
    }
    cuts
}
