//! Unit tests of the logical context Σ (ARCHITECTURE.md, "The logical context Σ").

use super::normal::{binary, var};
use super::*;
use crate::hir::expr::BinOp;
use crate::lower::tests::lower_src;

/// A cart `C` and an arm `A`; `x`'s invariant is `-10 <= x <= 10`, `ze`'s `0 <= ze <= 1`.
const SRC: &str = "
    const gx: real = 1.6;
    const cz: real = 0.2;
    robot Cart { state x: real, v: real; invariant: -10 <= x <= 10; }
    robot Arm { state ze: real; invariant: 0 <= ze <= 1; }
    motion Cart.idle { interruptible: true; post: x == old(x) && v == 0; }
    motion Cart.move(xf: real) { interruptible: false; pre: xf > x; post: x == xf && v == 0; }
    motion Cart.step(d: real) { interruptible: false; post: x == old(x) + d; }
    motion Arm.work { interruptible: true; post: min(cz, old(ze)) <= ze && ze <= max(cz, old(ze)); }
    system S { participant C: Cart { init: x == 0 && v == 0; } participant A: Arm { init: ze >= cz; } }
";

/// Lowers SRC with a choreography whose messages carry `preds` as guards, in order;
/// `C:` or `A:` in front says who sends (and whose variables are unqualified). The
/// first message binds the value `n`, which later guards may read.
fn setup(preds: &[&str]) -> (Program, Vec<Expr>) {
    let mut msgs = vec!["C -> A : first(n: real)".to_string()];
    for (i, p) in preds.iter().enumerate() {
        let (who, g) = p.split_at(2);
        let (from, to) = if who == "C:" { ("C", "A") } else { ("A", "C") };
        msgs.push(format!("{from} -> {to} : [{g}] m{i}"));
    }
    let (prog, d) = lower_src(&format!("{SRC} choreography G = {}. end;", msgs.join(". ")));
    assert!(d.is_empty(), "{d:?}");
    let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else { panic!("a sequence") };
    let guards = items
        .iter()
        .filter_map(|g| match g {
            Global::Msg(m) => m.guard.clone(),
            _ => None,
        })
        .collect();
    (prog, guards)
}

fn shown(prog: &Program, s: &Sigma) -> Vec<String> {
    s.facts().iter().map(|e| print::expr(prog, None, e)).collect()
}

fn role(prog: &Program, name: &str) -> RoleId {
    prog.role_by_name(name).expect("role")
}

fn prim(prog: &Program, name: &str) -> PrimId {
    PrimId(prog.prims.iter().position(|p| p.name == name).expect("primitive") as u32)
}

fn constant(prog: &Program, name: &str) -> Expr {
    let i = prog.consts.iter().position(|c| c.name == name).expect("constant");
    var(Var::Const(ConstId(i as u32)), &Sort::Real)
}

#[test]
fn assume_splits_orients_and_dedupes() {
    let (prog, g) = setup(&["C: x >= 0 && v == 0 && 0 <= x", "C: gx > 1", "C: 0 == v && n > x"]);
    let s = Sigma::from_facts(&g);
    // `0 == v` is `C.v == 0` again; `gx > 1` speaks of constants only.
    assert_eq!(shown(&prog, &s), vec!["0 <= C.x", "C.v == 0", "C.x < n"]);
    let clock = Expr { kind: ExprKind::Var(Var::Clock), sort: Sort::Real, loc: Loc::default() };
    let mut t = s.clone();
    t.assume(&binary(BinOp::Le, &clock, &g[1]));
    assert_eq!(t, s, "facts about clock describe no single state");
}

#[test]
fn forgetting_values_by_binding_site() {
    let (prog, g) = setup(&["C: n > x && v == 0"]);
    let mut s = Sigma::from_facts(&g);
    let n = ValueId(prog.values.iter().position(|v| v.name == "n").expect("n") as u32);
    s.forget_values(&[n]);
    assert_eq!(shown(&prog, &s), vec!["C.v == 0"]);
}

/// The refinements `n == 0` of two payload fields that are both named `n`.
fn two_values_named_n() -> (Program, Expr, Expr, ValueId, ValueId) {
    let (prog, d) = lower_src(&format!(
        "{SRC} choreography G = C -> A : first(n: real {{n == 0}}). A -> C : second(n: real {{n == 0}}). end;"
    ));
    assert!(d.is_empty(), "{d:?}");
    let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else { panic!("a sequence") };
    let fields: Vec<Field> = items
        .iter()
        .filter_map(|g| match g {
            Global::Msg(m) => m.payload.first().cloned(),
            _ => None,
        })
        .collect();
    let [a, b] = &fields[..] else { panic!("two messages") };
    let r = |f: &Field| f.refinement.clone().expect("refinement");
    (prog, r(a), r(b), a.value, b.value)
}

