//! Mutation test of the checker. Every verified example under `choreographies/` (not
//! `rejected/`; motion, geometry and MAVLink) is mutated, together with the `.mochi`
//! libraries it imports and the URDF files its robots name, by the operators of
//! `tests/mutation/ops.rs` (the MAVLink ones for examples with a `dialect`), and each mutant
//! is checked. A mutant is *killed* when mochi rejects it, or says unknown for a reason no
//! machine changes (an unsupported construct, an incomplete theory); it *survives* when
//! mochi still says `verified`. A mutant that is unknown only because a limit was reached (a
//! query's timeout, the geometric search's time or box budget) is neither: it is checked
//! again with a longer limit ([`RETRY_TIMEOUT`]) and, if still undecided, reported as timed
//! out (printed and in the table), never counted as a kill.
//!
//! Every survivor must be listed in `tests/mutation-survivors.toml` with an explanation:
//! `status = "equivalent"` (the mutated protocol is still correct, and why) or
//! `status = "limitation"` (the mutant changes a trusted part of the model, a primitive's
//! contract or footprint, in a way mochi cannot check yet: no dynamics, no geometry; counted
//! and printed, not a failure) or `status = "bug"` (a wrong protocol that mochi verifies: a
//! soundness defect). The test fails
//! on an unlisted or unexplained survivor, and on a `bug` survivor unless
//! `MOCHI_MUTATION_ALLOW_KNOWN_BUGS=1`. Listed survivors that are now killed are reported as
//! stale (not a failure).
//!
//! Environment:
//! - `MOCHI_MUTATION_BLESS=1` rewrites the list: current survivors keep their entry (status and
//!   explanation, keyed by the mutation id), new ones are added as `unexplained`, stale ones go.
//! - `MOCHI_MUTATION_ONLY=substring` runs only the mutants whose id contains it, all of them
//!   (not only the sample's; no stale report). With `MOCHI_MUTATION_BLESS=1` it blesses
//!   those and keeps every other entry (e.g. `MOCHI_MUTATION_ONLY=mavlink/`: every MAVLink
//!   mutant, not only the sampled ones, is in the list).
//! - `MOCHI_MUTATION_JOBS=n` mutants checked in parallel (default 2, one SMT thread each).
//! - Which mutants run: all of them with `MOCHI_MUTATION_FULL=1` (seven times the sample);
//!   otherwise, and so on CI, a fixed sample: one mutant in [`SAMPLE`] (about 2,100), chosen
//!   by a hash of its id (the same every run). A run of `cargo test` checks one of the
//!   sample's [`SLICES`] slices (the next bits of the same hash): the day's, so that
//!   successive days check different mutants and the whole sample is checked every
//!   [`SLICES`] days, at an eighth of the time (`.ci/run --full` checks the whole sample). The
//!   run prints its slice;
//!   `MOCHI_MUTATION_SLICE=k` checks slice `k` again and `MOCHI_MUTATION_SLICE=all` the whole
//!   sample (the default when blessing or with `MOCHI_MUTATION_ONLY`). The sample is a subset
//!   of the full set, so one survivors list serves both. `cargo test` builds the checking
//!   crates optimised (`[profile.test.package.mochi-verify]` and its siblings in Cargo.toml),
//!   so the sample runs at about the speed of a release build.
//! - A run fails when more than one mutant in [`MAX_TIMED_OUT_ONE_IN`] is still undecided for
//!   want of time after the second look: timeouts are neither kills nor survivors, and a run
//!   with many of them tests too little.
//! - `MOCHI_MUTATION_LIST=1` only lists the mutants (counts per operator on stderr, ids and
//!   descriptions in `target/mutation/list.tsv`).
//! - Blessing updates the entries of the mutants that ran and keeps the others (a sampled bless
//!   does not forget the full run's survivors; entries whose mutant no longer exists go). It
//!   checks again with a long timeout ([`BLESS_TIMEOUT`]) every mutant that came back unknown: a
//!   mutant that times out here but verifies on a faster machine must already be in the list.
//!
//! The table of every mutant (id, verdict, codes, description) is written to
//! `target/mutation/table.tsv`.

use crate::ops;

use mochi::driver::{Config, Verdict};
use mochi::fsload::check_file;
use mochi::smt::SmtConfig;
use mochi::source::SourceDb;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const LIST: &str = "tests/mutation-survivors.toml";
const TIMEOUT: Duration = Duration::from_secs(2);
/// The per-query timeout for the second look at unknown mutants when blessing.
const BLESS_TIMEOUT: Duration = Duration::from_secs(30);
/// The per-query timeout for the second look at mutants that ran out of time.
const RETRY_TIMEOUT: Duration = Duration::from_secs(10);
/// Outside CI, one mutant in this many runs (chosen by a hash of its id).
const SAMPLE: u64 = 7;

/// The sample is cut into this many slices (by the same hash); a run of `cargo test` checks
/// one of them, a different one each day: about 160 mutants, a minute or two on two cores
/// while the other tests run beside it.
const SLICES: u64 = 8;
/// A run fails when more than one mutant in this many is still undecided for want of time
/// after the second look: such a run tests too little of what it sampled.
const MAX_TIMED_OUT_ONE_IN: usize = 20;

