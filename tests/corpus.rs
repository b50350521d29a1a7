//! The corpus harness: every file of the corpus is checked ONCE, and everything the tests
//! assert about it is read off that one report. One test per file (a `libtest-mimic`
//! harness, as typst's), named by its path, so one file's test runs alone:
//! `cargo test --test corpus -- sorting-case-study` (a substring of the name), or a folder's:
//! `cargo test --test corpus -- mavlink/rejected/`.
//!
//! The corpus is every `.chor` under `choreographies/` (every folder: `pgcd/`, `mavlink/`,
//! `rejected/`, and any added later; not `pending/`), and the rejected libraries (a `.mochi`
//! file of a rejected folder whose first line is an `// expect:` line). For each file:
//!
//! - **golden snapshot** (every `.chor`): its verdict, checks, diagnostics and projections
//!   are compared with `tests/snapshots/golden__every_choreography_matches_its_golden_file@PATH.snap`
//!   (insta; the names are those of the former per-harness glob). After an intended change,
//!   run `INSTA_UPDATE=always cargo test --test corpus` and read the diff before committing.
//! - **rejected corpus** (a file of [`DIRS`]): its first line says which rule it breaks, as
//!   `// expect: E0301 at 5:3`: the check must reject the file, every error must carry that
//!   code and a hint, and one of them must start at that line and column. A diagnostic that
//!   points into another file (a URDF) is expected as `// expect: E0501 at
//!   robots/pybullet_data/husky/husky.urdf:97:18`, the path relative to the repository root.
//!   The file name starts with the code.
//! - **counterexamples**: each counterexample the report shows falsifies its goal, evaluated
//!   exactly under the values shown, and a corrupted one is noticed (see
//!   [`counterexamples_falsify_their_goals`]).
//! - **round trip**: each projection prints as a local type that parses back to the same
//!   type.
//!
//! Totals over the whole corpus (at least 20 counterexamples decided violated, 2 geometric
//! contacts replayed in exact arithmetic, at most 4
//! unreadable, at least 8 projections round-tripped) are checked after every file ran, when
//! no filter left a file out. The tests that are not per file: every code in `diag.rs` is
//! accounted for (produced by a rejected file, listed in [`NOT_ALONE`], or reserved), the
//! folders are read, every snapshot has its file, and the value-hiding of the snapshots.
//!
//! What a snapshot does not store, and why:
//! - **model values.** The values of a counterexample are whatever model Z3 found; another
//!   Z3 version finds another one, equally right. A snapshot keeps which variables the
//!   counterexample names and replaces each value by `_`;
//!   [`counterexamples_falsify_their_goals`] checks the values themselves, by
//!   evaluating the obligation under them in exact arithmetic.
//! - **the checks' free-text summaries** ("3 obligation(s), 5 queries (2 cached)"). How
//!   many queries a check asks depends on which worker answered which question first.
//!   Only the report's structured fields are stored: each check's name and status, and
//!   the number of obligations that held vacuously. (The obligation counts per check are
//!   only in the summary text; they come back when the report carries them as numbers.)

use libtest_mimic::{Arguments, Failed, Trial};
use mochi::diag::{Code, Counterexample, Diagnostic, Severity};
use mochi::driver::{Config, Verdict};
use mochi::fsload::check_file;
use mochi::render;
use mochi::source::SourceDb;
use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A check's counts that do not depend on scheduling: how many obligations, how many
/// failed, were undecided or held vacuously. Query, cache and "settled without Z3" counts
/// are left out: which worker asked first decides them (a contract witnessed by a `dt`'s
/// query needs no query of its own).
fn golden_detail(d: &mochi::driver::Detail) -> String {
    use mochi::driver::Detail;
    match d {
        Detail::None => String::new(),
        Detail::Errors(n) => format!(" errors={n}"),
        Detail::Obligations { total, failed, undecided, vacuous, .. } => {
            format!(" obligations={total} failed={failed} undecided={undecided} vacuous={vacuous}")
        }
        Detail::NotDecided(n) => format!(" not-decided={n}"),
        Detail::Vacuity { vacuous, proved, unsure } => format!(" proved={proved} vacuous={vacuous} unsure={unsure}"),
        Detail::PastDeadline { .. } => " past-deadline".to_string(),
    }
}

/// Every `.chor` under `choreographies/`, in every folder, sorted.
fn chor_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<PathBuf> =
            std::fs::read_dir(dir).expect("readable folder").map(|e| e.expect("entry").path()).collect();
        entries.sort();
        for p in entries {
            // `choreographies/pending/`: examples the geometric procedure does not decide in
            // reasonable time yet; each takes minutes, then says unknown.
            if p.is_dir() && p.file_name().is_some_and(|n| n == "pending") {
                continue;
            }
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "chor") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(Path::new("choreographies"), &mut out);
    out
}

/// A counterexample with each model value replaced by `_`: which variables it names,
/// and whether it has a point where two footprints meet (and at how many times).
fn without_values(cx: &Counterexample, note: &str) -> String {
    let mut parts = Vec::new();
    if let Some(o) = &cx.overlap {
        let at = match o.times.len() {
            0 => String::new(),
            1 => "at time _ s, ".to_string(),
            n => format!("at times {} s, ", vec!["_"; n].join(" and ")),
        };
        // What the point is (in both footprints, in a footprint and an obstacle, a point of
        // the body outside its footprint) is the note's words after the point.
        let what =
            note.split_once(") m ").map_or("is in both footprints", |(_, rest)| rest.split(';').next().unwrap_or(rest));
        parts.push(format!("{at}the point (x, y, z) = (_, _, _) m {what}"));
    }
    // The point and the time are shown above when there is an overlap.
    let hidden = |n: &str| cx.overlap.is_some() && (n.starts_with("point.") || n.starts_with("time"));
    let values: Vec<String> =
        cx.values.iter().filter(|a| !hidden(&a.name)).map(|a| format!("{} = _", a.name)).collect();
    if !values.is_empty() {
        parts.push(values.join(", "));
    }
    format!("counterexample: {}", parts.join("; "))
}

