//! Tidy: the architecture invariants of ARCHITECTURE.md that can be checked by reading the
//! source, checked here (as rust-analyzer's `tidy` test does):
//!
//! - (a) only files under `checker/verify/src/smt/` name `z3`;
//! - (b) only the IO edge, `checker/cli/main.rs`, `checker/verify/src/fsload.rs`,
//!   `checker/cli/io.rs` and `checker/proxy/main.rs` (the small enforcing executable), touches the file system or the standard streams (`std::fs`,
//!   `File::`, `print!`, `println!`, `eprint!`, `eprintln!`, `stdout()`, `stderr()`,
//!   `stdin()`);
//! - (c) every `.rs` file under `checker/` starts with a `//!` module comment;
//! - (d) only the renderer, `checker/cli/render.rs` and its files `checker/cli/render/`,
//!   knows output formats and colours: it alone names `serde_json`, `termcolor`, `codespan`
//!   and `NO_COLOR`, and writes JSON by hand (`"null"`, `b"null"`, `{\"` in the code); the
//!   one other writer of JSON is the proxy's event lines, `checker/monitor/src/proxy/lines.rs`
//!   (by hand, without serde_json: the small executable `mochi-proxy` has no renderer);
//! - (e) only files under `checker/verify/src/geometry/` name the geometry crates
//!   (`parry3d`, `nalgebra`, `urdf_rs`, `stl_io`, `tobj`, `roxmltree`); `roxmltree` may
//!   also be named under `checker/core/src/dialect/` (the reader of the MAVLink XML
//!   definitions);
//! - (f) the map is true: every path, file, corpus file, module path and link that
//!   ARCHITECTURE.md and `docs/` name exists;
//! - (g) the core is pure: `checker/core/Cargo.toml` depends on no solver, no geometry
//!   crate and no other crate of mochi (Cargo then keeps its code from naming them), and
//!   no file under `checker/core/`, its tests included, touches the file system or names
//!   a crate of the verifier or the command line;
//! - (h) the run-time monitor, `checker/monitor/` (the crate `mochi-monitor`, over the core
//!   alone), names only the modules of the verification core (`hir`, `lower`, `dialect`,
//!   `exact`, `sigma`, `project`, `syntax`, `source`, `diag`) and its own (`mavio`,
//!   `monitor`), never `z3` or `parry3d`: it must run without the solver and the geometry
//!   engine; the small executable `checker/proxy/` names only `mochi_monitor` (never the
//!   library `mochi::`, `mochi_verify`, `z3` or `parry3d`), so it links neither;
//! - (i) the MAVLink readers, `checker/monitor/src/mavio/`, stand alone: they name no other
//!   module of mochi (`crate::` only as `crate::mavio`), no `z3` and no geometry crate, so
//!   the run-time side (the monitor, the proxy) can use them without the verifier.
//!   `checker/monitor/src/mavio/mission.rs` may name `serde_json`: it reads `.plan` files
//!   (an input format; rule (d) is about output).
//! - (j) the modules of `mochi-verify` import each other without cycles: among the
//!   top-level modules and among the files of each folder, every import goes one way
//!   (paths from `crate::`, `super::` and `self::` outside tests and comments).
//!
//! The rules are textual on purpose: simple to state, simple to audit. Rules (a), (b), (d)
//! ignore comments (`//` to the end of a line) and everything from the first line that is
//! `#[cfg(test)]` on its own (the attribute that opens a file's unit-test module, which
//! mochi's files put last): tests may read fixtures and print (outside the core, rule (g)).

use std::path::{Path, PathBuf};

/// The IO edge: the only files that may touch the file system and the standard streams.
const IO_EDGE: &[&str] =
    &["checker/cli/main.rs", "checker/verify/src/fsload.rs", "checker/cli/io.rs", "checker/proxy/main.rs"];

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
/// name;` is test code as a whole, so it is read as empty.
fn code_sources() -> Vec<(String, String)> {
    let mut out = sources();
    let test_only = test_only_files(&out);
    for (f, t) in &mut out {
        if test_only.iter().any(|o| o == f || (o.ends_with('/') && f.starts_with(o.as_str()))) {
            t.clear();
        }
    }
    out
}

/// The files declared by `#[cfg(test)]` on the line before `mod name;` in their parent
/// (`dir/mod.rs`, `dir.rs` or the crate root `dir/lib.rs` declares `dir/name.rs`, or the
/// folder `dir/name/`, given as `dir/name/`, whose files are all test code).
fn test_only_files(files: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (f, t) in files {
        // A crate root (`lib.rs`, `main.rs`) and `mod.rs` declare their siblings.
        let dir = ["/mod.rs", "/lib.rs", "/main.rs"]
            .iter()
            .find_map(|end| f.strip_suffix(end))
            .map(str::to_string)
            .unwrap_or_else(|| f.trim_end_matches(".rs").to_string());
        let lines: Vec<&str> = t.lines().map(str::trim).collect();
        for w in lines.windows(2) {
            if w[0] != "#[cfg(test)]" {
                continue;
            }
            let name = w[1].strip_prefix("pub(crate) ").unwrap_or(w[1]);
            if let Some(name) = name.strip_prefix("mod ").and_then(|n| n.strip_suffix(';')) {
                out.push(format!("{dir}/{name}.rs"));
                out.push(format!("{dir}/{name}/"));
            }
        }
    }
    out
}

