//! Replaying a counterexample in exact arithmetic before it is shown.
//!
//! A part fails when its query is satisfiable; the model is then the counterexample.
//! Before it is reported, the model's values (exact rationals, [`crate::exact`]) are put
//! back into the obligation's own expressions — independently of the encoding — and
//! evaluated: every hypothesis must not be false, and the goal (the conjunct, the
//! precondition, the two footprints) must not be true. If either happens, the model
//! does not falsify the goal: the encoding and the evaluator disagree, which is a bug,
//! and the part is reported **unknown** ("its model did not replay") rather than as a
//! wrong counterexample. Undecided evaluations (an enclosure of `sqrt` or `sin`, a
//! variable the model leaves out) never refute: replay only rejects on definite answers.

use super::encode::Encoder;
use super::goals::Part;
use crate::exact::{self, Num, Tri, Value};
use crate::hir::{Builtin, Expr, Footprint, Program, RoleId, Slot, Var};
use crate::obligation::{Goal, Obligation};
use std::collections::HashMap;

/// A model: values by the names the encoder gives variables (`Cart.x`, `old(Cart.x)`,
/// `Cart.x(t)`, `time`, `point.x`, value names).
pub type Valuation = HashMap<String, Value>;

/// The exact values of every named variable of a query in `model`.
pub fn valuation(enc: &Encoder, model: &z3::Model) -> Valuation {
    let mut m: Valuation =
        enc.terms().filter_map(|(n, t)| Some((n.clone(), super::goals::witness::value_of(model, t)?))).collect();
    // A value is looked up by its binding site: two values named `v` are `v` and `v#2`.
    for (id, symbol) in enc.value_symbols() {
        if let Some(v) = m.get(symbol).cloned() {
            m.insert(value_key(*id), v);
        }
    }
    m
}

/// The key of value variable `id` in a [`Valuation`].
fn value_key(id: crate::hir::ValueId) -> String {
    format!("#value{}", id.idx())
}

/// Why a model does not falsify its part, or `None` if it does (or cannot be decided).
pub fn refutes(prog: &Program, ob: &Obligation, part: &Part, m: &Valuation) -> Option<String> {
    let shared = |v: &Var| shared_var(prog, v, m);
    let false_hyp = |hs: &[Expr]| {
        hs.iter()
            .find(|h| exact::holds(prog, h, &shared) == Tri::False)
            .map(|h| format!("the hypothesis `{}` is false under it", crate::hir::print::expr(prog, None, h)))
    };
    match (&ob.goal, part) {
        (Goal::Valid(g), Part::Valid | Part::Conjunct(_)) => {
            let goal = match part {
                Part::Conjunct(k) => g.conjuncts().get(*k).copied()?,
                _ => g,
            };
            false_hyp(&ob.hyps).or_else(|| {
                (exact::holds(prog, goal, &shared) == Tri::True)
                    .then(|| format!("the goal `{}` holds under it", crate::hir::print::expr(prog, None, goal)))
            })
        }
        (Goal::Compatible { parts }, Part::Pre(i)) => false_hyp(&ob.hyps).or_else(|| {
            let (r, app) = parts.get(*i)?;
            let args = app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
            let env = frame(prog, *r, m, None, &args, None);
            let prim = prog.prim(app.prim);
            (exact::holds(prog, &prim.pre, &env) == Tri::True)
                .then(|| format!("the precondition of `{}` holds under it", prim.name))
        }),
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => false_hyp(&ob.hyps).or_else(|| {
            let world = model_point(m)?;
            [*i, *j].iter().find_map(|k| outside_footprint(prog, m, parts.get(*k)?, &world))
        }),
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => false_hyp(&ob.hyps).or_else(|| {
            let world = model_point(m)?;
            if let Some(why) = outside_footprint(prog, m, parts.get(*i)?, &world) {
                return Some(why);
            }
            let obstacle = prog.obstacles.get(*o)?;
            let region = crate::space::region::obstacle_region(prog, obstacle)?;
            let at = |v: &Var| match v {
                Var::Point(k) => world.get(*k).cloned().map(Value::Num),
                other => shared_var(prog, other, m),
            };
            (exact::holds(prog, &region, &at) == Tri::False)
                .then(|| format!("its point is not in obstacle `{}`", obstacle.name))
        }),
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let hs: Vec<Expr> = [(a, ra), (b, rb)]
                .iter()
                .filter_map(|(s, r)| sides.get(**s)?.runs.get(**r))
                .flat_map(|run| run.hyps.iter().cloned())
                .collect();
            false_hyp(&hs)
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => false_hyp(&sides.get(*a)?.runs.get(*ra)?.hyps),
        _ => false_hyp(&ob.hyps),
    }
}

