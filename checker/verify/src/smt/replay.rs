//! Replaying a counterexample in exact arithmetic before it is shown.
//!
//! A part fails when its query is satisfiable; the model is then the counterexample.
//! Before it is reported, the model's values (exact rationals, [`crate::exact`]) are put
//! back into the obligation's own expressions — independently of the encoding — and
//! evaluated against the part's **own goal**, for every kind of part ([`replay`]): no
//! hypothesis may be false, and the violation itself (the goal false; a precondition or
//! an assumption false; a point in both footprints, in a footprint and an obstacle, in a
//! footprint and outside its side's region; a duration outside another; an item of
//! Def 3.4 broken) must be true, decided exactly. A model that does not falsify its goal
//! makes the part **unknown**, never failed: refuted outright (a model of a neighbouring
//! rotation that the enclosure of a pose's angle admits, as in
//! `tests/data/rotation-far-from-origin.chor`; otherwise the encoding and the evaluator
//! disagree, a bug), or undecided (an enclosure of a
//! pose's rotation, `sin`, `cos` or `sqrt` straddles a boundary, as a point on the edge of
//! a footprint turned by `1.5708` does: "not confirmed as a counterexample").
//!
//! Two things are not evaluated here: a footprint with no predicate (a URDF or mesh
//! part; those parts are the geometric procedure's, which checks its own contacts), and
//! the existential of a progress goal's payload ("no payload satisfies the refinement"),
//! which evaluation cannot decide: only the branches with no payload to choose are
//! evaluated, and the solver's unsat answer about the others stands.

use super::encode::Encoder;
use super::goals::Part;
use crate::exact::{self, Num, Tri, Value};
use crate::hir::{Builtin, Expr, Footprint, PrimApp, Program, RoleId, Slot, Var};
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

/// What replaying a model against its part found.
#[derive(Clone, Debug, PartialEq)]
pub enum Replay {
    /// Evaluated exactly, the model falsifies the part's goal: every condition that makes
    /// up the violation (the goal false, a point in both footprints, a duration outside
    /// another, ...) is true under it, and no hypothesis is false.
    Falsifies,
    /// A hypothesis is false, or a condition of the violation is, under the model: the
    /// encoding and the evaluator disagree (a bug), with why.
    Refuted(String),
    /// Neither: some condition of the violation cannot be decided exactly under the model
    /// (an enclosure of `sin`, `cos` or `sqrt` that straddles a boundary, a variable the
    /// model leaves out, a footprint with no predicate), with which.
    Undecided(String),
}

/// The conditions of a violation, evaluated one by one.
struct Violation<'p> {
    prog: &'p Program,
    refuted: Option<String>,
    open: Option<String>,
}

impl<'p> Violation<'p> {
    fn new(prog: &'p Program) -> Self {
        Violation { prog, refuted: None, open: None }
    }

    /// The violation needs `what` (a sentence: "the goal `g` fails") to be true: `t`.
    fn need(&mut self, t: Tri, what: impl FnOnce() -> String) {
        match t {
            Tri::True => {}
            Tri::False => {
                self.refuted.get_or_insert_with(|| format!("it does not show that {}", what()));
            }
            Tri::Unknown => {
                self.open.get_or_insert_with(|| format!("whether {} is not decided exactly under it", what()));
            }
        }
    }

    /// The violation needs `e` (under `env`) to be false.
    fn fails(&mut self, e: &Expr, env: &dyn exact::Env, what: impl FnOnce() -> String) {
        let t = exact::holds(self.prog, e, env).not();
        self.need(t, what)
    }

    /// The violation needs `e` (under `env`) to be true.
    fn holds(&mut self, e: &Expr, env: &dyn exact::Env, what: impl FnOnce() -> String) {
        let t = exact::holds(self.prog, e, env);
        self.need(t, what)
    }

    fn verdict(self) -> Replay {
        match (self.refuted, self.open) {
            (Some(why), _) => Replay::Refuted(why),
            (None, Some(why)) => Replay::Undecided(why),
            (None, None) => Replay::Falsifies,
        }
    }
}

