//! A body as a predicate: "the point `p` lies in this body" (Sec 3.1's `geom(p)` written
//! as a footprint predicate), for the bodies the SMT solver can decide: boxes, spheres,
//! cylinders and capsules, each placed by a pose. Placements that read the state
//! (`box(...) at pose(x, 0, 0)`) stay polynomial when their rotation is constant; a
//! rotation by a state variable gives `cos`/`sin` of it, which the encoder reports as
//! unsupported (the geometric decision procedure decides those). URDF and mesh parts have
//! no predicate: [`region`] gives `None` for a body with one.
//!
//! The predicate is exact (no over-approximation): `p` satisfies it iff `p` is a point
//! of the body, given the pose's cosines and sines; the encoder encloses the irrational
//! ones soundly (LANGUAGE.md, Systems), and an exact quarter turn is written with 0, ±1.

use crate::bounds;
use crate::hir::body::{Body, BodyPart, Pose, Shape};
use crate::hir::expr::{BinOp, Builtin, ExprKind, Sort};
use crate::hir::{Expr, Loc, Program};

/// The predicate "`p` is a point of `body`", `p` in the body's owner frame; `None` when
/// a part has no predicate (URDF, mesh).
pub fn region(prog: &Program, body: &Body, p: &[Expr; 3]) -> Option<Expr> {
    let loc = Loc(body.span);
    let mut parts = Vec::new();
    for part in &body.parts {
        parts.push(part_region(prog, part, p)?);
    }
    Some(parts.into_iter().reduce(|a, b| bin(BinOp::Or, a, b, Sort::Bool)).unwrap_or_else(|| Expr::bool(false, loc)))
}

fn part_region(prog: &Program, part: &BodyPart, p: &[Expr; 3]) -> Option<Expr> {
    let q = match &part.place {
        Some(pose) => to_part_frame(prog, pose, p),
        None => p.clone(),
    };
    let loc = Loc(part.span);
    let zero = || num(0, loc);
    let between = |lo: Expr, x: &Expr, hi: Expr| {
        bin(
            BinOp::And,
            bin(BinOp::Le, lo, x.clone(), Sort::Bool),
            bin(BinOp::Le, x.clone(), hi, Sort::Bool),
            Sort::Bool,
        )
    };
    let sq = |e: &Expr| bin(BinOp::Pow, e.clone(), num(2, loc), Sort::Real);
    let sum = |es: Vec<Expr>| es.into_iter().reduce(|a, b| bin(BinOp::Add, a, b, Sort::Real)).expect("terms");
    let half = |e: &Expr| bin(BinOp::Div, e.clone(), num(2, loc), Sort::Real);
    let and = |a: Expr, b: Expr| bin(BinOp::And, a, b, Sort::Bool);
    let or = |a: Expr, b: Expr| bin(BinOp::Or, a, b, Sort::Bool);
    Some(match &part.shape {
        Shape::Box([lx, ly, lz]) => {
            let x = between(neg(half(lx)), &q[0], half(lx));
            let y = between(neg(half(ly)), &q[1], half(ly));
            and(and(x, y), between(zero(), &q[2], lz.clone()))
        }
        Shape::Sphere(r) => bin(BinOp::Le, sum(vec![sq(&q[0]), sq(&q[1]), sq(&q[2])]), sq(r), Sort::Bool),
        Shape::Cylinder(r, h) => {
            and(bin(BinOp::Le, sum(vec![sq(&q[0]), sq(&q[1])]), sq(r), Sort::Bool), between(zero(), &q[2], h.clone()))
        }
        Shape::Capsule(r, h) => {
            // The segment from (0, 0, r) to (0, 0, h - r), thickened by r: the side
            // cylinder and the two end balls.
            let top = bin(BinOp::Sub, h.clone(), r.clone(), Sort::Real);
            let side = and(
                bin(BinOp::Le, sum(vec![sq(&q[0]), sq(&q[1])]), sq(r), Sort::Bool),
                between(r.clone(), &q[2], top.clone()),
            );
            let ball = |c: Expr| {
                let dz = bin(BinOp::Sub, q[2].clone(), c, Sort::Real);
                bin(BinOp::Le, sum(vec![sq(&q[0]), sq(&q[1]), sq(&dz)]), sq(r), Sort::Bool)
            };
            or(or(side, ball(r.clone())), ball(top))
        }
        Shape::Urdf { .. } | Shape::Mesh { .. } => return None,
    })
}

