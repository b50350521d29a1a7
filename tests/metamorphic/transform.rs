//! The rewritings of the metamorphic relations, on a program's text: each takes the files of
//! a program (the root and its imports, as parsed by mochi's own parser, with its spans)
//! and returns new texts for them. A rewriting that does not apply to a program (a parse
//! error, nothing to rewrite) returns `None`.

use super::common::Program;
use mochi::source::{FileId, SourceDb, Span};
use mochi::syntax::ast::*;
use mochi::syntax::lexer::{lex, Tok};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// A program's files as mochi parses them.
pub struct Parsed {
    pub db: SourceDb,
    pub files: Vec<(FileId, File)>,
}

/// Parses `root` and its imports; `None` when it does not parse cleanly (the rewritings
/// need every name's span, which a file with a syntax error does not give).
pub fn parse(root: &Path) -> Option<Parsed> {
    let mut db = SourceDb::new();
    let text = std::fs::read_to_string(root).ok()?;
    let id = db.add(root.display().to_string(), text);
    let mut read = |p: &Path| mochi::fsload::read_source(p);
    let (parsed, diags) = mochi::syntax::parse_with_imports(&mut db, id, &mut read);
    if diags.iter().any(|d| d.is_error()) {
        return None;
    }
    Some(Parsed { db, files: parsed.files })
}

/// Applies `edits` (span → replacement; spans of one file never overlap) to the files.
fn apply(p: &Parsed, root: &Path, edits: &[(Span, String)]) -> Program {
    let mut by_file: BTreeMap<u32, Vec<(usize, usize, &str)>> = BTreeMap::new();
    for (s, r) in edits {
        by_file.entry(s.file.0).or_default().push((s.start as usize, s.end as usize, r));
    }
    let mut texts = HashMap::new();
    for (fid, mut es) in by_file {
        let f = p.db.file(FileId(fid));
        es.sort_by_key(|e| (e.0, e.1));
        es.dedup_by_key(|e| (e.0, e.1));
        let mut out = String::with_capacity(f.text.len() + 64);
        let mut at = 0;
        for (s, e, r) in es {
            assert!(s >= at, "overlapping edits in {} at {s}", f.name);
            out.push_str(&f.text[at..s]);
            out.push_str(r);
            at = e;
        }
        out.push_str(&f.text[at..]);
        texts.insert(f.name.clone(), out);
    }
    Program { root: root.to_path_buf(), texts }
}

// ---------------------------------------------------------------- renaming

/// Where a name occurs and what to do there.
enum Site {
    /// Replace the name.
    Name(Span, String),
    /// A MAVLink field bound under its own name: append ` as NEW` (the field stays).
    BindAs(Span, String),
}

/// Every user binder and every use of one, in all files: the names declared (by kind of
/// declaration) and the sites.
#[derive(Default)]
struct Names {
    declared: BTreeSet<String>,
    participants: BTreeSet<String>,
    /// State variables of kinds with a URDF body: their names are the URDF's joints.
    pinned: BTreeSet<String>,
    sites: Vec<Site>,
    mavlink: bool,
}

impl Names {
    fn decl(&mut self, i: &Ident) {
        self.declared.insert(i.name.clone());
        self.sites.push(Site::Name(i.span, i.name.clone()));
    }
    fn use_(&mut self, i: &Ident) {
        self.sites.push(Site::Name(i.span, i.name.clone()));
    }