/// A trace note with each value (`name = value` in a message's payload or a loop head's
/// parameters) replaced by `_`: the values are a Z3 model's, and another model (another
/// Z3 build, another order of queries) is as good a counterexample. Guards (`==`, `!=`,
/// `<=`, `>=`) are the program's text and stay.
fn trace_without_values(note: &str) -> String {
    let b = note.as_bytes();
    let mut out = String::with_capacity(note.len());
    let mut i = 0;
    while i < b.len() {
        let assign = b[i] == b'='
            && i >= 1
            && b[i - 1] == b' '
            && i >= 2
            && !matches!(b[i - 2], b'=' | b'!' | b'<' | b'>')
            && b.get(i + 1) == Some(&b' ')
            && b.get(i + 2) != Some(&b'=');
        if !assign {
            let ch = note[i..].chars().next().expect("a char");
            out.push(ch);
            i += ch.len_utf8();
            continue;
        }
        out.push_str("= _");
        i += 2;
        // The value: a quoted string, or everything up to `,`, `)` or white space.
        if b.get(i) == Some(&b'"') {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
        } else {
            while i < b.len() && !matches!(b[i], b',' | b')' | b' ' | b'\n') {
                i += 1;
            }
        }
    }
    out
}

/// `d` as it is stored: its counterexample and trace notes without the model's values.
fn stable(d: &Diagnostic) -> Diagnostic {
    let mut d = d.clone();
    if let Some(cx) = d.counterexample.as_deref() {
        for note in &mut d.notes {
            if note.starts_with("counterexample: ") {
                *note = without_values(cx, note);
            } else if note.starts_with("trace to this point") {
                *note = trace_without_values(note);
            }
        }
    }
    d
}

fn trace_values_are_hidden_and_guards_kept() {
    let note = "trace to this point (one path; values from the counterexample):\n    \
                GCS -> UAV: MISSION_COUNT(count = 3, mission_type = 0)\n    \
                mu t: i = 2, r = 1, dup = true   (loop head: this iteration's parameters)\n    \
                UAV -> GCS: [res == MAV_X && k != 2 && a <= 1] ACK(s = \"a, b\", t = -1.5e-3)";
    let got = trace_without_values(note);
    assert_eq!(
        got,
        "trace to this point (one path; values from the counterexample):\n    \
         GCS -> UAV: MISSION_COUNT(count = _, mission_type = _)\n    \
         mu t: i = _, r = _, dup = _   (loop head: this iteration's parameters)\n    \
         UAV -> GCS: [res == MAV_X && k != 2 && a <= 1] ACK(s = _, t = _)"
    );
}

/// The stable part of a report: no timings, no query counts, no model values, paths
/// relative to the package root.
fn dump(db: &SourceDb, report: &mochi::driver::Report) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "==== VERDICT ====\n{:?}", report.verdict);
    out.push_str("==== CHECKS ====\n");
    for c in &report.checks {
        let _ = writeln!(out, "{:<20} {:?}{}", c.name, c.status, golden_detail(&c.detail));
    }
    let _ = writeln!(out, "held vacuously: {}", report.vacuous);
    out.push_str("==== DIAGNOSTICS ====\n");
    for d in &report.diagnostics {
        out.push_str(&render::text(db, &stable(d), false));
    }
    if !report.projections.is_empty() {
        out.push_str("==== PROJECTIONS ====\n");
        for (role, t) in &report.projections {
            let _ = writeln!(out, "{role} = {t}");
        }
    }
    out
}

/// The snapshot's name: the one the former `insta::glob!("../choreographies", "**/*.chor")`
/// of the golden test gave (the test's name, `@`, the path below `choreographies/`), so
/// that the snapshots stay where they are.
const SNAPSHOT: &str = "golden__every_choreography_matches_its_golden_file";

/// Compares `text`, the stable part of `path`'s report, with its golden snapshot.
fn matches_its_golden_file(path: &Path, text: String) {
    let below = path.strip_prefix("choreographies").expect("a file of the corpus");
    let mut settings = insta::Settings::clone_current();
    settings.set_prepend_module_to_snapshot(false);
    settings.set_snapshot_path("snapshots");
    settings.set_input_file(path);
    settings.set_snapshot_suffix(below.to_str().expect("a UTF-8 path"));
    settings.bind(|| insta::assert_snapshot!(SNAPSHOT, text));
}

/// `mochi project` prints local types that parse back to the same type: for a file that
/// projects, each local type is printed, parsed, lowered for its role and compared with
/// the projection. Returns how many were round-tripped, or what failed.
fn printed_projections_parse_back_to_the_same_type(path: &Path) -> Result<usize, Vec<String>> {
    use mochi::hir::print;
    use mochi::syntax::{parse_with_imports, parser::parse_local};
    let mut checked = 0;
    let mut failures = Vec::new();
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, path).expect("readable");
    let (parsed, d) = parse_with_imports(&mut db, root, &mut |p| std::fs::read_to_string(p));
    // The rejected corpus holds syntax errors on purpose; every other file parses.
    if path.starts_with("choreographies/rejected") && !d.is_empty() {
        return Ok(0);
    }
    if !d.is_empty() {
        return Err(vec![format!("{}: {d:?}", path.display())]);
    }
    let (prog, d) = mochi::lower::lower(&parsed);
    if !d.is_empty() {
        return Ok(0);
    }
    // As in the driver, a choreography is projected only when it is well-formed (a
    // rejected file with two branches of one label prints a choice that reads back
    // as a different one).
    let Some(body) = prog.choreography.as_ref().map(|c| c.body.clone()) else { return Ok(0) };
    let ill_formed = !mochi::wf::side::check(&prog, &body).is_empty()
        || !mochi::wf::scope::check(&prog, &body).is_empty()
        || !mochi::wf::sync::check(&prog, &body).is_empty();
    if ill_formed {
        return Ok(0);
    }
    let (locals, d) = mochi::project::project_all(&prog);
    if !d.is_empty() {
        return Ok(0);
    }
    for (role, t) in &locals {
        let text = print::local(&prog, t);
        let who = format!("{}: the printed type of {}", path.display(), prog.role_name(*role));
        let file = db.add("printed", text.clone());
        let (ast, d) = parse_local(file, &text);
        let Some(ast) = ast.filter(|_| d.is_empty()) else {
            failures.push(format!("{who} does not parse: {d:?}\n{text}"));
            continue;
        };
        let (back, d) = mochi::lower::lower_local(&prog, *role, &ast);
        if !d.is_empty() {
            failures.push(format!("{who} does not lower: {d:?}\n{text}"));
        } else if !mochi::project::alpha_equal(&back, t) || print::local(&prog, &back) != text {
            failures.push(format!("{who} reads back differently\n{text}"));
        } else {
            checked += 1;
        }
    }
    if failures.is_empty() {
        Ok(checked)
    } else {
        Err(failures)
    }
}

