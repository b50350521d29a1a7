//! Tidy: the architecture invariants of ARCHITECTURE.md that can be checked by reading the
//! source, checked here (as rust-analyzer's `tidy` test does):
//!
//! - (a) only files under `checker/smt/` name `z3`;
//! - (b) only the IO edge, `checker/main.rs` and `checker/fsload.rs`, touches the file
//!   system or the standard streams (`std::fs`, `File::`, `print!`, `println!`,
//!   `eprint!`, `eprintln!`, `stdout()`, `stderr()`, `stdin()`);
//! - (c) every `.rs` file under `checker/` starts with a `//!` module comment;
//! - (d) only `checker/render.rs` knows output formats and colours: it alone names
//!   `serde_json`, `termcolor`, `codespan` and `NO_COLOR`;
//! - (e) only files under `checker/geometry/` name the geometry crates (`parry3d`,
//!   `nalgebra`, `urdf_rs`, `stl_io`, `tobj`, `roxmltree`); `roxmltree` may also be named
//!   under `checker/dialect/` (the reader of the MAVLink XML definitions).
//!
//! The rules are textual on purpose: simple to state, simple to audit. Rules (a), (b), (d)
//! ignore comments (`//` to the end of a line) and everything from the first line that is
//! `#[cfg(test)]` on its own (the attribute that opens a file's unit-test module, which
//! mochi's files put last): tests may read fixtures and print.

use std::path::{Path, PathBuf};

/// The IO edge: the only files that may touch the file system and the standard streams.
const IO_EDGE: &[&str] = &["checker/main.rs", "checker/fsload.rs", "checker/io.rs"];

/// Files that still do IO outside the edge, each with the reason and who removes it. The
/// lead removes an entry when the branch that fixes it is merged; the test fails if an
/// entry is no longer needed, so the list cannot go stale.
const IO_ALLOWED_FOR_NOW: &[(&str, &str)] = &[];

/// The words rule (b) looks for.
const IO_WORDS: &[&str] =
    &["std::fs", "File::", "print!", "println!", "eprint!", "eprintln!", "stdout()", "stderr()", "stdin()"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `checker/`, as `checker/...` with `/` separators, sorted.
fn sources() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![root().join("checker")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("list checker/") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(root()).expect("under the root");
                let rel = rel.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/");
                out.push((rel, std::fs::read_to_string(&path).expect("read a source file")));
            }
        }
    }
    out.sort();
    assert!(out.len() > 20, "found only {} files under checker/", out.len());
    out
}

/// [`sources`] for the rules about code: a file its parent declares `#[cfg(test)] mod
/// name;` is test code as a whole, so it is read as if it opened with `#[cfg(test)]`.
fn code_sources() -> Vec<(String, String)> {
    let mut out = sources();
    let test_only = test_only_files(&out);
    for (f, t) in &mut out {
        if test_only.contains(f) {
            *t = "#[cfg(test)]\n".to_string() + t;
        }
    }
    out
}

/// The files declared by `#[cfg(test)]` on the line before `mod name;` in their parent
/// (`dir/mod.rs` or `dir.rs` declares `dir/name.rs`).
fn test_only_files(files: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (f, t) in files {
        let dir =
            f.strip_suffix("/mod.rs").map(str::to_string).unwrap_or_else(|| f.trim_end_matches(".rs").to_string());
        let lines: Vec<&str> = t.lines().map(str::trim).collect();
        for w in lines.windows(2) {
            if w[0] != "#[cfg(test)]" {
                continue;
            }
            let name = w[1].strip_prefix("pub(crate) ").unwrap_or(w[1]);
            if let Some(name) = name.strip_prefix("mod ").and_then(|n| n.strip_suffix(';')) {
                out.push(format!("{dir}/{name}.rs"));
            }
        }
    }
    out
}

/// The lines rules (a) and (b) read: up to the first `#[cfg(test)]` line, comments cut.
fn code_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .take_while(|(_, l)| l.trim() != "#[cfg(test)]")
        .map(|(i, l)| (i + 1, l.find("//").map_or(l, |at| &l[..at])))
}

/// Whether `word` occurs in `line` not as the end of a longer name (`SourceFile::` is not
/// `File::`, `eprintln!` is not `println!`: each is looked for on its own).
fn mentions(line: &str, word: &str) -> bool {
    line.match_indices(word)
        .any(|(at, _)| !line[..at].chars().next_back().is_some_and(|c| c.is_alphanumeric() || c == '_'))
}

/// `file:line: text` of each line of `text` outside the tests that contains a word of `words`.
fn hits(file: &str, text: &str, words: &[&str]) -> Vec<String> {
    code_lines(text)
        .filter(|(_, l)| words.iter().any(|w| mentions(l, w)))
        .map(|(n, l)| format!("{file}:{n}: {}", l.trim()))
        .collect()
}