/// The lines the rules about code read, numbered from 1, with `//` comments cut: every line
/// but the items under `#[cfg(test)]`. Such an item is the attribute, the attributes and doc
/// comments after it, and the item itself: one line when it ends there (`mod tests;`,
/// `use a::B;`, a body opened and closed on that line), otherwise every line up to the `}`
/// at the attribute's indentation that closes it (as rustfmt writes it). Code after a test
/// module, or after one `#[cfg(test)]` helper near the top of a file, is read.
fn code_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut skip: Option<(String, bool)> = None; // (indentation, inside the item's body)
    text.lines().enumerate().filter_map(move |(i, l)| {
        let in_test = match &mut skip {
            Some((indent, body)) => {
                if *body {
                    if l.strip_prefix(indent.as_str()).is_some_and(|r| r.starts_with('}') && r.len() <= 2) {
                        skip = None;
                    }
                } else if !(l.trim_start().starts_with("#[") || l.trim_start().starts_with("//")) {
                    let opens = l.matches('{').count();
                    if opens > l.matches('}').count() {
                        *body = true;
                    } else {
                        skip = None;
                    }
                }
                true
            }
            None if l.trim() == "#[cfg(test)]" => {
                let indent = l[..l.len() - l.trim_start().len()].to_string();
                skip = Some((indent, false));
                true
            }
            None => false,
        };
        (!in_test).then(|| (i + 1, l.find("//").map_or(l, |at| &l[..at])))
    })
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
        .filter(|(f, _)| !f.starts_with("checker/verify/src/smt/"))
        .flat_map(|(f, t)| hits(f, t, &["z3"]))
        .collect();
    assert!(bad.is_empty(), "only checker/verify/src/smt/ may name z3 (ARCHITECTURE.md):\n{}", bad.join("\n"));
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

/// The geometry engine's folder.
const GEOMETRY: &str = "checker/verify/src/geometry/";

/// Crates of [`GEOMETRY_CRATES`] that one more folder may name: the MAVLink dialect reader
/// reads XML with roxmltree too.
const ALSO_ALLOWED: &[(&str, &str)] = &[("roxmltree", "checker/core/src/dialect/")];

#[test]
fn only_geometry_names_the_geometry_crates() {
    let files = code_sources();
    let bad: Vec<String> = files
        .iter()
        .filter(|(f, _)| !f.starts_with(GEOMETRY))
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
        "only {GEOMETRY} may name parry3d, nalgebra, urdf_rs, stl_io, tobj, roxmltree \
         (and checker/core/src/dialect/ roxmltree) (ARCHITECTURE.md); use the engine's own types and functions:\n{}",
        bad.join("\n")
    );
    // The rule is not vacuous: the engine does name each of them.
    for w in GEOMETRY_CRATES {
        assert!(
            files.iter().any(|(f, t)| f.starts_with(GEOMETRY) && !hits(f, t, &[w]).is_empty()),
            "{GEOMETRY} names no `{w}`: is the rule's word list stale?"
        );
    }
}

/// The crate modules `checker/monitor/` may name (rule (h)): the verification core, the
/// frame type, and itself.
const MONITOR_MAY_NAME: &[&str] =
    &["hir", "lower", "dialect", "exact", "sigma", "project", "syntax", "source", "diag", "mavio", "monitor"];

/// `crate::X` (or `mochi::X`) paths of `line` whose `X` is not in `allowed`.
fn foreign_modules(line: &str, allowed: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for prefix in ["crate::", "mochi::"] {
        for (at, _) in line.match_indices(prefix) {
            if line[..at].chars().next_back().is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let rest = &line[at + prefix.len()..];
            let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !allowed.contains(&name.as_str()) {
                out.push(name);
            }
        }
    }
    out
}

#[test]
fn the_monitor_names_only_the_core() {
    let files = code_sources();
    let monitor: Vec<&(String, String)> = files.iter().filter(|(f, _)| f.starts_with("checker/monitor/")).collect();
    assert!(!monitor.is_empty(), "no checker/monitor/: is the rule stale?");
    let mut bad = Vec::new();
    for (f, t) in &monitor {
        for (n, l) in code_lines(t) {
            for m in foreign_modules(l, MONITOR_MAY_NAME) {
                bad.push(format!("{f}:{n}: names `{m}`: {}", l.trim()));
            }
        }
        bad.extend(hits(f, t, &["z3", "parry3d"]));
    }
    assert!(
        bad.is_empty(),
        "checker/monitor/ may name only the verification core ({}) and never z3 or parry3d:\n{}",
        MONITOR_MAY_NAME.join(", "),
        bad.join("\n")
    );
}

/// Rule (h), the small executable: `checker/proxy/` names the monitor's crate and nothing of
/// the verifier, so `mochi-proxy` links no Z3 and no geometry engine (tests/proxy.rs checks
/// the running process maps no libz3).
#[test]
fn the_small_executable_names_only_the_monitor() {
    let files = code_sources();
    let small: Vec<&(String, String)> = files.iter().filter(|(f, _)| f.starts_with("checker/proxy/")).collect();
    assert!(!small.is_empty(), "no checker/proxy/: is the rule stale?");
    let bad: Vec<String> =
        small.iter().flat_map(|(f, t)| hits(f, t, &["mochi::", "mochi_verify", "z3", "parry3d", "clap"])).collect();
    assert!(bad.is_empty(), "checker/proxy/ may name only mochi_monitor (and std):\n{}", bad.join("\n"));
    assert!(
        small.iter().any(|(f, t)| !hits(f, t, &["mochi_monitor"]).is_empty()),
        "checker/proxy/ names no mochi_monitor"
    );
}

