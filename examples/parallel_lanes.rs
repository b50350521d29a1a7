//! Writes the parallel-lanes benchmark source (paper Sec 5 (1)) for N carts, or with
//! `--wide` the same carts in one joint motion (the wide `dt`).
//!
//! ```text
//! cargo run --example parallel_lanes -- N [--wide] [--out FILE]
//! ```
//!
//! Without `--out` the source goes to standard output, so it can be piped into
//! `mochi check` or saved under `choreographies/`.

use std::io::Write;
use std::process::ExitCode;

// The generator, shared with the benchmark and the tests (not part of the library).
#[path = "common/lanes.rs"]
#[allow(dead_code)]
mod lanes;

const USAGE: &str = "usage: parallel_lanes N [--wide] [--out FILE]";

fn main() -> ExitCode {
    let mut n: Option<usize> = None;
    let mut out: Option<String> = None;
    let mut wide = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--out" | "-o" => match args.next() {
                Some(f) => out = Some(f),
                None => return fail("`--out` needs a file name"),
            },
            "--wide" => wide = true,
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

    let src = if wide { lanes::wide_dt(n) } else { lanes::parallel_lanes(n) };
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

#[cfg(test)]
mod tests {
    use super::lanes::*;
    use mochi::source::FileId;
    use mochi::syntax::ast::Item;
    use mochi::syntax::parser::parse;

    #[test]
    fn two_lanes_parse_without_diagnostics() {
        let src = parallel_lanes(2);
        let (file, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{diags:?}\n{src}");
        let processes = file.items.iter().filter(|i| matches!(i, Item::Process(_))).count();
        assert_eq!(processes, 2);
        assert!(!src.contains("import"), "the benchmark must be self-contained");
    }

    #[test]
    fn every_cart_is_a_participant_in_its_lane() {
        let n = 7;
        let src = parallel_lanes(n);
        let (file, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{diags:?}");
        let system = file
            .items
            .iter()
            .find_map(|i| match i {
                Item::System(s) => Some(s),
                _ => None,
            })
            .expect("a system");
        let names: Vec<_> = system.participants.iter().map(|p| p.name.name.clone()).collect();
        let expected: Vec<_> = (1..=n).map(|i| format!("C{i}")).collect();
        assert_eq!(names, expected);
        for i in 1..=n {
            assert!(src.contains(&format!("participant C{i}: LaneCart {{ init: x == 0 && y == lane_dy * {}.0;", i - 1)));
            assert!(src.contains(&format!("(dt<C{i}: forward(0.5)> . dt<C{i}: back(0.5)>)")));
            assert!(src.contains(&format!("process C{i} = mu x.")));
        }
        assert_eq!(src.matches("\n  * (dt<").count(), n - 1);
    }

    #[test]
    fn one_lane_has_no_separating_conjunction() {
        let src = parallel_lanes(1);
        let (_, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{diags:?}");
        let chor = &src[src.find("choreography").expect("a choreography")..];
        let chor = &chor[..chor.find(';').expect("terminated")];
        assert!(!chor.contains('*'), "{chor}");
    }

    #[test]
    fn ten_thousand_lanes_are_generated_and_parsed_in_one_go() {
        let src = parallel_lanes(10_000);
        assert!(
            src.len() <= HEADER.len() + PRELUDE.len() + 200 + 10_000 * BYTES_PER_CART,
            "capacity estimate too small"
        );
        let (_, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{:?}", diags.first());
    }

    #[test]
    fn a_wide_dt_is_one_joint_motion_of_every_cart() {
        let n = 5;
        let src = wide_dt(n);
        let (file, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{diags:?}\n{src}");
        let processes = file.items.iter().filter(|i| matches!(i, Item::Process(_))).count();
        assert_eq!(processes, n);
        let chor = &src[src.find("choreography").expect("a choreography")..];
        let chor = &chor[..chor.find(';').expect("terminated")];
        assert_eq!(chor.matches("dt<").count(), 1, "{chor}");
        assert!(!chor.contains('*'), "{chor}");
        assert_eq!(chor.matches("cruise(0.5)").count(), n, "{chor}");
        for i in 1..=n {
            assert!(chor.contains(&format!("C{i}: ")), "C{i} in {chor}");
        }
    }

    #[test]
    fn a_wide_dt_of_one_thousand_carts_fits_its_capacity_estimate() {
        let src = wide_dt(1000);
        assert!(src.len() <= HEADER.len() + PRELUDE.len() + CRUISE.len() + 200 + 1000 * BYTES_PER_CART);
        let (_, diags) = parse(FileId(0), &src);
        assert!(diags.is_empty(), "{:?}", diags.first());
    }
}
