//! Property tests: no input makes mochi panic. Random token soups and random mutations
//! (deletions, duplications, token insertions) of the bundled choreographies (every
//! `.chor` under `choreographies/`, subfolders included) go through
//! every stage of `check_source`; whatever the verdict, it must come back with
//! diagnostics that point inside the loaded files.
//!
//! The fuzz target is [`fuzz_mutated_corpus_for_a_bounded_time`]: mutations of the
//! corpus (the bundled choreographies and `tests/fuzz-corpus/`) for
//! `MOCHI_FUZZ_SECONDS` seconds (default 3, so `cargo test` in CI runs it every time;
//! set more for a longer hunt). An input that panics is written to
//! `target/fuzz-crashes/`; add it to `tests/fuzz-corpus/` with a comment saying what it
//! broke, and [`the_fuzz_corpus_of_past_crashes_is_handled`] keeps it fixed.

use mochi::driver::Config;
use mochi::fsload::check_source;
use mochi::source::SourceDb;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

const TOKENS: &[&str] = &[
    "robot",
    "motion",
    "system",
    "participant",
    "choreography",
    "process",
    "local",
    "const",
    "import",
    "mu",
    "dt",
    "end",
    "if",
    "then",
    "else",
    "true",
    "false",
    "inf",
    "state",
    "input",
    "pre",
    "post",
    "assume",
    "guarantee",
    "footprint",
    "duration",
    "interruptible",
    "init",
    "at",
    "pose",
    // Bodies, mounts and obstacles (LANGUAGE.md, Robots and Systems).
    "geometry",
    "mount",
    "on",
    "obstacle",
    "box",
    "sphere",
    "cylinder",
    "capsule",
    "urdf",
    "mesh",
    "\"r.urdf\"",
    "old",
    "sqrt",
    "pi",
    "P",
    "Q",
    "R",
    "x",
    "t",
    "a",
    "->",
    "=>",
    "==",
    "<=",
    ">=",
    "&&",
    "||",
    "/\\",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    "<",
    ">",
    ",",
    ";",
    ":",
    ".",
    "+",
    "-",
    "*",
    "/",
    "^",
    "!",
    "?",
    "=",
    "&",
    "0",
    "1.5",
    "\"f.mochi\"",
    "é",
    "→",
    "/*",
    "//",
    "\n",
];

/// Every `.chor` under `choreographies/`, in every folder (`pgcd/`, `rejected/`, ...).
fn examples() -> Vec<(PathBuf, String)> {
    read_chor(&["choreographies"])
}

/// The examples and the corpus of past crashes (some need a large stack: see
/// [`on_big_stack`]).
fn corpus() -> Vec<(PathBuf, String)> {
    read_chor(&["choreographies", "tests/fuzz-corpus"])
}

/// The `.chor` files under `dirs`, recursively, sorted by path.
fn read_chor(dirs: &[&str]) -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries.flatten() {
            let p = e.path();
            // `choreographies/pending/`: minutes per check (tests/corpus.rs).
            if p.is_dir() && p.file_name().is_some_and(|n| n == "pending") {
                continue;
            }
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "chor") {
                if let Ok(text) = std::fs::read_to_string(&p) {
                    out.push((p, text));
                }
            }
        }
    }
    let mut out = Vec::new();
    for dir in dirs {
        walk(Path::new(dir), &mut out);
    }
    out.sort();
    out
}

fn check_does_not_panic(name: &str, text: &str) {
    let mut db = SourceDb::new();
    let report = check_source(&mut db, name, text, &Config::default());
    // Rendering is part of the target: no panic, no raw control character, bounded size.
    let out = mochi::render::diagnostics_text(&db, &report, false);
    assert!(!out.bytes().any(|b| b < 0x20 && b != b'\n' && b != b'\t'), "raw control character in {out:?}");
    assert!(out.len() < 200 * 1024, "{} bytes of diagnostics for {} bytes of input", out.len(), text.len());
    for d in &report.diagnostics {
        let file = db.file(d.span.file);
        assert!(d.span.start <= d.span.end && d.span.end as usize <= file.text.len(), "span out of range: {d:?}");
    }
    // "Verified implies no error" is not asserted here: `driver::Pipeline::finish` computes the
    // verdict from the very same diagnostics, so it could not fail. tests/cli.rs checks it
    // where it can: on what the `mochi` binary prints and the exit code it returns.
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize, usize),
    Duplicate(usize, usize),
    Insert(usize, usize),
    /// Inserts one of [`ODD`].
    Odd(usize, usize),
}

