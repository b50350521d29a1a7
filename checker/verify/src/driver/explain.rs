//! How a decision becomes a diagnostic: the error for a failed obligation (code, what was
//! required, the counterexample in the user's terms, the trace to its point), the help for
//! an undecided one.

use super::*;

/// The path through the global type to `ob`'s point, with the counterexample's values
/// (`wf::trace`), as lines; empty when the point is not in the global type.
pub(super) fn trace(prog: &crate::hir::Program, ob: &Obligation, f: &smt::Failure) -> Vec<String> {
    let Some(chor) = &prog.choreography else { return Vec::new() };
    match crate::wf::trace::path_to(&chor.body, ob.span) {
        Some(steps) => crate::wf::trace::lines(prog, &steps, &f.values, &f.bound),
        None => Vec::new(),
    }
}

/// The trace as a note: "trace to this point: ..." one step a line.
pub(super) fn trace_note(lines: &[String], values: bool) -> Option<String> {
    let how = if values { "one path; values from the counterexample" } else { "one path" };
    (!lines.is_empty()).then(|| format!("trace to this point ({how}):\n  {}", lines.join("\n  ")))
}

/// The error for a failed obligation: the code of the rule and part that failed, what
/// was required, and the counterexample in the user's terms.
pub(super) fn failure(
    prog: &crate::hir::Program,
    ob: &Obligation,
    f: smt::Failure,
    hint: Option<&String>,
) -> Diagnostic {
    let steps = trace(prog, ob, &f);
    let code = match (ob.rule, &f.which) {
        (Rule::TotalChoice, _) => Code::ChoiceNotTotal,
        (Rule::AgComp, Some(Part::Pre(_))) => Code::PreconditionAtMotion,
        (Rule::AgComp, Some(Part::CanEnd)) => Code::MotionCannotEnd,
        (Rule::AgComp, Some(Part::Assume(_))) => Code::AssumptionNotDischarged,
        (Rule::AgComp, Some(Part::Within(..) | Part::Meet)) => Code::DurationsIncompatible,
        (Rule::AgComp, Some(Part::ClearOf { .. })) => Code::ObstacleHit,
        (Rule::AgComp, Some(Part::CommonEnd(..))) => Code::TwoNonInterruptible,
        (Rule::AgComp, _) => Code::FootprintsOverlap,
        (Rule::FullSeparation, _) => Code::SidesOverlap,
        (Rule::Refinement, _) => Code::RefinementFails,
        (Rule::TMotion, _) => Code::MotionPrecondition,
        (Rule::TOut, _) => Code::SendPredicate,
        (Rule::TSess, _) => Code::InitialCollision,
        (Rule::Subtype, _) => Code::SubtypePredicate,
        (Rule::RecInit, _) => Code::RecInitRefinement,
        (Rule::RecJump, _) => Code::RecJumpRefinement,
        (Rule::MeasureBound, _) => Code::MeasureNegative,
        (Rule::MeasureDecrease, _) => Code::MeasureNotDecreasing,
        (Rule::Progress, _) => Code::Stuck,
        (Rule::EnumEntry, _) => Code::NotAnEntry,
        (Rule::TRecInit, _) => Code::ProcessRecInit,
        (Rule::TRecJump, _) => Code::ProcessRecJump,
        (Rule::TRecArgs, _) => Code::ProcessRecArgs,
        (Rule::Contract, _) => Code::VacuousContract,
        (Rule::Occupies, _) => Code::EmptyFootprint,
        (Rule::Reachable, _) => Code::StuckContext,
        (Rule::InitInvariant, Some(Part::Before(_))) => Code::StuckContext,
        (Rule::InitInvariant, _) => Code::InitOutsideInvariant,
        (Rule::Contains, _) => Code::FootprintMissesBody,
    };
    let help = match code {
        Code::ChoiceNotTotal => "add a branch whose guard covers the counterexample's state, or weaken a guard",
        Code::PreconditionAtMotion => "establish the precondition before the motion (an earlier motion's postcondition, a message's refinement), or weaken it",
        Code::AssumptionNotDischarged => "strengthen the partners' guarantees so that they imply the assumption, or weaken the assumption",
        Code::FootprintsOverlap => "keep the participants apart: change a pose or a motion's target, shrink a footprint, or strengthen a guarantee so the footprints stay clear of each other",
        Code::FootprintMissesBody => "widen the footprint to cover the robot's body wherever the guarantee lets it be, or write it as `footprint: geometry;`",
        Code::ObstacleHit => "keep the motion clear of the obstacle: change its target or the participant's pose, or tighten its footprint",
        Code::MotionCannotEnd => "change the motion's arguments so that it ends inside the robot's invariant, or fix its postcondition",
        Code::DurationsIncompatible => "make the non-interruptible primitive's duration fit within its partners' (or let it be interrupted)",
        Code::TwoNonInterruptible => "give the non-interruptible primitives the same single duration `[d, d]` (equal under what is known at the motion), or make all but one of them interruptible",
        Code::SidesOverlap => "keep the sides of `*` in disjoint regions, or merge the motions that meet into one joint motion",
        Code::RefinementFails => "use a primitive whose contract refines the one the choreography names (Def 3.4, corrected direction)",
        Code::MotionPrecondition => "establish the precondition before the motion in the process, or choose another primitive",
        Code::SendPredicate => "send values that satisfy the refinement, or establish the guard before sending",
        Code::InitialCollision => "move the participants apart (`at: pose(...)` or `init:`)",
        Code::RecInitRefinement | Code::ProcessRecInit => "start the parameter at a value that satisfies its refinement, or weaken the refinement",
        Code::RecJumpRefinement | Code::ProcessRecJump => "guard the branch that jumps back (e.g. `[n > 0]` before `t(n - 1)`), or pass arguments that satisfy the refinement",
        Code::MeasureNegative => "guard the branch that jumps back so that the measure is still non-negative there (e.g. `[i < count]`), or choose another measure",
        Code::MeasureNotDecreasing => "pass arguments that make the measure smaller (e.g. `t(i + 1)` for `decreases count - i`), or drop `decreases` if the loop may run forever",
        Code::NotAnEntry => "make the refinement admit an entry named above: compare with the entries' names (`{x == ENTRY}`; flags summed, or tested with `has_flag`), not with numbers that are none",
        Code::Stuck => "weaken the refinement or guard that no value satisfies in the counterexample's state, or add a branch for that state",
        Code::ProcessRecArgs => "pass the loop the same values as the local type's recursion (its initial values and the arguments of its jump), computed from what the process sent and received",
        Code::EmptyFootprint => "write a footprint that contains the robot at every state its guarantee allows (a footprint no point satisfies, such as `false`, hides every collision)",
        Code::VacuousContract => "fix the duration's bounds (lo <= hi, hi >= 0), or make the guarantee and the postcondition agree at the end of the motion (with every `sqrt` taken of a value >= 0 and every divisor non-zero: an undefined value satisfies nothing)",
        Code::StuckContext => "fix the step named above (an `init` no state satisfies, a refinement or guard that contradicts what holds there): no execution gets past it",
        Code::InitOutsideInvariant => "make `init` and the robot kind's invariant agree on at least one state (fix `init`, or widen the invariant)",
        Code::SubtypePredicate => "in the declared local type, strengthen the send's guard or refinement (weaken the reception's) until it implies the projection's, or drop the `local` item",
        _ => "make the process's predicate imply the type's",
    };
    // A fix more precise than the code's, found where the obligation was made
    // (`typeck::Hints`): e.g. the type's refinement a process loop parameter lacks.
    let help = hint.cloned().unwrap_or_else(|| help.to_string());
    let mut d = Diagnostic::error(code, ob.span, format!("{} ({})", code.title(), ob.what))
        .with_note(format!("required: {}", f.part))
        .with_note(format!("rule: {}", ob.rule.name()));
    // Two values of one name are two variables (`v`, `v#2`): say where each is bound.
    for (symbol, name, span) in &f.bound {
        d = d.with_label(*span, format!("`{symbol}` in the counterexample is the `{name}` bound here"));
    }
    if let Some(text) = trace_note(&steps, !f.values.is_empty()) {
        d = d.with_note(text);
    }
    let cx = Counterexample { values: f.values, overlap: f.overlap, trace: steps };
    let since = matches!(code, Code::FootprintsOverlap | Code::ObstacleHit).then(|| since_start(prog, ob));
    if let Some(text) = counterexample_text(&cx, code, since.as_ref()) {
        d = d.with_note(text);
    }
    d.with_help(help).with_counterexample(cx)
}

