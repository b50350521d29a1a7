//! What the metamorphic and differential tests share: the corpus, how a (possibly
//! rewritten) program is checked, and what of a report is compared.
//!
//! A program is a root file and the files it imports. A rewritten program is the same root
//! path with new texts for some of its files ([`Program::texts`]): the pipeline reads them
//! through a loader that serves the new texts and falls back to the disk, so imports,
//! URDFs and meshes resolve exactly as for the original.

#![allow(dead_code)]

use mochi::driver::{check_loaded, Config, Verdict};
use mochi::source::SourceDb;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

/// What the relations compare: the verdict and the codes of every diagnostic (errors and
/// warnings), sorted. Positions and messages are left out: a rewritten text moves them and
/// names them differently.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Outcome {
    pub verdict: Verdict,
    pub codes: Vec<String>,
}

impl Outcome {
    /// The codes of the errors alone.
    pub fn error_codes(&self) -> Vec<String> {
        self.codes.iter().filter(|c| c.starts_with('E')).cloned().collect()
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?} [{}]", self.verdict, self.codes.join(", "))
    }
}

/// A program to check: the root's path (relative to the package root, as the tests run
/// there) and the texts that replace files on disk, by the name the pipeline gives them
/// (the root's path as given, an import's path joined to its importer's folder).
#[derive(Clone, Debug, Default)]
pub struct Program {
    pub root: PathBuf,
    pub texts: HashMap<String, String>,
}

impl Program {
    pub fn on_disk(root: &Path) -> Program {
        Program { root: root.to_path_buf(), texts: HashMap::new() }
    }
}

/// The number of cases each property runs: `MOCHI_META_CASES` when set (the long mode),
/// else `default`.
pub fn cases(default: u32) -> u32 {
    std::env::var("MOCHI_META_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Whether the long mode is on (`MOCHI_META_CASES` set): then the heavy files are in the
/// corpus too.
pub fn long_mode() -> bool {
    std::env::var_os("MOCHI_META_CASES").is_some()
}

/// The configuration every run uses: the patient per-query limit of the golden suite (so a
/// verdict does not depend on the machine's load) and `jobs` worker threads.
pub fn config(jobs: usize, no_cache: bool) -> Config {
    let mut c = Config::patient();
    c.smt.jobs = jobs;
    c.smt.no_cache = no_cache;
    c
}

/// Checks `p` under `cfg`.
pub fn check(p: &Program, cfg: &Config) -> Outcome {
    let mut db = SourceDb::new();
    let name = p.root.display().to_string();
    let root_text = match p.texts.get(&name) {
        Some(t) => t.clone(),
        None => match std::fs::read(&p.root) {
            Ok(b) => match String::from_utf8(b) {
                Ok(t) => t,
                // Not UTF-8: the file-system path reports it (E0107).
                Err(_) => {
                    let report = mochi::fsload::check_file(&mut db, &p.root, cfg).expect("readable");
                    return outcome(&report);
                }
            },
            Err(e) => panic!("cannot read {name}: {e}"),
        },
    };
    let root = db.add(name, root_text);
    let texts = &p.texts;
    let mut load = |path: &Path| -> std::io::Result<Vec<u8>> {
        match texts.get(&path.display().to_string()) {
            Some(t) => Ok(t.clone().into_bytes()),
            None => mochi::fsload::read_bytes(path),
        }
    };
    let report = check_loaded(&mut db, root, cfg, &mut load);
    outcome(&report)
}

fn outcome(report: &mochi::driver::Report) -> Outcome {
    let mut codes: Vec<String> = report.diagnostics.iter().map(|d| d.code.as_str().to_string()).collect();
    codes.sort();
    Outcome { verdict: report.verdict, codes }
}

/// Files whose check takes tens of seconds or more in a debug build (the geometric
/// procedure on URDF arms, meshes and mounted robots): in the corpus of the long mode only.
const HEAVY: &[&str] = &[
    "choreographies/mounted-arm.chor",
    "choreographies/sorting-case-study.chor",
    "choreographies/cart-and-arms.chor",
    "choreographies/sorting.chor",
    "choreographies/pgcd/fetch.chor",
    "choreographies/pgcd/handover.chor",
    "choreographies/rejected/geometry/",
    // Two queries that run out the 60 s limit (it tests that a timeout is unknown).
    "tests/data/hard-integer-guard.chor",
];

pub fn is_heavy(p: &Path) -> bool {
    let s = p.display().to_string();
    HEAVY.iter().any(|h| if h.ends_with('/') { s.starts_with(h) } else { s == *h })
}

/// Every `.chor` under `choreographies/` (but `pending/`) and `tests/data/`, sorted; the
/// heavy ones only in the long mode.
pub fn corpus() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(rd) = std::fs::read_dir(dir) else { return };
        let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n == "pending") {
                    continue;
                }
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "chor") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(Path::new("choreographies"), &mut out);
    walk(Path::new("tests/data"), &mut out);
    let long = long_mode();
    out.retain(|p| long || !is_heavy(p));
    out
}

