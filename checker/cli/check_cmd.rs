//! `mochi check` and `mochi project`: each input file (a directory stands for the `.chor`
//! files below it, `-` for standard input) is checked on its own by the pipeline
//! ([`mochi::fsload::check_file`]) under the run's options (`--timeout`, `--deadline`,
//! `--jobs`, `--dump-smt`, `--clearance`), and what [`mochi::render`] makes of its report is
//! written: diagnostics to stderr, the table and verdict (or JSON, one object per input and a
//! summary object for several) to stdout. `project` prints the local types of that report.

use super::{eprint_safe, eprintln_safe, expand, print_safe, writable_dir, ColorChoice, Format, Outcome};
use clap::Args;
use mochi::driver::{CheckResult, Config, Detail, Report, Status, Verdict};
use mochi::render::{self, Json, RunSummary};
use mochi::source::SourceDb;
use mochi::{fsload, syntax};
use std::panic::{self, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub(crate) struct CheckArgs {
    /// The files to check, each on its own with its imports; a directory means every
    /// `.chor` file below it (sorted), `-` standard input (imports relative to the
    /// current directory)
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Also list the files read, the inferred partitions and the local types
    #[arg(long, short)]
    verbose: bool,
    /// Seconds Z3 may spend on one query before it counts as unknown (positive, finite)
    #[arg(long, value_name = "SECONDS", default_value_t = mochi::smt::DEFAULT_TIMEOUT.as_secs_f64(),
          value_parser = parse_seconds, allow_negative_numbers = true)]
    timeout: f64,
    /// Seconds for the whole run: files not started by then are unknown, and no query of
    /// a file started before runs past it
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, allow_negative_numbers = true)]
    deadline: Option<f64>,
    /// Worker threads for the SMT queries, at least 1 (default: all cores)
    #[arg(long, short, value_name = "N", value_parser = parse_jobs, allow_negative_numbers = true)]
    jobs: Option<usize>,
    /// Write every SMT query as an SMT-LIB file into DIR
    #[arg(long, value_name = "DIR")]
    dump_smt: Option<PathBuf>,
    /// Reuse no solver answer: ask Z3 every query afresh (slower; for comparing verdicts
    /// with the cache on and off)
    #[arg(long)]
    no_cache: bool,
    /// Also list, for each pair of participants moving together (and each participant and
    /// obstacle), the least distance between their bodies and where and when it occurs
    #[arg(long)]
    clearance: bool,
}