    fn expr(&mut self, e: &Expr) {
        match &e.kind {
            ExprKind::Var(n) => self.sites.push(Site::Name(e.span, n.clone())),
            ExprKind::Dot(base, field) => {
                if let ExprKind::Var(b) = &base.kind {
                    if self.participants.contains(b) {
                        self.use_(field);
                    }
                }
                self.expr(base);
            }
            ExprKind::Call(_, args) | ExprKind::Tuple(args) => args.iter().for_each(|a| self.expr(a)),
            ExprKind::Unary(_, a) => self.expr(a),
            ExprKind::Binary(_, a, b) => {
                self.expr(a);
                self.expr(b);
            }
            ExprKind::If(a, b, c) => {
                self.expr(a);
                self.expr(b);
                self.expr(c);
            }
            _ => {}
        }
    }
    fn body(&mut self, b: &BodyAst) {
        for part in &b.parts {
            part.shape.args.iter().for_each(|a| self.expr(a));
            if let Some(p) = &part.place {
                self.pose(p);
            }
        }
    }
    fn pose(&mut self, p: &Pose) {
        p.args.iter().for_each(|a| self.expr(a));
    }
    fn field(&mut self, f: &Field) {
        if self.mavlink {
            match &f.binder {
                Some(b) => self.decl(b),
                None => {
                    self.declared.insert(f.name.name.clone());
                    self.sites.push(Site::BindAs(f.name.span, f.name.name.clone()));
                }
            }
        } else {
            self.decl(&f.name);
        }
        if let Some(r) = &f.refinement {
            self.expr(r);
        }
    }
    fn label(&mut self, l: &Ident) {
        if !self.mavlink {
            self.decl(l);
        }
    }
    fn params(&mut self, ps: &[RecParam]) {
        for p in ps {
            self.decl(&p.name);
            if let Some(r) = &p.refinement {
                self.expr(r);
            }
            self.expr(&p.init);
        }
    }
    fn call(&mut self, c: &PrimCall) {
        self.use_(&c.name);
        c.args.iter().for_each(|a| self.expr(a));
    }
    fn global(&mut self, g: &Global) {
        match g {
            Global::Msg(m) => {
                self.use_(&m.from);
                self.use_(&m.to);
                if let Some(e) = &m.guard {
                    self.expr(e);
                }
                self.label(&m.label);
                m.payload.iter().for_each(|f| self.field(f));
            }
            Global::Motion { parts, .. } => {
                for (r, c) in parts {
                    self.use_(r);
                    self.call(c);
                }
            }
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => gs.iter().for_each(|g| self.global(g)),
            Global::Rec { var, params, decreases, body, .. } => {
                self.decl(var);
                self.params(params);
                if let Some(d) = decreases {
                    self.expr(d);
                }
                self.global(body);
            }
            Global::Var { var, args, .. } => {
                self.use_(var);
                args.iter().for_each(|a| self.expr(a));
            }
            Global::End(_) => {}
            Global::After { bound, by, .. } => {
                self.expr(bound);
                self.use_(by);
            }
        }
    }
    fn local(&mut self, l: &Local) {
        match l {
            Local::Motion { prims, cont, .. } => {
                prims.iter().for_each(|c| self.call(c));
                self.local(cont);
            }
            Local::Send { branches, .. } => {
                for b in branches {
                    if let Some(g) = &b.guard {
                        self.expr(g);
                    }
                    self.use_(&b.to);
                    self.label(&b.label);
                    b.payload.iter().for_each(|f| self.field(f));
                    self.local(&b.cont);
                }
            }
            Local::Recv { branches, default, .. } => {
                for b in branches {
                    self.use_(&b.from);
                    self.label(&b.label);
                    b.payload.iter().for_each(|f| self.field(f));
                    self.local(&b.cont);
                }
                if let Some((cs, k)) = default {
                    cs.iter().for_each(|c| self.call(c));
                    self.local(k);
                }
            }
            Local::Rec { var, params, body, .. } => {
                self.decl(var);
                self.params(params);
                self.local(body);
            }
            Local::Var { var, args, .. } => {
                self.use_(var);
                args.iter().for_each(|a| self.expr(a));
            }
            Local::End(_) => {}
        }
    }
    fn process(&mut self, p: &Process) {
        match p {
            Process::Send { to, label, args, cont, .. } => {
                self.use_(to);
                self.label(label);
                args.iter().for_each(|a| self.expr(a));
                self.process(cont);
            }
            Process::Recv { from, label, binders, cont, .. } => {
                self.use_(from);
                self.label(label);
                binders.iter().for_each(|b| self.decl(b));
                self.process(cont);
            }
            Process::Motion { prim, cont, .. } => {
                self.call(prim);
                self.process(cont);
            }
            Process::Sum(ps, _) => ps.iter().for_each(|p| self.process(p)),
            Process::If { cond, then, els, .. } => {
                self.expr(cond);
                self.process(then);
                self.process(els);
            }
            Process::Rec { var, params, body, .. } => {
                self.decl(var);
                self.params(params);
                self.process(body);
            }
            Process::Var { var, args, .. } => {
                self.use_(var);
                args.iter().for_each(|a| self.expr(a));
            }
            Process::End(_) => {}
        }
    }
    fn item(&mut self, it: &Item) {
        match it {
            Item::Import(_) | Item::Dialect(_) => {}
            Item::Const(c) => {
                self.decl(&c.name);
                self.expr(&c.value);
            }
            Item::Robot(r) => {
                self.decl(&r.name);
                let urdf = r.geometry.iter().flat_map(|b| &b.parts).any(|p| p.shape.name.name == "urdf");
                for v in r.state.iter().chain(&r.inputs) {
                    if urdf {
                        self.pinned.insert(v.name.name.clone());
                    }
                    self.decl(&v.name);
                }
                r.geometry.iter().for_each(|b| self.body(b));
                for m in &r.mounts {
                    self.decl(&m.name);
                    self.pose(&m.pose);
                }
                if let Some(e) = &r.invariant {
                    self.expr(e);
                }
            }
            Item::Motion(m) => {
                self.use_(&m.kind);
                self.decl(&m.name);
                m.params.iter().for_each(|p| self.decl(&p.name));
                for f in &m.fields {
                    match &f.value {
                        FieldValue::Pred(e) => self.expr(e),
                        FieldValue::Footprint { point, pred } => {
                            point.iter().for_each(|i| self.decl(i));
                            self.expr(pred);
                        }
                        FieldValue::Duration { lo, hi } => {
                            self.expr(lo);
                            if let Some(h) = hi {
                                self.expr(h);
                            }
                        }
                        FieldValue::Body(b) => self.body(b),
                        FieldValue::Flag(_) | FieldValue::OwnGeometry(_) => {}
                    }
                }
            }
            Item::System(s) => {
                self.decl(&s.name);
                for p in &s.participants {
                    self.decl(&p.name);
                    if let Some(k) = &p.kind {
                        self.use_(k);
                    }
                    if let Some(e) = &p.init {
                        self.expr(e);
                    }
                    if let Some(a) = &p.at {
                        self.pose(a);
                    }
                    for on in &p.on {
                        self.use_(&on.carrier);
                        self.use_(&on.mount);
                    }
                }
                for o in &s.obstacles {
                    self.decl(&o.name);
                    o.geometry.iter().for_each(|b| self.body(b));
                    o.at.iter().for_each(|a| self.pose(a));
                }
                // A stream names its participants, and its fields bind observed names as a
                // payload's do.
                for st in &s.streams {
                    self.use_(&st.from);
                    st.to.iter().for_each(|t| self.use_(t));
                    st.payload.iter().for_each(|f| self.field(f));
                }
            }
            Item::Choreography(c) => {
                self.decl(&c.name);
                self.global(&c.body);
                for part in &c.partitions {
                    part.point.iter().for_each(|i| self.decl(i));
                    part.regions.iter().for_each(|e| self.expr(e));
                }
            }
            Item::Process(p) => {
                self.use_(&p.role);
                self.process(&p.body);
            }
            Item::Local(l) => {
                self.use_(&l.role);
                self.local(&l.body);
            }
        }
    }
}