/// The outcome of each corpus file as it is on disk: for a file of `choreographies/`, the
/// one its golden snapshot records ([`golden_outcome`]); for another (`tests/data/`), its
/// check under `config(1, false)`, computed once per test binary and shared by its tests (a
/// test that asks for a file another is checking waits for that check rather than running
/// its own).
///
/// Reading the snapshot is reading a check: the corpus harness (tests/corpus.rs, run by the
/// same `cargo test`) checks every file of `choreographies/` with the same 60 s limit
/// (`Config::patient`, one SMT worker per core) and fails unless its report is the
/// snapshot's. A relation is then checked against that check rather than a second one of
/// the same text; [`golden_outcome`]'s reading is itself tested against fresh checks
/// (tests/metamorphic.rs, `the_golden_snapshots_are_the_checks_outcomes`).
pub fn baseline(p: &Path) -> Outcome {
    type Cell = Arc<OnceLock<Outcome>>;
    static BASE: OnceLock<Mutex<BTreeMap<PathBuf, Cell>>> = OnceLock::new();
    let base = BASE.get_or_init(|| Mutex::new(BTreeMap::new()));
    let cell: Cell = Arc::clone(base.lock().unwrap_or_else(|e| e.into_inner()).entry(p.to_path_buf()).or_default());
    cell.get_or_init(|| golden_outcome(p).unwrap_or_else(|| check(&Program::on_disk(p), &config(1, false)))).clone()
}

/// The golden snapshot of a file of `choreographies/` (tests/corpus.rs names it), or `None`
/// for a file elsewhere or without one.
pub fn golden_snapshot(p: &Path) -> Option<String> {
    let below = p.strip_prefix("choreographies").ok()?;
    let below = below.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("__");
    let snap = format!("tests/snapshots/golden__every_choreography_matches_its_golden_file@{below}.snap");
    std::fs::read_to_string(snap).ok()
}

/// The outcome a file's golden snapshot records: the verdict line, and the code of every
/// diagnostic (each rendered starting `error[CODE]:`, `warning[CODE]:` or `note[CODE]:` at
/// the start of a line), sorted. `None` when there is no snapshot; a snapshot without a
/// verdict line is a broken golden file and panics.
pub fn golden_outcome(p: &Path) -> Option<Outcome> {
    let text = golden_snapshot(p)?;
    let verdict = text.split("==== VERDICT ====\n").nth(1).and_then(|r| r.lines().next()).map(str::trim);
    let verdict = match verdict {
        Some("Verified") => Verdict::Verified,
        Some("Rejected") => Verdict::Rejected,
        Some("Unknown") => Verdict::Unknown,
        other => panic!("{}: the golden snapshot has no verdict line ({other:?})", p.display()),
    };
    let diags = text.split("==== DIAGNOSTICS ====\n").nth(1).unwrap_or("");
    let diags = diags.split("==== PROJECTIONS ====\n").next().unwrap_or("");
    let mut codes: Vec<String> = diags
        .lines()
        .filter_map(|l| {
            let rest = ["error[", "warning[", "note["].iter().find_map(|s| l.strip_prefix(s))?;
            let (code, after) = rest.split_once(']')?;
            after.starts_with(':').then(|| code.to_string())
        })
        .collect();
    codes.sort();
    Some(Outcome { verdict, codes })
}

/// How many slices the corpus sweeps are cut into: a run checks one slice of each sweep (the
/// day's), so that the sweeps fit in a `cargo test` of a few minutes and every file is swept
/// by every relation every [`SLICES`] days.
pub const SLICES: u64 = 4;

/// A stable hash (FNV-1a), for slices that are the same every run.
pub fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// Which slice of the sweeps this run checks: every slice with `MOCHI_META_SLICE=all` or in
/// the long mode (`MOCHI_META_CASES` set), slice `k` with `MOCHI_META_SLICE=k`, otherwise
/// the day's (days since 1970 modulo [`SLICES`]), as the mutation test's sample. Printed once
/// per binary with how to run it again.
pub fn slice() -> Option<u64> {
    static SLICE: OnceLock<Option<u64>> = OnceLock::new();
    *SLICE.get_or_init(|| {
        let s = match std::env::var("MOCHI_META_SLICE").ok().as_deref().map(str::trim) {
            Some("all") => None,
            Some(k) => Some(
                k.parse::<u64>().unwrap_or_else(|_| panic!("MOCHI_META_SLICE={k}: a number or `all`")) % SLICES,
            ),
            None if long_mode() => None,
            None => {
                let days = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs() / 86_400);
                Some(days % SLICES)
            }
        };
        match s {
            Some(k) => eprintln!(
                "corpus sweeps: slice {k} of {SLICES} (MOCHI_META_SLICE={k} runs it again, MOCHI_META_SLICE=all every file)"
            ),
            None => eprintln!("corpus sweeps: every file (MOCHI_META_SLICE=all or the long mode)"),
        }
        s
    })
}

/// Whether the sweep `what` checks `p` in this run ([`slice`]): each sweep's slices are cut
/// by a hash of its name and the file, so one day's run sweeps most files with some
/// relation (about three in four with five relations), and each relation every file over
/// [`SLICES`] days.
pub fn in_slice(what: &str, p: &Path) -> bool {
    slice().is_none_or(|k| (fnv(&format!("{what}:{}", p.display())) % SLICES) == k)
}

/// Runs `f` on every item of `items` on `threads` threads, results in the items' order,
/// printing each item's time to standard error (seen with `--nocapture`).
pub fn par_map<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let out: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= items.len() {
                    break;
                }
                let r = f(&items[i]);
                *out[i].lock().expect("slot") = Some(r);
            });
        }
    });
    out.into_iter().map(|m| m.into_inner().expect("slot").expect("every item ran")).collect()
}

/// Runs `f` and says on standard error how long it took.
pub fn timed<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let t = Instant::now();
    let r = f();
    eprintln!("  {:>8.2} s  {what}", t.elapsed().as_secs_f64());
    r
}
