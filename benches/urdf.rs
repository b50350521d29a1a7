//! Benchmark of the URDF reader on hostile inputs: the times the unit tests of
//! `checker/geometry/urdf/hostile.rs` do not assert (speed is measured here, by a benchmark,
//! not by timed unit tests that fail on a loaded machine).
//!
//! ```text
//! cargo bench --bench urdf              # best of 3 runs per row
//! cargo bench --bench urdf -- --quick   # one run per row
//! ```
//!
//! Two tables, all rows in one process so that the ratios compare like with like:
//!
//! - **a chain of links**: a URDF of n links in a chain (each a revolute joint 1 cm above the
//!   last), for n = 1,000, 10,000 and 100,000: the time to load it, and the time of forward
//!   kinematics plus the displacement bound over every joint, with the ratio to the row ten
//!   times smaller. Linear time gives ratios near 10; the reader that kept every link's chain
//!   of joints was quadratic (5·10^9 indices, 40 GB, at 100,000 links).
//! - **refused at once**: documents past the pre-scan's limits (200,000 nested elements,
//!   100,000 attributes on one element, a flood of namespace declarations, a million numbers
//!   in one attribute). Each is refused at the first item past the limit, so its time should
//!   be that of reading the text once (milliseconds); before the pre-scan, roxmltree and
//!   urdf-rs took from 22 s to minutes on them.
//!
//! No dependencies (no criterion): the numbers are meant to be read. Each row also checks its
//! result (the chain's tip height, the refusal's code), so a benchmark of a wrong answer fails.

use mochi::geometry::load_robot;
use mochi::geometry::Robot;
use mochi::source::{SourceDb, Span};
use std::path::Path;
use std::time::{Duration, Instant};

/// A URDF of `n` links in a chain, each a revolute joint 1 cm above the last.
fn chain(n: usize) -> String {
    let mut s = String::from("<robot name=\"chain\">\n<link name=\"l0\"/>\n");
    for i in 1..n {
        s += &format!(
            "<link name=\"l{i}\"/>\n<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0 0 0.01\"/><axis xyz=\"1 0 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
            i - 1
        );
    }
    s + "</robot>\n"
}

/// Loads `urdf` from memory (no mesh files).
fn load(urdf: &str) -> Result<Robot, Vec<mochi::diag::Diagnostic>> {
    let mut db = SourceDb::new();
    let at = Span::new(db.add("bench.chor", "robot"), 0, 5);
    let mut read = |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == Path::new("/mem/r.urdf") {
            Ok(urdf.as_bytes().to_vec())
        } else {
            Err(std::io::Error::new(std::io::ErrorKind::NotFound, "not in memory"))
        }
    };
    load_robot(&mut db, Path::new("/mem/r.urdf"), at, &mut read)
}

/// The best of `runs` timings of `f`, and its last result.
fn best<R>(runs: usize, mut f: impl FnMut() -> R) -> (Duration, R) {
    let mut best = Duration::MAX;
    let mut out = None;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed());
        out = Some(r);
    }
    (best, out.expect("one run"))
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let runs = if quick { 1 } else { 3 };

    println!("a chain of n links (best of {runs}):");
    println!("{:>8} {:>12} {:>8} {:>14} {:>8}", "n", "load ms", "ratio", "kinematics ms", "ratio");
    let mut last: Option<(Duration, Duration)> = None;
    for n in [1_000usize, 10_000, 100_000] {
        let text = chain(n);
        let (loaded, robot) = best(runs, || load(&text).expect("the chain loads"));
        assert_eq!(robot.links.len(), n);
        let q = vec![0.0; n - 1];
        let (kin, (poses, b)) = best(runs, || (robot.link_poses(&q), robot.displacement_bound(&q, &vec![1e-3; n - 1])));
        // The answers, so that a fast wrong one does not pass for a benchmark.
        assert!((poses[n - 1].translation.vector.z - 0.01 * (n - 1) as f64).abs() < 1e-6);
        let tip = 1e-5 * ((n - 1) * (n - 2) / 2) as f64;
        assert!(b[n - 1] >= tip && b[n - 1] < tip * (1.0 + 1e-6), "{} vs {tip}", b[n - 1]);
        let ratio = |now: Duration, before: Option<Duration>| {
            before.map_or("-".to_string(), |b| format!("{:.1}", now.as_secs_f64() / b.as_secs_f64().max(1e-9)))
        };
        println!(
            "{n:>8} {:>12.1} {:>8} {:>14.2} {:>8}",
            ms(loaded),
            ratio(loaded, last.map(|l| l.0)),
            ms(kin),
            ratio(kin, last.map(|l| l.1))
        );
        last = Some((loaded, kin));
    }

    println!("\nrefused at once (best of {runs}):");
    let nested = format!("<robot name=\"r\">{}{}</robot>", "<a>".repeat(200_000), "</a>".repeat(200_000));
    let attrs: String = (0..100_000).map(|k| format!(" a{k}=\"1\"")).collect();
    let attributes = format!("<robot name=\"r\">\n<link name=\"a\"{attrs}/>\n</robot>\n");
    let mut namespaces = String::from("<robot name=\"r\">\n<link name=\"a\"/>\n");
    for k in 0..20 {
        let decls: String = (0..60).map(|i| format!(" xmlns:n{k}_{i}=\"u{k}_{i}\"")).collect();
        namespaces += &format!("<e{k}{decls}>\n");
    }
    namespaces += &"<x xmlns:z=\"q\"/>".repeat(1000);
    for k in (0..20).rev() {
        namespaces += &format!("</e{k}>");
    }
    namespaces += "\n</robot>\n";
    let numbers = format!(
        "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<joint name=\"j\" type=\"fixed\">\n \
         <parent link=\"a\"/>\n <child link=\"b\"/>\n <origin xyz=\"{}\"/>\n</joint>\n</robot>\n",
        vec!["1"; 1_000_000].join(" ")
    );
    println!("{:<40} {:>10} {:>10} {:>8}", "input", "bytes", "ms", "code");
    for (what, text) in [
        ("200,000 nested elements", &nested),
        ("100,000 attributes on one element", &attributes),
        ("1,200 namespace declarations", &namespaces),
        ("a million numbers in one attribute", &numbers),
    ] {
        let (t, r) = best(runs, || load(text));
        let ds = r.err().unwrap_or_else(|| panic!("{what}: loaded, and it must be refused"));
        let code = ds.first().map(|d| d.code.as_str()).unwrap_or("-");
        assert!(code.starts_with("E05"), "{what}: refused with {code}, not a URDF error");
        println!("{what:<40} {:>10} {:>10.1} {:>8}", text.len(), ms(t), code);
    }
}
