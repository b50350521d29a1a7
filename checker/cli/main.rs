//! The `mochi` command line: `check`, `project`, `explain` and `simulate`.
//!
//! This is the IO edge, with [`mochi::fsload`] (which reads source files): it reads
//! arguments, hands each file to the pipeline ([`mochi::fsload::check_file`], which runs
//! [`mochi::driver`] with the file-system loader), writes what [`mochi::render`] makes of
//! the report, and turns the verdicts into the exit code:
//!
//! | code | meaning                                                              |
//! |------|----------------------------------------------------------------------|
//! | 0    | every file verified                                                  |
//! | 1    | a file was rejected, or the input was invalid (unreadable, no role)  |
//! | 2    | command-line usage error: a bad option value (`--timeout 0`, `--jobs |
//! |      | 0`, an unwritable `--dump-smt` directory), or an unknown code to explain |
//! | 3    | undecided: some verdict unknown, none rejected                       |
//! | 101  | mochi crashed (a bug: the panic message says where)                  |
//!
//! Output follows rustc, for every subcommand: results (the check table and verdict, the
//! summary line, JSON, projections, explanations, simulation reports) go to stdout;
//! diagnostics and errors go to stderr. With `--format json` every input file yields
//! exactly one JSON object on stdout, even one that could not be read, and a run of
//! several inputs ends with a summary object. The only text made here is the one-line
//! `error: ...` of a failure of the run itself (an unreadable file, a bad option value);
//! everything else, and the colour decision, is [`mochi::render`]'s.

use clap::{Args, Parser, Subcommand, ValueEnum};
use mochi::diag::Code;
use mochi::driver::{CheckResult, Config, Detail, Report, Status, Verdict};
use mochi::render::{self, Json, RunSummary};
use mochi::source::SourceDb;
use mochi::{fsload, syntax};
use std::io::{IsTerminal, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Checks run on a thread with this much stack, so that deeply nested input is limited
/// by the parser's own depth limit rather than by the main thread's stack.
const STACK_SIZE: usize = 256 << 20;

const USAGE: u8 = 2;

#[derive(Parser)]
#[command(name = "mochi", version, about = "Type checker and verifier for motion choreographies")]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// When to colour the output
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, global = true)]
    color: ColorChoice,
}

#[derive(Subcommand)]
enum Command {
    /// Check choreography files and report a verdict for each
    Check(CheckArgs),
    /// Print the local type of one participant (the projection of the choreography)
    Project(ProjectArgs),
    /// Explain a diagnostic code, e.g. `mochi explain E0301`
    Explain(ExplainArgs),
    /// Run the choreography on concrete trajectories (a protocol without motion as each
    /// participant's projection) and report collisions, stuck states and violations
    Simulate(SimulateArgs),
    /// Check MAVLink logs (.tlog, raw streams, .pcapng) against verified protocols: each
    /// session conformant, incomplete, or its violations, with coverage
    Monitor(MonitorArgs),
    /// Stand between a ground station and a vehicle: forward MAVLink both ways and drop (or
    /// only report) every message that breaks a verified protocol; one JSON line per verdict
    Proxy(proxy_cmd::ProxyArgs),
    /// Vet a mission file (.plan, .waypoints, Mission Planner .txt) against verified upload
    /// protocols: the upload it implies, item by item
    Mission(mission_cmd::MissionArgs),
}

mod mission_cmd;
mod proxy_cmd;

#[derive(Args)]
struct MonitorArgs {
    /// A verified MAVLink protocol (`.chor` with a `dialect`); repeat for several, monitored
    /// together over each log
    #[arg(long = "protocol", short = 'p', required = true, value_name = "FILE")]
    protocols: Vec<PathBuf>,
    /// The logs; a directory means every log below it (`.tlog`, `.bin`, `.raw`, `.mav`,
    /// `.pcapng`, `.pcap`; sorted), checked in parallel
    #[arg(required = true, value_name = "LOG")]
    logs: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Args)]
struct SimulateArgs {
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// How many runs
    #[arg(long, default_value_t = 10)]
    runs: usize,
    /// Seed of the random choices (runs are reproducible)
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Messages and motions per run
    #[arg(long, default_value_t = 40)]
    steps: usize,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Args)]
