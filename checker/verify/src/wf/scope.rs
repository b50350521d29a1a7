//! Well-scopedness (Sec 4.1, labelling rules (1)-(6)) on the once-unfolded type, with
//! the participant half of full separation (E0307), total motion (Def 4.4 (3), E0309),
//! `pt{G} = P` of [T-SESS] (E0313) and the coupling half of full separation (E0315).
//! The predicates of the type (its [AGCOMP], separation, total-choice and other
//! obligations) are planned by [`crate::plan`]; this walk decides only what is structural.
//!
//! The labelling is deterministic: the root gets every participant, `.` and `+` pass
//! their label down, and `g1 * ... * gn` gives each side exactly `pt{g_i}`. That choice
//! loses nothing: any valid labelling must give side i at least `pt{g_i}`, and a
//! participant given to no side has no motion there, which total motion forbids.

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use std::collections::HashMap;

/// The scoping errors of the global type `g`.
pub fn check(prog: &Program, g: &Global) -> Vec<Diagnostic> {
    let mut s = Scope { prog, diags: Vec::new(), recs: HashMap::new(), unfolding: Vec::new() };
    let used = participants(g);
    let all: Vec<RoleId> = prog.role_ids().collect();
    for r in not_in(&all, &used) {
        s.diags.push(
            Diagnostic::error(
                Code::ParticipantUnused,
                prog.role(r).span,
                format!("participant `{}` takes no part in the choreography", prog.role_name(r)),
            )
            .with_note("[T-SESS] requires pt{G} = P")
            .with_help("give it a role in the choreography or remove it from the system"),
        );
    }
    // The root scope is P; an unused participant was reported above (E0313), so scope
    // with pt{G} to avoid reporting it again at every motion.
    s.walk(g, &used, true);
    s.diags
}

struct Scope<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
    /// Recursion variable → its body, for the one unfolding.
    recs: HashMap<&'a str, &'a Global>,
    /// Variables being unfolded (their second occurrence is a leaf).
    unfolding: Vec<&'a str>,
}

/// pt{G} in order of appearance, as [`Global::participants`] gives it, through a set:
/// a joint motion of n participants is n lookups, not n²/2 comparisons.
fn participants(g: &Global) -> Vec<RoleId> {
    fn go(g: &Global, seen: &mut std::collections::HashSet<RoleId>, out: &mut Vec<RoleId>) {
        let mut add = |r: RoleId| {
            if seen.insert(r) {
                out.push(r)
            }
        };
        match g {
            Global::Msg(m) => {
                add(m.from);
                add(m.to);
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| add(*r)),
            Global::After(a) => add(a.by),
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
                gs.iter().for_each(|g| crate::stack::deep(|| go(g, seen, out)))
            }
            Global::Rec { body, .. } => crate::stack::deep(|| go(body, seen, out)),
            Global::Var(_) | Global::End(_) => {}
        }
    }
    let mut out = Vec::new();
    let mut seen = Default::default();
    crate::stack::deep(|| go(g, &mut seen, &mut out));
    out
}

/// The participants of `rs` not in `of`, in the order of `rs`. A joint motion of n
/// participants in a scope of n compares them through a set, not pairwise.
fn not_in(rs: &[RoleId], of: &[RoleId]) -> Vec<RoleId> {
    if rs.len() * of.len() > 4096 {
        let of: std::collections::HashSet<&RoleId> = of.iter().collect();
        rs.iter().copied().filter(|r| !of.contains(r)).collect()
    } else {
        rs.iter().copied().filter(|r| !of.contains(r)).collect()
    }
}

pub(crate) fn names(prog: &Program, rs: &[RoleId]) -> String {
    let v: Vec<_> = rs.iter().map(|r| format!("`{}`", prog.role_name(*r))).collect();
    v.join(", ")
}

impl<'a> Scope<'a> {
    /// `original` is false inside an unfolded copy, where per-node errors were already
    /// produced for the original.
    fn walk(&mut self, g: &'a Global, scope: &[RoleId], original: bool) {
        crate::stack::deep(|| self.walk_inner(g, scope, original))
    }

