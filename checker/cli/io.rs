//! The IO edge of the SMT stage: the sinks it reports to ([`crate::smt::DumpSink`],
//! [`crate::smt::ProgressSink`]) as they are wired for the command line. The SMT stage
//! itself never touches files or the terminal; `main.rs` (or any other caller) passes
//! these, or its own, in [`crate::smt::SmtConfig`].

use crate::smt::{DumpSink, ProgressEvent, ProgressSink};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// Writes each dumped query to `dir/<label>.smt2` (`--dump-smt`), creating `dir` if it is
/// missing. An error names the file and says why.
pub fn dump_to_dir(dir: PathBuf) -> DumpSink {
    Arc::new(move |label: &str, text: &str| {
        let path = dir.join(format!("{label}.smt2"));
        let write = || std::fs::write(&path, text);
        write()
            .or_else(|e| match e.kind() {
                std::io::ErrorKind::NotFound => std::fs::create_dir_all(&dir).and_then(|()| write()),
                _ => Err(e),
            })
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    })
}

/// A progress bar on standard error, for runs of at least 20 obligations, when standard
/// error is a terminal.
pub fn progress_bar() -> ProgressSink {
    let bar: Mutex<Option<indicatif::ProgressBar>> = Mutex::new(None);
    Arc::new(move |e: ProgressEvent| {
        use std::io::IsTerminal;
        let Ok(mut bar) = bar.lock() else { return };
        match e {
            ProgressEvent::Start { total } if total >= 20 && std::io::stderr().is_terminal() => {
                let b = indicatif::ProgressBar::new(total as u64);
                if let Ok(style) = indicatif::ProgressStyle::with_template(
                    "{spinner} checking obligations {pos}/{len} {wide_bar} {elapsed}",
                ) {
                    b.set_style(style);
                }
                *bar = Some(b);
            }
            ProgressEvent::Start { .. } => {}
            ProgressEvent::Decided { done, .. } => {
                if let Some(b) = bar.as_ref() {
                    b.set_position(done as u64);
                }
            }
            ProgressEvent::Finish => {
                if let Some(b) = bar.take() {
                    b.finish_and_clear();
                }
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dump_that_cannot_be_written_says_where_and_why() {
        let dir = std::env::temp_dir().join(format!("mochi-io-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let sink = dump_to_dir(dir.clone());
        // Missing directory: created.
        assert_eq!(sink("00000-a-0", "(check-sat)\n"), Ok(()));
        assert_eq!(std::fs::read_to_string(dir.join("00000-a-0.smt2")).ok().as_deref(), Some("(check-sat)\n"));
        // A file where the directory should be: an error naming the path.
        let file = dir.join("plain");
        std::fs::write(&file, "").expect("write");
        let bad = dump_to_dir(file.clone());
        let e = bad("00001-b-0", "(check-sat)\n").expect_err("not a directory");
        assert!(e.contains("00001-b-0.smt2"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