#[test]
fn the_monitor_rule_finds_foreign_modules() {
    assert_eq!(foreign_modules("use crate::smt::goals; crate::hir::Expr", MONITOR_MAY_NAME), ["smt"]);
    assert_eq!(foreign_modules("mochi::driver::program(x)", MONITOR_MAY_NAME), ["driver"]);
    assert!(foreign_modules("use crate::exact::Rat; my_crate::smt", MONITOR_MAY_NAME).is_empty());
}

/// The one writer of JSON outside the renderer (rule (d)): the proxy's event lines.
const JSON_WRITER: &str = "checker/monitor/src/proxy/lines.rs";

/// What writing JSON by hand looks like in the code (rule (d)).
const JSON_BY_HAND: &[&str] = &["\"null\"", "b\"null\"", "{\\\""];

#[test]
fn only_render_knows_formats_and_colours() {
    let words = ["serde_json", "termcolor", "codespan", "NO_COLOR"];
    let files = code_sources();
    let bad: Vec<String> = files
        .iter()
        .filter(|(f, _)| f != "checker/cli/render.rs" && !f.starts_with("checker/cli/render/"))
        .flat_map(|(f, t)| {
            let mut words: Vec<&str> = words
                .iter()
                .copied()
                .filter(|w| !(*w == "serde_json" && f == "checker/monitor/src/mavio/mission.rs"))
                .collect();
            if f != JSON_WRITER {
                words.extend(JSON_BY_HAND);
            }
            hits(f, t, &words)
        })
        .collect();
    assert!(
        bad.is_empty(),
        "only checker/cli/render.rs and checker/cli/render/ build JSON and decide colour (ARCHITECTURE.md), \
         and {JSON_WRITER} the proxy's event lines; return data and let the renderer render it:\n{}",
        bad.join("\n")
    );
    // The exception is not stale: the writer writes JSON by hand.
    let writer = &files.iter().find(|(f, _)| f == JSON_WRITER).expect("the proxy's event writer").1;
    assert!(!hits(JSON_WRITER, writer, JSON_BY_HAND).is_empty(), "{JSON_WRITER} writes no JSON: is the rule stale?");
}

#[test]
fn the_json_rule_finds_json_written_by_hand() {
    let text = "//! m\nfn f(o: &mut Vec<u8>) { o.extend_from_slice(b\"null\"); }\nfn g() -> String { format!(\"{\\\"a\\\":1}\") }\n";
    assert_eq!(hits("x.rs", text, JSON_BY_HAND).len(), 2);
    assert!(hits("x.rs", "let s = \"numbers and null\";\n", JSON_BY_HAND).is_empty());
}

/// The crates no manifest of the core may name (rule (g)): the solver, the geometry engine
/// and its readers, and the other crates of mochi.
const NOT_IN_THE_CORE: &[&str] =
    &["z3", "z3-sys", "parry3d", "parry3d-f64", "nalgebra", "urdf-rs", "stl_io", "tobj", "mochi-verify", "mochi"];

/// What the core's code may not name, its tests included (rule (g)): the file system and
/// the crates of the verifier and the command line.
const NOT_IN_THE_CORE_CODE: &[&str] = &["std::fs", "File::", "mochi_verify", "mochi::"];

