//! Tests of the branch and bound: turned boxes, passing balls, an arm on a cart past a
//! pillar, the first contact, the minimum distance, and the certified distance bound.

use super::*;
use parry3d::shape::SharedShape;

const T: usize = 0;

/// A solid placed by one affine pose.
fn solid(name: &str, shape: SharedShape, pose: AffinePose) -> SearchSolid {
    SearchSolid::new(name, shape, Box::new(vec![pose]))
}

fn ball(r: f64) -> SharedShape {
    SharedShape::ball(r)
}

/// Ball A (r 0.5) moves along x from -5 to 5 over t ∈ [0, 10]; ball B (r 0.5) rests at
/// (0, y, 0). Their least distance is `y - 1`, at t = 5.
fn passing_balls(y: f64) -> ParryScene {
    let a = solid("A", ball(0.5), AffinePose::fixed([-5.0, 0.0, 0.0, 0.0, 0.0, 0.0]).with(0, T, 1.0));
    let b = solid("B", ball(0.5), AffinePose::fixed([0.0, y, 0.0, 0.0, 0.0, 0.0]));
    ParryScene::new(1, [vec![a], vec![b]])
}

fn opts(res: &[f64]) -> Options {
    let mut o = Options::new(res.to_vec());
    o.time_dim = Some(T);
    o
}

fn root1() -> QBox {
    QBox::new(vec![0.0], vec![10.0])
}

fn report(name: &str, d: &Verdict) {
    eprintln!(
        "{name}: {} nodes, {} distance calls, {} witness calls, {:?}",
        d.stats.nodes, d.stats.distance_calls, d.stats.witness_calls, d.stats.elapsed
    );
}

/// The passing balls with the constraint `t >= 6` (after the balls have passed), told to
/// the search only through `contract` (`feasible` says Maybe everywhere), possibly
/// answering with a box larger than asked (`widen`: a contraction may only shrink).
struct AfterSix {
    inner: ParryScene,
    widen: bool,
}
impl Scene for AfterSix {
    fn dims(&self) -> usize {
        1
    }
    fn distance(&self, q: &[f64]) -> Closest {
        self.inner.distance(q)
    }
    fn motion_bound(&self, lo: &[f64], hi: &[f64], c: &[f64]) -> f64 {
        self.inner.motion_bound(lo, hi, c)
    }
    fn feasible(&self, _: &[f64], _: &[f64]) -> Feasible {
        Feasible::Maybe
    }
    fn contract(&self, b: &QBox) -> Option<QBox> {
        if self.widen {
            return Some(QBox::new(vec![b.lo[0] - 100.0], vec![b.hi[0] + 100.0]));
        }
        let lo = b.lo[0].max(6.0);
        (lo <= b.hi[0]).then(|| QBox::new(vec![lo], b.hi.clone()))
    }
    fn witness(&self, lo: &[f64], hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        let lo = [lo[0].max(6.0)];
        (lo[0] <= hi[0]).then(|| Unconstrained.witness(&lo, hi, near)).flatten()
    }
    fn solid_name(&self, side: usize, solid: usize) -> String {
        self.inner.solid_name(side, solid)
    }
}