/// The help of an undecided obligation (U0001): what to change, matched to why it was
/// not decided: the hard construct the query holds (`smt::hard`), the engine that
/// stopped and how, or the limit that was reached.
pub(super) fn undecided_help(why: &smt::Why, cut_by_deadline: bool) -> String {
    const STAYS: &str = "the verdict stays `unknown`, never `verified`";
    match why {
        smt::Why::Timeout(..) if cut_by_deadline => format!(
            "give the run a later `--deadline` (or none), or check this file on its own; {STAYS}"
        ),
        smt::Why::Timeout(_, hard) => match hard.advice() {
            Some(a) => format!("{a}; or raise the per-query limit with `--timeout SECONDS`; {STAYS}"),
            None => format!(
                "raise the per-query limit with `--timeout SECONDS`, or simplify the predicates (keep them polynomial and local); {STAYS}"
            ),
        },
        smt::Why::Interval(s) if s.contains("against obstacle") => format!(
            "leave more room between the footprint and the obstacle (the search cannot separate surfaces closer than its resolution), bound the footprint's extent with a conjunct such as `x - r <= px <= x + r` so that the boxes of the interval index separate them, or raise the limit with `--timeout SECONDS`; {STAYS}"
        ),
        smt::Why::Interval(_) => format!(
            "widen the footprint where the body comes close to it (the search bounds each URDF or mesh solid by a sphere or a cylinder about its part's frame, so it needs room for those), or write it as `footprint: geometry;` (the body itself, which holds without a question); {STAYS}"
        ),
        smt::Why::Unsupported(_) => {
            format!("rewrite the predicate with the supported constructs (LANGUAGE.md, \"Expressions\"); {STAYS}")
        }
        smt::Why::Abandoned(_) | smt::Why::NotRun(_) => format!(
            "simplify the predicates (keep them polynomial and local; Z3 ignored the interrupt on this one, so a higher `--timeout` may not help); {STAYS}"
        ),
        smt::Why::Incomplete(_, hard) => match hard.advice() {
            Some(a) => format!("{a}; {STAYS}"),
            None => format!(
                "simplify the predicate (nonlinear and trigonometric facts are decided only partially); {STAYS}"
            ),
        },
        // The geometric search: what to change depends on how it stopped.
        smt::Why::Search(s) if s.contains("time limit") || s.contains("boxes searched") => format!(
            "give the geometric search more time with `--timeout SECONDS`, or narrow what it must cover (tighter bounds on the motion's variables in its precondition or guarantee); {STAYS}"
        ),
        smt::Why::Search(s) if s.contains("resolution") => format!(
            "leave more clearance between the parts (the search cannot separate surfaces closer than its resolution), or tighten the motion's bounds near the contact shown; {STAYS}"
        ),
        smt::Why::Search(_) => format!(
            "simplify the motion's geometry or bounds (primitive shapes instead of meshes, tighter bounds on its variables), or write a footprint predicate for Z3 to decide; {STAYS}"
        ),
    }
}

