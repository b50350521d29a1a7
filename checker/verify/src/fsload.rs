//! The IO edge for source files: reading a `.chor` or `.mochi` file from disk or standard
//! input with the checks every input gets, and the file-system [`Loader`](crate::syntax::Loader) the pipeline is
//! given for imports.
//!
//! **Architecture invariant:** this module and `main.rs` are the only ones that touch the
//! file system and the standard streams (`tests/tidy.rs` checks it). The pipeline
//! ([`crate::driver::check_loaded`], [`crate::syntax::parse_with_imports`]) reads imports
//! only through the loader it is passed, so it runs unchanged on files held in memory.
//!
//! Every file read here is a regular file (metadata checked first, so `/dev/zero` or a FIFO
//! is never opened for reading), at most [`MAX_FILE_SIZE`] bytes (checked before and while
//! reading) and UTF-8 (else E0107 with the first bad byte); an import that is not one of
//! these is E0106 or E0107 at the import ([`crate::syntax::parse_with_imports`]).
//!
//! [`check_file`], [`check_stdin`] and [`check_source`] are the pipeline with this loader,
//! for the command line and for library users who check files on disk.

use crate::diag::{Code, Diagnostic};
use crate::driver::{self, Config, Report};
use crate::source::{FileId, SourceDb, Span};
use crate::syntax::{decode, source_error, SourceError, MAX_FILE_SIZE, STDIN_NAME};
use std::path::Path;

