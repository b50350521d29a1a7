//! Mutation test of the checker (issue 7). Every verified example under `choreographies/`
//! (not `rejected/`) is mutated, together with the `.mochi` libraries it imports, by the
//! operators of `tests/mutation/ops.rs`, and each mutant is checked. A mutant is *killed* when
//! mochi does not say `verified` (rejected, or unknown: a timeout is not a pass, but the table
//! records the difference); it *survives* when mochi still says `verified`.
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
//! - `MOCHI_MUTATION_ONLY=substring` runs only the mutants whose id contains it (no blessing,
//!   no stale report).
//! - `MOCHI_MUTATION_JOBS=n` mutants checked in parallel (default 2, one SMT thread each).
//! - Which mutants run: all of them with `MOCHI_MUTATION_FULL=1` (about seven times the
//!   sample, which is 1,299 mutants and about three minutes in a release build on two cores
//!   since the sorting case study joined); otherwise, and so on CI, a fixed sample: one
//!   mutant in [`SAMPLE`], chosen by a hash of its id (the same every run), so that `cargo test`
//!   stays quick. The sample is a subset of the full set, so one survivors list serves both.
//! - Blessing updates the entries of the mutants that ran and keeps the others (a sampled bless
//!   does not forget the full run's survivors; entries whose mutant no longer exists go). It
//!   checks again with a long timeout ([`BLESS_TIMEOUT`]) every mutant that came back unknown: a
//!   mutant that times out here but verifies on a faster machine must already be in the list.
//!
//! The table of every mutant (id, verdict, codes, description) is written to
//! `target/mutation/table.tsv`.

#[path = "mutation/ops.rs"]
mod ops;

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
/// Outside CI, one mutant in this many runs (chosen by a hash of its id).
const SAMPLE: u64 = 7;

/// Whether every mutant runs (`MOCHI_MUTATION_FULL=1`) or only the sample.
fn full_run() -> bool {
    std::env::var("MOCHI_MUTATION_FULL").is_ok_and(|x| x == "1" || x == "true")
}

/// A stable hash of a mutant's id (FNV-1a), for the sample.
fn in_sample(id: &str) -> bool {
    let h = id.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    h % SAMPLE == 0
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn cfg(timeout: Duration) -> Config {
    Config { smt: SmtConfig { timeout, jobs: 1, ..SmtConfig::default() }, structural_only: false, ..Config::default() }
}

/// A mutant ready to run: the example (relative to `choreographies/`), the mutated file
/// (relative to the package root) and its new text.
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
}

/// The verified examples: every `.chor` under `choreographies/` except `rejected/`.
fn verified_examples() -> Vec<String> {
    let mut all = Vec::new();
    let mut stack = vec![root().join("choreographies")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                // Not `pending/` either: unknown after minutes (golden.rs).
                if p.file_name().is_some_and(|n| n != "rejected" && n != "pending") {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "chor") {
                all.push(p);
            }
        }
    }
    all.sort();
    all.into_iter()
        .filter(|p| {
            let mut db = SourceDb::new();
            check_file(&mut db, p, &cfg(Duration::from_secs(10)))
                .map(|r| r.verdict == Verdict::Verified)
                .unwrap_or(false)
        })
        .map(|p| p.strip_prefix(root().join("choreographies")).unwrap().display().to_string())
        .collect()
}

/// The files an example reads (itself and its imports), relative to the package root.
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
    files.sort();
    files.dedup();
    files
}

fn jobs(filter: Option<&str>) -> Vec<Job> {
    jobs_of(filter, full_run())
}

