//! A generator of turning footprints beside obstacles, with a ground truth of its own: a
//! defence for the interval search that decides a footprint written with `cos`/`sin` of
//! the state against a static obstacle (E0510, `collision/predicate.rs`).
//!
//! Each scene is the cart of `choreographies/turning-cart-beside-a-post.chor` (a square
//! footprint of half-side 0.262 m in its heading frame, turning on the spot from heading 0
//! to 1.5 rad, its frame at (1, 2) turned by 0.4 rad) beside one obstacle: a box (turned
//! by a random yaw), a cylinder or a ball, of random size, at a random bearing and a
//! distance where the square's corners may or may not reach it (0.30 to 0.48 m).
//!
//! **The oracle is independent of mochi.** It samples the obstacle's points on the floor
//! (`z == 0`, which every obstacle here and the footprint share) and the heading, and
//! measures each point in the square's own norm: `max(|u|, |v|) - 0.262` in the heading
//! frame. A sampled point with a negative measure is a contact (a point in both at that
//! heading), so the scene must never be `verified`; a clearly negative minimum must be
//! found (`rejected`); a minimum above the sampling's resolution must verify. Between the
//! two thresholds mochi may say anything but `verified` on a contact.
//!
//! Budget: `MOCHI_GEN_CASES` scenes (default 6; the long mode is a larger count, with
//! `MOCHI_GEN_SEED` for another sequence). Failures print the scene's source.

use mochi::driver::{Config, Verdict};
use mochi::source::SourceDb;
use mochi_core::splitmix::SplitMix64;

const HALF: f64 = 0.262;

/// The obstacle of a scene, in metres and radians (world frame).
#[derive(Clone, Copy, Debug)]
enum Shape {
    Box { l: f64, w: f64, yaw: f64 },
    Cylinder { r: f64 },
    Ball { r: f64 },
}

#[derive(Clone, Copy, Debug)]
struct Scene {
    shape: Shape,
    cx: f64,
    cy: f64,
}

/// The scenes' generator (`mochi_core::splitmix`), so a seed names a sequence of scenes.
struct Rng(SplitMix64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// A value in [lo, hi], rounded to 0.1 mm (so the source writes it exactly).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        ((lo + (hi - lo) * u) * 1e4).round() / 1e4
    }
}

fn scene(rng: &mut Rng) -> Scene {
    let shape = match rng.next() % 3 {
        0 => Shape::Box { l: rng.uniform(0.03, 0.2), w: rng.uniform(0.03, 0.2), yaw: rng.uniform(0.0, 3.0) },
        1 => Shape::Cylinder { r: rng.uniform(0.02, 0.1) },
        _ => Shape::Ball { r: rng.uniform(0.02, 0.1) },
    };
    let (bearing, d) = (rng.uniform(0.0, std::f64::consts::TAU), rng.uniform(0.30, 0.48));
    let round = |v: f64| (v * 1e4).round() / 1e4;
    Scene { shape, cx: round(1.0 + d * bearing.cos()), cy: round(2.0 + d * bearing.sin()) }
}

fn source(s: &Scene) -> String {
    let geometry = match s.shape {
        Shape::Box { l, w, yaw } => format!("box({l}, {w}, 0.5) at pose(0, 0, 0, 0, 0, {yaw})"),
        Shape::Cylinder { r } => format!("cylinder({r}, 0.5)"),
        Shape::Ball { r } => format!("sphere({r})"),
    };
    format!(
        "const half: real = {HALF};
robot HexCart {{
  state x: real, y: real, theta: real;
  geometry: cylinder(0.257, 0.08) at pose(x, y, 0);
  invariant: -10 <= x <= 10 && -10 <= y <= 10 && -4 <= theta <= 4;
}}
motion HexCart.spin(d: real) {{
  interruptible: false;
  pre: 0 < d && d <= 10 && -1 <= theta <= 1;
  assume: true;
  guarantee: theta == old(theta) + 0.15 * clock && x == old(x) && y == old(y);
  post: theta == old(theta) + 0.15 * d && x == old(x) && y == old(y);
  footprint(px, py, pz): abs(cos(theta) * (px - x) + sin(theta) * (py - y)) <= half
                      && abs(cos(theta) * (py - y) - sin(theta) * (px - x)) <= half
                      && 0 <= pz <= 0.085;
  duration: [d, d];
}}
system Spin {{
  participant Cart: HexCart {{ init: x == 0 && y == 0 && theta == 0; at: pose(1, 2, 0, 0, 0, 0.4); }}
  obstacle Post {{ geometry: {geometry}; at: pose({}, {}, 0); }}
}}
choreography Spin = dt<Cart: spin(10)>. end;
process Cart = dt<spin(10)>.end;
",
        s.cx, s.cy
    )
}

