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

/// The outcome of each corpus file as it is on disk under `config(1, false)`, computed once
/// per test binary and shared by its tests: a test that asks for a file another is checking
/// waits for that check rather than running its own.
pub fn baseline(p: &Path) -> Outcome {
    type Cell = Arc<OnceLock<Outcome>>;
    static BASE: OnceLock<Mutex<BTreeMap<PathBuf, Cell>>> = OnceLock::new();
    let base = BASE.get_or_init(|| Mutex::new(BTreeMap::new()));
    let cell: Cell = Arc::clone(base.lock().unwrap_or_else(|e| e.into_inner()).entry(p.to_path_buf()).or_default());
    cell.get_or_init(|| check(&Program::on_disk(p), &config(1, false))).clone()
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
