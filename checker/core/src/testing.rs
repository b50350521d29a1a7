//! Helpers shared by the unit tests of several stages, of this crate and of `mochi-verify`
//! (compiled for tests, and with the feature `testing`, which `mochi-verify`'s tests enable).

use crate::diag::Diagnostic;
use crate::hir::Program;
use crate::lower::lower;
use crate::source::{FileId, SourceDb};
use crate::syntax::Parsed;
use std::time::Duration;

/// Asserts that `time(n)` grows about linearly: at `big` = 8 x `small` the time may be at
/// most 24 times as long (linear is x8, the quadratic code these tests guard against was
/// x40 and more). Timings on a loaded machine stray, so one of three attempts must pass.
/// The tests that use it are `#[ignore]`d: speed is the benchmarks' to measure, and these
/// are for a quiet machine (`cargo test -- --ignored`).
pub fn assert_near_linear(what: &str, small: usize, big: usize, time: impl Fn(usize) -> Duration) {
    let mut seen = Vec::new();
    for _ in 0..3 {
        let (s, b) = (time(small), time(big));
        seen.push((s, b));
        if b < s * 24 {
            return;
        }
    }
    panic!("{what}: {small} vs {big}: {seen:?}");
}

/// Lowers `src` (which must be clean) and returns the guard of the choreography's first
/// message, which must be a sequence starting with a guarded message.
pub fn first_guard(src: &str) -> (Program, crate::hir::Expr) {
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
        panic!("a sequence")
    };
    let crate::hir::Global::Msg(m) = &items[0] else { panic!("a message") };
    let g = m.guard.clone().expect("guard");
    (prog, g)
}

/// Parses and lowers one source text (which must parse): the program and lowering's
/// diagnostics.
pub fn lower_src(src: &str) -> (Program, Vec<Diagnostic>) {
    let mut db = SourceDb::new();
    let id = db.add("test.chor", src);
    let (f, mut d) = crate::syntax::parser::parse(id, src);
    assert!(d.is_empty(), "parse errors: {d:?}");
    let (p, d2) = lower(&Parsed { files: vec![(FileId(id.0), f)] });
    d.extend(d2);
    (p, d)
}

pub const HEADER: &str = "
    const amax = 0.5;
    robot Cart { state x: real, v: real; invariant: v >= 0; }
    robot Arm { state h: real; input x: real; }
    motion Cart.move(xf: real) { interruptible: false; pre: xf > x && v == 0; post: x == xf; duration: [2 * sqrt(xf / amax), inf]; }
    motion Cart.idle { interruptible: true; guarantee: x == old(x); }
    motion Arm.work { interruptible: true; assume: x <= 1.0; footprint(px, py, pz): pz >= 0 && clock >= 0; }
    system S {
      participant C: Cart { init: x == 0 && v == 0; at: pose(0, 0, 0); }
      participant A: Arm { at: pose(2, 1, 0); }
    }
";

/// The cart-and-arms example (Fig 2 as corrected in wf-rules.md): the cart tells
/// both arms which one it serves, moves there, and comes back.
pub const CART_ARMS: &str = "
    robot Cart { state x: real; }
    robot Arm { state h: real; }
    motion Cart.m_move(p: real) { interruptible: false; post: x == p; }
    motion Cart.m_idle { interruptible: true; }
    motion Arm.work { interruptible: true; }
    motion Arm.pick { interruptible: false; }
    system CartAndArms {
      participant Cart: Cart { init: x == 0; }
      participant G: Arm;
      participant R: Arm;
    }
    choreography Fig2 = mu t. (
        Cart -> G : arrive. Cart -> R : free.
        ((dt<Cart: m_move(1.0), G: work>. Cart -> G : ready. dt<Cart: m_idle, G: pick>. G -> Cart : ok.
          (dt<Cart: m_move(0.0)> * dt<G: work>)) * dt<R: work>). t
      + Cart -> G : free. Cart -> R : arrive.
        ((dt<Cart: m_move(2.0), R: work>. Cart -> R : ready. dt<Cart: m_idle, R: pick>. R -> Cart : ok.
          (dt<Cart: m_move(0.0)> * dt<R: work>)) * dt<G: work>). t
    );
";

/// `path` (relative to the repository's root) from the crate's directory, where `cargo
/// test` runs unit tests: the corpus and the test data live at the root.
pub fn repo(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}
