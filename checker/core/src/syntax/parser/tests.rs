//! Unit tests of the parser: each part of the grammar, recovery and the nesting bound.

use super::*;

fn global(src: &str) -> Global {
    let (g, d) = parse_global(FileId(0), src);
    assert!(d.is_empty(), "{d:?}");
    g.expect("parses")
}

#[test]
fn sequence_binds_tighter_than_star_and_choice() {
    let g = global("p -> q : a. dt<p: m> * dt<r: n> + p -> q : b. t");
    let Global::Choice(branches, _) = g else { panic!("expected a choice") };
    assert_eq!(branches.len(), 2);
    let Global::Par(sides, _) = &branches[0] else { panic!("expected `*` in the first branch") };
    assert!(matches!(&sides[0], Global::Seq(items, _) if items.len() == 2));
}

#[test]
fn mu_extends_to_the_right() {
    let g = global("mu t. p -> q : a. t");
    let Global::Rec { body, .. } = g else { panic!("expected mu") };
    assert!(matches!(*body, Global::Seq(ref v, _) if v.len() == 2));
}

#[test]
fn message_with_guard_and_refined_payload() {
    let g = global("Cart -> Arm : [x > 0] arrive(t: real { t >= 1.5 }, y: int)");
    let Global::Msg(m) = g else { panic!("expected a message") };
    assert!(m.guard.is_some());
    assert_eq!(m.payload.len(), 2);
    assert!(m.payload[0].refinement.is_some());
}

#[test]
fn comparison_chains_are_conjunctions() {
    let (e, d) = parse_expr(FileId(0), "a <= x <= b");
    assert!(d.is_empty());
    assert!(matches!(e.unwrap().kind, ExprKind::Binary(BinOp::And, _, _)));
}

#[test]
fn comparison_chains_of_any_length_are_conjunctions_of_neighbours() {
    let (e, d) = parse_expr(FileId(0), "1 < 2 < 3 < 4");
    assert!(d.is_empty(), "{d:?}");
    // ((1 < 2 && 2 < 3) && 3 < 4)
    let ExprKind::Binary(BinOp::And, l, r) = e.unwrap().kind else { panic!("expected &&") };
    assert!(matches!(l.kind, ExprKind::Binary(BinOp::And, _, _)));
    let ExprKind::Binary(BinOp::Lt, a, b) = r.kind else { panic!("expected 3 < 4") };
    assert!(matches!((a.kind, b.kind), (ExprKind::Int(3), ExprKind::Int(4))));
    // A parenthesised comparison is an operand, not the start of a chain.
    let (e, _) = parse_expr(FileId(0), "(x < y) == b");
    assert!(matches!(e.unwrap().kind, ExprKind::Binary(BinOp::Eq, _, _)));
}

#[test]
fn operator_chains_count_as_nesting() {
    for src in [format!("{}1", "2 ^ ".repeat(10_000)), format!("1{}", " + 1".repeat(10_000))] {
        let (_, d) = parse_expr(FileId(0), &src);
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].code, Code::TooDeep);
    }
    let (_, d) = parse_expr(FileId(0), &format!("1{}", " + 1".repeat(900)));
    assert!(d.is_empty(), "{d:?}");
}

#[test]
fn sorts_and_field_chains_count_as_nesting() {
    // Before: a sort nested a million deep overflowed the stack (a crash, not an error).
    on_big_stack(|| {
        let deep_sort = format!("const a: {}int{} = 1;", "(".repeat(1_000_000), ")".repeat(1_000_000));
        let dots = format!("const a = x{};", ".y".repeat(100_000));
        for src in [deep_sort, dots] {
            let (_, d) = parse(FileId(0), &src);
            assert_eq!(d.len(), 1, "{d:?}");
            assert_eq!(d[0].code, Code::TooDeep);
        }
    });
}

#[test]
fn process_sum_of_inputs_with_default_motion() {
    let (f, d) = parse(FileId(0), "process A = p?a(x).dt<m>.X + p?b.end + dt<idle>.X;");
    assert!(d.is_empty(), "{d:?}");
    let Item::Process(p) = &f.items[0] else { panic!() };
    assert!(matches!(&p.body, Process::Sum(v, _) if v.len() == 3));
}