#[test]
fn the_core_depends_on_no_solver_no_geometry_and_no_file_system() {
    let manifest = std::fs::read_to_string(root().join("checker/core/Cargo.toml")).expect("read the core's manifest");
    // The dependency tables' keys: `name = ...` or `name.workspace = true` under a
    // `[...dependencies]` header.
    let mut deps = Vec::new();
    let mut in_deps = false;
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            in_deps = line.trim_matches(['[', ']']).ends_with("dependencies");
            continue;
        }
        let key = line.split(['=', '.', ' ']).next().unwrap_or("");
        if in_deps && !key.is_empty() && !key.starts_with('#') {
            deps.push(key.to_string());
        }
    }
    assert!(deps.iter().any(|d| d == "num-rational"), "the core's dependencies were not read: {deps:?}");
    let bad: Vec<&String> = deps.iter().filter(|d| NOT_IN_THE_CORE.contains(&d.as_str())).collect();
    assert!(
        bad.is_empty(),
        "mochi-core may not depend on {bad:?} (ARCHITECTURE.md, the core has no solver and no geometry engine)"
    );
    let files: Vec<(String, String)> = sources().into_iter().filter(|(f, _)| f.starts_with("checker/core/")).collect();
    assert!(files.len() > 20, "found only {} files of the core", files.len());
    let bad: Vec<String> = files
        .iter()
        .flat_map(|(f, t)| {
            t.lines()
                .enumerate()
                .map(|(i, l)| (i + 1, l.find("//").map_or(l, |at| &l[..at])))
                .filter(|(_, l)| NOT_IN_THE_CORE_CODE.iter().any(|w| mentions(l, w)))
                .map(move |(n, l)| format!("{f}:{n}: {}", l.trim()))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "the core reads no file and names no verifier (ARCHITECTURE.md): take text or bytes from \
         the caller, and put tests that need the pipeline in checker/verify/src/pipeline_tests/:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_mavlink_readers_stand_alone() {
    let files = code_sources();
    let mut bad = Vec::new();
    for (f, t) in &files {
        if f.starts_with("checker/monitor/src/mavio/") {
            let mut words = vec!["z3"];
            words.extend(GEOMETRY_CRATES);
            bad.extend(hits(f, t, &words));
            // `crate::mavio::...` is the module itself; any other `crate::` path is not.
            bad.extend(
                hits(f, t, &["crate::"]).into_iter().filter(|h| h.replace("crate::mavio", "").contains("crate::")),
            );
        }
    }
    assert!(
        bad.is_empty(),
        "checker/monitor/src/mavio/ names no other mochi module, no z3 and no geometry crate (tests/tidy.rs, rule (i)):\n{}",
        bad.join("\n")
    );
    // Not vacuous: the rule reads the readers' code (they name the module itself).
    assert!(files
        .iter()
        .any(|(f, t)| f.starts_with("checker/monitor/src/mavio/") && !hits(f, t, &["super::"]).is_empty()));
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
    // Code after a test module, or after a one-line test item, is read; the module is not.
    let after = "#[cfg(test)]\nmod tests {\n    fn g() { std::fs::read(\"\"); }\n}\nfn late() { println!(\"y\"); }\n";
    assert_eq!(hits("x.rs", after, IO_WORDS), ["x.rs:5: fn late() { println!(\"y\"); }"]);
    let helper = "#[cfg(test)]\n/// doc\nuse std::fs;\nfn h() { std::fs::read(\"\"); }\n";
    assert_eq!(hits("x.rs", helper, IO_WORDS), ["x.rs:4: fn h() { std::fs::read(\"\"); }"]);
    assert!(hits("x.rs", "SourceFile::new(); let z3x = 1;\n", IO_WORDS).is_empty());
    assert_eq!(hits("x.rs", "let f = std::fs::File::open(p);\n", IO_WORDS).len(), 1);
    assert_eq!(hits("x.rs", "use z3::ast;\n", &["z3"]).len(), 1);
    assert!(Path::new(&root()).join(IO_EDGE[0]).is_file());
}

// ---- the map is true: ARCHITECTURE.md and docs/ name only what exists -----------------

/// ARCHITECTURE.md and every `docs/*.md`, as (path relative to the root, text), sorted.
fn map_files() -> Vec<(String, String)> {
    let mut out = vec![(
        "ARCHITECTURE.md".to_string(),
        std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("read ARCHITECTURE.md"),
    )];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("list docs/")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    for p in docs {
        let name = format!("docs/{}", p.file_name().expect("a file name").to_string_lossy());
        out.push((name, std::fs::read_to_string(&p).expect("read a doc")));
    }
    assert!(out.len() >= 6, "docs/ has only {} files", out.len() - 1);
    out
}

/// Every file and folder of the repository (not `target/`, not `.git/`), relative to the
/// root with `/` separators; folders end with `/`.
fn repository_paths() -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![root()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("list a folder") {
            let path = entry.expect("a directory entry").path();
            let rel = path.strip_prefix(root()).expect("under the root");
            let rel = rel.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/");
            if path.is_dir() {
                if rel == "target" || rel == ".git" {
                    continue;
                }
                out.push(format!("{rel}/"));
                stack.push(path);
            } else {
                out.push(rel);
            }
        }
    }
    out
}