/// A box is evaluated after contraction: its centre and motion bound are the narrowed
/// box's. Balls touching at t = 5 (y = 0.9) are apart for t >= 6, which the search proves
/// in a few boxes only through the contraction; a contraction answering a larger box is
/// intersected with the box, so the touching balls are still found (never lost).
#[test]
fn a_contracted_box_is_evaluated_and_a_contraction_only_shrinks() {
    let s = AfterSix { inner: passing_balls(0.9), widen: false };
    let d = decide(&s, &root1(), &opts(&[1e-4]));
    report("after six", &d);
    assert!(matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
    assert!(d.stats.nodes <= 3, "{:?}", d.stats);
    let w = AfterSix { inner: passing_balls(0.9), widen: true };
    let d = decide(&w, &root1(), &opts(&[1e-4]));
    // The widened answer is cut back to the box; the witness still only looks at t >= 6,
    // so no contact is confirmed there, but nothing is proved apart either.
    assert!(!matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
}

#[test]
fn grazing_balls_1e_3_apart_are_proved_apart() {
    let s = passing_balls(1.001);
    let d = decide(&s, &root1(), &opts(&[1e-4]));
    report("grazing 1e-3", &d);
    match d.outcome {
        Outcome::Apart { min_lower_bound, .. } => {
            assert!(min_lower_bound > 0.0 && min_lower_bound <= 1e-3 + 1e-6, "{min_lower_bound}");
        }
        o => panic!("expected apart, got {o:?}"),
    }
}

#[test]
fn penetrating_balls_1e_3_deep_contact_at_the_first_time_and_place() {
    let s = passing_balls(0.999);
    let d = decide(&s, &root1(), &opts(&[1e-4]));
    report("penetrating 1e-3", &d);
    let Outcome::Contact(c) = d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
    // First touch: (t - 5)^2 + 0.999^2 = 1.
    let first = 5.0 - (1.0f64 - 0.999 * 0.999).sqrt();
    let before = c.clear_before.unwrap();
    assert!(before <= first + 1e-5, "clear before {before} > first contact {first}");
    // Boxes in the band where the distance is below the pads stay unknown: the
    // guaranteed window [clear_before, q] is a little wider than the resolution.
    assert!(c.q[0] >= first - 1e-5 && c.q[0] - before <= 2e-3, "{c:?}");
    assert!(c.distance <= 0.0);
    assert_eq!(c.names, ["A".to_string(), "B".to_string()]);
    // Near the first touch the contact point lies on the segment between the centres,
    // at half the way: ((t - 5) / 2, 0.4995, 0).
    assert!((c.point[0] - (c.q[0] - 5.0) / 2.0).abs() < 1e-3, "{:?}", c.point);
    assert!((c.point[1] - 0.4995).abs() < 1e-3, "{:?}", c.point);
}

#[test]
fn the_first_of_two_contacts_is_reported() {
    // A passes B2 (at x = -2) before B1 (at x = 2).
    let a = solid("A", ball(0.5), AffinePose::fixed([-5.0, 0.0, 0.0, 0.0, 0.0, 0.0]).with(0, T, 1.0));
    let b1 = solid("B1", ball(0.5), AffinePose::fixed([2.0, 0.5, 0.0, 0.0, 0.0, 0.0]));
    let b2 = solid("B2", ball(0.5), AffinePose::fixed([-2.0, 0.5, 0.0, 0.0, 0.0, 0.0]));
    let s = ParryScene::new(1, [vec![a], vec![b1, b2]]);
    let d = decide(&s, &root1(), &opts(&[1e-3]));
    let Outcome::Contact(c) = d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
    assert_eq!(c.names[1], "B2");
    let first = 3.0 - 0.75f64.sqrt();
    assert!(c.clear_before.unwrap() <= first && c.q[0] - first < 2e-3, "{c:?}");
}

/// A bar (4 x 0.1 x 0.1, centred on the origin) turning about z by yaw = t, t ∈ [0, π],
/// and a box of side 0.4 turned by 30° with its centre at (c, c, 0).
fn turning_bar(c: f64) -> ParryScene {
    let bar = solid("bar", SharedShape::cuboid(2.0, 0.05, 0.05), AffinePose::fixed([0.0; 6]).with(5, T, 1.0));
    let obstacle =
        solid("box", SharedShape::cuboid(0.2, 0.2, 0.2), AffinePose::fixed([c, c, 0.0, 0.0, 0.0, 30f64.to_radians()]));
    ParryScene::new(1, [vec![bar], vec![obstacle]])
}

#[test]
fn turning_bar_sweeping_past_a_turned_box() {
    let root = QBox::new(vec![0.0], vec![std::f64::consts::PI]);
    // The box's nearest point is about 2.12 - 0.27 = 1.85 < 2 from the axis: contact.
    let d = decide(&turning_bar(1.5), &root, &opts(&[1e-4]));
    report("turning bar, contact", &d);
    let Outcome::Contact(c) = &d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
    assert!(c.q[0] > 0.5 && c.q[0] < std::f64::consts::FRAC_PI_4, "{c:?}");
    assert_eq!(c.names, ["bar".to_string(), "box".to_string()]);
    // Far enough: the box's nearest point is about 2.4 - 0.27 > 2.0006.
    let d = decide(&turning_bar(1.7), &root, &opts(&[1e-4]));
    report("turning bar, apart", &d);
    assert!(matches!(d.outcome, Outcome::Apart { .. }), "{:?}", d.outcome);
    assert!(d.stats.nodes < 5_000, "{:?}", d.stats);
}

/// `t ≤ limit`.
struct Before(f64);
impl Constraints for Before {
    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
        if lo[T] > self.0 {
            Feasible::No
        } else if hi[T] <= self.0 {
            Feasible::All
        } else {
            Feasible::Maybe
        }
    }
    fn witness(&self, lo: &[f64], _hi: &[f64], near: &[f64]) -> Option<Vec<f64>> {
        (lo[T] <= self.0).then(|| vec![near[T].min(self.0)])
    }
}

#[test]
fn an_infeasible_collision_is_apart() {
    let mut s = passing_balls(0.5);
    s.constraints = Box::new(Before(4.0));
    let d = decide(&s, &root1(), &opts(&[1e-4]));
    report("infeasible collision", &d);
    match d.outcome {
        Outcome::Apart { infeasible, .. } => assert!(infeasible > 0),
        o => panic!("expected apart, got {o:?}"),
    }
    // Without the constraint it collides (the test can fail).
    let s = passing_balls(0.5);
    assert!(matches!(decide(&s, &root1(), &opts(&[1e-4])).outcome, Outcome::Contact(_)));
}

#[test]
fn everywhere_infeasible_is_apart_but_vacuous() {
    let mut s = passing_balls(0.0);
    s.constraints = Box::new(Before(-1.0));
    let d = decide(&s, &root1(), &opts(&[1e-4]));
    assert!(d.outcome.is_vacuous(), "{:?}", d.outcome);
    let mut s = passing_balls(0.0);
    s.constraints = Box::new(Before(4.0));
    assert!(!decide(&s, &root1(), &opts(&[1e-4])).outcome.is_vacuous());
}

#[test]
fn closer_than_the_resolution_is_unknown() {
    // 1e-7 apart: beyond what a coarse resolution can prove, and not a contact.
    let s = passing_balls(1.0 + 1e-7);
    let d = decide(&s, &root1(), &opts(&[0.05]));
    match d.outcome {
        Outcome::Unknown { why: UnknownWhy::Resolution, qbox, .. } => {
            assert!(qbox.lo[0] >= 4.0 && qbox.hi[0] <= 6.0, "{qbox:?}")
        }
        o => panic!("expected unknown, got {o:?}"),
    }
}

#[test]
fn budgets_exhausted_are_unknown() {
    let s = passing_balls(1.001);
    let mut o = opts(&[1e-4]);
    o.max_nodes = 5;
    let d = decide(&s, &root1(), &o);
    assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::Nodes(5), .. }), "{:?}", d.outcome);
    let mut o = opts(&[1e-4]);
    o.deadline = Some(Instant::now());
    let d = decide(&s, &root1(), &o);
    assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::Deadline, .. }), "{:?}", d.outcome);
}

