//! What a part of an obligation checks, in the user's terms: the text of a failed or
//! undecided part.

use super::*;

/// What a part checks, in the user's terms.
pub(super) fn describe(prog: &Program, ob: &Obligation, part: &Part) -> String {
    let prim = |app: &crate::hir::PrimApp| crate::hir::print::prim_app(prog, app);
    match (&ob.goal, part) {
        (Goal::Compatible { parts }, Part::Pre(i)) => {
            format!(
                "the precondition of `{}` ({}) holds when the joint motion starts",
                prim(&parts[*i].1),
                prog.role_name(parts[*i].0)
            )
        }
        (Goal::Compatible { parts }, Part::CanEnd) => {
            let all: Vec<String> =
                parts.iter().map(|(r, a)| format!("`{}` ({})", prim(a), prog.role_name(*r))).collect();
            format!(
                "{} can end{}: from what is known when {} and the precondition{}, some time t in {} duration at which {} guarantee (at 0 and at t), postcondition and robot invariant hold together",
                all.join(", "),
                if parts.len() > 1 { " together" } else { "" },
                if parts.len() > 1 { "they start" } else { "it starts" },
                if parts.len() > 1 { "s" } else { "" },
                if parts.len() > 1 { "every part's" } else { "its" },
                if parts.len() > 1 { "every part's" } else { "its" },
            )
        }
        (Goal::Occupies { prim: p }, Part::Occupies) => {
            format!(
                "the footprint of `{}` holds some point when it starts, for some arguments and start state its precondition and the invariant allow",
                prog.prim(*p).name
            )
        }
        (Goal::Contains { prim: p }, Part::Contains(k)) => {
            let prim = prog.prim(*p);
            let what =
                prog.kind(prim.kind).body.as_ref().and_then(|b| b.parts.get(*k)).map_or("?", |part| match part.shape {
                    crate::hir::body::Shape::Box(_) => "box",
                    crate::hir::body::Shape::Sphere(_) => "sphere",
                    crate::hir::body::Shape::Cylinder(..) => "cylinder",
                    crate::hir::body::Shape::Capsule(..) => "capsule",
                    crate::hir::body::Shape::Urdf { .. } => "URDF",
                    crate::hir::body::Shape::Mesh { .. } => "mesh",
                });
            format!(
                "the footprint of `{}` contains the robot's body (its {what}, part {} of `geometry:`) at every time and state its guarantee allows",
                prim.name,
                k + 1
            )
        }
        (Goal::CanEnd { prim: p }, _) => {
            let p = prog.prim(*p);
            format!(
                "`{}` can end: for some arguments and some start state allowed by its precondition and the invariant, some time t in its duration and an end state at which its guarantee (at 0 and at t), postcondition and invariant hold",
                p.name
            )
        }
        (Goal::Reachable { .. }, _) if ob.rule == crate::obligation::Rule::InitInvariant => {
            format!("some state satisfies both {} and the kind's invariant", ob.what)
        }
        (Goal::Reachable { .. }, _) if ob.rule == crate::obligation::Rule::EnumEntry => ob.what.clone(),
        (Goal::Reachable { .. }, _) => format!("{} is satisfiable", ob.what),
        (Goal::Valid(goal), Part::Conjunct(k)) => {
            format!("{}: `{}`", ob.what, crate::hir::print::expr(prog, None, goal.conjuncts()[*k]))
        }
        (Goal::Compatible { parts }, Part::Assume(i)) => format!(
            "the guarantees of the other primitives discharge the assumption of `{}` ({})",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0)
        ),
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => format!(
            "the footprints of `{}` ({}) and `{}` ({}) are disjoint at every time",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0),
            prim(&parts[*j].1),
            prog.role_name(parts[*j].0)
        ),
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => format!(
            "the footprint of `{}` ({}) never meets obstacle `{}`",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0),
            prog.obstacles.get(*o).map_or("?", |x| x.name.as_str())
        ),
        (Goal::Compatible { parts }, Part::Within(n, j)) => format!(
            "the duration of the non-interruptible `{}` ({}) lies within that of `{}` ({})",
            prim(&parts[*n].1),
            prog.role_name(parts[*n].0),
            prim(&parts[*j].1),
            prog.role_name(parts[*j].0)
        ),
        (Goal::Compatible { parts }, Part::CommonEnd(n, j)) => {
            let lasts = |i: usize| {
                let p = prog.prim(parts[i].1.prim);
                // The bounds with the arguments put in (`[d, d]` of `stroke(20)` is
                // `[20, 20]`), a constant printed as its value.
                let bound = |e: &crate::hir::Expr| {
                    let e = crate::sigma::instantiate(e, parts[i].0, &parts[i].1.args);
                    match crate::exact::eval(prog, &e, &|_: &crate::hir::Var| None) {
                        Ok(crate::exact::Value::Num(n))
                            if n.is_exact() && !crate::exact::decimal(&n.lo).starts_with('≈') =>
                        {
                            crate::exact::decimal(&n.lo)
                        }
                        _ => crate::hir::print::expr(prog, None, &e),
                    }
                };
                let lo = bound(&p.duration.lo);
                let hi = p.duration.hi.as_ref().map(bound);
                format!(
                    "`{}` ({}, duration [{lo}, {}])",
                    prim(&parts[i].1),
                    prog.role_name(parts[i].0),
                    hi.as_deref().unwrap_or("inf")
                )
            };
            format!(
                "the non-interruptible {} and {} end together: both durations are the same single instant (joint end)",
                lasts(*n),
                lasts(*j)
            )
        }
        (Goal::Compatible { .. }, Part::Meet) => "the durations of the primitives share a time".to_string(),
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let (x, y) = (&sides[*a].runs[*ra], &sides[*b].runs[*rb]);
            format!(
                "the footprint of `{}` ({}) on side {} and that of `{}` ({}) on side {} never meet",
                prim(&x.app),
                prog.role_name(x.role),
                a + 1,
                prim(&y.app),
                prog.role_name(y.role),
                b + 1
            )
        }
        (Goal::Separated { .. }, Part::RegionsApart(a, b)) => {
            format!("the regions of sides {} and {} of the written partition are disjoint", a + 1, b + 1)
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => {
            let run = &sides[*a].runs[*ra];
            format!(
                "the footprint of `{}` ({}) stays in the region the partition gives side {}",
                prim(&run.app),
                prog.role_name(run.role),
                a + 1
            )
        }
        (Goal::Refines { concrete, abstract_, .. }, Part::Refine(item)) => {
            let abs: Vec<String> = abstract_.iter().map(prim).collect();
            format!("`{}` refines `{}`: {}", prim(concrete), abs.join(" /\\ "), item.text())
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => {
            format!(
                "`{}` and `{}` start apart (their first footprints at time 0 are disjoint)",
                prog.role_name(firsts[*r].0),
                prog.role_name(firsts[*s].0)
            )
        }
        _ => ob.what.clone(),
    }
}