struct CheckArgs {
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
struct ProjectArgs {
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// The participant to project onto (default: every participant, as `local R = T;`)
    #[arg(long, value_name = "R")]
    role: Option<String>,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Args)]
struct ExplainArgs {
    /// A code such as E0301
    #[arg(required_unless_present = "list", conflicts_with = "list")]
    code: Option<String>,
    /// List every code with its title
    #[arg(long)]
    list: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Text,
    /// JSON; with several files, one object per line (JSON Lines)
    Json,
}

#[derive(Clone, Copy, ValueEnum)]
enum ColorChoice {
    /// Colour when writing to a terminal and `NO_COLOR` is not set
    Auto,
    Always,
    Never,
}

impl ColorChoice {
    /// Whether to colour stdout (`stdout: true`) or stderr: [`render::use_color`] decides
    /// from the facts gathered here.
    fn for_stream(self, stdout: bool) -> bool {
        let choice = match self {
            ColorChoice::Auto => render::ColorChoice::Auto,
            ColorChoice::Always => render::ColorChoice::Always,
            ColorChoice::Never => render::ColorChoice::Never,
        };
        let terminal = if stdout { std::io::stdout().is_terminal() } else { std::io::stderr().is_terminal() };
        render::use_color(choice, terminal, std::env::var_os(render::COLOR_OFF_VAR).as_deref())
    }
}

/// How a file, or a whole run, ended. Later variants win when files are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Verified,
    Unknown,
    Rejected,
    Invalid,
    Usage,
    Crashed,
}

impl Outcome {
    fn exit_code(self) -> u8 {
        match self {
            Outcome::Verified => 0,
            Outcome::Rejected | Outcome::Invalid => 1,
            Outcome::Unknown => 3,
            Outcome::Usage => USAGE,
            Outcome::Crashed => 101,
        }
    }
}

fn main() -> ExitCode {
    // Usage errors exit with 2, `--help` and `--version` with 0 (clap's defaults).
    let cli = Cli::parse();
    let worker = std::thread::Builder::new().name("mochi".into()).stack_size(STACK_SIZE).spawn(move || run(cli));
    match worker.map(|w| w.join()) {
        Ok(Ok(code)) => ExitCode::from(code),
        Ok(Err(_)) => ExitCode::from(Outcome::Crashed.exit_code()),
        Err(e) => {
            eprintln_safe(&format!("error: cannot start the checking thread: {e}"));
            ExitCode::from(Outcome::Crashed.exit_code())
        }
    }
}

fn run(cli: Cli) -> u8 {
    match cli.command {
        Command::Check(args) => check(&args, cli.color).exit_code(),
        Command::Project(args) => project(&args, cli.color).exit_code(),
        Command::Explain(args) => explain(&args),
        Command::Simulate(args) => simulate(&args, cli.color).exit_code(),
        Command::Monitor(args) => monitor(&args, cli.color).exit_code(),
        Command::Proxy(args) => proxy_cmd::proxy(&args, cli.color, Box::new(std::io::stdout())).exit_code(),
        Command::Mission(args) => mission_cmd::mission(&args, cli.color).exit_code(),
    }
}

