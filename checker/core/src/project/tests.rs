//! Unit tests of projection (Def 4.8) and merging (Def 4.7), on Example 4.9 and small
//! choreographies.

use super::*;
use crate::diag::Code;
use crate::hir::print::{print_bounded, NOTE_NODES};
use crate::lower::tests::lower_src;

pub(crate) use crate::testing::CART_ARMS;

fn projections(src: &str) -> (Program, BTreeMap<RoleId, LocalArc>, Vec<Diagnostic>) {
    let (prog, d) = lower_src(src);
    assert!(d.is_empty(), "{d:?}");
    let (map, diags) = project_all(&prog);
    (prog, map, diags)
}

fn printed(prog: &Program, map: &BTreeMap<RoleId, LocalArc>, role: &str) -> String {
    let r = prog.role_by_name(role).expect("role exists");
    print::local(prog, map.get(&r).expect("projection exists"))
}

#[test]
fn example_4_9_cart_and_arms() {
    let (prog, map, diags) = projections(CART_ARMS);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(
        printed(&prog, &map, "Cart"),
        "mu t. +{
  G!arrive.R!free.dt<m_move(1.0)>.G!ready.dt<m_idle>.G?ok.dt<m_move(0.0)>.t,
  G!free.R!arrive.dt<m_move(2.0)>.R!ready.dt<m_idle>.R?ok.dt<m_move(0.0)>.t
}"
    );
    assert_eq!(
        printed(&prog, &map, "G"),
        "mu t. &{
  Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.t,
  Cart?free.dt<work>.t
}"
    );
    // R does not take part in the choosing message: its branches are merged.
    assert_eq!(
        printed(&prog, &map, "R"),
        "mu t. &{
  Cart?free.dt<work>.t,
  Cart?arrive.dt<work>.Cart?ready.dt<pick>.Cart!ok.dt<work>.t
}"
    );
}

const ABC: &str = "
    robot K { state x: real; }
    motion K.m { interruptible: true; }
    motion K.n { interruptible: true; }
    motion K.w { interruptible: true; }
    motion K.stop { interruptible: false; }
    system S { participant A: K; participant B: K; participant C: K; }
";

#[test]
fn tails_are_shared_not_copied() {
    let src = format!("{ABC} choreography G = (A -> B : x. B -> A : y + A -> B : z). dt<A: m>. end;");
    let (prog, map, _) = projections(&src);
    let Some(a) = map.get(&RoleId(0)) else { panic!() };
    assert_eq!(print::local(&prog, a), "+{\n  B!x.B?y.dt<m>.end,\n  B!z.dt<m>.end\n}");
    let Local::Send { branches, .. } = &**a else { panic!() };
    let Local::Recv { branches: inner, .. } = &*branches[0].cont else { panic!() };
    assert!(Arc::ptr_eq(&inner[0].cont, &branches[1].cont));
}

#[test]
fn a_motion_merges_with_receptions_into_a_default() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. dt<A: m, B: n, C: w>. A -> C : stop. end
          + A -> B : l2. A -> C : go. end;"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "C"), "&{\n  A?go.end\n} & dt<w>.A?stop.end");
}

#[test]
fn two_defaults_merge_into_the_meet_of_their_motions() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. dt<A: m, B: n, C: w>. A -> C : stop. end
          + A -> B : l2. A -> C : go. end
          + A -> B : l3. dt<A: m, B: n, C: n>. A -> C : stop. end;"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "C"), "&{\n  A?go.end\n} & dt<w /\\ n>.A?stop.end");
}

#[test]
fn motions_of_different_interruptibility_do_not_merge() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. A -> C : go. end
          + A -> B : l2. dt<A: m, B: n, C: w>. A -> C : done. end
          + A -> B : l3. dt<A: m, B: n, C: stop>. A -> C : done. end;"
    );
    let (_, _, diags) = projections(&src);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!(diags[0].code, Code::Unmergeable);
    assert!(diags[0].notes[0].contains("interruptibility"), "{:?}", diags[0].notes);
}

