//! Kinematic trees: links carrying collision solids, joints between them, forward
//! kinematics (nalgebra) and sound bounds on how far a link can move when its joints move
//! within a box (for branch and bound, `geometry::search::bnb`).
//!
//! A joint places its child link's frame in its parent's: `parent ∘ origin ∘ motion(q)`,
//! where `motion` is a rotation by `q` about the joint's unit axis (revolute, continuous),
//! a translation by `q · axis` (prismatic) or the identity (fixed). The axis is expressed
//! in the joint frame (`parent ∘ origin`), and passes through its origin.
//!
//! The robot's joint variables ([`Robot::joint_names`]) are its movable joints that do
//! not mimic another, in the order the URDF lists them. A mimic joint's value is
//! `multiplier · q_master + offset` (resolved through chains of mimics), as ROS and
//! MoveIt read `<mimic>`; it has no variable of its own.

use super::shape::Solid;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

/// How a joint moves its child.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    Fixed,
    Revolute,
    /// A revolute joint without limits.
    Continuous,
    Prismatic,
}

impl JointKind {
    pub fn is_movable(self) -> bool {
        self != JointKind::Fixed
    }
}

/// `value = multiplier · joint[master] + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mimic {
    /// Index of the followed joint in [`Robot::joints`].
    pub master: usize,
    pub multiplier: f64,
    pub offset: f64,
}

/// A joint between two links (indices into [`Robot::links`]).
#[derive(Clone, Debug)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    pub parent: usize,
    pub child: usize,
    /// The joint frame in the parent link's frame.
    pub origin: Isometry3<f64>,
    /// The unit axis, in the joint frame.
    pub axis: Unit<Vector3<f64>>,
    /// `(lower, upper)` for revolute and prismatic joints; continuous and fixed: `None`.
    pub limits: Option<(f64, f64)>,
    /// `<limit velocity>` of a movable joint (rad/s or m/s) when it is a positive finite
    /// number; `None` otherwise (fixed joints, a missing or zero velocity).
    pub velocity: Option<f64>,
    pub mimic: Option<Mimic>,
}

/// A rigid body of the robot with its collision solids (in the link's frame).
#[derive(Clone, Debug)]
pub struct Link {
    pub name: String,
    pub solids: Vec<Solid>,
}

/// Why links and joints do not form one kinematic tree; `joint`/`link` say where.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeError {
    pub message: String,
    pub joint: Option<usize>,
    pub link: Option<usize>,
}

/// A kinematic tree (see the module doc).
#[derive(Clone, Debug)]
pub struct Robot {
    pub name: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    root: usize,
    /// Links, parents before children.
    order: Vec<usize>,
    /// The joint whose child each link is (`None` for the root).
    parent_joint: Vec<Option<usize>>,
    /// The joints that are variables, in variable order.
    vars: Vec<usize>,
    /// Per joint: `(variable, multiplier, offset)` with value `m · q[variable] + o`.
    drive: Vec<Option<(usize, f64, f64)>>,
    /// Per link: the bounding radius of its solids about its frame's origin.
    link_radius: Vec<f64>,
}