/// Whether every mutant runs (`MOCHI_MUTATION_FULL=1`) or only the sample.
fn full_run() -> bool {
    std::env::var("MOCHI_MUTATION_FULL").is_ok_and(|x| x == "1" || x == "true")
}

/// A stable hash of a mutant's id (FNV-1a), for the sample and its slices.
fn fnv(id: &str) -> u64 {
    id.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

fn in_sample(id: &str) -> bool {
    fnv(id).is_multiple_of(SAMPLE)
}

/// The slice of the sample a mutant is in (the hash's bits above those of the sample).
fn slice_of(id: &str) -> u64 {
    (fnv(id) / SAMPLE) % SLICES
}

/// Which slice of the sample this run checks: `MOCHI_MUTATION_SLICE=k` (0 to [`SLICES`] - 1),
/// or every slice with `MOCHI_MUTATION_SLICE=all`; otherwise the day's (days since 1970
/// modulo [`SLICES`]), so that successive days' CI runs check different mutants and every
/// mutant of the sample is checked every [`SLICES`] days. The slice is printed, with how to
/// run it again. A blessing or a filtered run checks every slice unless told one.
fn slice(whole_by_default: bool) -> Option<u64> {
    match std::env::var("MOCHI_MUTATION_SLICE").ok().as_deref().map(str::trim) {
        Some("all") => None,
        Some(k) => {
            Some(k.parse::<u64>().unwrap_or_else(|_| panic!("MOCHI_MUTATION_SLICE={k}: a number or `all`")) % SLICES)
        }
        None if whole_by_default => None,
        None => {
            let days =
                std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() / 86_400);
            Some(days % SLICES)
        }
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn cfg(timeout: Duration) -> Config {
    Config { smt: SmtConfig { timeout, jobs: 1, ..SmtConfig::default() }, structural_only: false, ..Config::default() }
}

/// A mutant ready to run: the example (relative to `choreographies/`), the mutated file
/// (relative to the package root) and its new text.
#[derive(Clone)]
struct Job {
    id: String,
    desc: String,
    example: String,
    file: String,
    text: String,
}

#[derive(Clone)]
struct Outcome {
    id: String,
    desc: String,
    verdict: Verdict,
    codes: Vec<String>,
    millis: u128,
    /// Unknown only because a limit was reached (a Z3 timeout, an abandoned query, the
    /// geometric search's time or box budget): neither a kill nor a survivor, reported apart.
    timed_out: bool,
}

/// Whether an unknown report is unknown only for want of time or search budget: every
/// undecided obligation says so. An undecided obligation for another reason (an unsupported
/// construct, Z3's incompleteness on a nonlinear fact) is a kill: mochi refuses the mutant
/// whatever the machine.
fn timed_out(report: &mochi::driver::Report) -> bool {
    const LIMITS: &[&str] = &[
        "timed out",
        "ran out of time",
        "abandoned",
        "time limit reached",
        "boxes searched",
        "timeout",
        "canceled",
        "not asked",
    ];
    // The undecided obligations (U0001 notes with their reason; the "and N more" line has none).
    let undecided: Vec<_> =
        report.diagnostics.iter().filter(|d| d.code.as_str() == "U0001" && !d.notes.is_empty()).collect();
    report.verdict == Verdict::Unknown
        && !undecided.is_empty()
        && undecided.iter().all(|d| d.notes.iter().any(|n| LIMITS.iter().any(|l| n.contains(l))))
}

/// The verified examples: every `.chor` under `choreographies/` except `rejected/` (and
/// `pending/`) whose golden snapshot says `Verified`. The corpus harness (tests/corpus.rs)
/// checks each file once and fails unless its report is the snapshot's, so the snapshot's
/// verdict is the file's; reading it spares checking every example again here.
fn verified_examples() -> &'static [String] {
    static EXAMPLES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    EXAMPLES.get_or_init(|| {
        let mut all = Vec::new();
        let mut stack = vec![root().join("choreographies")];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).expect("readable dir") {
                let p = e.expect("entry").path();
                if p.is_dir() {
                    // Not `pending/` either: unknown after minutes (corpus.rs).
                    if p.file_name().is_some_and(|n| n != "rejected" && n != "pending") {
                        stack.push(p);
                    }
                } else if p.extension().is_some_and(|x| x == "chor") {
                    all.push(p);
                }
            }
        }
        all.sort();
        let examples: Vec<String> = all
            .into_iter()
            .map(|p| p.strip_prefix(root().join("choreographies")).unwrap().display().to_string())
            .filter(|ex| golden_verdict(ex) == Verdict::Verified)
            .collect();
        assert!(examples.len() >= 20, "the verified examples were found ({})", examples.len());
        examples
    })
}

/// The verdict recorded in the golden snapshot of `example` (a path below `choreographies/`).
fn golden_verdict(example: &str) -> Verdict {
    let snap = root()
        .join("tests/snapshots")
        .join(format!("golden__every_choreography_matches_its_golden_file@{}.snap", example.replace('/', "__")));
    let text = std::fs::read_to_string(&snap)
        .unwrap_or_else(|e| panic!("{example}: no golden snapshot {} ({e})", snap.display()));
    match text.split("==== VERDICT ====\n").nth(1).and_then(|r| r.lines().next()).map(str::trim) {
        Some("Verified") => Verdict::Verified,
        Some("Rejected") => Verdict::Rejected,
        Some("Unknown") => Verdict::Unknown,
        other => panic!("{}: no verdict line ({other:?})", snap.display()),
    }
}

