//! `mochi-proxy`: the enforcing half of `mochi proxy` (docs/proxy.md, "Two processes"). A
//! small executable over the run-time monitor alone (`mochi-monitor`, which depends on the
//! core only: no Z3, no geometry engine, no renderer), so the long-running process that
//! stands on the link maps none of them.
//!
//! `mochi proxy` verifies the protocols and then replaces itself with this executable,
//! handing it each protocol with the digest of the sources it verified
//! (`--protocol P --verified DIGEST`). Here each protocol is read again and lowered only if
//! the digest of what is read matches (`mochi_monitor::proxy::handoff`): run by hand on a
//! protocol `mochi proxy` did not verify, it refuses it (E0801) and exits 1.
//!
//! This file is an IO edge (tests/tidy.rs, rule (b)): it reads the protocols' files and
//! writes the event lines to stdout and the refusals to stderr.

use mochi_monitor::proxy::handoff::{self, Request};
use mochi_monitor::proxy::lines::{start_line, Lines};
use mochi_monitor::proxy::{Endpoint, Mode, Proxy, Totals};
use mochi_monitor::source::SourceDb;
use mochi_monitor::syntax::{decode, SourceError, MAX_FILE_SIZE};
use std::ffi::OsString;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

/// Usage errors exit with 2, as `mochi`'s.
const USAGE: u8 = 2;
/// The stack the protocols are lowered and compiled on (the size `mochi` checks them on;
/// only the pages used are resident).
const STACK_SIZE: usize = 256 << 20;

const HELP: &str = "mochi-proxy: the enforcing process of `mochi proxy` (no Z3)

Run `mochi proxy` instead: it verifies each protocol, then starts this executable with the
digest of what it verified. Run by hand, mochi-proxy refuses (E0801) every protocol that comes
without the digest of its sources as `mochi proxy` verified them.

Usage: mochi-proxy [--protocol FILE --verified DIGEST]... --gcs ENDPOINT --vehicle ENDPOINT
                   [--alert-only] [--violations-only]
";

struct Args {
    protocols: Vec<(PathBuf, Option<String>)>,
    gcs: Endpoint,
    vehicle: Endpoint,
    alert_only: bool,
    violations_only: bool,
}

/// The command line, or the message and exit code to stop with.
fn parse(mut args: impl Iterator<Item = OsString>) -> Result<Args, (String, u8)> {
    let usage = |m: String| (format!("error: {m}\n\n{HELP}"), USAGE);
    let (mut protocols, mut gcs, mut vehicle) = (Vec::new(), None, None);
    let (mut alert_only, mut violations_only) = (false, false);
    while let Some(a) = args.next() {
        let flag = a.to_string_lossy().into_owned();
        let mut value = |what: &str| args.next().ok_or_else(|| usage(format!("`{flag}` needs {what}")));
        match flag.as_str() {
            "-h" | "--help" => return Err((HELP.to_string(), 0)),
            "-V" | "--version" => return Err((format!("mochi-proxy {}\n", env!("CARGO_PKG_VERSION")), 0)),
            "-p" | "--protocol" => protocols.push((PathBuf::from(value("a file")?), None)),
            handoff::VERIFIED => {
                let d = value("a digest")?.to_string_lossy().into_owned();
                match protocols.last_mut() {
                    Some((_, slot @ None)) => *slot = Some(d),
                    _ => return Err(usage(format!("`{flag}` follows the `--protocol FILE` it is the digest of"))),
                }
            }
            "--gcs" | "--vehicle" => {
                let e = Endpoint::parse(&value("an endpoint")?.to_string_lossy()).map_err(usage)?;
                *(if flag == "--gcs" { &mut gcs } else { &mut vehicle }) = Some(e);
            }
            "--alert-only" => alert_only = true,
            "--violations-only" => violations_only = true,
            _ => return Err(usage(format!("unexpected argument `{flag}`"))),
        }
    }
    let gcs = gcs.ok_or_else(|| usage("`--gcs ENDPOINT` is required".into()))?;
    let vehicle = vehicle.ok_or_else(|| usage("`--vehicle ENDPOINT` is required".into()))?;
    Ok(Args { protocols, gcs, vehicle, alert_only, violations_only })
}