// ---- counterexamples, checked by their meaning ----------------------------------------

use mochi::exact::{self, Tri, Value};
use mochi::hir::{Program, Var};
use mochi::obligation::Obligation;
use mochi::smt::{goals::Part, replay, Decision};
use std::collections::HashMap;

/// A value as the report prints it (`0.5`, `-3`, `1e-7`, `true`, `(1, 0, 2)`), exactly;
/// `None` for what is not a decimal (an algebraic number Z3 prints as a root).
fn parse_value(text: &str) -> Option<Value> {
    match text {
        "true" => return Some(Value::Bool(Tri::True)),
        "false" => return Some(Value::Bool(Tri::False)),
        _ => {}
    }
    if let Some(inner) = text.strip_prefix('(').and_then(|t| t.strip_suffix(')')) {
        let c: Vec<exact::Num> =
            inner.split(',').map(|c| exact::parse_decimal(c.trim()).map(exact::Num::exact)).collect::<Option<_>>()?;
        return <[exact::Num; 3]>::try_from(c).ok().map(Value::Vec3);
    }
    // A fraction `n/d` is shown where the value is no short decimal; `≈` marks a value that
    // is only approximate (then it is not read: nothing can be checked of it).
    if let Some((n, d)) = text.split_once('/') {
        let (n, d) = (exact::parse_decimal(n)?, exact::parse_decimal(d)?);
        return (!num_traits::Zero::is_zero(&d)).then(|| Value::rat(n / d));
    }
    exact::parse_decimal(text).map(Value::rat)
}

/// The values a report shows, by name, and which value variable each value name means.
struct Model {
    by_name: HashMap<String, Value>,
    /// The value variable each shown value name stands for (`v`, `v#2`).
    values: HashMap<mochi::hir::ValueId, String>,
}

impl Model {
    /// One reading of diagnostic `d`'s counterexample per way its value names can be
    /// bound. A name two values of the query share is told apart by a label on `d`
    /// ("`v#2` in the counterexample is the `v` bound here"). A name that values of the
    /// program share but the query has only one of carries no label: it is one of them,
    /// the report does not say which, so each is tried.
    fn readings(prog: &Program, d: &Diagnostic) -> Vec<Model> {
        let cx = d.counterexample.as_deref().expect("a counterexample");
        let by_name: HashMap<String, Value> =
            cx.values.iter().filter_map(|a| Some((a.name.clone(), parse_value(&a.value)?))).collect();
        let ids = (0..prog.values.len()).map(|i| mochi::hir::ValueId(i as u32));
        let mut values = HashMap::new();
        let mut ambiguous: Vec<Vec<mochi::hir::ValueId>> = Vec::new();
        for id in ids.clone() {
            let v = prog.value(id);
            let labelled = d
                .labels
                .iter()
                .find(|l| l.span == v.span && l.message.ends_with("bound here"))
                .and_then(|l| l.message.strip_prefix('`')?.split('`').next().map(str::to_string));
            if let Some(symbol) = labelled {
                values.insert(id, symbol);
                continue;
            }
            let namesakes: Vec<_> = ids.clone().filter(|o| prog.value(*o).name == v.name).collect();
            let labelled_namesake = namesakes.iter().any(|o| d.labels.iter().any(|l| l.span == prog.value(*o).span));
            if namesakes.len() == 1 {
                values.insert(id, v.name.clone());
            } else if !labelled_namesake && by_name.contains_key(&v.name) && !ambiguous.contains(&namesakes) {
                ambiguous.push(namesakes);
            }
        }
        let mut readings = vec![Model { by_name, values }];
        for group in ambiguous {
            readings = readings
                .into_iter()
                .flat_map(|m| {
                    group.iter().map(move |id| {
                        let mut values = m.values.clone();
                        values.insert(*id, prog.value(*id).name.clone());
                        Model { by_name: m.by_name.clone(), values }
                    })
                })
                .collect();
        }
        readings
    }

    /// The value of a variable of the shared vocabulary (`Cart.x`, `old(Cart.x)`, a
    /// value), named as the report names it.
    fn get(&self, prog: &Program, v: &Var) -> Option<Value> {
        let name = match prog.source_of(v) {
            Var::Role(r, slot) => format!("{}.{}", prog.role_name(r), prog.kind_of(r).var(slot).0),
            Var::Snap(r, slot) => format!("old({}.{})", prog.role_name(r), prog.kind_of(r).var(slot).0),
            Var::Value(id, _) => self.values.get(&id)?.clone(),
            _ => return None,
        };
        self.by_name.get(&name).cloned()
    }

    /// The valuation [`replay::refutes`] reads: the same values, value variables also
    /// under the key the SMT stage gives them by binding site.
    fn valuation(&self) -> replay::Valuation {
        let mut m: replay::Valuation = self.by_name.clone().into_iter().collect();
        for (id, symbol) in &self.values {
            if let Some(v) = self.by_name.get(symbol) {
                m.insert(format!("#value{}", id.idx()), v.clone());
            }
        }
        m
    }
}

/// How a counterexample fared when its obligation was evaluated under it.
#[derive(Debug, PartialEq)]
enum Replay {
    /// No hypothesis false and the part's goal violated, exactly ([`replay::replay`]):
    /// a `Valid` goal false, a precondition or assumption false, a point inside both
    /// footprints, a duration outside another, a refinement item broken.
    Violated,
    /// Not contradicted, but not decided either, with why (a value shown only
    /// approximately, an enclosure that straddles a boundary).
    Undecided(String),
}

/// Evaluates obligation `ob`'s failed `part` under the values diagnostic `d` shows: the
/// best outcome over the readings of its value names (see [`Model::readings`]), with the
/// index of the reading that found the part violated.
fn replay_readings(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    d: &Diagnostic,
) -> (Result<Replay, String>, Option<usize>) {
    let mut outcome: Option<Result<Replay, String>> = None;
    for (k, model) in Model::readings(prog, d).into_iter().enumerate() {
        let this = replay_reading(prog, ob, part, &model);
        match (&outcome, &this) {
            (_, Ok(Replay::Violated)) => return (this, Some(k)),
            (None, _) | (Some(Err(_)), Ok(_)) => outcome = Some(this),
            _ => {}
        }
    }
    (outcome.unwrap_or_else(|| Err("no reading of the counterexample".into())), None)
}