#[test]
fn malformed_boxes_are_unknown() {
    let s = passing_balls(2.0);
    for b in [
        QBox::new(vec![0.0, 1.0], vec![1.0, 2.0]),
        QBox::new(vec![1.0], vec![0.0]),
        QBox::new(vec![0.0], vec![f64::INFINITY]),
        QBox::new(vec![f64::NAN], vec![1.0]),
    ] {
        let d = decide(&s, &b, &opts(&[1e-3]));
        assert!(matches!(d.outcome, Outcome::Unknown { why: UnknownWhy::BadBox, .. }));
    }
}

#[test]
fn certified_lower_bound_is_below_the_true_distance() {
    // Two unit cubes 0.25 apart, one turned: the exact distance is known.
    let s1 = SharedShape::cuboid(0.5, 0.5, 0.5);
    let p1 = pose_isometry(&[0.0; 6]);
    let p2 = pose_isometry(&[1.25, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let (d, lower, _) = parry_closest(&s1, &p1, &s1, &p2);
    assert!((d - 0.25).abs() < 1e-5 && lower <= 0.25 && lower > 0.2499, "{d} {lower}");
    // A sphere against a cube corner: sqrt(3) * 2 - 0.5*sqrt(3) - 1.
    let b = SharedShape::ball(1.0);
    let p2 = pose_isometry(&[2.0, 2.0, 2.0, 0.0, 0.0, 0.0]);
    let truth = 2.0 * 3f64.sqrt() - 0.5 * 3f64.sqrt() - 1.0;
    let (d, lower, _) = parry_closest(&s1, &p1, &b, &p2);
    assert!((d - truth).abs() < 1e-4 && lower <= truth && lower > truth - 1e-4, "{d} {lower}");
}

/// Property: for random turned boxes against balls (whose exact distance is the
/// distance from the ball's centre to the box, in the box's frame, minus the radius),
/// the certified lower bound never exceeds the truth and is close to it.
#[test]
fn certified_lower_bound_on_random_box_ball_pairs() {
    use crate::geometry::placement::tests::Rng;
    let mut rng = Rng::new(17);
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        // Lengths representable in f32, so parry's shapes are exactly these.
        let mut f = |a: f64, b: f64| rng.range(a, b);
        let h = [f(0.05, 1.0), f(0.05, 1.0), f(0.05, 1.0)];
        let cube = SharedShape::cuboid(h[0], h[1], h[2]);
        let args = [
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
        ];
        let p1 = pose_isometry(&args);
        let r = rng.range(0.05, 1.0);
        let centre =
            Point3::new(args[0] + rng.range(-3.0, 3.0), args[1] + rng.range(-3.0, 3.0), args[2] + rng.range(-3.0, 3.0));
        let p2 = Isometry3::translation(centre.x, centre.y, centre.z);
        let local = p1.inverse_transform_point(&centre);
        let out = Vector3::new(
            (local.x.abs() - h[0]).max(0.0),
            (local.y.abs() - h[1]).max(0.0),
            (local.z.abs() - h[2]).max(0.0),
        );
        let truth = out.norm() - r;
        if truth <= 1e-3 {
            continue;
        }
        let (d, lower, _) = parry_closest(&cube, &p1, &SharedShape::ball(r), &p2);
        assert!(lower <= truth, "lower {lower} above the truth {truth} (parry {d})");
        worst = worst.max(truth - lower);
    }
    assert!(worst < 1e-3, "certificate too loose: {worst}");
}

#[test]
fn clearance_of_passing_balls() {
    let s = passing_balls(2.0);
    let c = min_distance(&s, &root1(), 1e-4, &opts(&[1e-6]));
    eprintln!("clearance: {c:?}");
    assert!(c.complete, "{c:?}");
    assert!(c.lower <= 1.0 && c.upper >= 1.0 - 1e-5 && c.upper - c.lower <= 1e-4, "{c:?}");
    let q = c.at_q.unwrap();
    assert!((q[0] - 5.0).abs() < 0.05, "{q:?}");
    assert_eq!(c.names.unwrap(), ["A".to_string(), "B".to_string()]);
    // With the constraint t ≤ 4 the least distance is at t = 4: sqrt(1 + 4) - 1.
    let mut s = passing_balls(2.0);
    s.constraints = Box::new(Before(4.0));
    let c = min_distance(&s, &root1(), 1e-4, &opts(&[1e-6]));
    let truth = 5f64.sqrt() - 1.0;
    assert!(c.lower <= truth && c.upper >= truth - 1e-5 && c.upper - c.lower <= 1e-4, "{c:?}");
    assert!(c.at_q.unwrap()[0] <= 4.0);
}

/// Property: random scenes of two to four solids in two dimensions (time and an
/// angle): apart means dense sampling finds no contact (and no distance below the
/// claimed lower bound); contact means the returned `q` is in the box and touches.
#[test]
fn random_scenes_agree_with_sampling() {
    use crate::geometry::placement::tests::Rng;
    let mut rng = Rng::new(3);
    let (mut apart, mut contact, mut unknown) = (0, 0, 0);
    for case in 0..60 {
        let shape = |rng: &mut Rng| match (rng.next() * 3.0) as usize {
            0 => SharedShape::ball(rng.range(0.1, 0.6)),
            1 => SharedShape::cuboid(rng.range(0.05, 0.6), rng.range(0.05, 0.6), rng.range(0.05, 0.6)),
            _ => SharedShape::capsule_z(rng.range(0.05, 0.5), rng.range(0.05, 0.3)),
        };
        let pose = |rng: &mut Rng| {
            let mut p = AffinePose::fixed([
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-0.5, 0.5),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ]);
            for j in 0..6 {
                for i in 0..2 {
                    if rng.next() < 0.3 {
                        p = p.with(j, i, rng.range(-1.0, 1.0));
                    }
                }
            }
            p
        };
        let side = |rng: &mut Rng, tag: &str| -> Vec<SearchSolid> {
            (0..1 + (rng.next() * 2.0) as usize)
                .map(|k| {
                    let chain: Vec<AffinePose> = (0..1 + (rng.next() * 2.0) as usize).map(|_| pose(rng)).collect();
                    SearchSolid::new(&format!("{tag}{k}"), shape(rng), Box::new(chain))
                })
                .collect()
        };
        let s = ParryScene::new(2, [side(&mut rng, "a"), side(&mut rng, "b")]);
        let root = QBox::new(vec![0.0, -1.0], vec![2.0, 1.0]);
        let mut o = Options::new(vec![1e-3, 1e-3]);
        o.time_dim = if case % 2 == 0 { Some(0) } else { None };
        o.split = if case % 3 == 0 { SplitRule::WidestScaled } else { SplitRule::Sensitivity };
        let d = decide(&s, &root, &o);
        match &d.outcome {
            Outcome::Apart { min_lower_bound, .. } => {
                apart += 1;
                for i in 0..=40 {
                    for j in 0..=40 {
                        let q = [2.0 * i as f64 / 40.0, -1.0 + 2.0 * j as f64 / 40.0];
                        let x = s.distance(&q).distance;
                        assert!(x > 0.0, "case {case}: apart, but distance {x} at {q:?}");
                        assert!(x >= min_lower_bound - 1e-4, "case {case}: {x} < {min_lower_bound}");
                    }
                }
            }
            Outcome::Contact(c) => {
                contact += 1;
                assert!(root.contains(&c.q) && s.distance(&c.q).distance <= 0.0, "case {case}: {c:?}");
            }
            Outcome::Unknown { .. } => unknown += 1,
        }
    }
    eprintln!("random scenes: {apart} apart, {contact} contact, {unknown} unknown");
    assert!(apart > 5 && contact > 5, "{apart} apart, {contact} contact");
}