/// A source file: a regular file of at most [`MAX_FILE_SIZE`] bytes, UTF-8 (the limits of
/// `mochi`'s reader).
fn read_source(path: &Path) -> std::io::Result<String> {
    let invalid = |e: SourceError| std::io::Error::new(std::io::ErrorKind::InvalidData, e);
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(invalid(SourceError::NotRegular(if meta.is_dir() { "a directory" } else { "a special file" })));
    }
    let mut bytes = Vec::with_capacity(meta.len().min(MAX_FILE_SIZE) as usize);
    std::fs::File::open(path)?.take(MAX_FILE_SIZE + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_FILE_SIZE {
        return Err(invalid(SourceError::TooLarge(bytes.len() as u64)));
    }
    decode(bytes).map_err(invalid)
}

/// The protocols, each checked against its digest, lowered and compiled; a refusal is
/// printed and ends the run with 1.
fn protocols(db: &mut SourceDb, args: &Args) -> Result<Vec<mochi_monitor::monitor::Automaton>, u8> {
    let mut out = Vec::new();
    for (path, digest) in &args.protocols {
        let text = match read_source(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: cannot read {}: {e}", path.display());
                return Err(1);
            }
        };
        let req = Request { path, verified: digest.as_deref() };
        match handoff::load(db, &req, text, &mut read_source) {
            Ok(a) => out.push(a),
            Err(diags) => {
                let text: String = diags.iter().map(|d| handoff::plain(db, d)).collect();
                let _ = std::io::stderr().write_all(text.as_bytes());
                return Err(1);
            }
        }
    }
    Ok(out)
}

fn main() -> ExitCode {
    let args = match parse(std::env::args_os().skip(1)) {
        Ok(a) => a,
        Err((text, code)) => {
            if code == 0 {
                print!("{text}");
            } else {
                eprint!("{text}");
            }
            return ExitCode::from(code);
        }
    };
    // Nothing here reads a dialect's description texts (they are for readers of the
    // definitions): without them the dialects the protocols name take about half the memory.
    mochi_monitor::dialect::without_descriptions();
    let loaded = std::thread::Builder::new().stack_size(STACK_SIZE).spawn(move || {
        let mut db = SourceDb::new();
        protocols(&mut db, &args).map(|a| (db, a, args))
    });
    let (db, automata, args) = match loaded.map(|t| t.join()) {
        Ok(Ok(Ok(loaded))) => loaded,
        Ok(Ok(Err(code))) => return ExitCode::from(code),
        Ok(Err(_)) => return ExitCode::from(3),
        Err(e) => {
            eprintln!("error: cannot start the loading thread: {e}");
            return ExitCode::from(3);
        }
    };
    let open = |which: &str, e: &Endpoint| match e.open() {
        Ok(p) => Some(p),
        Err(err) => {
            eprintln!("error: cannot open the {which} end `{e}`: {err}");
            None
        }
    };
    let Some(gcs) = open("ground station", &args.gcs) else { return ExitCode::from(1) };
    let Some(vehicle) = open("vehicle", &args.vehicle) else { return ExitCode::from(1) };
    let names: Vec<String> = automata.iter().map(|a| a.name.clone()).collect();
    let mut start = Vec::new();
    let local = |p: &dyn mochi_monitor::proxy::Port| p.local_addr().map(|a| a.to_string());
    start_line(
        &mut start,
        &args.gcs.to_string(),
        local(&*gcs).as_deref(),
        &args.vehicle.to_string(),
        local(&*vehicle).as_deref(),
        &names,
        args.alert_only,
    );
    let sink = Lines::new(std::io::stdout(), names);
    sink.raw_line(&start);
    let proxy = Proxy {
        protocols: automata,
        db: Some(&db),
        mode: if args.alert_only { Mode::AlertOnly } else { Mode::Enforce },
        config: Default::default(),
        steps: !args.violations_only,
    };
    proxy.run(&*gcs, &*vehicle, &sink, &AtomicBool::new(false), &Totals::default());
    ExitCode::SUCCESS
}
