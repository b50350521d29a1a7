//! Bodies (LANGUAGE.md, Robots, Motion primitives, Systems; Sec 3.1's `geom(p)`): a
//! robot kind's `geometry:` and `mount`s, a primitive's geometric footprint, a system's
//! obstacles, and the `on: Carrier.mount` of a mounted participant. Each place reads
//! only what it may (E0211, the place named): a kind's geometry and mounts its **state**
//! and constants (a body cannot depend on another robot, so no inputs); a geometric
//! footprint also `old(...)`, parameters and `clock`; an obstacle constants only.
//! Shapes and their arguments are E0214, `footprint: geometry` without a body E0215,
//! mount cycles E0216, an obstacle used as a participant E0217, unknown mounts E0218.

use super::*;
use crate::hir::body::{Body, BodyPart, Mount, MountedOn, Obstacle, Pose, Shape};

/// The shapes, as the diagnostics list them.
const SHAPES: &str =
    "`box(lx, ly, lz)`, `sphere(r)`, `cylinder(r, h)`, `capsule(r, h)`, `urdf(\"file.urdf\")`, `mesh(\"file.stl\")`";

/// The place a kind's `geometry:` is lowered in (E0211 messages name it).
pub(super) const KIND_GEOMETRY: &str = "a robot's geometry";
pub(super) const MOUNT: &str = "a mount";
pub(super) const GEOMETRIC_FOOTPRINT: &str = "a geometric footprint";
pub(super) const OBSTACLE: &str = "an obstacle";

/// Whether `part` is one of the places of this module (for [`Lowerer::not_allowed`]).
pub(super) fn is_body_place(part: &str) -> bool {
    [KIND_GEOMETRY, MOUNT, GEOMETRIC_FOOTPRINT, OBSTACLE].contains(&part)
}

impl Lowerer {
    /// A kind's `geometry:` and `mount`s, after all kinds and constants are known (and
    /// before the primitives, whose `footprint: geometry` reads the body).
    pub(super) fn robot_body(&mut self, r: &ast::RobotDecl) {
        let Some(&kind) = self.kinds.get(&r.name.name) else { return };
        if self.kind_spans[kind.idx()] != r.name.span {
            return; // a duplicate kind, already reported
        }
        let env = Env { who: Who::Kind(kind), state: true, part: Some(KIND_GEOMETRY), ..Env::consts_only() };
        if let Some((first, rest)) = r.geometry.split_first() {
            for g in rest {
                let d = dup(g.span, "field", "geometry", first.span);
                self.diags.push(d);
            }
            self.kinds_with_geometry.insert(kind);
            self.prog.kinds[kind.idx()].body = self.body(first, &env);
        }
        let env = Env { part: Some(MOUNT), ..env };
        let names: Vec<&ast::Ident> = r.mounts.iter().map(|m| &m.name).collect();
        super::distinct("mount", names, &mut self.diags);
        let mut mounts: Vec<Mount> = Vec::new();
        for m in &r.mounts {
            if mounts.iter().any(|k| k.name == m.name.name) {
                continue;
            }
            let pose = self.pose(&m.pose, &env);
            mounts.push(Mount { name: m.name.name.clone(), pose, span: m.span });
        }
        self.prog.kinds[kind.idx()].mounts = mounts;
    }

    /// A body in `env`; `None` (with the errors reported) if a part is malformed.
    pub(super) fn body(&mut self, b: &ast::BodyAst, env: &Env) -> Option<Body> {
        let mut parts = Vec::new();
        let mut ok = true;
        for p in &b.parts {
            let shape = self.shape(&p.shape, env);
            let place = p.place.as_ref().map(|pose| self.pose(pose, env));
            match shape {
                Some(shape) => parts.push(BodyPart { shape, place, span: p.span }),
                None => ok = false,
            }
        }
        ok.then_some(Body { parts, span: b.span })
    }