/// The MAVLink dialect of an example (`dialect NAME;`), for the MAVLink operators.
fn dialect_of(text: &str) -> Option<&'static mochi::dialect::Dialect> {
    let line = text.lines().find_map(|l| l.trim().strip_prefix("dialect "))?;
    mochi::dialect::builtin(line.trim().trim_end_matches(';').trim())
}

/// The files an example reads (itself, its imports and the URDF files its robots name),
/// relative to the package root.
fn closure(example: &str) -> Vec<String> {
    let mut db = SourceDb::new();
    let path = root().join("choreographies").join(example);
    let _ = check_file(&mut db, &path, &Config { structural_only: true, ..cfg(TIMEOUT) });
    let mut files: Vec<String> = db
        .files()
        .map(|(_, f)| {
            let p = PathBuf::from(&f.name);
            let mut out = PathBuf::new();
            for c in p.components() {
                match c {
                    std::path::Component::ParentDir => {
                        out.pop();
                    }
                    std::path::Component::CurDir => {}
                    c => out.push(c),
                }
            }
            out.strip_prefix(root()).unwrap_or(&out).display().to_string()
        })
        .collect();
    // The URDF files named by `urdf("...")` (relative to the file that names them), in case
    // the structural stages did not read them.
    for f in files.clone() {
        let Ok(text) = std::fs::read_to_string(root().join(&f)) else { continue };
        for (k, _) in text.match_indices("urdf(\"") {
            let rest = &text[k + 6..];
            let Some(end) = rest.find('"') else { continue };
            let p = Path::new(&f).parent().unwrap_or(Path::new("")).join(&rest[..end]);
            if root().join(&p).is_file() {
                files.push(p.display().to_string());
            }
        }
    }
    files.sort();
    files.dedup();
    files
}

fn jobs(filter: Option<&str>) -> Vec<Job> {
    jobs_of(filter, full_run())
}

/// Every mutant (`all`), or the sample, of the ids containing `filter`.
fn jobs_of(filter: Option<&str>, all: bool) -> Vec<Job> {
    jobs_of_examples(verified_examples(), filter, all)
}

/// Every mutant (`all`), or the sample, of the ids containing `filter`, of `examples`.
fn jobs_of_examples(examples: &[String], filter: Option<&str>, all: bool) -> Vec<Job> {
    let mut out = Vec::new();
    for ex in examples {
        let files = closure(ex);
        let (mut consts, mut states) = (Vec::new(), Vec::new());
        for f in files.iter().filter(|f| !f.ends_with(".urdf")) {
            let (c, s) = ops::declared_names(&std::fs::read_to_string(root().join(f)).unwrap());
            consts.extend(c);
            states.extend(s);
        }
        states.sort();
        states.dedup();
        let dialect = dialect_of(&std::fs::read_to_string(root().join("choreographies").join(ex)).unwrap());
        for f in &files {
            let text = std::fs::read_to_string(root().join(f)).unwrap();
            let prefix = if f == &format!("choreographies/{ex}") { ex.clone() } else { format!("{ex}@{f}") };
            let ms = if f.ends_with(".urdf") {
                ops::urdf_mutants(&text)
            } else {
                ops::mutants(&text, &states, &consts, dialect)
            };
            for m in ms {
                let id = format!("{prefix}:{}", m.id);
                if filter.is_some_and(|s| !id.contains(s)) || (filter.is_none() && !all && !in_sample(&id)) {
                    continue;
                }
                out.push(Job { id, desc: m.desc.clone(), example: ex.clone(), file: f.clone(), text: m.apply(&text) });
            }
        }
    }
    out
}

/// A private copy of the libraries and examples for one worker.
/// Worker `n`'s copy of the examples for run `run`. Each call of [`run`] has its own
/// directories: two tests of this binary run at once, and one deleting `work-0` while the
/// other copied into it made the test flaky.
fn work_tree(run: usize, n: usize) -> PathBuf {
    let dir = root().join("target").join("mutation").join(format!("work-{run}-{n}"));
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["choreographies", "motion-primitives", "robots"] {
        copy_dir(&root().join(sub), &dir.join(sub));
    }
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create work dir");
    for e in std::fs::read_dir(from).expect("read dir") {
        let p = e.expect("entry").path();
        let t = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &t);
        } else {
            std::fs::copy(&p, &t).expect("copy");
        }
    }
}

/// The jobs' indices in the order to start them: the mutants of the largest examples first
/// (by the example's size in bytes, then in the jobs' order). Size stands for the cost of a
/// check: the two largest examples (sorting-case-study, pgcd/handover) took the most time
/// (64 and 30 of 211 worker seconds in one run; sorting-case-study's mutants 2.8 s each on
/// average, against 0.8 s for all), and listed by path sorting-case-study's came last,
/// where one of them kept a worker busy alone for 11 s at the end of the run. The order of
/// the results does not depend on it.
fn heaviest_first(jobs: &[Job]) -> Vec<usize> {
    let mut size: BTreeMap<&str, u64> = BTreeMap::new();
    for j in jobs {
        size.entry(&j.example).or_insert_with(|| {
            std::fs::metadata(root().join("choreographies").join(&j.example)).map_or(0, |m| m.len())
        });
    }
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by_key(|&k| std::cmp::Reverse(size[jobs[k].example.as_str()]));
    order
}

