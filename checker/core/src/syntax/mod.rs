//! Syntax: lexing and parsing of mochi's language (LANGUAGE.md), and following a file's
//! imports into a [`SourceDb`] through a [`Loader`] the caller passes in (the file system's
//! is `mochi_verify::fsload::read_source`). This module does no IO and knows nothing of name
//! resolution.

pub mod ast;
pub mod lexer;
pub mod parser;

use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, SourceDb};
use std::path::{Path, PathBuf};

/// Where imports come from: the text of the file at a path (already joined to the
/// importer's directory and normalised), or why it cannot be had. A [`SourceError`] inside
/// the `io::Error` ([`source_error`]) becomes E0106 or E0107 at the import; any other
/// error E0105. The file system's loader is `mochi_verify::fsload::read_source`; tests and
/// library users pass closures over memory.
pub type Loader<'a> = dyn FnMut(&Path) -> std::io::Result<String> + 'a;

/// Where the bytes of files that are not mochi source come from (URDF files and the meshes
/// they name, read by `crate::geometry`): the file system at the edge
/// (`mochi_verify::fsload::read_bytes`, same limits as a [`Loader`]: regular files of at most
/// [`MAX_FILE_SIZE`] bytes), memory in tests. A [`Loader`] is this plus [`decode`].
pub type ByteLoader<'a> = dyn FnMut(&Path) -> std::io::Result<Vec<u8>> + 'a;

/// A file and everything it imports, parsed, in dependency order (imports first).
#[derive(Debug, Default)]
pub struct Parsed {
    pub files: Vec<(FileId, ast::File)>,
}

/// The largest source file mochi reads (64 MiB); LANGUAGE.md states it.
pub const MAX_FILE_SIZE: u64 = 64 << 20;

/// Why a file could not be taken as source text. Carried inside an [`std::io::Error`]
/// (kind `InvalidData` or `InvalidInput`) by a [`Loader`] such as
/// `mochi_verify::fsload::read_source`, so loaders stay `io::Result<String>`; [`source_error`]
/// gets it back.
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

/// The [`SourceError`] inside `e`, if a [`Loader`] put one there.
pub fn source_error(e: &std::io::Error) -> Option<&SourceError> {
    e.get_ref().and_then(|inner| inner.downcast_ref::<SourceError>())
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

/// The display name of standard input; its imports are relative to the current directory.
pub const STDIN_NAME: &str = "<stdin>";

/// Parses `root` (already in `db`) and, transitively, the files it imports. Imported
/// paths are relative to the importing file; each file is parsed once, so cycles are
/// harmless. `read` is where the imported files come from: the file system at the edge
/// (`mochi_verify::fsload::read_source`), memory in tests and for the library API. Whatever
/// the loader, an import must name a `.mochi` or `.chor` file (E0106): that is the
/// language's rule, checked here before the loader is asked.
pub fn parse_with_imports(db: &mut SourceDb, root: FileId, read: &mut Loader<'_>) -> (Parsed, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut order = Vec::new();
    let mut seen: Vec<PathBuf> = vec![normalise(Path::new(&db.file(root).name))];
    visit(db, root, read, &mut seen, &mut order, &mut diags);
    (Parsed { files: order }, diags)
}

fn visit(
    db: &mut SourceDb,
    id: FileId,
    read: &mut Loader<'_>,
    seen: &mut Vec<PathBuf>,
    order: &mut Vec<(FileId, ast::File)>,
    diags: &mut Vec<Diagnostic>,
) {
    let (mut file, mut d) = parser::parse(id, &db.file(id).text);
    diags.append(&mut d);
    let base = Path::new(&db.file(id).name).parent().map(Path::to_path_buf).unwrap_or_default();
    resolve_shape_paths(&mut file, &base);
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

/// Resolves the file of every `urdf("...")` and `mesh("...")` shape against `base`, the
/// directory of the file that names it, as imports are: a robot library under `robots/`
/// names its URDF relative to itself, whichever choreography imports it. Nothing is read
/// here; the geometry stage loads the files.
fn resolve_shape_paths(file: &mut ast::File, base: &Path) {
    let mut bodies: Vec<&mut ast::BodyAst> = Vec::new();
    for item in &mut file.items {
        match item {
            ast::Item::Robot(r) => bodies.extend(r.geometry.iter_mut()),
            ast::Item::Motion(m) => bodies.extend(m.fields.iter_mut().filter_map(|f| match &mut f.value {
                ast::FieldValue::Body(b) => Some(b),
                _ => None,
            })),
            ast::Item::System(s) => bodies.extend(s.obstacles.iter_mut().flat_map(|o| o.geometry.iter_mut())),
            _ => {}
        }
    }
    for body in bodies {
        for part in &mut body.parts {
            // An empty path stays empty, for lowering to report (E0214).
            if let Some((path, _)) = part.shape.path.as_mut().filter(|(p, _)| !p.is_empty()) {
                *path = normalise(&base.join(&*path)).display().to_string();
            }
        }
    }
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
    fn shape_files_are_resolved_against_the_file_that_names_them() {
        let mut db = SourceDb::new();
        let root = db.add(
            "dir/main.chor",
            "import \"../robots/r.mochi\"; system S { obstacle O { geometry: mesh(\"o.stl\"); } }",
        );
        let mut read = |_: &Path| {
            Ok("robot R { state q: real; geometry: urdf(\"panda/p.urdf\") + mesh(\"\"); } motion R.m { interruptible: true; footprint: mesh(\"../m.obj\"); }".to_string())
        };
        let (parsed, diags) = parse_with_imports(&mut db, root, &mut read);
        assert!(diags.is_empty(), "{diags:?}");
        let mut paths = Vec::new();
        for (_, f) in &parsed.files {
            for item in &f.items {
                let bodies: Vec<&ast::BodyAst> = match item {
                    ast::Item::Robot(r) => r.geometry.iter().collect(),
                    ast::Item::Motion(m) => m
                        .fields
                        .iter()
                        .filter_map(|f| if let ast::FieldValue::Body(b) = &f.value { Some(b) } else { None })
                        .collect(),
                    ast::Item::System(s) => s.obstacles.iter().flat_map(|o| &o.geometry).collect(),
                    _ => Vec::new(),
                };
                for b in bodies {
                    paths.extend(b.parts.iter().filter_map(|p| p.shape.path.as_ref().map(|(s, _)| s.clone())));
                }
            }
        }
        assert_eq!(paths, ["robots/panda/p.urdf", "", "m.obj", "dir/o.stl"]);
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