/// `mochi monitor`: 0 when no log breaks a protocol, 1 for a violation (or invalid input).
/// The automata of `protocols`, each checked first: only a verified protocol is monitored
/// (the monitor enforces what the static checks assumed, worth nothing for a protocol they
/// did not prove). An error is printed and its exit code returned. Shared by `monitor` and
/// `proxy` (`verb` says which: "monitors", "enforces").
pub(crate) fn verified_automata(
    db: &mut SourceDb,
    protocols: &[std::path::PathBuf],
    color: ColorChoice,
    verb: &str,
) -> Result<Vec<mochi::monitor::Automaton>, Outcome> {
    let mut automata = Vec::new();
    for p in protocols {
        let report = match fsload::check_file(db, p, &Config::default()) {
            Ok(r) => r,
            Err(e) => {
                eprintln_safe(&format!("error: cannot read {}: {e}", p.display()));
                return Err(Outcome::Invalid);
            }
        };
        if report.verdict != Verdict::Verified {
            let color = color.for_stream(false);
            let shown: String =
                report.diagnostics.iter().filter(|d| d.is_error()).map(|d| render::text(db, d, color)).collect();
            eprint_safe(&shown);
            // The refusal itself (E0801), at the protocol's first error or undecided
            // obligation, else at the start of the file.
            let at = report
                .diagnostics
                .iter()
                .find(|d| d.is_error())
                .or_else(|| report.diagnostics.iter().find(|d| d.code == mochi::diag::Code::Undecided))
                .map(|d| d.span)
                .or_else(|| file_start(db, p));
            let verdict = format!("{:?}", report.verdict).to_lowercase();
            match at {
                Some(span) => {
                    let d = mochi::diag::Diagnostic::error(
                        mochi::diag::Code::MonitorNotVerified,
                        span,
                        format!("{} is {verdict}, not verified: mochi {verb} only verified protocols", p.display()),
                    )
                    .with_help(format!(
                        "the monitor enforces what the static checks assume, which is proved only for a verified protocol; run `mochi check {}` and fix what it reports",
                        p.display()
                    ));
                    eprint_safe(&render::text(db, &d, color));
                }
                None => eprintln_safe(&format!(
                    "error[E0801]: {} is {verdict}, not verified: mochi {verb} only verified protocols; run `mochi check {}`",
                    p.display(),
                    p.display()
                )),
            }
            return Err(Outcome::Invalid);
        }
        automata.push(monitorable(db, p, color)?);
    }
    Ok(automata)
}

/// A protocol lowered and compiled for the monitor (no Z3: the caller has had it verified).
pub(crate) fn monitorable(
    db: &mut SourceDb,
    p: &std::path::Path,
    color: ColorChoice,
) -> Result<mochi::monitor::Automaton, Outcome> {
    let root = match fsload::load_root(db, p) {
        Ok(r) => r,
        Err(e) => {
            eprintln_safe(&format!("error: cannot read {}: {e}", p.display()));
            return Err(Outcome::Invalid);
        }
    };
    let prog = match mochi::driver::prepare(db, root, &mut fsload::read_bytes, mochi::driver::Stage::Names) {
        Ok(prog) => prog,
        Err(diags) => {
            let color = color.for_stream(false);
            eprint_safe(&diags.iter().map(|d| render::text(db, d, color)).collect::<String>());
            return Err(Outcome::Invalid);
        }
    };
    match mochi::monitor::Automaton::compile(&prog) {
        Ok(a) => Ok(a),
        Err(e) => {
            let fallback = mochi::source::Span::new(root, 0, 0);
            eprint_safe(&render::text(db, &e.diagnostic(fallback), color.for_stream(false)));
            Err(Outcome::Invalid)
        }
    }
}

/// The first character of a file the database holds, as a span.
fn file_start(db: &SourceDb, p: &Path) -> Option<mochi::source::Span> {
    let name = p.display().to_string();
    db.find(&name).map(|f| mochi::source::Span::new(f, 0, 0))
}

/// Only verified protocols are monitored: the monitor enforces what the static checks
/// assumed, which is worth nothing for a protocol they did not prove.
fn monitor(args: &MonitorArgs, color: ColorChoice) -> Outcome {
    use mochi::monitor::Monitor;
    let mut db = SourceDb::new();
    let automata = match verified_automata(&mut db, &args.protocols, color, "monitors") {
        Ok(a) => a,
        Err(o) => return o,
    };
    let mut files = Vec::new();
    for l in &args.logs {
        if l.is_dir() {
            collect_files(l, &mut files);
        } else {
            files.push(l.clone());
        }
    }
    // Logs are checked in parallel, each with its own monitor; the results keep the order.
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).min(files.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<std::sync::Mutex<Option<render::MonitoredLog>>> =
        files.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(path) = files.get(i) else { break };
                let mut m = Monitor::new(automata.clone());
                let log = monitor_log(&db, path, &mut m);
                if let Ok(mut slot) = results[i].lock() {
                    *slot = Some(log);
                }
            });
        }
    });
    let logs: Vec<render::MonitoredLog> = results.into_iter().filter_map(|r| r.into_inner().ok().flatten()).collect();
    match args.format {
        Format::Text => print_safe(&render::monitor_text(&logs)),
        Format::Json => match render::monitor_json_text(&logs) {
            Ok(s) => print_safe(&s),
            Err(e) => {
                eprintln_safe(&format!("error: cannot write the report as JSON: {e}"));
                return Outcome::Crashed;
            }
        },
    }
    if logs.iter().any(|l| l.stats.violations > 0 || l.error.is_some()) {
        Outcome::Rejected
    } else {
        Outcome::Verified
    }
}