/// Reads a source file: only a regular file (after following links), at most
/// [`MAX_FILE_SIZE`] bytes, in UTF-8. The size is checked before and while reading, so
/// a file that grows meanwhile cannot exhaust memory either. This is the file system's
/// [`Loader`](crate::syntax::Loader).
pub fn read_source(path: &Path) -> std::io::Result<String> {
    let bytes = read_bytes(path)?;
    decode(bytes).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// Reads any file mochi reads (a source file, a URDF, a mesh) as bytes: only a regular
/// file (after following links), at most [`MAX_FILE_SIZE`] bytes, checked before and while
/// reading. The one place that reads a file's contents; [`read_source`] adds UTF-8
/// decoding. This is the file system's [`ByteLoader`](crate::syntax::ByteLoader).
pub fn read_bytes(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let fail = |e: SourceError| std::io::Error::new(std::io::ErrorKind::InvalidData, e);
    let meta = std::fs::metadata(path)?;
    let ft = meta.file_type();
    if !ft.is_file() {
        let kind = if ft.is_dir() { "a directory" } else { special_kind(&ft) };
        return Err(fail(SourceError::NotRegular(kind)));
    }
    if meta.len() > MAX_FILE_SIZE {
        return Err(fail(SourceError::TooLarge(meta.len())));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)?.take(MAX_FILE_SIZE + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_FILE_SIZE {
        return Err(fail(SourceError::TooLarge(bytes.len() as u64)));
    }
    Ok(bytes)
}

#[cfg(unix)]
fn special_kind(ft: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_fifo() {
        "a FIFO"
    } else if ft.is_socket() {
        "a socket"
    } else {
        "a special file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "a special file"
}

/// Reads the file the user named into `db` ([`read_source`]). A file that is not UTF-8
/// is still added (with replacement characters) so that its E0107 can point at the
/// bad byte: that diagnostic is returned beside the id.
pub fn load(db: &mut SourceDb, path: &Path) -> std::io::Result<(FileId, Option<Diagnostic>)> {
    match read_source(path) {
        Ok(text) => Ok((db.add(path.display().to_string(), text), None)),
        Err(e) => match source_error(&e) {
            Some(&SourceError::NotUtf8 { offset, .. }) => {
                let bytes = read_bytes(path)?;
                let err = e.get_ref().map(|e| e.to_string()).unwrap_or_default();
                // Replacement characters keep the valid prefix, and so the bad offset, as is.
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let id = db.add(path.display().to_string(), text);
                let d = Diagnostic::error(Code::NotUtf8, Span::new(id, offset, offset + 1), err)
                    .with_help("save the file as UTF-8 (mochi source is ASCII outside comments and strings)");
                Ok((id, Some(d)))
            }
            _ => Err(e),
        },
    }
}

/// Reads a file from disk into `db` ([`read_source`]); the caller reports an unreadable
/// root file. [`load`] turns a file that is not UTF-8 into a diagnostic instead.
pub fn load_root(db: &mut SourceDb, path: &Path) -> std::io::Result<FileId> {
    let text = read_source(path)?;
    Ok(db.add(path.display().to_string(), text))
}

/// Loads standard input as the root file, named `<stdin>`; imports are then relative to
/// the current directory. Same limits as [`read_source`].
pub fn load_stdin(db: &mut SourceDb) -> std::io::Result<(FileId, Option<Diagnostic>)> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::io::stdin().lock().take(MAX_FILE_SIZE + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_FILE_SIZE {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, SourceError::TooLarge(bytes.len() as u64)));
    }
    match decode(bytes.clone()) {
        Ok(text) => Ok((db.add(STDIN_NAME, text), None)),
        Err(e) => {
            let offset = if let SourceError::NotUtf8 { offset, .. } = e { offset } else { 0 };
            let id = db.add(STDIN_NAME, String::from_utf8_lossy(&bytes).into_owned());
            let d = Diagnostic::error(Code::NotUtf8, Span::new(id, offset, offset + 1), e.to_string())
                .with_help("send UTF-8 text (mochi source is ASCII outside comments and strings)");
            Ok((id, Some(d)))
        }
    }
}

/// Reads the file at `path` and its imports from disk and simulates it (`mochi simulate`).
/// `Err` of the inner result holds the errors that stopped it before a program existed.
pub fn simulate_file(
    db: &mut SourceDb,
    path: &Path,
    cfg: &crate::simulate::SimConfig,
) -> std::io::Result<Result<crate::simulate::SimReport, Vec<Diagnostic>>> {
    let root = load_root(db, path)?;
    Ok(crate::simulate::simulate_loaded(db, root, cfg, &mut read_bytes))
}

/// Checks the file at `path`, its imports read from disk. A file that is not UTF-8 is a
/// rejected report with its E0107; a file that cannot be read at all (missing, a
/// directory, a device, too large) is the `Err`.
pub fn check_file(db: &mut SourceDb, path: &Path, cfg: &Config) -> std::io::Result<Report> {
    let loaded = load(db, path)?;
    Ok(check_root(db, loaded, cfg))
}

/// Checks standard input (named `<stdin>`; imports relative to the current directory).
pub fn check_stdin(db: &mut SourceDb, cfg: &Config) -> std::io::Result<Report> {
    let loaded = load_stdin(db)?;
    Ok(check_root(db, loaded, cfg))
}

/// Checks source text given in memory under the display name `name`; its imports are read
/// from disk relative to `name`. (To read them from elsewhere, add the text to `db` and
/// call [`driver::check_loaded`] with a loader of your own.)
pub fn check_source(db: &mut SourceDb, name: &str, text: &str, cfg: &Config) -> Report {
    let root = db.add(name, text);
    driver::check_loaded(db, root, cfg, &mut read_bytes)
}

fn check_root(db: &mut SourceDb, (root, bad): (FileId, Option<Diagnostic>), cfg: &Config) -> Report {
    match bad {
        None => driver::check_loaded(db, root, cfg, &mut read_bytes),
        Some(d) => driver::unreadable_root(d),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pipeline reads imports only through the loader it is given: the example's
    /// library, served from memory under a name that exists nowhere on disk, verifies; the
    /// same text checked with the file-system loader cannot find it (E0105).
    #[test]
    fn the_pipeline_reads_imports_only_through_its_loader() {
        let dir = crate::testing::repo("");
        let chor = read_source(&dir.join("choreographies/example-4-2-4.chor")).expect("example");
        let lib = read_source(&dir.join("motion-primitives/bot.mochi")).expect("library");
        let chor = chor.replace("\"../motion-primitives/bot.mochi\"", "\"nowhere/in-memory.mochi\"");
        let mut asked = Vec::new();
        let mut memory = |p: &Path| {
            asked.push(p.to_path_buf());
            match p.strip_prefix("virtual") {
                Ok(rest) if rest == Path::new("nowhere/in-memory.mochi") => Ok(lib.clone().into_bytes()),
                // What the library imports in turn (`../robots/bot.mochi`): the real file.
                Ok(rest) => read_bytes(&dir.join(rest)),
                Err(_) => Err(std::io::Error::new(std::io::ErrorKind::NotFound, "not in memory")),
            }
        };
        let mut db = SourceDb::new();
        let root = db.add("virtual/example.chor", chor.as_str());
        let report = driver::check_loaded(&mut db, root, &Config::default(), &mut memory);
        assert_eq!(report.verdict, driver::Verdict::Verified, "{:?}", report.diagnostics);
        assert_eq!(asked[0], Path::new("virtual/nowhere/in-memory.mochi"), "{asked:?}");
        let report = check_source(&mut SourceDb::new(), "virtual/example.chor", &chor, &Config::default());
        assert_eq!(report.diagnostics.first().map(|d| d.code), Some(Code::ImportNotFound), "{:?}", report.diagnostics);
    }

    #[test]
    fn only_regular_utf8_files_within_the_size_limit_are_read() {
        let dir = std::env::temp_dir().join(format!("mochi-read-source-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let kind = |p: &Path| read_source(p).map_err(|e| source_error(&e).cloned());
        assert_eq!(kind(&dir), Err(Some(SourceError::NotRegular("a directory"))));
        #[cfg(unix)]
        assert_eq!(kind(Path::new("/dev/zero")), Err(Some(SourceError::NotRegular("a character device"))));
        // A sparse file just over the limit: refused from its metadata, nothing is read.
        let big = dir.join("big.mochi");
        std::fs::File::create(&big).and_then(|f| f.set_len(MAX_FILE_SIZE + 1)).expect("sparse file");
        assert_eq!(kind(&big), Err(Some(SourceError::TooLarge(MAX_FILE_SIZE + 1))));
        let bad = dir.join("bad.mochi");
        std::fs::write(&bad, b"ab\r\ncd\rx\xffy").expect("write");
        assert_eq!(kind(&bad), Err(Some(SourceError::NotUtf8 { byte: 0xff, offset: 8, line: 3, column: 2 })));
        std::fs::write(&bad, "const a = 1;").expect("write");
        assert_eq!(kind(&bad), Ok("const a = 1;".to_string()));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