#[test]
fn local_types_parse() {
    let (t, d) = parse_local(FileId(0), "mu t. +{ [x > 0] B!a(v: real).dt<m /\\ n>.t, B!b.end }");
    assert!(d.is_empty(), "{d:?}");
    assert!(matches!(t, Some(Local::Rec { .. })));
    let (t, d) = parse_local(FileId(0), "&{ A?a.t, A?b.end } & dt<idle>.t");
    assert!(d.is_empty(), "{d:?}");
    assert!(matches!(t, Some(Local::Recv { default: Some(_), .. })));
}

/// Runs `f` on a thread with a large stack: dropping (and later stages walking) a
/// 100,000-step process recurses once per step, beyond a test thread's 2 MiB.
fn on_big_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new().stack_size(256 << 20).spawn(f).expect("thread").join().expect("no panic");
}

#[test]
fn long_sequences_are_not_nesting() {
    on_big_stack(|| {
        let n = 100_000;
        let src = format!(
            "choreography C = {}end;\nprocess A = {}end;\nlocal A = {}end;\nlocal B = {}end;",
            "A -> B : m.\n".repeat(n),
            "dt<w>.B!m(1).B?r(x).".repeat(n / 2),
            "dt<w>.B!m.".repeat(n / 2),
            "A?m(x: real).".repeat(n)
        );
        let (f, d) = parse(FileId(0), &src);
        assert!(d.is_empty(), "{:?}", &d[..d.len().min(3)]);
        let Item::Process(p) = &f.items[1] else { panic!("a process") };
        let (mut steps, mut cur) = (0, &p.body);
        while let Process::Motion { cont, .. } | Process::Send { cont, .. } | Process::Recv { cont, .. } = cur {
            steps += 1;
            cur = cont;
        }
        assert_eq!(steps, 3 * n / 2);
        assert!(matches!(cur, Process::End(_)));
        let Item::Local(l) = &f.items[2] else { panic!("a local type") };
        let Local::Motion { span, .. } = &l.body else { panic!("a motion") };
        assert_eq!(span.end, l.span.end - 1, "the span covers the sequence up to its `end`");
    });
}

#[test]
fn errors_recover_at_the_next_item() {
    let (f, d) = parse(FileId(0), "const a = ;\nconst b = 2;\nrobot R { state x: real; bogus; }\nconst c = 3;");
    assert_eq!(f.items.len(), 3, "{:?}", f.items);
    assert_eq!(d.len(), 2, "{d:?}");
    assert!(d.iter().all(|d| d.code == Code::UnexpectedToken));
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let src = format!("const a = {}1{};", "(".repeat(5000), ")".repeat(5000));
    let (_, d) = parse(FileId(0), &src);
    assert!(d.iter().any(|d| d.message.contains("nesting deeper") && d.code == Code::TooDeep));
}

fn file(src: &str) -> (File, Vec<Diagnostic>) {
    parse(FileId(0), src)
}

#[test]
fn robots_have_bodies_of_placed_shapes_and_mounts() {
    let (f, d) = file(
        "robot Cart { state x: real, th: real;
           geometry: box(l, 0.4, 0.1) at pose(x, 0, 0, 0, 0, th) + cylinder(0.05, 0.3) + urdf(\"p.urdf\") at pose(0, 0, 1);
           mount deck: pose(x, 0, 0.1, 0, 0, th);
           invariant: x >= 0; }",
    );
    assert!(d.is_empty(), "{d:?}");
    let Item::Robot(r) = &f.items[0] else { panic!("a robot") };
    let parts = &r.geometry[0].parts;
    assert_eq!(parts.len(), 3);
    assert_eq!(parts[0].shape.name.name, "box");
    assert_eq!(parts[0].shape.args.len(), 3);
    assert_eq!(parts[0].place.as_ref().map(|p| p.args.len()), Some(6));
    assert!(parts[1].place.is_none());
    assert_eq!(parts[2].shape.path.as_ref().map(|(p, _)| p.as_str()), Some("p.urdf"));
    assert_eq!(r.mounts.len(), 1);
    assert_eq!(r.mounts[0].name.name, "deck");
    assert!(r.invariant.is_some());
}