/// The predicate "the world point `(Point(0), Point(1), Point(2))` is in the obstacle":
/// the obstacle's body moved into the world by its `at:` pose. `None` for a body with a
/// URDF or mesh part.
pub fn obstacle_region(prog: &Program, o: &crate::hir::body::Obstacle) -> Option<Expr> {
    let loc = Loc(o.span);
    let p = [0, 1, 2].map(|k| Expr { kind: ExprKind::Var(crate::hir::Var::Point(k)), sort: Sort::Real, loc });
    let local = match &o.pose {
        Some(pose) => to_part_frame(prog, pose, &p),
        None => p,
    };
    region(prog, &o.body, &local)
}

/// `R^T (p - t)` for `pose(t, roll, pitch, yaw)`, `R = Rz(yaw) Ry(pitch) Rx(roll)`: undo
/// the translation, then yaw, pitch and roll (as `smt::goals::frames` does for a
/// participant's pose). An angle that is exactly 0 is skipped; an exact quarter turn
/// rotates by 0 and ±1.
pub fn to_part_frame(prog: &Program, pose: &Pose, p: &[Expr; 3]) -> [Expr; 3] {
    let loc = Loc(pose.span);
    let mut v = p.clone();
    for (k, c) in v.iter_mut().enumerate() {
        if !is_zero(prog, &pose.args[k]) {
            *c = bin(BinOp::Sub, c.clone(), pose.args[k].clone(), Sort::Real);
        }
    }
    for (idx, (a, b)) in [(5usize, (0usize, 1usize)), (4, (2, 0)), (3, (1, 2))] {
        let angle = &pose.args[idx];
        if is_zero(prog, angle) {
            continue;
        }
        let (c, s) = match bounds::quarter_turn(prog, angle) {
            Some((c, s)) => (num(c, loc), num(s, loc)),
            None => (
                Expr { kind: ExprKind::Call(Builtin::Cos, vec![angle.clone()]), sort: Sort::Real, loc },
                Expr { kind: ExprKind::Call(Builtin::Sin, vec![angle.clone()]), sort: Sort::Real, loc },
            ),
        };
        let (x, y) = (v[a].clone(), v[b].clone());
        // x' = c x + s y, y' = c y - s x.
        v[a] = add(mul(&c, &x), mul(&s, &y));
        v[b] = sub(mul(&c, &y), mul(&s, &x));
    }
    v
}

fn is_zero(prog: &Program, e: &Expr) -> bool {
    bounds::exact(prog, e).is_some_and(|q| num_traits::Zero::is_zero(&q))
}

fn num(n: i64, loc: Loc) -> Expr {
    Expr { kind: ExprKind::Int(n), sort: Sort::Int, loc }
}

fn bin(op: BinOp, a: Expr, b: Expr, sort: Sort) -> Expr {
    let loc = a.loc;
    Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort, loc }
}

fn neg(e: Expr) -> Expr {
    let loc = e.loc;
    Expr { kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(e)), sort: Sort::Real, loc }
}

/// `c * x`, simplified for `c` an integer 0 or ±1 (a quarter turn's exact cosines).
fn mul(c: &Expr, x: &Expr) -> Option<Expr> {
    match c.kind {
        ExprKind::Int(0) => None,
        ExprKind::Int(1) => Some(x.clone()),
        ExprKind::Int(-1) => Some(neg(x.clone())),
        _ => Some(bin(BinOp::Mul, c.clone(), x.clone(), Sort::Real)),
    }
}

fn add(a: Option<Expr>, b: Option<Expr>) -> Expr {
    match (a, b) {
        (Some(a), Some(b)) => bin(BinOp::Add, a, b, Sort::Real),
        (Some(e), None) | (None, Some(e)) => e,
        (None, None) => num(0, Loc::default()),
    }
}

