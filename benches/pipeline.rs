//! Pipeline benchmark on the parallel-lanes family (paper Sec 5 (1), Fig 7).
//!
//! ```text
//! cargo bench --bench pipeline                  # n = 10, 100, 1000
//! cargo bench --bench pipeline -- --quick       # fewer iterations
//! MOCHI_BENCH_LARGE=1 cargo bench --bench pipeline   # also n = 300, 3000
//! ```
//!
//! For each size the benchmark generates the source with `parallel_lanes` (`examples/common/lanes.rs`),
//! runs `check_source` for a tenth of the budget to warm up, then repeatedly until the time budget is spent
//! (at least three runs), and prints the mean, median and minimum wall time, the mean time of
//! each stage as reported in `Report::checks`, the time per cart and the ratio
//! time(n) / time(n/10). All sizes run in the same process, one after the other, so the
//! ratios compare like with like. With the separating conjunction the checker should
//! grow about linearly, i.e. ratios near 10. Peak RSS (`VmHWM`) is printed at the end.
//!
//! A second table times hostile input shapes once each (`MOCHI_BENCH_SHAPES=0`
//! skips it): flat sequences of 1,000, 10,000 and 100,000 messages, checked end to end
//! (target: 10^5 in under 2 s), with the time of each stage that took a
//! millisecond or more; sequences of 1,000 to 100,000 joint motions, each followed by a
//! message, through the well-formedness checks only (their compatibility obligations,
//! one per motion, are the SMT stage's cost, not a shape cost); 20 MB of one repeated
//! definition, and a 10^4 chain of `^`. For each it prints the size of the rendered text
//! diagnostics, which the caps keep small.
//!
//! A third table times the wide joint motion once per size (`MOCHI_BENCH_WIDE=0` skips
//! it): `wide_dt(n)` (`examples/common/lanes.rs`), the n carts in one `dt`, for n = 10, 100,
//! 300, 1000, with the whole check's time, the stages that grew with the participants of one
//! `dt` (well-scoped, synchronisable, compatibility, typing obligations) and the queries
//! [AGCOMP] asked. Without the interval index every pair of footprints was a query over all
//! n carts (n = 100: 131 s); until the snapshots of Σ were eliminated through an index of
//! their uses, the well-scoped stage was quadratic (n = 1000: 5.4 s, now 0.06 s).
//!
//! A fourth table times each file of `tests/fuzz-corpus/` (past crashes and hangs;
//! `MOCHI_BENCH_FUZZ=0` skips it) beside the 10-cart lanes checked just before it, best of
//! three each, with the ratio of the two: a past hang that came back shows as a ratio in
//! the hundreds, whatever the machine's load (`tests/props.rs` checks that none panics).
//!
//! No dependencies (no criterion): the numbers are meant to be read, not tracked.

use mochi::driver::{Config, Report};
use mochi::fsload::check_source;
use mochi::source::SourceDb;
use std::hint::black_box;
use std::time::{Duration, Instant};

// The generator, shared with `examples/parallel_lanes.rs` (not part of the library).
#[path = "../examples/common/lanes.rs"]
#[allow(dead_code)]
mod lanes;
use lanes::parallel_lanes;

/// Minimum number of timed runs per size.
const MIN_RUNS: usize = 3;