#[test]
fn footprints_are_predicates_the_own_geometry_or_shapes() {
    let (f, d) = file(
        "motion C.a { footprint: geometry; interruptible: true; }
         motion C.b { footprint: box(1, 1, 1) at pose(old(x), 0, 0) + sphere(r); }
         motion C.c { footprint(px, py, pz): px >= 0; }",
    );
    assert!(d.is_empty(), "{d:?}");
    let field = |i: usize| match &f.items[i] {
        Item::Motion(m) => m.fields[0].value.clone(),
        _ => panic!("a motion"),
    };
    assert!(matches!(field(0), FieldValue::OwnGeometry(_)));
    assert!(matches!(field(1), FieldValue::Body(b) if b.parts.len() == 2));
    assert!(matches!(field(2), FieldValue::Footprint { .. }));
}

#[test]
fn systems_have_mounted_participants_and_obstacles() {
    let (f, d) = file(
        "system S {
           participant C: Cart { init: x == 0; at: pose(0, 0, 0); }
           obstacle Bridge { geometry: box(0.1, 1, 0.6) at pose(0, -0.55, 0) + box(0.1, 1.2, 0.05); at: pose(2, 0, 0); }
           participant A: Arm { on: C.deck; at: pose(0, 0, 0, 0, 0, pi / 2); }
           obstacle Pillar { geometry: cylinder(0.1, 2); }
         }",
    );
    assert!(d.is_empty(), "{d:?}");
    let Item::System(s) = &f.items[0] else { panic!("a system") };
    assert_eq!(s.participants.len(), 2);
    assert_eq!(s.obstacles.len(), 2);
    let on = &s.participants[1].on[0];
    assert_eq!((on.carrier.name.as_str(), on.mount.name.as_str()), ("C", "deck"));
    assert_eq!(s.obstacles[0].geometry[0].parts.len(), 2);
    assert_eq!(s.obstacles[0].at.len(), 1);
    assert!(s.obstacles[1].at.is_empty());
}

#[test]
fn a_bad_shape_or_pose_does_not_cascade() {
    // A malformed part is one error; the rest of the block and the file still parse.
    let (f, d) = file(
        "robot R { state x: real; geometry: box(1,, 2) at pose(x); mount m: pos(1, 2, 3); invariant: x >= 0; }
         system S { obstacle O { geometry: sphere(1) at; at: pose(1, 0, 0); } participant P: R { on: C; } participant Q: R; }",
    );
    assert_eq!(d.len(), 4, "{d:?}");
    assert!(d.iter().all(|d| d.code == Code::UnexpectedToken));
    let Item::Robot(r) = &f.items[0] else { panic!("a robot") };
    assert!(r.invariant.is_some());
    let Item::System(s) = &f.items[1] else { panic!("a system") };
    assert_eq!(s.obstacles[0].at.len(), 1);
    assert_eq!(s.participants.len(), 2);
    // An unknown shape name is not a parse error: lowering says which shapes exist (E0214).
    let (_, d) = file("robot R { geometry: cone(1, 2) + boxx(1); }");
    assert!(d.is_empty(), "{d:?}");
    // A system entry that is none of them names them all.
    let (_, d) = file("system S { obstacl O { } }");
    assert!(d[0].message.contains("`participant`, `stream` or `obstacle`"), "{}", d[0].message);
}

/// A label's key is a command name or a string literal, kept as the wire reads it (up to
/// its first NUL); anything else is E0103. The guard's `[` comes before the label, so the
/// `[` after it is the key.
#[test]
fn labels_take_a_command_or_a_name_as_their_key() {
    let label = |src: &str| match global(src) {
        Global::Msg(m) => (m.label.name, m.guard.is_some()),
        other => panic!("expected a message: {other:?}"),
    };
    assert_eq!(label("p -> q : COMMAND_LONG[MAV_CMD_X]"), ("COMMAND_LONG[MAV_CMD_X]".to_string(), false));
    assert_eq!(label("p -> q : [x > 0] PARAM_SET[\"MC_X\"](v)"), ("PARAM_SET[\"MC_X\"]".to_string(), true));
    assert_eq!(label("p -> q : PARAM_SET[\"MC_X\0Y\"]"), ("PARAM_SET[\"MC_X\"]".to_string(), false));
    assert_eq!(label("p -> q : PARAM_SET[\"\"]"), ("PARAM_SET[\"\"]".to_string(), false));
    let (_, d) = parse_global(FileId(0), "p -> q : PARAM_SET[3]");
    assert_eq!(d.iter().map(|d| d.code.as_str()).collect::<Vec<_>>(), ["E0103"]);
}
