//! `mochi proxy`: the monitor between a ground station and a vehicle (docs/proxy.md).
//!
//! Two processes, one after the other (docs/proxy.md, "Two processes"): this one verifies
//! each protocol (Z3), computes the digest of the sources it verified
//! (`mochi::proxy::handoff`), and replaces itself (`exec`) with `mochi-proxy`, the small
//! executable over the monitor alone, found next to `mochi`, which enforces. With
//! `--in-process` this process enforces itself, as the fallback when `mochi-proxy` is not
//! installed and as the comparison the benchmark measures.

use super::{eprintln_safe, ColorChoice, Outcome};
use clap::Args;
use mochi::proxy::lines::{start_line, Lines};
use mochi::proxy::{handoff, Endpoint, Mode, Proxy, Totals};
use mochi::source::SourceDb;
use std::io::Write;
use std::path::PathBuf;
use std::process::Command;
use std::sync::atomic::AtomicBool;

#[derive(Args)]
pub(crate) struct ProxyArgs {
    /// A verified MAVLink protocol (`.chor` with a `dialect`); repeat for several, enforced
    /// together. Without one, frames are only checked (checksum) and forwarded
    #[arg(long = "protocol", short = 'p', value_name = "FILE")]
    protocols: Vec<PathBuf>,
    /// The ground station's end: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT,
    /// tcpin:HOST:PORT (serial ports are refused: bridge them to UDP)
    #[arg(long, value_name = "ENDPOINT", value_parser = Endpoint::parse)]
    gcs: Endpoint,
    /// The vehicle's end, in the same notation
    #[arg(long, value_name = "ENDPOINT", value_parser = Endpoint::parse)]
    vehicle: Endpoint,
    /// Forward violating messages too (only report them); by default they are dropped
    #[arg(long)]
    alert_only: bool,
    /// Print only violations, resets, input counts and errors (no line per protocol step)
    #[arg(long)]
    violations_only: bool,
    /// Enforce in this process (the `mochi` executable, which links Z3: about twice the
    /// resident memory) instead of the small `mochi-proxy` next to it
    #[arg(long)]
    in_process: bool,
}

/// The automata of `protocols`, each verified by `mochi check` in a child process first, so
/// that this long-running process never runs Z3: the solver's memory (tens of MB, kept by
/// the allocator after the check) would stay resident for the proxy's lifetime. Only
/// lowering and the monitor's compilation run here. A protocol the child does not verify is
/// refused with the child's diagnostics.
fn verified_in_children(
    db: &mut SourceDb,
    protocols: &[PathBuf],
    color: ColorChoice,
) -> Result<Vec<mochi::monitor::Automaton>, Outcome> {
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln_safe(&format!("error: cannot find the mochi executable to verify the protocols with: {e}"));
            return Err(Outcome::Crashed);
        }
    };
    let mut automata = Vec::new();
    for p in protocols {
        let out = std::process::Command::new(&exe).arg("check").arg(p).stdin(std::process::Stdio::null()).output();
        let out = match out {
            Ok(o) => o,
            Err(e) => {
                eprintln_safe(&format!("error: cannot run `mochi check {}`: {e}", p.display()));
                return Err(Outcome::Crashed);
            }
        };
        if !out.status.success() {
            eprintln_safe(&String::from_utf8_lossy(&out.stdout));
            eprintln_safe(&String::from_utf8_lossy(&out.stderr));
            eprintln_safe(&format!(
                "error[E0801]: {} is not verified (`mochi check` exits with {}): mochi enforces only verified protocols (the monitor enforces what the static checks assume)",
                p.display(),
                out.status.code().map_or("a signal".to_string(), |c| c.to_string())
            ));
            return Err(Outcome::Invalid);
        }
        automata.push(crate::monitorable(db, p, color)?);
    }
    Ok(automata)
}

/// The name of the small executable, next to `mochi`.
const SMALL: &str = "mochi-proxy";

/// `mochi-proxy` next to this executable, or why not (the message says what to do).
fn small_executable() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("error: cannot find the mochi executable: {e}"))?;
    let small = exe.with_file_name(format!("{SMALL}{}", std::env::consts::EXE_SUFFIX));
    if small.is_file() {
        return Ok(small);
    }
    Err(format!(
        "error: `mochi proxy` enforces in `{SMALL}`, a small executable without Z3 that must be next to `mochi`, \
         and there is none at {}\n  = help: build it with `cargo build --release` (it is a binary of the mochi \
         package, built with `mochi`) or install both (`cargo install --path .`); or enforce in this process with \
         `--in-process` (it links Z3: about twice the resident memory)",
        small.display()
    ))
}