fn replay_reading(prog: &Program, ob: &Obligation, part: &Part, model: &Model) -> Result<Replay, String> {
    // The SMT stage's replay (the one it runs on Z3's exact model), now on the values the
    // user is shown: the part's own goal evaluated, for every kind of part.
    let verdict = replay::replay(prog, ob, part, &model.valuation());
    // A hypothesis that reads none of the values shown is about variables the query left
    // out (it is sliced to what the goal depends on): it does not bear on the
    // counterexample. Every other one must not be false (the replay checks that too).
    let print = |e| mochi::hir::print::expr(prog, None, e);
    let shared = |v: &Var| model.get(prog, v);
    for h in &ob.hyps {
        if exact::holds(prog, h, &shared) == Tri::False {
            return Err(format!("the hypothesis `{}` is false", print(h)));
        }
    }
    match verdict {
        replay::Replay::Falsifies => Ok(Replay::Violated),
        replay::Replay::Refuted(why) => Err(why),
        replay::Replay::Undecided(why) => Ok(Replay::Undecided(why)),
    }
}

/// A geometric contact evaluated exactly: the part's own goal ([`replay::replay`]) under
/// the values shown, with the contact's point (parry's midpoint of its two witness points,
/// read as the shortest decimal of each double) and its time. `None` when the part's query
/// cannot state the bodies (a mesh, a URDF link: parry's replay is the check, in f64).
/// A contact refuted exactly (the point is outside a side, or a hypothesis is false) is an
/// error; undecided (an enclosure of a turned pose straddles a face) is said.
fn exact_contact(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    d: &Diagnostic,
    point: [f64; 3],
) -> Option<Result<Replay, String>> {
    mochi::smt::goals::build(prog, ob, part).ok()?;
    let cx = d.counterexample.as_deref()?;
    let time = cx.overlap.as_ref().and_then(|o| o.times.first().copied());
    let rat = |v: f64| exact::parse_decimal(&format!("{v}")).map(Value::rat);
    let mut outcome = None;
    for mut m in Model::readings(prog, d) {
        for (k, name) in ["point.x", "point.y", "point.z"].iter().enumerate() {
            if let Some(v) = rat(point[k]) {
                m.by_name.entry(name.to_string()).or_insert(v);
            }
        }
        if let Some(v) = time.and_then(rat) {
            m.by_name.entry("time".to_string()).or_insert(v);
        }
        let r = replay_reading(prog, ob, part, &m);
        if matches!(r, Ok(Replay::Violated)) {
            return Some(r);
        }
        outcome.get_or_insert(r);
    }
    outcome
}

/// The kind of a part, for the coverage of the corpus's counterexamples.
fn part_kind(p: &Part) -> String {
    let text = format!("{p:?}");
    text.split(['(', ' ', '{']).next().unwrap_or_default().to_string()
}

/// The note of a counterexample found by the geometric procedure (parry's contact).
const GEOMETRIC: &str = "[found by the geometric procedure";

/// A geometric counterexample placed again ([`mochi::collision::replay_contact`]): each
/// body or footprint at the states and time the diagnostic shows, the point `point` (the
/// one shown, or a corruption of it).
fn replay_geometric(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    cx: &Counterexample,
    point: [f64; 3],
) -> Result<mochi::collision::ContactReplay, String> {
    // A value as shown: `≈v` (the configuration itself), a decimal or a fraction `n/d` of
    // Z3's model with the configuration pinned (each a double, so `n / d` is exact).
    let number = |text: &str| -> Option<f64> {
        let text = text.trim_start_matches('≈');
        match text.split_once('/') {
            Some((n, d)) => Some(n.parse::<f64>().ok()? / d.parse::<f64>().ok()?),
            None => text.parse::<f64>().ok(),
        }
    };
    let times = cx.overlap.as_ref().map(|o| o.times.clone()).unwrap_or_default();
    let value = |name: &str| -> Option<f64> {
        if let Some(a) = cx.values.iter().find(|a| a.name == name) {
            return number(&a.value);
        }
        match name {
            "time" | "time 1" => times.first().copied(),
            "time 2" => times.get(1).copied(),
            _ => None,
        }
    };
    mochi::collision::replay_contact(prog, ob, part, &value, point)
}

/// Every counterexample a report shows, with the obligation and part it refutes.
fn shown_counterexamples(path: &Path, report: &mochi::driver::Report) -> Vec<(Program, Obligation, Part, Diagnostic)> {
    let (geometric, shown): (Vec<Diagnostic>, Vec<Diagnostic>) = report
        .diagnostics
        .iter()
        .filter(|d| d.counterexample.as_deref().is_some_and(|c| !c.values.is_empty() || c.overlap.is_some()))
        .cloned()
        .partition(|d| d.notes.iter().any(|n| n.contains(GEOMETRIC)));
    if shown.is_empty() && geometric.is_empty() {
        return Vec::new();
    }
    let mochi::driver::Planned { program: prog, obligations } =
        report.planned.as_ref().unwrap_or_else(|| panic!("{}: a counterexample, but no obligations", path.display()));
    let mut out = Vec::new();
    // The geometric procedure's contacts: the part is the one at the diagnostic's span whose
    // requirement the note states (deciding again would meet whichever pair the search's
    // time budget reaches first).
    for d in geometric {
        let found = obligations.iter().filter(|ob| ob.span == d.span).find_map(|ob| {
            let mochi::smt::goals::Plan::Parts(parts) = mochi::smt::goals::plan(prog, ob) else { return None };
            parts.into_iter().find_map(|part| {
                let required = format!("required: {} {GEOMETRIC}", mochi::smt::describe_part(prog, ob, &part));
                d.notes.iter().any(|n| n.starts_with(&required)).then(|| (ob.clone(), part))
            })
        });
        let (ob, part) = found
            .unwrap_or_else(|| panic!("{}: no geometric part explains {} ({})", path.display(), d.code, d.message));
        out.push((prog.clone(), ob, part, d));
    }
    if shown.is_empty() {
        return out;
    }
    // The obligations the driver planned (its one wiring), decided again here so that each
    // shown counterexample can be matched to its failed part.
    let labels = vec![String::new(); obligations.len()];
    let results = mochi::smt::discharge(prog, obligations, &labels, &Config::patient().smt);
    for d in shown {
        // The obligation at the diagnostic's span whose failed part the diagnostic names.
        let found = obligations.iter().zip(&results).find_map(|(ob, (decision, _))| match decision {
            Decision::Fails(f) if ob.span == d.span && d.notes.contains(&format!("required: {}", f.part)) => {
                Some((ob.clone(), f.which.clone()?))
            }
            _ => None,
        });
        let (ob, part) = found
            .unwrap_or_else(|| panic!("{}: no failed obligation explains {} ({})", path.display(), d.code, d.message));
        out.push((prog.clone(), ob, part, d));
    }
    out
}

