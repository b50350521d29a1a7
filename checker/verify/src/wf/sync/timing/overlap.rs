//! E0318: two parts of different participants that may run at the same time with nothing
//! comparing their footprints.

use super::*;

impl Checker<'_, '_> {
    /// E0318: two parts of different participants that may run at the same time and that
    /// neither [AGCOMP] (one dt) nor a separation obligation (two sides of one `*`) covers.
    pub(super) fn overlaps(&mut self, parts: &[MotionPart], inst: &Instants, ends_here: bool) {
        // Parts of one dt are compared by [AGCOMP] while all of them run (its query bounds
        // the time by every part's duration and assumes every guarantee). Two interruptible
        // parts that run on after the motion ends (left later, or never before `end`) are
        // not compared after that when a third part bounds the query.
        let overruns = |p: &MotionPart| {
            self.prog.prim(p.app.prim).interruptible
                && match p.left {
                    Some(l) => !inst.same(l, p.end_of_motion),
                    None => ends_here,
                }
        };
        // A part bounds the query in time when its duration has an upper bound or its
        // guarantee reads the clock (its other variables are its own, fresh at each time).
        let bounds_time = |p: &MotionPart| {
            let prim = self.prog.prim(p.app.prim);
            let mut clock = false;
            prim.guarantee.visit_vars(&mut |v, _| clock |= matches!(v, Var::Clock));
            prim.duration.hi.is_some() || clock
        };
        let mut together: std::collections::BTreeMap<usize, Vec<String>> = std::collections::BTreeMap::new();
        // The parts of one motion are pushed together: `same[i]` is the range of `i`'s.
        let mut same: Vec<std::ops::Range<usize>> = Vec::with_capacity(parts.len());
        let mut lo = 0;
        for i in 0..parts.len() {
            if i + 1 == parts.len() || parts[i + 1].ev != parts[i].ev {
                same.extend(std::iter::repeat_n(lo..i + 1, i + 1 - lo));
                lo = i + 1;
            }
        }
        // Each part's two properties, and per motion (by its first part) how many parts
        // bound the time, computed once: the pairs of a wide dt are many.
        let over: Vec<bool> = parts.iter().map(overruns).collect();
        let bt: Vec<usize> = parts.iter().map(|p| usize::from(bounds_time(p))).collect();
        let mut bounding_of: HashMap<usize, usize> = HashMap::new();
        for (i, x) in parts.iter().enumerate() {
            if !over[i] {
                continue;
            }
            let mine = same[i].clone();
            // Whether a third part bounds the time: count them once per motion.
            let bounding = *bounding_of.entry(mine.start).or_insert_with(|| bt[mine.clone()].iter().sum());
            // A pair with `x` needs bounding > bt(x) + bt(y) >= bt(x): none without.
            if bounding <= bt[i] {
                continue;
            }
            for (j, y) in parts.iter().enumerate().take(mine.end).skip(i + 1).filter(|(j, y)| y.ev == x.ev && over[*j])
            {
                let bounded = bounding > bt[i] + bt[j];
                if bounded {
                    together.entry(x.ev).or_default().push(format!(
                        "`{}` with `{}`",
                        self.part_name(x),
                        self.part_name(y)
                    ));
                }
            }
        }
        for (e, pairs) in together {
            let d = Diagnostic::error(
                Code::UncheckedOverlap,
                self.ev[e].loc().0,
                format!(
                    "some primitives of this motion may run on together after the others stop, and no check compares them then: {}",
                    pairs.join(", ")
                ),
            )
            .with_note("they are interrupted later than the motion ends (or not before `end`); [AGCOMP] compares the footprints of a dt only while all its primitives run")
            .with_help("interrupt them in the burst of messages that ends the motion, or give them a dt (or `*` sides) of their own");
            self.push(d);
        }

        // A part that does not run on (non-interruptible, or left when the motion ends)
        // leaves its participant standing still, outside any motion, at its last state; a
        // part of the same dt that runs on is compared with it by [AGCOMP] only as long as
        // some other part bounds the query's time. After that the standing body is seen by
        // no check, unless the part running on stays where it started (its footprint is
        // then the one [AGCOMP] compared up to the end).
        let mut standing: Vec<(usize, String, String)> = Vec::new();
        // Per motion (by its first part): whether some part of it stops with it, computed
        // once, so that a wide dt whose parts all run on costs one pass.
        let mut stops: HashMap<usize, bool> = HashMap::new();
        for (j, y) in parts.iter().enumerate() {
            let mine = same[j].clone();
            if !over[j] || !*stops.entry(mine.start).or_insert_with(|| mine.clone().any(|i| !over[i])) {
                continue;
            }
            let carrier_still = |c: RoleId| {
                parts[mine.clone()]
                    .iter()
                    .zip(&over[mine.clone()])
                    .any(|(p, o)| p.role == c && (!o || stationary(self.prog, self.prog.prim(p.app.prim))))
            };
            if stays_in_place(self.prog, y.role, self.prog.prim(y.app.prim), &carrier_still) {
                continue;
            }
            let bounding = *bounding_of.entry(mine.start).or_insert_with(|| bt[mine.clone()].iter().sum());
            if bounding <= bt[j] {
                continue;
            }
            for (i, x) in parts.iter().enumerate().take(mine.end).skip(mine.start) {
                if i != j && !over[i] && x.role != y.role && !attached(self.prog, x.role, y.role) {
                    standing.push((y.ev, self.part_name(y), self.prog.role_name(x.role).to_string()));
                }
            }
        }
        for (e, y, x) in standing {
            let d = stands_still(self.ev[e].loc().0, &y, &x);
            self.push(d);
        }

        // Group by enclosing `*` sides: whether a pair is covered depends only on them.
        let mut groups: Vec<(Sides, Vec<usize>)> = Vec::new();
        let mut index: HashMap<&[(usize, u32)], usize> = HashMap::new();
        for (i, p) in parts.iter().enumerate() {
            let sig: &[(usize, u32)] = &self.ev[p.ev].pars;
            let g = *index.entry(sig).or_insert_with(|| {
                groups.push((sig, Vec::new()));
                groups.len() - 1
            });
            groups[g].1.push(i);
        }
        let before = |x: &MotionPart, y: &MotionPart| x.left.is_some_and(|l| inst.le(l, y.start));
        // Each part's group and position in it, and each group's uncovered groups.
        let mut slot = vec![(0, 0); parts.len()];
        for (g, (_, members)) in groups.iter().enumerate() {
            for (k, &i) in members.iter().enumerate() {
                slot[i] = (g, k);
            }
        }
        let open: Vec<Vec<usize>> =
            groups.iter().map(|(a, _)| (0..groups.len()).filter(|&h| !covered(a, groups[h].0)).collect()).collect();
        // Sweep the parts in order, each against the earlier ones of uncovered groups not
        // retired before it (a retired part is before every later one).
        let mut live: Vec<Vec<usize>> = vec![Vec::new(); groups.len()];
        // (Sort key: groups then positions of the two parts; the two parts.)
        type Hit = ((usize, usize, usize, usize), usize, usize);
        let mut hits: Vec<Hit> = Vec::new();
        for (b, y) in parts.iter().enumerate() {
            let (gb, kb) = slot[b];
            for &g in &open[gb] {
                live[g].retain(|&a| parts[a].retired > b);
                for &a in &live[g] {
                    let x = &parts[a];
                    if x.role == y.role || x.ev == y.ev || before(x, y) || before(y, x) {
                        continue;
                    }
                    // The order of an all-pairs loop: groups, then positions.
                    let (ga, ka) = slot[a];
                    let (first, second) = if (ga, ka) < (gb, kb) { (a, b) } else { (b, a) };
                    let (g1, k1) = slot[first];
                    let (g2, k2) = slot[second];
                    hits.push(((g1, g2, k1, k2), first, second));
                }
            }
            // A motion's parts join the sweep once all of them have been swept: parts of
            // one dt are never paired here ([AGCOMP] compares them), so they need not see
            // each other (a wide dt's parts were n² skipped pairs). None of them is retired
            // before the next motion, so the later sweeps keep them as before.
            if b + 1 == parts.len() || parts[b + 1].ev != y.ev {
                live[gb].extend(same[b].clone());
            }
        }
        hits.sort_unstable_by_key(|h| h.0);
        // Per pair of motions (earlier, later), the pairs of parts that may overlap.
        type Pairs = Vec<(String, String, RoleId, RoleId)>;
        let mut found: std::collections::BTreeMap<(usize, usize), Pairs> = std::collections::BTreeMap::new();
        for (_, a, b) in hits {
            let (x, y) = (&parts[a], &parts[b]);
            let (x, y) = if x.ev < y.ev { (x, y) } else { (y, x) };
            found.entry((x.ev, y.ev)).or_default().push((self.part_name(x), self.part_name(y), x.role, y.role));
        }
        for ((xe, ye), pairs) in found {
            let list: Vec<String> = pairs.iter().map(|(a, b, _, _)| format!("`{b}` with `{a}`")).collect();
            let (_, _, xr, yr) = pairs[0];
            let d = Diagnostic::error(
                Code::UncheckedOverlap,
                self.ev[ye].loc().0,
                format!(
                    "this motion may start while {} is still running, and no check compares them: {}",
                    self.describe(xe),
                    list.join(", ")
                ),
            )
            .with_label(self.ev[xe].loc().0, "may still be running")
            .with_note("nothing orders the two in time, and they are neither one dt ([AGCOMP]) nor the two sides of one `*` (full separation, Sec 4.1), so their footprints are never compared")
            .with_help(format!(
                "order them with a message (e.g. let `{}` tell `{}` when it is done), or put them on the two sides of one `*`",
                self.prog.role_name(xr),
                self.prog.role_name(yr)
            ));
            self.push(d);
        }
    }
}