/// Why a model does not falsify its part, or `None` if it does or cannot be decided:
/// [`replay`]'s refutations only.
pub fn refutes(prog: &Program, ob: &Obligation, part: &Part, m: &Valuation) -> Option<String> {
    match replay(prog, ob, part, m) {
        Replay::Refuted(why) => Some(why),
        Replay::Falsifies | Replay::Undecided(_) => None,
    }
}

/// Replays model `m` against `part` of `ob`: the hypotheses the part's query assumes must
/// not be false, and the part's own goal must be false, decided exactly, for every kind
/// of part (see [`Replay`]). The sat questions (a witness, not a counterexample) have no
/// goal to falsify here: they are [`Replay::Falsifies`] when no hypothesis is false.
pub fn replay(prog: &Program, ob: &Obligation, part: &Part, m: &Valuation) -> Replay {
    let shared = |v: &Var| shared_var(prog, v, m);
    let print = |e: &Expr| crate::hir::print::expr(prog, None, e);
    let false_hyp = |hs: &[Expr]| {
        hs.iter()
            .find(|h| exact::holds(prog, h, &shared) == Tri::False)
            .map(|h| format!("the hypothesis `{}` is false under it", print(h)))
    };
    let hyps: &[Expr] = match (&ob.goal, part) {
        (Goal::Separated { .. }, _) => &[],
        _ => &ob.hyps,
    };
    if let Some(why) = false_hyp(hyps) {
        return Replay::Refuted(why);
    }
    let mut v = Violation::new(prog);
    let args_of = |app: &PrimApp| app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
    let world = model_point(m);
    let no_point = || "the model gives the point".to_string();
    match (&ob.goal, part) {
        (Goal::Valid(g), Part::Valid | Part::Conjunct(_)) => {
            let goal = match part {
                Part::Conjunct(k) => g.conjuncts().get(*k).copied(),
                _ => Some(g),
            };
            match goal {
                Some(goal) => v.fails(goal, &shared, || format!("the goal `{}` fails", print(goal))),
                None => v.need(Tri::False, || "the conjunct exists".into()),
            }
        }
        (Goal::Progress { branches }, Part::Valid) => {
            // No branch is enabled: each one's guard is false, or (with no payload value
            // left to choose) its refinement is. A branch with a payload still to choose is
            // blocked by an existential (no payload satisfies its refinement), which
            // evaluation cannot replay: its guard must not be false, nothing more.
            for b in branches.iter().filter(|b| b.fields.is_empty()) {
                let guard = b.guard.as_ref().map_or(Tri::True, |g| exact::holds(prog, g, &shared));
                let blocked = guard.not().or(exact::holds(prog, &b.refinement, &shared).not());
                v.need(blocked, || format!("`{}` cannot be taken", b.what));
            }
        }
        (Goal::Compatible { parts }, Part::Pre(i)) => match parts.get(*i) {
            Some((r, app)) => {
                let args = args_of(app);
                let prim = prog.prim(app.prim);
                let env = frame(prog, *r, m, Tags::START, &args, None);
                // An argument that cannot be evaluated is the violation by itself.
                let undefined = |a: &Expr| exact::holds(prog, &crate::hir::expr::definedness(a), &shared) == Tri::False;
                if !app.args.iter().any(undefined) {
                    v.fails(&prim.pre, &env, || format!("the precondition of `{}` fails", prim.name));
                }
            }
            None => v.need(Tri::False, || "the part exists".into()),
        },
        (Goal::Compatible { parts }, Part::Assume(i)) => match parts.get(*i) {
            Some((r, app)) => {
                let args = args_of(app);
                let prim = prog.prim(app.prim);
                let env = frame(prog, *r, m, Tags::AT_T, &args, None);
                v.fails(&prim.assume, &env, || format!("the assumption of `{}` fails at the time shown", prim.name));
            }
            None => v.need(Tri::False, || "the part exists".into()),
        },
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => match world {
            Some(world) => {
                for k in [*i, *j] {
                    match parts.get(k) {
                        Some(p) => in_footprint(&mut v, prog, m, p, Tags::AT_T, &world),
                        None => v.need(Tri::False, || "the part exists".into()),
                    }
                }
            }
            None => v.need(Tri::Unknown, no_point),
        },
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => match (world, parts.get(*i), prog.obstacles.get(*o)) {
            (Some(world), Some(p), Some(obstacle)) => {
                in_footprint(&mut v, prog, m, p, Tags::AT_T, &world);
                match crate::space::region::obstacle_region(prog, obstacle) {
                    Some(region) => {
                        let at = at_point(prog, m, &world);
                        v.holds(&region, &at, || format!("the point is in obstacle `{}`", obstacle.name));
                    }
                    None => v.need(Tri::Unknown, || format!("the point is in obstacle `{}`", obstacle.name)),
                }
            }
            (None, ..) => v.need(Tri::Unknown, no_point),
            _ => v.need(Tri::False, || "the part and the obstacle exist".into()),
        },
        (Goal::Compatible { parts }, Part::Within(n, j)) => {
            match (parts.get(*n).map(|p| duration(prog, m, p)), parts.get(*j).map(|p| duration(prog, m, p))) {
                (Some(Some((nlo, nhi))), Some(Some((jlo, jhi)))) => {
                    let inside = match (nhi, jhi) {
                        (_, None) => le(&jlo, &nlo),
                        (Some(nhi), Some(jhi)) => le(&jlo, &nlo).and(le(&nhi, &jhi)),
                        (None, Some(_)) => Tri::False,
                    };
                    v.need(inside.not(), || "one duration does not lie within the other".into());
                }
                _ => v.need(Tri::Unknown, || "the durations are outside one another".into()),
            }
        }
        (Goal::Compatible { parts }, Part::CommonEnd(n, j)) => {
            match (parts.get(*n).map(|p| duration(prog, m, p)), parts.get(*j).map(|p| duration(prog, m, p))) {
                (Some(Some((nlo, nhi))), Some(Some((jlo, jhi)))) => {
                    let same = match (nhi, jhi) {
                        (Some(nhi), Some(jhi)) => eq(&nlo, &nhi).and(eq(&jlo, &jhi)).and(eq(&nlo, &jlo)),
                        _ => Tri::False,
                    };
                    v.need(same.not(), || "the two durations are not one common instant".into());
                }
                _ => v.need(Tri::Unknown, || "the durations differ".into()),
            }
        }
        (Goal::Compatible { parts }, Part::Meet) => {
            let ds: Option<Vec<_>> = parts.iter().map(|p| duration(prog, m, p)).collect();
            match ds {
                Some(ds) => {
                    // No common time: some part ends before another starts.
                    let mut apart = Tri::False;
                    for (lo, _) in &ds {
                        for (_, hi) in &ds {
                            if let Some(hi) = hi {
                                apart = apart.or(le(lo, hi).not());
                            }
                        }
                    }
                    v.need(apart, || "some duration ends before another starts".into());
                }
                None => v.need(Tri::Unknown, || "the durations share no time".into()),
            }
        }
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let runs = [(a, ra, Tags::RUN_1), (b, rb, Tags::RUN_2)];
            for (s, r, tags) in runs {
                let Some(run) = sides.get(*s).and_then(|side| side.runs.get(*r)) else {
                    v.need(Tri::False, || "the run exists".into());
                    continue;
                };
                if let Some(why) = false_hyp(&run.hyps) {
                    return Replay::Refuted(why);
                }
                match &world {
                    Some(world) => in_footprint(&mut v, prog, m, &(run.role, run.app.clone()), tags, world),
                    None => v.need(Tri::Unknown, no_point),
                }
            }
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => {
            let Some(run) = sides.get(*a).and_then(|side| side.runs.get(*ra)) else {
                return Replay::Refuted("no such run".into());
            };
            if let Some(why) = false_hyp(&run.hyps) {
                return Replay::Refuted(why);
            }
            match (world, prog.partition(ob.span).and_then(|p| p.regions.get(*a))) {
                (Some(world), Some(region)) => {
                    in_footprint(&mut v, prog, m, &(run.role, run.app.clone()), Tags::AT_T, &world);
                    let at = at_point(prog, m, &world);
                    v.fails(region, &at, || "the point is outside the side's region".into());
                }
                (None, _) => v.need(Tri::Unknown, no_point),
                (_, None) => v.need(Tri::False, || "the partition has the side's region".into()),
            }
        }
        (Goal::Separated { .. }, Part::RegionsApart(a, b)) => {
            let regions = prog.partition(ob.span).map(|p| &p.regions);
            match (world, regions.and_then(|r| r.get(*a)), regions.and_then(|r| r.get(*b))) {
                (Some(world), Some(ra), Some(rb)) => {
                    let at = at_point(prog, m, &world);
                    v.holds(ra, &at, || "the point is in the first region".into());
                    v.holds(rb, &at, || "the point is in the second region".into());
                }
                (None, ..) => v.need(Tri::Unknown, no_point),
                _ => v.need(Tri::False, || "the partition has both regions".into()),
            }
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => match world {
            Some(world) => {
                for k in [*r, *s] {
                    let Some((role, apps)) = firsts.get(k) else {
                        v.need(Tri::False, || "the participant exists".into());
                        continue;
                    };
                    // Every first footprint holds the robot at time 0; one with no
                    // predicate is met by the robot's body placed by its start state.
                    for app in apps {
                        let prim = prog.prim(app.prim);
                        match &prim.footprint {
                            Footprint::Solid { .. } => match initial_body(prog, *role) {
                                Some(body) => {
                                    let args = args_of(app);
                                    let local = to_local(prog, *role, &world);
                                    let env = frame(prog, *role, m, Tags::AT_0, &args, local);
                                    let name = prog.role_name(*role).to_string();
                                    v.holds(&body, &env, || format!("the point is in `{name}`'s body at the start"));
                                }
                                None => v.need(Tri::Unknown, || format!("the point is in `{}`", prim.name)),
                            },
                            _ => in_footprint(&mut v, prog, m, &(*role, app.clone()), Tags::AT_0, &world),
                        }
                    }
                }
            }
            None => v.need(Tri::Unknown, no_point),
        },
        (Goal::Contains { prim }, Part::Contains(k)) => {
            let p = prog.prim(*prim);
            let role = prog.role_ids().find(|r| prog.role(*r).kind == p.kind);
            let body = prog.kind(p.kind).body.as_ref().and_then(|b| b.parts.get(*k));
            let fp = p.footprint.predicate();
            match (role, body, fp, model_point(m)) {
                (Some(role), Some(part), Some(fp), Some(local)) => {
                    let one = crate::hir::body::Body { parts: vec![part.clone()], span: part.span };
                    let region = crate::space::region::region(prog, &one, &point_vars());
                    let args: Vec<Option<Value>> = p.params.iter().map(|(n, _)| m.get(n).cloned()).collect();
                    let env = frame(prog, role, m, Tags::AT_T, &args, Some(local));
                    match region {
                        Some(region) => v.holds(&region, &env, || "the point is in the body's part".into()),
                        None => v.need(Tri::Unknown, || "the point is in the body's part".into()),
                    }
                    v.fails(&fp.pred, &env, || format!("the point is outside the footprint of `{}`", p.name));
                }
                (.., None) => v.need(Tri::Unknown, no_point),
                _ => v.need(Tri::Unknown, || "the body's part lies outside the footprint".into()),
            }
        }
        (Goal::Refines { role, concrete, abstract_ }, Part::Refine(item)) => {
            refinement(&mut v, prog, m, *role, concrete, abstract_, *item, world.as_ref());
        }
        // A witness (sat question): nothing to falsify.
        (_, p) if p.is_sat_question() => {}
        (_, p) => v.need(Tri::Unknown, || format!("the part {p:?} of this goal fails")),
    }
    v.verdict()
}

/// Which model variables a primitive's frame reads: its state (`None`: the shared start
/// state, else `R.x(tag)`), its inputs, and its clock.
#[derive(Clone, Copy)]
struct Tags {
    state: Option<&'static str>,
    input: Option<&'static str>,
    clock: Option<&'static str>,
}

impl Tags {
    /// At the start (a precondition, a duration).
    const START: Tags = Tags { state: None, input: None, clock: None };
    /// At the query's time `t` (`Cart.x(t)`, `time`).
    const AT_T: Tags = Tags { state: Some("t"), input: Some("t"), clock: Some("time") };
    /// The two runs of a separation query.
    const RUN_1: Tags = Tags { state: Some("t1"), input: Some("t1"), clock: Some("time 1") };
    const RUN_2: Tags = Tags { state: Some("t2"), input: Some("t2"), clock: Some("time 2") };
    /// At time 0, in the state named `Cart.x(0)`.
    const AT_0: Tags = Tags { state: Some("0"), input: Some("0"), clock: None };
    /// At the end of a refinement's run (`Cart.x(end)`), its inputs still at `t`.
    const END: Tags = Tags { state: Some("end"), input: Some("t"), clock: None };
}

/// `[px, py, pz]` as expressions (`Var::Point`), to build regions of body parts with.
fn point_vars() -> [Expr; 3] {
    [0, 1, 2].map(|i| Expr {
        kind: crate::hir::ExprKind::Var(Var::Point(i)),
        sort: crate::hir::Sort::Real,
        loc: Default::default(),
    })
}

/// The region of `role`'s kind's body, as a predicate of the point (`None` for a body
/// with a URDF or mesh part).
fn initial_body(prog: &Program, role: RoleId) -> Option<Expr> {
    let body = prog.kind_of(role).body.as_ref()?;
    crate::space::region::region(prog, body, &point_vars())
}

/// The environment of a region of the world: `Var::Point` the world point.
fn at_point<'m>(prog: &'m Program, m: &'m Valuation, world: &'m [Num; 3]) -> impl Fn(&Var) -> Option<Value> + 'm {
    move |v: &Var| match v {
        Var::Point(k) => world.get(*k).cloned().map(Value::Num),
        other => shared_var(prog, other, m),
    }
}

