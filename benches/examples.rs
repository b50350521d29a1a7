//! End-to-end benchmark on the bundled examples: the paper's cart and arms (Fig 2),
//! the sorting case (Sec 4.5), PGCD's Fetch and Handover (Sec 5 (2), Table 2), and the
//! geometry examples (a bridge, turning and diagonal carts, and the sorting case
//! study of Sec 5 (3) with the robots' URDFs, the arm mounted on a turning cart with a rover
//! driving around it), and the rejected variants of the two geometric case studies (how long
//! a contact takes to find and confirm).
//!
//! ```text
//! cargo bench --bench examples                 # 10 runs per example
//! cargo bench --bench examples -- --quick      # 3 runs
//! ```
//!
//! Each example is checked from its file (imports included) with the default
//! configuration: every check, Z3 on all cores, a fresh query cache per run. The table
//! prints the verdict, the wall time (mean, min), the number of SMT queries and of those
//! answered from the cache, and the time of each phase. The SMT phases' times add up
//! the time their obligations took on the worker threads, so with two workers they can
//! exceed the wall time. PGCD's own figures (its artifact on this kind of machine, and
//! the paper's Table 2) are printed beside them for reference; PGCD itself (Python and
//! dReal) is not run here.
//!
//! The sorting case study (Sec 5 (3), Table 3) gets a second table, one line per phase (the
//! report's check lines, in pipeline order) with its mean and min over the runs, its
//! status and its SMT queries, beside PGCD's figures for the same case study: the paper
//! reports 2410 s of compatibility checks with dReal on 6 cores, and PGCD's artifact on
//! this machine did not finish in 900 s. The benchmark measures and prints; it asserts no
//! time (the verdict it prints says whether the times are those of a proof).
//!
//! Measured (`--quick`, 2 cores shared with other jobs): the case study verified in 220 ms
//! wall (min 204 ms; compatibility about 160 ms of worker time, typing obligations 100 ms,
//! separation 40 ms, geometry stage 35 ms), against PGCD's 2410 s (paper) and more than
//! 900 s here; 405 ms without the compiled contraction of the geometric search
//! (`bounds::compiled`). The mounted arm verified in 170 ms; its variant with the rover's circle
//! too tight rejected in 655 ms and the Panda variant of the case study in 728 ms (each
//! about half the search for a contact, half its refinement towards the first). The other
//! examples: cart-and-arms 91 ms, sorting 98, fetch 63, handover 144, bridge 12,
//! turn-together 18, diagonal 49.

use mochi::driver::{Config, Report};
use mochi::fsload::check_file;
use mochi::source::SourceDb;
use std::path::Path;
use std::time::Instant;

const EXAMPLES: &[(&str, &str)] = &[
    ("choreographies/cart-and-arms.chor", "-"),
    ("choreographies/sorting.chor", "-"),
    ("choreographies/pgcd/fetch.chor", "PGCD: 5.0 s, 387 queries (Table 2: 7 s on 6 cores)"),
    ("choreographies/pgcd/handover.chor", "PGCD: 218 s (Table 2: 70 s on 6 cores)"),
    ("choreographies/bridge.chor", "-"),
    ("choreographies/turn-together.chor", "-"),
    ("choreographies/diagonal.chor", "-"),
    ("choreographies/mounted-arm.chor", "-"),
    ("choreographies/rejected/geometry/E0404-mounted-arm-orbit-too-small.chor", "-"),
    ("choreographies/rejected/geometry/E0406-sorting-panda-reaches-into-cart-path.chor", "-"),
    (CASE_STUDY, "PGCD: did not finish in 900 s here (paper: 2410 s of compatibility checks, dReal, 6 cores)"),
];

/// The example whose phases are tabulated one per line.
const CASE_STUDY: &str = "choreographies/sorting-case-study.chor";

