//! The probe: with Σ threaded through, the predicate obligations of the bundled
//! examples hold (they failed while [T-MOTION] forgot the positions a post with
//! `old(x)` keeps).

use crate::hir::{print, Program};
use crate::obligation::{Goal, Obligation};
use crate::smt::{check_valid, SmtConfig, Validity};
use crate::source::SourceDb;

/// The obligations of well-formedness and typing for a bundled example.
fn example_obligations(path: &str) -> (Program, Vec<Obligation>) {
    let mut db = SourceDb::new();
    let file = crate::testing::repo(path);
    let root = crate::fsload::load_root(&mut db, &file).expect("example readable");
    let (parsed, d) = crate::syntax::parse_with_imports(&mut db, root, &mut |p| std::fs::read_to_string(p));
    assert!(d.is_empty(), "{d:?}");
    let (prog, d) = crate::lower::lower(&parsed);
    assert!(d.is_empty(), "{d:?}");
    let body = prog.choreography.as_ref().map(|c| c.body.clone()).expect("a choreography");
    let (mut obs, d) = (crate::plan::obligations(&prog, &body), crate::wf::scope::check(&prog, &body));
    assert!(d.is_empty(), "{d:?}");
    let (locals, d) = crate::project::project_all(&prog);
    assert!(d.is_empty(), "{d:?}");
    let (typing, d) = crate::typeck::check_processes(&prog, &locals);
    assert!(d.is_empty(), "{d:?}");
    obs.extend(typing);
    (prog, obs)
}

/// Decides every `Goal::Valid` obligation; returns one line per obligation.
fn decide(path: &str) -> Vec<(String, Validity)> {
    let (prog, obs) = example_obligations(path);
    obs.iter()
        .filter_map(|ob| match &ob.goal {
            Goal::Valid(goal) => {
                let v = check_valid(&prog, &ob.hyps, goal, &SmtConfig::default());
                let hyps: Vec<String> = ob.hyps.iter().map(|h| print::expr(&prog, None, h)).collect();
                let line = format!(
                    "{} {}: {}  [{}]",
                    ob.rule.name(),
                    ob.what,
                    print::expr(&prog, None, goal),
                    hyps.join(", ")
                );
                Some((line, v))
            }
            _ => None,
        })
        .collect()
}

fn all_hold(path: &str, expected: usize) {
    let results = decide(path);
    for (line, v) in &results {
        eprintln!("{path}: {v:?}: {line}");
    }
    let failed: Vec<&(String, Validity)> = results.iter().filter(|(_, v)| *v != Validity::Holds).collect();
    assert!(failed.is_empty(), "{path}: {failed:#?}");
    assert_eq!(results.len(), expected, "{path}: the number of predicate obligations");
}

#[test]
fn cart_and_arms_obligations_hold() {
    all_hold("choreographies/cart-and-arms.chor", 10);
}

#[test]
fn sorting_obligations_hold() {
    all_hold("choreographies/sorting.chor", 14);
}
