//! The space robots occupy, between the HIR and the checks (the "geometry" stage of the
//! pipeline): shapes are checked for sizes that describe a body ([`prepare`], E0511),
//! and bodies become footprint predicates ([`region`]) where the SMT solver can decide
//! them, so that a geometric footprint written with boxes, spheres, cylinders and
//! capsules is checked by the same queries as a written predicate. The remaining ones
//! (URDF, meshes, rotation by a state variable) are the geometric decision procedure's.

pub mod contain;
pub mod enclose;
pub mod literal;
pub mod region;

pub mod world;

use crate::bounds;
use crate::diag::{Code, Diagnostic};
use crate::hir::body::{Body, Shape};
use crate::hir::expr::{ExprKind, Sort};
use crate::hir::{Expr, Footprint, Loc, PointPred, Program, Var};
use num_traits::ToPrimitive;

/// Checks every body's sizes and gives each geometric footprint a predicate where one
/// exists: a [`Footprint::Solid`] all of whose parts are shapes becomes a
/// [`Footprint::Shapes`]; one with a URDF or mesh part stays a `Solid`.
pub fn prepare(prog: &mut Program) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    let bodies = prog
        .kinds
        .iter()
        .filter_map(|k| k.body.as_ref())
        .chain(prog.prims.iter().filter_map(|p| p.footprint.body()))
        .chain(prog.obstacles.iter().map(|o| &o.body));
    for body in bodies {
        sizes(prog, body, &mut diags);
    }
    if diags.iter().any(Diagnostic::is_error) {
        return diags;
    }
    for i in 0..prog.prims.len() {
        let Footprint::Solid { body, own } = &prog.prims[i].footprint else { continue };
        let loc = Loc(body.span);
        let point = [0, 1, 2].map(|k| Expr { kind: ExprKind::Var(Var::Point(k)), sort: Sort::Real, loc });
        if let Some(pred) = region::region(prog, body, &point) {
            let region = PointPred { point: ["x", "y", "z"].map(String::from), pred };
            prog.prims[i].footprint = Footprint::Shapes { body: body.clone(), own: *own, region };
        }
    }
    diags
}

/// Every size of a shape is a constant whose enclosure is positive (a negative or zero
/// size would describe no body, or less of one than meant: a footprint of a box of
/// length -1 holds no point and would make every collision check about it hold
/// vacuously); a capsule is at least as tall as it is wide.
fn sizes(prog: &Program, body: &Body, diags: &mut Vec<Diagnostic>) {
    for part in &body.parts {
        let (name, dims): (&str, Vec<(&str, &Expr)>) = match &part.shape {
            Shape::Box([x, y, z]) => ("box", vec![("length", x), ("width", y), ("height", z)]),
            Shape::Sphere(r) => ("sphere", vec![("radius", r)]),
            Shape::Cylinder(r, h) => ("cylinder", vec![("radius", r), ("height", h)]),
            Shape::Capsule(r, h) => ("capsule", vec![("radius", r), ("height", h)]),
            Shape::Urdf { .. } | Shape::Mesh { .. } => continue,
        };
        let mut ok = true;
        for (what, e) in &dims {
            let iv = bounds::eval(prog, e, &bounds::closed);
            if !iv.is_some_and(|iv| iv.lo > 0.0 && iv.hi.is_finite()) {
                ok = false;
                let constant = !crate::hir::expr::mentions(e, &|v| !matches!(v, Var::Const(_)));
                let found = match (bounds::exact(prog, e), iv) {
                    (Some(q), _) => format!("it is {}", q.to_f64().map_or_else(|| q.to_string(), |v| format!("{v}"))),
                    (None, Some(iv)) if constant && iv.is_finite() => format!("it lies in [{}, {}]", iv.lo, iv.hi),
                    _ if constant => "it cannot be bounded".to_string(),
                    _ => "it reads a variable".to_string(),
                };
                diags.push(
                    Diagnostic::error(
                        Code::BadShapeSize,
                        e.loc.0,
                        format!("the {what} of a {name} must be a positive constant; {found}"),
                    )
                    .with_help(
                        "write a positive number or constant (metres); a shape that changes with the state is placed by `at pose(...)`, not sized by it",
                    ),
                );
            }
        }
        if let (true, Shape::Capsule(r, h)) = (ok, &part.shape) {
            let r = bounds::eval(prog, r, &bounds::closed);
            let h = bounds::eval(prog, h, &bounds::closed);
            if let (Some(r), Some(h)) = (r, h) {
                if h.lo.is_nan() || r.hi.is_nan() || h.lo < 2.0 * r.hi {
                    diags.push(
                        Diagnostic::error(
                            Code::BadShapeSize,
                            part.span,
                            format!("a capsule of radius {} is at least {} tall; this one is {}", r.hi, 2.0 * r.hi, h.lo),
                        )
                        .with_help("a capsule's height counts both end caps: make it at least twice the radius, or use a sphere"),
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::hir::body::{Body, BodyPart, Pose, Shape};
    use crate::hir::{Expr, ExprKind, Loc, Slot, Sort, Var};
    use crate::smt::{discharge, Decision, SmtConfig};

    fn lit(v: &str) -> Expr {
        Expr { kind: ExprKind::Real(v.into()), sort: Sort::Real, loc: Loc::default() }
    }

    /// A cart whose body is a 0.5 x 0.4 x 0.1 box at its position `x`, sliding from
    /// `old(x)` to `xf`, with a footprint reaching `margin` past the swept segment's ends.
    /// The body is attached by hand (the test is about the check, not the syntax).
    fn slide(margin: &str) -> Decision {
        let src = format!(
            "robot Cart {{ state x: real; invariant: -10 <= x <= 10; }}
             motion Cart.go(xf: real) {{ interruptible: false; pre: x < xf; guarantee: old(x) <= x <= xf; post: x == xf; duration: [1, 1];
               footprint(px, py, pz): old(x) - {margin} <= px <= xf + {margin} && -0.2 <= py <= 0.2 && 0 <= pz <= 0.1; }}
             system S {{ participant C: Cart {{ init: x == 0; }} }}
             choreography G = dt<C: go(1)>. end;"
        );
        let (mut prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let x = Expr { kind: ExprKind::Var(Var::Own(Slot::State(0))), sort: Sort::Real, loc: Loc::default() };
        let at = Pose { args: [x, lit("0"), lit("0"), lit("0"), lit("0"), lit("0")], span: Default::default() };
        prog.kinds[0].body = Some(Body {
            parts: vec![BodyPart {
                shape: Shape::Box([lit("0.5"), lit("0.4"), lit("0.1")]),
                place: Some(at),
                span: Default::default(),
            }],
            span: Default::default(),
        });
        let used = std::iter::once(crate::hir::PrimId(0)).collect();
        let obs: Vec<_> = crate::library::contracts(&prog, &used)
            .into_iter()
            .filter(|o| o.rule == crate::obligation::Rule::Contains)
            .collect();
        assert_eq!(obs.len(), 1);
        discharge(&prog, &obs, &[], &SmtConfig::default()).remove(0).0
    }

    #[test]
    fn a_footprint_must_contain_the_body_at_every_state_the_guarantee_allows() {
        assert_eq!(slide("0.25"), Decision::Holds(None));
        let Decision::Fails(f) = slide("0.2") else { panic!("the body's ends stick out by 0.05") };
        let o = f.overlap.expect("a point of the body outside the footprint");
        // The point sticks out past one end of the swept segment.
        assert!(o.point[0] < -0.2 || o.point[0] > 1.2, "{o:?}");
    }
}