#[derive(Args)]
pub(crate) struct ProjectArgs {
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// The participant to project onto (default: every participant, as `local R = T;`)
    #[arg(long, value_name = "R")]
    role: Option<String>,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

pub(crate) fn check(args: &CheckArgs, color: ColorChoice) -> Outcome {
    let started = Instant::now();
    let out_color = color.for_stream(true);
    let err_color = color.for_stream(false);
    let mut config = Config::default();
    config.smt.timeout = Duration::from_secs_f64(args.timeout);
    if let Some(j) = args.jobs {
        config.smt.jobs = j;
    }
    config.smt.no_cache = args.no_cache;
    // Certified to within a millimetre.
    config.clearance = args.clearance.then_some(1e-3);
    if let Some(dir) = &args.dump_smt {
        if let Err(e) = writable_dir(dir) {
            eprintln_safe(&format!("error: --dump-smt {}: cannot write there: {e}", dir.display()));
            return Outcome::Usage;
        }
    }
    config.smt.dump = args.dump_smt.clone().map(mochi::io::dump_to_dir);
    config.smt.on_progress = Some(mochi::io::progress_bar());
    let deadline = args.deadline.map(|d| started + Duration::from_secs_f64(d));
    let mut inputs = Vec::new();
    for path in &args.files {
        expand(path, &mut inputs);
    }
    let json_lines = inputs.len() > 1;
    let mut worst = Outcome::Verified;
    let mut counts = RunSummary::default();
    for (i, input) in inputs.iter().enumerate() {
        let name = match input {
            Input::File(p) | Input::Unreadable(p, _) => p.display().to_string(),
            Input::Stdin => syntax::STDIN_NAME.to_string(),
        };
        let mut db = SourceDb::new();
        let mut cfg = config.clone();
        let result = match (input, deadline) {
            (Input::Unreadable(_, e), _) => Err(e.clone()),
            (_, Some(d)) if Instant::now() >= d => Ok(past_deadline(args.deadline.unwrap_or_default())),
            _ => {
                if let Some(d) = deadline {
                    let left = d.saturating_duration_since(Instant::now());
                    if left < cfg.smt.timeout {
                        // An unknown then says the deadline, not the timeout, ran out.
                        cfg.smt.timeout = left;
                        cfg.cut_by_deadline = true;
                    }
                }
                check_input(&mut db, input, &cfg)
            }
        };
        let report = match result {
            Ok(report) => report,
            Err(CheckError::Unreadable(msg)) => {
                counts.unreadable += 1;
                worst = worst.max(Outcome::Invalid);
                eprintln_safe(&format!("error: cannot read {name}: {msg}"));
                if let Format::Json = args.format {
                    print_json(&render::no_report_json(&name, "unreadable", &msg), json_lines);
                }
                continue;
            }
            Err(CheckError::Crashed) => {
                counts.unreadable += 1;
                worst = worst.max(Outcome::Crashed);
                if let Format::Json = args.format {
                    print_json(&render::no_report_json(&name, "crashed", "internal error: a bug in mochi"), json_lines);
                }
                continue;
            }
        };
        match args.format {
            Format::Text => {
                // Diagnostics on stderr, the table and verdict on stdout (rustc's split).
                eprint_safe(&render::diagnostics_text(&db, &report, err_color));
                let sep = if i > 0 { "\n" } else { "" };
                print_safe(&format!("{sep}{}", render::summary_text(&db, &name, &report, out_color, args.verbose)));
                if args.clearance {
                    print_safe(&render::clearance_text(&db, &report.clearances));
                }
            }
            Format::Json => {
                let mut json = render::report_json(&db, &name, &report);
                if args.clearance {
                    json["clearance"] = render::clearance_json(&db, &report.clearances);
                }
                if !print_json(&json, json_lines) {
                    worst = worst.max(Outcome::Crashed);
                    continue;
                }
            }
        }
        *match report.verdict {
            Verdict::Verified => &mut counts.verified,
            Verdict::Rejected => &mut counts.rejected,
            Verdict::Unknown => &mut counts.unknown,
        } += 1;
        worst = worst.max(match report.verdict {
            Verdict::Verified => Outcome::Verified,
            Verdict::Unknown => Outcome::Unknown,
            Verdict::Rejected => Outcome::Rejected,
        });
    }
    // With several inputs, a last summary: a line of text, or a last JSON object.
    if inputs.len() > 1 {
        counts.seconds = started.elapsed().as_secs_f64();
        match args.format {
            Format::Text => print_safe(&render::run_summary_text(&counts)),
            Format::Json => {
                if !print_json(&render::run_summary_json(&counts), true) {
                    worst = worst.max(Outcome::Crashed);
                }
            }
        }
    }
    if inputs.is_empty() {
        eprintln_safe("error: no `.chor` files to check");
        worst = Outcome::Invalid;
    }
    worst
}

/// One input of `mochi check` after directories are expanded.
pub(crate) enum Input {
    File(PathBuf),
    Stdin,
    /// A directory that could not be listed: reported in its turn like an unreadable file.
    Unreadable(PathBuf, CheckError),
}

#[derive(Clone)]
pub(crate) enum CheckError {
    Unreadable(String),
    Crashed,
}

/// The report of a file not started because the `--deadline` had passed: unknown, never
/// verified.
fn past_deadline(seconds: f64) -> Report {
    Report {
        verdict: Verdict::Unknown,
        diagnostics: Vec::new(),
        checks: vec![CheckResult {
            name: "deadline",
            status: Status::Unknown,
            millis: 0.0,
            detail: Detail::PastDeadline { seconds },
            queries: 0,
        }],
        projections: Default::default(),
        partitions: Vec::new(),
        separations: Vec::new(),
        vacuous: 0,
        planned: None,
        clearances: Vec::new(),
    }
}

/// Prints `value` as one line (several inputs: JSON Lines) or pretty; false if it could
/// not be serialised (reported).
fn print_json(value: &Json, one_line: bool) -> bool {
    match render::json_text(value, one_line) {
        Ok(s) => {
            print_safe(&s);
            true
        }
        Err(e) => {
            eprintln_safe(&format!("error: cannot write a report as JSON: {e}"));
            false
        }
    }
}

/// `--timeout` and `--deadline`: a positive, finite number of seconds that a `Duration`
/// can hold (`0`, `-1`, `inf`, `nan` and `1e400` are usage errors, exit 2).
fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number of seconds"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("`{s}` is not a positive, finite number of seconds"));
    }
    if v > 1e9 {
        return Err(format!("`{s}` seconds is more than 10^9 (about 31 years)"));
    }
    Ok(v)
}