/// The world point of an overlap in the model (`point.x`, `point.y`, `point.z`).
fn model_point(m: &Valuation) -> Option<[Num; 3]> {
    let point = ["point.x", "point.y", "point.z"].map(|n| m.get(n).and_then(|v| v.num().ok().cloned()));
    let [Some(px), Some(py), Some(pz)] = point else { return None };
    Some([px, py, pz])
}

/// Why the model refutes "the world point is in the footprint of `app` run by `r` at time
/// `t`", if it does (the footprint is false there, exactly).
fn outside_footprint(
    prog: &Program,
    m: &Valuation,
    (r, app): &(RoleId, crate::hir::PrimApp),
    world: &[Num; 3],
) -> Option<String> {
    let shared = |v: &Var| shared_var(prog, v, m);
    let prim = prog.prim(app.prim);
    let fp = match &prim.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => fp,
        // All space holds every point; a body with no predicate is not replayed here.
        Footprint::Everywhere | Footprint::Solid { .. } => return None,
    };
    let local = to_local(prog, *r, world)?;
    let args = app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
    let env = frame(prog, *r, m, Some("t"), &args, Some(local));
    (exact::holds(prog, &fp.pred, &env) == Tri::False)
        .then(|| format!("its point is not in the footprint of `{}`", prim.name))
}

/// A variable of the shared vocabulary, named as the encoder names it.
fn shared_var(prog: &Program, v: &Var, m: &Valuation) -> Option<Value> {
    let name = match prog.source_of(v) {
        Var::Role(r, slot) => format!("{}.{}", prog.role_name(r), prog.kind_of(r).var(slot).0),
        Var::Snap(r, slot) => format!("old({}.{})", prog.role_name(r), prog.kind_of(r).var(slot).0),
        Var::Value(id, _) => value_key(id),
        _ => return None,
    };
    m.get(&name).cloned()
}

/// The environment of `r`'s primitive: own variables at `tag` (`Cart.x(t)`) or at the
/// start, `old` the start, the arguments, `clock` the query's `time`, the local point.
fn frame<'m>(
    prog: &'m Program,
    r: RoleId,
    m: &'m Valuation,
    tag: Option<&'m str>,
    args: &'m [Option<Value>],
    point: Option<[Num; 3]>,
) -> impl Fn(&Var) -> Option<Value> + 'm {
    move |v: &Var| {
        let role = prog.role_name(r);
        let kind = prog.kind_of(r);
        match v {
            Var::Own(slot) => {
                let n = &kind.var(*slot).0;
                match (tag, slot) {
                    (Some(t), _) => m.get(&format!("{role}.{n}({t})")).cloned(),
                    (None, Slot::State(_)) => shared_var(prog, &Var::Role(r, *slot), m),
                    (None, Slot::Input(_)) => m.get(&format!("{role}.{n}")).cloned(),
                }
            }
            Var::Old(i) => shared_var(prog, &Var::Role(r, Slot::State(*i)), m),
            Var::Param(i) => args.get(*i).cloned().flatten(),
            Var::Clock => m.get("time").cloned(),
            Var::Point(k) => point.as_ref().and_then(|p| p.get(*k).cloned()).map(Value::Num),
            other => shared_var(prog, other, m),
        }
    }
}