fn sub(a: Option<Expr>, b: Option<Expr>) -> Expr {
    match (a, b) {
        (Some(a), Some(b)) => bin(BinOp::Sub, a, b, Sort::Real),
        (Some(e), None) => e,
        (None, Some(e)) => neg(e),
        (None, None) => num(0, Loc::default()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smt::{check_valid, SmtConfig, Validity};

    fn lit(v: &str) -> Expr {
        Expr { kind: ExprKind::Real(v.into()), sort: Sort::Real, loc: Loc::default() }
    }

    fn pose(args: [&str; 6]) -> Pose {
        Pose { args: args.map(lit), span: Default::default() }
    }

    /// Is the constant point `p` in the body? Decided by Z3 on the closed predicate.
    fn inside(prog: &Program, body: &Body, p: [&str; 3]) -> bool {
        let e = region(prog, body, &p.map(lit)).expect("a predicate");
        match check_valid(prog, &[], &e, &SmtConfig::default()) {
            Validity::Holds => true,
            Validity::Fails(_) => false,
            Validity::Unknown(w) => panic!("unknown: {w:?}"),
        }
    }

    fn body(shape: Shape, place: Option<Pose>) -> Body {
        Body { parts: vec![BodyPart { shape, place, span: Default::default() }], span: Default::default() }
    }

    fn prog() -> Program {
        crate::lower::tests::lower_src(
            "robot R { state x: real; } system S { participant A: R; } choreography G = end;",
        )
        .0
    }

    #[test]
    fn a_box_stands_on_its_origin_and_is_centred_in_x_and_y() {
        let p = prog();
        let b = body(Shape::Box([lit("2"), lit("1"), lit("0.5")]), None);
        assert!(inside(&p, &b, ["0.99", "-0.49", "0.01"]));
        assert!(inside(&p, &b, ["1", "0.5", "0.5"]), "closed: the faces belong to the box");
        assert!(!inside(&p, &b, ["1.01", "0", "0.1"]));
        assert!(!inside(&p, &b, ["0", "0", "-0.01"]), "it stands on z = 0");
    }

    #[test]
    fn a_placed_box_is_moved_then_turned() {
        let p = prog();
        // A 2 x 0.2 x 1 bar at x = 5, turned a quarter turn about z: it now runs along y.
        let turned = pose(["5", "0", "0", "0", "0", "1.5707963267948966"]);
        let unturned = pose(["5", "0", "0", "0", "0", "0"]);
        let straight = body(Shape::Box([lit("2"), lit("0.2"), lit("1")]), Some(unturned));
        assert!(inside(&p, &straight, ["5.9", "0", "0.5"]));
        assert!(!inside(&p, &straight, ["5", "0.9", "0.5"]));
        let b = body(Shape::Box([lit("2"), lit("0.2"), lit("1")]), Some(turned));
        assert!(inside(&p, &b, ["5", "0.9", "0.5"]));
        assert!(!inside(&p, &b, ["5.9", "0", "0.5"]));
    }

    #[test]
    fn spheres_cylinders_and_capsules_are_exact() {
        let p = prog();
        let s = body(Shape::Sphere(lit("1")), None);
        assert!(inside(&p, &s, ["0.6", "0.6", "0.5"]));
        assert!(!inside(&p, &s, ["0.6", "0.6", "0.6"]));
        let c = body(Shape::Cylinder(lit("1"), lit("2")), None);
        assert!(inside(&p, &c, ["0.7", "0.7", "1.9"]));
        assert!(!inside(&p, &c, ["0.8", "0.7", "1"]));
        assert!(!inside(&p, &c, ["0", "0", "2.1"]));
        // A capsule of radius 1 and height 4: segment from z = 1 to z = 3.
        let k = body(Shape::Capsule(lit("1"), lit("4")), None);
        assert!(inside(&p, &k, ["0", "0", "0"]), "bottom of the lower ball");
        assert!(inside(&p, &k, ["0.99", "0", "2"]), "the side");
        assert!(!inside(&p, &k, ["0.7", "0.7", "0.1"]), "outside the lower ball, inside its cylinder");
        assert!(inside(&p, &k, ["0", "0", "4"]));
        assert!(!inside(&p, &k, ["0", "0", "4.01"]));
    }

    #[test]
    fn urdf_and_mesh_parts_have_no_predicate() {
        let p = prog();
        let b = body(Shape::Mesh { path: "m.stl".into(), span: Default::default() }, None);
        assert!(region(&p, &b, &["0", "0", "0"].map(lit)).is_none());
    }
}
