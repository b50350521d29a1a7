//! End-to-end runs of the `mochi` binary: exit codes, text and JSON output.
//!
//! Each test writes its inputs into its own directory under the system temp dir, runs
//! the binary built by cargo and checks what a user or a script would see.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh directory for one test, removed when the test ends (even on failure).
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("mochi-cli-{}-{test}", std::process::id()));
        // A leftover from an earlier run with the same pid would mix in stale files.
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create a temp dir");
        TempDir(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("write a test input");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn mochi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mochi")).args(args).env_remove("NO_COLOR").output().expect("run mochi")
}

fn path_arg(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const SYNTAX_ERROR: &str = "const a = ;\n";

#[test]
fn explain_prints_the_title_and_the_paragraph() {
    let o = mochi(&["explain", "E0301"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.starts_with("E0301: message to oneself\n"), "{out}");
    assert!(out.contains("Def 4.1 requires"), "{out}");
    assert!(out.lines().all(|l| l.chars().count() <= 90), "wrapped at 90 columns: {out}");
}

#[test]
fn explain_rejects_an_unknown_code_as_a_usage_error() {
    let o = mochi(&["explain", "E9999"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stdout(&o).is_empty());
    assert!(stderr(&o).contains("E9999"), "{}", stderr(&o));
}

#[test]
fn explain_list_names_every_code() {
    let o = mochi(&["explain", "--list"]);
    assert_eq!(o.status.code(), Some(0));
    let out = stdout(&o);
    assert!(out.lines().any(|l| l.starts_with("E0103") && l.contains("unexpected token")), "{out}");
    assert!(out.lines().any(|l| l.starts_with("U0001")), "{out}");
}

#[test]
fn a_bad_flag_is_a_usage_error() {
    let o = mochi(&["check", "--no-such-flag", "x.chor"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--no-such-flag"), "{}", stderr(&o));
    assert_eq!(mochi(&["check", "--format", "yaml", "x.chor"]).status.code(), Some(2));
    assert_eq!(mochi(&[]).status.code(), Some(2), "a subcommand is required");
}

#[test]
fn help_and_version_succeed() {
    let help = mochi(&["--help"]);
    assert_eq!(help.status.code(), Some(0));
    assert!(stdout(&help).contains("check"));
    let version = mochi(&["--version"]);
    assert_eq!(version.status.code(), Some(0));
    assert!(stdout(&version).starts_with("mochi "), "{}", stdout(&version));
}

#[test]
fn a_syntax_error_is_reported_in_text() {
    let dir = TempDir::new("syntax-text");
    let file = dir.write("bad.chor", SYNTAX_ERROR);
    let o = mochi(&["check", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(1));
    // rustc's split: diagnostics on stderr, the check table and verdict on stdout.
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(err.contains("error[E0103]"), "{err}");
    assert!(err.contains(&format!("{}:1:11", file.display())), "{err}");
    assert!(err.contains("1 | const a = ;"), "{err}");
    assert!(!out.contains("error["), "{out}");
    assert!(out.contains("verdict: rejected"), "{out}");
    assert!(!out.contains('\x1b') && !err.contains('\x1b'), "no colour when writing to a pipe: {out}");
}

#[test]
fn colour_can_be_forced_on() {
    let dir = TempDir::new("colour");
    let file = dir.write("bad.chor", SYNTAX_ERROR);
    let o = mochi(&["check", "--color", "always", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains('\x1b'), "{}", stdout(&o));
    assert!(stderr(&o).contains('\x1b'), "{}", stderr(&o));
}

#[test]
fn a_syntax_error_is_reported_in_json() {
    let dir = TempDir::new("syntax-json");
    let file = dir.write("bad.chor", SYNTAX_ERROR);
    let o = mochi(&["check", "--format", "json", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&o.stdout).expect("stdout is one JSON document");
    assert_eq!(v["file"], path_arg(&file));
    assert_eq!(v["verdict"], "rejected");
    let d = &v["diagnostics"][0];
    assert_eq!(d["code"], "E0103");
    assert_eq!(d["severity"], "error");
    assert_eq!(d["file"], path_arg(&file));
    assert_eq!(d["line"], 1);
    assert_eq!(d["column"], 11);
    assert!(d["message"].as_str().is_some_and(|m| m.contains("expected")), "{d}");
    assert!(d["notes"].is_array() && d["labels"].is_array(), "{d}");
    assert_eq!(v["checks"][0]["name"], "parse");
    assert_eq!(v["checks"][0]["status"], "fail");
    assert!(v["checks"][0]["millis"].is_number());
}

#[test]
fn a_missing_file_is_invalid_input() {
    let dir = TempDir::new("missing");
    let file = dir.0.join("does-not-exist.chor");
    let o = mochi(&["check", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    let err = stderr(&o);
    assert!(err.starts_with(&format!("error: cannot read {}: ", file.display())), "{err}");
}

#[test]
fn several_files_in_json_give_one_line_each() {
    let dir = TempDir::new("json-lines");
    let first = dir.write("first.chor", SYNTAX_ERROR);
    let second = dir.write("second.chor", "const b = 1;\nconst c = ;\n");
    let o = mochi(&["check", "--format", "json", path_arg(&first), path_arg(&second)]);
    assert_eq!(o.status.code(), Some(1));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3, "one line per file, then the summary: {out}");
    let parsed: Vec<Value> = lines.iter().map(|l| serde_json::from_str(l).expect("each line is JSON")).collect();
    assert_eq!(parsed[0]["file"], path_arg(&first));
    assert_eq!(parsed[1]["file"], path_arg(&second));
    assert_eq!(parsed[1]["diagnostics"][0]["line"], 2);
    assert_eq!(parsed[1]["diagnostics"][0]["column"], 11);
    let summary = &parsed[2]["summary"];
    assert_eq!((summary["files"].as_u64(), summary["rejected"].as_u64()), (Some(2), Some(2)), "{summary}");
    assert!(parsed[2].get("file").is_none(), "the summary is not a file's report: {}", parsed[2]);
}

#[test]
fn an_unreadable_file_among_others_fails_the_run() {
    let dir = TempDir::new("mixed");
    let bad = dir.write("bad.chor", SYNTAX_ERROR);
    let missing = dir.0.join("missing.chor");
    let o = mochi(&["check", "--format", "json", path_arg(&bad), path_arg(&missing)]);
    assert_eq!(o.status.code(), Some(1));
    // Every input yields one JSON object, the unreadable one too (it failed before).
    let lines: Vec<Value> = stdout(&o).lines().map(|l| serde_json::from_str(l).expect("JSON")).collect();
    assert_eq!(lines.len(), 3, "{}", stdout(&o));
    assert_eq!(lines[1]["file"], path_arg(&missing));
    assert_eq!(lines[1]["verdict"], "unreadable");
    assert!(lines[1]["error"].as_str().is_some_and(|e| !e.is_empty()));
    assert_eq!(lines[2]["summary"]["rejected"], 1, "{}", lines[2]);
    assert_eq!(lines[2]["summary"]["unreadable"], 1, "{}", lines[2]);
    assert!(stderr(&o).contains("cannot read"), "{}", stderr(&o));
    let o = mochi(&["check", "--format", "json", path_arg(&missing)]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("one JSON document for one missing file");
    assert_eq!(v["verdict"], "unreadable");
}

#[test]
fn project_explains_why_there_is_no_local_type() {
    let dir = TempDir::new("project");
    let file = dir.write("bad.chor", SYNTAX_ERROR);
    let o = mochi(&["project", path_arg(&file), "--role", "A"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    assert!(stderr(&o).contains("error[E0103]"), "{}", stderr(&o));
}

// ---- the bundled examples, end to end -----------------------------------------------

#[test]
fn the_quick_start_example_is_verified_with_every_check_run() {
    let o = mochi(&["check", "choreographies/cart-and-arms.chor", "--format", "json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified");
    let checks = v["checks"].as_array().expect("checks");
    let status = |name: &str| checks.iter().find(|c| c["name"] == name).map(|c| c["status"].clone());
    for check in [
        "parse",
        "names",
        "well-scoped",
        "synchronisable",
        "projection",
        "typing",
        "compatibility",
        "separation",
        "typing-obligations",
    ] {
        assert_eq!(status(check), Some("pass".into()), "{check}");
    }
    // The compatibility check really asked Z3 (it is not folded away).
    let queries = |name: &str| checks.iter().find(|c| c["name"] == name).and_then(|c| c["queries"].as_u64());
    assert!(queries("compatibility").is_some_and(|n| n > 0), "{v}");
    assert!(v["diagnostics"].as_array().expect("diagnostics").is_empty());
    // Partitions are structured (they were free text): sides with roles, written regions as
    // predicates, boxes as numbers.
    let parts = v["partitions"].as_array().expect("partitions");
    let written = parts.iter().find(|p| p["how"] == "written").expect("the written partition of Fig. 2");
    assert_eq!(written["point"], serde_json::json!(["px", "py", "pz"]));
    assert_eq!(written["sides"][0]["region"], "px >= -0.5", "{written}");
    assert_eq!(written["sides"][1]["roles"], serde_json::json!(["RRobot"]), "{written}");
    for p in parts {
        assert!(p["line"].is_u64() && p["column"].is_u64(), "{p}");
        for side in p["sides"].as_array().expect("sides") {
            assert!(side["roles"].as_array().is_some_and(|r| !r.is_empty()), "{side}");
            let b = &side["box"];
            assert!(
                b.is_null()
                    || b.as_array().is_some_and(|b| b.len() == 3 && b.iter().all(|i| i[0].as_f64() <= i[1].as_f64())),
                "{side}"
            );
        }
    }
}

#[test]
fn example_4_2_is_judged_as_in_the_paper() {
    for (file, code) in [("1", Some("E0310")), ("2", Some("E0312")), ("3", Some("E0312")), ("4", None)] {
        let path = format!("choreographies/example-4-2-{file}.chor");
        let o = mochi(&["check", &path, "--format", "json"]);
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
        match code {
            Some(code) => {
                assert_eq!(o.status.code(), Some(1), "{path}");
                assert_eq!(v["verdict"], "rejected", "{path}");
                assert!(v["diagnostics"].as_array().expect("diags").iter().all(|d| d["code"] == code), "{path}: {v}");
            }
            // Well-formed, and its predicates hold.
            None => assert_eq!(o.status.code(), Some(0), "{path}: {v}"),
        }
    }
}

#[test]
fn project_prints_example_4_9s_local_type_of_the_cart() {
    let o = mochi(&["project", "choreographies/cart-and-arms.chor", "--role", "Cart"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.starts_with("mu t. +{"), "{out}");
    assert!(
        out.contains("GRobot!arrive(") && out.contains("RRobot!free.dt<m_move(g_x)>.GRobot!ready.dt<m_idle>.GRobot?ok")
    );
    let o = mochi(&["project", "choreographies/cart-and-arms.chor", "--role", "Nobody"]);
    assert_eq!(o.status.code(), Some(1));
}

// ---- honesty: what Z3 cannot decide is unknown, never verified ------------------------

/// The undecided diagnostics of a JSON report, with their notes joined.
fn undecided_notes(v: &serde_json::Value) -> Vec<String> {
    v["diagnostics"]
        .as_array()
        .expect("diagnostics")
        .iter()
        .filter(|d| d["code"] == "U0001")
        .map(|d| {
            d["notes"]
                .as_array()
                .map(|n| n.iter().filter_map(|s| s.as_str()).collect::<Vec<_>>().join(" | "))
                .unwrap_or_default()
        })
        .collect()
}

#[test]
fn a_forced_timeout_gives_unknown_and_exit_3() {
    // True by Fermat's last theorem for cubes, far beyond what Z3 proves in 0.3 s.
    let o = mochi(&["check", "tests/data/hard-integer-guard.chor", "--timeout", "0.3", "--format", "json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "unknown");
    let notes = undecided_notes(&v);
    assert!(!notes.is_empty() && notes.iter().all(|n| n.contains("timed out after 300 ms")), "{notes:?}");
    assert!(v["diagnostics"].as_array().expect("diagnostics").iter().all(|d| d["severity"] != "error"), "{v}");
}

#[test]
fn a_query_cut_by_the_deadline_says_so_not_raise_the_timeout() {
    // The same query, with the default --timeout (10 s) but a --deadline of 0.5 s for the
    // run: the file starts at once, its queries get only the time left, and run out.
    let o = mochi(&["check", "tests/data/hard-integer-guard.chor", "--deadline", "0.5", "--format", "json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "unknown");
    let notes = undecided_notes(&v);
    assert!(!notes.is_empty(), "{v}");
    for n in &notes {
        assert!(n.contains("the run's --deadline was reached (the query had only 0."), "{n}");
        assert!(!n.contains("--timeout"), "raising --timeout would not help: {n}");
    }
    let helps: Vec<&str> = v["diagnostics"]
        .as_array()
        .expect("diagnostics")
        .iter()
        .filter(|d| d["code"] == "U0001")
        .filter_map(|d| d["help"].as_str())
        .collect();
    assert!(helps.iter().all(|h| h.contains("later `--deadline`") && !h.contains("--timeout")), "{helps:?}");
}

#[test]
fn a_nonlinear_query_beyond_the_encoding_gives_unknown_and_exit_3() {
    // Valid for the real cosine, but its polynomial enclosure admits a model: Z3 answers
    // sat, mochi sees the model's cosine is not the real one and reports unknown.
    let o = mochi(&["check", "tests/data/trig-beyond-enclosure.chor", "--format", "json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "unknown");
    let notes = undecided_notes(&v);
    assert!(
        !notes.is_empty() && notes.iter().all(|n| n.contains("sin/cos values the real functions do not take")),
        "{notes:?}"
    );
}

#[test]
fn a_mesh_footprint_is_placed_by_the_body_at_the_start_not_read_as_all_space() {
    // [T-SESS] with mesh first footprints: each robot starts in its body (which E0512
    // shows lies within the mesh), so the two pucks 1 m apart start apart.
    let o = mochi(&["check", "tests/data/mesh-footprint-start.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{}", stdout(&o));
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn a_footprint_within_a_mesh_is_not_decided_and_never_passed() {
    // Refinement with an abstract mesh footprint and a concrete 10 m ball: the SMT solver
    // has no predicate for the mesh, so the footprint item is unknown with the reason.
    let o = mochi(&["check", "tests/data/wide-footprint-refines-a-mesh.chor", "--format", "json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "unknown");
    let notes = undecided_notes(&v);
    assert!(notes.len() == 1 && notes[0].contains("URDF or mesh part") && notes[0].contains("`hold`"), "{notes:?}");
}

#[test]
fn dump_smt_writes_one_smt_lib_file_per_query() {
    let dir = TempDir::new("dump");
    let out = dir.0.join("queries");
    let o = mochi(&["check", "choreographies/cart-and-arms.chor", "--dump-smt", path_arg(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let files: Vec<_> = std::fs::read_dir(&out).expect("dump directory").filter_map(|e| e.ok()).collect();
    assert!(files.len() >= 10, "{} files", files.len());
    for f in &files {
        let name = f.file_name().to_string_lossy().into_owned();
        // Named after the obligation's file: the choreography, or for a primitive's
        // contract (E0409), footprint (E0412) or its containing the body (E0512) the
        // library that declares it.
        let library = name.contains("-contract-") || name.contains("-occupies-") || name.contains("-contains-");
        let file = name.contains("cart-and-arms-chor-") || (library && name.contains("-mochi-"));
        assert!(name.ends_with(".smt2") && file, "{name}");
        let text = std::fs::read_to_string(f.path()).expect("readable");
        assert!(text.starts_with("; mochi: ") && text.trim_end().ends_with("(check-sat)"), "{name}: {text}");
    }
    assert!(files.iter().any(|f| f.file_name().to_string_lossy().contains("-agcomp-")), "no [AGCOMP] query dumped");
}

// ---- hardening: option values, special inputs, output size ---------------------------

/// A small verified choreography with `steps` messages in sequence; `lib` is its library.
fn sequence(steps: usize) -> (String, String) {
    // The library is shared from outside the test's directory, as users share theirs.
    let bot = std::fs::canonicalize("motion-primitives/bot.mochi").expect("bot.mochi");
    let lib = format!("import \"{}\";\n", bot.display());
    let chor = format!(
        "import \"lib.mochi\";\nsystem S {{ participant p1: Bot {{ init: s == 0; at: pose(0, 0, 0); }} \
         participant p2: Bot {{ init: s == 0; at: pose(1, 0, 0); }} }}\n\
         choreography C = dt<p1: wave, p2: wave>.\n{}end;\nprocess p1 = dt<wave>.{}end;\nprocess p2 = dt<wave>.{}end;\n",
        "p1 -> p2: l.\n".repeat(steps),
        "p2!l.".repeat(steps),
        "p1?l.".repeat(steps)
    );
    (chor, lib)
}

#[test]
fn bad_option_values_are_usage_errors() {
    // Before: 0, inf, nan and 1e400 exited 1, -1 gave clap's "unexpected argument",
    // --jobs 0 silently meant 1.
    for t in ["0", "inf", "nan", "1e400", "abc", "-1", "-0.5"] {
        let o = mochi(&["check", "--timeout", t, "x.chor"]);
        assert_eq!(o.status.code(), Some(2), "--timeout {t}: {}", stderr(&o));
        assert!(stderr(&o).contains("--timeout"), "{}", stderr(&o));
        assert!(!stderr(&o).contains("unexpected argument"), "{}", stderr(&o));
        assert_eq!(mochi(&["check", "--deadline", t, "x.chor"]).status.code(), Some(2), "--deadline {t}");
    }
    for j in ["0", "-1", "x"] {
        assert_eq!(mochi(&["check", "-j", j, "x.chor"]).status.code(), Some(2), "--jobs {j}");
    }
}

#[test]
fn an_unwritable_dump_directory_is_an_error_before_any_work() {
    let dir = TempDir::new("dump-unwritable");
    let file = dir.write("a-file", "");
    let o = mochi(&["check", "choreographies/example-4-2-1.chor", "--dump-smt", path_arg(&file.join("sub"))]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--dump-smt"), "{}", stderr(&o));
    assert!(stdout(&o).is_empty(), "nothing was checked: {}", stdout(&o));
}

#[cfg(unix)]
#[test]
fn imports_of_devices_and_non_mochi_files_are_refused_quickly() {
    let dir = TempDir::new("devices");
    std::os::unix::fs::symlink("/dev/zero", dir.0.join("zero.mochi")).expect("symlink");
    std::os::unix::fs::symlink("/dev/urandom", dir.0.join("random.chor")).expect("symlink");
    for (import, want) in [
        ("zero.mochi", "a character device, not a regular file"),
        ("random.chor", "a character device"),
        ("/etc/passwd", "not a mochi file"),
        (".", "not a mochi file"),
    ] {
        let file = dir.write("main.chor", &format!("import \"{import}\";\n"));
        // Refused before it is opened: the words are those of the metadata check (a device)
        // and of the extension check, which run before any byte is read, so `/dev/zero` is
        // never read (were it read, the run would not end, or would end with E0107 for its
        // size).
        let o = mochi(&["check", "--format", "json", path_arg(&file)]);
        let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
        let d = &v["diagnostics"][0];
        assert_eq!(d["code"], "E0106", "{import}: {v}");
        assert!(d["message"].as_str().is_some_and(|m| m.contains(want)), "{import}: {d}");
        assert!(!d["message"].as_str().unwrap_or_default().contains("root:"), "no line of /etc/passwd: {d}");
    }
    // The file named on the command line is refused too, not read forever.
    let o = mochi(&["check", path_arg(&dir.0.join("zero.mochi"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("not a regular file"), "{}", stderr(&o));
}

#[test]
fn a_byte_order_mark_cr_line_ends_nul_and_bad_utf8_are_handled() {
    let dir = TempDir::new("encodings");
    let (chor, lib) = sequence(2);
    dir.write("lib.mochi", &lib);
    // BOM: before, E0101 on an invisible character.
    let bom = dir.write("bom.chor", &format!("\u{feff}{chor}"));
    let o = mochi(&["check", path_arg(&bom)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    // CR-only line ends: before, the first comment swallowed the whole file.
    let cr = dir.write("cr.chor", &format!("// a comment\r{}\rconst x = ;\r", chor.replace('\n', "\r")));
    let o = mochi(&["check", "--format", "json", path_arg(&cr)]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let d = &v["diagnostics"][0];
    assert_eq!(d["code"], "E0103", "{v}");
    assert_eq!(d["line"], 1 + chor.lines().count() + 2, "comment, choreography, blank line, const: {d}");
    // NUL: escaped, never written raw.
    let nul = dir.write("nul.chor", "const a = 1;\0\n");
    let o = mochi(&["check", path_arg(&nul)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!o.stderr.contains(&0) && !o.stdout.contains(&0), "{}", stderr(&o));
    assert!(stderr(&o).contains("unexpected character `\\0`"), "{}", stderr(&o));
    // Not UTF-8: before, "stream did not contain valid UTF-8" with no code or position.
    let latin1 = dir.0.join("latin1.chor");
    std::fs::write(&latin1, b"const a = 1;\n// caf\xe9\n").expect("write");
    let o = mochi(&["check", "--format", "json", path_arg(&latin1)]);
    assert_eq!(o.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let d = &v["diagnostics"][0];
    assert_eq!(
        (d["code"].as_str(), d["line"].as_u64(), d["column"].as_u64()),
        (Some("E0107"), Some(2), Some(7)),
        "{d}"
    );
    assert!(d["message"].as_str().is_some_and(|m| m.contains("byte 0xe9 at offset 19")), "{d}");
}

#[test]
fn garbage_gives_a_screenful_not_megabytes() {
    let dir = TempDir::new("garbage");
    // Before: 5,000 errors and 38 MB of output.
    let tilde = dir.write("tilde.chor", &"~ ".repeat(2500));
    let o = mochi(&["check", path_arg(&tilde)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stderr.len() < 20_000, "{} bytes", o.stderr.len());
    assert!(stderr(&o).contains("more diagnostic(s) not shown"), "{}", stderr(&o));
    // Before: a 10^4 chain of `^` escaped the nesting limit and printed 129 MB.
    let pow = dir.write("pow.chor", &format!("const x = {}1;\n", "2 ^ ".repeat(10_000)));
    let o = mochi(&["check", "--format", "json", path_arg(&pow)]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["diagnostics"][0]["code"], "E0108", "{v}");
    let o = mochi(&["check", path_arg(&pow)]);
    assert!(o.stderr.len() < 5_000, "{} bytes: the long line is cut", o.stderr.len());
    // A repeated definition: one screenful however often it repeats.
    let rep = dir.write("rep.chor", &"const a = 1;\n".repeat(20_000));
    let o = mochi(&["check", path_arg(&rep)]);
    assert!(o.stderr.len() < 20_000, "{} bytes", o.stderr.len());
}

#[test]
fn sequences_are_not_nesting_and_constants_come_in_any_order() {
    let dir = TempDir::new("sequence");
    // Before: 1,000 sequential steps hit "nesting deeper than 1000 levels". (100,000 are
    // parsed in syntax::parser's tests and in benches/pipeline.rs: the synchronisability
    // stage, not the parser, is what makes long sequences slow.)
    let (chor, lib) = sequence(1500);
    dir.write("lib.mochi", &lib);
    let file = dir.write(
        "long.chor",
        &chor.replace("system S", "const later: real = early * 2;\nconst early: real = 1;\nsystem S"),
    );
    let o = mochi(&["check", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let o = mochi(&["check", "--format", "json", "choreographies/rejected/E0213-constant-cycle.chor"]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["diagnostics"][0]["code"], "E0213");
    assert!(v["diagnostics"][0]["message"].as_str().is_some_and(|m| m.contains("`reach` -> `margin` -> `reach`")));
}

#[test]
fn directories_stdin_summary_and_deadline() {
    let dir = TempDir::new("inputs");
    let (chor, lib) = sequence(2);
    dir.write("lib.mochi", &lib);
    dir.write("b.chor", &chor);
    std::fs::create_dir_all(dir.0.join("sub")).expect("mkdir");
    std::fs::write(dir.0.join("sub/lib.mochi"), &lib).expect("write");
    std::fs::write(dir.0.join("sub/a.chor"), SYNTAX_ERROR).expect("write");
    dir.write("notes.txt", "not a choreography");
    let o = mochi(&["check", path_arg(&dir.0)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let out = stdout(&o);
    let b = out.find("verdict: verified").expect(&out);
    let a = out.find("verdict: rejected").expect(&out);
    assert!(b < a, "sorted by path: b.chor before sub/a.chor: {out}");
    assert!(out.lines().any(|l| l.starts_with("1 verified, 1 rejected, 0 unknown in ") && l.ends_with(" s")), "{out}");
    // Standard input, imports relative to the current directory.
    let mut child = Command::new(env!("CARGO_BIN_EXE_mochi"))
        .args(["check", "-"])
        .current_dir(&dir.0)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    use std::io::Write;
    child.stdin.take().expect("stdin").write_all(chor.as_bytes()).expect("write stdin");
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout(&o).contains("verdict: verified (<stdin>)"), "{}", stdout(&o));
    // A deadline already past: unknown (exit 3), never verified.
    let o =
        mochi(&["check", "--deadline", "0.000001", path_arg(&dir.0.join("b.chor")), path_arg(&dir.0.join("b.chor"))]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    assert!(stdout(&o).contains("the --deadline of"), "{}", stdout(&o));
    assert!(!stdout(&o).contains("verdict: verified"), "{}", stdout(&o));
}

#[test]
fn project_without_a_role_prints_every_local_type() {
    let o = mochi(&["project", "choreographies/example-4-2-4.chor"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    let roles: Vec<&str> = out.lines().filter_map(|l| l.strip_prefix("local ")).map(|l| &l[..2]).collect();
    assert_eq!(roles, ["p1", "p2", "p3"], "{out}");
    let o = mochi(&["project", "--format", "json", "choreographies/example-4-2-4.chor"]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["locals"].as_array().map(Vec::len), Some(3), "{v}");
}

#[test]
fn explain_list_is_sorted_by_code() {
    let o = mochi(&["explain", "--list"]);
    let codes: Vec<&str> =
        std::str::from_utf8(&o.stdout).expect("utf8").lines().filter_map(|l| l.split(' ').next()).collect();
    let mut sorted = codes.clone();
    sorted.sort();
    assert_eq!(codes, sorted);
    assert!(codes.contains(&"E0108") && codes.contains(&"E0213"));
}

#[test]
fn a_dead_branch_is_a_warning_and_its_vacuous_checks_are_counted() {
    let o = mochi(&["check", "tests/data/dead-branch.chor", "--format", "json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified");
    let diags = v["diagnostics"].as_array().expect("diagnostics");
    assert!(
        diags.iter().any(|d| d["code"] == "E0410" && d["severity"] == "warning" && d["line"] == 13),
        "the dead branch at line 13 is reported: {v}"
    );
    // The [AGCOMP] check of the dead branch's joint motion held only vacuously.
    assert!(v["vacuous"].as_u64().is_some_and(|n| n >= 1), "{v}");
    let text = stdout(&mochi(&["check", "--color", "never", "tests/data/dead-branch.chor"]));
    assert!(text.contains("held only because their context is unsatisfiable"), "{text}");
}

#[test]
fn an_input_is_its_source_state_when_a_motion_starts() {
    // Rejected before (E0402 and E0708): the input at the start was a fresh variable, and
    // the process did not know its source's initial state.
    let o = mochi(&["check", "tests/data/input-precondition.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{v}");
    assert_eq!(v["vacuous"], 0, "{v}");
}

/// The verified twin of `rejected/E0409-postcondition-takes-sqrt-of-a-negative.chor`: a
/// contract predicate with a partial operator that is defined where the motion ends.
#[test]
fn a_postcondition_with_a_defined_square_root_can_end() {
    let o = mochi(&["check", "tests/data/postcondition-takes-sqrt-of-a-positive.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{v}");
}

/// The verified twin of `rejected/E0709-receiver-relates-two-rounds.chor`: a receiver
/// assumes a refinement over a value only others hold, and uses only what that tells it of
/// the current round.
#[test]
fn a_receiver_echoing_the_current_round_is_typed() {
    let o = mochi(&["check", "tests/data/receiver-echoes-the-current-round.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{v}");
}

// ---- the verdict, the diagnostics and the exit code agree ----------------------------

/// Every `.chor` under `dir`, in every folder, sorted.
fn chor_files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).expect("a folder").flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        // `choreographies/pending/` takes minutes per file and says unknown (corpus.rs).
        if p.is_dir() && p.file_name().is_some_and(|n| n == "pending") {
            continue;
        }
        if p.is_dir() {
            out.extend(chor_files_under(&p));
        } else if p.extension().is_some_and(|e| e == "chor") {
            out.push(p);
        }
    }
    out
}

/// `text` with its relative imports made absolute (resolved from `dir`), so that a
/// mutant written elsewhere still reads the libraries of its original.
fn imports_from(dir: &Path, text: &str) -> String {
    text.lines()
        .map(|line| {
            let Some(rest) = line.trim_start().strip_prefix("import \"") else { return line.to_string() };
            let Some((target, tail)) = rest.split_once('"') else { return line.to_string() };
            match std::fs::canonicalize(dir.join(target)) {
                Ok(abs) if !Path::new(target).is_absolute() => format!("import \"{}\"{tail}", abs.display()),
                _ => line.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// How many slices the sweep of [`verdict_diagnostics_and_exit_code_agree_on_every_input`]
/// over the corpus and its mutants is cut into: a run checks the day's slice, so that every
/// file and mutant is run every [`SWEEP_SLICES`] days at a quarter of the time.
const SWEEP_SLICES: u64 = 4;

/// A stable hash (FNV-1a), for slices that are the same every run.
fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// Which slice of the sweep this run checks: `MOCHI_CLI_SLICE=k` (0 to [`SWEEP_SLICES`] - 1),
/// every slice with `MOCHI_CLI_SLICE=all`, otherwise the day's (days since 1970 modulo
/// [`SWEEP_SLICES`], as the mutation and metamorphic sweeps). Printed with how to run it again.
fn sweep_slice() -> Option<u64> {
    let s = match std::env::var("MOCHI_CLI_SLICE").ok().as_deref().map(str::trim) {
        Some("all") => None,
        Some(k) => {
            Some(k.parse::<u64>().unwrap_or_else(|_| panic!("MOCHI_CLI_SLICE={k}: a number or `all`")) % SWEEP_SLICES)
        }
        None => {
            let days =
                std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() / 86_400);
            Some(days % SWEEP_SLICES)
        }
    };
    match s {
        Some(k) => eprintln!(
            "cli sweep: slice {k} of {SWEEP_SLICES} of the corpus and its mutants (MOCHI_CLI_SLICE={k} runs it \
             again, MOCHI_CLI_SLICE=all every file)"
        ),
        None => eprintln!("cli sweep: every file and mutant (MOCHI_CLI_SLICE=all)"),
    }
    s
}

/// Whether the input named `key` is in `slice` (every input when `slice` is `None`).
fn in_sweep_slice(slice: Option<u64>, key: &str) -> bool {
    slice.is_none_or(|k| fnv(key) % SWEEP_SLICES == k)
}

/// "Verified implies no error", checked where it can fail: on what the `mochi` binary
/// prints (`--format json`) and the exit code it returns, for the cases under `tests/data/`,
/// the fuzz corpus of past crashes (every run), and the day's slice ([`sweep_slice`]) of the
/// choreographies under `choreographies/` and of mutants of the bundled examples (one line
/// deleted). For each input, alone:
/// - `verified`: no error diagnostic, every check passed, exit 0;
/// - an error diagnostic: `rejected`, exit 1; `rejected` always comes with an error;
/// - `unknown`: no error, an undecided note (U0001) or an undecided check, exit 3
///   (README, "exit code");
/// - never any other verdict or exit code (2 is a usage error, 101 a crash).
///
/// In-process, this is a restatement of `driver::Pipeline::finish`; through the binary it can
/// fail: `main` maps outcomes to exit codes (`Outcome::exit_code`) and `render::json`
/// writes the verdict and severities, so an unknown run exiting 0, a JSON report that
/// drops or renames a severity, a verdict printed from a different report than the one
/// the exit code came from, or a crash on a mutant each break an assertion here.
/// (Mapping `Outcome::Unknown` to exit 0 in main.rs makes it fail on
/// tests/data/trig-beyond-enclosure.chor and hard-integer-guard.chor: tried.)
#[test]
fn verdict_diagnostics_and_exit_code_agree_on_every_input() {
    let dir = TempDir::new("agree");
    let slice = sweep_slice();
    let mut inputs: Vec<PathBuf> = chor_files_under(Path::new("choreographies"))
        .into_iter()
        .filter(|p| in_sweep_slice(slice, &p.display().to_string()))
        .collect();
    // Every run: the unknown cases (a timeout, a trigonometric query beyond the enclosure)
    // are here, so that each verdict occurs whatever the slice.
    inputs.extend(chor_files_under(Path::new("tests/data")));
    inputs.extend(chor_files_under(Path::new("tests/fuzz-corpus")));
    // Mutants: each example outside rejected/ with one line deleted, at four places.
    let examples: Vec<PathBuf> = chor_files_under(Path::new("choreographies"))
        .into_iter()
        .filter(|p| !p.starts_with("choreographies/rejected"))
        .collect();
    for (i, path) in examples.iter().enumerate() {
        let text = std::fs::read_to_string(path).expect("readable");
        let text = imports_from(path.parent().expect("a folder"), &text);
        let lines: Vec<&str> = text.lines().collect();
        for k in 1..=4 {
            if !in_sweep_slice(slice, &format!("{}:{k}", path.display())) {
                continue;
            }
            let cut = (k * lines.len() / 5 + i) % lines.len().max(1);
            let mutant: Vec<&str> = lines.iter().enumerate().filter(|(j, _)| *j != cut).map(|(_, l)| *l).collect();
            inputs.push(dir.write(&format!("mutant-{i}-{k}.chor"), &mutant.join("\n")));
        }
    }
    // Two workers: each input is one run of the binary.
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(path) = inputs.get(i) else { break };
                // A short per-query limit: tests/data/hard-integer-guard.chor is unknown
                // by timeout, and the property holds whatever the verdict.
                let o = mochi(&["check", "--format", "json", "--timeout", "1", path_arg(path)]);
                results.lock().expect("lock").push((path.clone(), o));
            });
        }
    });
    let mut failures = Vec::new();
    let mut seen = std::collections::BTreeMap::new();
    for (path, o) in results.into_inner().expect("lock") {
        let name = path.display();
        let code = o.status.code();
        let Ok(v) = serde_json::from_slice::<Value>(&o.stdout) else {
            failures.push(format!("{name}: exit {code:?}, stdout is not one JSON document: {}", stderr(&o)));
            continue;
        };
        let verdict = v["verdict"].as_str().unwrap_or("?").to_string();
        let diags = v["diagnostics"].as_array().cloned().unwrap_or_default();
        let errors = diags.iter().filter(|d| d["severity"] == "error").count();
        let undecided = diags.iter().any(|d| d["code"] == "U0001")
            || v["checks"].as_array().is_some_and(|c| c.iter().any(|c| c["status"] == "unknown"));
        let all_pass = v["checks"].as_array().is_some_and(|c| c.iter().all(|c| c["status"] == "pass"));
        let ok = match verdict.as_str() {
            "verified" => errors == 0 && all_pass && code == Some(0),
            "rejected" => errors > 0 && code == Some(1),
            "unknown" => errors == 0 && undecided && code == Some(3),
            _ => false,
        };
        if !ok {
            failures.push(format!("{name}: verdict {verdict}, {errors} error(s), exit {code:?}"));
        }
        *seen.entry(verdict).or_insert(0) += 1;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Every verdict occurs, so that no branch above holds vacuously.
    for verdict in ["verified", "rejected", "unknown"] {
        assert!(seen.get(verdict).is_some_and(|n| *n > 0), "no input was {verdict}: {seen:?}");
    }
}

/// rustc's split, for every subcommand: results on stdout, diagnostics and errors on
/// stderr, so `2>/dev/null` keeps exactly the results and `>/dev/null` exactly the
/// problems (README, "Output streams").
#[test]
fn every_subcommand_writes_results_to_stdout_and_problems_to_stderr() {
    let dir = TempDir::new("streams");
    let bad = dir.write("bad.chor", SYNTAX_ERROR);
    let bad = path_arg(&bad);
    let missing = dir.0.join("missing.chor");
    let missing = path_arg(&missing);
    let good = "choreographies/example-4-2-4.chor";
    // (arguments, exit code, what stdout holds, what stderr holds); `None`: nothing at all.
    type Case<'a> = (&'a [&'a str], i32, Option<&'a str>, Option<&'a str>);
    let cases: &[Case] = &[
        (&["check", good], 0, Some("verdict: verified"), None),
        (&["check", bad], 1, Some("verdict: rejected"), Some("error[E0103]")),
        (&["check", "--format", "json", bad], 1, Some("\"verdict\": \"rejected\""), None),
        (&["check", missing], 1, None, Some("error: cannot read")),
        (
            &["check", good, missing],
            1,
            Some("1 verified, 0 rejected, 0 unknown, 1 unreadable in "),
            Some("error: cannot read"),
        ),
        (&["check", "--format", "json", good, bad], 1, Some("{\"summary\":"), None),
        (&["project", "--role", "p1", good], 0, Some("mu t. dt<open>"), None),
        (&["project", "--format", "json", good], 0, Some("\"locals\""), None),
        (&["project", bad], 1, None, Some("error[E0103]")),
        (&["project", "--role", "nobody", good], 1, None, Some("error: no participant named `nobody`")),
        (&["project", missing], 1, None, Some("error: cannot read")),
        (&["explain", "E0301"], 0, Some("E0301: message to oneself"), None),
        (&["explain", "--list"], 0, Some("E0301  message to oneself"), None),
        (&["explain", "E9999"], 2, None, Some("error: unknown code `E9999`")),
        (&["simulate", "--runs", "1", "--steps", "4", good], 0, Some("no collision, no stuck state"), None),
        (&["simulate", "--runs", "1", "--steps", "4", "--format", "json", good], 0, Some("\"findings\": []"), None),
        (&["simulate", bad], 1, None, Some("error[E0103]")),
        (&["simulate", missing], 1, None, Some("error: cannot read")),
    ];
    for (args, code, out, err) in cases {
        let o = mochi(args);
        let (so, se) = (stdout(&o), stderr(&o));
        assert_eq!(o.status.code(), Some(*code), "{args:?}\nstdout: {so}\nstderr: {se}");
        match out {
            Some(want) => assert!(so.contains(want), "{args:?}: stdout lacks {want:?}:\n{so}"),
            None => assert!(so.is_empty(), "{args:?}: a result on stdout where there is none:\n{so}"),
        }
        match err {
            Some(want) => assert!(se.contains(want), "{args:?}: stderr lacks {want:?}:\n{se}"),
            None => assert!(se.is_empty(), "{args:?}: stderr should be empty:\n{se}"),
        }
        // Diagnostics never reach stdout, results never reach stderr.
        assert!(!so.contains("error[") && !so.contains("error:"), "{args:?}: a problem on stdout:\n{so}");
        assert!(!se.contains("verdict:") && !se.contains("\"verdict\""), "{args:?}: a result on stderr:\n{se}");
    }
}

// ---- the SMT stage's sinks and hard limit --------------------------------------------

/// A dump that cannot be written is reported (E0430, a warning at the obligation whose
/// query it was) instead of being dropped; the verdict stands and nothing more is dumped.
#[test]
fn a_dump_that_cannot_be_written_is_a_warning_not_a_lost_error() {
    let dir = TempDir::new("dump-fails");
    let first = dir.0.join("first");
    let args = |out: &Path| {
        let out = path_arg(out).to_string();
        let o = Command::new(env!("CARGO_BIN_EXE_mochi"))
            .args(["check", "choreographies/pgcd/fetch.chor", "--jobs", "1", "--format", "json", "--dump-smt", &out])
            .output()
            .expect("run mochi");
        o
    };
    let o = args(&first);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    // With one worker the queries are numbered in a fixed order: block the first one's
    // file with a directory of its name, in a fresh dump directory.
    let mut names: Vec<String> = std::fs::read_dir(&first)
        .expect("dump directory")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let blocked = dir.0.join("blocked");
    std::fs::create_dir_all(blocked.join(&names[0])).expect("block the first dump");
    let o = args(&blocked);
    assert_eq!(o.status.code(), Some(0), "the verdict stands: {}", stdout(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified");
    let warnings: Vec<&Value> =
        v["diagnostics"].as_array().expect("diagnostics").iter().filter(|d| d["code"] == "E0430").collect();
    assert_eq!(warnings.len(), 1, "{v}");
    assert_eq!(warnings[0]["severity"], "warning");
    let text = warnings[0].to_string();
    assert!(text.contains(&names[0]) && text.contains("--dump-smt"), "{text}");
    // Nothing after the failure.
    let left = std::fs::read_dir(&blocked).expect("dump directory").count();
    assert_eq!(left, 1, "only the blocking directory");
}

/// `mochi project` of a library says what a library is and what to run instead.
#[test]
fn projecting_a_library_says_it_is_one() {
    let o = mochi(&["project", "motion-primitives/bot.mochi"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("is a library") && e.contains("mochi check"), "{e}");
}

// ---- clearance -----------------------------------------------------------------------

/// `--clearance` lists the least distance between the cart and the bridge it passes under:
/// the deck is 3 cm above the cart's top (bridge.chor's header), so the certified lower
/// bound lies within the tolerance (1 mm) below 0.03 and the attained distance at 0.03.
#[test]
fn clearance_lists_the_least_distance_of_each_pair() {
    // A patient limit (as the golden suite's, `Config::patient`): in a debug build on a
    // loaded machine the search may otherwise stop on the clock before its bounds meet.
    let o = mochi(&["check", "--timeout", "60", "--clearance", "choreographies/bridge.chor"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let out = stdout(&o);
    let line = out.lines().find(|l| l.trim_start().starts_with("Cart - Bridge: at least ")).expect(&out);
    let num = |after: &str| -> f64 {
        let rest = &line[line.find(after).expect(line) + after.len()..];
        rest.split([',', ' ']).next().unwrap().parse().expect(line)
    };
    let (lower, upper) = (num("at least "), num(", "));
    assert!((0.029..=0.030).contains(&lower), "{line}");
    assert!((lower..=0.0301).contains(&upper), "{line}");
    let j = mochi(&["check", "--timeout", "60", "--clearance", "--format", "json", "choreographies/bridge.chor"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&j)).expect("json");
    assert_eq!(v["clearance"][0]["b"], "Bridge", "{v}");
}

// ---- MAVLink protocols: the front end end to end -------------------------------------

/// A protocol with a dialect and no process is checked without typing processes, says so
/// (the note E0242), and is verified; its projection prints MAVLink labels and fields.
#[test]
fn a_mavlink_protocol_without_processes_is_verified_and_says_no_process_was_typed() {
    let o = mochi(&["check", "tests/data/mavlink/mission-upload.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{v}");
    assert_eq!(o.status.code(), Some(0));
    let diags = v["diagnostics"].as_array().expect("diagnostics");
    assert_eq!(diags.len(), 1, "{v}");
    assert_eq!(diags[0]["code"], "E0242");
    assert!(diags[0]["message"].as_str().unwrap_or("").contains("no process was typed"), "{v}");
    let o = mochi(&["check", "tests/data/mavlink/mission-upload.chor"]);
    assert!(
        stdout(&o)
            .contains("verdict: verified (tests/data/mavlink/mission-upload.chor) -- protocol only: no process typed"),
        "{}",
        stdout(&o)
    );
    let o = mochi(&["project", "tests/data/mavlink/mission-upload.chor", "--role", "UAV"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.starts_with("GCS?MISSION_COUNT(count: int { 1 <= count && count <= MISSION_ITEM_LIMIT }"), "{out}");
    assert!(out.contains("GCS!MISSION_REQUEST_INT(seq: int { seq == i })"), "{out}");
    assert!(out.contains("GCS?MISSION_ITEM_INT(seq as s: int { s == i })"), "{out}");
    assert!(out.contains("[i == count] GCS!MISSION_ACK(type: int { type == MAV_MISSION_ACCEPTED }).end"), "{out}");
    // With one process, every participant needs one (E0701), as without a dialect.
    let dir = TempDir::new("mavlink-one-process");
    let src = std::fs::read_to_string("tests/data/mavlink/mission-upload.chor").expect("fixture")
        + "\nprocess GCS = UAV!MISSION_COUNT(1, 0).end;\n";
    let file = dir.write("one-process.chor", &src);
    let o = mochi(&["check", path_arg(&file), "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "rejected", "{v}");
    let codes: Vec<&str> =
        v["diagnostics"].as_array().expect("diagnostics").iter().filter_map(|d| d["code"].as_str()).collect();
    assert!(codes.contains(&"E0701") && !codes.contains(&"E0242"), "{codes:?}");
}

/// The encodings of `has_flag`, strings and the widest wire ranges, end to end: each
/// verified fixture holds only because the encoding is exact (the armed bit implies
/// `base_mode >= 128` only with `base_mode <= 255`; two literals differ; 2^64 - 1 is the
/// largest uint64_t), and each wrong variant is rejected with a counterexample in the
/// user's terms.
#[test]
fn mavlink_flags_strings_and_wire_ranges_are_decided_exactly() {
    for (file, want, cx) in [
        ("armed-flag", "verified", None),
        ("armed-flag-wrong", "rejected", Some("base_mode = ")),
        ("param-id", "verified", None),
        ("param-id-wrong", "rejected", Some("param_id = \"MC_PITCH_P\"")),
        ("wire-limits", "verified", None),
        ("wire-limits-wrong", "rejected", Some("time_unix_usec = 18446744073709551615")),
        ("parachute-action", "verified", None),
        // The verified twins of the float32 and NUL regressions in mavlink/rejected/.
        ("float-window-holds-a-float32", "verified", None),
        ("float-literal-rounds-inside", "verified", None),
        ("char-literals-without-nul", "verified", None),
        // The verified twin of a partial operator on integer fields (class 4 without floats).
        ("request-index-divided-by-a-nonzero-count", "verified", None),
    ] {
        let path = format!("tests/data/mavlink/{file}.chor");
        // The golden suite's patience: on a loaded machine the default 10 s a query can leave
        // one of these exact queries unknown, and each verdict here is a decided one.
        let o = mochi(&["check", "--timeout", "60", &path]);
        let out = stdout(&o) + &stderr(&o);
        assert!(out.contains(&format!("verdict: {want}")), "{path}:\n{out}");
        if let Some(cx) = cx {
            assert!(out.contains("error[E0414]") && out.contains(cx), "{path}:\n{out}");
        }
    }
}

/// Processes over MAVLink messages are typed like any others: the values of a payload
/// positionally, in the order its fields are listed. An acknowledgement the type does not
/// allow is E0709.
#[test]
fn processes_of_a_mavlink_protocol_are_typed_against_their_projections() {
    let o = mochi(&["check", "tests/data/mavlink/mission-upload-processes.chor"]);
    let out = stdout(&o) + &stderr(&o);
    assert!(out.contains("verdict: verified") && !out.contains("E0242"), "{out}");
    let dir = TempDir::new("mavlink-wrong-ack");
    let src = std::fs::read_to_string("tests/data/mavlink/mission-upload-processes.chor").expect("fixture");
    assert!(src.contains("GCS!MISSION_ACK(MAV_MISSION_ACCEPTED)"));
    let file = dir.write(
        "wrong-ack.chor",
        &src.replace("GCS!MISSION_ACK(MAV_MISSION_ACCEPTED)", "GCS!MISSION_ACK(MAV_MISSION_ERROR)"),
    );
    let o = mochi(&["check", path_arg(&file)]);
    let out = stdout(&o) + &stderr(&o);
    assert!(out.contains("verdict: rejected") && out.contains("error[E0709]"), "{out}");
}

#[test]
fn a_footprint_turned_with_the_heading_contains_a_round_body_or_is_never_passed() {
    // E0512 with a footprint written in the cart's heading frame (cos/sin of theta) around
    // a cylinder body: decided by the interval search of `space::enclose` (Z3 timed out on
    // it), and its twin 5 mm too small is rejected by the search's refutation (a rim point
    // outside the footprint at every heading), within the first second.
    let o = mochi(&["check", "choreographies/pgcd/underpass.chor", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "verified", "{}", stdout(&o));
    let twin = "choreographies/rejected/geometry/E0512-underpass-footprint-too-small.chor";
    let o = mochi(&["check", twin, "--timeout", "1", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "rejected", "{}", stdout(&o));
    assert!(v["diagnostics"].as_array().is_some_and(|ds| ds.iter().any(|d| d["code"] == "E0512")), "{v}");
    assert_ne!(o.status.code(), Some(0));
}

#[test]
fn a_process_loop_parameter_without_the_types_refinement_is_advised_to_add_it() {
    // The process's `k` stands for the type's `n {n >= 0}` but is declared without it: the
    // failed send's fix is the refinement on the loop parameter, in the process's names.
    let o = mochi(&[
        "check",
        "choreographies/rejected/E0709-loop-parameter-without-the-types-refinement.chor",
        "--format",
        "json",
    ]);
    let v: Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(v["verdict"], "rejected");
    let helps: Vec<&str> = v["diagnostics"]
        .as_array()
        .expect("diagnostics")
        .iter()
        .filter(|d| d["code"] == "E0709")
        .filter_map(|d| d["help"].as_str())
        .collect();
    assert!(!helps.is_empty(), "{v}");
    for h in helps {
        assert!(h.starts_with("add `{k >= 0}` to the process's loop parameter `k`"), "{h}");
        assert!(!h.contains("establish the guard"), "{h}");
    }
}

#[test]
fn a_timeout_names_the_construct_that_made_the_query_hard_and_its_simplification() {
    // Fermat's cubes: the query Z3 times out on holds the product `n * n * n`; the report
    // names it (from the query's terms) and advises making it linear.
    let o = mochi(&["check", "tests/data/hard-integer-guard.chor", "--timeout", "0.3", "--format", "json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).expect("json");
    let notes = undecided_notes(&v);
    assert!(!notes.is_empty(), "{v}");
    for n in &notes {
        assert!(n.contains("what makes it hard: the nonlinear product `A."), "{n}");
    }
    let helps: Vec<&str> = v["diagnostics"]
        .as_array()
        .expect("diagnostics")
        .iter()
        .filter(|d| d["code"] == "U0001")
        .filter_map(|d| d["help"].as_str())
        .collect();
    assert!(!helps.is_empty() && helps.iter().all(|h| h.starts_with("make the product linear")), "{helps:?}");
}

#[test]
fn a_collision_counterexample_gives_every_participants_state_and_the_time_since_the_start() {
    // The cart's swept box reaches the arm's base column in the first joint motion: the
    // report gives both participants' states when the footprints meet, and the time since
    // the choreography started (the same: only a message precedes the motion).
    let o = mochi(&["check", "choreographies/rejected/E0404-target-too-close.chor", "--color", "never"]);
    let out = format!("{}{}", stdout(&o), String::from_utf8_lossy(&o.stderr));
    let line = out.lines().find(|l| l.contains("counterexample:")).unwrap_or_else(|| panic!("{out}"));
    // The time is bisected: a meeting that replays, and a time at or before which no
    // meeting is possible (proved by the solver; the values are the model's, so only the
    // shape of the text is fixed here).
    assert!(line.contains("the footprints meet at "), "{line}");
    assert!(line.contains("s into this joint motion, and no meeting is possible at or before "), "{line}");
    assert!(line.contains("the joint motion starts when the choreography does"), "{line}");
    assert!(line.contains("states at that time: Cart: v = "), "{line}");
    assert!(line.contains("; GRobot: ze = "), "{line}");
    assert!(line.contains("at the start of the joint motion: Cart: v = "), "{line}");
}

/// `mochi monitor` on logs written here: a conforming mission upload is one conformant
/// session; the seed's stale-buffer attack (the vehicle accepts after 1 of 3 items) is a
/// violation that names the refinement with its position, exit 1; telemetry in between
/// passes through. A protocol `mochi check` does not verify is refused; one that reads
/// observed state is monitored (the log has none of its messages: no violation).
#[test]
fn monitor_reads_logs_against_a_verified_protocol() {
    use mavlink::dialects::common::{
        MavMessage, MavMissionResult, MavMissionType, ATTITUDE_DATA, MISSION_ACK_DATA, MISSION_COUNT_DATA,
        MISSION_ITEM_INT_DATA, MISSION_REQUEST_INT_DATA,
    };
    use mavlink::{MavHeader, MavlinkVersion};
    let (gcs, uav) = ((255u8, 190u8), (1u8, 1u8));
    let mt = MavMissionType::MAV_MISSION_TYPE_MISSION;
    let count = MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        target_system: 1,
        target_component: 1,
        count: 3,
        mission_type: mt,
        ..Default::default()
    });
    let request = |seq| {
        MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            target_system: 255,
            target_component: 190,
            seq,
            mission_type: mt,
        })
    };
    let item = |seq| {
        MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
            target_system: 1,
            target_component: 1,
            seq,
            mission_type: mt,
            ..Default::default()
        })
    };
    let ack = MavMessage::MISSION_ACK(MISSION_ACK_DATA {
        target_system: 255,
        target_component: 190,
        mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
        mission_type: mt,
        ..Default::default()
    });
    let telemetry = MavMessage::ATTITUDE(ATTITUDE_DATA::default());
    let log = |msgs: &[((u8, u8), &MavMessage)]| {
        let mut bytes = Vec::new();
        for (k, (from, m)) in msgs.iter().enumerate() {
            let h = MavHeader { system_id: from.0.into(), component_id: from.1, sequence: k as u8 };
            mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, h, *m).expect("encode");
        }
        bytes
    };
    let dir = TempDir::new("monitor");
    let (r0, r1, r2, i0, i1, i2) = (request(0), request(1), request(2), item(0), item(1), item(2));
    let good = log(&[
        (gcs, &count),
        (uav, &r0),
        (uav, &telemetry),
        (gcs, &i0),
        (uav, &r1),
        (gcs, &i1),
        (uav, &r2),
        (gcs, &i2),
        (uav, &ack),
    ]);
    let good_path = dir.0.join("good.bin");
    std::fs::write(&good_path, good).expect("write");
    let protocol = "choreographies/mavlink/mission-upload.chor";
    let o = mochi(&["monitor", "-p", protocol, good_path.to_str().expect("utf-8")]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("9 frames") && out.contains("1 passed through") && out.contains("conformant"), "{out}");
    assert!(out.contains("0 violation(s)"), "{out}");

    let attack = log(&[(gcs, &count), (uav, &r0), (gcs, &i0), (uav, &ack)]);
    let attack_path = dir.0.join("attack.bin");
    std::fs::write(&attack_path, attack).expect("write");
    let o = mochi(&["monitor", "-p", protocol, attack_path.to_str().expect("utf-8")]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("violation: frame 3") && out.contains("mission-upload.chor:"), "{out}");
    assert!(out.contains("incomplete"), "the session stays open after the dropped ACK: {out}");
    // The same as JSON: one log, its violation listed.
    let o = mochi(&["monitor", "-p", protocol, "--format", "json", attack_path.to_str().expect("utf-8")]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["logs"][0]["violations"].as_array().map(Vec::len), Some(1), "{v}");

    let o = mochi(&["monitor", "-p", "choreographies/mavlink/rejected/E0316-rally-count-beyond-storage.chor", "x.bin"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not verified"));
    let o = mochi(&["monitor", "-p", "choreographies/mavlink/parachute.chor", attack_path.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `mochi mission`: a list that breaks the protocol's refinements is rejected at the file's
/// line of the item (text and JSON), exit 1; a list that follows it is accepted, exit 0; a
/// malformed file is an error at its line.
#[test]
fn mission_vets_a_file_against_an_upload_protocol() {
    let dir = TempDir::new("mission");
    let rally = "choreographies/mavlink/rally-upload.chor";
    // Rally points: the second lies at latitude 95 degrees, outside rally-upload.chor's range.
    let bad = dir.write(
        "bad-rally.txt",
        "QGC WPL 110\n0\t0\t0\t5100\t0\t0\t0\t0\t-35.36\t149.16\t60\t1\n1\t0\t0\t5100\t0\t0\t0\t0\t95.0\t149.16\t60\t1\n",
    );
    let o = mochi(&["mission", "-p", rally, path_arg(&bad)]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}{}", stderr(&o));
    assert!(out.contains(&format!("{}:3: error: the rally upload breaks", bad.display())), "{out}");
    assert!(out.contains("MISSION_ITEM_INT 1") && out.contains("rejected"), "{out}");
    let o = mochi(&["mission", "-p", rally, "--format", "json", path_arg(&bad)]);
    let v: Value = serde_json::from_slice(&o.stdout).expect("one JSON line");
    assert_eq!(v["verdict"], "rejected", "{v}");
    assert_eq!(v["lists"][0]["violations"][0]["line"], 3, "{v}");
    assert_eq!(v["lists"][0]["violations"][0]["field"], "x", "{v}");

    let good = dir.write("good-rally.txt", "QGC WPL 110\n0\t0\t0\t5100\t0\t0\t0\t0\t-35.36\t149.16\t60\t1\n");
    let o = mochi(&["mission", "-p", rally, path_arg(&good)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    assert!(stdout(&o).contains("accepted (rally 1 items)"), "{}", stdout(&o));

    let broken = dir.write("broken.txt", "QGC WPL 110\n0\t0\t0\t16\t0\n");
    let o = mochi(&["mission", "-p", rally, path_arg(&broken)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains(&format!("error: {}:2:", broken.display())), "{}", stdout(&o));

    let o = mochi(&[
        "mission",
        "-p",
        "choreographies/mavlink/rejected/E0316-rally-count-beyond-storage.chor",
        path_arg(&good),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("not verified"), "{}", stderr(&o));
}

/// The upload protocols `mochi mission` is checked with in docs/missions.md.
const MISSION_PROTOCOLS: [&str; 4] = [
    "choreographies/mavlink/mission-upload.chor",
    "choreographies/mavlink/mission-upload-tolerant.chor",
    "choreographies/mavlink/fence-upload.chor",
    "choreographies/mavlink/rally-upload.chor",
];

/// docs/missions.md's "Verdicts" table is what `mochi mission` finds on every file of
/// ../shared/data/missions/: one row per file, its lists and each protocol's verdict.
/// `MISSIONS_BLESS=1` prints the rows to paste.
#[test]
fn the_missions_table_is_what_mochi_mission_finds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let base = root.join("../shared/data/missions");
    let mut files = Vec::new();
    let mut stack = vec![base.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("../shared/data/missions") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_none_or(|x| x != "md") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut args: Vec<String> = vec!["mission".into(), "--format".into(), "json".into()];
    for p in MISSION_PROTOCOLS {
        args.push("-p".into());
        args.push(p.into());
    }
    args.extend(files.iter().map(|p| p.display().to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_mochi")).args(&args).current_dir(root).output().expect("run mochi");
    let mut found = Vec::new();
    for line in String::from_utf8_lossy(&o.stdout).lines() {
        let v: Value = serde_json::from_str(line).expect("a JSON line per file");
        let file = v["file"].as_str().expect("file");
        // Named from the repository's root as the docs name them (a path under `../shared`,
        // which tidy's map check does not look for in the repository).
        let rel = Path::new(file)
            .strip_prefix(&base)
            .map_or(file.to_string(), |p| format!("../shared/data/missions/{}", p.display()));
        let lists = v["lists"].as_array().cloned().unwrap_or_default();
        let mut kinds: Vec<String> = Vec::new();
        for l in &lists {
            let k = format!("{} {}", l["mission_type"].as_str().unwrap_or("?"), l["items"]);
            if !kinds.contains(&k) {
                kinds.push(k);
            }
        }
        let cell = |proto: &str| {
            let name = Path::new(proto).file_name().and_then(|n| n.to_str()).unwrap_or(proto);
            let vs: Vec<&str> =
                lists.iter().filter(|l| l["protocol"] == name).map(|l| l["verdict"].as_str().unwrap_or("?")).collect();
            if vs.is_empty() {
                "-".to_string()
            } else {
                vs.join(", ")
            }
        };
        let mut row = format!("| `{rel}` | {} |", if kinds.is_empty() { "-".into() } else { kinds.join(", ") });
        for p in MISSION_PROTOCOLS {
            row += &format!(" {} |", cell(p));
        }
        row += &format!(" {} |", v["verdict"].as_str().unwrap_or("?"));
        found.push(row);
    }
    assert_eq!(found.len(), files.len(), "one line per file: {}", String::from_utf8_lossy(&o.stderr));
    if std::env::var_os("MISSIONS_BLESS").is_some() {
        println!("{}", found.join("\n"));
    }
    let doc = std::fs::read_to_string(root.join("docs/missions.md")).expect("docs/missions.md");
    let table = doc.split("## Verdicts").nth(1).expect("a `## Verdicts` section");
    let rows: Vec<String> = table
        .lines()
        .skip_while(|l| !l.starts_with("| file"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            // The last cell (why) is prose: compared are the cells before it.
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            format!("| {} |", cells[..cells.len().saturating_sub(1)].join(" | "))
        })
        .collect();
    assert_eq!(rows, found, "docs/missions.md is not what `mochi mission` finds");
    let rejected = found.iter().filter(|r| !r.ends_with("| accepted |")).count();
    assert_eq!(o.status.code(), Some(if rejected > 0 { 1 } else { 0 }), "{}", String::from_utf8_lossy(&o.stderr));
}