/// Each counterexample a report shows falsifies its obligation: evaluated exactly under
/// the values shown, no hypothesis is false and the goal is not true (the SMT stage's
/// replay, [`replay::refutes`], on the values the user sees rather than on Z3's model);
/// for a `Valid` goal, an [AGCOMP] precondition or two footprints, this test's own
/// evaluation finds the part violated and every hypothesis about the values shown true.
/// The snapshots store no values: this is where they are checked, whatever model the
/// installed Z3 finds.
///
/// It fails when a value is shown wrongly (rounded across a boundary, given to the wrong
/// variable or to the wrong one of two same-named values) or when the encoding and the
/// language disagree. That it can fail is shown for each counterexample decided violated:
/// it is corrupted (each value in turn replaced by a few others) and some corruption must
/// be caught. The counts go to `totals` (at least 20 decided violated over the corpus, at
/// most 4 unreadable).
fn counterexamples_falsify_their_goals(
    path: &Path,
    report: &mochi::driver::Report,
    totals: &Mutex<Totals>,
) -> Vec<String> {
    // `geometric`: counterexamples this test cannot read back (values shown only
    // approximately, an algebraic number or a long fraction); each was replayed exactly
    // before it was shown.
    let (mut violated, mut geometric, mut failures, mut exact_contacts) = (0, 0, Vec::new(), 0);
    let mut decided = Vec::new();
    let mut kinds = std::collections::BTreeSet::new();
    for (prog, ob, part, d) in shown_counterexamples(path, report) {
        // Parry's contact between bodies: placed again at the states and time shown, the
        // sides must touch there and the point must lie on both, at a configuration the
        // contracts allow; the point moved by a metre must be caught.
        if d.notes.iter().any(|n| n.contains(GEOMETRIC)) {
            let cx = d.counterexample.as_deref().expect("a counterexample");
            let Some(point) = cx.overlap.as_ref().map(|o| o.point) else {
                failures.push(format!("{}: {} ({}): a contact without its point", path.display(), d.code, d.message));
                continue;
            };
            // Exactly too, where the part's query can state the bodies (primitive shapes
            // placed by the language's poses): the part's own goal evaluated in rational
            // arithmetic at the values shown, the point and the time (`exact_contact`).
            match exact_contact(&prog, &ob, &part, &d, point) {
                Some(Ok(Replay::Violated)) => exact_contacts += 1,
                Some(Ok(Replay::Undecided(why))) => eprintln!(
                    "{}: {} [{part:?}]: the contact is replayed by parry only (exactly undecided: {why})",
                    path.display(),
                    d.code
                ),
                Some(Err(why)) => failures.push(format!(
                    "{}: {} ({}) [{part:?}]: the contact is refuted in exact arithmetic: {why}",
                    path.display(),
                    d.code,
                    d.message
                )),
                // Meshes, URDF links, a mounted body: parry's replay below is the check.
                None => {}
            }
            match replay_geometric(&prog, &ob, &part, cx, point) {
                Ok(r) if r.falsifies() => {
                    violated += 1;
                    kinds.insert(part_kind(&part));
                    let moved = [point[0] + 1.0, point[1] + 1.0, point[2] + 1.0];
                    if replay_geometric(&prog, &ob, &part, cx, moved).is_ok_and(|r| r.falsifies()) {
                        failures.push(format!(
                            "{}: moving {}'s contact point by a metre is not noticed",
                            path.display(),
                            d.code
                        ));
                    }
                }
                Ok(r) => failures.push(format!(
                    "{}: {} ({}) [{part:?}]: the contact does not replay: {r:?}",
                    path.display(),
                    d.code,
                    d.message
                )),
                Err(why) => failures.push(format!(
                    "{}: {} ({}) [{part:?}]: the contact cannot be replayed: {why}",
                    path.display(),
                    d.code,
                    d.message
                )),
            }
            continue;
        }
        // A value shown only approximately (`≈`, an algebraic number or a long
        // fraction) cannot be read back: the SMT stage replayed Z3's exact model.
        let approximate =
            d.counterexample.as_deref().is_some_and(|c| c.values.iter().any(|a| a.value.starts_with('≈')));
        match replay_readings(&prog, &ob, &part, &d) {
            (Ok(Replay::Undecided(_)), _) if approximate => geometric += 1,
            (Ok(Replay::Violated), Some(reading)) => {
                violated += 1;
                kinds.insert(part_kind(&part));
                decided.push((prog, ob, part, d, reading));
            }
            (Ok(Replay::Violated), None) => unreachable!("a violation comes from a reading"),
            (Ok(Replay::Undecided(why)), _) | (Err(why), _) => {
                failures.push(format!("{}: {} ({}) [{part:?}]: {why}", path.display(), d.code, d.message))
            }
        }
    }
    if !failures.is_empty() {
        failures.insert(0, "counterexamples that do not falsify their goal:".to_string());
    }
    {
        let mut t = totals.lock().unwrap_or_else(|e| e.into_inner());
        t.violated += violated;
        t.geometric += geometric;
        t.exact_contacts += exact_contacts;
        t.kinds.extend(kinds);
    }
    // The check can fail: a corrupted counterexample is caught.
    // The corruption is read as the original was (the same binding of names to values):
    // another reading could bind a changed name to a namesake the goal does not read.
    for (prog, ob, part, d, reading) in &decided {
        // A violation that needs no value (all space is within no bounded footprint, so
        // any run of the concrete primitive falsifies the refinement): nothing to corrupt.
        if replay::replay(prog, ob, part, &Default::default()) == replay::Replay::Falsifies {
            continue;
        }
        let cx = d.counterexample.as_deref().expect("a counterexample");
        let caught = (0..cx.values.len()).any(|i| {
            ["0", "1", "-1", "0.5", "1000", "-1000", "true", "false"].iter().any(|other| {
                let mut c = cx.clone();
                c.values[i].value = other.to_string();
                let bad = Diagnostic { counterexample: Some(Box::new(c)), ..d.clone() };
                let model = Model::readings(prog, &bad).into_iter().nth(*reading).expect("the same readings");
                replay_reading(prog, ob, part, &model).is_err()
            })
        });
        if !caught {
            failures.push(format!(
                "{}: no change of a value of {}'s counterexample is noticed",
                path.display(),
                d.code
            ));
        }
    }
    failures
}

