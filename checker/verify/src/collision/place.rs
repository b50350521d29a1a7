//! The question's scene built and laid out (its dimensions and root box), the bodies placed
//! at a box's centre with their motion bounds, the per-box contraction, and the search run
//! (docs/soundness-geometry.md, "How the checks use the geometric procedure").

use super::*;

impl<'a> Geo<'a> {
    pub(super) fn new(
        prog: &'a Program,
        world: &'a World,
        ob: &'a Obligation,
        runs: Vec<Run>,
        who: [Who; 2],
        mode: Mode,
    ) -> Result<Geo<'a>, String> {
        let initial = mode == Mode::Initial;
        let mut sides: [Vec<Placed<'a>>; 2] = [Vec::new(), Vec::new()];
        for (side, w) in sides.iter_mut().zip(who) {
            match w {
                Who::Run(k) => {
                    let r = &runs[k];
                    let kind = prog.role(r.role).kind;
                    let pieces = if mode != Mode::Footprints {
                        &world.kinds[kind.idx()]
                    } else {
                        match world.prims.get(r.app.prim.idx()).and_then(|p| p.as_ref()) {
                            Some(p) => p,
                            // A predicate footprint of a mounted participant: its body stands
                            // for it only if the predicate is the body (not known): unknown.
                            None => {
                                return Err(format!(
                                    "`{}` of `{}` has a footprint written as a predicate, which the geometric procedure cannot place; write it as `footprint: geometry;` or shapes",
                                    prog.prim(r.app.prim).name,
                                    prog.role_name(r.role)
                                ))
                            }
                        }
                    };
                    let run = (!initial).then_some(k);
                    side.extend(pieces.iter().map(|piece| Placed {
                        piece,
                        role: Some(r.role),
                        run,
                        at: None,
                        obstacle: None,
                        turned: turns_about_z(prog, piece).then(|| piece.solid.z_cylinder()),
                    }));
                }
                Who::Obstacle(o) => {
                    let obstacle = &prog.obstacles[o];
                    side.extend(world.obstacles[o].iter().map(|piece| Placed {
                        piece,
                        role: None,
                        run: None,
                        at: obstacle.pose.as_ref(),
                        obstacle: Some(o),
                        turned: None,
                    }));
                }
            }
            if side.is_empty() {
                return Err("a side with no solid (a body that failed to load, or an empty one)".into());
            }
        }
        // The context's ranges, and each run's own ranges and arguments.
        let mut shared = Vec::new();
        let mut own = Vec::new();
        let mut params = Vec::new();
        for r in &runs {
            let facts: Vec<&Expr> = r.hyps.iter().collect();
            let s = bounds::ranges_from(prog, &facts, &bounds::closed);
            if initial {
                own.push(HashMap::new());
                params.push(Vec::new());
            } else {
                let prim = prog.prim(r.app.prim);
                let lookup = |v: &Var| s.get(v).copied();
                let ps: Vec<Option<Interval>> = r.app.args.iter().map(|a| bounds::eval(prog, a, &lookup)).collect();
                let role = r.role;
                let lift = |v: &Var| -> Option<Interval> {
                    match v {
                        Var::Old(i) => s.get(&Var::Role(role, Slot::State(*i))).copied(),
                        Var::Param(i) => ps.get(*i).copied().flatten(),
                        Var::Clock => Some(Interval::new(0.0, f64::INFINITY)),
                        _ => None,
                    }
                };
                let mut facts: Vec<&Expr> = vec![&prim.guarantee];
                facts.extend(prog.kind(prim.kind).invariant.as_ref());
                own.push(bounds::ranges_from(prog, &facts, &lift));
                params.push(ps);
            }
            shared.push(s);
        }
        let mut geo = Geo {
            prog,
            ob,
            runs,
            dims: Vec::new(),
            root: QBox::new(Vec::new(), Vec::new()),
            shared,
            own,
            params,
            carrier: HashMap::new(),
            sides,
            initial,
            tight: mode == Mode::Bodies,
            contracted: std::cell::RefCell::new(None),
            contractions: Vec::new(),
            scratch: Default::default(),
            poses: Default::default(),
            at_poses: Default::default(),
            pose_stack: Default::default(),
        };
        geo.layout()?;
        if !initial {
            geo.contractions = (0..geo.runs.len()).map(|k| geo.compile_contraction(k)).collect();
        }
        Ok(geo)
    }