/// `--jobs`: at least one worker thread.
fn parse_jobs(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(0) => Err("`0` workers cannot run anything: give at least 1".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("`{s}` is not a positive whole number")),
    }
}

pub(crate) fn project(args: &ProjectArgs, color: ColorChoice) -> Outcome {
    let mut db = SourceDb::new();
    // Projection needs the structural checks only, not the SMT stage.
    let config = Config { structural_only: true, ..Config::default() };
    let input = if args.file.as_os_str() == "-" { Input::Stdin } else { Input::File(args.file.clone()) };
    let name = match &input {
        Input::Stdin => syntax::STDIN_NAME.to_string(),
        _ => args.file.display().to_string(),
    };
    let report = match check_input(&mut db, &input, &config) {
        Ok(r) => r,
        Err(CheckError::Unreadable(msg)) => {
            eprintln_safe(&format!("error: cannot read {name}: {msg}"));
            return Outcome::Invalid;
        }
        Err(CheckError::Crashed) => return Outcome::Crashed,
    };
    let selected: Vec<(&String, &String)> = match &args.role {
        Some(role) => report.projections.get_key_value(role).into_iter().collect(),
        None => report.projections.iter().collect(),
    };
    if selected.is_empty() {
        // The errors say why projection did not run; without any, the role is wrong.
        let color = color.for_stream(false);
        let errors: String =
            report.diagnostics.iter().filter(|d| d.is_error()).map(|d| render::text(&db, d, color)).collect();
        let role = args.role.as_deref().unwrap_or_default();
        if !errors.is_empty() {
            eprint_safe(&errors);
        } else if report.projections.is_empty() && name.ends_with(".mochi") {
            eprintln_safe(&format!(
                "error: {name} is a library: it has no choreography to project (`mochi check {name}` checks \
                 its kinds and primitives)"
            ));
        } else if report.projections.is_empty() {
            eprintln_safe(&format!("error: no local types were computed for {name}: it has no participants"));
        } else {
            let roles: Vec<&str> = report.projections.keys().map(String::as_str).collect();
            eprintln_safe(&format!(
                "error: no participant named `{role}`; the participants of {name} are {}",
                roles.join(", ")
            ));
        }
        return Outcome::Invalid;
    }
    match (args.format, &args.role) {
        (Format::Text, Some(_)) => print_safe(&render::local_text(selected[0].1)),
        (Format::Text, None) => print_safe(&render::locals_text(&selected)),
        (Format::Json, Some(role)) => {
            if !print_json(&render::local_json(&name, role, selected[0].1), false) {
                return Outcome::Crashed;
            }
        }
        (Format::Json, None) => {
            if !print_json(&render::locals_json(&name, &selected), false) {
                return Outcome::Crashed;
            }
        }
    }
    Outcome::Verified
}

/// Runs the driver on one input. `Err` when it cannot be read (the caller reports it) or
/// when a stage panicked (reported here as a bug, after the panic message).
fn check_input(db: &mut SourceDb, input: &Input, config: &Config) -> Result<Report, CheckError> {
    // The panic hook has already printed the message and location when this returns.
    let res = panic::catch_unwind(AssertUnwindSafe(|| match input {
        Input::File(path) => fsload::check_file(db, path, config),
        Input::Stdin => fsload::check_stdin(db, config),
        Input::Unreadable(_, _) => Err(std::io::Error::other("unreadable")),
    }));
    match res {
        Ok(Ok(report)) => Ok(report),
        Ok(Err(e)) => Err(CheckError::Unreadable(match syntax::source_error(&e) {
            Some(err) => err.to_string(),
            None => e.to_string(),
        })),
        Err(_) => {
            let name = match input {
                Input::File(p) | Input::Unreadable(p, _) => p.display().to_string(),
                Input::Stdin => syntax::STDIN_NAME.to_string(),
            };
            eprintln_safe(&format!(
                "error: internal error while checking {name}; this is a bug in mochi, please report it"
            ));
            Err(CheckError::Crashed)
        }
    }
}