/// The text of `md` outside fenced code blocks.
fn prose(md: &str) -> String {
    let mut fenced = false;
    let mut out = String::new();
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The `code spans` of `md`'s prose, each within one line.
fn code_spans(md: &str) -> Vec<String> {
    prose(md).lines().flat_map(|l| l.split('`').skip(1).step_by(2).map(str::to_string).collect::<Vec<_>>()).collect()
}

/// GitHub's anchor of a heading: lower case, spaces to `-`, punctuation other than `-` and
/// `_` dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of `md`'s headings.
fn anchors(md: &str) -> Vec<String> {
    prose(md)
        .lines()
        .filter_map(|l| {
            let t = l.trim_start_matches('#');
            (t.len() < l.len() && t.starts_with(' ')).then(|| anchor(t))
        })
        .collect()
}

const PATH_ENDINGS: &[&str] =
    &[".rs", ".chor", ".mochi", ".md", ".toml", ".urdf", ".stl", ".obj", ".xml", ".txt", ".snap", "/"];

/// Whether `segment` occurs in `text` as a whole identifier.
fn names(text: &str, segment: &str) -> bool {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(segment).any(|(at, _)| {
        !text[..at].chars().next_back().is_some_and(ident)
            && !text[at + segment.len()..].chars().next().is_some_and(ident)
    })
}

/// The module files a module path resolves to, and the segments left after the last
/// module (items: functions, types, tests), which must be named in those files. `None`
/// when the first segment is no module of the library (a type's path, `Expr::map`).
fn resolve_module(path: &str, modules: &[(String, PathBuf)]) -> Option<Result<(), String>> {
    let path = ["crate::", "mochi::", "mochi_core::", "mochi_verify::"]
        .iter()
        .find_map(|p| path.strip_prefix(p))
        .unwrap_or(path);
    let path = path.strip_suffix("()").unwrap_or(path);
    let segments: Vec<&str> = path.split("::").collect();
    let (_, mut dir) = modules.iter().find(|(m, _)| m == segments[0])?.clone();
    let mut files: Vec<PathBuf> = Vec::new();
    let mut rest = &segments[..];
    while let Some((first, tail)) = rest.split_first() {
        let (file, folder) = (dir.join(format!("{first}.rs")), dir.join(first));
        if !file.is_file() && !folder.is_dir() {
            break;
        }
        files = if file.is_file() { vec![file] } else { vec![] };
        if folder.is_dir() {
            let mut stack = vec![folder.clone()];
            while let Some(d) = stack.pop() {
                for e in std::fs::read_dir(&d).expect("list a module folder") {
                    let p = e.expect("an entry").path();
                    if p.is_dir() {
                        stack.push(p);
                    } else if p.extension().is_some_and(|x| x == "rs") {
                        files.push(p);
                    }
                }
            }
        }
        dir = folder;
        rest = tail;
    }
    let text: String = files.iter().map(|f| std::fs::read_to_string(f).expect("read a module")).collect();
    match rest.iter().find(|s| !names(&text, s)) {
        None => Some(Ok(())),
        Some(s) => Some(Err(format!("`{path}`: no `{s}` in its module"))),
    }
}

/// What `md` (named `file`) names that does not exist: backticked paths (from the root,
/// or the tail of a path, as `smt/goals/geo/` or `rejected/E0406-tiny-pose-offset.chor`),
/// file names (`scope.rs`), corpus names (`E0316-guards-about-shadowed-value`, `E0408-*`),
/// module paths (`space::enclose`, `wf::scope::refined_tests`), and links to files and
/// headings.
fn stale_names(
    file: &str,
    md: &str,
    repo: &[String],
    docs: &[(String, String)],
    modules: &[(String, PathBuf)],
) -> Vec<String> {
    let mut bad = Vec::new();
    let exists = |p: &str| repo.iter().any(|r| r == p || r.ends_with(&format!("/{p}")));
    for span in code_spans(md) {
        let s = span.trim();
        let skip = s.is_empty()
            || s.contains([' ', '{', '<', '[', '$', '~'])
            || s.contains("...")
            || s.contains("://")
            || s.contains("xxx")
            || s.starts_with(['-', '.', '/']);
        if skip {
            continue;
        }
        let corpus_name = {
            let last = s.rsplit('/').next().unwrap_or(s);
            let b = last.as_bytes();
            b.len() > 6
                && (b[0] == b'E' || b[0] == b'U')
                && b[1..5].iter().all(u8::is_ascii_digit)
                && b[5] == b'-'
                && !last.contains('.')
        };
        if corpus_name {
            let ok = match s.strip_suffix('*') {
                Some(prefix) => repo.iter().any(|r| {
                    (r.starts_with(prefix) || r.contains(&format!("/{prefix}"))) && r.starts_with("choreographies/")
                }),
                None => [".chor", ".mochi"].iter().any(|e| exists(&format!("{s}{e}"))),
            };
            if !ok {
                bad.push(format!("{file}: `{s}` is no file of the corpus"));
            }
        } else if s.contains('*') {
            continue;
        } else if s.contains('/') && PATH_ENDINGS.iter().any(|e| s.ends_with(e)) {
            if !exists(s) {
                bad.push(format!("{file}: `{s}` does not exist"));
            }
        } else if !s.contains('/') && [".rs", ".chor", ".mochi"].iter().any(|e| s.ends_with(e)) {
            if !repo.iter().any(|r| r == s || r.ends_with(&format!("/{s}"))) {
                bad.push(format!("{file}: no file is named `{s}`"));
            }
        } else if s.contains("::")
            && s.trim_end_matches("()")
                .split("::")
                .all(|seg| !seg.is_empty() && seg.chars().all(|c| c.is_alphanumeric() || c == '_'))
        {
            if let Some(Err(e)) = resolve_module(s, modules) {
                bad.push(format!("{file}: {e}"));
            }
        }
    }
    // Links: `](target)` to a file that exists, and to a heading of it when `#anchor` is given.
    let text = prose(md);
    for (at, _) in text.match_indices("](") {
        let Some(end) = text[at + 2..].find(')') else { continue };
        let target = &text[at + 2..at + 2 + end];
        if target.contains("://") || target.starts_with("mailto:") || target.contains(' ') {
            continue;
        }
        let (path, frag) = target.split_once('#').unwrap_or((target, ""));
        let base = Path::new(file).parent().unwrap_or(Path::new(""));
        let joined = if path.is_empty() { PathBuf::from(file) } else { base.join(path) };
        // Normalise `docs/../x` to `x`.
        let mut norm: Vec<String> = Vec::new();
        for c in joined.components() {
            match c {
                std::path::Component::ParentDir => {
                    norm.pop();
                }
                std::path::Component::CurDir => {}
                c => norm.push(c.as_os_str().to_string_lossy().to_string()),
            }
        }
        let norm = norm.join("/");
        if !root().join(&norm).exists() {
            bad.push(format!("{file}: the link `{target}` points at no file"));
            continue;
        }
        if !frag.is_empty() && norm.ends_with(".md") {
            let heads = match docs.iter().find(|(f, _)| *f == norm) {
                _ if path.is_empty() => anchors(md),
                Some((_, t)) => anchors(t),
                None => anchors(&std::fs::read_to_string(root().join(&norm)).expect("read a linked file")),
            };
            if !heads.iter().any(|h| h == frag) {
                bad.push(format!("{file}: the link `{target}` names no heading of {norm}"));
            }
        }
    }
    bad
}

/// The modules of mochi's crates (`pub mod name;` in each crate root), each with the folder
/// of the crate's sources: `mochi::x` names the same module as `mochi_core::x` or
/// `mochi_verify::x`, whichever declares it.
fn library_modules() -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    for dir in ["checker/core/src", "checker/verify/src", "checker/cli"] {
        let lib = std::fs::read_to_string(root().join(dir).join("lib.rs")).expect("read lib.rs");
        out.extend(
            lib.lines()
                .filter_map(|l| l.trim().strip_prefix("pub mod ")?.strip_suffix(';'))
                .map(|m| (m.to_string(), root().join(dir))),
        );
    }
    out
}

