//! Collisions at one time of a run, on concrete states.
//!
//! A footprint is read through [`footprint`], the one place that knows how a primitive's
//! footprint is stored. Two footprints that are predicates are compared by Z3 at the
//! concrete states (a common point, replayed exactly, is a collision). Footprints that are
//! solids (shapes, meshes, URDF links, `footprint: geometry`) are placed at the concrete
//! poses: the participant's `at:`, each carrier's `at:` and mount at the carrier's state
//! now, the part's own pose (which may read `old(x)`, parameters and `clock`), and a URDF
//! link's pose by forward kinematics of the joint values; their parry distance at most 0
//! is a collision. Obstacles are compared the same way. A robot's body must lie in its
//! footprint: points on the boundary of each solid of the body are tested against the
//! footprint (its predicate, exactly, or its solids).

use super::motion::{frame_env, show_values};
use super::report::Kind;
use super::run::Runner;
use crate::exact::{self, Num, Rat, Tri, Value};
use crate::geometry::{self, Pose3, Relation, Solid};
use crate::hir::body::Pose;
use crate::hir::{Footprint, PointPred, PrimId, Program, RoleId, Slot, Var};
use crate::smt::goals::witness::Occupant;
use crate::space::world::Piece;

/// A primitive's footprint as the simulator reads it.
pub(super) enum Fp<'p> {
    /// A predicate over the point; with the solids it was derived from when it is a
    /// primitive shape's.
    Pred(&'p PointPred, Option<&'p [Piece]>),
    /// Solids only (a mesh, a URDF body): no predicate.
    Solids(&'p [Piece]),
    /// A geometric footprint whose solids were not built (the geometry stage did not run).
    Unplaced,
    /// No footprint declared: all space.
    All,
}

/// How `prim`'s footprint reads here: its kind ([`Footprint`]) with the world's solids
/// of it (built by the geometry stage for every geometric footprint).
pub(super) fn footprint(prog: &Program, prim: PrimId) -> Fp<'_> {
    let p = prog.prim(prim);
    let solids = crate::space::world::of(prog).and_then(|w| w.prims.get(prim.idx())).and_then(|s| s.as_deref());
    match &p.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => Fp::Pred(fp, solids),
        Footprint::Solid { .. } => solids.map_or(Fp::Unplaced, Fp::Solids),
        Footprint::Everywhere => Fp::All,
    }
}

/// Whether one of `a`, `b` rides (directly or through other carriers) on the other: they
/// are attached at the mount, as two links of one robot, as the checks read them.
pub(super) fn attached(prog: &Program, a: RoleId, b: RoleId) -> bool {
    prog.carriers(a).iter().any(|m| m.carrier == b) || prog.carriers(b).iter().any(|m| m.carrier == a)
}

/// How two placed sets of solids relate.
pub(super) enum Meet {
    Apart,
    Contact { distance: f64, point: [f64; 3], names: [String; 2] },
}

pub(super) fn meet(a: &[(Pose3, &Solid)], b: &[(Pose3, &Solid)]) -> Option<Meet> {
    let c = geometry::distance(a, b)?;
    if c.distance > 0.0 {
        return Some(Meet::Apart);
    }
    let point = [c.point_a.x, c.point_a.y, c.point_a.z];
    let names = [c.name_a.clone(), c.name_b.clone()];
    if c.relation != Relation::HullsTouch {
        return Some(Meet::Contact { distance: c.distance, point, names });
    }
    // Hulls of meshes touch: the meshes themselves must meet, surface to surface, or one
    // solid lies inside the other's closed mesh (a point of it inside, by the winding
    // number), where the surfaces are apart.
    for (pa, sa) in a {
        for (pb, sb) in b {
            let (wa, wb) = (pa * sa.pose, pb * sb.pose);
            if let Some((d, pts)) = geometry::search::bnb::mesh_distance(sa, &wa, sb, &wb) {
                if d <= 0.0 {
                    return Some(Meet::Contact {
                        distance: d,
                        point: pts[0],
                        names: [sa.name.clone(), sb.name.clone()],
                    });
                }
            }
            let inner = |(po, so): (&Pose3, &Solid), (pi, si): (&Pose3, &Solid)| {
                geometry::within::some_point(pi, si).filter(|p| geometry::within::solid_contains(po, so, *p, 0.0))
            };
            if let Some(point) = inner((pa, sa), (pb, sb)).or_else(|| inner((pb, sb), (pa, sa))) {
                return Some(Meet::Contact { distance: 0.0, point, names: [sa.name.clone(), sb.name.clone()] });
            }
        }
    }
    Some(Meet::Apart)
}