fn run(jobs: &[Job], workers: usize, timeout: Duration) -> Vec<Outcome> {
    static RUNS: AtomicUsize = AtomicUsize::new(0);
    let run_id = RUNS.fetch_add(1, Ordering::SeqCst);
    let order = heaviest_first(jobs);
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::new());
    let started = Instant::now();
    std::thread::scope(|s| {
        for w in 0..workers {
            let (next, results, started, order) = (&next, &results, &started, &order);
            std::thread::Builder::new()
                .stack_size(256 << 20)
                .spawn_scoped(s, move || {
                    let tree = work_tree(run_id, w);
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        let Some(j) = order.get(i).map(|&k| &jobs[k]) else { break };
                        let target = tree.join(&j.file);
                        let original = std::fs::read_to_string(&target).unwrap();
                        std::fs::write(&target, &j.text).unwrap();
                        let t = Instant::now();
                        let mut db = SourceDb::new();
                        let report = check_file(&mut db, &tree.join("choreographies").join(&j.example), &cfg(timeout))
                            .expect("readable");
                        std::fs::write(&target, original).unwrap();
                        if (i + 1) % 100 == 0 {
                            eprintln!(
                                "mutation: {} of {} mutants checked ({:.0?})",
                                i + 1,
                                jobs.len(),
                                started.elapsed()
                            );
                        }
                        let mut codes: Vec<String> =
                            report.diagnostics.iter().map(|d| d.code.as_str().to_string()).collect();
                        codes.sort();
                        codes.dedup();
                        results.lock().unwrap().push(Outcome {
                            id: j.id.clone(),
                            desc: j.desc.clone(),
                            verdict: report.verdict,
                            codes,
                            millis: t.elapsed().as_millis(),
                            timed_out: timed_out(&report),
                        });
                    }
                })
                .expect("spawn");
        }
    });
    let mut r = results.into_inner().unwrap();
    let order: BTreeMap<&str, usize> = jobs.iter().enumerate().map(|(i, j)| (j.id.as_str(), i)).collect();
    r.sort_by_key(|o| order[o.id.as_str()]);
    r
}

/// One entry of the survivors list.
#[derive(Clone, Debug, PartialEq)]
struct Entry {
    id: String,
    status: String,
    why: String,
}

/// Reads `[[survivor]]` tables with `id`, `status` and `why` string values (basic TOML
/// strings on one line; `#` comments).
fn parse_list(text: &str) -> Result<Vec<Entry>, String> {
    let mut out: Vec<Entry> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line == "[[survivor]]" {
            out.push(Entry { id: String::new(), status: String::new(), why: String::new() });
            continue;
        }
        let Some((k, v)) = line.split_once('=') else { return Err(format!("line {}: expected key = value", n + 1)) };
        let v = unquote(v.trim()).ok_or_else(|| format!("line {}: expected a \"string\"", n + 1))?;
        let e = out.last_mut().ok_or_else(|| format!("line {}: key outside [[survivor]]", n + 1))?;
        match k.trim() {
            "id" => e.id = v,
            "status" => e.status = v,
            "why" => e.why = v,
            other => return Err(format!("line {}: unknown key `{other}`", n + 1)),
        }
    }
    Ok(out)
}

fn unquote(v: &str) -> Option<String> {
    let inner = v.strip_prefix('"')?.strip_suffix('"')?;
    let mut out = String::new();
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next()? {
                'n' => out.push('\n'),
                c => out.push(c),
            }
        } else {
            out.push(c);
        }
    }
    Some(out)
}

fn quote(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n"))
}

fn explained(e: &Entry) -> bool {
    let w = e.why.trim();
    !(w.is_empty() || w.eq_ignore_ascii_case("todo") || w.eq_ignore_ascii_case("tbd") || w.len() < 20)
}

fn write_list(entries: &[(Entry, String)]) -> String {
    let mut s = String::from(
        "# Survivors of the mutation test (tests/mutation.rs): mutants that mochi still verifies.\n\
         # status = \"equivalent\": the mutated protocol is still correct (why says why);\n\
         # status = \"limitation\": a change of a trusted contract or footprint that mochi cannot check yet;\n\
         # status = \"bug\": a wrong protocol that mochi verifies (a soundness defect; the test fails\n\
         # on it unless MOCHI_MUTATION_ALLOW_KNOWN_BUGS=1). Regenerate with MOCHI_MUTATION_BLESS=1:\n\
         # entries are keyed by id and keep their status and explanation.\n",
    );
    for (e, desc) in entries {
        s.push_str(&format!(
            "\n[[survivor]]\n# {desc}\nid = {}\nstatus = {}\nwhy = {}\n",
            quote(&e.id),
            quote(&e.status),
            quote(&e.why)
        ));
    }
    s
}