/// The violation needs the world point in the footprint of `app` run by `r` (read at
/// `tags`): all space holds it; a footprint with no predicate is not decided here.
fn in_footprint(
    v: &mut Violation,
    prog: &Program,
    m: &Valuation,
    (r, app): &(RoleId, PrimApp),
    tags: Tags,
    world: &[Num; 3],
) {
    let shared = |x: &Var| shared_var(prog, x, m);
    let prim = prog.prim(app.prim);
    let what = || format!("the point is in the footprint of `{}`", prim.name);
    let fp = match &prim.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => fp,
        Footprint::Everywhere => return,
        Footprint::Solid { .. } => return v.need(Tri::Unknown, what),
    };
    let Some(local) = to_local(prog, *r, world) else { return v.need(Tri::Unknown, what) };
    let args = app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
    let env = frame(prog, *r, m, tags, &args, Some(local));
    v.holds(&fp.pred, &env, what)
}

/// The duration `(lo, hi)` of `app` run by `r`, read at its start (`hi = None`: no end).
fn duration(prog: &Program, m: &Valuation, (r, app): &(RoleId, PrimApp)) -> Option<(Num, Option<Num>)> {
    let shared = |x: &Var| shared_var(prog, x, m);
    let args = app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
    let env = frame(prog, *r, m, Tags::START, &args, None);
    let d = &prog.prim(app.prim).duration;
    let num = |e: &Expr| exact::eval(prog, e, &env).ok()?.num().ok().cloned();
    let hi = match &d.hi {
        Some(h) => Some(num(h)?),
        None => None,
    };
    Some((num(&d.lo)?, hi))
}