#[test]
fn unmergeable_branches_are_e0601_with_both_labels() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. C -> A : x. end
          + A -> B : l2. C -> A : y. end;"
    );
    let (prog, map, diags) = projections(&src);
    assert_eq!(diags.len(), 1, "{diags:?}");
    let d = &diags[0];
    assert_eq!(d.code, Code::Unmergeable);
    assert!(d.message.contains("onto `C`"), "{}", d.message);
    assert_eq!(d.labels.len(), 2);
    let text = &src;
    let snippet = |s: crate::source::Span| &text[s.range()];
    assert_eq!(snippet(d.span), "A -> B : l1");
    assert_eq!(snippet(d.labels[0].span), "C -> A : x");
    assert_eq!(snippet(d.labels[1].span), "C -> A : y");
    assert!(d.labels[0].message.contains("A!x"), "{:?}", d.labels);
    assert!(d.help.as_deref().unwrap_or("").contains("inform `C`"));
    // The other participants still have projections.
    assert!(map.contains_key(&RoleId(0)) && map.contains_key(&RoleId(1)));
    assert!(!map.contains_key(&RoleId(2)));
    let _ = prog;
}

#[test]
fn shared_labels_merge_their_continuations() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. A -> C : go. dt<C: m>. C -> A : a. end
          + A -> B : l2. A -> C : go. A -> C : more. end;"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "C"), "A?go.&{\n  A?more.end\n} & dt<m>.A!a.end");
}

/// Def 4.7 compares the branches' projections up to the renaming of their binders:
/// each branch's `go(v)` is its own binding site, and the projections onto `C` are
/// alpha-equal, so they merge.
#[test]
fn alpha_equal_branches_merge() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. A -> C : go(v: real {{v >= 0}}). C -> A : ok(u: real {{u == v}}). end
          + A -> B : l2. A -> C : go(v: real {{v >= 0}}). C -> A : ok(u: real {{u == v}}). end;"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "C"), "A?go(v: real { v >= 0 }).A!ok(u: real { u == v }).end");
}

/// Merging a shared label reads the second branch's continuation in terms of the
/// first branch's binders: the merged `A?b` speaks of the merged `go`'s `v`.
#[test]
fn merged_continuations_refer_to_the_merged_binder() {
    let src = format!(
        "{ABC} choreography G =
            A -> B : l1. A -> C : go(v: real). A -> C : a(u: real {{u == v}}). end
          + A -> B : l2. A -> C : go(v: real). A -> C : b(u: real {{u == v}}). end;"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    let c = map.get(&prog.role_by_name("C").expect("C")).expect("projection");
    let Local::Recv { branches, .. } = &**c else { panic!("a receive: {c:?}") };
    let v = branches[0].payload[0].value;
    let Local::Recv { branches: inner, .. } = &*branches[0].cont else { panic!("a receive") };
    assert_eq!(inner.len(), 2);
    for b in inner {
        let mut seen = Vec::new();
        b.payload[0].refinement.as_ref().expect("refinement").visit_vars(&mut |x, _| {
            if let Var::Value(id, name) = x {
                if name == "v" {
                    seen.push(*id);
                }
            }
        });
        assert_eq!(seen, vec![v], "`{}` must read the merged `go`'s `v`", b.label);
        // `u == v`, the renamed `v` keeping its sort.
        let Some(ExprKind::Binary(_, _, rhs)) = b.payload[0].refinement.as_ref().map(|r| &r.kind) else {
            panic!("an equation")
        };
        assert_eq!((&rhs.kind, &rhs.sort), (&ExprKind::Var(Var::Value(v, "v".into())), &Sort::Real));
    }
}

/// Two projections that print the same but speak of different values are not
/// equal: in the first branch `v` is the `v` C received before the choice, in the second
/// the field of `nv` that C received since. Merged by name, `C` would have assumed in
/// both branches that `w` is the first `v`.
#[test]
fn same_text_about_different_values_does_not_merge() {
    let src = format!(
        "{ABC} choreography G = A -> C : pre(v: real).
            ( A -> B : l1. A -> C : nv(u: real). A -> C : go(w: real {{w == v}}). end
            + A -> B : l2. A -> C : nv(v: real). A -> C : go(w: real {{w == v}}). end );"
    );
    let (prog, map, diags) = projections(&src);
    assert_eq!(diags.iter().map(|d| d.code).collect::<Vec<_>>(), vec![Code::Unmergeable], "{diags:?}");
    assert!(!map.contains_key(&prog.role_by_name("C").expect("C")));
}

#[test]
fn a_role_outside_a_recursion_gets_end() {
    let src = format!("{ABC} choreography G = A -> C : hi. mu t. A -> B : ping. B -> A : pong. t;");
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "C"), "A?hi.end");
    assert_eq!(printed(&prog, &map, "B"), "mu t. A?ping.A!pong.t");
}

