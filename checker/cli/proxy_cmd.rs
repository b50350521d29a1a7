//! `mochi proxy`: the monitor between a ground station and a vehicle (docs/proxy.md).

use super::{eprintln_safe, ColorChoice, Outcome};
use clap::Args;
use mochi::proxy::{Endpoint, Event, Mode, Proxy, Sink, Totals};
use mochi::render;
use mochi::source::SourceDb;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Mutex;

/// Events rendered as JSON lines, written and flushed per batch.
struct Lines<'a> {
    out: Mutex<Box<dyn Write + Send>>,
    protocols: &'a [String],
}

impl Sink for Lines<'_> {
    fn events(&self, events: &[Event]) {
        let mut text = String::new();
        for e in events {
            text += &render::proxy_event_json(e, self.protocols);
            text.push('\n');
        }
        if let Ok(mut w) = self.out.lock() {
            let _ = w.write_all(text.as_bytes());
            let _ = w.flush();
        }
    }
}

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

/// Runs until killed, writing the events to `out` (stdout). Exit 1 when a protocol is not
/// verified or cannot be monitored, or an end cannot be opened.
pub(crate) fn proxy(args: &ProxyArgs, color: ColorChoice, out: Box<dyn Write + Send>) -> Outcome {
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
    let start = render::proxy_start_json(
        &args.gcs.to_string(),
        gcs.local_addr().map(|a| a.to_string()),
        &args.vehicle.to_string(),
        vehicle.local_addr().map(|a| a.to_string()),
        &names,
        args.alert_only,
    );
    let sink = Lines { out: Mutex::new(out), protocols: &names };
    if let Ok(mut w) = sink.out.lock() {
        let _ = writeln!(w, "{start}");
        let _ = w.flush();
    }
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
