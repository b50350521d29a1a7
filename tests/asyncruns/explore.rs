//! The explorer of asynchronous runs: each role runs its projection (`mochi::project`), one
//! FIFO queue per ordered pair of roles, a timeout may fire at any moment its waiting role
//! waits, and every interleaving is followed up to a bound. It knows nothing of E0326: what
//! it calls a misread is defined on the runs alone (see `Misread`).
//!
//! **Late messages, by the runs alone.** Every message carries how many messages its sender
//! had received from its receiver when it sent it (a vector-clock entry; a message it ignored
//! as late counts, since it was received and dropped). When a role takes a
//! timeout at a reception from `q`, it notes how many messages it had sent to `q`: a message
//! from `q` that carries at most that number was sent before `q` could know of the timeout
//! (FIFO: `q` hears of it only from a message sent after), so it belongs to the abandoned
//! choice or to what `q` did before learning of it. Such a message is **late**. A late
//! message that fits no reception of its receiver's state is ignored (what real peers and
//! the monitor do); one that fits a reception is taken, because the receiver cannot tell it
//! apart, and that is a misread unless the reception **absorbs** it: the receiver is, after
//! it, at the same node of its local type with the same loop parameters (it took the message
//! as one more of a stream it accepts anyway).
//!
//! Values are concrete: loop parameters and guards are evaluated exactly
//! (`mochi::exact`), and a sender picks each field from a few candidates its refinement
//! admits (the values its comparisons name, their neighbours, 0, 1, 2), so a late answer
//! whose index no longer matches the one asked for is read with the wrong index.

use mochi::exact::{self, Tri, Value};
use mochi::hir::expr::BinOp;
use mochi::hir::local::{Local, LocalArc, RecvBranch};
use mochi::hir::{Expr, ExprKind, Field, Program, RecParam, RoleId, ValueId, Var};
use std::collections::{BTreeMap, HashSet, VecDeque};
use std::fmt::Write;
use std::sync::Arc;

/// A message on the wire.
#[derive(Clone, Debug)]
pub struct Message {
    pub from: RoleId,
    pub to: RoleId,
    pub label: String,
    /// The payload, field by field: its MAVLink field (if any) and value.
    pub values: Vec<(Option<String>, Value)>,
    /// How many messages the sender had received from the receiver when it sent this one.
    heard: u32,
    /// Its position in the run (the index of its send event).
    pub id: usize,
}

/// What happened at one step of a run.
#[derive(Clone, Debug)]
pub enum Event {
    Send(Message),
    /// Received as a step; `late` when it was late (then absorbed: otherwise a misread).
    Recv {
        msg: Message,
        late: bool,
    },
    /// A late message its receiver ignored.
    Ignored(Message),
    /// `role` gave up waiting after `ms`.
    Timeout {
        role: RoleId,
        ms: i64,
    },
}

/// A run that is not one of the protocol's: the oracle's finding.
#[derive(Clone, Debug)]
pub struct Misread {
    pub what: String,
    pub trace: Vec<Event>,
}

#[derive(Clone)]
struct RoleState {
    at: LocalArc,
    env: BTreeMap<ValueId, Value>,
    loops: BTreeMap<String, (Vec<RecParam>, LocalArc)>,
    sent: Vec<u32>,
    heard: Vec<u32>,
    /// Per sender: the number of messages sent to it when this role last gave up waiting
    /// for it. A message from it that heard at most as many is late.
    late_bound: Vec<Option<u32>>,
    /// The span start of the timeout this role took last.
    last_timeout: Option<u32>,
}

#[derive(Clone)]
struct Config {
    roles: Vec<RoleState>,
    queues: BTreeMap<(u32, u32), VecDeque<Message>>,
    trace: Vec<Event>,
}

/// What one exploration found.
#[derive(Default, Debug)]
pub struct Explored {
    pub misread: Option<Misread>,
    /// Configurations visited.
    pub states: usize,
    /// Runs that ended with every role at `end` and every queue empty, and runs cut at the
    /// depth bound (at most `keep` of them, for the monitor's replay).
    pub runs: Vec<(Vec<Event>, bool)>,
    /// Guards, refinements or arguments that could not be evaluated (a value not held).
    pub undecided: usize,
    /// Whether the state bound stopped the search before it was complete.
    pub cut: bool,
}

pub struct Explorer<'p> {
    prog: &'p Program,
    pub depth: usize,
    pub max_states: usize,
    pub keep: usize,
}

/// Not explorable: motion, or no projection.
#[derive(Debug)]
pub struct Unsupported(pub String);

enum Step {
    To(Box<Config>),
    Bad(String),
}

