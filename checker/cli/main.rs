//! The `mochi` command line: the subcommands' arguments, `explain`, `simulate` and `monitor`,
//! and the writing of results; `check` and `project` are in `check_cmd.rs`, `proxy` in
//! `proxy_cmd.rs`, `mission` in `mission_cmd.rs`.
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
use mochi::driver::{Config, Verdict};
use mochi::fsload;
use mochi::render::{self};
use mochi::source::SourceDb;
use std::io::{IsTerminal, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
    Check(check_cmd::CheckArgs),
    /// Print the local type of one participant (the projection of the choreography)
    Project(check_cmd::ProjectArgs),
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

mod check_cmd;
mod mission_cmd;
mod proxy_cmd;

use check_cmd::{CheckError, Input};

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
        Command::Check(args) => check_cmd::check(&args, cli.color).exit_code(),
        Command::Project(args) => check_cmd::project(&args, cli.color).exit_code(),
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

/// `-` is standard input; a directory stands for every `.chor` file below it, sorted by
/// path (hidden entries and symbolic links to directories are not followed, so a link
/// cycle cannot make the walk endless); anything else is taken as a file.
pub(crate) fn expand(path: &Path, out: &mut Vec<Input>) {
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

/// Creates `dir` if needed and proves it writable by creating and removing a file, so a
/// bad `--dump-smt` fails before any work instead of silently writing nothing.
pub(crate) fn writable_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let probe = dir.join(format!(".mochi-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")?;
    std::fs::remove_file(&probe)
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