/// Every path, file, corpus file, module and link that ARCHITECTURE.md and `docs/` name
/// exists, so the map cannot silently drift from the code.
#[test]
fn the_map_names_only_what_exists() {
    let (repo, docs, modules) = (repository_paths(), map_files(), library_modules());
    let bad: Vec<String> = docs.iter().flat_map(|(f, t)| stale_names(f, t, &repo, &docs, &modules)).collect();
    assert!(bad.is_empty(), "ARCHITECTURE.md and docs/ name what does not exist; fix the text:\n{}", bad.join("\n"));
    // Not vacuous: the map names paths and modules, and they are read.
    let spans: Vec<String> = docs.iter().flat_map(|(_, t)| code_spans(t)).collect();
    assert!(spans.iter().any(|s| s == "checker/verify/src/library.rs") && spans.iter().any(|s| s == "space::enclose"));
}

/// The check itself finds each kind of stale name.
#[test]
fn the_map_check_finds_what_does_not_exist() {
    let (repo, modules) = (repository_paths(), library_modules());
    let md = "# Title\n\nSee `checker/verify/src/smt/nowhere.rs`, `smt/goals/nowhere/`, `typeck.rs`, `space::no_such_module`, \
              `wf::scope::no_such_test`, `E0999-no-such-file`, [a](#no-heading) and [b](docs/none.md).\n\
              These exist: `checker/verify/src/smt/key.rs`, `smt/goals/geo/`, `scope.rs`, `space::enclose`, \
              `E0316-guards-about-shadowed-value`, `E0408-*`, `Expr::map`, [c](#title).\n";
    let bad = stale_names("ARCHITECTURE.md", md, &repo, &[], &modules);
    assert_eq!(bad.len(), 8, "{bad:#?}");
}

// ---- (j) the modules of mochi-verify import each other without cycles -----------------

/// Folders of `checker/verify/src/` whose files still import each other in a cycle. The
/// test fails when a listed folder has none, so the list cannot go stale.
const CYCLES_ALLOWED_FOR_NOW: &[&str] = &["geometry", "simulate"];

/// Top-level cycles still allowed, each by the set of modules on it: the SMT worker hands the
/// questions its encoding cannot represent to `collision`, which asks Z3 for witnesses back
/// through `smt::goals::geo` (to break it, the worker would take the geometric procedure as a
/// callback, or `collision` the witness questions as a trait object). The test fails when a
/// listed cycle is gone.
const ROOT_CYCLES_ALLOWED_FOR_NOW: &[&[&str]] = &[&["collision", "smt"]];

/// The modules on a reported cycle (`(crate root): a → b → a` gives `{a, b}`), when it is a
/// top-level one.
fn root_cycle_modules(text: &str) -> Option<Vec<String>> {
    let ring = text.lines().next()?.strip_prefix("(crate root): ")?;
    let mut m: Vec<String> = ring.split(" → ").map(str::to_string).collect();
    m.sort();
    m.dedup();
    Some(m)
}

fn root_cycle_allowed(text: &str) -> bool {
    root_cycle_modules(text).is_some_and(|m| ROOT_CYCLES_ALLOWED_FOR_NOW.iter().any(|a| a.iter().eq(m.iter())))
}

/// The module path of a source file of a crate whose sources are under `src`
/// (`smt/goals/query.rs` is `smt::goals::query`; `smt/mod.rs` is `smt`; `lib.rs` the root).
fn module_of(src: &str, file: &str) -> Option<Vec<String>> {
    let rel = file.strip_prefix(src)?.strip_prefix('/')?.strip_suffix(".rs")?;
    let mut segs: Vec<String> = rel.split('/').map(str::to_string).collect();
    if matches!(segs.last().map(String::as_str), Some("mod" | "lib")) {
        segs.pop();
    }
    Some(segs)
}