/// `a <= b` of two enclosures.
fn le(a: &Num, b: &Num) -> Tri {
    a.le(b)
}

fn eq(a: &Num, b: &Num) -> Tri {
    le(a, b).and(le(b, a))
}

/// The violation of one item of Def 3.4 (corrected direction), as [`super::goals`]'s
/// refinement query states it: the meet's precondition (some abstract one) at the start,
/// and the item's own condition false.
#[allow(clippy::too_many_arguments)]
fn refinement(
    v: &mut Violation,
    prog: &Program,
    m: &Valuation,
    role: RoleId,
    c: &PrimApp,
    ss: &[PrimApp],
    item: super::goals::RefineItem,
    world: Option<&[Num; 3]>,
) {
    use super::goals::RefineItem as I;
    let shared = |x: &Var| shared_var(prog, x, m);
    let args_of = |app: &PrimApp| app.args.iter().map(|a| exact::eval(prog, a, &shared).ok()).collect::<Vec<_>>();
    let cp = prog.prim(c.prim);
    let cargs = args_of(c);
    let sargs: Vec<Vec<Option<Value>>> = ss.iter().map(args_of).collect();
    // Some conjunct over the abstract primitives, each in its own arguments.
    let any = |f: &dyn Fn(&crate::hir::Primitive) -> &Expr, tags: Tags, point: Option<[Num; 3]>| {
        ss.iter().zip(&sargs).fold(Tri::False, |acc, (s, args)| {
            let env = frame(prog, role, m, tags, args, point.clone());
            acc.or(exact::holds(prog, f(prog.prim(s.prim)), &env))
        })
    };
    let all = |f: &dyn Fn(&crate::hir::Primitive) -> &Expr, tags: Tags, point: Option<[Num; 3]>| {
        ss.iter().zip(&sargs).fold(Tri::True, |acc, (s, args)| {
            let env = frame(prog, role, m, tags, args, point.clone());
            acc.and(exact::holds(prog, f(prog.prim(s.prim)), &env))
        })
    };
    let names = || ss.iter().map(|s| format!("`{}`", prog.prim(s.prim).name)).collect::<Vec<_>>().join(" ∧ ");
    let cenv = |tags: Tags, point: Option<[Num; 3]>| frame(prog, role, m, tags, &cargs, point);
    if item != I::Realisable {
        v.need(any(&|p| &p.pre, Tags::START, None), || format!("the precondition of {} holds at the start", names()));
    }
    match item {
        I::Realisable => {}
        I::Pre => v.fails(&cp.pre, &cenv(Tags::START, None), || format!("the precondition of `{}` fails", cp.name)),
        I::Assume => {
            v.need(any(&|p| &p.assume, Tags::AT_T, None), || format!("the assumption of {} holds", names()));
            v.fails(&cp.assume, &cenv(Tags::AT_T, None), || format!("the assumption of `{}` fails", cp.name));
        }
        I::Guarantee => {
            v.need(all(&|p| &p.guarantee, Tags::AT_T, None).not(), || format!("the guarantee of {} fails", names()))
        }
        I::Post => {
            v.need(all(&|p| &p.post, Tags::END, None).not(), || format!("the postcondition of {} fails", names()))
        }
        I::Footprint => {
            let pred = |p: &crate::hir::Primitive| match &p.footprint {
                Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => Some(fp.pred.clone()),
                Footprint::Everywhere => Some(Expr::bool(true, Default::default())),
                Footprint::Solid { .. } => None,
            };
            let bounded = ss.iter().any(|s| prog.prim(s.prim).footprint.is_declared());
            if matches!(cp.footprint, Footprint::Everywhere) && bounded {
                // All space lies within no bounded footprint: any run falsifies it.
                return;
            }
            let Some(world) = world else { return v.need(Tri::Unknown, || "the model gives the point".into()) };
            let Some(local) = to_local(prog, role, world) else {
                return v.need(Tri::Unknown, || "the point lies in the participant's frame".into());
            };
            match pred(cp) {
                Some(fc) => v.holds(&fc, &cenv(Tags::AT_T, Some(local.clone())), || {
                    format!("the point is in the footprint of `{}`", cp.name)
                }),
                None => v.need(Tri::Unknown, || format!("the point is in the footprint of `{}`", cp.name)),
            }
            let mut inside = Tri::True;
            for (s, args) in ss.iter().zip(&sargs) {
                let env = frame(prog, role, m, Tags::AT_T, args, Some(local.clone()));
                inside = inside.and(match pred(prog.prim(s.prim)) {
                    Some(fs) => exact::holds(prog, &fs, &env),
                    None => Tri::Unknown,
                });
            }
            v.need(inside.not(), || format!("the point is outside the footprint of {}", names()));
        }
        I::Duration => {
            let (cr, sr): ((RoleId, PrimApp), Vec<(RoleId, PrimApp)>) =
                ((role, c.clone()), ss.iter().map(|s| (role, s.clone())).collect());
            let Some((clo, chi)) = duration(prog, m, &cr) else {
                return v.need(Tri::Unknown, || "the durations do not nest".into());
            };
            let mut nested = Tri::True;
            for s in &sr {
                let Some((slo, shi)) = duration(prog, m, s) else {
                    return v.need(Tri::Unknown, || "the durations do not nest".into());
                };
                let (olo, ohi, ilo, ihi) = if cp.interruptible {
                    (clo.clone(), chi.clone(), slo, shi)
                } else {
                    (slo, shi, clo.clone(), chi.clone())
                };
                let hi_ok = match (ihi, ohi) {
                    (_, None) => Tri::True,
                    (Some(i), Some(o)) => le(&i, &o),
                    (None, Some(_)) => Tri::False,
                };
                nested = nested.and(le(&olo, &ilo).and(hi_ok));
            }
            v.need(nested.not(), || "the durations do not nest".into());
        }
    }
}

