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
    let out = stdout(&o);
    assert!(out.contains("error[E0103]"), "{out}");
    assert!(out.contains(&format!("{}:1:11", file.display())), "{out}");
    assert!(out.contains("1 | const a = ;"), "{out}");
    assert!(out.contains("verdict: rejected"), "{out}");
    assert!(!out.contains('\x1b'), "no colour when stdout is a pipe: {out}");
}

#[test]
fn colour_can_be_forced_on() {
    let dir = TempDir::new("colour");
    let file = dir.write("bad.chor", SYNTAX_ERROR);
    let o = mochi(&["check", "--color", "always", path_arg(&file)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains('\x1b'), "{}", stdout(&o));
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
    assert_eq!(lines.len(), 2, "{out}");
    let parsed: Vec<Value> = lines.iter().map(|l| serde_json::from_str(l).expect("each line is JSON")).collect();
    assert_eq!(parsed[0]["file"], path_arg(&first));
    assert_eq!(parsed[1]["file"], path_arg(&second));
    assert_eq!(parsed[1]["diagnostics"][0]["line"], 2);
    assert_eq!(parsed[1]["diagnostics"][0]["column"], 11);
}

#[test]
fn an_unreadable_file_among_others_fails_the_run() {
    let dir = TempDir::new("mixed");
    let bad = dir.write("bad.chor", SYNTAX_ERROR);
    let missing = dir.0.join("missing.chor");
    let o = mochi(&["check", "--format", "json", path_arg(&bad), path_arg(&missing)]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stdout(&o).lines().count(), 1, "only readable files produce a report");
    assert!(stderr(&o).contains("cannot read"), "{}", stderr(&o));
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
        // contract (E0409) the library that declares it.
        let file = name.contains("cart-and-arms-chor-") || (name.contains("-contract-") && name.contains("-mochi-"));
        assert!(name.ends_with(".smt2") && file, "{name}");
        let text = std::fs::read_to_string(f.path()).expect("readable");
        assert!(text.starts_with("; mochi: ") && text.trim_end().ends_with("(check-sat)"), "{name}: {text}");
    }
    assert!(files.iter().any(|f| f.file_name().to_string_lossy().contains("-agcomp-")), "no [AGCOMP] query dumped");
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