// ---- the rejected corpus ---------------------------------------------------------------

/// The folders of the rejected corpus (each file breaks exactly one rule).
const DIRS: &[&str] =
    &["choreographies/rejected", "choreographies/rejected/geometry", "choreographies/mavlink/rejected"];

/// Rejected variants whose code the geometric procedure does not give in reasonable time
/// yet (they live in `choreographies/pending/` with the examples they vary, which the other
/// harnesses skip): their first line says in prose what they expect, and they join the
/// corpus when it is an `// expect: CODE at ...` line (the test below says when).
/// (None now: the mounted arm's variant joined the corpus as
/// `rejected/geometry/E0404-mounted-arm-orbit-too-small.chor`.)
const PENDING: &[&str] = &[];

/// Whether `path` is a file of the rejected corpus: a `.chor` of one of [`DIRS`] (not
/// [`PENDING`]), or a `.mochi` there whose first line is an `// expect:` line (the other
/// libraries are imported by the `.chor` files).
fn is_rejected(path: &Path) -> bool {
    let in_dir = path.parent().is_some_and(|d| DIRS.iter().any(|dir| d == Path::new(dir)));
    let kind = path.extension().is_some_and(|e| e == "chor")
        || (path.extension().is_some_and(|e| e == "mochi")
            && std::fs::read(path).is_ok_and(|t| t.starts_with(b"// expect: ")));
    in_dir && kind && !PENDING.iter().any(|q| Path::new(q) == path)
}

/// The rejected corpus, sorted.
fn rejected_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in DIRS {
        files.extend(
            std::fs::read_dir(dir)
                .unwrap_or_else(|e| panic!("{dir}: {e}"))
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| is_rejected(p)),
        );
    }
    files.sort();
    files
}

/// Every folder of the corpus is read (a walk that missed one would pass).
fn the_corpus_reads_every_folder() {
    let files = rejected_files();
    assert!(files.len() >= 25, "the corpus has {} files, at least 25 expected", files.len());
    // The geometry folder is read too.
    assert!(
        files.iter().filter(|p| p.starts_with("choreographies/rejected/geometry")).count() >= 7,
        "the URDF and mesh files (choreographies/rejected/geometry/E050*.chor) are in the corpus"
    );
    // The MAVLink variants are read too (each case study's defective variants).
    assert!(
        files.iter().filter(|p| p.starts_with("choreographies/mavlink/rejected")).count() >= 8,
        "the MAVLink variants (choreographies/mavlink/rejected/E*.chor) are in the corpus"
    );
    // The library files are read too (a filter that dropped them all would pass).
    assert!(
        files.iter().filter(|p| p.extension().is_some_and(|e| e == "mochi")).count() >= 2,
        "the rejected libraries (E0409-library-*.mochi, E0412-library-*.mochi) are in the corpus"
    );
    let all = corpus_files();
    assert!(files.iter().all(|f| all.contains(f)), "every rejected file is a test of the corpus");
    assert!(all.iter().any(|p| p.parent().is_some_and(|d| d.ends_with("pgcd"))), "pgcd/ is walked");
}

/// Every golden snapshot belongs to a file of the corpus: a renamed or deleted file
/// leaves none behind.
fn every_snapshot_has_its_file() {
    let names: Vec<String> = chor_files()
        .iter()
        .map(|p| {
            let below = p.strip_prefix("choreographies").expect("under choreographies/");
            let below = below.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("__");
            format!("{SNAPSHOT}@{below}.snap")
        })
        .collect();
    let orphans: Vec<String> = std::fs::read_dir("tests/snapshots")
        .expect("tests/snapshots")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with(SNAPSHOT) && n.ends_with(".snap") && !names.contains(n))
        .collect();
    assert!(orphans.is_empty(), "snapshots without their file (delete them): {orphans:?}");
}

/// Where an expected diagnostic starts: a file (the rejected file itself unless the
/// expectation names another), a line and a column.
struct Expected {
    code: Code,
    file: PathBuf,
    line: usize,
    col: usize,
}

/// Parses `// expect: CODE at LINE:COL` or `// expect: CODE at PATH:LINE:COL` (PATH
/// relative to the repository root).
fn expectation(path: &Path) -> Expected {
    let text = std::fs::read_to_string(path).expect("readable");
    let first = text.lines().next().unwrap_or_default();
    let rest = first.strip_prefix("// expect: ").unwrap_or_else(|| panic!("{}: no `// expect:` line", path.display()));
    let (code, pos) = rest.split_once(" at ").unwrap_or_else(|| panic!("{}: malformed expect line", path.display()));
    let code: Code = code.parse().unwrap_or_else(|_| panic!("{}: unknown code {code}", path.display()));
    let mut parts = pos.trim().rsplitn(3, ':');
    let (c, l, file) = (parts.next(), parts.next(), parts.next());
    let num = |s: Option<&str>, what: &str| -> usize {
        s.and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("{}: `{pos}` is not [PATH:]LINE:COL ({what})", path.display()))
    };
    let file = match file {
        None => path.to_path_buf(),
        Some(f) => {
            assert!(Path::new(f).is_file(), "{}: the expected file `{f}` does not exist", path.display());
            PathBuf::from(f)
        }
    };
    Expected { code, file, line: num(l, "line"), col: num(c, "column") }
}