    fn shape(&mut self, s: &ast::ShapeAst, env: &Env) -> Option<Shape> {
        let name = s.name.name.as_str();
        let arity = match name {
            "box" => 3,
            "sphere" => 1,
            "cylinder" | "capsule" => 2,
            "urdf" | "mesh" => 0,
            _ => {
                let near = ["box", "sphere", "cylinder", "capsule", "urdf", "mesh"]
                    .into_iter()
                    .find(|k| edit_distance(k, name) <= 2 || name.to_ascii_lowercase() == *k);
                let help = match near {
                    Some(k) => format!("did you mean `{k}`? The shapes are {SHAPES}"),
                    None => format!("the shapes are {SHAPES}"),
                };
                self.err(Code::BadShape, s.name.span, format!("unknown shape `{name}`"), help);
                return None;
            }
        };
        let usage = match name {
            "box" => "box(lx, ly, lz)",
            "sphere" => "sphere(r)",
            "cylinder" => "cylinder(r, h)",
            "capsule" => "capsule(r, h)",
            "urdf" => "urdf(\"file.urdf\")",
            _ => "mesh(\"file.stl\")",
        };
        if arity == 0 {
            let Some((path, span)) = s.path.as_ref().filter(|_| s.args.is_empty()) else {
                self.err(
                    Code::BadShape,
                    s.span,
                    format!("`{name}` takes one file path in double quotes"),
                    format!("write `{usage}`, the path relative to this file"),
                );
                return None;
            };
            if path.is_empty() {
                self.err(Code::BadShape, *span, format!("`{name}` names no file"), format!("write `{usage}`"));
                return None;
            }
            if name == "mesh" {
                let ext = std::path::Path::new(path).extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
                if !matches!(ext.as_deref(), Some("stl" | "obj")) {
                    self.err(
                        Code::BadShape,
                        *span,
                        format!("`mesh` reads STL and OBJ files, not `{path}`"),
                        "convert the mesh to `.stl` or `.obj`, or describe the part with primitive shapes",
                    );
                    return None;
                }
            }
            let path = path.clone();
            return Some(if name == "urdf" {
                Shape::Urdf { path, span: *span }
            } else {
                Shape::Mesh { path, span: *span }
            });
        }
        if s.path.is_some() || s.args.len() != arity {
            let found =
                if s.path.is_some() { "a file path".to_string() } else { format!("{} argument(s)", s.args.len()) };
            self.err(
                Code::BadShape,
                s.span,
                format!("`{name}` takes {arity} real argument(s), found {found}"),
                format!("write `{usage}` in metres; the shapes are {SHAPES}"),
            );
            return None;
        }
        let args: Vec<Expr> = s.args.iter().map(|a| self.expr(a, env)).collect();
        for a in &args {
            self.expect_sort(a, &Sort::Real, &format!("a size of `{name}`"));
        }
        let mut it = args.into_iter();
        let mut next = || it.next().unwrap_or_else(|| Expr::error(Loc(s.span)));
        Some(match name {
            "box" => Shape::Box([next(), next(), next()]),
            "sphere" => Shape::Sphere(next()),
            "cylinder" => Shape::Cylinder(next(), next()),
            _ => Shape::Capsule(next(), next()),
        })
    }

