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

/// Runs until killed, writing the events to `out` (stdout). Exit 1 when a protocol is not
/// verified or cannot be monitored, or an end cannot be opened.
pub(crate) fn proxy(args: &ProxyArgs, color: ColorChoice, out: Box<dyn Write + Send>) -> Outcome {
    let mut db = SourceDb::new();
    let automata = match crate::verified_automata(&mut db, &args.protocols, color, "enforces") {
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
