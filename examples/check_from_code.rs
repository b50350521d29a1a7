//! Checks a choreography built as a string in code, without touching the file system.
//!
//! ```text
//! cargo run --example check_from_code
//! ```
//!
//! Two carts on parallel tracks: `A` tells `B` to hold still while it drives to x = 1,
//! tells it again before driving back, and repeats. The example checks this file, then a
//! copy with a slip in it, and prints each verdict, the checks that ran and every
//! diagnostic with its code and `file:line:column`.

use mochi::driver::{Config, Report};
use mochi::fsload::check_source;
use mochi::source::SourceDb;

/// A tiny two-robot choreography, assembled from pieces the way a tool would.
fn two_carts() -> String {
    let robot = "\
robot Cart {
  state x: real, y: real;
  geometry: box(0.4, 0.3, 0.2);
  invariant: -10 <= x <= 10;
}
";
    // A non-interruptible drive and an interruptible wait; footprints in world coordinates.
    let motions = "\
motion Cart.drive(xf: real) {
  interruptible: false;
  pre: -10 <= xf <= 10;
  guarantee: min(old(x), xf) <= x <= max(old(x), xf) && y == old(y);
  post: x == xf && y == old(y);
  footprint(px, py, pz): min(old(x), xf) - 0.2 <= px <= max(old(x), xf) + 0.2
    && y - 0.15 <= py <= y + 0.15 && 0 <= pz <= 0.2;
  duration: [abs(xf - old(x)) / 0.5, abs(xf - old(x)) / 0.1];
}
motion Cart.hold {
  interruptible: true;
  guarantee: x == old(x) && y == old(y);
  post: x == old(x) && y == old(y);
  footprint(px, py, pz): x - 0.2 <= px <= x + 0.2 && y - 0.15 <= py <= y + 0.15 && 0 <= pz <= 0.2;
  duration: [0, inf];
}
";
    let mut src = String::new();
    src.push_str(robot);
    src.push_str(motions);
    src.push_str("system Pair {\n");
    for (name, lane) in [("A", 0.0), ("B", 1.0)] {
        src.push_str(&format!("  participant {name}: Cart {{ init: x == 0 && y == {lane:?}; at: pose(0, 0, 0); }}\n"));
    }
    src.push_str("}\n");
    src.push_str(
        "choreography Pair =\n  mu t. A -> B : out . dt<A: drive(1), B: hold> . A -> B : home . dt<A: drive(0), B: hold> . t;\n",
    );
    src.push_str("process A = mu t. B!out. dt<drive(1)>. B!home. dt<drive(0)>. t;\n");
    src.push_str("process B = mu t. A?out. dt<hold>. A?home. dt<hold>. t;\n");
    src
}

fn print_report(db: &SourceDb, title: &str, report: &Report) {
    println!("== {title}: verdict {:?}", report.verdict);
    for check in &report.checks {
        let status = format!("{:?}", check.status).to_lowercase();
        println!("   check {:<12} {status:<7} {:>8.3} ms  {}", check.name, check.millis, check.detail);
    }
    if report.diagnostics.is_empty() {
        println!("   no diagnostics");
    }
    for d in &report.diagnostics {
        print!("{}", mochi::render::text(db, d, false));
    }
}

fn main() {
    let cfg = Config::default();
    let mut db = SourceDb::new();

    let good = two_carts();
    let report = check_source(&mut db, "pair.chor", &good, &cfg);
    print_report(&db, "pair.chor", &report);

    // The same file with the `:` after `A -> B` forgotten, to show a diagnostic.
    let broken = good.replacen("A -> B : home", "A -> B home", 1);
    let report = check_source(&mut db, "pair-broken.chor", &broken, &cfg);
    print_report(&db, "pair-broken.chor", &report);
}