    fn out_of_scope(&mut self, who: &[RoleId], scope: &[RoleId], loc: Loc, what: &str) {
        let outside = not_in(who, scope);
        if outside.is_empty() {
            return;
        }
        self.diags.push(
            Diagnostic::error(
                Code::OutOfScope,
                loc.0,
                format!(
                    "{what} involves {}, outside its scope {{{}}}",
                    names(self.prog, &outside),
                    names(self.prog, scope)
                ),
            )
            .with_note("Sec 4.1, well-scopedness: a `*` splits the participants in scope between its sides")
            .with_help("move this action out of the `*`, or move the participant into this side"),
        );
    }

    fn walk_inner(&mut self, g: &'a Global, scope: &[RoleId], original: bool) {
        match g {
            Global::Msg(m) => {
                if original {
                    self.out_of_scope(&[m.from, m.to], scope, m.loc, "this message");
                }
            }
            Global::Motion(m) => {
                if original {
                    self.motion(m, scope);
                }
            }
            Global::After(a) => {
                if original {
                    self.out_of_scope(&[a.by], scope, a.loc, "this timeout");
                }
            }
            Global::Seq(items, _) => items.iter().for_each(|i| self.walk(i, scope, original)),
            Global::Choice(branches, _) => branches.iter().for_each(|b| self.walk(b, scope, original)),
            Global::Par(sides, loc) => self.par(sides, *loc, scope, original),
            Global::Rec { var, body, .. } => {
                self.recs.insert(var, body);
                self.walk(body, scope, original);
            }
            Global::Var(v) => {
                if self.unfolding.contains(&v.var.as_str()) {
                    return;
                }
                let Some(body) = self.recs.get(v.var.as_str()).copied() else { return };
                let mut pt = Vec::new();
                body.participants(&mut pt);
                let outside = not_in(&pt, scope);
                if !outside.is_empty() {
                    self.diags.push(
                        Diagnostic::error(
                            Code::OutOfScope,
                            v.loc.0,
                            format!(
                                "unfolding `{}` here brings {} into a scope of only {{{}}}",
                                v.var,
                                names(self.prog, &outside),
                                names(self.prog, scope)
                            ),
                        )
                        .with_note("Sec 4.1: well-scopedness is checked on the once-unfolded type")
                        .with_help("recurse outside the `*`, where every participant of the loop is in scope"),
                    );
                    return;
                }
                self.unfolding.push(&v.var);
                self.walk(body, scope, false);
                self.unfolding.pop();
            }
            Global::End(_) => {}
        }
    }

    fn motion(&mut self, m: &Motion, scope: &[RoleId]) {
        let who: Vec<RoleId> = m.parts.iter().map(|(r, _)| *r).collect();
        self.out_of_scope(&who, scope, m.loc, "this joint motion");
        let missing = not_in(scope, &who);
        if !missing.is_empty() {
            self.diags.push(
                Diagnostic::error(
                    Code::IncompleteMotion,
                    m.loc.0,
                    format!("this joint motion gives no primitive to {}, in scope here", names(self.prog, &missing)),
                )
                .with_note("Def 4.4 (3), total motion: time passes for every participant in scope, so each must run a primitive")
                .with_help("add a primitive for them (an idle one if they stay put), or separate them with `*`"),
            );
        }
        // Several non-interruptible primitives are not an error here: whether their
        // durations force a common end (joint end, ARCHITECTURE.md) depends on Σ, so the
        // SMT stage decides it as a part of this motion's [AGCOMP] obligation (E0401).
    }

