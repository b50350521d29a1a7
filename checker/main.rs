//! The `mochi` command line: `check`, `project`, `explain` and `simulate`.
//!
//! This is the only place that does IO: it reads arguments, hands each file to
//! [`mochi::driver`], prints what [`mochi::render`] makes of the report, and turns the
//! verdicts into the exit code:
//!
//! | code | meaning                                                              |
//! |------|----------------------------------------------------------------------|
//! | 0    | every file verified                                                  |
//! | 1    | a file was rejected, or the input was invalid (unreadable, no role)  |
//! | 2    | command-line usage error (from clap), or an unknown code to explain  |
//! | 3    | undecided: some verdict unknown, none rejected                       |
//! | 101  | mochi crashed (a bug: the panic message says where)                  |

use clap::{Args, Parser, Subcommand, ValueEnum};
use mochi::diag::Code;
use mochi::driver::{self, Config, Report, Verdict};
use mochi::render;
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
    Check(CheckArgs),
    /// Print the local type of one participant (the projection of the choreography)
    Project(ProjectArgs),
    /// Explain a diagnostic code, e.g. `mochi explain E0301`
    Explain(ExplainArgs),
    /// Run the choreography on concrete trajectories and report collisions and stuck states
    Simulate(SimulateArgs),
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
    /// The files to check; each is checked on its own, with its imports
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// Also list the files read, the inferred partitions and the local types
    #[arg(long, short)]
    verbose: bool,
    /// Seconds Z3 may spend on one query before it counts as unknown
    #[arg(long, value_name = "SECONDS", default_value_t = mochi::smt::DEFAULT_TIMEOUT.as_secs_f64())]
    timeout: f64,
    /// Worker threads for the SMT queries (default: all cores)
    #[arg(long, short, value_name = "N")]
    jobs: Option<usize>,
    /// Write every SMT query as an SMT-LIB file into DIR
    #[arg(long, value_name = "DIR")]
    dump_smt: Option<PathBuf>,
}

#[derive(Args)]
struct ProjectArgs {
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// The participant to project onto
    #[arg(long, value_name = "R")]
    role: String,
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

/// How a file, or a whole run, ended. Later variants win when files are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Verified,
    Unknown,
    Rejected,
    Invalid,
    Crashed,
}