#[test]
fn only_smt_names_z3() {
    let bad: Vec<String> = code_sources()
        .iter()
        .filter(|(f, _)| !f.starts_with("checker/smt/"))
        .flat_map(|(f, t)| hits(f, t, &["z3"]))
        .collect();
    assert!(bad.is_empty(), "only checker/smt/ may name z3 (ARCHITECTURE.md):\n{}", bad.join("\n"));
}

#[test]
fn only_the_io_edge_does_io() {
    let files = code_sources();
    let allowed = |f: &str| IO_EDGE.contains(&f) || IO_ALLOWED_FOR_NOW.iter().any(|(a, _)| *a == f);
    let bad: Vec<String> = files.iter().filter(|(f, _)| !allowed(f)).flat_map(|(f, t)| hits(f, t, IO_WORDS)).collect();
    assert!(
        bad.is_empty(),
        "only {} touch the file system and the standard streams (ARCHITECTURE.md); \
         pass a loader or a callback instead:\n{}",
        IO_EDGE.join(" and "),
        bad.join("\n")
    );
    for (f, why) in IO_ALLOWED_FOR_NOW {
        let text = &files.iter().find(|(g, _)| g == f).unwrap_or_else(|| panic!("{f} is gone: remove it")).1;
        assert!(!hits(f, text, IO_WORDS).is_empty(), "{f} ({why}) does no IO any more: remove it from the list");
    }
    for f in IO_EDGE {
        assert!(files.iter().any(|(g, _)| g == f), "the IO edge {f} is gone: update IO_EDGE");
    }
}

/// The crates only the geometry engine may name (rule (e)).
const GEOMETRY_CRATES: &[&str] = &["parry3d", "nalgebra", "urdf_rs", "stl_io", "tobj", "roxmltree"];

/// Crates of [`GEOMETRY_CRATES`] that one more folder may name: the MAVLink dialect reader
/// reads XML with roxmltree too.
const ALSO_ALLOWED: &[(&str, &str)] = &[("roxmltree", "checker/dialect/")];

#[test]
fn only_geometry_names_the_geometry_crates() {
    let files = code_sources();
    let bad: Vec<String> = files
        .iter()
        .filter(|(f, _)| !f.starts_with("checker/geometry/"))
        .flat_map(|(f, t)| {
            let words: Vec<&str> = GEOMETRY_CRATES
                .iter()
                .copied()
                .filter(|w| !ALSO_ALLOWED.iter().any(|(a, dir)| a == w && f.starts_with(dir)))
                .collect();
            hits(f, t, &words)
        })
        .collect();
    assert!(
        bad.is_empty(),
        "only checker/geometry/ may name parry3d, nalgebra, urdf_rs, stl_io, tobj, roxmltree \
         (and checker/dialect/ roxmltree) (ARCHITECTURE.md); use the engine's own types and functions:\n{}",
        bad.join("\n")
    );
    // The rule is not vacuous: the engine does name each of them.
    for w in GEOMETRY_CRATES {
        assert!(
            files.iter().any(|(f, t)| f.starts_with("checker/geometry/") && !hits(f, t, &[w]).is_empty()),
            "checker/geometry/ names no `{w}`: is the rule's word list stale?"
        );
    }
}

#[test]
fn only_render_knows_formats_and_colours() {
    let words = ["serde_json", "termcolor", "codespan", "NO_COLOR"];
    let bad: Vec<String> =
        code_sources().iter().filter(|(f, _)| f != "checker/render.rs").flat_map(|(f, t)| hits(f, t, &words)).collect();
    assert!(
        bad.is_empty(),
        "only checker/render.rs builds JSON and decides colour (ARCHITECTURE.md); return data and let it \
         render:\n{}",
        bad.join("\n")
    );
}

#[test]
fn every_file_starts_with_a_module_comment() {
    let bad: Vec<String> = sources().into_iter().filter(|(_, t)| !t.starts_with("//!")).map(|(f, _)| f).collect();
    assert!(bad.is_empty(), "every file under checker/ starts with `//!` saying what it is for:\n{}", bad.join("\n"));
}

/// The rules themselves: a word in a comment or in the tests does not count, one in code does.
#[test]
fn the_rules_read_code_not_comments_or_tests() {
    let text = "//! m\nuse a; // std::fs here is a comment\nfn f() { println!(\"x\"); }\n#[cfg(test)]\nmod tests { fn g() { std::fs::read(\"\"); } }\n";
    assert_eq!(hits("x.rs", text, IO_WORDS), ["x.rs:3: fn f() { println!(\"x\"); }"]);
    assert!(hits("x.rs", "fn f() {}\n", IO_WORDS).is_empty());
    assert!(hits("x.rs", "SourceFile::new(); let z3x = 1;\n", IO_WORDS).is_empty());
    assert_eq!(hits("x.rs", "let f = std::fs::File::open(p);\n", IO_WORDS).len(), 1);
    assert_eq!(hits("x.rs", "use z3::ast;\n", &["z3"]).len(), 1);
    assert!(Path::new(&root()).join(IO_EDGE[0]).is_file());
}