    fn par(&mut self, sides: &'a [Global], loc: Loc, scope: &[RoleId], original: bool) {
        let pts: Vec<Vec<RoleId>> = sides.iter().map(Global::participant_list).collect();
        if original {
            // Each participant's side, found in one pass (n-ary `*` of PGCD's lanes has
            // hundreds of sides, so no pairwise comparison of sides).
            let mut owner: HashMap<RoleId, usize> = HashMap::new();
            let mut reported: Vec<RoleId> = Vec::new();
            for (i, pt) in pts.iter().enumerate() {
                for r in pt {
                    match owner.get(r) {
                        Some(&j) if j != i && !reported.contains(r) => {
                            reported.push(*r);
                            self.diags.push(
                                Diagnostic::error(
                                    Code::SeparationOverlap,
                                    sides[i].loc().0,
                                    format!("{} on both sides of `*`", names(self.prog, &[*r])),
                                )
                                .with_label(sides[j].loc().0, "the other side")
                                .with_note("Sec 4.1, full separation: pt{g1} ∩ pt{g2} = ∅")
                                .with_help("keep each participant's actions on one side of the `*`"),
                            );
                        }
                        Some(_) => {}
                        None => {
                            owner.insert(*r, i);
                        }
                    }
                }
            }
            let dropped: Vec<RoleId> = scope.iter().copied().filter(|r| !owner.contains_key(r)).collect();
            if !dropped.is_empty() {
                self.diags.push(
                    Diagnostic::error(
                        Code::IncompleteMotion,
                        loc.0,
                        format!("{} in scope but on no side of this `*`", names(self.prog, &dropped)),
                    )
                    .with_note(
                        "Def 4.4 (3), total motion: while the sides run, every participant in scope must be moving",
                    )
                    .with_help("add a side `dt<P: idle>` for them"),
                );
            }
            self.coupling(sides, &owner);
        }
        for (side, pt) in sides.iter().zip(&pts) {
            let sub: Vec<RoleId> = if pt.len() * scope.len() > 4096 {
                let in_scope: std::collections::HashSet<&RoleId> = scope.iter().collect();
                pt.iter().copied().filter(|r| in_scope.contains(r)).collect()
            } else {
                pt.iter().copied().filter(|r| scope.contains(r)).collect()
            };
            self.walk(side, &sub, original);
        }
    }

    /// Full separation, coupling half (Sec 4.1): the assumption of a primitive in side i
    /// reads only inputs fed by participants of side i.
    fn coupling(&mut self, sides: &[Global], owner: &HashMap<RoleId, usize>) {
        for (i, side) in sides.iter().enumerate() {
            let mut motions = Vec::new();
            collect_motions(side, &mut motions);
            for m in motions {
                for (r, app) in &m.parts {
                    let prim = self.prog.prim(app.prim);
                    let sources = &self.prog.role(*r).input_sources;
                    let mut bad = Vec::new();
                    prim.assume.visit_vars(&mut |v, _| {
                        if let Var::Own(Slot::Input(k)) = v {
                            if let Some(Some(src)) = sources.get(*k) {
                                if owner.get(src) != Some(&i) && !bad.iter().any(|(kk, _)| kk == k) {
                                    bad.push((*k, *src));
                                }
                            }
                        }
                    });
                    for (k, src) in bad {
                        let input = &self.prog.kind_of(*r).inputs[k].0;
                        self.diags.push(
                            Diagnostic::error(
                                Code::CoupledAcrossSeparation,
                                app.loc.0,
                                format!(
                                    "the assumption of `{}` reads input `{input}` of `{}`, fed by `{}` outside this side of `*`",
                                    prim.name,
                                    self.prog.role_name(*r),
                                    self.prog.role_name(src)
                                ),
                            )
                            .with_note("Sec 4.1, full separation: assumptions depend only on state variables of the same side")
                            .with_help(format!("put `{}` and `{}` on the same side", self.prog.role_name(*r), self.prog.role_name(src))),
                        );
                    }
                }
            }
        }
    }
}

fn collect_motions<'g>(g: &'g Global, out: &mut Vec<&'g Motion>) {
    match g {
        Global::Motion(m) => out.push(m),
        Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
            gs.iter().for_each(|g| collect_motions(g, out))
        }
        Global::Rec { body, .. } => collect_motions(body, out),
        Global::Msg(_) | Global::Var(_) | Global::End(_) | Global::After(_) => {}
    }
}

#[cfg(test)]
mod tests {
    use crate::diag::Code;
    use crate::lower::tests::lower_src;
    use crate::obligation::Rule;

    const SYS: &str = "
        robot R { state x: real; }
        robot W { input x: real; }
        motion R.go { interruptible: false; }
        motion R.wait { interruptible: true; }
        motion W.watch { interruptible: true; assume: x >= 0; }
        system S { participant P: R; participant Q: R; participant V: R; }
    ";