/// Shadowing: a fact about one `n` is no fact about another `n`. The loop fixpoint
/// keeps a candidate fact only if every `t` reached `contains` it, the `*` conjoins
/// the sides' facts, and the join keeps the shared ones: all by identity. (Before,
/// values compared by name and the second `n == 0` "re-established" the first.)
#[test]
fn same_named_values_are_different_facts() {
    let (prog, first, second, n1, n2) = two_values_named_n();
    assert_ne!(n1, n2);
    assert_ne!(first, second, "equal by name, different by binding site");
    let s = Sigma::from_facts([&first]);
    assert!(!s.contains(&second));
    assert!(s.join(&Sigma::from_facts([&second]), &prog).is_empty());
    let mut both = s.clone();
    both.meet(Sigma::from_facts([&second]));
    assert_eq!(both.len(), 2);
    // Forgetting the second `n` (it is rebound) keeps what is known of the first.
    both.forget_values(&[n2]);
    assert_eq!(both, s);
    assert_eq!(shown(&prog, &both), vec!["n == 0"]);
}

#[test]
fn initial_context_is_init_and_invariant() {
    let (prog, _) = setup(&[]);
    let s = Sigma::initial(&prog, prog.role_ids());
    assert_eq!(
        shown(&prog, &s),
        vec!["C.x == 0", "C.v == 0", "-10 <= C.x", "C.x <= 10", "cz <= A.ze", "0 <= A.ze", "A.ze <= 1"]
    );
}

#[test]
fn a_post_with_old_keeps_what_was_known() {
    // Sec 3.5's m_idle: `x == old(x)`. Before, the cart is at gx.
    let (prog, g) = setup(&["C: x == gx && v == 0 && n > x"]);
    let c = role(&prog, "C");
    let mut s = Sigma::from_facts(&g);
    s.apply_motion(&prog, c, prim(&prog, "idle"), &[]);
    assert_eq!(shown(&prog, &s), vec!["gx < n", "C.x == gx", "C.v == 0", "-10 <= C.x", "C.x <= 10"]);
}

#[test]
fn a_move_replaces_the_position_and_keeps_facts_about_values() {
    let (prog, _) = setup(&["C: n > x"]);
    let c = role(&prog, "C");
    let mut s = Sigma::initial(&prog, [c]);
    let (_, g) = setup(&["C: n > x"]);
    s.assume(&g[0]);
    s.apply_motion(&prog, c, prim(&prog, "move"), &[constant(&prog, "gx")]);
    // `old(C.x) == 0` defines the snapshot: `C.x < n` before is `0 < n` now.
    assert_eq!(shown(&prog, &s), vec!["0 < n", "C.x == gx", "C.v == 0", "-10 <= C.x", "C.x <= 10"]);
}

