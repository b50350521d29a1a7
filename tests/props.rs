//! Property tests: no input makes mochi panic. Random token soups and random mutations
//! (deletions, duplications, token insertions) of the bundled choreographies go through
//! every stage of `check_source`; whatever the verdict, it must come back with
//! diagnostics that point inside the loaded files.

use mochi::driver::{check_source, Config, Verdict};
use mochi::source::SourceDb;
use proptest::prelude::*;
use std::path::PathBuf;

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
    "old",
    "sqrt",
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

fn examples() -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for dir in ["choreographies", "choreographies/rejected"] {
        let Ok(entries) = std::fs::read_dir(dir) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.extension().is_some_and(|x| x == "chor") {
                if let Ok(text) = std::fs::read_to_string(&p) {
                    out.push((p, text));
                }
            }
        }
    }
    out.sort();
    out
}

fn check_does_not_panic(name: &str, text: &str) {
    let mut db = SourceDb::new();
    let report = check_source(&mut db, name, text, &Config::default());
    for d in &report.diagnostics {
        let file = db.file(d.span.file);
        assert!(d.span.start <= d.span.end && d.span.end as usize <= file.text.len(), "span out of range: {d:?}");
    }
    if report.verdict == Verdict::Verified {
        assert!(report.diagnostics.iter().all(|d| !d.is_error()));
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize, usize),
    Duplicate(usize, usize),
    Insert(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), 1usize..80).prop_map(|(a, n)| Mutation::Duplicate(a, n)),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(a, t)| Mutation::Insert(a, t)),
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

#[test]
fn the_bundled_examples_are_found() {
    assert!(examples().len() >= 5, "the property tests need the bundled examples");
}