    /// The dimensions (clocks, then the state variables the bodies are placed by) and the
    /// root box.
    pub(super) fn layout(&mut self) -> Result<(), String> {
        let prog = self.prog;
        let clocks = self.runs.iter().map(|r| r.clock).max().map_or(0, |m| m + 1);
        let mut dims: Vec<Dim> = (0..clocks).map(Dim::Clock).collect();
        let add = |d: Dim, dims: &mut Vec<Dim>| {
            if !dims.contains(&d) {
                dims.push(d);
            }
        };
        for side in &self.sides {
            for p in side {
                let Some(role) = p.role else { continue };
                let mut placing = vec![role];
                for m in prog.carriers(role) {
                    let mount = &prog.kind_of(m.carrier).mounts[m.mount];
                    for e in &mount.pose.args {
                        e.visit_vars(&mut |v, _| {
                            if let Var::Own(slot) = v {
                                add(Dim::Now(m.carrier, *slot), &mut dims);
                            }
                        });
                    }
                    placing.push(m.carrier);
                }
                if let Some(pose) = &p.piece.place {
                    for e in &pose.args {
                        e.visit_vars(&mut |v, _| {
                            if let Var::Own(slot) = v {
                                add(Dim::Now(role, *slot), &mut dims);
                            }
                        });
                    }
                }
                if let Some(link) = &p.piece.link {
                    for slot in link.joints.iter() {
                        add(Dim::Now(role, *slot), &mut dims);
                    }
                }
            }
        }
        // Carriers that run nothing here: their state ranges over their invariant.
        for d in &dims {
            if let Dim::Now(r, _) = d {
                if !self.runs.iter().any(|x| x.role == *r) && !self.carrier.contains_key(r) {
                    let inv = prog.kind_of(*r).invariant.as_ref();
                    let facts: Vec<&Expr> = inv.into_iter().collect();
                    self.carrier.insert(*r, bounds::ranges_from(prog, &facts, &bounds::closed));
                }
            }
        }
        self.dims = dims;
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        for d in &self.dims.clone() {
            let iv = match d {
                Dim::Clock(k) => self.clock_range(*k)?,
                Dim::Now(r, slot) => self.state_range(*r, *slot),
            };
            if !iv.is_finite() || iv.lo > iv.hi {
                let what = match d {
                    Dim::Clock(_) => {
                        "the time of a motion whose guarantee reads `clock` and whose duration has no upper end"
                            .to_string()
                    }
                    Dim::Now(r, slot) => {
                        format!("`{}.{}`, which places a body", prog.role_name(*r), prog.kind_of(*r).var(*slot).0)
                    }
                };
                return Err(format!(
                    "{what} is not bounded: the geometric procedure searches a bounded box (give the kind an invariant that bounds it)"
                ));
            }
            lo.push(iv.lo);
            hi.push(iv.hi);
        }
        self.root = QBox::new(lo, hi);
        Ok(())
    }