#[test]
fn every_survivor_is_explained() {
    let filter = std::env::var("MOCHI_MUTATION_ONLY").ok().filter(|s| !s.is_empty());
    let bless = std::env::var("MOCHI_MUTATION_BLESS").is_ok_and(|v| v == "1");
    let allow_bugs = std::env::var("MOCHI_MUTATION_ALLOW_KNOWN_BUGS").is_ok_and(|v| v == "1");
    let workers = std::env::var("MOCHI_MUTATION_JOBS").ok().and_then(|v| v.parse().ok()).unwrap_or(2usize);
    let t = Instant::now();
    let mut jobs = jobs(filter.as_deref());
    assert!(!jobs.is_empty() || filter.is_some(), "no mutants generated");
    let slice = slice(bless || filter.is_some() || full_run());
    let which = match slice {
        Some(k) => {
            let before = jobs.len();
            jobs.retain(|j| slice_of(&j.id) == k);
            format!(
                "slice {k} of {SLICES} of the sample ({} of {before} mutants; the day's slice: MOCHI_MUTATION_SLICE={k} checks it again, MOCHI_MUTATION_SLICE=all every slice)",
                jobs.len()
            )
        }
        None => format!("{} mutants, every slice", jobs.len()),
    };
    eprintln!("mutation: {which}");
    if std::env::var("MOCHI_MUTATION_LIST").is_ok_and(|v| v == "1") {
        let mut per_op = BTreeMap::<String, usize>::new();
        for j in &jobs {
            let op = j.id.rsplit(':').next().unwrap_or("").split('(').next().unwrap_or("").to_string();
            *per_op.entry(op).or_default() += 1;
        }
        eprintln!("mutation: {} mutants (not run): {per_op:?}", jobs.len());
        let ids: String = jobs.iter().map(|j| format!("{}\t{}\n", j.id, j.desc)).collect();
        let dir = root().join("target").join("mutation");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("list.tsv"), ids).unwrap();
        return;
    }
    let mut outcomes = run(&jobs, workers.max(1), TIMEOUT);
    eprintln!("mutation: first pass over {} mutants in {:.0?} ({} worker(s))", jobs.len(), t.elapsed(), workers.max(1));
    // A second look, with a longer limit, at every mutant that ran out of time: a timeout is
    // neither a kill nor a survivor.
    let slow: Vec<&Job> = jobs.iter().filter(|j| outcomes.iter().any(|o| o.id == j.id && o.timed_out)).collect();
    if !slow.is_empty() && !bless {
        eprintln!("mutation: {} mutant(s) ran out of time; checked again with a {RETRY_TIMEOUT:?} limit", slow.len());
        let again: Vec<Job> = slow.into_iter().map(|j| Job { ..j.clone() }).collect();
        for o in run(&again, workers.max(1), RETRY_TIMEOUT) {
            if let Some(slot) = outcomes.iter_mut().find(|x| x.id == o.id) {
                *slot = o;
            }
        }
    }
    if bless {
        // A second look, with a long timeout, at every mutant that came back unknown.
        let again: Vec<Job> = jobs
            .into_iter()
            .filter(|j| outcomes.iter().any(|o| o.id == j.id && o.verdict == Verdict::Unknown))
            .collect();
        eprintln!("mutation: {} unknown mutant(s) checked again with a {BLESS_TIMEOUT:?} timeout", again.len());
        for o in run(&again, workers.max(1), BLESS_TIMEOUT) {
            if let Some(slot) = outcomes.iter_mut().find(|x| x.id == o.id) {
                *slot = o;
            }
        }
    }

    // The table.
    let dir = root().join("target").join("mutation");
    std::fs::create_dir_all(&dir).unwrap();
    let mut table = String::from("id\tverdict\tcodes\tms\tdescription\n");
    for o in &outcomes {
        table.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\n",
            o.id,
            if o.timed_out { "TimedOut".to_string() } else { format!("{:?}", o.verdict) },
            o.codes.join(","),
            o.millis,
            o.desc.replace('\t', " ")
        ));
    }
    std::fs::write(dir.join("table.tsv"), &table).unwrap();

    let count = |v: Verdict| outcomes.iter().filter(|o| o.verdict == v && !o.timed_out).count();
    let timeouts: Vec<&Outcome> = outcomes.iter().filter(|o| o.timed_out).collect();
    eprintln!(
        "mutation: {} mutants in {:.0?}: {} rejected, {} unknown (killed: undecided whatever the time), {} timed out (not killed, not survived), {} verified (survived); table in target/mutation/table.tsv",
        outcomes.len(),
        t.elapsed(),
        count(Verdict::Rejected),
        count(Verdict::Unknown),
        timeouts.len(),
        count(Verdict::Verified)
    );
    for o in &timeouts {
        eprintln!("mutation: timed out (undecided within {RETRY_TIMEOUT:?} a query): {}  ({})", o.id, o.desc);
    }

    let list_text = std::fs::read_to_string(root().join(LIST)).unwrap_or_default();
    let list = parse_list(&list_text).unwrap_or_else(|e| panic!("{LIST}: {e}"));
    let by_id: BTreeMap<&str, &Entry> = list.iter().map(|e| (e.id.as_str(), e)).collect();
    let survivors: Vec<&Outcome> = outcomes.iter().filter(|o| o.verdict == Verdict::Verified).collect();

    let mut unlisted = Vec::new();
    let mut unexplained = Vec::new();
    let mut bugs = Vec::new();
    let mut limitations = 0;
    for o in &survivors {
        match by_id.get(o.id.as_str()) {
            None => unlisted.push(format!("{}  ({})", o.id, o.desc)),
            Some(e) if !explained(e) || !matches!(e.status.as_str(), "equivalent" | "limitation" | "bug") => {
                unexplained.push(format!("{}  ({})", o.id, o.desc))
            }
            Some(e) if e.status == "bug" => bugs.push(format!("{}  ({})\n      {}", o.id, o.desc, e.why)),
            Some(e) if e.status == "limitation" => limitations += 1,
            Some(_) => {}
        }
    }
    if filter.is_none() && full_run() {
        let alive: std::collections::HashSet<&str> = survivors.iter().map(|o| o.id.as_str()).collect();
        for e in &list {
            if !alive.contains(e.id.as_str()) {
                eprintln!("mutation: stale entry (no longer survives; bless to remove): {}", e.id);
            }
        }
    }
    if bless {
        // The mutants that did not run keep their entries, if they still exist.
        let ran: std::collections::HashSet<&str> = outcomes.iter().map(|o| o.id.as_str()).collect();
        let every: BTreeMap<String, String> = jobs_of(None, true).into_iter().map(|j| (j.id, j.desc)).collect();
        let kept = list
            .iter()
            .filter(|e| !ran.contains(e.id.as_str()))
            .filter_map(|e| every.get(&e.id).map(|d| (e.clone(), d.clone())));
        let mut entries: Vec<(Entry, String)> = survivors
            .iter()
            .map(|o| {
                let e = by_id.get(o.id.as_str()).map(|e| (*e).clone()).unwrap_or(Entry {
                    id: o.id.clone(),
                    status: "unexplained".into(),
                    why: String::new(),
                });
                (e, o.desc.clone())
            })
            .chain(kept)
            .collect();
        entries.sort_by(|a, b| a.0.id.cmp(&b.0.id));
        std::fs::write(root().join(LIST), write_list(&entries)).unwrap();
        eprintln!("mutation: wrote {} survivors to {LIST}", entries.len());
    }
    eprintln!(
        "mutation: {} survivor(s) explained by a documented limitation (contracts and footprints are trusted: no dynamics, no geometry)",
        limitations
    );
    if !bugs.is_empty() {
        eprintln!("mutation: {} survivor(s) listed as soundness bugs:\n  {}", bugs.len(), bugs.join("\n  "));
    }
    assert!(
        unlisted.is_empty() && unexplained.is_empty(),
        "{} survivor(s) not in {LIST} and {} without an explanation ({which}; run with MOCHI_MUTATION_BLESS=1 to add them, then explain each):\n  {}",
        unlisted.len(),
        unexplained.len(),
        unlisted.iter().chain(&unexplained).cloned().collect::<Vec<_>>().join("\n  ")
    );
    assert!(
        bugs.is_empty() || allow_bugs,
        "{} survivor(s) are known soundness bugs (listed with status = \"bug\" in {LIST}); set MOCHI_MUTATION_ALLOW_KNOWN_BUGS=1 to accept them for now",
        bugs.len()
    );
    // A timeout is neither a kill nor a survivor; a run where many mutants end undecided
    // tests too little of its sample to pass.
    assert!(
        timeouts.len() * MAX_TIMED_OUT_ONE_IN <= outcomes.len(),
        "{} of {} mutants ({which}) were still undecided for want of time after a second look with {RETRY_TIMEOUT:?} a query (at most one in {MAX_TIMED_OUT_ONE_IN} may be): they are neither killed nor survivors, and so many leave the sample untested:\n  {}",
        timeouts.len(),
        outcomes.len(),
        timeouts.iter().map(|o| format!("{}  ({})", o.id, o.desc)).collect::<Vec<_>>().join("\n  ")
    );
}