/// Inputs that are not what they seem: a byte-order mark, line ends, control
/// characters, deep nesting and long operator chains.
const ODD: &[&str] =
    &["\u{feff}", "\r", "\r\n", "\0", "\x1b[31m", "\t", "((((((((((", "2 ^ 2 ^ 2 ^ ", "~~~~", "\u{2192}"];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), 1usize..80).prop_map(|(a, n)| Mutation::Duplicate(a, n)),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(a, t)| Mutation::Insert(a, t)),
        (any::<usize>(), 0..ODD.len()).prop_map(|(a, t)| Mutation::Odd(a, t)),
    ]
}

fn boundary(s: &str, i: usize) -> usize {
    let mut i = i % (s.len() + 1);
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, m: &Mutation) -> String {
    match *m {
        Mutation::Delete(a, n) => {
            let a = boundary(text, a);
            let b = boundary(text, a + n);
            let b = b.max(a);
            format!("{}{}", &text[..a], &text[b..])
        }
        Mutation::Duplicate(a, n) => {
            let a = boundary(text, a);
            let b = boundary(text, a + n).max(a);
            format!("{}{}{}", &text[..b], &text[a..b], &text[b..])
        }
        Mutation::Insert(a, t) => {
            let a = boundary(text, a);
            format!("{} {} {}", &text[..a], TOKENS[t], &text[a..])
        }
        Mutation::Odd(a, t) => {
            let a = boundary(text, a);
            format!("{}{}{}", &text[..a], ODD[t], &text[a..])
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn token_soup_never_panics(toks in prop::collection::vec(0..TOKENS.len(), 0..120)) {
        let text: Vec<&str> = toks.iter().map(|&i| TOKENS[i]).collect();
        check_does_not_panic("soup.chor", &text.join(" "));
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        check_does_not_panic("text.chor", &text);
    }

    #[test]
    fn mutated_examples_never_panic(pick in any::<prop::sample::Index>(), muts in prop::collection::vec(mutation(), 1..4)) {
        let ex = examples();
        prop_assume!(!ex.is_empty());
        let (path, text) = &ex[pick.index(ex.len())];
        let mut t = text.clone();
        for m in &muts {
            t = apply(&t, m);
        }
        check_does_not_panic(&path.display().to_string(), &t);
    }
}

/// Runs `f` on a thread with a large stack, as `main` does: later stages recurse once per
/// step of a long sequence.
fn on_big_stack(f: impl FnOnce() + Send + 'static) {
    let worker = std::thread::Builder::new().stack_size(256 << 20).spawn(f).expect("spawn");
    if let Err(panic) = worker.join() {
        std::panic::resume_unwind(panic);
    }
}

#[test]
fn the_fuzz_corpus_of_past_crashes_is_handled() {
    let corpus: Vec<(PathBuf, String)> =
        corpus().into_iter().filter(|(p, _)| p.starts_with("tests/fuzz-corpus")).collect();
    assert!(corpus.len() >= 8, "{} files in tests/fuzz-corpus", corpus.len());
    on_big_stack(move || {
        // How long each takes is measured by `cargo bench --bench pipeline` (the fuzz corpus
        // table, beside a baseline run at the same moment), not asserted here.
        for (path, text) in &corpus {
            check_does_not_panic(&path.display().to_string(), text);
        }
    });
}

/// The fuzz target: random mutations of the corpus for a bounded time (see the module
/// documentation). A panicking input is saved before the test fails.
#[test]
fn fuzz_mutated_corpus_for_a_bounded_time() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::{Config as RunnerConfig, TestRunner};
    let seconds: f64 = std::env::var("MOCHI_FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(3.0);
    on_big_stack(move || {
        let corpus = corpus();
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
        let mut runner = TestRunner::new(RunnerConfig::default());
        let strategy = (any::<prop::sample::Index>(), prop::collection::vec(mutation(), 1..6));
        let mut runs = 0;
        while std::time::Instant::now() < deadline {
            let (pick, muts) = strategy.new_tree(&mut runner).expect("a case").current();
            let (path, text) = &corpus[pick.index(corpus.len())];
            let t = muts.iter().fold(text.clone(), |t: String, m| apply(&t, m));
            let name = path.display().to_string();
            if std::panic::catch_unwind(|| check_does_not_panic(&name, &t)).is_err() {
                let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("../fuzz-crashes");
                let _ = std::fs::create_dir_all(&dir);
                let file = dir.join(format!("crash-{runs}.chor"));
                let _ = std::fs::write(&file, &t);
                panic!("{name} mutated by {muts:?} fails; input saved to {}", file.display());
            }
            runs += 1;
        }
        assert!(runs > 0, "no fuzz case ran in {seconds} s");
    });
}

#[test]
fn the_bundled_examples_are_found() {
    let ex = examples();
    assert!(ex.len() >= 5, "the property tests need the bundled examples");
    // Every folder is read: the subfolders too.
    for sub in ["choreographies/pgcd", "choreographies/rejected"] {
        assert!(ex.iter().any(|(p, _)| p.starts_with(sub)), "nothing read from {sub}");
    }
}

// The URDF reader on hostile input (URDF files and meshes are downloaded): arbitrary
// bytes, and the Moveo arm's URDF (robots/moveo_urdf) mutated by deletions, duplications
// and insertions of XML fragments, go to `geometry::load_robot`. It must return, without a
// panic, either a robot whose link poses are finite (at zero and at random joint values)
// or diagnostics, each with a help and a span inside the URDF's text.

const MOVEO: &str = "robots/moveo_urdf/urdf/moveo_urdf.urdf";

/// Fragments that make XML and URDFs go wrong: markup, nesting, references, numbers that
/// are not finite or not numbers, names that collide.
const XML_BITS: &[&str] = &[
    "<",
    ">",
    "/>",
    "</link>",
    "</joint>",
    "\"",
    "'",
    "=",
    "&amp;",
    "&#0;",
    "&bogus;",
    "<!--",
    "-->",
    "<![CDATA[",
    "]]>",
    "<?xml version=\"1.0\"?>",
    "<!DOCTYPE r [<!ENTITY e \"x\">]>",
    "<a><a><a><a><a><a><a><a>",
    "<link name=\"base_link\"/>",
    "<joint name=\"j\" type=\"fixed\"><parent link=\"base_link\"/><child link=\"base_link\"/></joint>",
    "<mimic joint=\"Joint_1\"/>",
    "1e400",
    "nan",
    "-inf",
    "1e308",
    "-",
    "0",
    " ",
    "\u{feff}",
    "\0",
    "\u{2192}",
    "type=\"floating\"",
    "xyz=\"0 0 0 0\"",
    "scale=\"1e300 1 1\"",
    "filename=\"../../x.stl\"",
    "package://",
];

#[derive(Clone, Debug)]
enum XmlMutation {
    Delete(usize, usize),
    Duplicate(usize, usize),
    Insert(usize, usize),
}

fn xml_mutation() -> impl Strategy<Value = XmlMutation> {
    prop_oneof![
        (any::<usize>(), 1usize..60).prop_map(|(a, n)| XmlMutation::Delete(a, n)),
        (any::<usize>(), 1usize..400).prop_map(|(a, n)| XmlMutation::Duplicate(a, n)),
        (any::<usize>(), 0..XML_BITS.len()).prop_map(|(a, t)| XmlMutation::Insert(a, t)),
    ]
}

fn apply_xml(text: &str, m: &XmlMutation) -> String {
    match *m {
        XmlMutation::Delete(a, n) => apply(text, &Mutation::Delete(a, n)),
        XmlMutation::Duplicate(a, n) => apply(text, &Mutation::Duplicate(a, n)),
        XmlMutation::Insert(a, t) => {
            let a = boundary(text, a);
            format!("{}{}{}", &text[..a], XML_BITS[t], &text[a..])
        }
    }
}

/// Loads `urdf` as if it were the Moveo's URDF file (its meshes are read from disk, once)
/// and checks the property.
fn urdf_loads_or_points_into_the_file(urdf: &[u8], meshes: &mut std::collections::HashMap<PathBuf, Vec<u8>>) {
    use mochi::geometry::load_robot;
    use mochi::source::Span;
    let mut db = SourceDb::new();
    let at = Span::new(db.add("test.chor", "robot"), 0, 5);
    let urdf_path = Path::new(env!("CARGO_MANIFEST_DIR")).join(MOVEO);
    let mut read = |p: &Path| -> std::io::Result<Vec<u8>> {
        if p == urdf_path {
            return Ok(urdf.to_vec());
        }
        if let Some(b) = meshes.get(p) {
            return Ok(b.clone());
        }
        let b = mochi::fsload::read_bytes(p)?;
        meshes.insert(p.to_path_buf(), b.clone());
        Ok(b)
    };
    match load_robot(&mut db, &urdf_path, at, &mut read) {
        Ok(robot) => {
            let n = robot.joint_names().len();
            for q in [vec![0.0; n], (0..n).map(|i| (i as f64 * 0.7).sin()).collect()] {
                for (l, p) in robot.link_poses(&q).iter().enumerate() {
                    let ok = p.translation.vector.iter().chain(p.rotation.coords.iter()).all(|c| c.is_finite());
                    assert!(ok, "link {} has the pose {p:?} at {q:?}", robot.links[l].name);
                }
            }
        }
        Err(ds) => {
            assert!(!ds.is_empty(), "rejected without a diagnostic");
            for d in &ds {
                let file = db.file(d.span.file);
                assert!(file.name.ends_with("moveo_urdf.urdf"), "{d:?} points into {}", file.name);
                assert!(
                    d.span.start <= d.span.end && d.span.end as usize <= file.text.len(),
                    "span out of range: {d:?}"
                );
                assert!(d.help.is_some(), "no help: {d:?}");
                assert!(d.message.len() < 2000, "a message of {} bytes", d.message.len());
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_as_a_urdf_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        urdf_loads_or_points_into_the_file(&bytes, &mut Default::default());
        // The same bytes inside a robot element: the parsers see well-formed prefixes.
        let mut wrapped = b"<robot name=\"r\"><link name=\"a\">".to_vec();
        wrapped.extend(&bytes);
        wrapped.extend(b"</link></robot>");
        urdf_loads_or_points_into_the_file(&wrapped, &mut Default::default());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, ..ProptestConfig::default() })]

    #[test]
    fn mutated_urdfs_load_or_point_into_the_file(muts in prop::collection::vec(xml_mutation(), 1..5)) {
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(MOVEO)).expect("the Moveo URDF");
        let t = muts.iter().fold(text, |t, m| apply_xml(&t, m));
        thread_local!(static MESHES: std::cell::RefCell<std::collections::HashMap<PathBuf, Vec<u8>>> = Default::default());
        MESHES.with(|m| urdf_loads_or_points_into_the_file(t.as_bytes(), &mut m.borrow_mut()));
    }
}

/// The property's own check: the unmutated Moveo loads, and a URDF whose diagnostics
/// would point outside it cannot pass (a rejected file is checked for positions).
#[test]
fn the_moveo_urdf_loads_as_the_property_starts() {
    use mochi::geometry::load_robot;
    use mochi::source::Span;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(MOVEO);
    let mut db = SourceDb::new();
    let at = Span::new(db.add("test.chor", "robot"), 0, 5);
    let robot = load_robot(&mut db, &path, at, &mut mochi::fsload::read_bytes).expect("the Moveo loads");
    assert_eq!(robot.links.len(), 13);
    urdf_loads_or_points_into_the_file(b"<robot name=\"r\"><link name=\"a\"/></robot>", &mut Default::default());
}