impl Outcome {
    fn exit_code(self) -> u8 {
        match self {
            Outcome::Verified => 0,
            Outcome::Rejected | Outcome::Invalid => 1,
            Outcome::Unknown => 3,
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
    }
}

/// `mochi simulate`: 0 when nothing was found, 1 for a finding (or invalid input), 3
/// when some run stopped undecided and nothing was found.
fn simulate(args: &SimulateArgs, color: ColorChoice) -> Outcome {
    use mochi::simulate::{simulate_file, SimConfig};
    let cfg = SimConfig { runs: args.runs, seed: args.seed, steps: args.steps, ..SimConfig::default() };
    let mut db = SourceDb::new();
    let report = match panic::catch_unwind(AssertUnwindSafe(|| simulate_file(&mut db, &args.file, &cfg))) {
        Ok(Ok(Ok(r))) => r,
        Ok(Ok(Err(diags))) => {
            let color = use_color(color, std::io::stderr().is_terminal());
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
        Format::Json => match serde_json::to_string_pretty(&report) {
            Ok(s) => print_safe(&(s + "\n")),
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
    let color = use_color(color, std::io::stdout().is_terminal());
    let json_lines = args.files.len() > 1;
    let mut worst = Outcome::Verified;
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        eprintln_safe("error: --timeout takes a positive number of seconds");
        return Outcome::Invalid;
    }
    let mut config = Config::default();
    config.smt.timeout = std::time::Duration::from_secs_f64(args.timeout.min(1e6));
    if let Some(j) = args.jobs {
        config.smt.jobs = j.max(1);
    }
    config.smt.dump_dir = args.dump_smt.clone();
    config.smt.progress = std::io::stderr().is_terminal();
    for (i, path) in args.files.iter().enumerate() {
        let mut db = SourceDb::new();
        let Some(report) = check_path(&mut db, path, &config) else {
            worst = worst.max(Outcome::Invalid);
            continue;
        };
        let name = path.display().to_string();
        let out = match args.format {
            Format::Text => {
                let sep = if i > 0 { "\n" } else { "" };
                format!("{sep}{}", render::report_text(&db, &name, &report, color, args.verbose))
            }
            Format::Json => {
                let value = render::report_json(&db, &name, &report);
                let res = if json_lines { serde_json::to_string(&value) } else { serde_json::to_string_pretty(&value) };
                match res {
                    Ok(s) => s + "\n",
                    Err(e) => {
                        eprintln_safe(&format!("error: cannot write the report of {name} as JSON: {e}"));
                        worst = worst.max(Outcome::Crashed);
                        continue;
                    }
                }
            }
        };
        print_safe(&out);
        worst = worst.max(match report.verdict {
            Verdict::Verified => Outcome::Verified,
            Verdict::Unknown => Outcome::Unknown,
            Verdict::Rejected => Outcome::Rejected,
        });
    }
    worst
}

fn project(args: &ProjectArgs, color: ColorChoice) -> Outcome {
    let mut db = SourceDb::new();
    // Projection needs the structural checks only, not the SMT stage.
    let config = Config { structural_only: true, ..Config::default() };
    let Some(report) = check_path(&mut db, &args.file, &config) else {
        return Outcome::Invalid;
    };
    let name = args.file.display().to_string();
    let Some(local) = report.projections.get(&args.role) else {
        // The errors say why projection did not run; without any, the role is wrong.
        let color = use_color(color, std::io::stderr().is_terminal());
        let errors: String =
            report.diagnostics.iter().filter(|d| d.is_error()).map(|d| render::text(&db, d, color)).collect();
        if !errors.is_empty() {
            eprint_safe(&errors);
        } else if report.projections.is_empty() {
            eprintln_safe(&format!(
                "error: no participant named `{}`: no local types were computed for {name}",
                args.role
            ));
        } else {
            let roles: Vec<&str> = report.projections.keys().map(String::as_str).collect();
            eprintln_safe(&format!(
                "error: no participant named `{}`; the participants of {name} are {}",
                args.role,
                roles.join(", ")
            ));
        }
        return Outcome::Invalid;
    };
    match args.format {
        Format::Text if local.ends_with('\n') => print_safe(local),
        Format::Text => print_safe(&format!("{local}\n")),
        Format::Json => {
            let value = serde_json::json!({ "file": name, "role": args.role, "local": local });
            match serde_json::to_string_pretty(&value) {
                Ok(s) => print_safe(&(s + "\n")),
                Err(e) => {
                    eprintln_safe(&format!("error: cannot write the projection as JSON: {e}"));
                    return Outcome::Crashed;
                }
            }
        }
    }
    Outcome::Verified
}

/// Runs the driver on one file. `None` when the file cannot be read (reported here) or
/// when a stage panicked (reported as a bug, after the panic message).
fn check_path(db: &mut SourceDb, path: &Path, config: &Config) -> Option<Report> {
    // The panic hook has already printed the message and location when this returns.
    let res = panic::catch_unwind(AssertUnwindSafe(|| driver::check_file(db, path, config)));
    match res {
        Ok(Ok(report)) => Some(report),
        Ok(Err(e)) => {
            eprintln_safe(&format!("error: cannot read {}: {e}", path.display()));
            None
        }
        Err(_) => {
            eprintln_safe(&format!(
                "error: internal error while checking {}; this is a bug in mochi, please report it",
                path.display()
            ));
            None
        }
    }
}

fn explain(args: &ExplainArgs) -> u8 {
    if args.list {
        let list: String = Code::ALL.iter().map(|c| format!("{c}  {}\n", c.title())).collect();
        print_safe(&list);
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
    print_safe(&format!("{code}: {}\n\n{}\n", code.title(), wrap(code.explain(), 90)));
    0
}

/// Greedy word wrap at `width` characters; a longer word gets a line of its own.
fn wrap(text: &str, width: usize) -> String {
    let mut out = String::new();
    let mut line_len = 0;
    for word in text.split_whitespace() {
        let n = word.chars().count();
        if line_len > 0 && line_len + 1 + n > width {
            out.push('\n');
            line_len = 0;
        } else if line_len > 0 {
            out.push(' ');
            line_len += 1;
        }
        out.push_str(word);
        line_len += n;
    }
    out
}

/// `auto` colours a terminal unless `NO_COLOR` is set to a non-empty value (no-color.org).
fn use_color(choice: ColorChoice, is_terminal: bool) -> bool {
    match choice {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => is_terminal && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()),
    }
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
    fn wrap_keeps_lines_short_and_words_whole() {
        let text = Code::NotTotallySynchronised.explain();
        let wrapped = wrap(text, 90);
        assert!(wrapped.lines().all(|l| l.chars().count() <= 90), "{wrapped}");
        assert_eq!(wrapped.split_whitespace().collect::<Vec<_>>(), text.split_whitespace().collect::<Vec<_>>());
        assert_eq!(wrap("a-very-long-word b", 4), "a-very-long-word\nb");
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