impl<'p> Explorer<'p> {
    pub fn new(prog: &'p Program) -> Explorer<'p> {
        Explorer { prog, depth: 16, max_states: 20_000, keep: 64 }
    }

    pub fn explore(&self) -> Result<Explored, Unsupported> {
        let (projections, diags) = mochi::project::project_all(self.prog);
        if !diags.is_empty() {
            return Err(Unsupported("a projection failed".into()));
        }
        let n = self.prog.roles.len();
        let mut out = Explored::default();
        let mut roles = Vec::new();
        for r in self.prog.role_ids() {
            let Some(t) = projections.get(&r) else { return Err(Unsupported("no projection".into())) };
            let mut st = RoleState {
                at: t.clone(),
                env: BTreeMap::new(),
                loops: BTreeMap::new(),
                sent: vec![0; n],
                heard: vec![0; n],
                late_bound: vec![None; n],
                last_timeout: None,
            };
            match self.settle(&mut st, &mut out.undecided) {
                Ok(()) => {}
                Err(e) => return Err(Unsupported(e)),
            }
            roles.push(st);
        }
        let start = Config { roles, queues: BTreeMap::new(), trace: Vec::new() };
        let mut seen = HashSet::new();
        let mut stack = vec![start];
        while let Some(c) = stack.pop() {
            if !seen.insert(key(&c)) {
                continue;
            }
            out.states += 1;
            if out.states > self.max_states {
                out.cut = true;
                break;
            }
            let steps = self.steps(&c, &mut out.undecided)?;
            let mut next = Vec::new();
            for s in steps {
                match s {
                    Step::To(c) => next.push(*c),
                    Step::Bad(what) => {
                        out.misread = Some(Misread { what, trace: c.trace.clone() });
                        return Ok(out);
                    }
                }
            }
            if next.is_empty() {
                let done = c.roles.iter().all(|r| matches!(&*r.at, Local::End(_)))
                    && c.queues.values().all(VecDeque::is_empty);
                if !done {
                    let what = self.stuck(&c);
                    out.misread = Some(Misread { what, trace: c.trace.clone() });
                    return Ok(out);
                }
                if out.runs.len() < self.keep {
                    out.runs.push((c.trace.clone(), true));
                }
                continue;
            }
            if c.trace.len() >= self.depth {
                if out.runs.len() < self.keep {
                    out.runs.push((c.trace.clone(), false));
                }
                continue;
            }
            stack.extend(next);
        }
        Ok(out)
    }

    fn stuck(&self, c: &Config) -> String {
        let mut s = String::from("no step is possible, yet the protocol is not over:");
        for (k, r) in c.roles.iter().enumerate() {
            let what = match &*r.at {
                Local::End(_) => "ended",
                Local::Send { .. } => "at a send none of whose branches it can take",
                Local::Recv { .. } => "waiting for a message that never comes",
                _ => "elsewhere",
            };
            let _ = write!(s, " `{}` {what};", self.prog.role_name(RoleId(k as u32)));
        }
        for ((f, t), q) in &c.queues {
            for m in q {
                let (f, t) = (self.prog.role_name(RoleId(*f)), self.prog.role_name(RoleId(*t)));
                let _ = write!(s, " `{}` from `{f}` to `{t}` never received;", m.label);
            }
        }
        s
    }

    /// Unfolds loops and jumps until `st` is at a send, a reception or the end.
    fn settle(&self, st: &mut RoleState, undecided: &mut usize) -> Result<(), String> {
        for _ in 0..64 {
            let at = st.at.clone();
            match &*at {
                Local::Rec { var, params, body, .. } => {
                    let mut vals = Vec::new();
                    for p in params {
                        vals.push(self.value(&st.env, &p.init).ok_or_else(|| {
                            *undecided += 1;
                            format!("the initial value of `{}`", p.name)
                        })?);
                    }
                    for (p, v) in params.iter().zip(vals) {
                        st.env.insert(p.value, v);
                    }
                    st.loops.insert(var.clone(), (params.clone(), body.clone()));
                    st.at = body.clone();
                }
                Local::Var { var, args, .. } => {
                    let Some((params, body)) = st.loops.get(var).cloned() else {
                        return Err(format!("a jump to `{var}` outside its loop"));
                    };
                    let mut vals = Vec::new();
                    for a in args {
                        vals.push(self.value(&st.env, a).ok_or_else(|| {
                            *undecided += 1;
                            format!("an argument of `{var}`")
                        })?);
                    }
                    for (p, v) in params.iter().zip(vals) {
                        st.env.insert(p.value, v);
                    }
                    st.at = body;
                }
                Local::Motion { .. } => return Err("a motion".into()),
                _ => return Ok(()),
            }
        }
        Err("a loop that never reaches a step".into())
    }

    fn value(&self, env: &BTreeMap<ValueId, Value>, e: &Expr) -> Option<Value> {
        let get = |v: &Var| match v {
            Var::Value(id, _) => env.get(id).cloned(),
            _ => None,
        };
        exact::eval(self.prog, e, &get).ok().filter(Value::is_exact)
    }

    fn holds(&self, env: &BTreeMap<ValueId, Value>, e: &Expr) -> Tri {
        let get = |v: &Var| match v {
            Var::Value(id, _) => env.get(id).cloned(),
            _ => None,
        };
        exact::holds(self.prog, e, &get)
    }

    /// Every step from `c`, or a misread found at it.
    fn steps(&self, c: &Config, undecided: &mut usize) -> Result<Vec<Step>, Unsupported> {
        let mut out = Vec::new();
        for i in 0..c.roles.len() {
            let me = RoleId(i as u32);
            let st = &c.roles[i];
            match &*st.at {
                Local::Send { branches, timeout, .. } => {
                    for b in branches {
                        if let Some(g) = &b.guard {
                            match self.holds(&st.env, g) {
                                Tri::True => {}
                                Tri::False => continue,
                                Tri::Unknown => {
                                    *undecided += 1;
                                    continue;
                                }
                            }
                        }
                        for vals in self.payloads(&st.env, &b.payload, undecided) {
                            let mut n = c.clone();
                            let r = &mut n.roles[i];
                            for (f, v) in b.payload.iter().zip(&vals) {
                                r.env.insert(f.value, v.clone());
                            }
                            let msg = Message {
                                from: me,
                                to: b.to,
                                label: b.label.clone(),
                                values: b
                                    .payload
                                    .iter()
                                    .map(|f| f.mav.as_ref().map(|m| m.field.clone()))
                                    .zip(vals)
                                    .collect(),
                                heard: r.heard[b.to.idx()],
                                id: c.trace.len(),
                            };
                            r.sent[b.to.idx()] += 1;
                            r.at = b.cont.clone();
                            if let Err(e) = self.settle(r, undecided) {
                                out.push(Step::Bad(format!("`{}` after sending `{}`: {e}", self.name(me), b.label)));
                                continue;
                            }
                            n.queues.entry((me.0, b.to.0)).or_default().push_back(msg.clone());
                            n.trace.push(Event::Send(msg));
                            out.push(Step::To(Box::new(n)));
                        }
                    }
                    if let Some(t) = timeout {
                        // This role learns of its peer's timeout from the timeout branch's
                        // first message, or, when its part there is `end`, its session is
                        // over once the peer took that timeout or the peer's session is
                        // over (it ended by an earlier timeout whose message crossed): the
                        // role learns nothing from the timeout either way, and in time, once
                        // the bound passed with nothing from the peer, its wait is over (the
                        // monitor ends such a session by time).
                        let mut learnt = st.clone();
                        learnt.at = t.cont.clone();
                        if self.settle(&mut learnt, undecided).is_ok() {
                            let by = t.after.by;
                            let at = learnt.at.clone();
                            match &*at {
                                Local::End(_)
                                    if c.roles[by.idx()].last_timeout == Some(t.after.loc.0.start)
                                        || matches!(&*c.roles[by.idx()].at, Local::End(_)) =>
                                {
                                    let mut n = c.clone();
                                    n.roles[i] = learnt;
                                    out.push(Step::To(Box::new(n)));
                                }
                                Local::Recv { branches, .. } => {
                                    if let Some(m) = c.queues.get(&(by.0, me.0)).and_then(VecDeque::front) {
                                        if branches.iter().any(|b| b.from == by && b.label == m.label) {
                                            let mut n = c.clone();
                                            n.roles[i] = learnt;
                                            out.push(self.receive(n, me, by, branches, undecided));
                                        }
                                    }
                                }
                                _ => {}
                            }
                        }
                    }
                }
                Local::Recv { branches, default, timeout, .. } => {
                    if default.is_some() {
                        return Err(Unsupported("a reception with a motion default".into()));
                    }
                    let mut from: Vec<RoleId> = branches.iter().map(|b| b.from).collect();
                    from.dedup();
                    for q in from {
                        if c.queues.get(&(q.0, me.0)).is_some_and(|x| !x.is_empty()) {
                            out.push(self.receive(c.clone(), me, q, branches, undecided));
                        }
                    }
                    if let Some(t) = timeout {
                        let mut n = c.clone();
                        let r = &mut n.roles[i];
                        for b in branches {
                            r.late_bound[b.from.idx()] = Some(r.sent[b.from.idx()]);
                        }
                        r.last_timeout = Some(t.after.loc.0.start);
                        r.at = t.cont.clone();
                        if let Err(e) = self.settle(r, undecided) {
                            out.push(Step::Bad(format!("`{}` after its timeout: {e}", self.name(me))));
                            continue;
                        }
                        n.trace.push(Event::Timeout { role: me, ms: t.after.ms });
                        out.push(Step::To(Box::new(n)));
                    }
                }
                _ => {}
            }
            // Late messages this role ignores, and messages that reach it after its end.
            for ((f, t), q) in &c.queues {
                if *t != me.0 {
                    continue;
                }
                let Some(m) = q.front() else { continue };
                let fits = match &*st.at {
                    Local::Recv { branches, .. } => branches.iter().any(|b| b.from.0 == *f && b.label == m.label),
                    _ => false,
                };
                if fits {
                    continue;
                }
                if is_late(st, m) {
                    let mut n = c.clone();
                    let m = n.queues.get_mut(&(*f, *t)).and_then(VecDeque::pop_front).expect("the head");
                    // Ignored, but received: what its sender sends later comes after it.
                    n.roles[i].heard[m.from.idx()] += 1;
                    n.trace.push(Event::Ignored(m));
                    out.push(Step::To(Box::new(n)));
                } else if matches!(&*st.at, Local::End(_)) {
                    out.push(Step::Bad(format!(
                        "`{}` from `{}` reaches `{}` after its session is over, and it is not late",
                        m.label,
                        self.name(m.from),
                        self.name(me)
                    )));
                }
            }
        }
        Ok(out)
    }

    /// `me` takes the head of its queue from `q` at a reception with `branches`.
    fn receive(&self, mut c: Config, me: RoleId, q: RoleId, branches: &[RecvBranch], undecided: &mut usize) -> Step {
        let Some(m) = c.queues.get_mut(&(q.0, me.0)).and_then(VecDeque::pop_front) else {
            return Step::Bad("an empty queue".into());
        };
        let before = c.roles[me.idx()].clone();
        let late = is_late(&before, &m);
        let Some(b) = branches.iter().find(|b| b.from == q && b.label == m.label) else {
            if late {
                c.roles[me.idx()].heard[q.idx()] += 1;
                c.trace.push(Event::Ignored(m));
                return Step::To(Box::new(c));
            }
            return Step::Bad(format!(
                "`{}` receives `{}` from `{}` where it expects {}",
                self.name(me),
                m.label,
                self.name(q),
                branches.iter().map(|b| format!("`{}`", b.label)).collect::<Vec<_>>().join(" or ")
            ));
        };
        let r = &mut c.roles[me.idx()];
        r.heard[q.idx()] += 1;
        for (f, (_, v)) in b.payload.iter().zip(&m.values) {
            r.env.insert(f.value, v.clone());
        }
        for f in &b.payload {
            if let Some(e) = &f.refinement {
                match self.holds(&r.env, e) {
                    Tri::False => {
                        return Step::Bad(format!(
                            "`{}` receives `{}` from `{}` with `{}` = {} which its refinement there does not admit{}",
                            self.name(me),
                            m.label,
                            self.name(q),
                            f.name,
                            r.env.get(&f.value).map(|v| v.to_string()).unwrap_or_default(),
                            if late { " (a late message)" } else { "" }
                        ))
                    }
                    Tri::Unknown => *undecided += 1,
                    Tri::True => {}
                }
            }
        }
        r.at = b.cont.clone();
        if let Err(e) = self.settle(r, undecided) {
            return Step::Bad(format!("`{}` after receiving `{}`: {e}", self.name(me), m.label));
        }
        if late && !absorbs(&before, r) {
            return Step::Bad(format!(
                "`{}` takes a late `{}` from `{}` as a step of its protocol (sent before `{}` could know of \
                 `{}`'s timeout)",
                self.name(me),
                m.label,
                self.name(q),
                self.name(q),
                self.name(me)
            ));
        }
        c.trace.push(Event::Recv { msg: m, late });
        Step::To(Box::new(c))
    }

    /// Candidate payloads for `fields` that the sender's refinements admit.
    fn payloads(&self, env: &BTreeMap<ValueId, Value>, fields: &[Field], undecided: &mut usize) -> Vec<Vec<Value>> {
        let mut partial: Vec<(BTreeMap<ValueId, Value>, Vec<Value>)> = vec![(env.clone(), Vec::new())];
        for f in fields {
            let mut next = Vec::new();
            for (env, vals) in &partial {
                let mut cands: Vec<Value> = Vec::new();
                if let Some(e) = &f.refinement {
                    self.named_values(env, e, f.value, &mut cands);
                }
                for k in 0..3 {
                    cands.push(int(k));
                }
                let mut kept = 0;
                let mut tried = Vec::new();
                for v in cands {
                    if kept == 2 || tried.contains(&v) {
                        continue;
                    }
                    tried.push(v.clone());
                    let mut e2 = env.clone();
                    e2.insert(f.value, v.clone());
                    let ok = match &f.refinement {
                        None => Tri::True,
                        Some(e) => self.holds(&e2, e),
                    };
                    match ok {
                        Tri::True => {
                            kept += 1;
                            let mut vs = vals.clone();
                            vs.push(v);
                            next.push((e2, vs));
                        }
                        Tri::Unknown => *undecided += 1,
                        Tri::False => {}
                    }
                }
            }
            partial = next;
        }
        partial.into_iter().map(|(_, v)| v).collect()
    }

    /// The values `e`'s comparisons of `x` name, and their neighbours.
    fn named_values(&self, env: &BTreeMap<ValueId, Value>, e: &Expr, x: ValueId, out: &mut Vec<Value>) {
        match &e.kind {
            ExprKind::Binary(op, a, b) => {
                let is_x = |e: &Expr| matches!(&e.kind, ExprKind::Var(Var::Value(id, _)) if *id == x);
                let cmp = matches!(op, BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge);
                if cmp && (is_x(a) || is_x(b)) {
                    let other = if is_x(a) { b } else { a };
                    if let Some(Value::Num(n)) = self.value(env, other) {
                        if let Some(r) = n.value() {
                            let one = exact::Rat::from_integer(1.into());
                            out.push(Value::rat(r.clone()));
                            out.push(Value::rat(r.clone() + one.clone()));
                            out.push(Value::rat(r.clone() - one));
                        }
                    }
                }
                self.named_values(env, a, x, out);
                self.named_values(env, b, x, out);
            }
            ExprKind::Unary(_, a) => self.named_values(env, a, x, out),
            _ => {}
        }
    }

    fn name(&self, r: RoleId) -> &str {
        self.prog.role_name(r)
    }

    /// The run as text, one event a line.
    pub fn render(&self, trace: &[Event]) -> String {
        let mut s = String::new();
        for e in trace {
            let line = match e {
                Event::Send(m) => format!("{} sends {}{}", self.name(m.from), m.label, vals(m)),
                Event::Recv { msg, late } => format!(
                    "{} receives {}{}{}",
                    self.name(msg.to),
                    msg.label,
                    vals(msg),
                    if *late { " (late, absorbed)" } else { "" }
                ),
                Event::Ignored(m) => format!("{} ignores the late {}{}", self.name(m.to), m.label, vals(m)),
                Event::Timeout { role, ms } => format!("{} gives up after {ms} ms", self.name(*role)),
            };
            let _ = writeln!(s, "  {line}");
        }
        s
    }
}

fn vals(m: &Message) -> String {
    if m.values.is_empty() {
        return String::new();
    }
    let v: Vec<String> = m.values.iter().map(|(f, v)| format!("{}={v}", f.as_deref().unwrap_or("_"))).collect();
    format!("({})", v.join(", "))
}

fn int(k: i64) -> Value {
    Value::rat(exact::Rat::from_integer(k.into()))
}

fn is_late(st: &RoleState, m: &Message) -> bool {
    st.late_bound[m.from.idx()].is_some_and(|n| m.heard <= n)
}

/// Whether a reception left the role where it was: the same node, the same loop parameters.
fn absorbs(before: &RoleState, after: &RoleState) -> bool {
    Arc::ptr_eq(&before.at, &after.at)
        && before.loops.values().flat_map(|(ps, _)| ps).all(|p| before.env.get(&p.value) == after.env.get(&p.value))
}

fn key(c: &Config) -> String {
    let mut s = String::new();
    for r in &c.roles {
        let _ = write!(
            s,
            "{:p}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?};",
            Arc::as_ptr(&r.at),
            r.env,
            r.loops.keys().collect::<Vec<_>>(),
            r.sent,
            r.heard,
            r.late_bound,
            r.last_timeout
        );
    }
    for ((f, t), q) in &c.queues {
        for m in q {
            let _ = write!(s, "{f}>{t}:{}{:?}@{},", m.label, m.values, m.heard);
            let _ = m.id;
        }
    }
    s
}