// ---- the harness's own tests -------------------------------------------------------------

fn ids(text: &str) -> Vec<String> {
    ops::mutants(text, &["x".into()], &["k".into()], None).into_iter().map(|m| m.id).collect()
}

fn mutant(text: &str, id: &str) -> String {
    let ms = ops::mutants(text, &["x".into()], &["k".into()], None);
    ms.iter().find(|m| m.id == id).unwrap_or_else(|| panic!("no mutant {id} in {:?}", ids(text))).apply(text)
}

#[test]
fn numbers_are_nudged_both_ways_but_not_exponents_or_comments() {
    let t = "const k: real = 1.6; // 7\nconst z: real = 0 + y^2;";
    assert_eq!(mutant(t, "1:17:nudge*10%"), "const k: real = 1.76; // 7\nconst z: real = 0 + y^2;");
    assert_eq!(mutant(t, "1:17:nudge/10%"), "const k: real = 1.44; // 7\nconst z: real = 0 + y^2;");
    assert_eq!(mutant(t, "1:17:nudge-1e-3"), "const k: real = 1.599; // 7\nconst z: real = 0 + y^2;");
    assert_eq!(mutant(t, "2:17:nudge-1e-3"), "const k: real = 1.6; // 7\nconst z: real = (-0.001) + y^2;");
    let all = ids(t);
    assert!(!all.iter().any(|i| i.starts_with("2:17:nudge*")), "zero has no relative nudge: {all:?}");
    assert!(!all.iter().any(|i| i.starts_with("2:23:")), "exponent left alone: {all:?}");
    assert!(!all.iter().any(|i| i.starts_with("1:25:")), "comment left alone: {all:?}");
}

