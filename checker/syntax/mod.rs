//! Syntax: lexing and parsing of mochi's language (LANGUAGE.md), and loading a file
//! with its imports into a [`SourceDb`]. This module knows nothing of name resolution.

pub mod ast;
pub mod lexer;
pub mod parser;

use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, SourceDb, Span};
use std::path::{Path, PathBuf};

/// A file and everything it imports, parsed, in dependency order (imports first).
#[derive(Debug, Default)]
pub struct Parsed {
    pub files: Vec<(FileId, ast::File)>,
}

/// The largest source file mochi reads (64 MiB); LANGUAGE.md states it.
pub const MAX_FILE_SIZE: u64 = 64 << 20;

/// Why a file could not be taken as source text. Carried inside an [`std::io::Error`]
/// (kind `InvalidData` or `InvalidInput`) by [`read_source`], so readers stay
/// `io::Result<String>`; [`source_error`] gets it back.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SourceError {
    /// A directory, device, FIFO or socket: reading `/dev/zero` never ends.
    NotRegular(&'static str),
    /// Larger than [`MAX_FILE_SIZE`].
    TooLarge(u64),
    /// Not UTF-8: the first bad byte, its offset, and its 1-based line and column.
    NotUtf8 { byte: u8, offset: usize, line: usize, column: usize },
}

impl std::fmt::Display for SourceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SourceError::NotRegular(kind) => write!(f, "it is {kind}, not a regular file"),
            SourceError::TooLarge(n) => {
                write!(f, "it has {n} bytes, more than the limit of {} MiB", MAX_FILE_SIZE >> 20)
            }
            SourceError::NotUtf8 { byte, offset, line, column } => {
                write!(f, "it is not valid UTF-8: byte 0x{byte:02x} at offset {offset} (line {line}, column {column})")
            }
        }
    }
}

impl std::error::Error for SourceError {}

/// The [`SourceError`] inside `e`, if [`read_source`] put one there.
pub fn source_error(e: &std::io::Error) -> Option<&SourceError> {
    e.get_ref().and_then(|inner| inner.downcast_ref::<SourceError>())
}

/// Reads a source file: only a regular file (after following links), at most
/// [`MAX_FILE_SIZE`] bytes, in UTF-8. The size is checked before and while reading, so
/// a file that grows meanwhile cannot exhaust memory either.
pub fn read_source(path: &Path) -> std::io::Result<String> {
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
    decode(bytes).map_err(fail)
}

/// UTF-8 text of `bytes`, or where the first invalid byte is.
pub fn decode(bytes: Vec<u8>) -> Result<String, SourceError> {
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let before = std::str::from_utf8(&bytes[..offset]).unwrap_or_default();
        let line_start = before.rfind(['\n', '\r']).map_or(0, |i| i + 1);
        let line = 1 + before.matches('\n').count() + before.matches('\r').count() - before.matches("\r\n").count();
        let column = before[line_start..].chars().count() + 1;
        SourceError::NotUtf8 { byte: bytes[offset], offset, line, column }
    })
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
                let bytes = std::fs::read(path)?;
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

/// The display name of standard input; its imports are relative to the current directory.
pub const STDIN_NAME: &str = "<stdin>";

/// Parses `root` (already in `db`) and, transitively, the files it imports. Imported
/// paths are relative to the importing file; each file is parsed once, so cycles are
/// harmless. `read` abstracts the file system for tests and for the library API.
pub fn parse_with_imports(
    db: &mut SourceDb,
    root: FileId,
    read: &mut dyn FnMut(&Path) -> std::io::Result<String>,
) -> (Parsed, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut order = Vec::new();
    let mut seen: Vec<PathBuf> = vec![normalise(Path::new(&db.file(root).name))];
    visit(db, root, read, &mut seen, &mut order, &mut diags);
    (Parsed { files: order }, diags)
}

fn visit(
    db: &mut SourceDb,
    id: FileId,
    read: &mut dyn FnMut(&Path) -> std::io::Result<String>,
    seen: &mut Vec<PathBuf>,
    order: &mut Vec<(FileId, ast::File)>,
    diags: &mut Vec<Diagnostic>,
) {
    let (file, mut d) = parser::parse(id, &db.file(id).text);
    diags.append(&mut d);
    let base = Path::new(&db.file(id).name).parent().map(Path::to_path_buf).unwrap_or_default();
    for item in &file.items {
        let ast::Item::Import(imp) = item else { continue };
        let path = normalise(&base.join(&imp.path));
        if seen.contains(&path) {
            continue;
        }
        seen.push(path.clone());
        if !is_source_name(&path) {
            diags.push(
                Diagnostic::error(
                    Code::NotSourceFile,
                    imp.span,
                    format!("`{}` is not a mochi file: imports name `.mochi` or `.chor` files", path.display()),
                )
                .with_help("import a `.mochi` library or a `.chor` file; rename the file if it is mochi source"),
            );
            continue;
        }
        match read(&path) {
            Ok(text) => {
                let child = db.add(path.display().to_string(), text);
                visit(db, child, read, seen, order, diags);
            }
            Err(e) => diags.push(match source_error(&e) {
                Some(err @ SourceError::NotUtf8 { .. }) => {
                    Diagnostic::error(Code::NotUtf8, imp.span, format!("cannot import `{}`: {err}", path.display()))
                        .with_help("save the imported file as UTF-8")
                }
                Some(err) => Diagnostic::error(
                    Code::NotSourceFile,
                    imp.span,
                    format!("cannot import `{}`: {err}", path.display()),
                )
                .with_help(format!("import a regular `.mochi` or `.chor` file of at most {} MiB", MAX_FILE_SIZE >> 20)),
                None => {
                    Diagnostic::error(Code::ImportNotFound, imp.span, format!("cannot read `{}`: {e}", path.display()))
                        .with_help("import paths are relative to the importing file")
                }
            }),
        }
    }
    order.push((id, file));
}

/// Whether `path` ends in `.mochi` or `.chor`, the only files an import may name.
fn is_source_name(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "mochi" || e == "chor")
}

/// Removes `.` and `a/..` components without touching the file system.
fn normalise(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                if matches!(out.components().next_back(), Some(std::path::Component::Normal(_))) {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imports_are_loaded_once_and_relative_to_the_importer() {
        let mut db = SourceDb::new();
        let root = db.add("dir/main.chor", "import \"../lib/a.mochi\"; import \"../lib/a.mochi\";");
        let mut reads = Vec::new();
        let mut read = |p: &Path| {
            reads.push(p.to_path_buf());
            if p == Path::new("lib/a.mochi") {
                Ok("import \"../dir/main.chor\"; const k = 1;".to_string())
            } else {
                Err(std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
            }
        };
        let (parsed, diags) = parse_with_imports(&mut db, root, &mut read);
        assert!(diags.is_empty(), "{diags:?}");
        assert_eq!(reads, vec![PathBuf::from("lib/a.mochi")]);
        assert_eq!(parsed.files.len(), 2);
        assert_eq!(parsed.files[1].0, root, "imports come first");
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

    #[test]
    fn a_missing_import_is_reported_at_the_import() {
        let mut db = SourceDb::new();
        let root = db.add("main.chor", "import \"nope.mochi\";");
        let mut read = |_: &Path| Err(std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"));
        let (_, diags) = parse_with_imports(&mut db, root, &mut read);
        assert_eq!(diags.len(), 1);
        assert_eq!(diags[0].code, Code::ImportNotFound);
        assert_eq!(diags[0].span.start, 0);
    }
}