/// The world point of an overlap in the model (`point.x`, `point.y`, `point.z`).
fn model_point(m: &Valuation) -> Option<[Num; 3]> {
    let point = ["point.x", "point.y", "point.z"].map(|n| m.get(n).and_then(|v| v.num().ok().cloned()));
    let [Some(px), Some(py), Some(pz)] = point else { return None };
    Some([px, py, pz])
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

/// The environment of `r`'s primitive: own variables as `tags` name them (`Cart.x(t)`, or
/// the shared start state), `old` the start, the arguments, `clock` the query's time, the
/// local point.
fn frame<'m>(
    prog: &'m Program,
    r: RoleId,
    m: &'m Valuation,
    tags: Tags,
    args: &'m [Option<Value>],
    point: Option<[Num; 3]>,
) -> impl Fn(&Var) -> Option<Value> + 'm {
    move |v: &Var| {
        let role = prog.role_name(r);
        let kind = prog.kind_of(r);
        match v {
            Var::Own(slot) => {
                let n = &kind.var(*slot).0;
                let tag = match slot {
                    Slot::State(_) => tags.state,
                    Slot::Input(_) => tags.input,
                };
                match (tag, slot) {
                    (Some(t), _) => m.get(&format!("{role}.{n}({t})")).cloned(),
                    (None, Slot::State(_)) => shared_var(prog, &Var::Role(r, *slot), m),
                    (None, Slot::Input(_)) => m.get(&format!("{role}.{n}")).cloned(),
                }
            }
            Var::Old(i) => shared_var(prog, &Var::Role(r, Slot::State(*i)), m),
            Var::Param(i) => args.get(*i).cloned().flatten(),
            Var::Clock => match tags.clock {
                Some(c) => m.get(c).cloned(),
                None => Some(Value::Num(Num::int(0))).filter(|_| tags.state == Some("0")),
            },
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
mod tests;

#[cfg(test)]
mod by_part;