#[test]
fn one_level_of_snapshots() {
    // Nothing defines the snapshot: facts about it stay, until the next motion.
    let (prog, g) = setup(&["C: x >= 1"]);
    let c = role(&prog, "C");
    let mut s = Sigma::from_facts(&g);
    let one = Expr { kind: ExprKind::Int(1), sort: Sort::Int, loc: Loc::default() };
    s.apply_motion(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
    assert_eq!(shown(&prog, &s), vec!["1 <= old(C.x)", "C.x == old(C.x) + 1", "-10 <= C.x", "C.x <= 10"]);
    s.apply_motion(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
    // The first snapshot is gone with every fact about it.
    assert_eq!(
        shown(&prog, &s),
        vec!["-10 <= old(C.x)", "old(C.x) <= 10", "C.x == old(C.x) + 1", "-10 <= C.x", "C.x <= 10"]
    );
    let again = {
        let mut t = s.clone();
        t.apply_motion(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
        t
    };
    assert_eq!(again, s, "a loop of steps reaches a fixpoint");
}

#[test]
fn arguments_are_evaluated_when_the_motion_starts() {
    // `dt<C: step(x)>`: the argument reads the state before the motion.
    let (prog, g) = setup(&["C: x == 2"]);
    let c = role(&prog, "C");
    let x = var(Var::Role(c, Slot::State(0)), &Sort::Real);
    let mut s = Sigma::from_facts(&g);
    s.apply_motion(&prog, c, prim(&prog, "step"), &[x]);
    assert_eq!(shown(&prog, &s), vec!["C.x == 4", "-10 <= C.x", "C.x <= 10"]);
}

#[test]
fn number_literals_are_computed_exactly() {
    let (prog, g) = setup(&[
        "C: x == 0 + 0.5 - 0.5",
        "C: v == 0.1 + 0.2",
        "C: x <= 1 - 2.5",
        "C: n == 1.5 * 2 + 1e-3",
        "C: x == n * (2 + 1)",
        "C: v < 9223372036854775807 + 1",
        "C: v <= 1e-2147483648 + 1",
    ]);
    let s = Sigma::from_facts(&g);
    assert_eq!(
        shown(&prog, &s),
        vec![
            "C.x == 0",
            "C.v == 0.3",
            "C.x <= -1.5",
            "n == 3.001",
            "C.x == n * 3",
            "C.v < 9223372036854775807 + 1",
            "C.v <= 1e-2147483648 + 1"
        ]
    );
    // PGCD's lanes: forward half a metre and back again is where the cart started.
    let c = role(&prog, "C");
    let mut s = Sigma::from_facts(&g[..1]);
    let half = |neg: bool| {
        let lit = Expr { kind: ExprKind::Real("0.5".into()), sort: Sort::Real, loc: Loc::default() };
        if neg {
            Expr {
                kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(lit)),
                sort: Sort::Real,
                loc: Loc::default(),
            }
        } else {
            lit
        }
    };
    let start = {
        let mut t = s.clone();
        t.apply_motion(&prog, c, prim(&prog, "step"), &[half(true)]);
        t.apply_motion(&prog, c, prim(&prog, "step"), &[half(false)]);
        t
    };
    s.apply_motion(&prog, c, prim(&prog, "step"), &[half(false)]);
    assert_eq!(shown(&prog, &s), vec!["C.x == 0.5", "-10 <= C.x", "C.x <= 10"]);
    s.apply_motion(&prog, c, prim(&prog, "step"), &[half(true)]);
    assert_eq!(shown(&prog, &s), vec!["C.x == 0", "-10 <= C.x", "C.x <= 10"]);
    assert_eq!(s, start);
}

#[test]
fn min_and_max_simplify_where_the_context_orders_them() {
    let (prog, _) = setup(&[]);
    let a = role(&prog, "A");
    let mut s = Sigma::initial(&prog, [a]);
    s.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    // `cz <= old(A.ze)` makes `min(cz, old(A.ze))` just `cz`.
    assert_eq!(
        shown(&prog, &s),
        vec![
            "cz <= old(A.ze)",
            "0 <= old(A.ze)",
            "old(A.ze) <= 1",
            "cz <= A.ze",
            "A.ze <= old(A.ze)",
            "0 <= A.ze",
            "A.ze <= 1"
        ]
    );
    // A second motion forgets `cz <= old(A.ze)` but `cz <= A.ze` survived, as `cz <= old(A.ze)`.
    s.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    assert!(shown(&prog, &s).contains(&"cz <= A.ze".to_string()), "{:?}", shown(&prog, &s));
}

#[test]
fn joint_motions_move_every_part() {
    let (prog, _) = setup(&[]);
    let (c, a) = (role(&prog, "C"), role(&prog, "A"));
    let mut s = Sigma::initial(&prog, prog.role_ids());
    let idle = PrimApp { prim: prim(&prog, "idle"), args: vec![], loc: Loc::default() };
    let work = PrimApp { prim: prim(&prog, "work"), args: vec![], loc: Loc::default() };
    s.apply_joint_motion(&prog, &[(c, idle), (a, work)]);
    let facts = shown(&prog, &s);
    for f in ["C.x == 0", "C.v == 0", "cz <= A.ze"] {
        assert!(facts.contains(&f.to_string()), "{f} in {facts:?}");
    }
}

#[test]
fn restriction_to_participants() {
    let (prog, g) = setup(&["C: x == 0 && n > 0", "A: ze >= C.x", "A: ze <= 1"]);
    let s = Sigma::from_facts(&g);
    let (c, a) = (role(&prog, "C"), role(&prog, "A"));
    assert_eq!(shown(&prog, &s.restrict(&[c])), vec!["C.x == 0", "0 < n"]);
    assert_eq!(shown(&prog, &s.restrict(&[a])), vec!["0 < n", "A.ze <= 1"]);
    assert_eq!(shown(&prog, &s.restrict(&[a, c])), shown(&prog, &s));
    let parts = s.split(&[vec![c], vec![a]]);
    assert_eq!(parts[0], s.restrict(&[c]));
    assert_eq!(parts[1], s.restrict(&[a]));
}

#[test]
fn meet_join_and_containment() {
    let (prog, g) = setup(&["C: x == 0", "C: v == 0", "C: n > 0"]);
    let ab = Sigma::from_facts(&g[..2]);
    let bc = Sigma::from_facts(&g[1..]);
    assert_eq!(shown(&prog, &ab.join(&bc, &prog)), vec!["C.v == 0"]);
    let mut all = ab.clone();
    all.meet(bc.clone());
    assert_eq!(all, Sigma::from_facts(&g));
    assert!(all.contains_all(&ab) && all.contains_all(&bc) && !ab.contains_all(&all));
}

#[test]
fn join_weakens_bounds_by_literals() {
    let (prog, g) = setup(&["C: x == 0", "C: x == 1.5", "C: 1 <= x", "C: x > 2", "C: v < 1 && x <= n"]);
    let one = |i: usize| Sigma::from_facts(&g[i..=i]);
    // Two positions: the interval between them.
    assert_eq!(shown(&prog, &one(0).join(&one(1), &prog)), vec!["0 <= C.x", "C.x <= 1.5"]);
    assert_eq!(shown(&prog, &one(1).join(&one(0), &prog)), vec!["0 <= C.x", "C.x <= 1.5"]);
    // The weaker lower bound, strictness included; a bound on one side only goes.
    assert_eq!(shown(&prog, &one(2).join(&one(3), &prog)), vec!["1 <= C.x"]);
    assert_eq!(shown(&prog, &one(3).join(&one(2), &prog)), vec!["1 <= C.x"]);
    assert_eq!(shown(&prog, &one(3).join(&one(4), &prog)), Vec::<String>::new());
    // What is common is kept as it is; nothing weaker is added beside it.
    let mut a = one(2);
    a.assume(&g[1]);
    assert_eq!(shown(&prog, &a.join(&one(2), &prog)), vec!["1 <= C.x"]);
}

/// The elimination of snapshots as a plain loop (the implementation before the index
/// of snapshot uses): take the first definition in the order of the facts, rewrite every
/// fact, keep the first of equal facts. Quadratic, but obviously what the documentation
/// says: the oracle of the indexed [`Sigma::eliminate_snapshots`].
fn eliminate_snapshots_plain(s: &mut Sigma) -> bool {
    use crate::hir::expr::{map_vars, mentions};
    fn definition(s: &Sigma, ground: bool) -> Option<(usize, Var, Expr)> {
        let is_snap = |v: &Var| matches!(v, Var::Snap(..));
        s.facts.iter().enumerate().find_map(|(i, f)| {
            let ExprKind::Binary(BinOp::Eq, a, b) = &f.kind else { return None };
            [(a, b), (b, a)].into_iter().find_map(|(x, e)| {
                let ExprKind::Var(v @ Var::Snap(..)) = &x.kind else { return None };
                let free = if ground { !mentions(e, &is_snap) } else { !mentions(e, &|w| w == v) };
                free.then(|| (i, v.clone(), (**e).clone()))
            })
        })
    }
    let mut changed = false;
    while let Some((i, v, def)) = definition(s, true).or_else(|| definition(s, false)) {
        changed = true;
        let facts = std::mem::take(&mut s.facts);
        s.set.clear();
        for (j, f) in facts.into_iter().enumerate() {
            if j == i {
                continue;
            }
            if !mentions(&f, &|w| *w == v) {
                s.insert(f);
                continue;
            }
            let g = map_vars(&f, &mut |w, _| if *w == v { Some(def.clone()) } else { None });
            s.insert(normalize(g));
        }
    }
    changed
}

/// Random contexts over two participants' variables, their snapshots and small literals
/// (definitions, chains of definitions, cycles, facts that become equal or reflexive
/// once rewritten): the indexed elimination gives the plain loop's facts, in its order.
#[test]
fn indexed_snapshot_elimination_is_the_plain_loop() {
    let (prog, _) = setup(&[]);
    let roles = [role(&prog, "C"), role(&prog, "A")];
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = |k: u64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed % k
    };
    let mut changed = 0;
    for _ in 0..3000 {
        let term = |next: &mut dyn FnMut(u64) -> u64| -> Expr {
            let r = roles[next(2) as usize];
            let slot = Slot::State(next(2) as usize);
            let atom = match next(5) {
                0 | 1 => var(Var::Snap(r, slot), &Sort::Real),
                2 | 3 => var(Var::Role(r, slot), &Sort::Real),
                _ => Expr { kind: ExprKind::Int(next(3) as i64), sort: Sort::Int, loc: Loc::default() },
            };
            if next(4) == 0 {
                let k = Expr { kind: ExprKind::Int(next(3) as i64), sort: Sort::Int, loc: Loc::default() };
                Expr {
                    kind: ExprKind::Binary(BinOp::Add, Box::new(atom), Box::new(k)),
                    sort: Sort::Real,
                    loc: Loc::default(),
                }
            } else {
                atom
            }
        };
        let mut s = Sigma::new();
        for _ in 0..(2 + next(14)) {
            let op = [BinOp::Eq, BinOp::Eq, BinOp::Le, BinOp::Lt][next(4) as usize];
            let (a, b) = (term(&mut next), term(&mut next));
            s.assume(&binary(op, &a, &b));
        }
        let mut plain = s.clone();
        let a = s.eliminate_snapshots();
        let b = eliminate_snapshots_plain(&mut plain);
        assert_eq!(a, b);
        assert_eq!(s.facts(), plain.facts(), "from the same context");
        assert!(s.facts().iter().all(|f| s.contains(f)) && s.set.len() == s.facts().len());
        changed += usize::from(a);
    }
    assert!(changed > 500, "the cases exercise the elimination: {changed}");
}

/// One joint motion of `n` carts, each in its own lane (the wide `dt`, as
/// `examples/common/lanes.rs` generates it): the program and the motion's parts.
fn wide_dt(n: usize) -> (Program, Vec<(RoleId, PrimApp)>) {
    let mut src = String::from(
        "robot Cart { state x: real, y: real; invariant: -10 <= x <= 10 && y >= 0; }
         motion Cart.cruise(d: real) { interruptible: true; pre: d > 0 && x + d <= 10;
           post: old(x) <= x <= old(x) + d && y == old(y); }
         system S {",
    );
    for i in 0..n {
        src.push_str(&format!(" participant C{i}: Cart {{ init: x == 0 && y == 0.65 * {i}.0; }}"));
    }
    let parts: Vec<String> = (0..n).map(|i| format!("C{i}: cruise(0.5)")).collect();
    src.push_str(&format!(" }} choreography G = dt<{}>. end;", parts.join(", ")));
    let (prog, d) = lower_src(&src);
    assert!(d.is_empty(), "{d:?}");
    let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else { panic!("a sequence") };
    let Some(Global::Motion(m)) = items.first() else { panic!("a motion") };
    let parts = m.parts.clone();
    (prog, parts)
}

/// The effect of a joint motion grows linearly with its participants: eliminating the
/// snapshot of each of n carts touches the facts about that cart, not all of Σ. (With
/// the plain loop, in a debug build, 200 carts took 0.64 s and 800 carts 11.8 s.)
#[test]
#[ignore = "a timing ratio, for a quiet machine: `cargo test -- --ignored`; the pipeline benchmark measures the wide dt"]
fn a_wide_joint_motion_takes_time_linear_in_its_participants() {
    let time = |n: usize| {
        let (prog, parts) = wide_dt(n);
        let start = Sigma::initial(&prog, prog.role_ids());
        let mut best = std::time::Duration::MAX;
        let mut after = Sigma::new();
        for _ in 0..3 {
            let mut s = start.clone();
            let t = std::time::Instant::now();
            s.apply_joint_motion(&prog, &parts);
            best = best.min(t.elapsed());
            after = s;
        }
        // Every cart's start is eliminated: `0 <= Ci.x <= 0.5`, its lane, its invariant (3).
        assert!(!after.facts().iter().any(|f| crate::hir::expr::mentions(f, &|v| matches!(v, Var::Snap(..)))));
        assert_eq!(after.len(), 6 * n, "{:?}", shown(&prog, &after).iter().take(12).collect::<Vec<_>>());
        best
    };
    // The plain loop was x64 at eight times the carts.
    crate::testing::assert_near_linear("carts", 100, 800, time);
}

/// A loop whose rounds end lower than they start: the arm starts at `cz <= A.ze`, a round
/// leaves it at `0.1 <= old(A.ze)` with `min(cz, old(A.ze)) <= A.ze` (`work` keeps it at
/// least where it was, or at cz). The loop head's join keeps the weaker bound `0.1 <= A.ze`,
/// which the round's facts imply (the smaller of cz = 0.2 and 0.1), rather than nothing.
#[test]
fn the_join_keeps_a_bound_the_other_side_implies_through_min() {
    let (prog, g) = setup(&["A: ze >= 0.1"]);
    let a = role(&prog, "A");
    let start = Sigma::initial(&prog, [a]);
    let mut round = Sigma::from_facts(&g);
    round.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    assert!(
        !shown(&prog, &round).contains(&"0.1 <= A.ze".to_string()),
        "implied, not stated: {:?}",
        shown(&prog, &round)
    );
    for joined in [start.join(&round, &prog), round.join(&start, &prog)] {
        assert!(shown(&prog, &joined).contains(&"0.1 <= A.ze".to_string()), "{:?}", shown(&prog, &joined));
        assert!(!shown(&prog, &joined).contains(&"cz <= A.ze".to_string()), "{:?}", shown(&prog, &joined));
    }
    // Without a bound on the snapshot, `min(cz, old(A.ze))` bounds nothing: only the
    // invariant's `0 <= A.ze` is common.
    let mut blind = Sigma::new();
    blind.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    let joined = start.join(&blind, &prog);
    assert!(
        shown(&prog, &joined).iter().all(|f| !f.contains("0.1") && !f.contains("cz")),
        "{:?}",
        shown(&prog, &joined)
    );
}

/// A motion forgets the snapshot of the one before, but keeps the bounds by constants
/// its facts imply for the current state: two `work`s after `0.1 <= A.ze` still know
/// `0.1 <= old(A.ze)` (so a later precondition `0.05 <= A.ze` follows).
#[test]
fn a_motion_keeps_the_bounds_the_forgotten_snapshot_implied() {
    let (prog, g) = setup(&["A: ze >= 0.1"]);
    let a = role(&prog, "A");
    let mut s = Sigma::from_facts(&g);
    s.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    s.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    let facts = shown(&prog, &s);
    assert!(facts.contains(&"0.1 <= old(A.ze)".to_string()), "{facts:?}");
    // A third round adds nothing new: the bounds come from a finite set of terms.
    let mut again = s.clone();
    again.apply_motion(&prog, a, prim(&prog, "work"), &[]);
    assert_eq!(again, s, "{:?}", shown(&prog, &again));
}

/// Bounds are compared by the constants' exact values; a `min` of two constants the
/// values cannot order bounds nothing from below (neither is implied).
#[test]
fn bounds_by_constants_compare_by_exact_value_and_never_guess() {
    let src = SRC.replace(
        "const cz: real = 0.2;",
        "const cz: real = 0.2; const pz: real = pi / 16; const qz: real = 0.196349540849362077403915211454;",
    );
    let (prog, d) = lower_src(&format!("{src} choreography G = C -> A : [A.ze >= pz] m. end;"));
    assert!(d.is_empty(), "{d:?}");
    let a = role(&prog, "A");
    let pz = constant(&prog, "pz");
    let qz = constant(&prog, "qz");
    let ze = var(Var::Role(a, Slot::State(0)), &Sort::Real);
    let old_ze = var(Var::Snap(a, Slot::State(0)), &Sort::Real);
    let min = |x: &Expr, y: &Expr| Expr {
        kind: ExprKind::Call(Builtin::Min, vec![x.clone(), y.clone()]),
        sort: Sort::Real,
        loc: Loc::default(),
    };
    // pi / 16 = 0.1963495408493620774039152114549... and qz agree to 30 digits: the enclosure
    // of pi (20 decimals) cannot order them.
    let s = Sigma::from_facts(&[binary(BinOp::Le, &pz, &old_ze), binary(BinOp::Le, &min(&qz, &old_ze), &ze)]);
    let start = Sigma::from_facts(&[binary(BinOp::Le, &qz, &ze)]);
    let joined = start.join(&s, &prog);
    assert!(joined.is_empty(), "{:?}", shown(&prog, &joined));
    // With cz (0.2 > pi / 16) the order is decided: the bound is pi / 16.
    let cz = constant(&prog, "cz");
    let s = Sigma::from_facts(&[binary(BinOp::Le, &pz, &old_ze), binary(BinOp::Le, &min(&cz, &old_ze), &ze)]);
    let start = Sigma::from_facts(&[binary(BinOp::Le, &cz, &ze)]);
    assert_eq!(shown(&prog, &start.join(&s, &prog)), vec!["pz <= A.ze"]);
}