/// The SMT stage's dump sink failed on a query of `ob` (E0430): a warning, the verdict
/// stands; nothing more is dumped.
pub(super) fn dump_failed(ob: &Obligation, e: &str) -> Diagnostic {
    Diagnostic {
        severity: diag::Severity::Warning,
        ..Diagnostic::error(Code::SmtDumpFailed, ob.span, format!("could not dump a query of {}", ob.what))
    }
    .with_note(e.to_string())
    .with_note("no further query was dumped; the checks are not affected")
    .with_help("make the `--dump-smt` directory writable (and free space), or run without `--dump-smt`")
}

/// A branch whose guard cannot hold where the choice is made: a warning (the branch is
/// unreachable; its obligations hold vacuously).
pub(super) fn dead_branch(prog: &crate::hir::Program, ob: &Obligation, f: smt::Failure) -> Diagnostic {
    let steps = trace(prog, ob, &f);
    let mut d = Diagnostic {
        severity: diag::Severity::Warning,
        ..Diagnostic::error(Code::StuckContext, ob.span, format!("dead branch: {} can never hold", ob.what))
    }
    .with_note("the context at the choice contradicts this branch's guard, or leaves no value its payload's refinements admit, so no execution takes it; its checks hold vacuously");
    if let Some(text) = trace_note(&steps, false) {
        d = d.with_note(text);
    }
    d.with_help("remove the branch, or fix its guard or its payload's refinements")
}