/// PGCD's figure for a phase of the case study, where there is one: the paper (Sec 5 (3))
/// times only its compatibility checks; its other phases have no published time.
fn pgcd_phase(name: &str) -> &'static str {
    match name {
        "compatibility" => "2410 s (paper, dReal, 6 cores); not finished in 900 s here",
        _ => "-",
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let runs = if quick { 3 } else { 10 };
    let cfg = Config::default();
    println!("mochi examples benchmark: {runs} runs each, {} SMT worker(s)\n", cfg.smt.jobs);

    let mut rows = Vec::new();
    // Per run of the case study: each check's (name, status, millis, queries).
    let mut case_runs: Vec<Vec<(&'static str, String, f64, usize)>> = Vec::new();
    for (path, reference) in EXAMPLES {
        let mut times = Vec::new();
        let mut last: Option<Report> = None;
        for _ in 0..runs {
            let mut db = SourceDb::new();
            let t = Instant::now();
            let report = match check_file(&mut db, Path::new(path), &cfg) {
                Ok(r) => r,
                Err(e) => {
                    println!("{path}: cannot read: {e}");
                    break;
                }
            };
            times.push(t.elapsed().as_secs_f64() * 1000.0);
            if *path == CASE_STUDY {
                case_runs.push(
                    report
                        .checks
                        .iter()
                        .map(|c| (c.name, format!("{:?}", c.status).to_lowercase(), c.millis, c.queries))
                        .collect(),
                );
            }
            last = Some(report);
        }
        let Some(report) = last else { continue };
        rows.push((path, reference, times, report));
    }
    println!(
        "{:<36} {:>9} {:>9} {:>9} {:>8}  phases (ms; queries)",
        "example", "verdict", "mean ms", "min ms", "queries"
    );
    for (path, reference, times, report) in &rows {
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        let min = times.iter().copied().fold(f64::INFINITY, f64::min);
        let queries: usize = report.checks.iter().map(|c| c.queries).sum();
        let detail: Vec<String> = report
            .checks
            .iter()
            .map(|c| {
                if c.queries > 0 {
                    format!("{} {:.1}; {}", c.name, c.millis, c.queries)
                } else {
                    format!("{} {:.1}", c.name, c.millis)
                }
            })
            .collect();
        let name = path.trim_start_matches("choreographies/");
        println!(
            "{:<36} {:>9} {:>9.1} {:>9.1} {:>8}  {}",
            name,
            format!("{:?}", report.verdict).to_lowercase(),
            mean,
            min,
            queries,
            detail.join(", ")
        );
        if **reference != "-" {
            println!("{:<36} {reference}", "");
        }
    }
    let case_wall = rows.iter().find(|r| *r.0 == CASE_STUDY).map(|r| r.2.clone()).unwrap_or_default();
    case_study_phases(&case_runs, &case_wall);
}

/// The case study's phases side by side with PGCD's: mean and min over the runs of each
/// check's time, its status and queries in the last run. A phase missing from some run (a
/// stage that stopped early) is averaged over the runs that have it, and says so. The last
/// line is the wall time end to end (the phases' sum is not: SMT phases add worker time).
fn case_study_phases(runs: &[Vec<(&'static str, String, f64, usize)>], wall: &[f64]) {
    let Some(last) = runs.last() else { return };
    println!("\n{CASE_STUDY}, per phase ({} run(s); SMT phases add up worker time):", runs.len());
    println!("{:<24} {:>8} {:>9} {:>9} {:>8}  PGCD", "phase", "status", "mean ms", "min ms", "queries");
    for (name, status, _, queries) in last {
        let times: Vec<f64> = runs.iter().filter_map(|r| r.iter().find(|c| c.0 == *name).map(|c| c.2)).collect();
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        let min = times.iter().copied().fold(f64::INFINITY, f64::min);
        let partial = if times.len() < runs.len() { format!(" (in {} runs)", times.len()) } else { String::new() };
        println!("{name:<24} {status:>8} {mean:>9.1} {min:>9.1} {queries:>8}  {}{partial}", pgcd_phase(name));
    }
    if !wall.is_empty() {
        let mean = wall.iter().sum::<f64>() / wall.len() as f64;
        let min = wall.iter().copied().fold(f64::INFINITY, f64::min);
        println!("{:<24} {:>8} {mean:>9.1} {min:>9.1} {:>8}  not finished in 900 s here", "end to end (wall)", "", "");
    }
}