    fn run(chor: &str) -> (Vec<Code>, Vec<Rule>) {
        let (p, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let c = p.choreography.as_ref().expect("choreography");
        let (o, d) = (crate::plan::obligations(&p, &c.body), super::check(&p, &c.body));
        (d.into_iter().map(|d| d.code).collect(), o.into_iter().map(|o| o.rule).collect())
    }

    #[test]
    fn figure_2_shape_is_well_scoped() {
        let (d, o) = run("mu t. P -> Q : a. P -> V : c. ((dt<P: go, Q: wait>. P -> Q : b. (dt<P: go> * dt<Q: wait>)) * dt<V: wait>). t");
        assert_eq!(d, vec![]);
        // Every dt needs [AGCOMP] (a lone one only that it can end: 4 of them); two `*` need separation.
        assert_eq!(o.iter().filter(|r| **r == Rule::AgComp).count(), 4);
        assert_eq!(o.iter().filter(|r| **r == Rule::FullSeparation).count(), 2);
    }

    #[test]
    fn scoping_errors_have_their_codes() {
        assert_eq!(
            run("(dt<P: go> * dt<P: wait, Q: wait> * dt<V: wait>). dt<V: wait, P: wait, Q: wait>. end").0,
            vec![Code::SeparationOverlap]
        );
        // V is unused: reported once (E0313), not again at every motion it misses.
        assert_eq!(run("dt<P: go, Q: wait>. end").0, vec![Code::ParticipantUnused]);
        assert_eq!(
            run("(dt<P: go> * dt<Q: wait>). dt<P: wait, Q: wait, V: wait>. end").0,
            vec![Code::IncompleteMotion]
        );
        // Two non-interruptible primitives: joint end is the SMT stage's to decide (E0401).
        assert_eq!(run("dt<P: go, Q: go, V: wait>. end").0, vec![]);
        assert_eq!(
            run("mu t. (P -> Q : a. dt<P: go, Q: wait>. t) * dt<V: wait>")
                .0
                .last()
                .copied()
                .into_iter()
                .collect::<Vec<_>>(),
            vec![Code::OutOfScope],
            "(besides E0314) the unfolded `t` needs V inside the left side"
        );
    }

    #[test]
    fn an_input_fed_from_the_other_side_couples_them() {
        let src = "robot R { state x: real; } robot W { input x: real; }
            motion R.go { interruptible: false; } motion W.watch { interruptible: true; assume: x >= 0; }
            system S { participant P: R; participant O: W; }
            choreography G = dt<P: go> * dt<O: watch>. end;";
        let (p, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let d = super::check(&p, &p.choreography.as_ref().unwrap().body);
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), vec![Code::CoupledAcrossSeparation]);
    }

    #[test]
    fn guarded_choices_need_total_choice() {
        let (_, o) = run("P -> Q : [x > 0] a. dt<P: wait, Q: wait, V: wait>. end + P -> Q : [x <= 0] b. dt<P: wait, Q: wait, V: wait>. end");
        assert!(o.contains(&Rule::TotalChoice));
        let (_, o) = run(
            "P -> Q : [x > 0] a. dt<P: wait, Q: wait, V: wait>. end + P -> Q : b. dt<P: wait, Q: wait, V: wait>. end",
        );
        assert!(!o.contains(&Rule::TotalChoice), "an unguarded branch makes it trivial");
    }
}

#[cfg(test)]
mod scale_tests {
    use crate::lower::tests::lower_src;

    /// A joint motion of n participants in a scope of n, and n participants to check
    /// against pt{G}: the scope checks compare them through sets, not pairwise.
    #[test]
    #[ignore = "a timing ratio, for a quiet machine: `cargo test -- --ignored`; the pipeline benchmark measures the wide dt"]
    fn a_wide_dt_is_scoped_in_time_linear_in_its_parts() {
        let time = |n: usize| {
            let mut src = String::from("robot R { state x: real; } motion R.hold { interruptible: true; } system S {");
            for i in 0..n {
                src.push_str(&format!(" participant P{i}: R;"));
            }
            let parts: Vec<String> = (0..n).map(|i| format!("P{i}: hold")).collect();
            src.push_str(&format!(" }} choreography G = dt<{}>. end;", parts.join(", ")));
            let (p, d) = lower_src(&src);
            assert!(d.is_empty(), "{d:?}");
            let g = &p.choreography.as_ref().expect("choreography").body;
            let mut best = std::time::Duration::MAX;
            for _ in 0..3 {
                let t = std::time::Instant::now();
                let (o, d) = (crate::plan::obligations(&p, g), super::check(&p, g));
                best = best.min(t.elapsed());
                assert!(d.is_empty(), "{d:?}");
                assert_eq!(o.len(), 1, "one [AGCOMP] obligation");
            }
            best
        };
        // The pairwise comparisons were x40 and more at eight times the parts.
        crate::testing::assert_near_linear("parts", 1000, 8000, time);
    }
}
