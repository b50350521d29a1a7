//! Well-scopedness (Sec 4.1, labelling rules (1)-(6)) on the once-unfolded type, with
//! the participant half of full separation (E0307), total motion (Def 4.4 (3), E0309),
//! `pt{G} = P` of [T-SESS] (E0313), the coupling half of full separation (E0315) and the
//! syntactic half of [AGCOMP]: at most one non-interruptible primitive (E0401).
//!
//! The labelling is deterministic: the root gets every participant, `.` and `+` pass
//! their label down, and `g1 * ... * gn` gives each side exactly `pt{g_i}`. That choice
//! loses nothing: any valid labelling must give side i at least `pt{g_i}`, and a
//! participant given to no side has no motion there, which total motion forbids.
//!
//! Predicates are not decided here; each joint motion yields an [AGCOMP] obligation,
//! each `*` a full-separation obligation and each guarded choice a total-choice one.

use crate::diag::{Code, Diagnostic};
use crate::hir::expr::BinOp;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use std::collections::HashMap;

pub fn check(prog: &Program, g: &Global) -> (Vec<Diagnostic>, Vec<Obligation>) {
    let mut s = Scope { prog, diags: Vec::new(), obligations: Vec::new(), recs: HashMap::new(), unfolding: Vec::new() };
    let mut used = Vec::new();
    g.participants(&mut used);
    for r in prog.role_ids() {
        if !used.contains(&r) {
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
    }
    // The root scope is P; an unused participant was reported above (E0313), so scope
    // with pt{G} to avoid reporting it again at every motion.
    s.walk(g, &used, true);
    (s.diags, s.obligations)
}

struct Scope<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
    obligations: Vec<Obligation>,
    /// Recursion variable → its body, for the one unfolding.
    recs: HashMap<&'a str, &'a Global>,
    /// Variables being unfolded (their second occurrence is a leaf).
    unfolding: Vec<&'a str>,
}

fn names(prog: &Program, rs: &[RoleId]) -> String {
    let v: Vec<_> = rs.iter().map(|r| format!("`{}`", prog.role_name(*r))).collect();
    v.join(", ")
}

impl<'a> Scope<'a> {
    /// `original` is false inside an unfolded copy, where obligations and per-node
    /// errors were already produced for the original.
    fn walk(&mut self, g: &'a Global, scope: &[RoleId], original: bool) {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.walk_inner(g, scope, original))
    }

    fn out_of_scope(&mut self, who: &[RoleId], scope: &[RoleId], loc: Loc, what: &str) {
        let outside: Vec<RoleId> = who.iter().copied().filter(|r| !scope.contains(r)).collect();
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
            Global::Seq(items, _) => items.iter().for_each(|i| self.walk(i, scope, original)),
            Global::Choice(branches, _) => {
                if original {
                    self.total_choice(branches, scope);
                }
                branches.iter().for_each(|b| self.walk(b, scope, original));
            }
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
                let outside: Vec<RoleId> = pt.iter().copied().filter(|r| !scope.contains(r)).collect();
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
        let missing: Vec<RoleId> = scope.iter().copied().filter(|r| !who.contains(r)).collect();
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
        let non: Vec<&(RoleId, PrimApp)> =
            m.parts.iter().filter(|(_, a)| !self.prog.prim(a.prim).interruptible).collect();
        if non.len() > 1 {
            let mut d = Diagnostic::error(
                Code::TwoNonInterruptible,
                m.loc.0,
                format!("{} primitives of this joint motion are non-interruptible", non.len()),
            );
            for (r, a) in &non {
                d = d.with_label(
                    a.loc.0,
                    format!("`{}` cannot be interrupted ({})", self.prog.prim(a.prim).name, self.prog.role_name(*r)),
                );
            }
            self.diags.push(
                d.with_note("[AGCOMP]: ‡1 = ↯ ∨ ‡2 = ↯ — at most one primitive of a joint motion is non-interruptible")
                    .with_help("make all but one of them interruptible"),
            );
        }
        // A lone participant whose assumption is literally `true` has nothing to compose:
        // [AGCOMP] with one primitive leaves only the assumption to discharge.
        let trivial = m.parts.len() == 1 && self.prog.prim(m.parts[0].1.prim).assume.is_true();
        if !trivial {
            self.obligations.push(Obligation {
                rule: Rule::AgComp,
                span: m.loc.0,
                what: format!("joint motion of {}", names(self.prog, &who)),
                hyps: Vec::new(),
                goal: Goal::Compatible { parts: m.parts.clone() },
            });
        }
    }

    fn total_choice(&mut self, branches: &[Global], _scope: &[RoleId]) {
        let guards: Vec<Option<&Expr>> =
            branches.iter().map(|b| super::side::first_message(b).and_then(|m| m.guard.as_ref())).collect();
        if guards.iter().any(|g| g.is_none_or(Expr::is_true)) {
            return; // an unguarded branch: the disjunction is trivially valid
        }
        let Some(m) = branches.first().and_then(super::side::first_message) else { return };
        let mut disj: Option<Expr> = None;
        for g in guards.into_iter().flatten() {
            disj = Some(match disj {
                None => g.clone(),
                Some(d) => {
                    let loc = d.loc;
                    Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(d), Box::new(g.clone())), sort: Sort::Bool, loc }
                }
            });
        }
        if let Some(goal) = disj {
            self.obligations.push(Obligation {
                rule: Rule::TotalChoice,
                span: m.loc.0,
                what: format!("the guards of the choice by `{}`", self.prog.role_name(m.from)),
                hyps: Vec::new(),
                goal: Goal::Valid(goal),
            });
        }
    }

    fn par(&mut self, sides: &'a [Global], loc: Loc, scope: &[RoleId], original: bool) {
        let pts: Vec<Vec<RoleId>> = sides
            .iter()
            .map(|s| {
                let mut v = Vec::new();
                s.participants(&mut v);
                v
            })
            .collect();
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
            if sides.len() > 1 {
                self.obligations.push(Obligation {
                    rule: Rule::FullSeparation,
                    span: loc.0,
                    what: format!("footprints of the {} sides of `*`", sides.len()),
                    hyps: Vec::new(),
                    goal: Goal::Separated {
                        sides: pts
                            .iter()
                            .map(|roles| crate::obligation::Side { roles: roles.clone(), runs: Vec::new() })
                            .collect(),
                    },
                });
            }
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
        Global::Msg(_) | Global::Var(_) | Global::End(_) => {}
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
        let (d, o) = super::check(&p, &c.body);
        (d.into_iter().map(|d| d.code).collect(), o.into_iter().map(|o| o.rule).collect())
    }

    #[test]
    fn figure_2_shape_is_well_scoped() {
        let (d, o) = run("mu t. P -> Q : a. P -> V : c. ((dt<P: go, Q: wait>. P -> Q : b. (dt<P: go> * dt<Q: wait>)) * dt<V: wait>). t");
        assert_eq!(d, vec![]);
        // One joint motion needs [AGCOMP]; lone primitives assuming `true` need none; two `*` need separation.
        assert_eq!(o.iter().filter(|r| **r == Rule::AgComp).count(), 1);
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
        assert_eq!(run("dt<P: go, Q: go, V: wait>. end").0, vec![Code::TwoNonInterruptible]);
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
        let (d, _) = super::check(&p, &p.choreography.as_ref().unwrap().body);
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
