//! Syntax: lexing and parsing of mochi's language (LANGUAGE.md), and loading a file
//! with its imports into a [`SourceDb`]. This module knows nothing of name resolution.

pub mod ast;
pub mod lexer;
pub mod parser;

use crate::diag::{Code, Diagnostic};
use crate::source::{FileId, SourceDb};
use std::path::{Path, PathBuf};

/// A file and everything it imports, parsed, in dependency order (imports first).
#[derive(Debug, Default)]
pub struct Parsed {
    pub files: Vec<(FileId, ast::File)>,
}

/// Reads a file from disk into `db`; the caller reports an unreadable root file.
pub fn load_root(db: &mut SourceDb, path: &Path) -> std::io::Result<FileId> {
    let text = std::fs::read_to_string(path)?;
    Ok(db.add(path.display().to_string(), text))
}

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
        match read(&path) {
            Ok(text) => {
                let child = db.add(path.display().to_string(), text);
                visit(db, child, read, seen, order, diags);
            }
            Err(e) => diags.push(
                Diagnostic::error(Code::ImportNotFound, imp.span, format!("cannot read `{}`: {e}", path.display()))
                    .with_help("import paths are relative to the importing file"),
            ),
        }
    }
    order.push((id, file));
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