    /// `[0, T]`: T the least upper end of the durations of the runs on clock `k` (they run
    /// together for one elapsed time); `[0, 0]` when none of their guarantees, invariants
    /// or bodies reads `clock` (every time is then alike) and no duration bounds it.
    pub(super) fn clock_range(&self, k: usize) -> Result<Interval, String> {
        if self.initial {
            return Ok(Interval::point(0.0));
        }
        let mut hi = f64::INFINITY;
        let mut reads = false;
        for (i, r) in self.runs.iter().enumerate().filter(|(_, r)| r.clock == k) {
            let prim = self.prog.prim(r.app.prim);
            if let Some(h) = &prim.duration.hi {
                let v = bounds::eval(self.prog, h, &|v: &Var| self.var_range(i, r.role, v, None));
                if let Some(v) = v {
                    hi = hi.min(v.hi);
                }
            }
            let clocky = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Clock));
            reads |= clocky(&prim.guarantee)
                || self.prog.kind(prim.kind).invariant.as_ref().is_some_and(clocky)
                || crate::space::world::of(self.prog)
                    .and_then(|w| w.prims.get(r.app.prim.idx()).cloned().flatten())
                    .is_some_and(|ps| {
                        ps.iter().any(|p| p.place.as_ref().is_some_and(|pose| pose.args.iter().any(clocky)))
                    });
        }
        if hi.is_finite() {
            Ok(Interval::new(0.0, hi.max(0.0)))
        } else if reads {
            Ok(Interval::new(0.0, f64::INFINITY))
        } else {
            Ok(Interval::point(0.0))
        }
    }

    pub(super) fn state_range(&self, r: RoleId, slot: Slot) -> Interval {
        let all = Interval::new(f64::NEG_INFINITY, f64::INFINITY);
        if let Some((k, run)) = self.runs.iter().enumerate().find(|(_, x)| x.role == r) {
            if self.initial {
                return self.shared[k].get(&Var::Role(r, slot)).copied().unwrap_or(all);
            }
            let _ = run;
            let a = self.own[k].get(&Var::Own(slot)).copied();
            return a.unwrap_or(all);
        }
        if self.initial {
            // At the start a carrier is where the context (its `init`) puts it.
            if let Some(iv) = self.shared.first().and_then(|s| s.get(&Var::Role(r, slot)).copied()) {
                return iv;
            }
        }
        self.carrier.get(&r).and_then(|m| m.get(&Var::Own(slot)).copied()).unwrap_or(all)
    }

    /// The range of variable `v` of participant `role`, read in run `run`'s frame (or as a
    /// carrier), with the dimensions taken from `q` (a box) when given.
    pub(super) fn var_range(&self, run: usize, role: RoleId, v: &Var, q: Option<(&[f64], &[f64])>) -> Option<Interval> {
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let from_q = |i: usize| q.map(|(lo, hi)| Interval::new(lo[i], hi[i]));
        match v {
            Var::Own(slot) => {
                if let Some(i) = dim(Dim::Now(role, *slot)) {
                    if let Some(iv) = from_q(i) {
                        return Some(iv);
                    }
                }
                Some(self.state_range(role, *slot)).filter(|i| i.is_finite())
            }
            Var::Old(i) => self.shared.get(run)?.get(&Var::Role(role, Slot::State(*i))).copied(),
            Var::Param(i) => self.params.get(run)?.get(*i).copied().flatten(),
            Var::Clock => {
                let k = self.runs.get(run)?.clock;
                dim(Dim::Clock(k)).and_then(from_q).or(Some(Interval::new(0.0, f64::INFINITY)))
            }
            Var::Point(_) => None,
            other => self.shared.get(run)?.get(other).copied(),
        }
    }

    /// One pose frame `pose(...)` whose arguments read `role`'s variables (in run `run`'s
    /// frame), over the box `[lo, hi]` with centre `c`: the frame at `c` and its bound.
    pub(super) fn pose_frame(
        &self,
        role: Option<RoleId>,
        run: usize,
        pose: &Pose,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Option<(Pose3, FrameBound)> {
        let key = (pose as *const Pose, role, run);
        if !self.poses.borrow().contains_key(&key) {
            let compiled = pose::CompiledPose::new(self.prog, pose, &|v: &Var| self.leaf(run, role, v));
            self.poses.borrow_mut().insert(key, compiled);
        }
        let poses = self.poses.borrow();
        poses.get(&key)?.frame(lo, hi, c, &mut self.pose_stack.borrow_mut())
    }

    /// The frames placing `role`'s own frame in the world (outermost first): each
    /// carrier's `at:` and mount, then its own `at:`.
    pub(super) fn role_chain(
        &self,
        role: RoleId,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Option<Vec<(Pose3, FrameBound)>> {
        let mut out = Vec::new();
        let mounts = self.prog.carriers(role);
        for m in mounts.iter().rev() {
            out.push(self.at_pose(m.carrier)?);
            let mount = &self.prog.kind_of(m.carrier).mounts[m.mount];
            let run = self.runs.iter().position(|x| x.role == m.carrier).unwrap_or(usize::MAX);
            out.push(self.pose_frame(Some(m.carrier), run, &mount.pose, lo, hi, c)?);
        }
        out.push(self.at_pose(role)?);
        Some(out)
    }

    /// The frames placing every solid of side `side` (outermost first; the solid's own
    /// pose in its owner frame is not included), over the box `[lo, hi]` with centre `c`.
    /// Chains of participants and forward kinematics are computed once per call.
    pub(super) fn side_frames(
        &self,
        side: usize,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Vec<Option<Vec<(Pose3, FrameBound)>>> {
        self.frames_of(side, None, lo, hi, c)
    }

    /// [`Geo::side_frames`], computed only for solid `only` when given (the others are
    /// `None`).
    pub(super) fn frames_of(
        &self,
        side: usize,
        only: Option<usize>,
        lo: &[f64],
        hi: &[f64],
        c: &[f64],
    ) -> Vec<Option<Vec<(Pose3, FrameBound)>>> {
        let mut chains: HashMap<Option<RoleId>, Option<Vec<(Pose3, FrameBound)>>> = HashMap::new();
        let mut fk: HashMap<(RoleId, usize), Option<Kinematics>> = HashMap::new();
        let mut out = Vec::new();
        for (idx, p) in self.sides[side].iter().enumerate() {
            if only.is_some_and(|k| k != idx) {
                out.push(None);
                continue;
            }
            let chain = chains
                .entry(p.role)
                .or_insert_with(|| match p.role {
                    Some(r) => self.role_chain(r, lo, hi, c),
                    None => match p.at {
                        Some(at) => self.pose_frame(None, 0, at, lo, hi, c).map(|f| vec![f]),
                        None => Some(Vec::new()),
                    },
                })
                .clone();
            let Some(mut frames) = chain else {
                out.push(None);
                continue;
            };
            if let Some(place) = &p.piece.place {
                match self.pose_frame(p.role, p.run.unwrap_or(usize::MAX), place, lo, hi, c) {
                    Some(f) => frames.push(f),
                    None => {
                        out.push(None);
                        continue;
                    }
                }
            }
            if let Some(link) = &p.piece.link {
                let key = (p.role.unwrap_or(RoleId(u32::MAX)), std::sync::Arc::as_ptr(&link.robot) as usize);
                let got = fk
                    .entry(key)
                    .or_insert_with(|| {
                        let nvars = link.robot.joint_names().len();
                        let mut qc = vec![0.0; nvars];
                        let mut half = vec![0.0; nvars];
                        for (k, s) in link.joints.iter().enumerate() {
                            let i = p.role.and_then(|r| self.dims.iter().position(|d| *d == Dim::Now(r, *s)))?;
                            qc[k] = c[i];
                            half[k] = (hi[i] - c[i]).max(c[i] - lo[i]);
                        }
                        Some((link.robot.link_poses(&qc), link.robot.displacement_bound(&qc, &half)))
                    })
                    .clone();
                let Some((poses, disp)) = got else {
                    out.push(None);
                    continue;
                };
                let (lp, d) = (poses[link.link], disp[link.link]);
                frames.push((lp, FrameBound { dt: d, drot: 0.0, reach: geometry::reach(&lp) + d }));
            }
            out.push(Some(frames));
        }
        out
    }

    /// Each solid of side `side` placed at `c` with the bounds on how far its points move
    /// over `[lo, hi]`; `None` if some solid cannot be placed (no bound).
    pub(super) fn placed(&self, side: usize, lo: &[f64], hi: &[f64], c: &[f64]) -> Option<Vec<At>> {
        self.side_frames(side, lo, hi, c)
            .into_iter()
            .zip(&self.sides[side])
            .map(|(frames, p)| Self::place_one(frames?, p))
            .collect()
    }

    /// Solid `k` of side `side` alone, as [`Geo::placed`] places it.
    pub(super) fn placed_one(&self, side: usize, k: usize, lo: &[f64], hi: &[f64], c: &[f64]) -> Option<At> {
        let frames = self.frames_of(side, Some(k), lo, hi, c).into_iter().nth(k)??;
        Self::place_one(frames, self.sides[side].get(k)?)
    }

    pub(super) fn place_one(frames: Vec<(Pose3, FrameBound)>, p: &Placed) -> Option<At> {
        let mut pose = geometry::identity();
        let mut fb = Vec::with_capacity(frames.len());
        for (f, b) in frames {
            pose *= f;
            fb.push(b);
        }
        let motion = chain_motion_bound(&fb, p.piece.solid.bounding_radius());
        // The stand-in's frame is the solid's own (`turns_about_z`: the last frame, with
        // roll and pitch fixed at 0), whose turn about z leaves it in place: only the other
        // frames' motion and that frame's translation move it.
        let turned_motion = p.turned.as_ref().map(|s| {
            if let Some(last) = fb.last_mut() {
                last.drot = 0.0;
            }
            chain_motion_bound(&fb, s.bounding_radius())
        });
        Some(At { pose: pose * p.piece.solid.pose, owner: pose, motion, turned_motion })
    }

    pub(super) fn at_pose(&self, role: RoleId) -> Option<(Pose3, FrameBound)> {
        if let Some(got) = self.at_poses.borrow().get(&role) {
            return *got;
        }
        let got = self.at_pose_uncached(role);
        self.at_poses.borrow_mut().insert(role, got);
        got
    }

    pub(super) fn at_pose_uncached(&self, role: RoleId) -> Option<(Pose3, FrameBound)> {
        let pose = &self.prog.role(role).pose;
        let mut a = [0.0; 6];
        let mut ab = ArgBounds::fixed([0.0; 6]);
        for (k, e) in pose.iter().enumerate().take(6) {
            let iv = bounds::eval(self.prog, e, &bounds::closed)?;
            a[k] = iv.lo / 2.0 + iv.hi / 2.0;
            ab.lo[k] = iv.lo;
            ab.hi[k] = iv.hi;
        }
        ab.centre = a;
        // The enclosure's width (a few ulps of an irrational angle) is the bound's.
        Some((geometry::pose6(a), FrameBound::pose(&ab)))
    }

    pub(super) fn solve(&self, limit: Duration) -> GeoAnswer {
        // One program on this thread for the whole search: its constants are evaluated once.
        let _consts = bounds::ConstCache::new();
        let n = self.dims.len();
        let res: Vec<f64> = (0..n).map(|i| ((self.root.hi[i] - self.root.lo[i]) * 1e-4).max(1e-6)).collect();
        let mut opts = Options::new(res);
        opts.deadline = Some(Instant::now() + limit);
        opts.max_nodes = 400_000;
        opts.time_dim = self.dims.iter().position(|d| *d == Dim::Clock(0));
        let d = bnb::decide(self, &self.root, &opts);
        if d.outcome.is_vacuous() {
            return self.all_cut_away(d.stats.nodes);
        }
        match d.outcome {
            bnb::Outcome::Apart { .. } => GeoAnswer::Apart,
            bnb::Outcome::Contact(c) => {
                // The earliest contact (`earliest.rs`): only for one clock (a joint motion;
                // the sides of `*` have two, the start state none).
                let one_clock = !self.initial && self.dims.iter().filter(|d| matches!(d, Dim::Clock(_))).count() == 1;
                let (c, window) = match opts.time_dim.filter(|_| one_clock) {
                    Some(t) => self.earliest_contact(c, t, &opts, d.stats.nodes),
                    None => (c, super::earliest::Earliest::default()),
                };
                // A contact is confirmed on the meshes themselves (`Geo::distance`), never on
                // convex hulls alone.
                let times: Vec<f64> = self
                    .dims
                    .iter()
                    .enumerate()
                    .filter_map(|(i, d)| matches!(d, Dim::Clock(_)).then_some(c.q[i]))
                    .collect();
                let values = match self.assignments(&c.q) {
                    Some(v) if !v.is_empty() => v,
                    _ => self.dim_values(&c.q),
                };
                // The bisection's bound, or the first search's refinement pass's, which
                // proved every configuration that satisfies the constraints with a time
                // below `clear_before` apart (`Overlap::not_before` claims "at or before",
                // so the largest double below it), whichever is later.
                let refined = c.clear_before.filter(|cb| cb.is_finite() && *cb > 0.0).map(f64::next_down);
                let not_before = window
                    .not_before
                    .into_iter()
                    .chain(refined)
                    .reduce(f64::max)
                    .filter(|nb| one_clock && *nb >= 0.0 && times.first().is_some_and(|t| nb <= t));
                let mut overlap = Overlap::at(c.point, if self.initial { Vec::new() } else { times });
                (overlap.not_before, overlap.earliest_open) = (not_before, window.open);
                GeoAnswer::Contact { values, overlap }
            }
            bnb::Outcome::Unknown { why, qbox, unresolved } => {
                let at: Vec<String> = self
                    .dims
                    .iter()
                    .enumerate()
                    .map(|(i, d)| format!("{} in [{:.4}, {:.4}]", self.dim_name(*d), qbox.lo[i], qbox.hi[i]))
                    .collect();
                let splits: Vec<String> = self
                    .dims
                    .iter()
                    .enumerate()
                    .filter_map(|(i, dim)| {
                        let n = d.stats.splits.get(i).copied().unwrap_or(0);
                        (n > 0).then(|| format!("{} {n}", self.dim_name(*dim)))
                    })
                    .collect();
                GeoAnswer::Unknown(format!(
                    "the geometric search did not decide ({}; {} box(es) searched in {:.1} s, {} left, split along {}; e.g. {})",
                    match why {
                        bnb::UnknownWhy::Resolution =>
                            "boxes at the resolution limit touch or are too close to call".to_string(),
                        bnb::UnknownWhy::Nodes(n) => format!("{n} boxes searched"),
                        bnb::UnknownWhy::Deadline => "time limit reached".to_string(),
                        bnb::UnknownWhy::BadBox => "the search box is malformed".to_string(),
                    },
                    d.stats.nodes,
                    d.stats.elapsed.as_secs_f64(),
                    unresolved,
                    if splits.is_empty() { "nothing".to_string() } else { splits.join(", ") },
                    at.join(", ")
                ))
            }
        }
    }

    /// The box narrowed to where the runs' guarantees and invariants can hold: bounds
    /// read off conjuncts `x <= e`, `e <= x`, `x == e` ([`bounds::ranges_from`], outward
    /// rounded) with the box's ranges for everything else. Sound: every configuration of
    /// the box that satisfies the constraints lies in the narrowed box. `None` when it is
    /// empty (no configuration of the box satisfies them).
    pub(super) fn narrow(&self, lo: &[f64], hi: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        if let Some(((l, h), got)) = self.contracted.borrow().as_ref() {
            if l == lo && h == hi {
                return got.clone();
            }
        }
        let got = self.contract_uncached(lo, hi);
        *self.contracted.borrow_mut() = Some(((lo.to_vec(), hi.to_vec()), got.clone()));
        got
    }

    pub(super) fn contract_uncached(&self, lo: &[f64], hi: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let (mut lo, mut hi) = (lo.to_vec(), hi.to_vec());
        let mut work = self.scratch.borrow_mut();
        // Each run over the box as the runs before it left it.
        for c in &self.contractions {
            if !c.narrow(&mut lo, &mut hi, &mut work) {
                return None;
            }
        }
        Some((lo, hi))
    }

    /// Run `k`'s contraction, compiled: its guarantee and invariant, with the ranges of
    /// everything that is not a dimension fixed for the question ([`Geo::var_range`]).
    pub(super) fn compile_contraction(&self, k: usize) -> contract::RunContraction {
        let r = &self.runs[k];
        let prim = self.prog.prim(r.app.prim);
        let mut facts: Vec<&Expr> = vec![&prim.guarantee];
        facts.extend(self.prog.kind(prim.kind).invariant.as_ref());
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let dim_of = |v: &Var| match v {
            Var::Own(slot) => dim(Dim::Now(r.role, *slot)),
            _ => None,
        };
        contract::RunContraction::new(self.prog, &facts, &dim_of, &|v: &Var| self.leaf(k, Some(r.role), v))
    }

    /// Where the range of variable `v` of participant `role`, read in run `run`'s frame,
    /// comes from in a box: [`Geo::var_range`] with the dimensions left to the box.
    /// `role` `None`: an obstacle's pose, which reads no variable.
    pub(super) fn leaf(&self, run: usize, role: Option<RoleId>, v: &Var) -> contract::Leaf {
        let Some(role) = role else { return contract::Leaf::Fixed(None) };
        let dim = |d: Dim| self.dims.iter().position(|x| *x == d);
        let i = match v {
            Var::Own(slot) => dim(Dim::Now(role, *slot)),
            Var::Clock => self.runs.get(run).and_then(|r| dim(Dim::Clock(r.clock))),
            _ => None,
        };
        match i {
            Some(i) => contract::Leaf::Dim(i),
            None => contract::Leaf::Fixed(self.var_range(run, role, v, None)),
        }
    }

    pub(super) fn dim_name(&self, d: Dim) -> String {
        match d {
            Dim::Clock(k) if self.runs.iter().any(|r| r.clock == 1) => format!("time {}", k + 1),
            Dim::Clock(_) => "time".to_string(),
            Dim::Now(r, slot) => format!("{}.{}", self.prog.role_name(r), self.prog.kind_of(r).var(slot).0),
        }
    }

    /// The value of dimension `d` in a counterexample, by the name the report gives it:
    /// `time` (`time 1`, `time 2` for the sides of `*`; 0 at the start), a participant's
    /// state at the time (`Cart.x(t)`, `(t1)`, `(t2)`; a state the report names only with
    /// `(t)`, as [`Geo::dim_values`] does) or at the start (`Cart.x`, [T-SESS]).
    pub(super) fn dim_value(&self, d: Dim, value: &dyn Fn(&str) -> Option<f64>) -> Option<f64> {
        let two = self.runs.iter().any(|r| r.clock == 1);
        match d {
            Dim::Clock(_) if self.initial => Some(0.0),
            Dim::Clock(k) => value(&self.dim_name(Dim::Clock(k))),
            Dim::Now(r, slot) => {
                let base = format!("{}.{}", self.prog.role_name(r), self.prog.kind_of(r).var(slot).0);
                if self.initial {
                    return value(&base);
                }
                let tag = match self.runs.iter().find(|x| x.role == r) {
                    Some(x) if two => ["t1", "t2"][x.clock.min(1)],
                    _ => "t",
                };
                value(&format!("{base}({tag})")).or_else(|| value(&format!("{base}(t)")))
            }
        }
    }

    /// The distance of world point `p` from side `side` placed at configuration `q`: the
    /// least over its solids of parry's distance from the point to the solid (0 inside).
    pub(super) fn point_distance(&self, side: usize, q: &[f64], p: [f64; 3]) -> f64 {
        self.side_frames(side, q, q, q)
            .into_iter()
            .zip(&self.sides[side])
            .map(|(frames, placed)| match frames {
                Some(frames) => {
                    let mut pose = geometry::identity();
                    for (f, _) in frames {
                        pose *= f;
                    }
                    (geometry::distance_to_point(&pose, &placed.piece.solid, p) - placed.piece.solid.slack).max(0.0)
                }
                None => f64::INFINITY,
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The question's configurations, as the SMT stage is asked about them.
    pub(super) fn configs(&self) -> Configs<'_> {
        Configs { prog: self.prog, hyps: &self.ob.hyps, runs: &self.runs, dims: &self.dims, initial: self.initial }
    }

    /// The search cut every box of the root away as infeasible: by the contraction, no
    /// configuration satisfies the constraints, so the sides never meet. That contradicts
    /// any configuration Z3 finds satisfying them exactly (the motion can run, the
    /// can-end question's witness): an enclosure then cut away a feasible configuration,
    /// and the search decides nothing (unknown, with the witness). Apart only when Z3
    /// confirms that no configuration of the root satisfies the constraints; unknown when
    /// it cannot tell.
    pub(super) fn all_cut_away(&self, nodes: usize) -> GeoAnswer {
        let what = format!("every box of the geometric search ({nodes}) was cut away as infeasible");
        match ask::exists(&self.configs(), &self.root.lo, &self.root.hi) {
            Exists::No => GeoAnswer::Apart,
            Exists::Yes(values) => {
                let at: Vec<String> = values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                GeoAnswer::Unknown(format!(
                    "{what}, yet Z3 finds a configuration that satisfies every constraint ({}): the interval contraction contradicts this witness, so the search proves nothing",
                    if at.is_empty() { "no values shown".to_string() } else { at.join(", ") }
                ))
            }
            Exists::Unknown(reason) => GeoAnswer::Unknown(format!(
                "{what}, and Z3 could not confirm that no configuration satisfies the constraints ({reason})"
            )),
            Exists::NotPosed => {
                GeoAnswer::Unknown(format!("{what}, and the constraints could not be put to Z3 to confirm it"))
            }
        }
    }

    /// The configuration `q` itself as the counterexample's values, when Z3 gives no model
    /// with the dimensions pinned to it (the witness the search confirmed was a Z3 model
    /// rounded to doubles, which may miss an equality by an ulp): each participant's
    /// state at the contact (`Cart.x(t)`, `Cart.x(t1)` on a side of `*`, or `Cart.x` at the
    /// start, [T-SESS]), marked
    /// approximate (`≈`); the time is the overlap's.
    pub(super) fn dim_values(&self, q: &[f64]) -> Vec<Assignment> {
        let mut out: Vec<Assignment> = self
            .dims
            .iter()
            .zip(q)
            .filter(|(d, _)| matches!(d, Dim::Now(..)))
            .map(|(d, v)| {
                // A state at the time: `(t)`, or on the sides of `*` the side's own time,
                // `(t1)` or `(t2)`, as the SMT stage names them.
                let two = self.runs.iter().any(|r| r.clock == 1);
                let name = match d {
                    Dim::Now(r, _) if !self.initial => {
                        let tag = match self.runs.iter().find(|x| x.role == *r) {
                            Some(x) if two => ["t1", "t2"][x.clock.min(1)],
                            _ => "t",
                        };
                        format!("{}({tag})", self.dim_name(*d))
                    }
                    _ => self.dim_name(*d),
                };
                Assignment { name, value: format!("≈{v}") }
            })
            .collect();
        out.sort_by(|a, b| a.name.cmp(&b.name));
        out
    }

    /// The counterexample's values at the configuration `q` (a model of the constraints
    /// with the dimensions pinned near `q`).
    pub(super) fn assignments(&self, q: &[f64]) -> Option<Vec<Assignment>> {
        ask::assignments(&self.configs(), q)
    }
}