    /// `pose(x, y, z)` or `pose(x, y, z, roll, pitch, yaw)` (E0204 otherwise, as a
    /// participant's `at:`), every argument real (E0208); omitted angles are 0.
    pub(super) fn pose(&mut self, p: &ast::Pose, env: &Env) -> Pose {
        self.pose_arity(p);
        let loc = Loc(p.span);
        let mut args: Vec<Expr> = p.args.iter().take(6).map(|a| self.expr(a, env)).collect();
        for a in &args {
            self.expect_sort(a, &Sort::Real, "pose coordinate");
        }
        while args.len() < 6 {
            args.push(Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc });
        }
        let mut it = args.into_iter();
        let mut next = || it.next().unwrap_or_else(|| Expr::error(loc));
        Pose { args: [next(), next(), next(), next(), next(), next()], span: p.span }
    }

    pub(super) fn pose_arity(&mut self, pose: &ast::Pose) {
        if pose.args.len() != 3 && pose.args.len() != 6 {
            self.err(
                Code::ArityMismatch,
                pose.span,
                format!("`pose` takes 3 or 6 arguments, found {}", pose.args.len()),
                "write `pose(x, y, z)` or `pose(x, y, z, roll, pitch, yaw)` in metres and radians",
            );
        }
    }

    /// A primitive's geometric footprint: `footprint: geometry` (the kind's own body) or
    /// shapes placed by its state, `old(...)`, parameters and `clock`.
    pub(super) fn footprint_body(
        &mut self,
        kind: KindId,
        params: &[(String, Sort)],
        f: &ast::FieldValue,
    ) -> Option<Body> {
        match f {
            ast::FieldValue::OwnGeometry(span) => {
                if let Some(b) = &self.prog.kind(kind).body {
                    return Some(Body { parts: b.parts.clone(), span: *span });
                }
                if !self.kinds_with_geometry.contains(&kind) {
                    let kname = self.prog.kind(kind).name.clone();
                    self.err(
                        Code::NoOwnGeometry,
                        *span,
                        format!("`footprint: geometry` but robot kind `{kname}` declares no `geometry:`"),
                        format!(
                            "add `geometry: SHAPES;` to `robot {kname}`, or write the footprint's shapes here (`footprint: box(...) at pose(...);`) or a predicate (`footprint(px, py, pz): ...;`)"
                        ),
                    );
                }
                None // a malformed geometry is reported at the kind
            }
            ast::FieldValue::Body(b) => {
                let env = Env {
                    who: Who::Kind(kind),
                    params,
                    state: true,
                    old: true,
                    clock: true,
                    part: Some(GEOMETRIC_FOOTPRINT),
                    ..Env::consts_only()
                };
                self.body(b, &env)
            }
            _ => None,
        }
    }

    /// A system's obstacles, after its participants (their names are distinct from the
    /// participants', E0206). Constants only.
    pub(super) fn obstacles(&mut self, s: &ast::SystemDecl) {
        let env = Env { part: Some(OBSTACLE), ..Env::consts_only() };
        for o in &s.obstacles {
            if let Some(first) = self.prog.obstacles.iter().find(|p| p.name == o.name.name) {
                let d = dup(o.name.span, "obstacle", &o.name.name, first.span);
                self.diags.push(d);
                continue;
            }
            if let Some(r) = self.prog.role_by_name(&o.name.name) {
                let d = dup(o.name.span, "participant or obstacle", &o.name.name, self.prog.role(r).span);
                self.diags.push(d);
                continue;
            }
            if self.poisoned.contains(&o.name.name) {
                continue; // a participant of an unknown kind, already reported
            }
            for g in o.geometry.iter().skip(1) {
                let d = dup(g.span, "field", "geometry", o.geometry[0].span);
                self.diags.push(d);
            }
            for a in o.at.iter().skip(1) {
                let d = dup(a.span, "field", "at", o.at[0].span);
                self.diags.push(d);
            }
            let body = match o.geometry.first() {
                Some(g) => self.body(g, &env),
                None => {
                    self.err(
                        Code::MissingField,
                        o.name.span,
                        format!("obstacle `{}` has no `geometry:`", o.name.name),
                        "add `geometry: SHAPES;` (e.g. `geometry: box(0.1, 1.0, 0.6);`): an obstacle is the space it occupies",
                    );
                    None
                }
            };
            let pose = o.at.first().map(|p| self.pose(p, &env));
            // A malformed body is reported; the obstacle keeps its name (so uses of it get
            // E0217, not E0202) with an empty body, in a program that is rejected anyway.
            let body = body.unwrap_or(Body { parts: Vec::new(), span: o.name.span });
            self.prog.obstacles.push(Obstacle { name: o.name.name.clone(), body, pose, span: o.name.span });
        }
    }

    /// `on: Carrier.mount` of each participant (E0206 twice, E0202 unknown carrier, E0217
    /// an obstacle, E0218 unknown mount), then cycles of mounts (E0216).
    pub(super) fn mounts(&mut self, ok: &[(RoleId, &ast::ParticipantDecl)]) {
        let mut on_spans: HashMap<RoleId, Span> = HashMap::new();
        for &(r, p) in ok {
            let Some((on, rest)) = p.on.split_first() else { continue };
            for o in rest {
                let d = dup(o.span, "field", "on", on.span);
                self.diags.push(d);
            }
            on_spans.insert(r, on.span);
            let Some(carrier) = self.role(&on.carrier) else { continue };
            let ckind = self.prog.kind_of(carrier);
            match ckind.mounts.iter().position(|m| m.name == on.mount.name) {
                Some(mount) => self.prog.roles[r.idx()].mounted_on = Some(MountedOn { carrier, mount }),
                None => {
                    let kname = ckind.name.clone();
                    let help = if ckind.mounts.is_empty() {
                        format!(
                            "robot kind `{kname}` declares no mounts; add `mount {}: pose(...);` to it",
                            on.mount.name
                        )
                    } else {
                        let names: Vec<_> = ckind.mounts.iter().map(|m| format!("`{}`", m.name)).collect();
                        format!("`{kname}` has {}", names.join(", "))
                    };
                    self.err(
                        Code::UnknownMount,
                        on.mount.span,
                        format!("`{}` (a `{kname}`) has no mount `{}`", on.carrier.name, on.mount.name),
                        help,
                    );
                }
            }
        }
        // Cycles: follow each chain of carriers; a participant met twice closes a cycle.
        let mut reported: std::collections::HashSet<RoleId> = std::collections::HashSet::new();
        for &(start, _) in ok {
            let mut path = vec![start];
            let mut at = start;
            while let Some(m) = self.prog.role(at).mounted_on {
                if let Some(i) = path.iter().position(|&q| q == m.carrier) {
                    let cycle: Vec<RoleId> = path[i..].to_vec();
                    if cycle.iter().all(|q| !reported.contains(q)) {
                        self.mount_cycle(&cycle, &on_spans);
                    }
                    reported.extend(cycle);
                    break;
                }
                path.push(m.carrier);
                at = m.carrier;
            }
        }
        // No participant is left on a cycle, so any walk along carriers ends.
        for r in reported {
            self.prog.roles[r.idx()].mounted_on = None;
        }
    }

    fn mount_cycle(&mut self, cycle: &[RoleId], on_spans: &HashMap<RoleId, Span>) {
        let first = cycle[0];
        let span = on_spans.get(&first).copied().unwrap_or(self.prog.role(first).span);
        let name = self.prog.role_name(first).to_string();
        let mut d = if cycle.len() == 1 {
            Diagnostic::error(Code::MountCycle, span, format!("participant `{name}` is mounted on itself"))
        } else {
            let names: Vec<String> = cycle.iter().map(|q| format!("`{}`", self.prog.role_name(*q))).collect();
            Diagnostic::error(
                Code::MountCycle,
                span,
                format!(
                    "participants mounted in a cycle: {} rides on {}, which rides on {}",
                    names[0],
                    names[1..].join(", which rides on "),
                    names[0]
                ),
            )
        };
        for q in &cycle[1..] {
            if let Some(s) = on_spans.get(q) {
                d = d.with_label(*s, format!("`{}` is mounted here", self.prog.role_name(*q)));
            }
        }
        d = d.with_help("a participant's world pose would depend on itself: mount the robots in a chain that ends at a participant placed in the world");
        self.diags.push(d);
    }

    /// E0217 if `name` is an obstacle: it has no process and takes part in no message or
    /// motion. Returns whether it reported.
    pub(super) fn obstacle_as_role(&mut self, name: &str, span: Span) -> bool {
        if self.prog.obstacle_by_name(name).is_none() {
            return false;
        }
        self.err(
            Code::ObstacleAsParticipant,
            span,
            format!("`{name}` is an obstacle, not a participant: it has no state, no process and takes part in no message or motion"),
            "an obstacle is static geometry checked against every footprint; declare a `participant` with a robot kind for something that moves or communicates",
        );
        true
    }
}