/// An arm on a cart, in four dimensions `(t, θ1, θ2, θ3)`: the cart drives along x
/// (x = -3 + t) while turning (yaw = 0.5 t), the arm's three revolute joints range
/// over [-0.5, 0.5] each (shoulder yaw θ1, elbow pitch θ2, wrist pitch θ3), and a
/// pillar stands at (0, y, 0). Sampling cross-checks the verdict.
fn mounted_arm(pillar_y: f64) -> ParryScene {
    let cart = || AffinePose::fixed([-3.0, 0.0, 0.1, 0.0, 0.0, 0.0]).with(0, 0, 1.0).with(5, 0, 0.5);
    let j1 = || AffinePose::fixed([0.0, 0.0, 0.2, 0.0, 0.0, 0.0]).with(5, 1, 1.0);
    let j2 = || AffinePose::fixed([0.0, 0.0, 0.1, 0.0, 0.0, 0.0]).with(4, 2, 1.0);
    let j3 = || AffinePose::fixed([0.0, 0.0, 0.4, 0.0, 0.0, 0.0]).with(4, 3, 1.0);
    // A link: a capsule from its joint's origin up its z axis, `len` long.
    let link = |len: f64| AffinePose::fixed([0.0, 0.0, len / 2.0, 0.0, 0.0, 0.0]);
    let side0 = vec![
        SearchSolid::new("cart", SharedShape::cuboid(0.3, 0.2, 0.1), Box::new(vec![cart()])),
        SearchSolid::new("base", SharedShape::ball(0.08), Box::new(vec![cart(), j1()])),
        SearchSolid::new("upper", SharedShape::capsule_z(0.2, 0.05), Box::new(vec![cart(), j1(), j2(), link(0.4)])),
        SearchSolid::new(
            "fore",
            SharedShape::capsule_z(0.2, 0.04),
            Box::new(vec![cart(), j1(), j2(), j3(), link(0.4)]),
        ),
    ];
    let pillar = SearchSolid::new(
        "pillar",
        // parry's cylinder stands on y; roll 90° stands it on z.
        SharedShape::cylinder(1.0, 0.15),
        Box::new(vec![AffinePose::fixed([0.0, pillar_y, 1.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0])]),
    );
    ParryScene::new(4, [side0, vec![pillar]])
}