/// Names a new name may be: mochi's own words with a meaning in their place, functions,
/// MAVLink fields and enum entries, reserved words (an error is then the right answer).
pub const TRICKY: &[&str] = &[
    "x",
    "y",
    "z",
    "clock",
    "old",
    "inf",
    "pose",
    "point",
    "vector",
    "norm2",
    "sqrt",
    "min",
    "max",
    "abs",
    "sin",
    "cos",
    "box",
    "sphere",
    "geometry",
    "footprint",
    "init",
    "at",
    "on",
    "as",
    "state",
    "input",
    "mount",
    "dialect",
    "partition",
    "decreases",
    "seq",
    "count",
    "mission_type",
    "target_system",
    "param_id",
    "command",
    "MAV_CMD_NAV_LAST",
    "MAV_RESULT_ACCEPTED",
    "MAV_MISSION_ACCEPTED",
    "MAV_MISSION_TYPE_MISSION",
    "MISSION_ITEM_INT",
    "HEARTBEAT",
    "common",
    "pi",
    "true",
    "mu",
    "end",
    "int",
    "real",
    "str",
    "bool",
    "unit",
];

/// Renames every user binder consistently: `choose(i)` gives the `i`-th name's new name
/// (called once per name, in sorted order; names it returns twice, or that collide with an
/// identifier that is not renamed, are made unique with a suffix). Returns the program and
/// the renaming, or `None` when the program does not parse or has no user binder.
pub fn rename(root: &Path, choose: &mut dyn FnMut(usize, &str) -> String) -> Option<(Program, Vec<(String, String)>)> {
    let p = parse(root)?;
    let mut names = Names {
        mavlink: p.files.iter().any(|(_, f)| f.items.iter().any(|i| matches!(i, Item::Dialect(_)))),
        ..Names::default()
    };
    for (_, f) in &p.files {
        for it in &f.items {
            if let Item::System(s) = it {
                names.participants.extend(s.participants.iter().map(|p| p.name.name.clone()));
            }
        }
    }
    for (_, f) in &p.files {
        f.items.iter().for_each(|it| names.item(it));
    }
    let renamed: Vec<String> = names.declared.iter().filter(|n| !names.pinned.contains(*n)).cloned().collect();
    if renamed.is_empty() {
        return None;
    }
    // Every identifier of the program that is not renamed: a new name must not meet one.
    let mut kept: BTreeSet<String> = BTreeSet::new();
    for (fid, _) in &p.files {
        for t in lex(*fid, &p.db.file(*fid).text).0 {
            if let Tok::Ident(s) = t.tok {
                if !renamed.contains(&s) {
                    kept.insert(s);
                }
            }
        }
    }
    let mut map: BTreeMap<String, String> = BTreeMap::new();
    let mut taken: BTreeSet<String> = kept.clone();
    for (i, old) in renamed.iter().enumerate() {
        let mut new = choose(i, old);
        let mut k = 0;
        while taken.contains(&new) {
            k += 1;
            new = format!("{}_{k}", choose(i, old));
        }
        taken.insert(new.clone());
        map.insert(old.clone(), new);
    }
    let mut edits = Vec::new();
    for s in &names.sites {
        match s {
            Site::Name(span, n) => {
                if let Some(new) = map.get(n) {
                    edits.push((*span, new.clone()));
                }
            }
            Site::BindAs(span, n) => {
                if let Some(new) = map.get(n) {
                    edits.push((*span, format!("{n} as {new}")));
                }
            }
        }
    }
    Some((apply(&p, root, &edits), map.into_iter().collect()))
}