pub(super) fn show_point(p: &[f64; 3]) -> String {
    format!("({:.6}, {:.6}, {:.6})", p[0], p[1], p[2])
}

impl Runner<'_, '_> {
    /// The state of `r` at this time: an occupant's when it is one of `moving`, else its
    /// last state.
    fn state_now(&self, r: RoleId, moving: &[&Occupant]) -> Vec<Value> {
        match moving.iter().find(|o| o.role == r) {
            Some(o) => o.now.clone(),
            None => self.state.get(r.idx()).cloned().unwrap_or_default(),
        }
    }

    /// A pose whose arguments read the environment `env`, at its value (the middle of
    /// an enclosure, such as that of `pi / 2`).
    pub(super) fn pose_at(&self, pose: &Pose, env: &dyn exact::Env) -> Result<Pose3, String> {
        let mut a = [0.0; 6];
        for (k, e) in pose.args.iter().enumerate() {
            let v = exact::eval(self.prog, e, env)?;
            a[k] = v.num()?.to_f64();
            if !a[k].is_finite() {
                return Err("a pose argument is not a finite number".into());
            }
        }
        Ok(geometry::pose6(a))
    }

    /// The frame of participant `r` in the world: each carrier's `at:` and its mount
    /// (at the carrier's state now), outermost first, then `r`'s own `at:`.
    fn role_frame(&self, r: RoleId, moving: &[&Occupant]) -> Result<Pose3, String> {
        let prog = self.prog;
        let at = |role: RoleId| -> Result<Pose3, String> {
            let pose = &prog.role(role).pose;
            let mut a = [0.0; 6];
            for (k, e) in pose.iter().enumerate().take(6) {
                a[k] = exact::eval(prog, e, &|_: &Var| None)?.num()?.to_f64();
            }
            Ok(geometry::pose6(a))
        };
        let mut frame = geometry::identity();
        for m in prog.carriers(r).iter().rev() {
            frame *= at(m.carrier)?;
            let state = self.state_now(m.carrier, moving);
            let mount = &prog.kind_of(m.carrier).mounts[m.mount];
            let env = move |v: &Var| match v {
                Var::Own(Slot::State(i)) => state.get(*i).cloned(),
                _ => None,
            };
            frame *= self.pose_at(&mount.pose, &env)?;
        }
        Ok(frame * at(r)?)
    }