fn arm_root() -> QBox {
    QBox::new(vec![0.0, -0.5, -0.5, -0.5], vec![6.0, 0.5, 0.5, 0.5])
}

fn sampled_min(s: &ParryScene, n: usize) -> f64 {
    let r = arm_root();
    let mut m = f64::INFINITY;
    let mut rng = crate::geometry::placement::tests::Rng::new(5);
    for _ in 0..n {
        let q: Vec<f64> = r.lo.iter().zip(&r.hi).map(|(l, h)| rng.range(*l, *h)).collect();
        m = m.min(s.distance(&q).distance);
    }
    m
}

#[test]
fn mounted_arm_past_a_pillar() {
    let mut o = Options::new(vec![1e-3; 4]);
    o.time_dim = Some(0);
    let apart = mounted_arm(0.9);
    let d = decide(&apart, &arm_root(), &o);
    report("mounted arm, apart", &d);
    let Outcome::Apart { min_lower_bound, .. } = d.outcome else { panic!("expected apart, got {:?}", d.outcome) };
    let sampled = sampled_min(&apart, 3000);
    assert!(min_lower_bound > 0.0 && sampled >= min_lower_bound, "{sampled} {min_lower_bound}");
    let touching = mounted_arm(0.6);
    // Coarser in the joints: the first-contact pass resolves the grazing band box by box.
    o.resolution = vec![1e-3, 1e-2, 1e-2, 1e-2];
    let d = decide(&touching, &arm_root(), &o);
    report("mounted arm, contact", &d);
    let Outcome::Contact(c) = &d.outcome else { panic!("expected contact, got {:?}", d.outcome) };
    eprintln!("  at {:?}, clear before {:?}", c.q, c.clear_before);
    assert!(touching.distance(&c.q).distance <= 0.0 && c.names[1] == "pillar", "{c:?}");
    let mut any = o.clone();
    any.time_dim = None;
    let d = decide(&touching, &arm_root(), &any);
    report("mounted arm, any contact", &d);
    assert!(matches!(d.outcome, Outcome::Contact(_)), "{:?}", d.outcome);
    let o = Options::new(vec![1e-3; 4]);
    let c = min_distance(&apart, &arm_root(), 2e-2, &o);
    eprintln!(
        "mounted arm clearance: [{}, {}] at {:?} ({:?}), {} nodes, {:?}",
        c.lower, c.upper, c.at_q, c.names, c.stats.nodes, c.stats.elapsed
    );
    assert!(c.lower <= sampled && c.lower > 0.0, "{c:?}");
}

