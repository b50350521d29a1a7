//! The hand-over from `mochi proxy` (which verifies, with Z3) to `mochi-proxy`, the small
//! executable that enforces (no Z3, no geometry engine: docs/proxy.md, "Two processes").
//!
//! `mochi proxy` verifies each protocol, then computes [`verified_digest`] of the sources it
//! verified (the root file and every file it imports, names and bytes, as the verification
//! read them) and replaces itself with `mochi-proxy --protocol P --verified DIGEST ...`. The
//! small executable reads the sources again ([`load`]), computes the same digest over what it
//! read, and refuses (E0801) a protocol without a digest or whose digest differs: it lowers
//! and enforces only bytes a `mochi` verification found verified.
//!
//! What the digest proves, and what not: it is SHA-256 over a fixed prefix (with the
//! package's version) and the sources' names and bytes, so two different sets of sources
//! have different digests (a collision is not feasible), and a protocol edited between the
//! verification and the start of enforcement, or another file at the same path, is refused.
//! It is not a signature: anyone can compute it, so it keeps a user from enforcing an
//! unverified protocol by mistake (running `mochi-proxy` by hand, a stale digest), not one who
//! computes the digest of an unverified protocol on purpose. Nor does it say which build of
//! mochi verified the sources: `mochi proxy` finds `mochi-proxy` next to itself, built from
//! the same sources.

use crate::diag::{Code, Diagnostic};
use crate::hir::Global;
use crate::monitor::Automaton;
use crate::source::{FileId, SourceDb, Span};
use crate::syntax::{self, Loader};
use sha2::{Digest, Sha256};
use std::path::Path;

/// The argument that carries a protocol's digest, after its `--protocol PATH`.
pub const VERIFIED: &str = "--verified";

/// What the digest starts with: the purpose and the version of the pipeline that verified.
const PREFIX: &str = concat!("mochi-proxy: sources verified by mochi ", env!("CARGO_PKG_VERSION"), "\n");

/// SHA-256 of `files` of `db` (names and texts, in order), as 64 lowercase hex digits.
fn digest(db: &SourceDb, files: &[FileId]) -> String {
    let mut h = Sha256::new();
    h.update(PREFIX.as_bytes());
    for f in files {
        let f = db.file(*f);
        for part in [f.name.as_bytes(), f.text.as_bytes()] {
            h.update((part.len() as u64).to_le_bytes());
            h.update(part);
        }
    }
    const HEX: &[u8; 16] = b"0123456789abcdef";
    h.finalize().iter().flat_map(|b| [HEX[usize::from(b >> 4)], HEX[usize::from(b & 0xf)]]).map(char::from).collect()
}

/// The digest of the sources a verification read: the file `root` of `db` and its imports,
/// each with the text `db` holds under its name (the first file of that name: the one the
/// verification read, not a later re-read). `None` when an import is not in `db` (the
/// verification did not read it: it did not verify).
pub fn verified_digest(db: &SourceDb, root: FileId) -> Option<String> {
    let mut copy = SourceDb::new();
    let r = copy.add(db.file(root).name.clone(), db.file(root).text.clone());
    let mut from_db = |p: &Path| match db.find(&p.display().to_string()) {
        Some(f) => Ok(db.file(f).text.clone()),
        None => Err(std::io::Error::new(std::io::ErrorKind::NotFound, "not read by the verification")),
    };
    let (parsed, diags) = syntax::parse_with_imports(&mut copy, r, &mut from_db);
    if diags.iter().any(Diagnostic::is_error) {
        return None;
    }
    let files: Vec<FileId> = parsed.files.iter().map(|(f, _)| *f).collect();
    Some(digest(&copy, &files))
}

/// A protocol the small executable was asked to enforce.
pub struct Request<'a> {
    pub path: &'a Path,
    /// The digest `mochi proxy` computed after verifying it; `None` when not given.
    pub verified: Option<&'a str>,
}

/// Checks one protocol against its digest, lowers and compiles it into `db`: `text` is the
/// root file as read from `req.path`, `read` reads its imports (the file system at the edge,
/// `mochi-proxy`'s main; memory in tests). The automaton, or the diagnostics that refuse it
/// (E0801 for a missing or different digest; what lowering or the monitor's compilation
/// reports otherwise).
pub fn load(
    db: &mut SourceDb,
    req: &Request<'_>,
    text: String,
    read: &mut Loader<'_>,
) -> Result<Automaton, Vec<Diagnostic>> {
    let shown = req.path.display().to_string();
    let root = db.add(shown.clone(), text);
    let at = Span::new(root, 0, 0);
    let (parsed, mut diags) = syntax::parse_with_imports(db, root, read);
    let files: Vec<FileId> = parsed.files.iter().map(|(f, _)| *f).collect();
    let refuse = |why: String| {
        vec![Diagnostic::error(Code::MonitorNotVerified, at, why).with_help(format!(
            "mochi-proxy enforces only protocols `mochi proxy` verified: run `mochi proxy --protocol {shown} ...` \
             with the same arguments (it verifies, then starts mochi-proxy with the digest of what it verified)"
        ))]
    };
    match req.verified {
        None => {
            return Err(refuse(format!("{shown} was not verified by `mochi proxy` (no `{VERIFIED}` digest given)")))
        }
        Some(d) if diags.iter().any(Diagnostic::is_error) || digest(db, &files) != d => {
            return Err(refuse(format!(
                "{shown} is not what `mochi proxy` verified: the digest of its sources (the file and its imports, \
                 as read now) differs from the `{VERIFIED}` digest given (the file or an import changed since \
                 it was verified, or the digest is not of these sources)"
            )))
        }
        Some(_) => {}
    }
    let (prog, more) = crate::lower::lower(&parsed);
    diags.extend(more);
    if diags.iter().any(Diagnostic::is_error) {
        diags.retain(Diagnostic::is_error);
        return Err(diags);
    }
    let mut a = Automaton::compile(&prog).map_err(|e| vec![e.diagnostic(at)])?;
    drop(prog);
    // The monitor runs the automaton and reads of the program only its names, constants and
    // strings (for evaluating and explaining predicates), never the choreography it was
    // compiled from: its body, with every guard and refinement as a tree, is dropped.
    if let Some(c) = &mut a.prog.choreography {
        c.body = Global::End(c.body.loc());
    }
    Ok(a)
}

/// A diagnostic as plain text, `error[CODE]: file:line:column: message` and its help (the
/// small executable has no renderer: these are its few refusals).
pub fn plain(db: &SourceDb, d: &Diagnostic) -> String {
    let (file, line, col) = db.location(d.span);
    let mut out = format!("error[{}]: {file}:{line}:{col}: {}\n", d.code, d.message);
    for n in &d.notes {
        out += &format!("  = note: {n}\n");
    }
    if let Some(h) = &d.help {
        out += &format!("  = help: {h}\n");
    }
    out
}

#[cfg(test)]
mod tests;