/// How the time of a contact in a joint motion relates to the choreography's start,
/// read off the path to the motion (`wf::trace`): messages take no time (README, "model
/// of time"), so with no motion, choice or loop before it on the path the motion starts
/// when the choreography does; otherwise the counterexample does not fix the time.
pub(super) enum Since {
    /// The motion starts when the choreography does.
    Start,
    /// Not determined by the counterexample: why.
    Open(String),
}

pub(super) fn since_start(prog: &crate::hir::Program, ob: &Obligation) -> Since {
    use crate::wf::trace::Step;
    let Some(chor) = &prog.choreography else { return Since::Open("the motion is not in the choreography".into()) };
    let Some(steps) = crate::wf::trace::path_to(&chor.body, ob.span) else {
        return Since::Open("the path to the motion is not known".into());
    };
    let motions = steps.iter().filter(|s| matches!(s, Step::Motion(_))).count();
    let choices = steps.iter().filter(|s| matches!(s, Step::Choice)).count();
    let looped = steps.iter().any(|s| matches!(s, Step::Loop { .. }));
    if motions == 0 && choices == 0 && !looped {
        return Since::Start;
    }
    let mut why = Vec::new();
    if motions > 0 {
        why.push(format!(
            "{motions} joint motion(s) precede it on this path, whose durations the counterexample does not fix"
        ));
    }
    if choices > 0 {
        why.push(format!("{choices} choice(s) before it may run motions"));
    }
    if looped {
        why.push("it is in a loop, and the counterexample does not say which iteration".to_string());
    }
    Since::Open(why.join("; "))
}

/// The participants' states in a collision's counterexample, one participant at a time:
/// `Cart: x = 0.8, v = 0.5` from the values `Cart.x(t)`, `Cart.v(t)` (at the contact; on
/// the sides of `*`, `Cart.x(t1)` and `Cart.x(t2)`, each side at its own time) or `Cart.x`,
/// `Cart.v` (at the motion's start, `at_start`).
pub(super) fn states(values: &[crate::diag::Assignment], at_start: bool) -> Vec<String> {
    let mut by_role: Vec<(String, Vec<String>)> = Vec::new();
    for a in values {
        let name = if at_start {
            if a.name.ends_with("(t)") || a.name.contains('(') {
                continue;
            }
            a.name.as_str()
        } else {
            match ["(t)", "(t1)", "(t2)"].iter().find_map(|tag| a.name.strip_suffix(tag)) {
                Some(n) if !n.contains('(') => n,
                _ => continue,
            }
        };
        let Some((role, var)) = name.split_once('.') else { continue };
        if role == "point" {
            continue;
        }
        let entry = format!("{var} = {}", a.value);
        match by_role.iter_mut().find(|(r, _)| r == role) {
            Some((_, vs)) => vs.push(entry),
            None => by_role.push((role.to_string(), vec![entry])),
        }
    }
    by_role.into_iter().map(|(r, vs)| format!("{r}: {}", vs.join(", "))).collect()
}

