//! Checking a library on its own (`mochi check lib.mochi`): a `.mochi` file with no
//! `system` and no `choreography` declares robot kinds and motion primitives for
//! choreographies to import. There is no protocol to verify, so what is checked is what
//! a library can be checked for:
//! - names and sorts (the `names` stage, as for any file);
//! - each kind's invariant admits a state (E0411: no state of the kind could exist);
//! - each primitive's contract is consistent: some arguments and start state satisfy its
//!   precondition and the invariant, some time in its duration and end state satisfy the
//!   guarantee (at 0 and at the end), the postcondition and the invariant (E0409, Fig 3
//!   [NON-INTERRUPT]/[INTERRUPT]; this catches an empty duration and a `pre` and `post`
//!   that contradict through the guarantee);
//! - each footprint of a kind with a body holds a point (E0412, Sec 3.1).
//!
//! These are the checks the protocol pipeline makes of the primitives a protocol runs
//! ([`contracts`]), made of every primitive. The SMT stage reads a primitive in
//! the frame of a participant of its kind, so [`synthetic_participants`] adds one per
//! kind, named after it, with no `init` (only the kind's invariant holds of it), no pose
//! and unconnected inputs (free: the questions are satisfiability questions, so a free
//! input is chosen as well as the state). Sound: each question is the same as in a
//! protocol, with fewer constraints on the start, so a contract found inconsistent here
//! is inconsistent in every protocol; one found consistent here may still be unable to
//! end from the states a protocol reaches, which the protocol's own checks (E0408) catch.

use crate::diag::{Code, Diagnostic};
use crate::hir::{KindId, Participant, PrimId, Program};
use crate::obligation::{Goal, Obligation, Rule};
use crate::source::{FileId, SourceDb};
use std::collections::HashSet;

/// Whether the file the user named is a library to check on its own: a `.mochi` file
/// whose program (with its imports) has no `system` and no `choreography`. A `.chor`
/// file (or standard input) without them is still E0210, and so is a file with only one.
pub fn is_library(db: &SourceDb, root: FileId, prog: &Program) -> bool {
    db.file(root).name.ends_with(".mochi") && prog.system.is_none() && prog.choreography.is_none()
}

/// One participant per robot kind, named after it: no `init`, no pose, inputs
/// unconnected.
pub fn synthetic_participants(prog: &mut Program) {
    for (i, k) in prog.kinds.iter().enumerate() {
        prog.roles.push(Participant {
            name: k.name.clone(),
            kind: KindId(i as u32),
            init: None,
            pose: Vec::new(),
            input_sources: vec![None; k.inputs.len()],
            mounted_on: None,
            span: k.span,
        });
    }
}

/// The obligations of a library (after [`synthetic_participants`]): each kind's
/// invariant is satisfiable (E0411), each primitive can end (E0409) and each footprint of
/// a kind with a body holds a point (E0412). The diagnostics are notes: a library with
/// nothing to check says so, at the start of `root`.
pub fn plan(prog: &Program, root: FileId) -> (Vec<Obligation>, Vec<Diagnostic>) {
    let mut notes = Vec::new();
    let mut obligations = Vec::new();
    for r in prog.role_ids() {
        let invariant = crate::sigma::invariant(prog, r);
        if invariant.is_empty() {
            continue;
        }
        let kind = prog.kind_of(r);
        obligations.push(Obligation {
            rule: Rule::InitInvariant,
            span: kind.invariant.as_ref().map_or(kind.span, |e| e.loc.0),
            what: format!("the invariant of robot kind `{}`", kind.name),
            hyps: invariant,
            goal: Goal::Reachable { before: vec![Vec::new()], dead_branch: false },
        });
    }
    let all: HashSet<PrimId> = (0..prog.prims.len()).map(|i| PrimId(i as u32)).collect();
    obligations.extend(contracts(prog, &all));
    if prog.kinds.is_empty() && prog.prims.is_empty() {
        let span = crate::source::Span::new(root, 0, 0);
        notes.push(
            Diagnostic::note_at(
                Code::EmptyLibrary,
                span,
                "this library declares no robot kind and no motion primitive: only its names and sorts were checked",
            )
            .with_help("a library is checked for its kinds' invariants and its primitives' contracts; constants alone have none"),
        );
    }
    (obligations, notes)
}