/// The paths a line names from `crate::`, `super::` or `self::`, each as the segments after
/// the root it names, resolved against `module` (`super::query::zero` in `smt::goals::agcomp`
/// is `smt::goals::query::zero`); a group `a::{b, c::d}` gives `a::b` and `a::c::d`.
fn named_paths(module: &[String], line: &str) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    for (at, _) in line.match_indices("::") {
        // Only the first `::` of a path, after `crate`, `super` or `self` read as a whole word.
        let head_start =
            line[..at].rfind(|c: char| !ident(c)).map_or(0, |i| i + line[i..].chars().next().map_or(1, char::len_utf8));
        let head = &line[head_start..at];
        if !matches!(head, "crate" | "super" | "self") || line[..head_start].ends_with("::") {
            continue;
        }
        let mut base: Vec<String> = if head == "crate" { Vec::new() } else { module.to_vec() };
        if head == "super" {
            base.pop();
        }
        let mut rest = &line[at + 2..];
        while let Some(r) = rest.strip_prefix("super::") {
            base.pop();
            rest = r;
        }
        let path_end = rest.find(|c: char| !(ident(c) || c == ':')).unwrap_or(rest.len());
        let mut stem = base.clone();
        stem.extend(rest[..path_end].split("::").filter(|s| !s.is_empty()).map(str::to_string));
        let group = rest[path_end..].starts_with('{') && (path_end == 0 || rest[..path_end].ends_with("::"));
        if group {
            let inner = &rest[path_end + 1..];
            let inner = &inner[..inner.find('}').unwrap_or(inner.len())];
            for item in inner.split(',') {
                let mut p = stem.clone();
                p.extend(item.trim().split("::").filter(|s| !s.is_empty() && s.chars().all(ident)).map(str::to_string));
                out.push(p);
            }
        } else {
            out.push(stem);
        }
    }
    out
}

/// The cycles among the children of each folder of a crate: the edge `a → b` between two
/// children of one folder when a file in `a` (or under it) names `b` or something in it,
/// outside the tests and comments (an import through a parent's glob re-export is not
/// seen). Each cycle as `folder: a → b → ... → a (file:line: text, ...)`.
fn sibling_cycles(src: &str, files: &[(String, String)]) -> Vec<(String, String)> {
    use std::collections::{BTreeMap, BTreeSet};
    let modules: BTreeSet<Vec<String>> = files.iter().filter_map(|(f, _)| module_of(src, f)).collect();
    // (parent, from child, to child) -> the first line that makes the edge.
    let mut edges: BTreeMap<(Vec<String>, String, String), String> = BTreeMap::new();
    for (f, t) in files {
        let Some(m) = module_of(src, f) else { continue };
        for (n, l) in code_lines(t) {
            for p in named_paths(&m, l) {
                // The module the path names: its longest prefix that is a module.
                let Some(target) = (0..=p.len()).rev().map(|k| p[..k].to_vec()).find(|k| modules.contains(k)) else {
                    continue;
                };
                let common = m.iter().zip(&target).take_while(|(a, b)| a == b).count();
                if common < m.len() && common < target.len() {
                    let key = (m[..common].to_vec(), m[common].clone(), target[common].clone());
                    edges.entry(key).or_insert_with(|| format!("{f}:{n}: {}", l.trim()));
                }
            }
        }
    }
    let mut out = Vec::new();
    let parents: BTreeSet<&Vec<String>> = edges.keys().map(|(p, _, _)| p).collect();
    for parent in parents {
        let next = |a: &str| -> Vec<String> {
            edges.keys().filter(|(p, x, _)| p == parent && x == a).map(|(_, _, y)| y.clone()).collect()
        };
        let nodes: BTreeSet<String> = edges.keys().filter(|(p, _, _)| p == parent).map(|(_, x, _)| x.clone()).collect();
        // A depth-first search from each node, in order; the first back edge found is a cycle.
        for start in &nodes {
            let mut path = vec![start.clone()];
            let mut stack = vec![next(start)];
            let mut found = None;
            while let Some(top) = stack.last_mut() {
                let Some(n) = top.pop() else {
                    stack.pop();
                    path.pop();
                    continue;
                };
                if n == *start {
                    found = Some(path.clone());
                    break;
                }
                if !path.contains(&n) && n > *start {
                    path.push(n.clone());
                    stack.push(next(&n));
                }
            }
            if let Some(cycle) = found {
                let mut ring = cycle.clone();
                ring.push(start.clone());
                let why: Vec<&String> =
                    ring.windows(2).map(|w| &edges[&(parent.clone(), w[0].clone(), w[1].clone())]).collect();
                let folder = if parent.is_empty() { "(crate root)".to_string() } else { parent.join("::") };
                let text = format!(
                    "{folder}: {}\n    {}",
                    ring.join(" → "),
                    why.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n    ")
                );
                out.push((parent.join("::"), text));
            }
        }
    }
    out
}

/// The modules of mochi-verify form no import cycle: at the crate's top level (the stages:
/// `wf`, `smt`, `space`, `driver`, ...) and among the files of each folder, an import goes
/// one way. A cycle is broken by moving what both sides need into a module of its own.
#[test]
fn the_verifier_modules_import_each_other_without_cycles() {
    let src = "checker/verify/src";
    let files: Vec<(String, String)> = code_sources().into_iter().filter(|(f, _)| f.starts_with(src)).collect();
    let cycles = sibling_cycles(src, &files);
    let bad: Vec<&String> = cycles
        .iter()
        .filter(|(p, t)| !CYCLES_ALLOWED_FOR_NOW.contains(&p.as_str()) && !root_cycle_allowed(t))
        .map(|(_, t)| t)
        .collect();
    assert!(
        bad.is_empty(),
        "the modules of mochi-verify import each other in a cycle; move what both sides need into a module \
         of its own:\n{}",
        bad.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n")
    );
    let stale: Vec<&&str> = CYCLES_ALLOWED_FOR_NOW.iter().filter(|a| !cycles.iter().any(|(p, _)| p == *a)).collect();
    assert!(stale.is_empty(), "{stale:?} have no cycle any more: remove them from CYCLES_ALLOWED_FOR_NOW");
    let stale_root: Vec<&&[&str]> = ROOT_CYCLES_ALLOWED_FOR_NOW
        .iter()
        .filter(|a| !cycles.iter().any(|(_, t)| root_cycle_modules(t).is_some_and(|m| a.iter().eq(m.iter()))))
        .collect();
    assert!(
        stale_root.is_empty(),
        "{stale_root:?} are no cycle any more: remove them from ROOT_CYCLES_ALLOWED_FOR_NOW"
    );
}

