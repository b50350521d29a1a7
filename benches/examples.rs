//! End-to-end benchmark on the bundled examples: the paper's cart and arms (Fig 2),
//! the sorting case (Sec 4.5) and PGCD's Fetch and Handover (Sec 5 (2), Table 2).
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
];

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let runs = if quick { 3 } else { 10 };
    let cfg = Config::default();
    println!("mochi examples benchmark: {runs} runs each, {} SMT worker(s)\n", cfg.smt.jobs);

    let mut rows = Vec::new();
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
}