#[test]
fn comparisons_flip_but_dt_brackets_do_not() {
    let t = "process P = mu l. dt<m(1)>.Q!a.l;\nconst c: bool = 1 < 2;";
    let all: Vec<String> = ids(t).into_iter().filter(|i| i.ends_with(":cmp")).collect();
    assert_eq!(all, vec!["2:19:cmp".to_string()]);
    assert!(mutant(t, "2:19:cmp").ends_with("1 <= 2;"));
}

#[test]
fn footprints_widen_on_the_unshared_side_and_not_in_antecedents() {
    let t =
        "motion K.m { footprint(px, py, pz): 0 <= px <= 1 && (c == 0 => pz >= 2) && (py <= 3 && k < 4 => py <= 5); }";
    let w = |id: &str| mutant(t, id);
    assert!(w("1:39:fp-widen").contains("0 - 0.05 <= px <= 1"));
    assert!(w("1:45:fp-widen").contains("0 <= px <= 0.05 + 1"));
    assert!(w("1:67:fp-widen").contains("pz >= (-0.05) + 2"));
    assert!(!ids(t).contains(&"1:80:fp-widen".to_string()), "antecedent `py <= 3 && k < 4 =>` is not relaxed");
    assert!(w("1:100:fp-widen").contains("=> py <= 0.05 + 5"));
}

#[test]
fn durations_swap_and_move() {
    let t = "motion K.m { duration: [2, 4]; }\nmotion K.n { duration: [0, inf]; }";
    assert!(mutant(t, "1:24:dur-swap").contains("[4, 2]"));
    assert!(mutant(t, "1:24:dur-hi-1").contains("[2, (4) - 1]"));
    assert!(mutant(t, "2:24:dur-lo+1").contains("[(0) + 1, inf]"));
    let all = ids(t);
    assert!(!all.contains(&"2:24:dur-swap".into()) && !all.contains(&"2:24:dur-lo-1".into()), "{all:?}");
}

#[test]
fn messages_drop_and_swap_consistently() {
    let t = "choreography G = P -> Q: a(v: real {v > 0}). P -> R: b. dt<P: m, Q: n, R: n>. end;\n\
             process P = Q!a(1).R!b.dt<m>.end;\nprocess Q = P?a(v).dt<n>.end;\nprocess R = P?b.dt<n>.end;\n\
             local R = P?b.dt<n>.end;";
    let all = mutant(t, "1:18:drop-msg-all");
    assert!(all.starts_with("choreography G = P -> R: b. dt<"), "{all}");
    assert!(all.contains("process P = R!b.dt<m>") && all.contains("process Q = dt<n>") && !all.contains("local"));
    let sw = mutant(t, "1:18:swap-all");
    assert!(sw.contains("G = P -> R: b.P -> Q: a(v: real {v > 0}). dt<") && sw.contains("process P = R!b.Q!a(1).dt<"));
    assert!(mutant(t, "1:46:swap").contains("dt<P: m, Q: n, R: n>.P -> R: b. end"));
    assert!(mutant(t, "3:13:drop-act").contains("process Q = dt<n>.end"));
}

#[test]
fn binders_shadow_with_their_uses_and_conjuncts_drop() {
    let t = "choreography G = mu t. P -> Q: a(v: real {v > x && v < k}, w: real {w == v}). t;";
    let s = mutant(t, "1:34:shadow(v->w)");
    assert!(s.contains("a(w: real {w > x && w < k}, w: real {w == w})"), "{s}");
    assert!(mutant(t, "1:34:shadow(v->x)").contains("a(x: real {x > x && x < k}, w: real {w == x})"));
    assert!(mutant(t, "1:34:shadow(v->k)").contains("{k > x && k < k}"));
    assert!(mutant(t, "1:43:drop-conj").contains("{v < k}"));
    assert!(mutant(t, "1:52:drop-conj").contains("{v > x}"));
}

#[test]
fn shapes_grow_and_shrink_and_poses_move() {
    let t = "robot R { state x: real; geometry: box(a, 0.2, 0.3) at pose(x, 0, 0, 0, 0, th); mount d: pose(x, 0, h); }";
    let g = mutant(t, "1:36:geo-grow");
    assert!(g.contains("box((a) * 1.2, (0.2) * 1.2, (0.3) * 1.2)"), "{g}");
    assert!(mutant(t, "1:36:geo-shrink").contains("box((a) * 0.8, (0.2) * 0.8, (0.3) * 0.8)"));
    assert!(mutant(t, "1:56:pose-x+").contains("pose((x) + 0.05, 0, 0, 0, 0, th)"));
    assert!(mutant(t, "1:56:pose-yaw-").contains("pose(x, 0, 0, 0, 0, (th) - 0.1)"));
    assert!(mutant(t, "1:90:pose-z-").contains("mount d: pose(x, 0, (h) - 0.05)"));
    let all = ids(t);
    assert!(!all.contains(&"1:90:pose-yaw+".to_string()), "a pose of three has no yaw: {all:?}");
}