/// `a/b/../c` as `a/c`: the loader names a URDF by the path the source wrote, joined to
/// the source's folder, so a diagnostic's file name may hold `..`.
fn lexical(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// The rejected file's expectation, read off its one report: rejected, every error with
/// the expected code and a hint, one of them at the expected position.
fn fails_with_exactly_its_code_at_its_position(
    path: &Path,
    db: &SourceDb,
    report: &mochi::driver::Report,
) -> Vec<String> {
    let mut failures = Vec::new();
    let Expected { code, file, line, col } = expectation(path);
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    if !name.starts_with(code.as_str()) {
        failures.push(format!("{name}: file name does not start with {code}"));
    }
    let errors: Vec<_> = report.diagnostics.iter().filter(|d| d.severity == Severity::Error).collect();
    let summary: Vec<String> = errors
        .iter()
        .map(|d| {
            let (f, l, c) = db.location(d.span);
            format!("{} at {f}:{l}:{c}: {}", d.code, d.message)
        })
        .collect();
    for d in &errors {
        if d.help.is_none() {
            failures.push(format!("{name}: {} has no hint: {}", d.code, d.message));
        }
    }
    if report.verdict != Verdict::Rejected {
        failures.push(format!("{name}: verdict {:?}, expected Rejected", report.verdict));
        return failures;
    }
    if errors.iter().any(|d| d.code != code) {
        failures.push(format!("{name}: expected only {code}, got {summary:#?}"));
        return failures;
    }
    let at = errors.iter().any(|d| {
        let (f, l, c) = db.location(d.span);
        l == line && c == col && lexical(Path::new(&f)) == lexical(&file)
    });
    if !at {
        failures.push(format!("{name}: no {code} at {}:{line}:{col}; got {summary:#?}", file.display()));
    }
    failures
}

/// Codes that cannot be the only error of a file, and why. Each is still tested where it
/// can fire (see the named test).
const NOT_ALONE: &[(&str, &str)] = &[
    (
        "E0801",
        "a refusal of `mochi monitor`/`proxy`/`mission`, not of `mochi check`: a protocol that is \
         not verified (every rejected file is one). Tested in tests/monitor.rs::\
         a_protocol_not_verified_is_refused_with_a_code_and_a_position",
    ),
    (
        "E0802",
        "a refusal of the run-time monitor's compilation, not of `mochi check`: a construct a \
         verified protocol may have but the monitor cannot run (no dialect, more than 64 roles). \
         Tested in monitor::tests::a_construct_the_monitor_cannot_run_is_refused_with_e0802_at_it",
    ),
    (
        "E0430",
        "a warning about the environment, not the source: an SMT dump that cannot be written \
         (`--dump-smt`). Tested in tests/cli.rs::a_dump_that_cannot_be_written_is_a_warning_not_a_lost_error",
    ),
    (
        "E0710",
        "[T-SESS] compares first footprints at time 0; every participant moves in the first motion \
         of its scope (total motion), so a collision there is also an [AGCOMP] (E0404) or separation \
         (E0406) failure at time 0. Tested in smt::tests::initially_apart_holds_for_distant_bots_and_fails_for_touching_ones",
    ),
    (
        "E0244",
        "a warning, not an error: a deprecated MAVLink message is checked as written (autopilots \
         still send some). Shown by choreographies/mavlink/mission-download.chor and \
         mission-upload-tolerant.chor (MISSION_REQUEST, MISSION_ITEM; golden snapshots) and \
         tested in lower::mav_tests::deprecated_messages_are_warned_about_once_naming_the_replacement",
    ),
    (
        "E0242",
        "a note, not an error: a program with a dialect and no process is a protocol, verified \
         without typing processes, and says so. Tested in tests/cli.rs::\
         a_mavlink_protocol_without_processes_is_verified_and_says_no_process_was_typed",
    ),
    (
        "E0420",
        "a note, not an error: a library with no robot kind and no motion primitive is verified \
         (names and sorts checked) and says so. Tested in library::tests::\
         a_library_of_constants_verifies_with_a_note_and_chor_files_still_need_a_system",
    ),
    (
        "U0001",
        "a note, not an error: an undecided obligation makes the verdict `unknown`, never \
         `rejected`. Tested in tests/cli.rs a_forced_timeout_gives_unknown_and_exit_3",
    ),
];

/// Each pending file exists and still says in prose what it expects: once its first line
/// is an `// expect: CODE at ...` line, its entry in [`PENDING`] must go.
fn pending_geometry_files_are_still_pending() {
    for p in PENDING {
        let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p}: {e}: drop it from PENDING"));
        let first = text.lines().next().unwrap_or_default();
        let code = first.strip_prefix("// expect: ").and_then(|r| r.split_once(" at ")).map(|(c, _)| c.parse::<Code>());
        assert!(
            !matches!(code, Some(Ok(_))),
            "{p} has an `// expect: CODE at` line now: drop it from PENDING so that the corpus checks it"
        );
    }
}

fn every_code_is_produced_by_a_rejected_example_or_explained() {
    let covered: BTreeSet<Code> = rejected_files().iter().map(|p| expectation(p).code).collect();
    let missing: Vec<&str> = Code::ALL
        .iter()
        .filter(|c| !covered.contains(c) && !c.is_reserved())
        .map(|c| c.as_str())
        .filter(|c| !NOT_ALONE.iter().any(|(n, _)| n == c))
        .collect();
    assert!(
        missing.is_empty(),
        "codes without a file in choreographies/rejected/, an entry in NOT_ALONE or a reserved mark in diag.rs: {missing:?}"
    );
    for (code, why) in NOT_ALONE {
        let c: Code = code.parse().unwrap_or_else(|_| panic!("NOT_ALONE names {code}, which is no code"));
        assert!(!covered.contains(&c), "{code} has a file now: drop it from NOT_ALONE");
        assert!(!c.is_reserved(), "{code} is reserved: drop it from NOT_ALONE");
        assert!(why.len() > 40, "{code}: say why it cannot be alone, and where it is tested");
    }
    // A reserved code is produced by no check, so no file can expect it.
    for c in &covered {
        assert!(!c.is_reserved(), "{c} is marked reserved in diag.rs but a rejected file expects it");
    }
}

// ---- the harness ------------------------------------------------------------------------

/// The corpus: every `.chor` of [`chor_files`] and the rejected libraries, sorted.
fn corpus_files() -> Vec<PathBuf> {
    let mut files = chor_files();
    files.extend(rejected_files().into_iter().filter(|p| p.extension().is_some_and(|e| e == "mochi")));
    files.sort();
    files
}

/// What the per-file tests add up over the whole corpus.
#[derive(Default)]
struct Totals {
    /// Counterexamples decided violated by the exact replay.
    violated: usize,
    /// Counterexamples that cannot be read back (approximate values).
    geometric: usize,
    /// The kinds of part whose counterexamples were decided violated.
    kinds: std::collections::BTreeSet<String>,
    /// Projections printed, parsed back and found equal.
    round_tripped: usize,
    /// SMT-decided rejections whose counterexamples were checked to replay.
    smt_rejected: usize,
    /// Geometric contacts (parry's) also decided violated in exact arithmetic.
    exact_contacts: usize,
}