/// Levenshtein distance, for did-you-mean on short names.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur.push(sub.min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::super::tests::lower_src;
    use super::*;

    const ROBOTS: &str = "
        const cl = 0.5;
        robot Cart {
          state x: real, th: real;
          geometry: box(cl, 0.4, 0.1) at pose(x, 0, 0, 0, 0, th) + cylinder(0.05, 0.3) at pose(x, 0, 0.1);
          mount deck: pose(x, 0, 0.1, 0, 0, th);
          mount back: pose(x - 0.2, 0, 0.1);
        }
        robot Arm { state q: real; geometry: urdf(\"arm.urdf\"); }
        robot Bare { state s: real; }
        motion Cart.turn(a: real) { interruptible: false; guarantee: x == old(x); footprint: geometry; duration: [1, 1]; }
        motion Cart.slide(xf: real) {
          interruptible: false;
          footprint: box(cl, 0.4, 0.1) at pose(min(xf, old(x)), 0, 0) + sphere(0.1) at pose(x, clock, 0);
          duration: [1, 1];
        }
        motion Arm.idle { interruptible: true; footprint: geometry; }
        motion Bare.idle { interruptible: true; }
    ";

    fn with_system(robots: &str, system: &str, rest: &str) -> (Program, Vec<Code>) {
        let (p, d) = lower_src(&format!("{robots} system S {{ {system} }} {rest}"));
        (p, d.iter().map(|d| d.code).collect())
    }

    fn codes(src: &str) -> Vec<Code> {
        lower_src(src).1.iter().map(|d| d.code).collect()
    }

    const SYSTEM: &str = "
        participant C: Cart { init: x == 0; }
        participant A: Arm { on: C.deck; at: pose(0, 0, 0, 0, 0, pi / 2); }
        obstacle Bridge { geometry: box(0.1, 1.0, 0.6) at pose(0, -0.55, 0) + box(0.1, 1.2, 0.05) at pose(0, 0, 0.6); at: pose(2, 0, 0); }
        obstacle Pillar { geometry: cylinder(0.1, 2); }
    ";
    const CHOR: &str =
        "choreography G = dt<C: turn(1), A: idle>. end; process C = dt<turn(1)>. end; process A = dt<idle>. end;";

    #[test]
    fn bodies_mounts_and_obstacles_lower_into_the_hir() {
        let (p, d) = with_system(ROBOTS, SYSTEM, CHOR);
        assert!(d.is_empty(), "{d:?}");
        let cart = &p.kinds[0];
        let body = cart.body.as_ref().expect("a body");
        assert_eq!(body.parts.len(), 2);
        assert!(matches!(body.parts[0].shape, Shape::Box(_)));
        assert!(matches!(body.parts[1].shape, Shape::Cylinder(..)));
        let place = body.parts[0].place.as_ref().expect("placed");
        assert!(matches!(place.args[0].kind, ExprKind::Var(Var::Own(Slot::State(0)))));
        assert!(matches!(place.args[5].kind, ExprKind::Var(Var::Own(Slot::State(1)))));
        // A 3-argument pose has zero angles.
        let place = body.parts[1].place.as_ref().expect("placed");
        assert!(matches!(place.args[3].kind, ExprKind::Int(0)));
        assert_eq!(cart.mounts.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(), ["deck", "back"]);
        assert!(
            matches!(&p.kinds[1].body.as_ref().unwrap().parts[0].shape, Shape::Urdf { path, .. } if path == "arm.urdf")
        );
        assert!(p.kinds[2].body.is_none());
        // `footprint: geometry` is the kind's body; a written one reads params, old and clock.
        let turn = &p.prims[0];
        assert!(matches!(turn.footprint, crate::hir::Footprint::Solid { own: true, .. }));
        assert_eq!(turn.footprint.body().unwrap().parts.len(), 2);
        assert!(matches!(p.prims[1].footprint, crate::hir::Footprint::Solid { own: false, .. }));
        let slide = p.prims[1].footprint.body().expect("a geometric footprint");
        let ExprKind::Call(Builtin::Min, args) = &slide.parts[0].place.as_ref().unwrap().args[0].kind else {
            panic!("min")
        };
        assert!(matches!(args[0].kind, ExprKind::Var(Var::Param(0))));
        assert!(matches!(args[1].kind, ExprKind::Var(Var::Old(0))));
        assert!(matches!(slide.parts[1].place.as_ref().unwrap().args[1].kind, ExprKind::Var(Var::Clock)));
        // The mounted participant: carrier and mount index; its pose stays relative.
        assert_eq!(p.roles[1].mounted_on, Some(MountedOn { carrier: RoleId(0), mount: 0 }));
        assert_eq!(p.roles[1].pose.len(), 6);
        assert_eq!(p.roles[0].mounted_on, None);
        assert_eq!(p.obstacles.len(), 2);
        assert_eq!(p.obstacles[0].name, "Bridge");
        assert_eq!(p.obstacles[0].body.parts.len(), 2);
        assert!(p.obstacles[0].pose.is_some());
        assert!(p.obstacles[1].pose.is_none());
    }

    #[test]
    fn a_kind_body_reads_its_state_and_constants_only() {
        let bad = |geom: &str| {
            codes(&format!("const k = 1; robot R {{ state x: real; input w: real; geometry: {geom}; }} motion R.m(p: real) {{ interruptible: true; }}"))
        };
        assert_eq!(bad("sphere(k) at pose(x, 0, 0)"), [Code::MissingItem]);
        assert_eq!(bad("sphere(w)"), [Code::VariableNotAllowed, Code::MissingItem]);
        assert_eq!(bad("sphere(1) at pose(clock, 0, 0)"), [Code::VariableNotAllowed, Code::MissingItem]);
        assert_eq!(bad("sphere(1) at pose(old(x), 0, 0)"), [Code::VariableNotAllowed, Code::MissingItem]);
        assert_eq!(bad("sphere(p)"), [Code::UnknownVariable, Code::MissingItem]);
        assert_eq!(bad("sphere(Other.x)"), [Code::VariableNotAllowed, Code::MissingItem]);
        let (_, d) = lower_src("robot R { state x: real; input w: real; mount m: pose(w, 0, 0); }");
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), [Code::VariableNotAllowed, Code::MissingItem]);
        assert!(d[0].message.contains("a mount cannot read input variable `w`"), "{}", d[0].message);
    }

    #[test]
    fn a_geometric_footprint_reads_state_old_params_and_clock_but_no_input() {
        let fp = |f: &str| {
            let mut c = codes(&format!(
                "robot R {{ state x: real; input w: real; }} motion R.m(p: real) {{ interruptible: true; footprint: {f}; }}"
            ));
            c.retain(|c| *c != Code::MissingItem);
            c
        };
        assert!(fp("box(p, 1, 1) at pose(old(x), x, clock)").is_empty());
        assert_eq!(fp("box(1, 1, 1) at pose(w, 0, 0)"), [Code::VariableNotAllowed]);
        assert_eq!(fp("box(1, 1, 1) at pose(Other.x, 0, 0)"), [Code::VariableNotAllowed]);
    }

    #[test]
    fn an_obstacle_reads_constants_only() {
        let sys = |o: &str| {
            with_system(ROBOTS, &format!("participant C: Cart; obstacle O {{ {o} }}"), "choreography G = end;").1
        };
        assert!(sys("geometry: sphere(cl); at: pose(cl, 0, 0);").is_empty());
        assert_eq!(sys("geometry: sphere(C.x);"), [Code::VariableNotAllowed]);
        assert_eq!(sys("geometry: sphere(1); at: pose(clock, 0, 0);"), [Code::VariableNotAllowed]);
        assert_eq!(sys("geometry: sphere(x);"), [Code::UnknownVariable]);
        assert_eq!(sys("at: pose(1, 0, 0);"), [Code::MissingField]);
        assert_eq!(sys("geometry: sphere(1); geometry: sphere(2);"), [Code::Duplicate]);
    }

    #[test]
    fn shapes_and_poses_are_checked() {
        let g = |geom: &str| codes(&format!("robot R {{ state x: real; geometry: {geom}; }}"));
        let only = |geom: &str, code: Code| assert_eq!(g(geom), [code, Code::MissingItem], "{geom}");
        only("boxx(1, 1, 1)", Code::BadShape);
        only("box(1, 1)", Code::BadShape);
        only("sphere(\"a.stl\")", Code::BadShape);
        only("urdf(1)", Code::BadShape);
        only("urdf(\"\")", Code::BadShape);
        only("mesh(\"a.png\")", Code::BadShape);
        only("sphere(1) at pose(1, 2)", Code::ArityMismatch);
        only("sphere(x > 1)", Code::SortMismatch);
        only("sphere(1) at pose(1, 2, true)", Code::SortMismatch);
        assert_eq!(g("mesh(\"a.obj\") + mesh(\"b.STL\") + capsule(0.1, 0.5)"), [Code::MissingItem]);
        let (_, d) = lower_src("robot R { state x: real; geometry: cylindre(1, 2); }");
        assert!(d[0].help.as_deref().unwrap().contains("did you mean `cylinder`?"), "{:?}", d[0].help);
        // A bad shape is one error, not one per use of the body.
        let d = codes(
            "robot R { state x: real; geometry: cone(1); } motion R.m { interruptible: true; footprint: geometry; }",
        );
        assert_eq!(d, [Code::BadShape, Code::MissingItem]);
        assert_eq!(g("sphere(1); geometry: sphere(2)"), [Code::Duplicate, Code::MissingItem]);
    }

    #[test]
    fn footprint_geometry_needs_a_body_and_one_footprint() {
        let d = codes("robot R { state x: real; } motion R.m { interruptible: true; footprint: geometry; }");
        assert_eq!(d, [Code::NoOwnGeometry, Code::MissingItem]);
        let d = codes(
            "robot R { state x: real; geometry: sphere(1); } motion R.m { interruptible: true; footprint: geometry; footprint(a, b, c): a == x; }",
        );
        assert_eq!(d, [Code::Duplicate, Code::MissingItem]);
    }

    #[test]
    fn mounts_resolve_and_cycles_are_rejected() {
        let sys = |s: &str| with_system(ROBOTS, s, "choreography G = end;");
        let (p, d) = sys("participant C: Cart; participant D: Cart { on: C.back; } participant A: Arm { on: D.deck; }");
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(p.roles[1].mounted_on, Some(MountedOn { carrier: RoleId(0), mount: 1 }));
        assert_eq!(p.roles[2].mounted_on, Some(MountedOn { carrier: RoleId(1), mount: 0 }));
        let chain: Vec<RoleId> = p.carriers(RoleId(2)).iter().map(|m| m.carrier).collect();
        assert_eq!(chain, [RoleId(1), RoleId(0)]);
        assert!(p.carriers(RoleId(0)).is_empty());
        assert_eq!(sys("participant C: Cart { on: C.deck; }").1, [Code::MountCycle]);
        let (p, d) = sys("participant C: Cart { on: D.deck; } participant D: Cart { on: C.back; } participant A: Arm { on: C.deck; }");
        assert_eq!(d, [Code::MountCycle], "one cycle, one error");
        assert!(p.roles.iter().take(2).all(|r| r.mounted_on.is_none()), "no walk along carriers loops");
        assert_eq!(p.carriers(RoleId(2)).len(), 1);
        assert_eq!(sys("participant C: Cart; participant A: Arm { on: C.roof; }").1, [Code::UnknownMount]);
        assert_eq!(sys("participant C: Cart; participant A: Arm { on: X.deck; }").1, [Code::UnknownParticipant]);
        assert_eq!(sys("participant C: Cart; participant A: Arm { on: C.deck; on: C.back; }").1, [Code::Duplicate]);
        let (_, d) = lower_src(&format!("{ROBOTS} system S {{ participant C: Cart; participant B: Bare; participant A: Arm {{ on: B.top; }} }} choreography G = end;"));
        assert!(d[0].help.as_deref().unwrap().contains("declares no mounts"), "{d:?}");
        let d = codes("robot R { state x: real; mount m: pose(0, 0, 0); mount m: pose(1, 0, 0); }");
        assert_eq!(d, [Code::Duplicate, Code::MissingItem]);
    }

    #[test]
    fn an_obstacle_is_no_participant() {
        let sys = |rest: &str| with_system(ROBOTS, SYSTEM, rest).1;
        let e0217 = [Code::ObstacleAsParticipant];
        assert_eq!(sys("choreography G = C -> Bridge: hi. end;"), e0217);
        assert_eq!(sys("choreography G = C -> A: [Bridge.x > 0] hi. end;").first(), Some(&Code::ObstacleAsParticipant));
        assert_eq!(
            sys("choreography G = dt<C: turn(1), Pillar: idle>. end;").first(),
            Some(&Code::ObstacleAsParticipant)
        );
        assert_eq!(sys("choreography G = end; process Bridge = end;"), e0217);
        assert_eq!(sys("choreography G = end; local Pillar = end;"), e0217);
        assert_eq!(sys("choreography G = end; process C = Bridge!hi.end;"), e0217);
        let (_, d) = with_system(
            ROBOTS,
            "participant C: Cart; participant A: Arm { on: Bridge.deck; } obstacle Bridge { geometry: sphere(1); }",
            "choreography G = end;",
        );
        assert_eq!(d, e0217);
        // Names are distinct from each other and from the participants'.
        let (_, d) = with_system(ROBOTS, "participant C: Cart; obstacle C { geometry: sphere(1); } obstacle O { geometry: sphere(1); } obstacle O { geometry: sphere(1); }", "choreography G = end;");
        assert_eq!(d, [Code::Duplicate, Code::Duplicate]);
        // A system of obstacles only is fine.
        let (p, d) = with_system(ROBOTS, "obstacle O { geometry: sphere(1); }", "choreography G = end;");
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(p.obstacles.len(), 1);
    }
}