#[test]
fn urdf_collisions_scale_grow_and_move_but_visuals_do_not() {
    let t = "<link name=\"a\">\n<visual><geometry><sphere radius=\"0.5\"/></geometry></visual>\n\
             <collision><origin xyz=\"0 0 .13\" rpy=\"0 0 0\"/>\n<geometry><mesh filename=\"m.stl\"/></geometry></collision>\n\
             <collision><origin xyz=\"1 2 3\"/><geometry><cylinder length=\"0.03\" radius=\"0.09\"/></geometry></collision></link>";
    let ms = ops::urdf_mutants(t);
    let get = |id: &str| {
        ms.iter()
            .find(|m| m.id == id)
            .unwrap_or_else(|| panic!("no {id}: {:?}", ms.iter().map(|m| &m.id).collect::<Vec<_>>()))
            .apply(t)
    };
    assert!(get("3:12:urdf-move-z").contains("xyz=\"0 0 0.1\""));
    assert!(get("3:12:urdf-move+x").contains("xyz=\"0.03 0 0.13\""));
    assert!(get("4:11:urdf-scale").contains("<mesh scale=\"1.2 1.2 1.2\" filename=\"m.stl\"/>"));
    let c = get("5:43:urdf-grow");
    assert!(c.contains("length=\"0.036\" radius=\"0.108\""), "{c}");
    assert!(!ms.iter().any(|m| m.id.starts_with("2:")), "the visual sphere is left alone");
}

#[test]
fn mavlink_operators_know_the_dialect_and_the_wire() {
    let d = mochi::dialect::builtin("common").expect("common");
    let t = "choreography U =\n  GCS -> UAV: MISSION_COUNT(count {1 <= count && count < 500}, mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).\n  \
             ( UAV -> GCS: [i < count] MISSION_ACK(type {type == MAV_MISSION_ACCEPTED}). end\n  + GCS -> UAV: PARAM_SET(param_value {param_value == 0.1}). end );";
    let ms = ops::mutants(t, &[], &[], Some(d));
    let get = |id: &str| {
        ms.iter()
            .find(|m| m.id == id)
            .unwrap_or_else(|| panic!("no {id}: {:?}", ms.iter().map(|m| &m.id).collect::<Vec<_>>()))
            .apply(t)
    };
    assert!(get("2:58:off-by-one-1").contains("count < 499}"));
    assert!(get("3:20:guard-neg").contains("[i >= count]"));
    assert!(get("3:55:enum(MAV_MISSION_ACCEPTED->MAV_MISSION_ERROR)").contains("type == MAV_MISSION_ERROR}"));
    let dup = get("2:3:dup-msg");
    assert_eq!(dup.matches("MISSION_COUNT(").count(), 2, "{dup}");
    assert!(get("2:29:field-swap")
        .contains("MISSION_COUNT(mission_type {1 <= count && count < 500}, count {mission_type =="));
    assert!(get("3:5:drop-msg").contains("( end\n"), "a guarded step is dropped whole");
    assert!(get("2:36:drop-conj").contains("count {count < 500}"));
    // 0.1 is not a float32: the literal becomes a number between float32 neighbours.
    let up = get("4:55:f32-up");
    let value = |m: &str| -> f64 {
        let at = m.find("param_value == ").unwrap() + 15;
        m[at..at + m[at..].find('}').unwrap()].parse().unwrap()
    };
    let v = value(&up);
    let (lo, hi) = (f64::from(0.1f32), f64::from(f32::from_bits(0.1f32.to_bits() + 1)));
    assert!(lo < v && v < hi && (v as f32) == hi as f32, "{v} between {lo} and {hi}, rounding up");
    let same = get("4:55:f32-same");
    let w = value(&same);
    assert!(lo < w && w < hi && (w as f32) == 0.1f32, "{w} rounds back to 0.1f32");
    assert!(ops::mutants(t, &[], &[], None).iter().all(|m| !m.id.contains("enum(") && !m.id.ends_with("dup-msg")));
}

#[test]
fn a_wrong_mutant_of_an_example_is_killed() {
    // cart-and-arms without `Cart -> GRobot: ready` (dropped from the choreography and from
    // both processes): the green arm would start `pick` while the cart may still be driving
    // in, with nothing telling it the cart has stopped. mochi must not verify it, and the
    // harness must report it killed.
    let example = "cart-and-arms.chor".to_string();
    assert!(verified_examples().contains(&example), "cart-and-arms.chor is a verified example");
    let js: Vec<Job> = jobs_of_examples(&[example], Some("cart-and-arms.chor:"), full_run())
        .into_iter()
        .filter(|j| j.id.ends_with(":drop-msg-all") && j.desc.contains("Cart -> GRobot: ready"))
        .collect();
    assert_eq!(js.len(), 1, "one consistent drop of the green `ready`");
    let out = run(&js, 1, TIMEOUT);
    assert_ne!(out[0].verdict, Verdict::Verified, "{} survived: {}", out[0].id, out[0].desc);
}

#[test]
fn the_survivors_list_parses_and_round_trips() {
    let e = Entry {
        id: "a.chor:1:2:cmp".into(),
        status: "equivalent".into(),
        why: "a \"quoted\" reason\\ long enough".into(),
    };
    let text = write_list(&[(e.clone(), "desc".into())]);
    assert_eq!(parse_list(&text).unwrap(), vec![e.clone()]);
    assert!(explained(&e));
    assert!(!explained(&Entry { why: "TODO".into(), ..e }));
    let list = std::fs::read_to_string(root().join(LIST)).unwrap_or_default();
    parse_list(&list).expect("the committed list parses");
}