/// The SMT-decided rejections of `choreographies/rejected/` (E04xx, E070x, E0316) show only
/// counterexamples that replay in exact arithmetic: none is turned into an unknown because
/// its model does not falsify its goal, or is shown unconfirmed. (Their poses turn by
/// multiples of `pi / 2`, where the encoding's enclosures are exact.)
fn smt_counterexamples_replay(path: &Path, report: &mochi::driver::Report, totals: &Mutex<Totals>) -> Vec<String> {
    let name = path.file_name().and_then(|s| s.to_str()).unwrap_or_default();
    let smt_decided = name.starts_with("E04") || name.starts_with("E070") || name.starts_with("E0316");
    if path.parent() != Some(Path::new("choreographies/rejected")) || !smt_decided {
        return Vec::new();
    }
    totals.lock().unwrap_or_else(|e| e.into_inner()).smt_rejected += 1;
    report
        .diagnostics
        .iter()
        .map(|d| format!("{d:?}"))
        .filter(|t| {
            t.contains("does not falsify the goal in exact arithmetic")
                || t.contains("not confirmed as a counterexample")
        })
        .map(|t| format!("{}: a counterexample that does not replay: {t}", path.display()))
        .collect()
}

/// The one test of `path`: checked once, every assertion read off that report.
fn check_one(path: &Path, totals: &Mutex<Totals>) -> Result<(), String> {
    let mut db = SourceDb::new();
    let report =
        check_file(&mut db, path, &Config::patient()).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut failures = Vec::new();
    if is_rejected(path) {
        failures.extend(fails_with_exactly_its_code_at_its_position(path, &db, &report));
    }
    failures.extend(counterexamples_falsify_their_goals(path, &report, totals));
    failures.extend(smt_counterexamples_replay(path, &report, totals));
    if path.extension().is_some_and(|e| e == "chor") {
        match printed_projections_parse_back_to_the_same_type(path) {
            Ok(n) => totals.lock().unwrap_or_else(|e| e.into_inner()).round_tripped += n,
            Err(e) => failures.extend(e),
        }
        // Last: a mismatch panics (insta prints the diff), and the failures above are
        // reported with it.
        let text = dump(&db, &report);
        if let Err(e) = std::panic::catch_unwind(|| matches_its_golden_file(path, text)) {
            let what = e.downcast_ref::<String>().cloned().or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()));
            failures.push(format!("{}: the golden snapshot differs: {}", path.display(), what.unwrap_or_default()));
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(failures.join("\n"))
    }
}

/// The totals over the whole corpus: not vacuous, counterexamples of many kinds of part
/// are decided violated, and projections are round-tripped.
fn check_totals(t: &Totals) -> Result<(), String> {
    eprintln!(
        "{} counterexamples decided violated ({} not readable, {} geometric contacts replayed exactly), of parts {:?}; {} projections round-tripped",
        t.violated, t.geometric, t.exact_contacts, t.kinds, t.round_tripped
    );
    let mut failures = Vec::new();
    if t.violated < 20 {
        failures.push(format!("only {} counterexamples decided violated", t.violated));
    }
    // The corpus has two geometric contacts between primitive shapes (measured: 2).
    if t.exact_contacts < 2 {
        failures.push(format!("only {} geometric contacts replayed in exact arithmetic", t.exact_contacts));
    }
    if t.geometric > 4 {
        failures.push(format!("{} counterexamples cannot be read back", t.geometric));
    }
    if t.smt_rejected < 5 {
        failures.push(format!("only {} SMT-decided rejections had their counterexamples replayed", t.smt_rejected));
    }
    if t.round_tripped < 8 {
        failures.push(format!("only {} projections were round-tripped", t.round_tripped));
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(failures.join("\n"))
    }
}

/// The files whose check takes longest, slowest first: the harness starts them before the
/// others, so that none is left running alone on one core at the end. Measured one process
/// per file (`cargo nextest run --test corpus`, 2 cores at load 16): 61 s, 21 s, 18 s, 16 s
/// and 9 s, against 1.1 s for the average file. Every name must be a file of the corpus.
const SLOWEST_FIRST: &[&str] = &[
    "choreographies/rejected/geometry/E0404-mounted-arm-orbit-too-small.chor",
    "choreographies/mavlink/param-pass.chor",
    "choreographies/mavlink/rejected/E0419-param-pass-index-out-of-range.chor",
    "choreographies/mavlink/rejected/E0410-only-a-real-answer-before-the-timeout.chor",
    "choreographies/rejected/geometry/E0406-sorting-panda-reaches-into-cart-path.chor",
];

/// [`corpus_files`] with the [`SLOWEST_FIRST`] first, the others in their order.
fn in_order_to_run() -> Vec<PathBuf> {
    let mut files = corpus_files();
    for (k, slow) in SLOWEST_FIRST.iter().enumerate() {
        let at = files.iter().position(|p| p == Path::new(slow));
        let at = at.unwrap_or_else(|| panic!("SLOWEST_FIRST names {slow}, which is not a file of the corpus"));
        let p = files.remove(at);
        files.insert(k, p);
    }
    files
}

fn main() {
    let args = Arguments::from_args();
    let totals = Arc::new(Mutex::new(Totals::default()));
    let plain = |name: &str, f: fn()| {
        Trial::test(name, move || {
            f();
            Ok(())
        })
    };
    let mut trials = vec![
        plain("trace_values_are_hidden_and_guards_kept", trace_values_are_hidden_and_guards_kept),
        plain(
            "every_code_is_produced_by_a_rejected_example_or_explained",
            every_code_is_produced_by_a_rejected_example_or_explained,
        ),
        plain("pending_geometry_files_are_still_pending", pending_geometry_files_are_still_pending),
        plain("the_corpus_reads_every_folder", the_corpus_reads_every_folder),
        plain("every_snapshot_has_its_file", every_snapshot_has_its_file),
    ];
    for path in in_order_to_run() {
        let totals = Arc::clone(&totals);
        let name = path.display().to_string();
        trials.push(Trial::test(name, move || check_one(&path, &totals).map_err(Failed::from)));
    }
    let conclusion = libtest_mimic::run(&args, trials);
    // The totals need every file: checked when no filter left one out.
    if !args.list && conclusion.num_filtered_out == 0 && conclusion.num_failed == 0 {
        if let Err(e) = check_totals(&totals.lock().unwrap_or_else(|e| e.into_inner())) {
            eprintln!("the corpus as a whole fails:\n{e}");
            std::process::exit(101);
        }
    }
    conclusion.exit()
}
