//! Writes the parallel-lanes benchmark source (paper Sec 5 (1)) for N carts.
//!
//! ```text
//! cargo run --example parallel_lanes -- N [--out FILE]
//! ```
//!
//! Without `--out` the source goes to standard output, so it can be piped into
//! `mochi check` or saved under `choreographies/`.

use std::io::Write;
use std::process::ExitCode;

const USAGE: &str = "usage: parallel_lanes N [--out FILE]";

fn main() -> ExitCode {
    let mut n: Option<usize> = None;
    let mut out: Option<String> = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--out" | "-o" => match args.next() {
                Some(f) => out = Some(f),
                None => return fail("`--out` needs a file name"),
            },
            "-h" | "--help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            _ if n.is_none() => match arg.parse::<usize>() {
                Ok(k) if k >= 1 => n = Some(k),
                _ => return fail(&format!("N must be a positive integer, got `{arg}`")),
            },
            _ => return fail(&format!("unexpected argument `{arg}`")),
        }
    }
    let Some(n) = n else { return fail("missing N") };

    let src = mochi::lanes::parallel_lanes(n);
    let written = match &out {
        Some(path) => std::fs::write(path, &src),
        None => std::io::stdout().lock().write_all(src.as_bytes()),
    };
    match written {
        Ok(()) => {
            if let Some(path) = out {
                eprintln!("wrote {n} lanes ({} bytes) to {path}", src.len());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: cannot write the source: {e}");
            ExitCode::FAILURE
        }
    }
}

fn fail(msg: &str) -> ExitCode {
    eprintln!("error: {msg}\n{USAGE}");
    ExitCode::from(2)
}