#[test]
fn separation_projects_the_side_of_the_role() {
    let src = format!("{ABC} choreography G = (dt<A: m> * dt<B: n>). A -> B : x. (dt<A: m> * dt<C: w>). end;");
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "A"), "dt<m>.B!x.dt<m>.end");
    assert_eq!(printed(&prog, &map, "B"), "dt<n>.A?x.end");
    assert_eq!(printed(&prog, &map, "C"), "dt<w>.end");
}

#[test]
fn guards_and_refined_payloads_are_kept() {
    let src = format!("{ABC} choreography G = A -> B : [x > 0] go(v: real {{ v > A.x }}). end;");
    let (prog, map, _) = projections(&src);
    assert_eq!(printed(&prog, &map, "A"), "[A.x > 0] B!go(v: real { v > A.x }).end");
    assert_eq!(printed(&prog, &map, "B"), "A?go(v: real { v > A.x }).end");
}

#[test]
fn declared_local_types_must_equal_the_projection() {
    let src = format!(
        "{ABC} choreography G = A -> B : l1(v: real). B -> C : x. end + A -> B : l2. B -> C : y. end;
         local B = &{{ A?l2.C!y.end, A?l1(v: real).C!x.end }};
         local C = &{{ B?x.end }};"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    let d = check_declared(&prog, &map);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0].code, Code::LocalMismatch);
    assert!(d[0].message.contains("`C`"));
    assert!(d[0].notes[0].contains("B?y.end"), "{:?}", d[0].notes);
    assert!(d[0].help.as_deref().unwrap_or("").contains("mochi project"));
}

#[test]
fn ill_formed_choreographies_get_diagnostics_not_panics() {
    let src = format!("{ABC} choreography G = dt<A: m> + A -> B : x;");
    let (_, _, diags) = projections(&src);
    assert!(diags.iter().all(|d| d.code == Code::ChoiceMismatch) && !diags.is_empty(), "{diags:?}");
    let src = format!("{ABC} choreography G = A -> B : x + A -> C : y;");
    let (_, _, diags) = projections(&src);
    assert!(diags.iter().all(|d| d.code == Code::ChoiceMismatch) && !diags.is_empty(), "{diags:?}");
    let src = format!("{ABC} choreography G = A -> B : x * A -> C : y;");
    let (_, map, diags) = projections(&src);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert_eq!(diags[0].code, Code::SeparationOverlap);
    assert_eq!(map.len(), 2);
}

#[test]
fn nested_choices_are_distributed() {
    let src =
        format!("{ABC} choreography G = (A -> B : x + A -> B : y). B -> C : z. end + A -> B : w. B -> C : v. end;");
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "A"), "+{\n  B!x.end,\n  B!y.end,\n  B!w.end\n}");
    assert_eq!(printed(&prog, &map, "B"), "&{\n  A?x.C!z.end,\n  A?y.C!z.end,\n  A?w.C!v.end\n}");
    assert_eq!(printed(&prog, &map, "C"), "&{\n  B?z.end,\n  B?v.end\n}");
}

#[test]
fn large_shared_types_are_summarised_in_notes() {
    // Each choice doubles the printed size of A's projection, not its size in memory.
    let choices: Vec<String> = (0..40).map(|i| format!("(A -> B : a{i} + A -> B : b{i})")).collect();
    let src = format!("{ABC} choreography G = {}. end;", choices.join(". "));
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    let a = map.get(&RoleId(0)).expect("A is projected");
    let text = print_bounded(&prog, a, NOTE_NODES);
    assert!(text.starts_with("+{B!a0, B!b0}. ..."), "{text}");
    let small = map.get(&RoleId(2)).expect("C is projected");
    assert_eq!(print_bounded(&prog, small, NOTE_NODES), "end");
}