/// Verifies the protocols here, then replaces this process with `mochi-proxy`, handing it
/// each protocol with the digest of the sources verified. Returns only when that fails.
fn hand_over(args: &ProxyArgs, color: ColorChoice) -> Outcome {
    let small = match small_executable() {
        Ok(s) => s,
        Err(msg) => {
            eprintln_safe(&msg);
            return Outcome::Invalid;
        }
    };
    let mut cmd = Command::new(&small);
    for p in &args.protocols {
        // A database per protocol: the digest covers the sources its verification read, in
        // the order it read them (`handoff::verified_digest`).
        let mut db = SourceDb::new();
        if let Err(o) = crate::verified_automata(&mut db, std::slice::from_ref(p), color, "enforces") {
            return o;
        }
        let digest = db.find(&p.display().to_string()).and_then(|root| handoff::verified_digest(&db, root));
        let Some(digest) = digest else {
            eprintln_safe(&format!("error: cannot compute the digest of the verified sources of {}", p.display()));
            return Outcome::Crashed;
        };
        cmd.arg("--protocol").arg(p).arg(handoff::VERIFIED).arg(digest);
    }
    cmd.arg("--gcs").arg(args.gcs.to_string()).arg("--vehicle").arg(args.vehicle.to_string());
    if args.alert_only {
        cmd.arg("--alert-only");
    }
    if args.violations_only {
        cmd.arg("--violations-only");
    }
    exec(cmd, &small)
}

#[cfg(unix)]
fn exec(mut cmd: Command, small: &std::path::Path) -> Outcome {
    use std::os::unix::process::CommandExt;
    let e = cmd.exec();
    eprintln_safe(&format!("error: cannot start {}: {e}", small.display()));
    Outcome::Crashed
}

/// Without `exec`, `mochi-proxy` runs as a child and this process waits for it.
#[cfg(not(unix))]
fn exec(mut cmd: Command, small: &std::path::Path) -> Outcome {
    match cmd.status() {
        Ok(s) if s.success() => Outcome::Verified,
        Ok(_) => Outcome::Invalid,
        Err(e) => {
            eprintln_safe(&format!("error: cannot start {}: {e}", small.display()));
            Outcome::Crashed
        }
    }
}

/// Runs until killed: in `mochi-proxy` (this process replaced), or here with
/// `--in-process`, writing the events to `out` (stdout). Exit 1 when a protocol is not
/// verified or cannot be monitored, `mochi-proxy` is missing, or an end cannot be opened.
pub(crate) fn proxy(args: &ProxyArgs, color: ColorChoice, out: Box<dyn Write + Send>) -> Outcome {
    if !args.in_process {
        return hand_over(args, color);
    }
    let mut db = SourceDb::new();
    let automata = match verified_in_children(&mut db, &args.protocols, color) {
        Ok(a) => a,
        Err(o) => return o,
    };
    let open = |which: &str, e: &Endpoint| match e.open() {
        Ok(p) => Some(p),
        Err(err) => {
            eprintln_safe(&format!("error: cannot open the {which} end `{e}`: {err}"));
            None
        }
    };
    let Some(gcs) = open("ground station", &args.gcs) else { return Outcome::Invalid };
    let Some(vehicle) = open("vehicle", &args.vehicle) else { return Outcome::Invalid };
    let names: Vec<String> = automata.iter().map(|a| a.name.clone()).collect();
    let mode = if args.alert_only { Mode::AlertOnly } else { Mode::Enforce };
    let mut start = Vec::new();
    start_line(
        &mut start,
        &args.gcs.to_string(),
        gcs.local_addr().map(|a| a.to_string()).as_deref(),
        &args.vehicle.to_string(),
        vehicle.local_addr().map(|a| a.to_string()).as_deref(),
        &names,
        args.alert_only,
    );
    let sink = Lines::new(out, names);
    sink.raw_line(&start);
    let proxy = Proxy {
        protocols: automata,
        db: Some(&db),
        mode,
        config: mochi::mavio::parse::Config::default(),
        steps: !args.violations_only,
    };
    let stop = AtomicBool::new(false);
    proxy.run(&*gcs, &*vehicle, &sink, &stop, &Totals::default());
    Outcome::Verified
}