/// The extensions of the logs a directory is searched for: telemetry logs (`.tlog`), raw
/// MAVLink streams (`.bin`, `.raw`, `.mav`) and packet captures (`.pcapng`, `.pcap`). A
/// file named on the command line is read whatever its name (its format is told from its
/// content).
const LOG_EXTENSIONS: &[&str] = &["tlog", "bin", "raw", "mav", "pcapng", "pcap"];

/// Every log below `dir` ([`LOG_EXTENSIONS`]), sorted, depth first.
fn collect_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            collect_files(&p, out);
        } else if p.is_file()
            && p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| LOG_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        {
            out.push(p);
        }
    }
}

/// One log read and run through `m`.
fn monitor_log(db: &SourceDb, path: &Path, m: &mut mochi::monitor::Monitor) -> render::MonitoredLog {
    let mut log = render::MonitoredLog { file: path.display().to_string(), ..Default::default() };
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) => {
            log.error = Some(e.to_string());
            return log;
        }
    };
    let summary = mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
        m.on_frame(&f);
    });
    m.finish();
    log.format = summary.format.name().to_string();
    log.counts = summary.counts;
    if let Some(e) = summary.error {
        log.error = Some(format!("the capture is malformed at byte {}: {}", e.offset, e.what));
    }
    log.stats = m.stats;
    let protos = m.protocols();
    log.sessions = m
        .summaries()
        .iter()
        .map(|s| {
            let a = &protos[s.protocol];
            let roles = a
                .roles
                .iter()
                .zip(&s.roles)
                .map(|(name, b)| {
                    let id = |x: Option<u8>| x.map_or("?".to_string(), |v| v.to_string());
                    format!("{name} = {}/{}", id(b.sys), id(b.comp))
                })
                .collect();
            render::MonitoredSession {
                protocol: a.name.clone(),
                session: s.session,
                conformant: s.conformant,
                state: s.state,
                first_frame: s.first_frame,
                last_frame: s.last_frame,
                roles,
                violations: s.violations,
                states: (s.visited.iter().filter(|v| **v).count(), s.visited.len()),
                edges: (s.taken.iter().filter(|t| **t > 0).count(), s.taken.len()),
            }
        })
        .collect();
    log.violations = (0..m.violations().len()).map(|i| m.describe(db, i)).collect();
    log
}

/// `mochi simulate`: 0 when nothing was found, 1 for a finding (or invalid input), 3
/// when some run stopped undecided and nothing was found.
fn simulate(args: &SimulateArgs, color: ColorChoice) -> Outcome {
    use mochi::fsload::simulate_file;
    use mochi::simulate::SimConfig;
    let cfg = SimConfig { runs: args.runs, seed: args.seed, steps: args.steps, ..SimConfig::default() };
    let mut db = SourceDb::new();
    let report = match panic::catch_unwind(AssertUnwindSafe(|| simulate_file(&mut db, &args.file, &cfg))) {
        Ok(Ok(Ok(r))) => r,
        Ok(Ok(Err(diags))) => {
            let color = color.for_stream(false);
            eprint_safe(&diags.iter().map(|d| render::text(&db, d, color)).collect::<String>());
            return Outcome::Invalid;
        }
        Ok(Err(e)) => {
            eprintln_safe(&format!("error: cannot read {}: {e}", args.file.display()));
            return Outcome::Invalid;
        }
        Err(_) => return Outcome::Crashed,
    };
    let name = args.file.display().to_string();
    match args.format {
        Format::Text => print_safe(&render::simulation_text(&name, &report)),
        Format::Json => match render::simulation_json_text(&report) {
            Ok(s) => print_safe(&s),
            Err(e) => {
                eprintln_safe(&format!("error: cannot write the simulation as JSON: {e}"));
                return Outcome::Crashed;
            }
        },
    }
    if report.failures().next().is_some() {
        Outcome::Rejected
    } else if report.findings.is_empty() {
        Outcome::Verified
    } else {
        Outcome::Unknown
    }
}