struct Row {
    n: usize,
    bytes: usize,
    gen_ms: f64,
    runs: usize,
    mean_ms: f64,
    median_ms: f64,
    min_ms: f64,
    /// Mean milliseconds per stage, in the order the driver ran them.
    stages: Vec<(&'static str, f64)>,
    verdict: String,
    errors: usize,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // `cargo bench` passes `--bench`; a name filter, if any, is ignored.
    let quick = args.iter().any(|a| a == "--quick");
    let large = std::env::var("MOCHI_BENCH_LARGE").is_ok_and(|v| !v.is_empty() && v != "0");
    let budget = Duration::from_millis(if quick { 50 } else { 500 });

    let mut sizes = vec![10, 100, 1000];
    if large {
        sizes.extend([300, 3000]);
        sizes.sort_unstable();
    }

    println!(
        "mochi pipeline benchmark: parallel lanes, budget {} ms per size, >= {MIN_RUNS} runs{}",
        budget.as_millis(),
        if quick { " (quick)" } else { "" }
    );
    let rows: Vec<Row> = sizes.iter().map(|&n| measure(n, budget)).collect();
    print_table(&rows);

    if std::env::var("MOCHI_BENCH_SHAPES").map_or(true, |v| v != "0") {
        // Later stages recurse once per step of a sequence: give them main's stack.
        let worker = std::thread::Builder::new().stack_size(256 << 20).spawn(shapes);
        if let Err(e) = worker.map(|w| w.join()) {
            println!("shapes: cannot start the thread: {e}");
        }
    }

    if std::env::var("MOCHI_BENCH_WIDE").map_or(true, |v| v != "0") {
        wide();
    }

    if std::env::var("MOCHI_BENCH_FUZZ").map_or(true, |v| v != "0") {
        let worker = std::thread::Builder::new().stack_size(256 << 20).spawn(fuzz_corpus);
        if let Err(e) = worker.map(|w| w.join()) {
            println!("fuzz corpus: cannot start the thread: {e}");
        }
    }

    match peak_rss_kib() {
        Some(kib) => println!("\npeak RSS (VmHWM): {:.1} MiB", kib as f64 / 1024.0),
        None => println!("\npeak RSS (VmHWM): unavailable"),
    }
}

/// One timed `check_source` on a fresh database.
fn run_once(name: &str, src: &str, cfg: &Config) -> (f64, Report) {
    let mut db = SourceDb::new();
    let t = Instant::now();
    let report = check_source(&mut db, name, black_box(src), cfg);
    let ms = t.elapsed().as_secs_f64() * 1000.0;
    (ms, black_box(report))
}

fn measure(n: usize, budget: Duration) -> Row {
    let t = Instant::now();
    let src = parallel_lanes(n);
    let gen_ms = t.elapsed().as_secs_f64() * 1000.0;
    let name = format!("lanes{n}.chor");
    let cfg = Config::default();

    // Warm up caches and the allocator for a tenth of the budget (at least one run).
    let (_, warm) = run_once(&name, &src, &cfg);
    let verdict = format!("{:?}", warm.verdict).to_lowercase();
    let errors = warm.diagnostics.iter().filter(|d| d.is_error()).count();
    drop(warm);
    let warm_start = Instant::now();
    while warm_start.elapsed() < budget / 10 {
        run_once(&name, &src, &cfg);
    }

    let mut times = Vec::new();
    let mut stages: Vec<(&'static str, f64)> = Vec::new();
    let start = Instant::now();
    while times.len() < MIN_RUNS || start.elapsed() < budget {
        let (ms, report) = run_once(&name, &src, &cfg);
        times.push(ms);
        for c in &report.checks {
            match stages.iter_mut().find(|(s, _)| *s == c.name) {
                Some((_, total)) => *total += c.millis,
                None => stages.push((c.name, c.millis)),
            }
        }
    }
    let runs = times.len();
    for (_, total) in &mut stages {
        *total /= runs as f64;
    }
    Row {
        n,
        bytes: src.len(),
        gen_ms,
        runs,
        mean_ms: times.iter().sum::<f64>() / runs as f64,
        median_ms: median(&mut times),
        min_ms: times.iter().copied().fold(f64::INFINITY, f64::min),
        stages,
        verdict,
        errors,
    }
}

fn print_table(rows: &[Row]) {
    // Stage columns: every stage any size reported, in first-seen order.
    let mut names: Vec<&'static str> = Vec::new();
    for r in rows {
        for (s, _) in &r.stages {
            if !names.contains(s) {
                names.push(s);
            }
        }
    }
    let mut header =
        format!("\n{:>6} {:>9} {:>5} {:>10} {:>10} {:>10}", "n", "src KiB", "runs", "mean ms", "median ms", "min ms");
    for s in &names {
        header.push_str(&format!(" {:>w$}", format!("{s} ms"), w = s.len().max(6) + 3));
    }
    header.push_str(&format!(" {:>11} {:>12} {:>8} {:>9}  verdict", "ms/cart", "t(n)/t(n/10)", "gen ms", "errors"));
    println!("{header}");
    for r in rows {
        let mut line = format!(
            "{:>6} {:>9.1} {:>5} {:>10.3} {:>10.3} {:>10.3}",
            r.n,
            r.bytes as f64 / 1024.0,
            r.runs,
            r.mean_ms,
            r.median_ms,
            r.min_ms
        );
        for s in &names {
            let w = s.len().max(6) + 3;
            match r.stages.iter().find(|(x, _)| x == s) {
                Some((_, ms)) => line.push_str(&format!(" {ms:>w$.3}")),
                None => line.push_str(&format!(" {:>w$}", "-")),
            }
        }
        let ratio = (r.n % 10 == 0)
            .then(|| rows.iter().find(|p| p.n == r.n / 10))
            .flatten()
            .map(|p| format!("{:.2}", r.mean_ms / p.mean_ms))
            .unwrap_or_else(|| "-".to_string());
        line.push_str(&format!(
            " {:>11.5} {:>12} {:>8.3} {:>9}  {}",
            r.mean_ms / r.n as f64,
            ratio,
            r.gen_ms,
            r.errors,
            r.verdict
        ));
        println!("{line}");
    }
}

/// A choreography of `n` messages in sequence between two Bots, with its processes
/// (`n` steps each); the library is imported by absolute path.
fn sequence(n: usize) -> String {
    let bot = std::fs::canonicalize("motion-primitives/bot.mochi").unwrap_or_default();
    format!(
        "import \"{}\";\nsystem S {{ participant p1: Bot {{ init: s == 0; at: pose(0, 0, 0); }} \
         participant p2: Bot {{ init: s == 0; at: pose(1, 0, 0); }} }}\n\
         choreography C = dt<p1: wave, p2: wave>.\n{}end;\nprocess p1 = dt<wave>.{}end;\nprocess p2 = dt<wave>.{}end;\n",
        bot.display(),
        "p1 -> p2: l.\n".repeat(n),
        "p2!l.".repeat(n),
        "p1?l.".repeat(n)
    )
}

/// A choreography of `n` joint motions of two Bots in sequence, each ended by a message
/// (the well-formedness checks only look at the choreography).
fn motions(n: usize) -> String {
    let bot = std::fs::canonicalize("motion-primitives/bot.mochi").unwrap_or_default();
    format!(
        "import \"{}\";\nsystem S {{ participant p1: Bot {{ init: s == 0; at: pose(0, 0, 0); }} \
         participant p2: Bot {{ init: s == 0; at: pose(1, 0, 0); }} }}\n\
         choreography C = {}end;\n",
        bot.display(),
        "dt<p1: open, p2: wave>. p1 -> p2: l.\n".repeat(n),
    )
}

/// How far a shape is checked.
#[derive(Clone, Copy, PartialEq)]
enum Depth {
    /// Parse and name resolution only.
    Names,
    /// Up to and including the well-formedness checks (side conditions, scoping,
    /// synchronisability).
    WellFormed,
    /// `check_source`, every stage.
    Full,
}

/// Times the hostile input shapes (see the module documentation).
fn shapes() {
    let mut cases: Vec<(String, String, Depth)> = Vec::new();
    for n in [1_000, 10_000, 100_000] {
        cases.push((format!("sequence of {n}"), sequence(n), Depth::Full));
    }
    for n in [1_000, 10_000, 100_000] {
        cases.push((format!("{n} motions"), motions(n), Depth::WellFormed));
    }
    cases.push(("20 MB repeated const".into(), "const a = 1;\n".repeat(20 << 20 >> 4), Depth::Names));
    cases.push(("10^4 chain of ^".into(), format!("const x = {}1;\n", "2 ^ ".repeat(10_000)), Depth::Full));
    println!(
        "\n{:<22} {:>9} {:>10} {:>10} {:>12} {:>14}  verdict / stages of 1 ms or more",
        "shape", "src KiB", "parse ms", "names ms", "check ms", "text out KiB"
    );
    for (name, src, depth) in cases {
        let mut db = SourceDb::new();
        let root = db.add(format!("{}.chor", name.replace(' ', "-")), src.as_str());
        let t = Instant::now();
        let (parsed, _) = mochi::syntax::parse_with_imports(&mut db, root, &mut |p| mochi::fsload::read_source(p));
        let parse_ms = t.elapsed().as_secs_f64() * 1000.0;
        let t = Instant::now();
        let (prog, _) = mochi::lower::lower(&parsed);
        let names_ms = t.elapsed().as_secs_f64() * 1000.0;
        let (check, out, verdict) = match depth {
            Depth::Names => ("skipped".into(), "-".into(), "-".into()),
            Depth::WellFormed => {
                let t = Instant::now();
                let body = &prog.choreography.as_ref().expect("a choreography").body;
                let side = mochi::wf::side::check(&prog, body);
                let scope = mochi::wf::scope::check(&prog, body);
                // The well-scoped stage also plans the obligations (as the driver times it).
                let _ = mochi::plan::obligations(&prog, body);
                let sync = mochi::wf::sync::check(&prog, body);
                let ms = t.elapsed().as_secs_f64() * 1000.0;
                let errors = side.iter().chain(&scope).chain(&sync).filter(|d| d.is_error()).count();
                (format!("{ms:.1}"), "-".into(), format!("well-formedness only: {errors} error(s)"))
            }
            Depth::Full => {
                let mut db = SourceDb::new();
                let t = Instant::now();
                let report = check_source(&mut db, &format!("{name}.chor"), &src, &Config::default());
                let ms = t.elapsed().as_secs_f64() * 1000.0;
                let text = mochi::render::report_text(&db, &name, &report, false, false);
                let stages: Vec<String> = report
                    .checks
                    .iter()
                    .filter(|c| c.millis >= 1.0)
                    .map(|c| format!("{} {:.0}", c.name, c.millis))
                    .collect();
                (
                    format!("{ms:.1}"),
                    format!("{:.1}", text.len() as f64 / 1024.0),
                    format!("{:?}; {}", report.verdict, stages.join(", ")),
                )
            }
        };
        drop((prog, parsed));
        println!(
            "{name:<22} {:>9.1} {parse_ms:>10.1} {names_ms:>10.1} {check:>12} {out:>14}  {verdict}",
            src.len() as f64 / 1024.0
        );
    }
}

/// Times one check of the wide `dt` for each size (see the module documentation), with the
/// stages that grew with the participants of one `dt`.
fn wide() {
    const STAGES: [(&str, &str); 4] = [
        ("well-scoped", "scope ms"),
        ("synchronisable", "sync ms"),
        ("compatibility", "compat ms"),
        ("typing-obligations", "typing-obl ms"),
    ];
    print!("\n{:>6} {:>9} {:>10}", "wide n", "src KiB", "check ms");
    for (_, head) in STAGES {
        print!(" {head:>13}");
    }
    println!(" {:>14}  verdict / slowest stage", "agcomp queries");
    for n in [10, 100, 300, 1000] {
        let src = lanes::wide_dt(n);
        let (ms, report) = run_once(&format!("wide{n}.chor"), &src, &Config::default());
        let stage = |name: &str| report.checks.iter().find(|c| c.name == name);
        let slowest = report.checks.iter().max_by(|a, b| a.millis.total_cmp(&b.millis));
        let slowest = slowest.map(|c| format!("{} {:.0} ms", c.name, c.millis)).unwrap_or_default();
        print!("{n:>6} {:>9.1} {ms:>10.1}", src.len() as f64 / 1024.0);
        for (name, _) in STAGES {
            print!(" {:>13}", stage(name).map_or("-".into(), |c| format!("{:.1}", c.millis)));
        }
        println!(
            " {:>14}  {:?}, {slowest}",
            stage("compatibility").map_or("-".into(), |c| c.queries.to_string()),
            report.verdict
        );
    }
}

fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(f64::total_cmp);
    let m = xs.len() / 2;
    if xs.len() % 2 == 1 {
        xs[m]
    } else {
        (xs[m - 1] + xs[m]) / 2.0
    }
}

/// Peak resident set size in KiB, from `/proc/self/status` (Linux only).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Each file of the fuzz corpus beside the 10-cart lanes (see the module comment).
fn fuzz_corpus() {
    let dir = std::path::Path::new("tests/fuzz-corpus");
    let mut files: Vec<std::path::PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries.filter_map(|e| Some(e.ok()?.path())).collect(),
        Err(e) => {
            println!("\nfuzz corpus: cannot list {}: {e}", dir.display());
            return;
        }
    };
    files.sort();
    let cfg = Config::default();
    let baseline = parallel_lanes(10);
    println!("\n{:<28} {:>10} {:>12} {:>8}", "fuzz corpus file", "min ms", "lanes10 ms", "ratio");
    for path in files {
        let Ok(text) = std::fs::read_to_string(&path) else { continue };
        let name = path.display().to_string();
        let (mut file_ms, mut base_ms) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..3 {
            base_ms = base_ms.min(run_once("lanes10.chor", &baseline, &cfg).0);
            file_ms = file_ms.min(run_once(&name, &text, &cfg).0);
        }
        let short = path.file_name().map_or(name.clone(), |f| f.to_string_lossy().to_string());
        println!("{short:<28} {file_ms:>10.2} {base_ms:>12.2} {:>8.2}", file_ms / base_ms);
    }
}