#[test]
fn deep_sequences_and_choices_do_not_overflow() {
    let mut g = String::from("end");
    for i in 0..150 {
        g = format!("(A -> B : a{i}. {g} + A -> B : b{i}. end)");
    }
    let seq: Vec<String> = (0..3000).map(|i| format!("A -> B : s{i}")).collect();
    let src = format!("{ABC} choreography G = {}. {g};", seq.join(". "));
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let (map, diags) = project_all(&prog);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(map.len(), 3);
    let b = map.get(&RoleId(1)).cloned().expect("B is projected");
    let Some(chor) = &prog.choreography else { panic!() };
    let again = project(&prog, &chor.body, RoleId(1), Arc::new(Local::End(Loc::default()))).expect("projects");
    assert!(!Arc::ptr_eq(&b, &again) && equal(&b, &again));
}

/// A receiver's refinement that reads values only others hold: the projection eliminates
/// what a definition `x == e` determines (with `x`'s own refinement) and drops the rest.
#[test]
fn a_receiver_learns_what_a_relay_can_tell_it() {
    let src = "
        system Relay { participant V; participant C; participant G; }
        choreography R =
          V -> C: battery(level: real {0 <= level && level <= 100}, minutes: real {minutes >= 0}, k: real).
          C -> G: summary(pct: real {pct == level && pct > 3}, spare: real {spare <= minutes && spare >= 0},
                          half: real {2 * half == k}, q: real {q < k + level}).
          end;";
    let (prog, map, d) = projections(src);
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(
        printed(&prog, &map, "G"),
        "C?summary(pct: real { pct > 3 && 0 <= pct && pct <= 100 }, spare: real { spare >= 0 }, half: real, q: real).end"
    );
    // The relay and the sender keep every conjunct: they hold every value read.
    assert!(printed(&prog, &map, "C").contains("pct == level && pct > 3"));
    for (r, t) in &map {
        assert_eq!(unheld_reads(&prog, *r, t), Vec::<String>::new(), "{}", prog.role_name(*r));
    }
}

/// A timeout branch (LANGUAGE.md, Timeouts): the waiting role's external choice gains
/// `after T ms. T_R`, the sender's internal choice `after T ms by R. T_p`, and a third role
/// merges its part of the timeout branch with the others'.
#[test]
fn a_timeout_branch_is_in_both_roles_local_types() {
    let src = format!(
        "{ABC} choreography G = ( A -> B: a. B -> C: x. end + after 500 ms by B. B -> A: again. B -> C: x. end );"
    );
    let (prog, map, diags) = projections(&src);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(printed(&prog, &map, "B"), "&{\n  A?a.C!x.end,\n  after 500 ms. A!again.C!x.end\n}");
    assert_eq!(printed(&prog, &map, "A"), "+{\n  B!a.end,\n  after 500 ms by B. B?again.end\n}");
    assert_eq!(printed(&prog, &map, "C"), "B?x.end");
}

/// Two external choices with different timeouts do not merge: the third role could not tell
/// whether to give up.
#[test]
fn different_timeouts_do_not_merge() {
    let src = format!(
        "{ABC} choreography G =
            ( A -> B: a. ( C -> A: p. end + after 100 ms by A. end )
            + A -> B: b. ( C -> A: p. end + after 200 ms by A. end ) );"
    );
    let (_, _, diags) = projections(&src);
    assert!(diags.iter().any(|d| d.code == Code::Unmergeable), "{diags:?}");
    let same = format!(
        "{ABC} choreography G =
            ( A -> B: a. ( C -> A: p. end + after 100 ms by A. end )
            + A -> B: b. ( C -> A: p. end + after 100 ms by A. end ) );"
    );
    let (_, _, diags) = projections(&same);
    assert!(diags.is_empty(), "{diags:?}");
}