// ---------------------------------------------------------------- constants

/// `text` of a decimal literal as an exact fraction `(p / q)`, or `None` when it is too
/// large to write so.
fn fraction(text: &str) -> Option<String> {
    let (mant, exp) = match text.find(['e', 'E']) {
        Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
        None => (text, 0),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let digits = format!("{int}{frac}");
    let digits = digits.trim_start_matches('0');
    let digits = if digits.is_empty() { "0" } else { digits };
    let scale = frac.len() as i32 - exp;
    // A numerator or a denominator beyond 64 bits would not be an integer literal (E0104:
    // `1e-20` cannot be written `1 / 100000000000000000000`): such literals stay.
    if !(-30..=18).contains(&scale) || digits.len() + (-scale).max(0) as usize > 18 {
        return None;
    }
    if scale <= 0 {
        return Some(format!("({digits}{} / 1)", "0".repeat((-scale) as usize)));
    }
    Some(format!("({digits} / 1{})", "0".repeat(scale as usize)))
}

/// Rewrites the numeric literals chosen by `pick` (called with each literal's index) as
/// equal expressions: an integer `n` as `(a + b)` with `a + b = n`, a real as the exact
/// fraction it denotes (`0.5` as `(5 / 10)`). Exponents of `^` stay literals. `None` when the
/// program does not parse or has no literal picked.
pub fn rewrite_constants(root: &Path, pick: &mut dyn FnMut(usize) -> bool) -> Option<Program> {
    let p = parse(root)?;
    // A duration's lower bound stays: E0319 asks an interruptible motion that anything may
    // interrupt for `[0, inf]` with a literal 0 (LANGUAGE.md), so `(1 - 1)` there is an error
    // by the language's rule.
    let mut lows: Vec<Span> = Vec::new();
    for (_, f) in &p.files {
        for it in &f.items {
            if let Item::Motion(m) = it {
                for fl in &m.fields {
                    if let FieldValue::Duration { lo, .. } = &fl.value {
                        lows.push(lo.span);
                    }
                }
            }
        }
    }
    let in_low = |s: Span| lows.iter().any(|l| l.file == s.file && l.start <= s.start && s.end <= l.end);
    let mut edits = Vec::new();
    let mut k = 0;
    for (fid, _) in &p.files {
        let toks = lex(*fid, &p.db.file(*fid).text).0;
        for (i, t) in toks.iter().enumerate() {
            if (i > 0 && toks[i - 1].tok == Tok::Punct("^")) || in_low(t.span) {
                continue;
            }
            let new = match &t.tok {
                Tok::Int(n) => {
                    let a = n / 2;
                    if *n == 0 {
                        Some("(1 - 1)".to_string())
                    } else {
                        Some(format!("({a} + {})", n - a))
                    }
                }
                Tok::Real(s) => fraction(s),
                _ => None,
            };
            if let Some(new) = new {
                if pick(k) {
                    edits.push((t.span, new));
                }
                k += 1;
            }
        }
    }
    if edits.is_empty() {
        return None;
    }
    Some(apply(&p, root, &edits))
}

// ---------------------------------------------------------------- reordering

fn item_span(it: &Item) -> Span {
    match it {
        Item::Import(i) => i.span,
        Item::Dialect(d) => d.span,
        Item::Const(c) => c.span,
        Item::Robot(r) => r.span,
        Item::Motion(m) => m.span,
        Item::System(s) => s.span,
        Item::Choreography(c) => c.span,
        Item::Process(p) => p.span,
        Item::Local(l) => l.span,
    }
}

/// Reorders the items of every file by `order` (a permutation of `0..n` for a file of `n`
/// items). An item is its text from its start to the next item's (its `;` and the comments
/// after it). `None` when the program does not parse or no file has two items.
pub fn reorder(root: &Path, order: &mut dyn FnMut(usize) -> Vec<usize>) -> Option<Program> {
    let p = parse(root)?;
    let mut texts = HashMap::new();
    for (fid, f) in &p.files {
        let n = f.items.len();
        if n < 2 {
            continue;
        }
        let text = &p.db.file(*fid).text;
        let starts: Vec<usize> = f.items.iter().map(|it| item_span(it).start as usize).collect();
        if starts.windows(2).any(|w| w[0] >= w[1]) {
            return None;
        }
        let piece = |i: usize| {
            let end = if i + 1 < n { starts[i + 1] } else { text.len() };
            text[starts[i]..end].trim_end().to_string()
        };
        let perm = order(n);
        let mut out = text[..starts[0]].to_string();
        for &i in &perm {
            out.push_str(&piece(i));
            out.push('\n');
        }
        texts.insert(p.db.file(*fid).name.clone(), out);
    }
    if texts.is_empty() {
        return None;
    }
    Some(Program { root: root.to_path_buf(), texts })
}

// ---------------------------------------------------------------- rigid motion of the scene

/// A rigid motion of the world: a turn by `angle` about z, then a translation.
#[derive(Clone, Copy, Debug)]
pub struct Rigid {
    pub angle: f64,
    pub shift: [f64; 3],
}

fn lit(v: f64) -> String {
    // `{:?}` prints the shortest text that reads back as `v`; mochi takes it as that decimal.
    let s = format!("{v:?}");
    if v < 0.0 {
        format!("({s})")
    } else {
        s
    }
}

impl Rigid {
    /// The pose `args` (3 or 6 expressions' texts) placed in the moved world.
    fn compose(&self, args: &[String]) -> String {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        let [dx, dy, dz] = self.shift;
        let (x, y, z) = (&args[0], &args[1], &args[2]);
        let (r, p, yaw) = if args.len() == 6 {
            (args[3].clone(), args[4].clone(), format!("({}) + {}", args[5], lit(self.angle)))
        } else {
            ("0".into(), "0".into(), lit(self.angle))
        };
        format!(
            "pose({c} * ({x}) - {s} * ({y}) + {dx}, {s} * ({x}) + {c} * ({y}) + {dy}, ({z}) + {dz}, {r}, {p}, {yaw})",
            c = lit(c),
            s = lit(s),
            dx = lit(dx),
            dy = lit(dy),
            dz = lit(dz),
        )
    }

    /// The expressions that give a point of the original world from the moved world's point
    /// `(px, py, pz)` (the inverse motion), by the names of the three coordinates.
    fn inverse(&self, names: [&str; 3]) -> [String; 3] {
        let (c, s) = (lit(self.angle.cos()), lit(self.angle.sin()));
        let [dx, dy, dz] = self.shift.map(lit);
        let [x, y, z] = names;
        [
            format!("({c} * ({x} - {dx}) + {s} * ({y} - {dy}))"),
            format!("(-{s} * ({x} - {dx}) + {c} * ({y} - {dy}))"),
            format!("({z} - {dz})"),
        ]
    }
}

fn pose_texts(db: &SourceDb, p: &Pose) -> Vec<String> {
    p.args.iter().map(|a| db.snippet(a.span).to_string()).collect()
}

/// Where `at: pose(...);` goes into a declaration that has none: before its closing `}`,
/// or, for `participant P: K;`, in a block that replaces the `;`.
fn insert_at(db: &SourceDb, span: Span, pose: &str) -> Option<(Span, String)> {
    let text = db.snippet(span).trim_end();
    let end = span.start as usize + text.len();
    if text.ends_with('}') {
        Some((Span::new(span.file, end - 1, end - 1), format!(" at: {pose}; ")))
    } else if text.ends_with(';') {
        Some((Span::new(span.file, end - 1, end), format!(" {{ at: {pose}; }}")))
    } else {
        let rest = &db.file(span.file).text[end..];
        // The span may stop before the `;` or `}` that closes the declaration.
        let skip = rest.len() - rest.trim_start().len();
        match rest.trim_start().chars().next() {
            Some(';') => Some((Span::new(span.file, end + skip, end + skip + 1), format!(" {{ at: {pose}; }}"))),
            _ => None,
        }
    }
}

/// Moves the whole scene by `m`: every participant placed in the world (not the mounted
/// ones, whose `at:` is relative to their mount) and every obstacle gets `m` composed with
/// its pose, and every written partition region is read at the inverse motion of its point.
/// Footprints and bodies are in each participant's own frame and stay. `None` when the
/// program does not parse or nothing in it is placed in the world.
pub fn move_scene(root: &Path, m: Rigid) -> Option<Program> {
    let p = parse(root)?;
    let mut edits = Vec::new();
    for (_, f) in &p.files {
        for it in &f.items {
            match it {
                Item::System(s) => {
                    for q in &s.participants {
                        if q.kind.is_none() || !q.on.is_empty() {
                            continue;
                        }
                        match &q.at {
                            Some(pose) => edits.push((pose.span, m.compose(&pose_texts(&p.db, pose)))),
                            None => {
                                edits.push(insert_at(&p.db, q.span, &m.compose(&["0".into(), "0".into(), "0".into()]))?)
                            }
                        }
                    }
                    for o in &s.obstacles {
                        match o.at.first() {
                            Some(pose) => edits.push((pose.span, m.compose(&pose_texts(&p.db, pose)))),
                            None => {
                                edits.push(insert_at(&p.db, o.span, &m.compose(&["0".into(), "0".into(), "0".into()]))?)
                            }
                        }
                    }
                }
                Item::Choreography(c) => {
                    for part in &c.partitions {
                        let names = [0, 1, 2].map(|i| part.point[i].name.as_str());
                        let inv = m.inverse(names);
                        let mut vars = Names::default();
                        part.regions.iter().for_each(|e| vars.expr(e));
                        for s in vars.sites {
                            if let Site::Name(span, n) = s {
                                if let Some(i) = names.iter().position(|x| *x == n) {
                                    edits.push((span, inv[i].clone()));
                                }
                            }
                        }
                    }
                }
                _ => {}
            }
        }
    }
    if edits.is_empty() {
        return None;
    }
    Some(apply(&p, root, &edits))
}

// ---------------------------------------------------------------- a box as a mesh

/// The value of a size written as a literal, or as a constant whose value is one, and
/// whether its half is a binary float exactly (the mesh's corners are at half sizes).
fn size(e: &Expr, consts: &HashMap<String, (f64, bool)>) -> Option<(f64, bool)> {
    match &e.kind {
        ExprKind::Int(n) => Some((*n as f64, n.unsigned_abs() < 1 << 52)),
        ExprKind::Real(s) => Some((s.parse().ok()?, binary_fraction(s))),
        ExprKind::Var(n) => consts.get(n).copied(),
        _ => None,
    }
}

/// Whether the decimal `text` (no exponent) is a binary fraction of at most 52 bits.
fn binary_fraction(text: &str) -> bool {
    if text.contains(['e', 'E']) {
        return false;
    }
    let (int, frac) = text.split_once('.').unwrap_or((text, ""));
    let Ok(mut p) = format!("{int}{frac}").parse::<u128>() else { return false };
    // p / 10^k is a binary fraction iff 5^k divides p.
    for _ in 0..frac.len() {
        if p % 5 != 0 {
            return false;
        }
        p /= 5;
    }
    p < 1 << 52
}

/// Replaces every `box(lx, ly, lz)` whose sizes are literals (or constants with a literal
/// value) by `mesh("...")` of the same box: an OBJ file in `dir` with its eight corners
/// (centred in x and y, from z = 0 up, as `box` is). `None` when the program does not parse
/// or has no such box; else the program and whether every size replaced is a binary fraction
/// (then the mesh's vertices are the box's corners exactly).
pub fn boxes_as_meshes(root: &Path, dir: &Path) -> Option<(Program, bool)> {
    let p = parse(root)?;
    let mut consts = HashMap::new();
    for (_, f) in &p.files {
        for it in &f.items {
            if let Item::Const(c) = it {
                if let Some(v) = size(&c.value, &HashMap::new()) {
                    consts.insert(c.name.name.clone(), v);
                }
            }
        }
    }
    let mut bodies: Vec<&BodyAst> = Vec::new();
    for (_, f) in &p.files {
        for it in &f.items {
            match it {
                Item::Robot(r) => bodies.extend(&r.geometry),
                Item::Motion(m) => bodies.extend(m.fields.iter().filter_map(|f| match &f.value {
                    FieldValue::Body(b) => Some(b),
                    _ => None,
                })),
                Item::System(s) => bodies.extend(s.obstacles.iter().flat_map(|o| &o.geometry)),
                _ => {}
            }
        }
    }
    let mut edits = Vec::new();
    let mut exact = true;
    for part in bodies.iter().flat_map(|b| &b.parts) {
        let sh = &part.shape;
        if sh.name.name != "box" || sh.args.len() != 3 {
            continue;
        }
        let Some(l) = sh.args.iter().map(|a| size(a, &consts)).collect::<Option<Vec<(f64, bool)>>>() else { continue };
        exact &= l.iter().all(|s| s.1);
        let l: Vec<f64> = l.iter().map(|s| s.0).collect();
        let (hx, hy, lz) = (l[0] / 2.0, l[1] / 2.0, l[2]);
        let mut obj = String::new();
        for z in [0.0, lz] {
            for (x, y) in [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)] {
                obj.push_str(&format!("v {x:?} {y:?} {z:?}\n"));
            }
        }
        for f in
            ["1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "2 3 7", "2 7 6", "3 4 8", "3 8 7", "4 1 5", "4 5 8"]
        {
            obj.push_str(&format!("f {f}\n"));
        }
        let file = dir.join(format!("box-{}x{}x{}.obj", l[0], l[1], l[2]));
        std::fs::write(&file, obj).ok()?;
        edits.push((sh.span, format!("mesh(\"{}\")", file.display())));
    }
    if edits.is_empty() {
        return None;
    }
    Some((apply(&p, root, &edits), exact))
}