impl Robot {
    /// Checks that `links` and `joints` form one tree (every link the child of at most one
    /// joint, exactly one root, no cycle, mimics resolvable) and builds it.
    pub fn new(name: String, links: Vec<Link>, joints: Vec<Joint>) -> Result<Robot, TreeError> {
        let err = |message: String, joint: Option<usize>, link: Option<usize>| TreeError { message, joint, link };
        if links.is_empty() {
            return Err(err("the robot has no link".into(), None, None));
        }
        let n = links.len();
        let mut parent_joint = vec![None; n];
        for (j, jt) in joints.iter().enumerate() {
            if jt.parent >= n || jt.child >= n {
                return Err(err(format!("joint `{}` names a link that does not exist", jt.name), Some(j), None));
            }
            if let Some(other) = parent_joint[jt.child] {
                let other: usize = other;
                return Err(err(
                    format!(
                        "link `{}` is the child of two joints, `{}` and `{}`: a URDF is a tree",
                        links[jt.child].name, joints[other].name, jt.name
                    ),
                    Some(j),
                    Some(jt.child),
                ));
            }
            parent_joint[jt.child] = Some(j);
        }
        let roots: Vec<usize> = (0..n).filter(|&l| parent_joint[l].is_none()).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] => {
                return Err(err("every link is some joint's child: the joints form a cycle".into(), Some(0), None));
            }
            [a, b, ..] => {
                return Err(err(
                    format!(
                        "the robot has {} root links (links no joint moves), `{}` and `{}`: connect them by a joint",
                        roots.len(),
                        links[*a].name,
                        links[*b].name
                    ),
                    None,
                    Some(*b),
                ));
            }
        };
        // Breadth first from the root; a link never reached sits on a cycle.
        let mut children = vec![Vec::new(); n];
        for (j, jt) in joints.iter().enumerate() {
            children[jt.parent].push(j);
        }
        let mut order = vec![root];
        let mut reached = vec![false; n];
        reached[root] = true;
        let mut i = 0;
        while i < order.len() {
            let l = order[i];
            for &j in &children[l] {
                let c = joints[j].child;
                reached[c] = true;
                order.push(c);
            }
            i += 1;
        }
        if order.len() < n {
            let l = (0..n).find(|&l| !reached[l]).unwrap_or(0);
            return Err(err(
                format!(
                    "link `{}` is not connected to the root `{}`: its joints form a cycle",
                    links[l].name, links[root].name
                ),
                parent_joint[l],
                Some(l),
            ));
        }
        // Variables and mimics.
        let vars: Vec<usize> =
            (0..joints.len()).filter(|&j| joints[j].kind.is_movable() && joints[j].mimic.is_none()).collect();
        let mut drive = vec![None; joints.len()];
        for (v, &j) in vars.iter().enumerate() {
            drive[j] = Some((v, 1.0, 0.0));
        }
        // Each movable joint's drive, following its mimics to a variable. A joint's drive
        // is resolved once (the path of unresolved mimics is walked, then resolved from its
        // far end back), so chains of mimics take linear time, not quadratic.
        let mut on_path = vec![false; joints.len()];
        for j in 0..joints.len() {
            if !joints[j].kind.is_movable() || drive[j].is_some() {
                continue;
            }
            let mut path = vec![j];
            on_path[j] = true;
            let mut k = j;
            while let Some(mi) = joints[k].mimic {
                if mi.master >= joints.len() || !joints[mi.master].kind.is_movable() || on_path[mi.master] {
                    let what = if mi.master < joints.len() && on_path[mi.master] {
                        "mimics that follow each other in a cycle"
                    } else {
                        "a joint that is not a movable joint"
                    };
                    return Err(err(format!("joint `{}` mimics {what}", joints[k].name), Some(k), None));
                }
                k = mi.master;
                if drive[k].is_some() {
                    break;
                }
                path.push(k);
                on_path[k] = true;
            }
            // `k` has a drive: resolve the path back from it (`m · value(master) + o`).
            for &p in path.iter().rev() {
                on_path[p] = false;
                let Some(mi) = joints[p].mimic else { continue };
                let Some((v, m, o)) = drive[mi.master] else { continue };
                drive[p] = Some((v, mi.multiplier * m, mi.multiplier * o + mi.offset));
            }
        }
        for (j, d) in drive.iter().enumerate() {
            if let Some((_, m, o)) = d {
                if !(m.is_finite() && o.is_finite()) {
                    return Err(err(
                        format!("joint `{}` has a mimic multiplier or offset that is not finite", joints[j].name),
                        Some(j),
                        None,
                    ));
                }
            }
        }
        let link_radius =
            links.iter().map(|l| l.solids.iter().map(Solid::bounding_radius).fold(0.0, f64::max)).collect();
        Ok(Robot { name, links, joints, root, order, parent_joint, vars, drive, link_radius })
    }

    /// The root link's index.
    pub fn root(&self) -> usize {
        self.root
    }

    /// The joint whose child `link` is (`None` for the root).
    pub fn parent_joint(&self, link: usize) -> Option<usize> {
        self.parent_joint[link]
    }

    /// The names of the joint variables: movable joints that mimic no other, in the order
    /// of the URDF. `q` of [`Robot::link_poses`] is indexed like this.
    pub fn joint_names(&self) -> Vec<&str> {
        self.vars.iter().map(|&j| self.joints[j].name.as_str()).collect()
    }

    /// Per variable: `(lower, upper)`; a continuous joint's is `(-∞, ∞)`.
    pub fn joint_limits(&self) -> Vec<(f64, f64)> {
        self.vars.iter().map(|&j| self.joints[j].limits.unwrap_or((f64::NEG_INFINITY, f64::INFINITY))).collect()
    }

    /// Per variable: its `<limit velocity>` (see [`Joint::velocity`]).
    pub fn joint_velocities(&self) -> Vec<Option<f64>> {
        self.vars.iter().map(|&j| self.joints[j].velocity).collect()
    }

    fn value(&self, j: usize, q: &[f64]) -> f64 {
        match self.drive[j] {
            Some((v, m, o)) => m * q[v] + o,
            None => 0.0,
        }
    }

    fn motion(&self, j: usize, value: f64) -> Isometry3<f64> {
        let jt = &self.joints[j];
        match jt.kind {
            JointKind::Fixed => Isometry3::identity(),
            JointKind::Revolute | JointKind::Continuous => {
                Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&jt.axis, value))
            }
            JointKind::Prismatic => {
                Isometry3::from_parts(Translation3::from(jt.axis.into_inner() * value), UnitQuaternion::identity())
            }
        }
    }

    /// Forward kinematics: the pose of every link's frame in the root's frame, for the
    /// joint variables `q` (indexed like [`Robot::joint_names`]; `q.len()` must be the
    /// number of variables).
    pub fn link_poses(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        assert_eq!(q.len(), self.vars.len(), "one value per joint variable of `{}`", self.name);
        let mut poses = vec![Isometry3::identity(); self.links.len()];
        for &l in &self.order[1..] {
            if let Some(j) = self.parent_joint[l] {
                let jt = &self.joints[j];
                poses[l] = poses[jt.parent] * jt.origin * self.motion(j, self.value(j, q));
            }
        }
        poses
    }

    /// Every collision solid with the pose of its link's frame in the root's frame (the
    /// solid's own [`Solid::pose`] places it in that frame).
    pub fn solids_at(&self, q: &[f64]) -> impl Iterator<Item = (Isometry3<f64>, &Solid)> + '_ {
        let poses = self.link_poses(q);
        self.links.iter().enumerate().flat_map(move |(l, link)| {
            let p = poses[l];
            link.solids.iter().map(move |s| (p, s))
        })
    }

    /// Per link, `(frame, solids)`: upper bounds on the distance from the root's origin of
    /// the link's frame and of any point of its collision geometry, over every
    /// configuration the model allows. Along the chain: the sum of the joint-origin offsets
    /// and of each prismatic joint's largest `|value|` within its limits (rotations
    /// preserve lengths), plus the link's bounding radius for its solids. Infinite below a
    /// prismatic joint whose variable's limits are not a finite range `lower < upper`
    /// (no limits: a mimic of a continuous joint; a `<limit>` without positions, URDF's
    /// `0` and `0`; `lower` above `upper`), because those are exactly the limits the kind's
    /// invariant does not receive (`space::world::add_joint_limits`): the joint then slides
    /// as far as the contracts let it, which the URDF does not bound. Infinite also when
    /// the sum overflows. Linear in the number of links.
    pub fn reach(&self) -> Vec<(f64, f64)> {
        self.chain_reach(true)
    }

    /// [`Robot::reach`] with every prismatic joint's travel read from the numbers its
    /// `<limit>` writes, whether or not they are a range: the size of the file's own
    /// numbers, for the URDF size check (E0530), never a bound on where a
    /// link can be.
    pub fn written_reach(&self) -> Vec<(f64, f64)> {
        self.chain_reach(false)
    }

    fn chain_reach(&self, range_only: bool) -> Vec<(f64, f64)> {
        let n = self.links.len();
        let mut frame = vec![0.0f64; n];
        for &c in &self.order[1..] {
            let Some(j) = self.parent_joint[c] else { continue };
            let jt = &self.joints[j];
            let mut r = frame[jt.parent] + jt.origin.translation.vector.norm();
            if jt.kind == JointKind::Prismatic {
                r += match self.drive[j] {
                    Some((v, m, o)) => match self.joints[self.vars[v]].limits {
                        Some((lo, hi)) if !range_only || (lo.is_finite() && hi.is_finite() && lo < hi) => {
                            (m * lo + o).abs().max((m * hi + o).abs())
                        }
                        _ => f64::INFINITY,
                    },
                    None => 0.0,
                };
            }
            frame[c] = r;
        }
        (0..n).map(|l| (frame[l], frame[l] + self.link_radius[l])).collect()
    }

    /// Per link, an upper bound on how far any point of its collision geometry can be from
    /// where it is at `centre` when each variable `i` ranges over `centre[i] ± half_width[i]`
    /// (root fixed). `f64::INFINITY` when a width or a reach is unbounded (callers treat it
    /// as unknown).
    ///
    /// **Soundness** (path length). For `q` in the box, follow the straight segment from
    /// `centre` to `q`: it stays in the box (a box is convex). A point `p` of link L moves
    /// with velocity `Σ_j q̇_j · v_j` over the movable joints j on L's chain, where for a
    /// revolute joint `v_j = a_j × (p − o_j)` (a_j its unit axis, o_j its origin, a point on
    /// the axis), so `|v_j| ≤ |p − o_j|`, and for a prismatic joint `|v_j| = 1`. Hence
    /// `|p(q) − p(centre)| ≤ ∫|ṗ| ≤ Σ_revolute R_j |δ_j| + Σ_prismatic |δ_j|`, where
    /// `δ_j = m_j δ_var(j)` (a mimic joint moves `|m_j|` times its master) and `R_j` bounds
    /// `|p − o_j|` over the box: by the triangle inequality along the chain below j, the sum
    /// of the lengths of the joint-origin offsets after j, plus the reach `|value|` of every
    /// prismatic joint after j over the box, plus L's bounding radius (of its solids, slack
    /// included). Rotations preserve lengths, so none of these depends on the configuration.
    /// (The bound uses the box's own prismatic ranges, not the URDF limits: tighter, and
    /// still sound because the path never leaves the box.) The sum is enlarged by a relative
    /// 1e-9 against the rounding of its own computation.
    pub fn displacement_bound(&self, centre: &[f64], half_width: &[f64]) -> Vec<f64> {
        assert_eq!(centre.len(), self.vars.len(), "one centre per joint variable of `{}`", self.name);
        assert_eq!(half_width.len(), self.vars.len(), "one half width per joint variable of `{}`", self.name);
        let delta = |j: usize| -> (f64, f64) {
            // (|δ_j|, reach of joint j's value over the box)
            match self.drive[j] {
                Some((v, m, o)) => {
                    let h = half_width[v].abs();
                    let d = if h == 0.0 { 0.0 } else { m.abs() * h };
                    (d, (m * centre[v] + o).abs() + d)
                }
                None => (0.0, 0.0),
            }
        };
        // One pass from the root down (parents before children), so the cost is linear in
        // the number of links however deep the tree. Per link L: `spin[L]` = Σ |δ_j| over
        // the revolute joints j on L's chain, and `moved[L]` = Σ_revolute |δ_j| · (the
        // offsets and prismatic reaches on the chain below j, down to L's frame) +
        // Σ_prismatic |δ_j|. Passing joint j from parent P to child C lengthens the lever of
        // every revolute joint above j by `|origin_j|` (and j's reach if prismatic):
        // `moved[C] = moved[P] + spin[P] · (|origin_j| + reach_j) (+ |δ_j| if prismatic)`;
        // L's own solids then add `spin[L] · radius_L`. This is the sum of the path-length
        // bound above regrouped (all terms are non-negative, no cancellation); a product
        // with a zero `spin` is skipped so that an infinite reach below no revolute motion
        // is not 0 · ∞. A NaN half width makes its links' bounds infinite.
        let n = self.links.len();
        let (mut spin, mut moved) = (vec![0.0f64; n], vec![0.0f64; n]);
        for &c in &self.order[1..] {
            let Some(j) = self.parent_joint[c] else { continue };
            let jt = &self.joints[j];
            let p = jt.parent;
            let (d, r) = delta(j);
            let d = if d.is_nan() { f64::INFINITY } else { d };
            let (mut s, mut m) = (spin[p], moved[p]);
            let lever = jt.origin.translation.vector.norm();
            match jt.kind {
                JointKind::Fixed => {
                    if s > 0.0 {
                        m += s * lever;
                    }
                }
                JointKind::Revolute | JointKind::Continuous => {
                    if s > 0.0 {
                        m += s * lever;
                    }
                    if d > 0.0 {
                        s += d;
                    }
                }
                JointKind::Prismatic => {
                    if s > 0.0 {
                        m += s * (r + lever);
                    }
                    m += d;
                }
            }
            spin[c] = s;
            moved[c] = m;
        }
        (0..n)
            .map(|l| {
                let total = if spin[l] > 0.0 { moved[l] + spin[l] * self.link_radius[l] } else { moved[l] };
                let b = total * (1.0 + 1e-9);
                if b.is_nan() {
                    f64::INFINITY
                } else {
                    b
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A planar two-link arm: base → (revolute z at origin) → l1 → (revolute z at x = 1) → l2
    /// with a unit sphere... of radius 0.1 at x = 1 in l2.
    pub(crate) fn two_link() -> Robot {
        let link = |name: &str, solids| Link { name: name.into(), solids };
        let tip = Solid::sphere(0.1, Isometry3::translation(1.0, 0.0, 0.0), "tip").unwrap();
        let joint = |name: &str, p, c, x| Joint {
            name: name.into(),
            kind: JointKind::Revolute,
            parent: p,
            child: c,
            origin: Isometry3::translation(x, 0.0, 0.0),
            axis: Vector3::z_axis(),
            limits: Some((-3.0, 3.0)),
            velocity: None,
            mimic: None,
        };
        Robot::new(
            "two".into(),
            vec![link("base", vec![]), link("l1", vec![]), link("l2", vec![tip])],
            vec![joint("j1", 0, 1, 0.0), joint("j2", 1, 2, 1.0)],
        )
        .unwrap()
    }

    /// A base and a carriage on a prismatic joint along x whose limits are `limits`, the
    /// carriage a sphere of radius 0.1 at its frame.
    fn slider(limits: Option<(f64, f64)>) -> Robot {
        let link = |name: &str, solids| Link { name: name.into(), solids };
        let ball = Solid::sphere(0.1, Isometry3::identity(), "ball").unwrap();
        let joint = Joint {
            name: "slide".into(),
            kind: JointKind::Prismatic,
            parent: 0,
            child: 1,
            origin: Isometry3::translation(0.0, 0.0, 0.5),
            axis: Vector3::x_axis(),
            limits,
            velocity: None,
            mimic: None,
        };
        Robot::new("slider".into(), vec![link("base", vec![]), link("carriage", vec![ball])], vec![joint]).unwrap()
    }

    #[test]
    fn a_slider_reaches_as_far_as_its_limits_and_without_a_range_without_bound() {
        // Limits [-1, 2]: the frame at most 0.5 + 2 from the root, the ball 0.1 beyond.
        let r = slider(Some((-1.0, 2.0))).reach();
        assert!((r[1].0 - 2.5).abs() < 1e-12 && (r[1].1 - 2.6).abs() < 1e-12, "{r:?}");
        // The carriage at slide = 1.5 (the kind's invariant allows it: URDF's 0 and 0, or
        // an upper below the lower, are not given to it) is 1.58 m from the root, beyond
        // any finite reach the limits would give.
        for limits in [Some((0.0, 0.0)), Some((1.0, -1.0)), None] {
            let s = slider(limits);
            let far = s.link_poses(&[1.5])[1].translation.vector.norm();
            assert!(far > 1.5);
            assert_eq!(s.reach()[1].0, f64::INFINITY, "{limits:?}");
            assert_eq!(s.reach()[1].1, f64::INFINITY, "{limits:?}");
        }
        // The file's own numbers, for the size check: 0 and 0 are small.
        assert!((slider(Some((0.0, 0.0))).written_reach()[1].1 - 0.6).abs() < 1e-12);
    }

    #[test]
    fn forward_kinematics_of_a_planar_arm() {
        let r = two_link();
        assert_eq!(r.joint_names(), vec!["j1", "j2"]);
        let p = r.link_poses(&[std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2]);
        let tip = p[2] * Isometry3::translation(1.0, 0.0, 0.0);
        assert!((tip.translation.vector - Vector3::new(1.0, 1.0, 0.0)).norm() < 1e-12, "{tip:?}");
        // At j = 0 the tip is at x = 2 with radius 0.1: its link's bound radius is 1.1.
        assert!((r.link_radius[2] - 1.1).abs() < 1e-12);
    }

    #[test]
    fn displacement_bound_of_a_planar_arm() {
        let r = two_link();
        let b = r.displacement_bound(&[0.0, 0.0], &[0.1, 0.2]);
        // Link 2: j1 at distance ≤ 1 + 1.1, j2 at ≤ 1.1: 2.1 · 0.1 + 1.1 · 0.2.
        assert!((b[2] - (0.21 + 0.22)).abs() < 1e-6, "{b:?}");
        assert_eq!(b[0], 0.0);
        assert_eq!(r.displacement_bound(&[0.0, 0.0], &[f64::INFINITY, 0.0])[2], f64::INFINITY);
    }

    /// The bound is tight where the path-length argument is: one revolute joint turning a
    /// point at its largest distance. Moving j1 of the planar arm by δ moves the tip
    /// sphere's far point (2.1 from the axis) by the chord 2 · 2.1 · sin(δ/2) ≈ 2.1 δ, the
    /// bound. A prismatic joint below a revolute one lengthens the revolute's lever by its
    /// reach over the box.
    #[test]
    fn displacement_bound_is_sound_and_tight_on_a_lever() {
        let r = two_link();
        let far = |q: &[f64]| (r.link_poses(q)[2] * nalgebra::Point3::new(1.1, 0.0, 0.0)).coords;
        let b = r.displacement_bound(&[0.0, 0.0], &[0.01, 0.0])[2];
        let moved = (far(&[0.01, 0.0]) - far(&[0.0, 0.0])).norm();
        assert!(moved <= b && moved >= 0.999 * b, "moved {moved}, bound {b}");

        // base -(revolute z)-> l1 -(prismatic x)-> l2 with the sphere at x = 1.
        let tip = Solid::sphere(0.1, Isometry3::translation(1.0, 0.0, 0.0), "tip").unwrap();
        let link = |name: &str, solids| Link { name: name.into(), solids };
        let j = |name: &str, kind, p, c| Joint {
            name: name.into(),
            kind,
            parent: p,
            child: c,
            origin: Isometry3::identity(),
            axis: if kind == JointKind::Prismatic { Vector3::x_axis() } else { Vector3::z_axis() },
            limits: Some((-1.0, 1.0)),
            velocity: None,
            mimic: None,
        };
        let r = Robot::new(
            "slide".into(),
            vec![link("base", vec![]), link("l1", vec![]), link("l2", vec![tip])],
            vec![j("turn", JointKind::Revolute, 0, 1), j("slide", JointKind::Prismatic, 1, 2)],
        )
        .unwrap();
        let far = |q: &[f64]| (r.link_poses(q)[2] * nalgebra::Point3::new(1.1, 0.0, 0.0)).coords;
        let b = r.displacement_bound(&[0.0, 0.5], &[0.01, 0.0])[2];
        let moved = (far(&[0.01, 0.5]) - far(&[0.0, 0.5])).norm();
        assert!(moved <= b && moved >= 0.999 * b, "moved {moved}, bound {b}");
        // The slide itself moves every point of l2 by its δ.
        let b = r.displacement_bound(&[0.0, 0.5], &[0.0, 0.2])[2];
        assert!((b - 0.2).abs() < 1e-9, "{b}");
    }

    #[test]
    fn tree_errors() {
        let link = |name: &str| Link { name: name.into(), solids: vec![] };
        let joint = |p, c| Joint {
            name: format!("j{p}{c}"),
            kind: JointKind::Fixed,
            parent: p,
            child: c,
            origin: Isometry3::identity(),
            axis: Vector3::x_axis(),
            limits: None,
            velocity: None,
            mimic: None,
        };
        let e = Robot::new("r".into(), vec![], vec![]).unwrap_err();
        assert!(e.message.contains("no link"));
        let e = Robot::new("r".into(), vec![link("a"), link("b")], vec![]).unwrap_err();
        assert!(e.message.contains("2 root links"), "{e:?}");
        let e =
            Robot::new("r".into(), vec![link("a"), link("b"), link("c")], vec![joint(0, 1), joint(2, 1)]).unwrap_err();
        assert!(e.message.contains("child of two joints"), "{e:?}");
        let e =
            Robot::new("r".into(), vec![link("a"), link("b"), link("c")], vec![joint(1, 2), joint(2, 1)]).unwrap_err();
        assert!(e.message.contains("cycle"), "{e:?}");
        let mut m = joint(0, 1);
        m.kind = JointKind::Revolute;
        m.mimic = Some(Mimic { master: 0, multiplier: 1.0, offset: 0.0 });
        let e = Robot::new("r".into(), vec![link("a"), link("b")], vec![m]).unwrap_err();
        assert!(e.message.contains("cycle"), "{e:?}");
    }
}