/// The world point in `role`'s frame, `R^T (p - o)`, with enclosures of the pose's
/// sines and cosines (the encoding rounds them; see ARCHITECTURE.md, "Pose rotations").
pub fn to_local(prog: &Program, role: RoleId, p: &[Num; 3]) -> Option<[Num; 3]> {
    if prog.role(role).mounted_on.is_some() {
        return None;
    }
    let pose = &prog.role(role).pose;
    let num = |i: usize| -> Option<Num> {
        match pose.get(i) {
            Some(e) => exact::eval(prog, e, &|_: &Var| None).ok()?.num().ok().cloned(),
            None => Some(Num::int(0)),
        }
    };
    let mut v = p.clone();
    for (k, c) in v.iter_mut().enumerate() {
        *c = c.sub(&num(k)?);
    }
    for (idx, (a, b)) in [(5usize, (0usize, 1usize)), (4, (2, 0)), (3, (1, 2))] {
        let angle = num(idx)?;
        if angle.value().is_some_and(num_traits::Zero::is_zero) {
            continue;
        }
        // An exact quarter turn (`pi / 2`) is exact here as in the encoding.
        let (c, s) = match pose.get(idx).and_then(|e| crate::bounds::quarter_turn(prog, e)) {
            Some((c, s)) => (Num::int(c), Num::int(s)),
            None => (exact::trig(Builtin::Cos, &angle), exact::trig(Builtin::Sin, &angle)),
        };
        let (x, y) = (v[a].clone(), v[b].clone());
        v[a] = c.mul(&x).add(&s.mul(&y));
        v[b] = c.mul(&y).sub(&s.mul(&x));
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;
    use crate::obligation::Rule;

    /// An obligation `hyp ⇒ goal` over `A.x` (guards of two messages).
    fn obligation(hyp: &str, goal: &str) -> (Program, Obligation) {
        let src = format!(
            "robot R {{ state x: real; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{hyp}] a. A -> B : [{goal}] b. end;"
        );
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("a sequence")
        };
        let guard = |i: usize| match &items[i] {
            crate::hir::Global::Msg(m) => m.guard.clone().expect("guard"),
            _ => panic!("a message"),
        };
        let ob = Obligation {
            rule: Rule::TOut,
            span: Default::default(),
            what: "test".into(),
            hyps: vec![guard(0)],
            goal: Goal::Valid(guard(1)),
        };
        (prog, ob)
    }

    fn model(x: &str) -> Valuation {
        let v = exact::parse_decimal(x).expect("number");
        [("A.x".to_string(), Value::rat(v))].into_iter().collect()
    }

    #[test]
    fn a_real_counterexample_replays() {
        let (prog, ob) = obligation("x >= 0", "x > 0");
        assert_eq!(refutes(&prog, &ob, &Part::Valid, &model("0")), None);
    }

    #[test]
    fn a_fake_model_that_satisfies_the_goal_is_refuted() {
        let (prog, ob) = obligation("x >= 0", "x > 0");
        let why = refutes(&prog, &ob, &Part::Valid, &model("0.5")).expect("the goal holds at 0.5");
        assert!(why.contains("goal"), "{why}");
    }

    #[test]
    fn a_fake_model_that_breaks_a_hypothesis_is_refuted() {
        let (prog, ob) = obligation("x >= 0", "x > 0");
        let why = refutes(&prog, &ob, &Part::Valid, &model("-1")).expect("the hypothesis fails at -1");
        assert!(why.contains("hypothesis"), "{why}");
    }

    /// Two bots (footprint: a ball of radius 0.1) 0.15 apart in one joint motion; the
    /// footprints part with a fake model whose point is `(px, 0, 0)`.
    fn footprints_part(px: &str) -> Option<String> {
        let src = "robot Bot { state s: real; }
             motion Bot.hold { interruptible: true; footprint(x, y, z): x^2 + y^2 + z^2 <= 0.01; }
             system S { participant A: Bot { init: s == 0; } participant B: Bot { init: s == 0; at: pose(0.15, 0, 0, 0, 0, 0.3); } }
             choreography G = dt<A: hold, B: hold>;";
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Motion(m)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("a motion")
        };
        let ob = Obligation {
            rule: Rule::AgComp,
            span: Default::default(),
            what: "test".into(),
            hyps: vec![],
            goal: Goal::Compatible { parts: m.parts.clone() },
        };
        let num = |v: &str| Value::rat(exact::parse_decimal(v).expect("number"));
        let model: Valuation = [
            ("point.x", num(px)),
            ("point.y", num("0")),
            ("point.z", num("0")),
            ("A.s(t)", num("0")),
            ("B.s(t)", num("0")),
            ("time", num("1")),
        ]
        .into_iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect();
        refutes(&prog, &ob, &Part::Disjoint(0, 1), &model)
    }

    #[test]
    fn a_common_point_replays_and_a_fake_one_does_not() {
        // Inside both balls (B's frame is rotated by a yaw of 0.3: enclosed, decided).
        assert_eq!(footprints_part("0.07"), None);
        // Outside A's ball: not a collision.
        let why = footprints_part("0.2").expect("0.2 is outside A's footprint");
        assert!(why.contains("not in the footprint of `hold`"), "{why}");
    }

    #[test]
    fn an_undecided_evaluation_does_not_refute() {
        // sqrt(2)^2 == 2 cannot be decided with enclosures; a missing variable neither.
        let (prog, ob) = obligation("x >= 0", "sqrt(x)^2 != 2");
        assert_eq!(refutes(&prog, &ob, &Part::Valid, &model("2")), None);
        assert_eq!(refutes(&prog, &ob, &Part::Valid, &Valuation::new()), None);
    }
}