/// Every mutant (`all`), or the sample, of the ids containing `filter`.
fn jobs_of(filter: Option<&str>, all: bool) -> Vec<Job> {
    let mut out = Vec::new();
    for ex in verified_examples() {
        let files = closure(&ex);
        let (mut consts, mut states) = (Vec::new(), Vec::new());
        for f in &files {
            let (c, s) = ops::declared_names(&std::fs::read_to_string(root().join(f)).unwrap());
            consts.extend(c);
            states.extend(s);
        }
        states.sort();
        states.dedup();
        for f in &files {
            let text = std::fs::read_to_string(root().join(f)).unwrap();
            let prefix = if f == &format!("choreographies/{ex}") { ex.clone() } else { format!("{ex}@{f}") };
            for m in ops::mutants(&text, &states, &consts) {
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

fn run(jobs: &[Job], workers: usize, timeout: Duration) -> Vec<Outcome> {
    static RUNS: AtomicUsize = AtomicUsize::new(0);
    let run_id = RUNS.fetch_add(1, Ordering::SeqCst);
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for w in 0..workers {
            let (next, results) = (&next, &results);
            std::thread::Builder::new()
                .stack_size(256 << 20)
                .spawn_scoped(s, move || {
                    let tree = work_tree(run_id, w);
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        let Some(j) = jobs.get(i) else { break };
                        let target = tree.join(&j.file);
                        let original = std::fs::read_to_string(&target).unwrap();
                        std::fs::write(&target, &j.text).unwrap();
                        let t = Instant::now();
                        let mut db = SourceDb::new();
                        let report = check_file(&mut db, &tree.join("choreographies").join(&j.example), &cfg(timeout))
                            .expect("readable");
                        std::fs::write(&target, original).unwrap();
                        if (i + 1) % 100 == 0 {
                            eprintln!("mutation: {} of {} mutants checked", i + 1, jobs.len());
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
    let bless = std::env::var("MOCHI_MUTATION_BLESS").is_ok_and(|v| v == "1") && filter.is_none();
    let allow_bugs = std::env::var("MOCHI_MUTATION_ALLOW_KNOWN_BUGS").is_ok_and(|v| v == "1");
    let workers = std::env::var("MOCHI_MUTATION_JOBS").ok().and_then(|v| v.parse().ok()).unwrap_or(2usize);
    let t = Instant::now();
    let jobs = jobs(filter.as_deref());
    assert!(!jobs.is_empty() || filter.is_some(), "no mutants generated");
    if std::env::var("MOCHI_MUTATION_LIST").is_ok_and(|v| v == "1") {
        let mut per_op = BTreeMap::<String, usize>::new();
        for j in &jobs {
            let op = j.id.rsplit(':').next().unwrap_or("").split('(').next().unwrap_or("").to_string();
            *per_op.entry(op).or_default() += 1;
        }
        eprintln!("mutation: {} mutants (not run): {per_op:?}", jobs.len());
        return;
    }
    let mut outcomes = run(&jobs, workers.max(1), TIMEOUT);
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
            "{}\t{:?}\t{}\t{}\t{}\n",
            o.id,
            o.verdict,
            o.codes.join(","),
            o.millis,
            o.desc.replace('\t', " ")
        ));
    }
    std::fs::write(dir.join("table.tsv"), &table).unwrap();

    let count = |v: Verdict| outcomes.iter().filter(|o| o.verdict == v).count();
    eprintln!(
        "mutation: {} mutants in {:.0?}: {} rejected, {} unknown (killed), {} verified (survived); table in target/mutation/table.tsv",
        outcomes.len(),
        t.elapsed(),
        count(Verdict::Rejected),
        count(Verdict::Unknown),
        count(Verdict::Verified)
    );

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
        "{} survivor(s) not in {LIST} and {} without an explanation (run with MOCHI_MUTATION_BLESS=1 to add them, then explain each):\n  {}",
        unlisted.len(),
        unexplained.len(),
        unlisted.iter().chain(&unexplained).cloned().collect::<Vec<_>>().join("\n  ")
    );
    assert!(
        bugs.is_empty() || allow_bugs,
        "{} survivor(s) are known soundness bugs (listed with status = \"bug\" in {LIST}); set MOCHI_MUTATION_ALLOW_KNOWN_BUGS=1 to accept them for now",
        bugs.len()
    );
}

// ---- the harness's own tests -------------------------------------------------------------

fn ids(text: &str) -> Vec<String> {
    ops::mutants(text, &["x".into()], &["k".into()]).into_iter().map(|m| m.id).collect()
}

fn mutant(text: &str, id: &str) -> String {
    let ms = ops::mutants(text, &["x".into()], &["k".into()]);
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
fn a_wrong_mutant_of_an_example_is_killed() {
    // cart-and-arms without `Cart -> GRobot: ready` (dropped from the choreography and from
    // both processes): the green arm would start `pick` while the cart may still be driving
    // in, with nothing telling it the cart has stopped. mochi must not verify it, and the
    // harness must report it killed.
    let js: Vec<Job> = jobs(Some("cart-and-arms.chor:"))
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