    /// `pieces` of participant `r` placed in the world: their owner frames' poses.
    /// `env` reads the piece poses' variables (own state, and for a footprint `old(x)`,
    /// parameters and `clock`); `now` drives URDF joints.
    pub(super) fn place<'w>(
        &self,
        r: RoleId,
        pieces: &'w [Piece],
        now: &[Value],
        env: &dyn exact::Env,
        moving: &[&Occupant],
    ) -> Result<Vec<(Pose3, &'w Solid)>, String> {
        let base = self.role_frame(r, moving)?;
        let mut out = Vec::new();
        for p in pieces {
            let mut pose = base;
            if let Some(place) = &p.place {
                pose *= self.pose_at(place, env)?;
            }
            if let Some(link) = &p.link {
                let mut q = vec![0.0; link.robot.joint_names().len()];
                for (k, slot) in link.joints.iter().enumerate() {
                    let Slot::State(i) = slot else { return Err("a URDF joint driven by an input".into()) };
                    let v = now.get(*i).ok_or("a joint value is missing")?;
                    q[k] = v.num()?.to_f64();
                }
                let poses = link.robot.link_poses(&q);
                pose *= *poses.get(link.link).ok_or("a URDF link out of range")?;
            }
            out.push((pose, &*p.solid));
        }
        Ok(out)
    }

    /// The solids of `o`'s footprint at its state and clock.
    fn footprint_solids<'w>(
        &self,
        o: &Occupant,
        pieces: &'w [Piece],
        moving: &[&Occupant],
    ) -> Result<Vec<(Pose3, &'w Solid)>, String> {
        let args = self.arg_values(&o.app);
        let env = frame_env(&o.now, &o.start, &args, &o.clock, &[]);
        self.place(o.role, pieces, &o.now, &env, moving)
    }

    fn who(&self, o: &Occupant) -> String {
        format!(
            "`{}` ({}: {})",
            self.prog.prim(o.app.prim).name,
            self.prog.role_name(o.role),
            show_values(self.prog, o.role, &o.now)
        )
    }

    /// Compares two footprints; false when the run must stop (a finding was made).
    /// `moving` are the participants moving now (their carriers' states are read there).
    pub(super) fn collide(&mut self, a: &Occupant, b: &Occupant, t: &Rat, context: &str, moving: &[&Occupant]) -> bool {
        let prog = self.prog;
        let (fa, fb) = (footprint(prog, a.app.prim), footprint(prog, b.app.prim));
        for (f, o) in [(&fa, a), (&fb, b)] {
            if matches!(f, Fp::All) {
                let msg = format!(
                    "{context}: `{}` ({}) declares no footprint, so it fills all space",
                    prog.prim(o.app.prim).name,
                    prog.role_name(o.role)
                );
                self.report(Kind::Collision, t, msg);
                return false;
            }
        }
        if attached(prog, a.role, b.role) {
            return true;
        }
        let mounted = |o: &Occupant| prog.role(o.role).mounted_on.is_some();
        fn solids<'p>(f: &Fp<'p>) -> Option<&'p [Piece]> {
            match f {
                Fp::Pred(_, s) => *s,
                Fp::Solids(s) => Some(*s),
                _ => None,
            }
        }
        // Solids where both have them (the poses are then concrete: no sine or cosine of
        // a state variable for Z3); predicates otherwise.
        let (Some(sa), Some(sb)) = (solids(&fa), solids(&fb)) else {
            if matches!((&fa, &fb), (Fp::Pred(..), Fp::Pred(..))) && !mounted(a) && !mounted(b) {
                return self.overlap(a, b, t, context);
            }
            let msg = format!(
                "{context}: the footprints of `{}` and `{}` cannot be compared here: one is a predicate of a mounted participant or a predicate against a mesh or URDF footprint",
                prog.prim(a.app.prim).name,
                prog.prim(b.app.prim).name
            );
            self.report(Kind::Undecided, t, msg);
            return false;
        };
        let placed =
            self.footprint_solids(a, sa, moving).and_then(|x| self.footprint_solids(b, sb, moving).map(|y| (x, y)));
        let (xa, xb) = match placed {
            Ok(p) => p,
            Err(e) => {
                self.report(Kind::Undecided, t, format!("{context}: placing the footprints: {e}"));
                return false;
            }
        };
        match meet(&xa, &xb) {
            Some(Meet::Apart) => true,
            Some(Meet::Contact { distance, point, names }) => {
                let msg = format!(
                    "{context}: the footprints of {} and {} meet at {} (`{}` and `{}`, distance {distance:.3e} m) at time {}",
                    self.who(a),
                    self.who(b),
                    show_point(&point),
                    names[0],
                    names[1],
                    exact::decimal(t)
                );
                self.report(Kind::Collision, t, msg);
                false
            }
            None => {
                self.report(Kind::Undecided, t, format!("{context}: a footprint with no solid"));
                false
            }
        }
    }

    /// Two predicate footprints: a common point from Z3 at the concrete states, replayed.
    fn overlap(&mut self, a: &Occupant, b: &Occupant, t: &Rat, context: &str) -> bool {
        match self.sess.overlap(self.prog, a, b) {
            Ok(None) => true,
            Ok(Some(p)) => {
                // Replay: the point must lie in both footprints, exactly (pose rotations
                // by enclosures, so a rotated point may be undecided, never wrongly false).
                let inside = [a, b].map(|o| self.in_footprint(o, &p));
                let point = format!("({}, {}, {})", p[0], p[1], p[2]);
                if inside.contains(&Tri::False) {
                    self.report(
                        Kind::Replay,
                        t,
                        format!("{context}: Z3's common point {point} of two footprints is not in both when replayed exactly"),
                    );
                } else {
                    let msg = format!(
                        "{context}: the footprints of {} and {} share the point {point} at time {}",
                        self.who(a),
                        self.who(b),
                        exact::decimal(t)
                    );
                    self.report(Kind::Collision, t, msg);
                }
                false
            }
            Err(why) => {
                self.undecided(t, &format!("{context}: comparing footprints"), why);
                false
            }
        }
    }

    /// Whether the world point `p` is in `o`'s footprint predicate, evaluated exactly
    /// (`Unknown` for a mounted participant or a footprint with no predicate).
    fn in_footprint(&self, o: &Occupant, p: &[Num; 3]) -> Tri {
        let prog = self.prog;
        let Fp::Pred(fp, _) = footprint(prog, o.app.prim) else { return Tri::Unknown };
        let Some(local) = crate::smt::replay::to_local(prog, o.role, p) else { return Tri::Unknown };
        let args = self.arg_values(&o.app);
        let env = frame_env(&o.now, &o.start, &args, &o.clock, &[]);
        let env = |v: &Var| match v {
            Var::Point(k) => local.get(*k).cloned().map(Value::Num),
            other => env(other),
        };
        exact::holds(prog, &fp.pred, &env)
    }

    /// `o`'s footprint against every obstacle: a common point (predicates, Z3) or a
    /// contact of solids. False when the run must stop.
    pub(super) fn clear_of_obstacles(&mut self, o: &Occupant, t: &Rat, context: &str, moving: &[&Occupant]) -> bool {
        let prog = self.prog;
        if crate::space::world::of(prog).is_none() {
            return true;
        }
        for (k, obstacle) in prog.obstacles.iter().enumerate() {
            let f = footprint(prog, o.app.prim);
            if let Fp::All = f {
                let msg = format!(
                    "{context}: `{}` ({}) declares no footprint, so it fills all space, obstacle `{}` included",
                    prog.prim(o.app.prim).name,
                    prog.role_name(o.role),
                    obstacle.name
                );
                self.report(Kind::Collision, t, msg);
                return false;
            }
            let region = crate::space::region::obstacle_region(prog, obstacle);
            let mounted = prog.role(o.role).mounted_on.is_some();
            if let (Fp::Pred(fp, None), Some(region), false) = (&f, &region, mounted) {
                // A footprint turned by the state (`cos(theta)`): the interval search over
                // the obstacle's points at this state, which Z3's nonlinear arithmetic
                // leaves open (`collision::predicate`).
                let args = self.arg_values(&o.app);
                let env = frame_env(&o.now, &o.start, &args, &o.clock, &[]);
                let limit = std::time::Duration::from_secs(10);
                match crate::collision::predicate::point_in_obstacle(prog, o.role, &fp.pred, obstacle, &env, limit) {
                    Some(Ok(None)) => continue,
                    Some(Ok(Some(p))) => {
                        let msg = format!(
                            "{context}: the footprint of {} reaches into obstacle `{}` at the point ({}, {}, {}) at time {}",
                            self.who(o),
                            obstacle.name,
                            exact::decimal(&p[0].lo),
                            exact::decimal(&p[1].lo),
                            exact::decimal(&p[2].lo),
                            exact::decimal(t)
                        );
                        self.report(Kind::Collision, t, msg);
                        return false;
                    }
                    Some(Err(why)) => {
                        let msg = format!(
                            "{context}: comparing with obstacle `{}`: the interval search stopped: {why}",
                            obstacle.name
                        );
                        self.report(Kind::Undecided, t, msg);
                        return false;
                    }
                    None => {}
                }
                match self.sess.overlap_region(prog, o, region) {
                    Ok(None) => continue,
                    Ok(Some(p)) => {
                        if self.in_footprint(o, &p) == Tri::False {
                            self.report(
                                Kind::Replay,
                                t,
                                format!("{context}: Z3's point of `{}` in obstacle `{}` is not in the footprint when replayed exactly", prog.prim(o.app.prim).name, obstacle.name),
                            );
                        } else {
                            let msg = format!(
                                "{context}: the footprint of {} reaches into obstacle `{}` at the point ({}, {}, {}) at time {}",
                                self.who(o),
                                obstacle.name,
                                p[0],
                                p[1],
                                p[2],
                                exact::decimal(t)
                            );
                            self.report(Kind::Collision, t, msg);
                        }
                        return false;
                    }
                    Err(why) => {
                        self.undecided(t, &format!("{context}: comparing with obstacle `{}`", obstacle.name), why);
                        return false;
                    }
                }
            }
            let pieces = match f {
                Fp::Pred(_, Some(s)) | Fp::Solids(s) => s,
                _ => {
                    let msg = format!(
                        "{context}: the footprint of `{}` cannot be compared with obstacle `{}` here (a predicate of a mounted participant, or a predicate against a mesh or URDF obstacle)",
                        prog.prim(o.app.prim).name,
                        obstacle.name
                    );
                    self.report(Kind::Undecided, t, msg);
                    return false;
                }
            };
            let placed = self.footprint_solids(o, pieces, moving).and_then(|a| Ok((a, self.obstacle_solids(k)?)));
            let (a, b) = match placed {
                Ok(x) => x,
                Err(e) => {
                    self.report(Kind::Undecided, t, format!("{context}: placing obstacle `{}`: {e}", obstacle.name));
                    return false;
                }
            };
            if let Some(Meet::Contact { distance, point, names }) = meet(&a, &b) {
                let msg = format!(
                    "{context}: the footprint of {} meets obstacle `{}` at {} (`{}` and `{}`, distance {distance:.3e} m) at time {}",
                    self.who(o),
                    obstacle.name,
                    show_point(&point),
                    names[0],
                    names[1],
                    exact::decimal(t)
                );
                self.report(Kind::Collision, t, msg);
                return false;
            }
        }
        true
    }

    /// The robot's body of `o`'s participant at its state lies in `o`'s footprint: points
    /// on the boundary of each solid of the body (1 µm inside) are in the footprint's
    /// predicate (exactly; undecided points are not counted) or in one of its solids. A
    /// point definitely outside is a violation. False when the run must stop.
    pub(super) fn body_in_footprint(&mut self, o: &Occupant, t: &Rat, context: &str, moving: &[&Occupant]) -> bool {
        let prog = self.prog;
        let Some(world) = crate::space::world::shared(prog) else { return true };
        let body = match world.kinds.get(prog.role(o.role).kind.idx()) {
            Some(b) if !b.is_empty() => b,
            _ => return true,
        };
        // `footprint: geometry` is the body itself at the same state: within it by
        // construction (and testing each vertex of a mesh body against the mesh's own
        // triangles costs vertices times triangles at every sample).
        if matches!(
            &prog.prim(o.app.prim).footprint,
            Footprint::Solid { own: true, .. } | Footprint::Shapes { own: true, .. }
        ) {
            return true;
        }
        let f = footprint(prog, o.app.prim);
        let own = |v: &Var| match v {
            Var::Own(Slot::State(i)) => o.now.get(*i).cloned(),
            _ => None,
        };
        let placed = match self.place(o.role, body, &o.now, &own, moving) {
            Ok(p) => p,
            // A body whose pose cannot be evaluated here: not checked (the collision
            // checks place the footprint, which is what the protocol is judged by).
            Err(_) => return true,
        };
        let fp_solids = match &f {
            Fp::Solids(s) => self.footprint_solids(o, s, moving).ok(),
            _ => None,
        };
        for (owner, solid) in &placed {
            // Solids: each solid of the body within their union, a mesh read as the
            // region its triangles bound (its hollows are outside), not as its hull.
            let out = fp_solids.as_ref().and_then(|s| geometry::within::point_outside(owner, solid, s, 1e-9));
            for p in out.into_iter().chain(geometry::boundary_points(owner, solid, 1e-6)) {
                let outside = out.is_some_and(|q| q == p)
                    || match &f {
                        Fp::Pred(..) if prog.role(o.role).mounted_on.is_none() => {
                            let point = p.map(|c| Num::exact(Rat::from_float(c).unwrap_or_default()));
                            self.in_footprint(o, &point) == Tri::False
                        }
                        _ => false,
                    };
                if outside {
                    let msg = format!(
                        "{context}: the body of `{}` ({}, solid `{}`) leaves the footprint of `{}` at {} at time {}; {}",
                        prog.role_name(o.role),
                        prog.kind_of(o.role).name,
                        solid.name,
                        prog.prim(o.app.prim).name,
                        show_point(&p),
                        exact::decimal(t),
                        show_values(prog, o.role, &o.now)
                    );
                    self.report(Kind::Violation, t, msg);
                    return false;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;

    const KINDS: &str = "robot Cube {
  state x: real;
  geometry: box(1, 1, 1) at pose(x, 0, 0);
}
motion Cube.stay() {
  interruptible: true; pre: true; assume: true; guarantee: x == old(x); post: true;
  footprint: geometry;
  duration: [1, 1];
}
motion Cube.free() {
  interruptible: true; pre: true; assume: true; guarantee: x == old(x); post: true;
  duration: [1, 1];
}
";

    #[test]
    fn the_accessor_reads_every_kind_of_footprint() {
        let src = format!(
            "{KINDS}
robot Pt {{ state x: real; }}
motion Pt.here() {{
  interruptible: true; pre: true; assume: true; guarantee: x == old(x); post: true;
  footprint(px, py, pz): px == x && py == 0 && pz == 0;
  duration: [1, 1];
}}
system S {{ participant A: Cube {{ init: x == 0; }} participant B: Pt {{ init: x == 0; }} }}
choreography C = end;
"
        );
        let (mut prog, diags) = lower_src(&src);
        assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
        let prim = |name: &str| PrimId(prog.prims.iter().position(|p| p.name == name).unwrap() as u32);
        let (stay, free, here) = (prim("stay"), prim("free"), prim("here"));
        // Before the geometry stage, a geometric footprint has no solids yet.
        assert!(matches!(footprint(&prog, stay), Fp::Unplaced));
        assert!(matches!(footprint(&prog, free), Fp::All));
        assert!(matches!(footprint(&prog, here), Fp::Pred(_, None)));
        let mut db = crate::source::SourceDb::new();
        let _ = crate::space::prepare(&mut prog);
        let (world, _) = crate::space::world::build(&prog, &mut db, &mut |_| Err(std::io::ErrorKind::NotFound.into()));
        prog.world = Some(std::sync::Arc::new(world));
        // A box footprint gets its predicate and keeps its solids.
        assert!(matches!(footprint(&prog, stay), Fp::Pred(_, Some(s)) if s.len() == 1));
        assert!(matches!(footprint(&prog, free), Fp::All));
    }
}