/// The cycle check finds a cycle between two files of a folder and between two top-level
/// modules, sees groups and `super::` paths, and ignores tests and comments.
#[test]
fn the_cycle_check_finds_cycles() {
    let src = "c/src";
    let f = |p: &str, t: &str| (format!("{src}/{p}"), t.to_string());
    let files = vec![
        f("lib.rs", "//! r\npub mod a;\npub mod b;\npub mod d;\n"),
        f("a/mod.rs", "//! a\nmod x;\nmod y;\nuse crate::b::f;\n"),
        f("a/x.rs", "//! x\nuse super::{y::g, z};\n"),
        f("a/y.rs", "//! y\nfn h() { super::super::a::x::k(); }\n"),
        f("b.rs", "//! b\nuse crate::{d, a::x};\n"),
        f("d.rs", "//! d\n// use crate::b;\n#[cfg(test)]\nmod tests { use crate::b; }\n"),
    ];
    let cycles = sibling_cycles(src, &files);
    let folders: Vec<&str> = cycles.iter().map(|(p, _)| p.as_str()).collect();
    assert_eq!(folders, ["", "a"], "{cycles:#?}");
    assert!(cycles[0].1.contains("a → b → a") && cycles[1].1.contains("x → y → x"), "{cycles:#?}");
    // Without `b`'s import of `a`, the top level is acyclic (`d`'s comment and test do not count).
    let mut files = files;
    files[4].1 = "//! b\nuse crate::d;\n".into();
    let cycles = sibling_cycles(src, &files);
    assert_eq!(cycles.iter().map(|(p, _)| p.as_str()).collect::<Vec<_>>(), ["a"], "{cycles:#?}");
}

/// Files of code longer than this hold more than one concept: split them by concept (tests
/// beside them may be in their own file, which does not count).
const MAX_FILE_LINES: usize = 800;

/// Files still over [`MAX_FILE_LINES`], each with its length when listed: they must shrink.
/// The test fails when a listed file is no longer over the limit, so the list cannot go
/// stale.
const LONG_FILES_ALLOWED_FOR_NOW: &[&str] = &[];

/// How many lines of code `text` has: its lines but its unit tests ([`code_lines`]).
fn code_length(text: &str) -> usize {
    code_lines(text).count()
}

/// No file of code is longer than [`MAX_FILE_LINES`] lines (test code aside).
#[test]
fn no_file_of_code_is_over_800_lines() {
    let lengths: Vec<(String, usize)> = code_sources().into_iter().map(|(f, t)| (f, code_length(&t))).collect();
    let long: Vec<String> = lengths
        .iter()
        .filter(|(f, n)| *n > MAX_FILE_LINES && !LONG_FILES_ALLOWED_FOR_NOW.contains(&f.as_str()))
        .map(|(f, n)| format!("{f}: {n} lines"))
        .collect();
    assert!(long.is_empty(), "files of code over {MAX_FILE_LINES} lines; split them by concept:\n{}", long.join("\n"));
    let stale: Vec<&&str> = LONG_FILES_ALLOWED_FOR_NOW
        .iter()
        .filter(|a| !lengths.iter().any(|(f, n)| f == *a && *n > MAX_FILE_LINES))
        .collect();
    assert!(
        stale.is_empty(),
        "{stale:?} are not over {MAX_FILE_LINES} lines any more: remove them from LONG_FILES_ALLOWED_FOR_NOW"
    );
}

/// The length rule counts code only: a file's unit tests and test-only files do not count.
#[test]
fn the_length_rule_counts_code_not_tests() {
    let text = format!("{}#[cfg(test)]\nmod tests {{\n{}}}\n", "fn f() {}\n".repeat(3), "    fn g() {}\n".repeat(900));
    assert_eq!(code_length(&text), 3);
    // Code after the tests counts, and so does code after a one-line test item.
    assert_eq!(code_length(&format!("{text}fn h() {{}}\n#[cfg(test)]\nuse a::B;\nfn k() {{}}\n")), 5);
    assert_eq!(code_length(&"x\n".repeat(801)), 801);
}

/// The top-level modules of mochi-core import each other without a cycle (`exact` uses the
/// float formats of `float`, not of `lower`, which evaluates constants with `exact`).
#[test]
fn the_core_modules_import_each_other_without_cycles() {
    let src = "checker/core/src";
    let files: Vec<(String, String)> = code_sources().into_iter().filter(|(f, _)| f.starts_with(src)).collect();
    let cycles: Vec<String> =
        sibling_cycles(src, &files).into_iter().filter(|(p, _)| p.is_empty()).map(|(_, t)| t).collect();
    assert!(
        cycles.is_empty(),
        "the top-level modules of mochi-core import each other in a cycle; move what both sides need into a \
         module of its own:\n{}",
        cycles.join("\n")
    );
}