/// Two dimensions tied by a thin band, `|y - x| <= 0.001` (a joint that follows the clock
/// within its tracking error), told through `contract` and `feasible`.
struct Band;
impl Scene for Band {
    fn dims(&self) -> usize {
        2
    }
    fn distance(&self, _: &[f64]) -> Closest {
        Closest { distance: 1.0, lower: 1.0, points: [[0.0; 3]; 2], solids: [0, 0] }
    }
    fn motion_bound(&self, _: &[f64], _: &[f64], _: &[f64]) -> f64 {
        0.0
    }
    fn feasible(&self, lo: &[f64], hi: &[f64]) -> Feasible {
        if hi[1] < lo[0] - 0.001 || lo[1] > hi[0] + 0.001 {
            Feasible::No
        } else {
            Feasible::Maybe
        }
    }
    fn contract(&self, b: &QBox) -> Option<QBox> {
        let (mut lo, mut hi) = (b.lo.clone(), b.hi.clone());
        lo[1] = lo[1].max(lo[0] - 0.001);
        hi[1] = hi[1].min(hi[0] + 0.001);
        lo[0] = lo[0].max(lo[1] - 0.001);
        hi[0] = hi[0].min(hi[1] + 0.001);
        (lo[0] <= hi[0] && lo[1] <= hi[1]).then(|| QBox::new(lo, hi))
    }
    fn witness(&self, _: &[f64], _: &[f64], _: &[f64]) -> Option<Vec<f64>> {
        None
    }
    fn solid_name(&self, _: usize, _: usize) -> String {
        "band".into()
    }
}

/// A probe drawn uniformly from the box almost never lands in a thin band of the
/// constraints (so a contact that needs it was never confirmed before the search had
/// narrowed the box: the mounted arm, whose joint follows the clock within 0.02 rad, came
/// back unknown when each box was slow); drawn one dimension at a time with the box
/// contracted after each, every probe is in the band.
#[test]
fn a_probe_drawn_through_the_contraction_lands_in_a_thin_band() {
    let b = QBox::new(vec![0.0, 0.0], vec![10.0, 10.0]);
    let inside = |q: &[f64]| Band.feasible(q, q) != Feasible::No;
    let uniform = (1..=200).filter(|s| inside(&draw(&b, *s))).count();
    let contracted: Vec<Vec<f64>> = (1..=200).filter_map(|s| draw_contracted(&Band, &b, s)).collect();
    assert!(uniform < 10, "{uniform} of 200 uniform draws in the band");
    assert_eq!(contracted.len(), 200);
    assert!(contracted.iter().all(|q| inside(q) && b.contains(q)), "{contracted:?}");
}