fn check(args: &CheckArgs, color: ColorChoice) -> Outcome {
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
enum Input {
    File(PathBuf),
    Stdin,
    /// A directory that could not be listed: reported in its turn like an unreadable file.
    Unreadable(PathBuf, CheckError),
}

#[derive(Clone)]
enum CheckError {
    Unreadable(String),
    Crashed,
}

/// `-` is standard input; a directory stands for every `.chor` file below it, sorted by
/// path (hidden entries and symbolic links to directories are not followed, so a link
/// cycle cannot make the walk endless); anything else is taken as a file.
fn expand(path: &Path, out: &mut Vec<Input>) {
    if path.as_os_str() == "-" {
        out.push(Input::Stdin);
        return;
    }
    if !path.is_dir() {
        out.push(Input::File(path.to_path_buf()));
        return;
    }
    let mut found = Vec::new();
    let mut stack = vec![path.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let entries = match std::fs::read_dir(&dir) {
            Ok(e) => e,
            Err(e) => {
                out.push(Input::Unreadable(dir, CheckError::Unreadable(e.to_string())));
                continue;
            }
        };
        for entry in entries.flatten() {
            let p = entry.path();
            let hidden = entry.file_name().to_string_lossy().starts_with('.');
            let Ok(ft) = entry.file_type() else { continue };
            if ft.is_dir() && !hidden {
                stack.push(p);
            } else if !ft.is_dir() && p.extension().is_some_and(|e| e == "chor") {
                found.push(p);
            }
        }
    }
    found.sort();
    out.extend(found.into_iter().map(Input::File));
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

/// Creates `dir` if needed and proves it writable by creating and removing a file, so a
/// bad `--dump-smt` fails before any work instead of silently writing nothing.
fn writable_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let probe = dir.join(format!(".mochi-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")?;
    std::fs::remove_file(&probe)
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

fn project(args: &ProjectArgs, color: ColorChoice) -> Outcome {
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

fn explain(args: &ExplainArgs) -> u8 {
    if args.list {
        print_safe(&render::code_list_text());
        return 0;
    }
    let text = args.code.as_deref().unwrap_or_default();
    let Ok(code) = text.parse::<Code>() else {
        eprintln_safe(&format!(
            "error: unknown code `{text}`: codes are a letter and four digits, such as E0301 \
             (E01 syntax, E02 names, E03 well-formedness, E04 contracts, E06 projection, \
             E07 typing, U0001 undecided); `mochi explain --list` lists them all"
        ));
        return USAGE;
    };
    print_safe(&render::explain_text(code));
    0
}

/// Writes to stdout. A closed pipe (`mochi check ... | head`) is not an error worth a
/// panic, which `print!` would raise; the exit code still reports the verdicts.
fn print_safe(s: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(s.as_bytes()).and_then(|()| out.flush());
}

fn eprint_safe(s: &str) {
    let _ = std::io::stderr().lock().write_all(s.as_bytes());
}

fn eprintln_safe(s: &str) {
    eprint_safe(&format!("{s}\n"));
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn the_worst_outcome_decides_the_exit_code() {
        let all = |o: &[Outcome]| o.iter().copied().fold(Outcome::Verified, Outcome::max).exit_code();
        assert_eq!(all(&[]), 0);
        assert_eq!(all(&[Outcome::Verified, Outcome::Unknown]), 3);
        assert_eq!(all(&[Outcome::Unknown, Outcome::Rejected, Outcome::Verified]), 1);
        assert_eq!(all(&[Outcome::Invalid, Outcome::Unknown]), 1);
    }
}