/// The least measure over the sampled floor points of the obstacle and the sampled
/// headings: negative means a sampled point lies in the footprint at a sampled heading.
fn measure(s: &Scene) -> f64 {
    let mut points = Vec::new();
    match s.shape {
        Shape::Box { l, w, yaw } => {
            for i in 0..=16 {
                for j in 0..=16 {
                    let (a, b) = (-l / 2.0 + l * f64::from(i) / 16.0, -w / 2.0 + w * f64::from(j) / 16.0);
                    points.push((s.cx + a * yaw.cos() - b * yaw.sin(), s.cy + a * yaw.sin() + b * yaw.cos()));
                }
            }
        }
        Shape::Cylinder { r } | Shape::Ball { r } => {
            for i in 0..=12 {
                for j in 0..64 {
                    let (rr, a) = (r * f64::from(i) / 12.0, std::f64::consts::TAU * f64::from(j) / 64.0);
                    points.push((s.cx + rr * a.cos(), s.cy + rr * a.sin()));
                }
            }
        }
    }
    let mut best = f64::INFINITY;
    for k in 0..=600 {
        let heading = 0.4 + 1.5 * f64::from(k) / 600.0;
        let (c, sn) = (heading.cos(), heading.sin());
        for &(px, py) in &points {
            let (dx, dy) = (px - 1.0, py - 2.0);
            let (u, v) = (c * dx + sn * dy, c * dy - sn * dx);
            best = best.min(u.abs().max(v.abs()) - HALF);
        }
    }
    best
}

fn cases() -> u64 {
    std::env::var("MOCHI_GEN_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(6)
}

#[test]
fn generated_turning_footprints_agree_with_their_sampled_ground_truth() {
    let seed: u64 = std::env::var("MOCHI_GEN_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(15);
    let mut rng = Rng(SplitMix64(seed));
    let mut tally = [0usize; 3];
    for n in 0..cases() {
        let s = scene(&mut rng);
        let src = source(&s);
        let m = measure(&s);
        let mut db = SourceDb::new();
        let mut cfg = Config::patient();
        cfg.smt.jobs = 1;
        let r = mochi::fsload::check_source(&mut db, "turning.chor", &src, &cfg);
        let codes: Vec<&str> = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code.as_str()).collect();
        tally[match r.verdict {
            Verdict::Verified => 0,
            Verdict::Rejected => 1,
            _ => 2,
        }] += 1;
        if m < 0.0 {
            assert_ne!(r.verdict, Verdict::Verified, "FALSE VERIFIED (scene {n}, sampled measure {m:.4}):\n{src}");
        }
        // The sampling's resolution: 1.5 / 600 rad of heading at 0.37 m, and the points'
        // spacing (at most 0.2 / 16 m), each well under 1 cm.
        if m < -0.01 {
            assert!(
                r.verdict == Verdict::Rejected && codes.contains(&"E0510"),
                "a contact {m:.4} m deep, yet {:?} {codes:?} (scene {n}):\n{src}",
                r.verdict
            );
        }
        if m > 0.01 {
            assert_eq!(r.verdict, Verdict::Verified, "false alarm: {m:.4} m clear, yet {codes:?} (scene {n}):\n{src}");
        }
    }
    eprintln!(
        "turning footprints: {} scenes, verified {}, rejected {}, other {}",
        cases(),
        tally[0],
        tally[1],
        tally[2]
    );
}