/// One obligation per primitive the protocol runs (`used`): its contract admits a run
/// that ends (Fig 3 [NON-INTERRUPT], [INTERRUPT]). A primitive nothing runs cannot make
/// this protocol deadlock; a library checked on its own asks it of every primitive
/// ([`plan`]). The driver asks it of the primitives a protocol runs.
pub fn contracts(prog: &crate::hir::Program, used: &HashSet<PrimId>) -> Vec<Obligation> {
    let used: Vec<PrimId> = (0..prog.prims.len()).map(|i| PrimId(i as u32)).filter(|p| used.contains(p)).collect();
    // Its footprint holds some point (E0412): asked of every primitive of a kind with a
    // body whose footprint is a predicate, witnessed or not. A geometric footprint holds a
    // point by construction (shapes of positive sizes, E0511; a mesh or URDF that loaded),
    // and all space every point. A kind is bodiless (an environment, a sensor) when it
    // declares no `geometry:` and every footprint of it is literally `false`: it occupies
    // no space.
    use crate::hir::Footprint;
    let is_false = |p: PrimId| match &prog.prim(p).footprint {
        Footprint::Predicate(f) => matches!(f.pred.kind, crate::hir::ExprKind::Bool(false)),
        Footprint::Everywhere | Footprint::Shapes { .. } | Footprint::Solid { .. } => false,
    };
    let has_body = |k: KindId| {
        prog.kind(k).body.is_some()
            || (0..prog.prims.len())
                .map(|i| PrimId(i as u32))
                .any(|p| prog.prim(p).kind == k && prog.prim(p).footprint.is_declared() && !is_false(p))
    };
    let asks_a_point = |p: &PrimId| match &prog.prim(*p).footprint {
        Footprint::Predicate(_) => has_body(prog.prim(*p).kind),
        Footprint::Everywhere | Footprint::Shapes { .. } | Footprint::Solid { .. } => false,
    };
    let occupies = used.iter().filter(|p| asks_a_point(p));
    let occupies = occupies.map(|&p| Obligation {
        rule: Rule::Occupies,
        span: prog.prim(p).footprint.span().unwrap_or(prog.prim(p).span),
        what: format!("the footprint of `{}`", prog.prim(p).name),
        hyps: Vec::new(),
        goal: Goal::Occupies { prim: p },
    });
    let contracts = used.iter().map(|&p| Obligation {
        rule: Rule::Contract,
        span: prog.prim(p).span,
        what: format!("the contract of `{}`", prog.prim(p).name),
        hyps: Vec::new(),
        goal: Goal::CanEnd { prim: p },
    });
    // Its footprint contains the body (E0512), for every kind with a `geometry:` and every
    // declared footprint: a written predicate, shapes placed by the state (which must
    // cover the body too), a mesh or URDF (unknown unless it is the body). All space
    // holds it at once, and so does `footprint: geometry`, which is the body
    // (`goals::plan` says so without a query).
    let contains = used
        .iter()
        .filter(|p| {
            let prim = prog.prim(**p);
            let asked = match &prim.footprint {
                Footprint::Everywhere => false,
                f @ (Footprint::Shapes { .. } | Footprint::Solid { .. }) => !f.is_own_geometry(),
                Footprint::Predicate(_) => true,
            };
            asked && prog.kind(prim.kind).body.is_some()
        })
        .map(|&p| Obligation {
            rule: Rule::Contains,
            span: prog.prim(p).footprint.span().unwrap_or(prog.prim(p).span),
            what: format!("footprint of `{}`", prog.prim(p).name),
            hyps: Vec::new(),
            goal: Goal::Contains { prim: p },
        });
    occupies.chain(contains).chain(contracts).collect()
}

#[cfg(test)]
mod tests {
    use crate::diag::{Code, Severity};
    use crate::driver::{Config, Report, Verdict};
    use crate::fsload::{check_file, check_source};
    use crate::source::SourceDb;
    use std::path::Path;

    fn check(path: &Path) -> Report {
        let mut db = SourceDb::new();
        check_file(&mut db, path, &Config::default()).expect("readable")
    }

    fn libraries(dir: &str) -> Vec<std::path::PathBuf> {
        let mut files: Vec<_> = std::fs::read_dir(crate::testing::repo(dir))
            .expect("the directory exists")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mochi"))
            .collect();
        files.sort();
        files
    }

    /// Every library the project ships verifies on its own, with a question per primitive.
    /// Before, each was E0210.
    #[test]
    fn the_shipped_libraries_verify() {
        let prims = libraries("motion-primitives");
        assert!(prims.len() >= 5, "{prims:?}");
        for path in prims.iter().chain(&libraries("robots")) {
            let r = check(path);
            assert_eq!(r.verdict, Verdict::Verified, "{}: {:?}", path.display(), r.diagnostics);
            assert!(r.diagnostics.iter().all(|d| d.severity != Severity::Error), "{}", path.display());
        }
        let r = check(&crate::testing::repo("motion-primitives/bot.mochi"));
        let contracts = r.checks.iter().find(|c| c.name == "contracts").expect("a contracts line");
        // bot.mochi's five primitives: each can end, each footprint holds a point and
        // contains the bot's ball.
        assert!(
            matches!(contracts.detail, crate::driver::Detail::Obligations { total: 15, failed: 0, .. }),
            "{}",
            contracts.detail
        );
    }

    /// An empty invariant (no state of the kind) is E0411 at the invariant.
    #[test]
    fn a_kind_whose_invariant_no_state_satisfies_is_e0411() {
        let mut db = SourceDb::new();
        let r = check_source(
            &mut db,
            "k.mochi",
            "robot K { state x: real; invariant: x > 1 && x < 0; }",
            &Config::default(),
        );
        assert_eq!(r.verdict, Verdict::Rejected);
        let codes: Vec<Code> = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code).collect();
        assert_eq!(codes, vec![Code::InitOutsideInvariant]);
    }

    /// A library with nothing but constants is verified, with a note saying so; a `.chor`
    /// file, or a `.mochi` file with a system but no choreography, is still E0210.
    #[test]
    fn a_library_of_constants_verifies_with_a_note_and_chor_files_still_need_a_system() {
        let mut db = SourceDb::new();
        let r = check_source(&mut db, "consts.mochi", "const k: real = 1.0;", &Config::default());
        assert_eq!(r.verdict, Verdict::Verified, "{:?}", r.diagnostics);
        assert_eq!(r.diagnostics.len(), 1);
        assert_eq!((r.diagnostics[0].code, r.diagnostics[0].severity), (Code::EmptyLibrary, Severity::Note));
        let r = check_source(&mut db, "consts.chor", "const k: real = 1.0;", &Config::default());
        assert_eq!(r.diagnostics.first().map(|d| d.code), Some(Code::MissingItem));
        let src = "robot K { state x: real; } system S { participant p: K; }";
        let r = check_source(&mut db, "half.mochi", src, &Config::default());
        assert_eq!(r.diagnostics.first().map(|d| d.code), Some(Code::MissingItem));
    }
}
