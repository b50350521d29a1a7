//! Projection over the whole corpus (Def 4.8, and what a receiver's refinement may read).

use crate::diag::Code;
use crate::hir::{Global, Program, ValueOrigin, Var};
use crate::project::project_all;
use crate::project::unheld_reads;

/// The programs of every `.chor` under `dir` that lower (rejected ones included: their
/// choreographies still project).
fn corpus_programs(dir: &std::path::Path, out: &mut Vec<(std::path::PathBuf, Program)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<std::path::PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            corpus_programs(&p, out);
        } else if p.extension().is_some_and(|e| e == "chor") {
            let mut db = crate::source::SourceDb::new();
            let Ok(root) = crate::fsload::load_root(&mut db, &p) else { continue };
            if let Ok(prog) =
                crate::driver::prepare(&mut db, root, &mut crate::fsload::read_bytes, crate::driver::Stage::Geometry)
            {
                out.push((p, prog));
            }
        }
    }
}

/// No local type of any corpus file reads a value its participant never holds, so every
/// printed projection has its names bound. The relay file guarantees the property is
/// exercised: before projection, its ground station's message reads such values.
#[test]
fn no_projection_of_the_corpus_reads_a_value_its_role_never_holds() {
    let root = crate::testing::repo("");
    let mut progs = Vec::new();
    corpus_programs(&root.join("choreographies"), &mut progs);
    corpus_programs(&root.join("tests/data"), &mut progs);
    assert!(progs.len() > 100, "only {} programs lowered", progs.len());
    let mut exercised = 0;
    for (path, prog) in &progs {
        let Some(chor) = &prog.choreography else { continue };
        if crate::wf::side::check(prog, &chor.body).iter().any(|d| d.code == Code::GuardNotLocal) {
            continue; // a knowledge leak (E0305): the program is rejected before projection matters
        }
        let (map, _) = project_all(prog);
        for (r, t) in &map {
            let unheld = unheld_reads(prog, *r, t);
            assert!(unheld.is_empty(), "{}: `{}` reads {unheld:?}", path.display(), prog.role_name(*r));
        }
        exercised += usize::from(reads_an_unheld_value_on_receipt(prog, &chor.body));
    }
    assert!(exercised >= 1, "no corpus file has a receiver refinement over a value the receiver never holds");
}

fn reads_an_unheld_value_on_receipt(prog: &Program, g: &Global) -> bool {
    match g {
        Global::Msg(m) => m.payload.iter().filter_map(|f| f.refinement.as_ref()).any(|r| {
            crate::hir::expr::mentions(r, &|v| {
                matches!(v, Var::Value(id, _) if matches!(prog.value(*id).origin,
                    ValueOrigin::Message { from, to } if from != m.to && to != m.to))
            })
        }),
        Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
            gs.iter().any(|c| reads_an_unheld_value_on_receipt(prog, c))
        }
        Global::Rec { body, .. } => reads_an_unheld_value_on_receipt(prog, body),
        Global::Motion(_) | Global::Var(_) | Global::End(_) | Global::After(_) => false,
    }
}