/// `counterexample: at time 2.1 s, the point (1.02, 0.2, 0.05) is in both footprints;
/// Cart.x = 0, tr = 2`.
pub(super) fn counterexample_text(cx: &Counterexample, code: Code, since: Option<&Since>) -> Option<String> {
    let mut parts = Vec::new();
    // A collision: the contact's time within the motion and since the choreography's
    // start, and every participant's state there. A contact is claimed the earliest only
    // with a proof (`Overlap::not_before`: no meeting at or before it), and why a window
    // was not narrowed is said (`Overlap::earliest_open`), never a guessed time.
    // The two sides of `*` (E0406): each side's time on its own clock, and every
    // participant's state at its side's time.
    let sides = code == Code::SidesOverlap && cx.overlap.as_ref().is_some_and(|o| o.times.len() == 2);
    let collision = sides || (since.is_some() && cx.overlap.as_ref().is_some_and(|o| o.times.len() == 1));
    if let Some(o) = &cx.overlap {
        let p = o.point.map(short);
        let meet = if code == Code::ObstacleHit { "the footprint meets the obstacle" } else { "the footprints meet" };
        let at = match (o.times.as_slice(), since) {
            ([], _) => String::new(),
            ([t1, t2], _) if sides => format!(
                "the footprints meet when side 1's motion has run {} s and side 2's {} s (each side of `*` on its own clock, from the start of its motion: the sides are not synchronised, so full separation asks that their footprints never meet at any two times of their motions, and these need not be one instant of the choreography): ",
                short(*t1),
                short(*t2)
            ),
            ([t], Some(since)) => {
                let t = *t;
                let mut when = match o.not_before {
                    Some(lo) => format!(
                        "{meet} at {} s into this joint motion, and no meeting is possible at or before {} s (proved), so the first is between {} and {} s",
                        short(t), short(lo), short(lo), short(t)
                    ),
                    None if t == 0.0 => format!("{meet} at 0 s, the joint motion's start (the earliest)"),
                    None => format!("{meet} at {} s into this joint motion (the first meeting is at or before it)", short(t)),
                };
                if let Some(why) = &o.earliest_open {
                    when.push_str(&format!("; an earlier first meeting is not excluded: {why}"));
                }
                match since {
                    Since::Start => format!("{when}; the joint motion starts when the choreography does (no motion precedes it on this path, and messages take no time), so these times are also since the choreography started: "),
                    Since::Open(why) => format!("{when} (the time since the choreography started is not determined: {why}): "),
                }
            }
            ([t], None) => format!("at time {} s, ", short(*t)),
            (ts, _) => format!("at times {} s, ", ts.iter().map(|t| short(*t)).collect::<Vec<_>>().join(" and ")),
        };
        let (frame, where_) = match code {
            Code::FootprintMissesBody => ("in the robot's own frame ", "is a point of the body outside the footprint"),
            Code::ObstacleHit => ("", "is in the footprint and in the obstacle"),
            Code::RefinementFails => ("", "is in the concrete footprint and outside the abstract one"),
            _ => ("", "is in both footprints"),
        };
        parts.push(format!("{at}the point (x, y, z) = ({}, {}, {}) m {frame}{where_}", p[0], p[1], p[2]));
    }
    if collision {
        let now = states(&cx.values, false);
        let start = states(&cx.values, true);
        if now.is_empty() {
            parts.push("the participants' states at that time are not part of this counterexample".to_string());
        } else {
            let when = if sides { "at those times" } else { "at that time" };
            parts.push(format!("the participants' states {when}: {}", now.join("; ")));
        }
        if !start.is_empty() {
            let motion = if sides { "at the start of their motions" } else { "at the start of the joint motion" };
            parts.push(format!("{motion}: {}", start.join("; ")));
        }
        // The rest (payload values, inputs): what the states above do not show.
        let shown = |n: &str| {
            n.starts_with("point.") || n.starts_with("time") || n.split_once('.').is_some_and(|(r, _)| r != "point")
        };
        let rest: Vec<String> = cx
            .values
            .iter()
            .filter(|a| !shown(&a.name))
            .take(16)
            .map(|a| format!("{} = {}", a.name, a.value))
            .collect();
        if !rest.is_empty() {
            parts.push(format!("with {}", rest.join(", ")));
        }
        return Some(format!("counterexample: {}", parts.join("; ")));
    }
    // The point and the time are shown above when there is an overlap.
    let hidden = |n: &str| cx.overlap.is_some() && (n.starts_with("point.") || n.starts_with("time"));
    let values: Vec<String> =
        cx.values.iter().filter(|a| !hidden(&a.name)).take(16).map(|a| format!("{} = {}", a.name, a.value)).collect();
    if !values.is_empty() {
        parts.push(values.join(", "));
    }
    (!parts.is_empty()).then(|| format!("counterexample: {}", parts.join("; ")))
}

pub(super) fn short(v: f64) -> String {
    let r = (v * 1e4).round() / 1e4;
    if r == 0.0 && v != 0.0 {
        format!("{v:.2e}")
    } else {
        format!("{r}")
    }
}
