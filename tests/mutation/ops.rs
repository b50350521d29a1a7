//! The mutation operators: deterministic text edits of one `.chor` or `.mochi` file, found on
//! mochi's own tokens (so comments are never mutated and positions are exact). Each mutant
//! has an id `L:C:op` (line and column of the mutated token, 1-based, columns in
//! characters) that does not depend on the order of generation; the runner prefixes it with
//! the example and the file.
//!
//! Operators (see ARCHITECTURE.md "Testing" for why these):
//! - `nudge*10%`, `nudge/10%`, `nudge+1e-3`, `nudge-1e-3`: a numeric literal scaled by 1.1 and
//!   0.9, and moved by +-0.001 (zero only gets the absolute nudges). Exponents (`x^2`) are
//!   syntax, not constants, and are left alone.
//! - `cmp`: `<` <-> `<=`, `>` <-> `>=` (not the brackets of `dt<...>`).
//! - `fp-widen`: in a `footprint:` an inequality relaxed by 0.05 m on its unshared side
//!   (`a <= b` becomes `a <= 0.05 + b` or `a - 0.05 <= b`); comparisons left of `=>` are
//!   skipped (relaxing them would narrow the footprint).
//! - `dur-swap`, `dur-lo+1`, `dur-lo-1`, `dur-hi+1`, `dur-hi-1`: a duration `[lo, hi]`
//!   swapped, or one end moved by one second (never `inf`, and not a literal `0` down).
//! - `drop-msg` (choreography only), `drop-msg-all` (choreography, sender and receiver
//!   processes, `local` declarations removed), `drop-act` (one process action only).
//! - `swap` (two adjacent steps of the choreography), `swap-all` (two adjacent messages with
//!   the same sender or the same receiver, swapped in the choreography and in that one
//!   process, `local` declarations removed), `swap-act` (two adjacent process actions).
//! - `shadow(b->n)`: a binder (payload, receive variable, motion parameter, footprint point,
//!   recursion variable) renamed, with its uses in the same item, to another binder of the
//!   item, a robot state variable, or a constant the item reads.
//! - `drop-conj`: one conjunct of a top-level `&&` chain dropped from a contract part
//!   (`pre`, `assume`, `guarantee`, `post`, `footprint`, `invariant`, `init`) or a payload
//!   refinement `{...}`.
//! - Geometry: `geo-grow`, `geo-shrink` (every size of a `box`, `cylinder` or `sphere` times
//!   1.2 or 0.8), `pose-x+` ... `pose-z-` (one coordinate of a `pose(...)`, a participant's
//!   place, a body part's, a mount point's or a mounted participant's offset, moved by
//!   0.05 m), `pose-yaw+`, `pose-yaw-` (its yaw by 0.1 rad).
//! - URDF files ([`urdf_mutants`]): `urdf-scale` (a collision mesh scaled by 1.2),
//!   `urdf-grow` (a collision box, cylinder or sphere 1.2 times as large), `urdf-move+x`,
//!   `urdf-move+y`, `urdf-move-z` (a collision element moved by 0.03 m).
//! - MAVLink (examples with a `dialect`): `off-by-one+1`, `off-by-one-1` (an integer literal
//!   moved by one), `f32-up`, `f32-same` (a literal replaced by a number between two
//!   neighbouring float32 values, which the wire rounds up or back), `enum(A->B)` (an enum
//!   entry replaced by its neighbour in the same enum), `guard-neg` (a branch guard's
//!   comparison negated), `dup-msg` (a message sent twice), `field-swap` (the names of two
//!   adjacent fields of a message swapped). `drop-conj` also drops conjuncts of a field's
//!   refinement and of a branch guard.
//!
//! The `*-all` mutants drop the file's `local` declarations: they only restate the projection
//! (E0601 compares them), and a consistent change of the protocol would otherwise be killed
//! for the stale restatement alone.

use mochi::dialect::Dialect;
use mochi::source::SourceDb;
use mochi::syntax::lexer::{lex, Tok, Token};

/// One mutant of one file: edits on the original text, non-overlapping.
#[derive(Clone, Debug)]
pub struct Mutant {
    /// `L:C:op`, unique within the file.
    pub id: String,
    pub desc: String,
    pub edits: Vec<(usize, usize, String)>,
}

impl Mutant {
    pub fn apply(&self, text: &str) -> String {
        let mut edits = self.edits.clone();
        edits.sort_by_key(|e| std::cmp::Reverse(e.0));
        let mut out = text.to_string();
        for (s, e, r) in edits {
            out.replace_range(s..e, &r);
        }
        out
    }
}

const ITEM_KWS: &[&str] = &["import", "const", "robot", "motion", "system", "choreography", "process", "local"];
const CLAUSES: &[&str] = &["pre", "assume", "guarantee", "post", "footprint", "invariant", "init"];
const CMPS: &[&str] = &["<", "<=", ">", ">="];
const SORTS: &[&str] = &["real", "int", "bool"];
/// Relative and absolute nudges: 10% breaks any margin that is not generous, 1e-3 any bound
/// that is meant to be tight (the smallest margin in the examples is Handover's 3 mm gap).
const FP_SLACK: &str = "0.05";
/// Shadowing targets per binder: the other binders of the item, then the state variables
/// and constants it reads, up to this many.
const MAX_SHADOW: usize = 3;

struct Src<'a> {
    text: &'a str,
    toks: Vec<Token>,
    /// Line starts (byte offsets).
    lines: Vec<usize>,
}

#[derive(Clone, Debug)]
struct Item {
    kw: String,
    name: String,
    /// Token range [start, end).
    start: usize,
    end: usize,
}

impl<'a> Src<'a> {
    fn new(text: &'a str) -> Src<'a> {
        let mut db = SourceDb::new();
        let id = db.add("m", text);
        let (mut toks, _) = lex(id, text);
        if matches!(toks.last(), Some(Token { tok: Tok::Eof, .. })) {
            toks.pop();
        }
        let mut lines = vec![0];
        lines.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Src { text, toks, lines }
    }
    fn s(&self, i: usize) -> usize {
        self.toks[i].span.start as usize
    }
    fn e(&self, i: usize) -> usize {
        self.toks[i].span.end as usize
    }
    fn punct(&self, i: usize) -> Option<&'static str> {
        match self.toks.get(i).map(|t| &t.tok) {
            Some(Tok::Punct(p)) => Some(p),
            _ => None,
        }
    }
    fn ident(&self, i: usize) -> Option<&str> {
        match self.toks.get(i).map(|t| &t.tok) {
            Some(Tok::Ident(s)) => Some(s),
            _ => None,
        }
    }
    fn is_p(&self, i: usize, p: &str) -> bool {
        self.punct(i) == Some(p)
    }
    fn pos(&self, i: usize) -> String {
        let off = self.s(i);
        let line = self.lines.partition_point(|&l| l <= off);
        let col = self.text[self.lines[line - 1]..off].chars().count() + 1;
        format!("{line}:{col}")
    }
    fn slice(&self, a: usize, b_incl: usize) -> &str {
        &self.text[self.s(a)..self.e(b_incl)]
    }
    /// Top-level items: a keyword at bracket depth 0 up to the next one.
    fn items(&self) -> Vec<Item> {
        let mut starts = Vec::new();
        let mut depth = 0i32;
        for i in 0..self.toks.len() {
            match self.punct(i) {
                Some("(" | "{" | "[") => depth += 1,
                Some(")" | "}" | "]") => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                if let Some(k) = self.ident(i) {
                    let prev_ok = i == 0 || matches!(self.punct(i - 1), Some(";" | "}"));
                    if ITEM_KWS.contains(&k) && prev_ok {
                        starts.push(i);
                    }
                }
            }
        }
        let mut items = Vec::new();
        for (n, &st) in starts.iter().enumerate() {
            let end = starts.get(n + 1).copied().unwrap_or(self.toks.len());
            let mut name = self.ident(st + 1).unwrap_or("").to_string();
            if self.is_p(st + 2, ".") {
                name = format!("{name}.{}", self.ident(st + 3).unwrap_or(""));
            }
            items.push(Item { kw: self.ident(st).unwrap_or("").to_string(), name, start: st, end });
        }
        items
    }
    /// Index of the token closing the bracket opened at `i`.
    fn matching(&self, i: usize, end: usize) -> Option<usize> {
        let mut depth = 0i32;
        for j in i..end {
            match self.punct(j) {
                Some("(" | "{" | "[") => depth += 1,
                Some(")" | "}" | "]") => {
                    depth -= 1;
                    if depth == 0 {
                        return Some(j);
                    }
                }
                _ => {}
            }
        }
        None
    }
    /// The `<` and `>` tokens that delimit `dt<...>`.
    fn dt_brackets(&self) -> Vec<usize> {
        let mut out = Vec::new();
        for i in 0..self.toks.len() {
            if self.ident(i) == Some("dt") && self.is_p(i + 1, "<") {
                out.push(i + 1);
                let mut depth = 0;
                for j in i + 2..self.toks.len() {
                    match self.punct(j) {
                        Some("(" | "[" | "{") => depth += 1,
                        Some(")" | "]" | "}") => depth -= 1,
                        Some(">") if depth == 0 => {
                            out.push(j);
                            break;
                        }
                        _ => {}
                    }
                }
            }
        }
        out
    }
    /// End (exclusive) of the expression region starting at `i`: the first `;`, `,` or
    /// unbalanced closing bracket.
    fn region_end(&self, i: usize, end: usize) -> usize {
        let mut depth = 0i32;
        for j in i..end {
            match self.punct(j) {
                Some("(" | "{" | "[") => depth += 1,
                Some(")" | "}" | "]") => {
                    if depth == 0 {
                        return j;
                    }
                    depth -= 1
                }
                Some(";" | ",") if depth == 0 => return j,
                _ => {}
            }
        }
        end
    }
}

fn fmt_num(v: f64) -> String {
    let mut s = format!("{v:.12}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.push('0');
    }
    if v < 0.0 {
        format!("({s})")
    } else {
        s
    }
}

/// Every mutant of `text`. `state_vars` are the robot state variables of the whole program
/// (binder shadowing targets); `consts` its constants; `dialect` the MAVLink dialect of the
/// example the file belongs to (`None` for motion choreographies), which turns on the MAVLink
/// operators.
pub fn mutants(text: &str, state_vars: &[String], consts: &[String], dialect: Option<&Dialect>) -> Vec<Mutant> {
    let src = Src::new(text);
    let items = src.items();
    let mut out = Vec::new();
    nudges(&src, &mut out);
    cmp_flips(&src, &mut out);
    for it in &items {
        clauses(&src, it, &mut out);
        if it.kw == "motion" {
            durations(&src, it, &mut out);
        }
        shadows(&src, it, state_vars, consts, &mut out);
    }
    messages(&src, &items, &mut out);
    shapes(&src, &mut out);
    poses(&src, &mut out);
    if let Some(d) = dialect {
        mav_numbers(&src, &mut out);
        mav_enums(&src, d, &mut out);
        mav_steps(&src, &items, &mut out);
    }
    // Unique ids (two operators never share a name, but be safe).
    let mut seen = std::collections::HashMap::<String, usize>::new();
    for m in &mut out {
        let n = seen.entry(m.id.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            m.id = format!("{}#{}", m.id, n);
        }
    }
    out
}

fn nudges(src: &Src, out: &mut Vec<Mutant>) {
    for i in 0..src.toks.len() {
        let v = match &src.toks[i].tok {
            Tok::Int(n) => *n as f64,
            Tok::Real(s) => match s.parse::<f64>() {
                Ok(v) => v,
                Err(_) => continue,
            },
            _ => continue,
        };
        if i > 0 && src.is_p(i - 1, "^") {
            continue;
        }
        let lit = src.slice(i, i);
        let mut ops: Vec<(&str, f64)> = vec![("nudge+1e-3", v + 1e-3), ("nudge-1e-3", v - 1e-3)];
        if v != 0.0 {
            ops.insert(0, ("nudge/10%", v * 0.9));
            ops.insert(0, ("nudge*10%", v * 1.1));
        }
        for (op, nv) in ops {
            let r = fmt_num(nv);
            out.push(Mutant {
                id: format!("{}:{op}", src.pos(i)),
                desc: format!("literal {lit} -> {r}"),
                edits: vec![(src.s(i), src.e(i), r)],
            });
        }
    }
}

fn cmp_flips(src: &Src, out: &mut Vec<Mutant>) {
    let dt = src.dt_brackets();
    for i in 0..src.toks.len() {
        let Some(p) = src.punct(i) else { continue };
        let to = match p {
            "<" => "<=",
            "<=" => "<",
            ">" => ">=",
            ">=" => ">",
            _ => continue,
        };
        if dt.contains(&i) {
            continue;
        }
        out.push(Mutant {
            id: format!("{}:cmp", src.pos(i)),
            desc: format!("`{p}` -> `{to}` in `{}`", context(src, i)),
            edits: vec![(src.s(i), src.e(i), to.to_string())],
        });
    }
}

/// A short snippet around token `i` for descriptions.
fn context(src: &Src, i: usize) -> String {
    let a = i.saturating_sub(3);
    let b = (i + 3).min(src.toks.len() - 1);
    src.slice(a, b).split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Contract parts and refinements: conjunct drops, and footprint widening.
fn clauses(src: &Src, it: &Item, out: &mut Vec<Mutant>) {
    let mut i = it.start;
    let mut parens = 0i32;
    while i < it.end {
        match src.punct(i) {
            Some("(") => parens += 1,
            Some(")") => parens -= 1,
            _ => {}
        }
        // `pre:` ... or `footprint(px, py, pz):` ...
        let mut body = None;
        // A MAVLink field's refinement (`count {...}`, `seq as x {...}`: a `{` after a name,
        // inside a message's parentheses) and a branch guard (`p -> q: [...]`).
        if src.is_p(i, "{") && parens > 0 && i > 0 && src.ident(i - 1).is_some_and(|k| !SORTS.contains(&k)) {
            body = Some(("refinement".to_string(), i + 1));
        } else if src.is_p(i, "[") && i >= 4 && src.is_p(i - 1, ":") && src.is_p(i - 3, "->") {
            body = Some(("guard".to_string(), i + 1));
        }
        if let Some(k) = src.ident(i).filter(|_| body.is_none()) {
            if CLAUSES.contains(&k) {
                if src.is_p(i + 1, ":") {
                    body = Some((k.to_string(), i + 2));
                } else if k == "footprint" && src.is_p(i + 1, "(") {
                    if let Some(c) = src.matching(i + 1, it.end) {
                        if src.is_p(c + 1, ":") {
                            body = Some((k.to_string(), c + 2));
                        }
                    }
                }
            } else if SORTS.contains(&k) && i > 0 && src.is_p(i - 1, ":") && src.is_p(i + 1, "{") {
                body = Some(("refinement".to_string(), i + 2));
            }
        }
        if let Some((kind, b)) = body {
            let e = src.region_end(b, it.end);
            drop_conjuncts(src, &kind, b, e, out);
            if kind == "footprint" {
                widen(src, b, e, out);
            }
        }
        i += 1;
    }
}

fn drop_conjuncts(src: &Src, kind: &str, b: usize, e: usize, out: &mut Vec<Mutant>) {
    let mut depth = 0i32;
    let mut ands = Vec::new();
    for j in b..e {
        match src.punct(j) {
            Some("(" | "{" | "[") => depth += 1,
            Some(")" | "}" | "]") => depth -= 1,
            Some("||" | "=>") if depth == 0 => return,
            Some("&&") if depth == 0 => ands.push(j),
            _ => {}
        }
    }
    if ands.is_empty() {
        return;
    }
    // Conjunct k spans [starts[k], ends[k]] (tokens, inclusive).
    let mut starts = vec![b];
    let mut ends = Vec::new();
    for &a in &ands {
        ends.push(a - 1);
        starts.push(a + 1);
    }
    ends.push(e - 1);
    for k in 0..starts.len() {
        // Remove the conjunct and the `&&` after it (the one before it for the last).
        let (s, t) = if k + 1 < starts.len() {
            (src.s(starts[k]), src.s(starts[k + 1]))
        } else {
            (src.e(ends[k - 1]), src.e(ends[k]))
        };
        let c = src.slice(starts[k], ends[k]).split_whitespace().collect::<Vec<_>>().join(" ");
        out.push(Mutant {
            id: format!("{}:drop-conj", src.pos(starts[k])),
            desc: format!("{kind}: drop conjunct `{c}`"),
            edits: vec![(s, t, String::new())],
        });
    }
}

fn widen(src: &Src, b: usize, e: usize, out: &mut Vec<Mutant>) {
    let stops = |p: Option<&str>| matches!(p, Some("&&" | "||" | "=>"));
    for j in b..e {
        let Some(op) = src.punct(j) else { continue };
        if !CMPS.contains(&op) {
            continue;
        }
        // Scan right at this depth for `=>`: a comparison in an antecedent is skipped.
        let mut antecedent = false;
        let mut depth = 0i32;
        for k in j + 1..e {
            match src.punct(k) {
                Some("(" | "{" | "[") => depth += 1,
                Some(")" | "}" | "]") => {
                    if depth == 0 {
                        break;
                    }
                    depth -= 1
                }
                Some("=>") if depth == 0 => {
                    antecedent = true;
                    break;
                }
                _ => {}
            }
        }
        // Is the right operand shared with a further comparison of the chain?
        let mut chain_r = false;
        let mut depth = 0i32;
        for k in j + 1..e {
            match src.punct(k) {
                Some("(" | "{" | "[") => depth += 1,
                Some(")" | "}" | "]") => {
                    if depth == 0 {
                        break;
                    }
                    depth -= 1
                }
                p if depth == 0 && stops(p) => break,
                Some(p) if depth == 0 && CMPS.contains(&p) => {
                    chain_r = true;
                    break;
                }
                _ => {}
            }
        }
        let mut chain_l = false;
        let mut depth = 0i32;
        for k in (b..j).rev() {
            match src.punct(k) {
                Some(")" | "}" | "]") => depth += 1,
                Some("(" | "{" | "[") => {
                    if depth == 0 {
                        break;
                    }
                    depth -= 1
                }
                p if depth == 0 && stops(p) => break,
                Some(p) if depth == 0 && CMPS.contains(&p) => {
                    chain_l = true;
                    break;
                }
                _ => {}
            }
        }
        if antecedent {
            continue;
        }
        let less = op.starts_with('<');
        // Relax on the side that no other comparison of the chain shares.
        let edit = if !chain_r {
            // Right operand unshared: raise it (<) or lower it (>).
            let ins = if less { format!("{FP_SLACK} + ") } else { format!("(-{FP_SLACK}) + ") };
            (src.s(j + 1), src.s(j + 1), ins)
        } else if !chain_l {
            let ins = if less { format!(" - {FP_SLACK}") } else { format!(" + {FP_SLACK}") };
            (src.e(j - 1), src.e(j - 1), ins)
        } else {
            continue;
        };
        out.push(Mutant {
            id: format!("{}:fp-widen", src.pos(j)),
            desc: format!("footprint: relax `{}` by {FP_SLACK}", context(src, j)),
            edits: vec![edit],
        });
    }
}

fn durations(src: &Src, it: &Item, out: &mut Vec<Mutant>) {
    for i in it.start..it.end {
        if src.ident(i) != Some("duration") || !src.is_p(i + 1, ":") || !src.is_p(i + 2, "[") {
            continue;
        }
        let open = i + 2;
        let Some(close) = src.matching(open, it.end) else { continue };
        let comma = src.region_end(open + 1, close);
        if comma >= close {
            continue;
        }
        let lo = src.slice(open + 1, comma - 1).to_string();
        let hi = src.slice(comma + 1, close - 1).to_string();
        let (s, e) = (src.s(open), src.e(close));
        let hi_inf = hi.trim() == "inf";
        let mk = |op: &str, l: String, h: String| Mutant {
            id: format!("{}:{op}", src.pos(open)),
            desc: format!("{}: duration [{lo}, {hi}] -> [{l}, {h}]", it.name),
            edits: vec![(s, e, format!("[{l}, {h}]"))],
        };
        if !hi_inf && lo.trim() != hi.trim() {
            out.push(mk("dur-swap", hi.clone(), lo.clone()));
        }
        out.push(mk("dur-lo+1", format!("({lo}) + 1"), hi.clone()));
        if lo.trim() != "0" {
            out.push(mk("dur-lo-1", format!("({lo}) - 1"), hi.clone()));
        }
        if !hi_inf {
            out.push(mk("dur-hi+1", lo.clone(), format!("({hi}) + 1")));
            out.push(mk("dur-hi-1", lo.clone(), format!("({hi}) - 1")));
        }
    }
}

/// Binders of an item, as (token index of the binding occurrence, name).
fn binders(src: &Src, it: &Item) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut i = it.start;
    while i < it.end {
        match (src.ident(i), src.punct(i)) {
            (Some("mu"), _) => {
                if let Some(n) = src.ident(i + 1) {
                    out.push((i + 1, n.to_string()));
                }
            }
            // payloads and parameters: `name: real` inside parentheses
            (Some(n), _)
                if src.is_p(i + 1, ":")
                    && src.ident(i + 2).is_some_and(|s| SORTS.contains(&s))
                    && i > 0
                    && matches!(src.punct(i - 1), Some("(" | ",")) =>
            {
                out.push((i, n.to_string()));
            }
            // `?label(a, b)`, `footprint(px, py, pz)`, `partition(px, py, pz)`
            (Some(k), _) if (k == "footprint" || k == "partition") && src.is_p(i + 1, "(") => {
                if let Some(c) = src.matching(i + 1, it.end) {
                    for j in i + 2..c {
                        if let Some(n) = src.ident(j) {
                            out.push((j, n.to_string()));
                        }
                    }
                    i = c;
                }
            }
            (_, Some("?")) if src.ident(i + 1).is_some() && src.is_p(i + 2, "(") && it.kw == "process" => {
                if let Some(c) = src.matching(i + 2, it.end) {
                    for j in i + 3..c {
                        if let Some(n) = src.ident(j) {
                            out.push((j, n.to_string()));
                        }
                    }
                    i = c;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

fn shadows(src: &Src, it: &Item, state_vars: &[String], consts: &[String], out: &mut Vec<Mutant>) {
    let bs = binders(src, it);
    if bs.is_empty() {
        return;
    }
    let idents: Vec<&str> = (it.start..it.end).filter_map(|i| src.ident(i)).collect();
    let mut done = std::collections::HashSet::new();
    for (bi, b) in &bs {
        if !done.insert(b.clone()) {
            continue; // the same name bound twice (two branches): rename all at once
        }
        let is_mu = *bi > 0 && src.ident(bi - 1) == Some("mu");
        let mut targets: Vec<String> = Vec::new();
        for (bj, n) in &bs {
            let other_mu = *bj > 0 && src.ident(bj - 1) == Some("mu");
            if n != b && other_mu == is_mu && !targets.contains(n) {
                targets.push(n.clone());
            }
        }
        if !is_mu {
            // Then the state variables and constants the item reads, in order of first use,
            // up to MAX_SHADOW targets in all (the cost of the run grows with them).
            for n in &idents {
                if targets.len() >= MAX_SHADOW {
                    break;
                }
                let n = n.to_string();
                if n != *b && !targets.contains(&n) && (state_vars.contains(&n) || consts.contains(&n)) {
                    targets.push(n);
                }
            }
        }
        for n in targets {
            let edits: Vec<_> = (it.start..it.end)
                .filter(|&i| src.ident(i) == Some(b.as_str()) && !(i > 0 && src.is_p(i - 1, ".")))
                .map(|i| (src.s(i), src.e(i), n.clone()))
                .collect();
            out.push(Mutant {
                id: format!("{}:shadow({b}->{n})", src.pos(*bi)),
                desc: format!("{} {}: binder `{b}` renamed to `{n}` with its uses", it.kw, it.name),
                edits,
            });
        }
    }
}

/// A message step of a choreography (`p -> q: l(...)`) or an action of a process
/// (`q!l(...)`, `p?l(...)`, `dt<...>`): token range [a, b] inclusive, and its parts.
#[derive(Clone, Debug)]
struct Step {
    a: usize,
    b: usize,
    /// (from, to, label) for messages; None for `dt`.
    msg: Option<(String, String, String)>,
}

fn steps(src: &Src, it: &Item) -> Vec<Step> {
    let mut out = Vec::new();
    let mut i = it.start;
    while i < it.end {
        let end_of_label = |l: usize| -> usize {
            if src.is_p(l + 1, "(") {
                src.matching(l + 1, it.end).unwrap_or(l)
            } else {
                l
            }
        };
        if src.ident(i) == Some("dt") && src.is_p(i + 1, "<") {
            let mut j = i + 2;
            let mut depth = 0;
            while j < it.end {
                match src.punct(j) {
                    Some("(" | "[" | "{") => depth += 1,
                    Some(")" | "]" | "}") => depth -= 1,
                    Some(">") if depth == 0 => break,
                    _ => {}
                }
                j += 1;
            }
            out.push(Step { a: i, b: j, msg: None });
            i = j + 1;
            continue;
        }
        if let (Some(p), true, Some(q), true) =
            (src.ident(i), src.is_p(i + 1, "->"), src.ident(i + 2), src.is_p(i + 3, ":"))
        {
            // `p -> q: [guard] LABEL[COMMAND](fields)`: the guard and the command are optional.
            let mut l = i + 4;
            if src.is_p(l, "[") {
                l = src.matching(l, it.end).map_or(l, |c| c + 1);
            }
            if let Some(label) = src.ident(l) {
                let mut b = l;
                if src.is_p(b + 1, "[") {
                    b = src.matching(b + 1, it.end).unwrap_or(b);
                }
                let b = end_of_label(b);
                out.push(Step { a: i, b, msg: Some((p.into(), q.into(), label.into())) });
                i = b + 1;
                continue;
            }
        }
        if let (Some(q), Some(d @ ("!" | "?")), Some(l)) = (src.ident(i), src.punct(i + 1), src.ident(i + 2)) {
            let b = end_of_label(i + 2);
            let (f, t) = if d == "!" { (it.name.clone(), q.to_string()) } else { (q.to_string(), it.name.clone()) };
            out.push(Step { a: i, b, msg: Some((f, t, l.into())) });
            i = b + 1;
            continue;
        }
        i += 1;
    }
    out
}

/// Removes a step and the `.` after it.
fn drop_step(src: &Src, s: &Step) -> Option<(usize, usize, String)> {
    if src.is_p(s.b + 1, ".") {
        Some((src.s(s.a), src.s(s.b + 2).min(src.text.len()), String::new()))
    } else {
        None
    }
}

/// Swaps two steps `A. B` (B right after A's dot).
fn swap_steps(src: &Src, x: &Step, y: &Step) -> Option<(usize, usize, String)> {
    if src.is_p(x.b + 1, ".") && y.a == x.b + 2 {
        Some((src.s(x.a), src.e(y.b), format!("{}.{}", src.slice(y.a, y.b), src.slice(x.a, x.b))))
    } else {
        None
    }
}

fn messages(src: &Src, items: &[Item], out: &mut Vec<Mutant>) {
    let locals: Vec<(usize, usize, String)> = items
        .iter()
        .filter(|it| it.kw == "local")
        .map(|it| (src.s(it.start), src.e(it.end - 1), String::new()))
        .collect();
    let procs: Vec<(&Item, Vec<Step>)> =
        items.iter().filter(|it| it.kw == "process").map(|it| (it, steps(src, it))).collect();
    let show = |s: &Step| src.slice(s.a, s.b).split_whitespace().collect::<Vec<_>>().join(" ");
    // k-th occurrence in `ps` of a message (from, to, label), in process `who`.
    let find = |who: &str, m: &(String, String, String), k: usize| -> Option<Step> {
        let (_, ps) = procs.iter().find(|(it, _)| it.name == who)?;
        ps.iter().filter(|s| s.msg.as_ref() == Some(m)).nth(k).cloned()
    };
    for it in items.iter().filter(|it| it.kw == "choreography") {
        let ss = steps(src, it);
        let mut count = std::collections::HashMap::<(String, String, String), usize>::new();
        for (n, s) in ss.iter().enumerate() {
            if let Some(m) = &s.msg {
                let k = *count.entry(m.clone()).and_modify(|c| *c += 1).or_insert(0);
                if let Some(e) = drop_step(src, s) {
                    out.push(Mutant {
                        id: format!("{}:drop-msg", src.pos(s.a)),
                        desc: format!("choreography: drop `{}`", show(s)),
                        edits: vec![e.clone()],
                    });
                    let (snd, rcv) = (find(&m.0, m, k), find(&m.1, m, k));
                    if let (Some(a), Some(b)) = (snd, rcv) {
                        if let (Some(ea), Some(eb)) = (drop_step(src, &a), drop_step(src, &b)) {
                            let mut edits = vec![e, ea, eb];
                            edits.extend(locals.iter().cloned());
                            out.push(Mutant {
                                id: format!("{}:drop-msg-all", src.pos(s.a)),
                                desc: format!("drop `{}` from the choreography and both processes", show(s)),
                                edits,
                            });
                        }
                    }
                }
            }
            if let Some(t) = ss.get(n + 1) {
                if let Some(e) = swap_steps(src, s, t) {
                    out.push(Mutant {
                        id: format!("{}:swap", src.pos(s.a)),
                        desc: format!("choreography: swap `{}` and `{}`", show(s), show(t)),
                        edits: vec![e.clone()],
                    });
                    // Consistent: two messages sharing the sender or the receiver, swapped
                    // in that one process as well.
                    if let (Some(m1), Some(m2)) = (&s.msg, &t.msg) {
                        let who = if m1.0 == m2.0 && m1.1 != m2.1 {
                            Some(m1.0.clone())
                        } else if m1.1 == m2.1 && m1.0 != m2.0 {
                            Some(m1.1.clone())
                        } else {
                            None
                        };
                        let k1 = count.get(m1).copied().unwrap_or(0);
                        if let Some(who) = who {
                            if let Some((_, ps)) = procs.iter().find(|(p, _)| p.name == who) {
                                let hit = ps
                                    .windows(2)
                                    .filter(|w| w[0].msg.as_ref() == Some(m1) && w[1].msg.as_ref() == Some(m2))
                                    .nth(k1);
                                if let Some(w) = hit {
                                    if let Some(pe) = swap_steps(src, &w[0], &w[1]) {
                                        let mut edits = vec![e, pe];
                                        edits.extend(locals.iter().cloned());
                                        out.push(Mutant {
                                            id: format!("{}:swap-all", src.pos(s.a)),
                                            desc: format!(
                                                "swap `{}` and `{}` in the choreography and in {who}",
                                                show(s),
                                                show(t)
                                            ),
                                            edits,
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    for (it, ps) in &procs {
        for (n, s) in ps.iter().enumerate() {
            if s.msg.is_some() {
                if let Some(e) = drop_step(src, s) {
                    out.push(Mutant {
                        id: format!("{}:drop-act", src.pos(s.a)),
                        desc: format!("process {}: drop `{}`", it.name, show(s)),
                        edits: vec![e],
                    });
                }
            }
            if let Some(t) = ps.get(n + 1) {
                if let Some(e) = swap_steps(src, s, t) {
                    out.push(Mutant {
                        id: format!("{}:swap-act", src.pos(s.a)),
                        desc: format!("process {}: swap `{}` and `{}`", it.name, show(s), show(t)),
                        edits: vec![e],
                    });
                }
            }
        }
    }
}

/// Names declared by `const NAME` and by `state a: real, b: real` in `text`.
pub fn declared_names(text: &str) -> (Vec<String>, Vec<String>) {
    let src = Src::new(text);
    let (mut consts, mut states) = (Vec::new(), Vec::new());
    for i in 0..src.toks.len() {
        match src.ident(i) {
            Some("const") => {
                if let Some(n) = src.ident(i + 1) {
                    consts.push(n.to_string());
                }
            }
            Some("state") => {
                let mut j = i + 1;
                while let (Some(n), true) = (src.ident(j), src.is_p(j + 1, ":")) {
                    states.push(n.to_string());
                    j += 3;
                    if !src.is_p(j, ",") {
                        break;
                    }
                    j += 1;
                }
            }
            _ => {}
        }
    }
    (consts, states)
}

// ---- geometry ----------------------------------------------------------------------------

/// The top-level arguments of the call whose `(` is token `open`: token ranges [a, b]
/// (inclusive) and the closing parenthesis.
fn args(src: &Src, open: usize) -> Option<(Vec<(usize, usize)>, usize)> {
    let close = src.matching(open, src.toks.len())?;
    let mut out = Vec::new();
    let mut a = open + 1;
    while a < close {
        let e = src.region_end(a, close);
        if e == a {
            return None;
        }
        out.push((a, e - 1));
        a = e + 1;
    }
    Some((out, close))
}

/// `geo-grow`, `geo-shrink`: every size of a `box(...)`, `cylinder(...)` or `sphere(...)`
/// (a body, an obstacle's part or a footprint) scaled by 1.2 or 0.8 at once.
fn shapes(src: &Src, out: &mut Vec<Mutant>) {
    for i in 0..src.toks.len() {
        let Some("box" | "cylinder" | "sphere") = src.ident(i) else { continue };
        if !src.is_p(i + 1, "(") {
            continue;
        }
        let Some((xs, _)) = args(src, i + 1) else { continue };
        for (op, f) in [("geo-grow", "1.2"), ("geo-shrink", "0.8")] {
            let edits: Vec<_> =
                xs.iter().map(|&(a, b)| (src.s(a), src.e(b), format!("({}) * {f}", src.slice(a, b)))).collect();
            out.push(Mutant {
                id: format!("{}:{op}", src.pos(i)),
                desc: format!("`{}` with every size times {f}", context(src, i)),
                edits,
            });
        }
    }
}

/// `pose-x+`, `pose-x-`, `pose-y+`, ..., `pose-yaw+`, `pose-yaw-`: one component of a
/// `pose(...)` (a participant's place, a mount point `mount deck: pose(...)` or a mounted
/// participant's offset on it, a body part's place) moved by 0.05 m, or its yaw by 0.1 rad.
fn poses(src: &Src, out: &mut Vec<Mutant>) {
    for i in 0..src.toks.len() {
        if src.ident(i) != Some("pose") || !src.is_p(i + 1, "(") {
            continue;
        }
        let Some((xs, _)) = args(src, i + 1) else { continue };
        let mut moves: Vec<(usize, &str, &str)> = Vec::new();
        for (k, axis) in ["x", "y", "z"].iter().enumerate().take(xs.len()) {
            moves.push((k, axis, "0.05"));
        }
        if xs.len() == 6 {
            moves.push((5, "yaw", "0.1"));
        }
        for (k, axis, by) in moves {
            let (a, b) = xs[k];
            for sign in ["+", "-"] {
                out.push(Mutant {
                    id: format!("{}:pose-{axis}{sign}", src.pos(i)),
                    desc: format!("`{}`: {axis} {sign} {by}", src.slice(i, xs.last().unwrap().1 + 1)),
                    edits: vec![(src.s(a), src.e(b), format!("({}) {sign} {by}", src.slice(a, b)))],
                });
            }
        }
    }
}

/// The mutants of a URDF file: `urdf-scale` (a collision mesh scaled by 1.2 about its
/// origin: `scale` added or multiplied), `urdf-grow` (a collision box, cylinder or sphere
/// 1.2 times as large), `urdf-move+x`, `urdf-move+y`, `urdf-move-z` (a collision element's
/// origin moved by 0.03 m). Only `<collision>` elements: visuals are not read.
pub fn urdf_mutants(text: &str) -> Vec<Mutant> {
    let mut lines = vec![0];
    lines.extend(text.match_indices('\n').map(|(i, _)| i + 1));
    let pos = |off: usize| {
        let line = lines.partition_point(|&l| l <= off);
        format!("{line}:{}", text[lines[line - 1]..off].chars().count() + 1)
    };
    // The attribute `name="..."` of the element starting at `at` (up to its `>`): value span.
    let attr = |at: usize, name: &str| -> Option<(usize, usize)> {
        let end = at + text[at..].find('>')?;
        let tag = &text[at..end];
        let k = tag.find(&format!(" {name}=\"")).or_else(|| tag.find(&format!("\n{name}=\"")));
        let k = k.or_else(|| tag.find(&format!("\t{name}=\""))).or_else(|| {
            tag.match_indices(&format!("{name}=\""))
                .map(|(i, _)| i)
                .find(|&i| i > 0 && tag.as_bytes()[i - 1].is_ascii_whitespace())
        })?;
        let vs = at + k + name.len() + 3;
        let ve = vs + text[vs..].find('"')?;
        Some((vs, ve))
    };
    let scaled = |v: &str, f: f64| -> Option<String> {
        let xs: Vec<f64> = v.split_whitespace().map(|x| x.parse().ok()).collect::<Option<_>>()?;
        Some(
            xs.iter()
                .map(|x| fmt_num(x * f).trim_matches(|c| c == '(' || c == ')').to_string())
                .collect::<Vec<_>>()
                .join(" "),
        )
    };
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = text[from..].find("<collision") {
        let cs = from + k;
        let Some(ce) = text[cs..].find("</collision>").map(|e| cs + e) else { break };
        from = ce;
        let body = &text[cs..ce];
        if let Some(o) = body.find("<origin") {
            let at = cs + o;
            if let Some((vs, ve)) = attr(at, "xyz") {
                let xyz: Option<Vec<f64>> = text[vs..ve].split_whitespace().map(|x| x.parse().ok()).collect();
                if let Some(xyz) = xyz.filter(|v| v.len() == 3) {
                    for (axis, d) in [(0usize, 0.03f64), (1, 0.03), (2, -0.03)] {
                        let mut v = xyz.clone();
                        v[axis] += d;
                        let nv = v.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(" ");
                        let name = ["x", "y", "z"][axis];
                        let sign = if d > 0.0 { "+" } else { "-" };
                        out.push(Mutant {
                            id: format!("{}:urdf-move{sign}{name}", pos(at)),
                            desc: format!("collision origin xyz=\"{}\" -> \"{nv}\"", &text[vs..ve]),
                            edits: vec![(vs, ve, nv)],
                        });
                    }
                }
            }
        }
        if let Some(m) = body.find("<mesh") {
            let at = cs + m;
            let edit = match attr(at, "scale") {
                Some((vs, ve)) => scaled(&text[vs..ve], 1.2).map(|nv| (vs, ve, nv)),
                None => Some((at + 5, at + 5, " scale=\"1.2 1.2 1.2\"".to_string())),
            };
            if let Some(e) = edit {
                out.push(Mutant {
                    id: format!("{}:urdf-scale", pos(at)),
                    desc: "collision mesh scaled by 1.2".into(),
                    edits: vec![e],
                });
            }
        }
        for (tag, names) in
            [("<box", &["size"][..]), ("<cylinder", &["radius", "length"][..]), ("<sphere", &["radius"][..])]
        {
            let Some(m) = body.find(tag) else { continue };
            let at = cs + m;
            let edits: Vec<_> = names
                .iter()
                .filter_map(|n| attr(at, n))
                .filter_map(|(vs, ve)| scaled(&text[vs..ve], 1.2).map(|nv| (vs, ve, nv)))
                .collect();
            if edits.len() == names.len() {
                out.push(Mutant {
                    id: format!("{}:urdf-grow", pos(at)),
                    desc: format!("collision {} 1.2 times as large", &tag[1..]),
                    edits,
                });
            }
        }
    }
    out
}

// ---- MAVLink -----------------------------------------------------------------------------

/// The float32 nearest to `v` and the next float32 above it.
fn f32_neighbours(v: f64) -> (f64, f64) {
    let f = v as f32;
    let up = f32::from_bits(if f >= 0.0 { f.to_bits() + 1 } else { f.to_bits() - 1 });
    let up = if f == 0.0 { f32::from_bits(1) } else { up };
    (f64::from(f), f64::from(up))
}

/// Every decimal digit of a finite f64 (exact: a binary fraction has a finite decimal).
fn exact_decimal(v: f64) -> String {
    let s = format!("{v:.60}");
    let s = s.trim_end_matches('0');
    let s = s.strip_suffix('.').map_or(s.to_string(), |t| format!("{t}.0"));
    if v < 0.0 {
        format!("({s})")
    } else {
        s
    }
}

/// `off-by-one+1`, `off-by-one-1`: an integer literal (a refinement's bound, a loop's start,
/// a constant) moved by one. `f32-up`, `f32-same`: a literal replaced by a number that is
/// not a float32: three quarters of the way (rounds on the wire to the next float32 up), or
/// a quarter of the way (rounds back to the literal's own float32) from the literal's
/// float32 to the next one.
fn mav_numbers(src: &Src, out: &mut Vec<Mutant>) {
    for i in 0..src.toks.len() {
        if i > 0 && src.is_p(i - 1, "^") {
            continue;
        }
        let lit = src.slice(i, i).to_string();
        let v = match &src.toks[i].tok {
            Tok::Int(n) => {
                for (op, d) in [("off-by-one+1", 1i64), ("off-by-one-1", -1)] {
                    let r = n.checked_add(d).map(|x| if x < 0 { format!("({x})") } else { x.to_string() });
                    if let Some(r) = r {
                        out.push(Mutant {
                            id: format!("{}:{op}", src.pos(i)),
                            desc: format!("literal {lit} -> {r} in `{}`", context(src, i)),
                            edits: vec![(src.s(i), src.e(i), r)],
                        });
                    }
                }
                *n as f64
            }
            Tok::Real(s) => match s.parse::<f64>() {
                Ok(v) => v,
                Err(_) => continue,
            },
            _ => continue,
        };
        let (f, up) = f32_neighbours(v);
        if !f.is_finite() || !up.is_finite() {
            continue;
        }
        for (op, w) in [("f32-up", 0.75), ("f32-same", 0.25)] {
            let r = exact_decimal(f + (up - f) * w);
            out.push(Mutant {
                id: format!("{}:{op}", src.pos(i)),
                desc: format!(
                    "literal {lit} -> {r} (not a float32; the wire rounds it to {})",
                    if w > 0.5 { up } else { f }
                ),
                edits: vec![(src.s(i), src.e(i), r)],
            });
        }
    }
}

/// `enum(A->B)`: an entry of the dialect's enums replaced by its neighbour in the same enum
/// (the next entry, the previous one for the last).
fn mav_enums(src: &Src, d: &Dialect, out: &mut Vec<Mutant>) {
    for i in 0..src.toks.len() {
        let Some(name) = src.ident(i) else { continue };
        let Some((en, _)) = d.entry(name) else { continue };
        let Some(k) = en.entries.iter().position(|e| e.name == name) else { continue };
        let other = en.entries.get(k + 1).or_else(|| k.checked_sub(1).and_then(|j| en.entries.get(j)));
        let Some(other) = other else { continue };
        out.push(Mutant {
            id: format!("{}:enum({name}->{})", src.pos(i), other.name),
            desc: format!("`{name}` -> `{}` (its neighbour in {}) in `{}`", other.name, en.name, context(src, i)),
            edits: vec![(src.s(i), src.e(i), other.name.clone())],
        });
    }
}

/// `guard-neg` (a comparison of a branch guard `[...]` negated: `<` to `>=`, `==` to `!=`,
/// ...), `dup-msg` (a message step of the choreography sent twice), `field-swap` (the names
/// of two adjacent fields of a message swapped, their refinements kept in place).
fn mav_steps(src: &Src, items: &[Item], out: &mut Vec<Mutant>) {
    for i in 4..src.toks.len() {
        if !(src.is_p(i, "[") && src.is_p(i - 1, ":") && src.is_p(i - 3, "->")) {
            continue;
        }
        let Some(close) = src.matching(i, src.toks.len()) else { continue };
        for j in i + 1..close {
            let to = match src.punct(j) {
                Some("<") => ">=",
                Some("<=") => ">",
                Some(">") => "<=",
                Some(">=") => "<",
                Some("==") => "!=",
                Some("!=") => "==",
                _ => continue,
            };
            out.push(Mutant {
                id: format!("{}:guard-neg", src.pos(j)),
                desc: format!("guard: `{}` -> `{to}` in `{}`", src.slice(j, j), context(src, j)),
                edits: vec![(src.s(j), src.e(j), to.to_string())],
            });
        }
    }
    for it in items.iter().filter(|it| it.kw == "choreography") {
        for s in steps(src, it) {
            let Some((_, _, label)) = &s.msg else { continue };
            if src.is_p(s.b + 1, ".") {
                let text = src.slice(s.a, s.b);
                out.push(Mutant {
                    id: format!("{}:dup-msg", src.pos(s.a)),
                    desc: format!(
                        "choreography: `{}` sent twice",
                        text.split_whitespace().collect::<Vec<_>>().join(" ")
                    ),
                    edits: vec![(src.s(s.a), src.s(s.a), format!("{text}.\n"))],
                });
            }
            // The fields: `LABEL(` ... `)` at the end of the step.
            if !src.is_p(s.b, ")") {
                continue;
            }
            let Some(open) = (s.a..s.b).rev().find(|&k| src.is_p(k, "(") && src.matching(k, s.b + 1) == Some(s.b))
            else {
                continue;
            };
            let Some((fs, _)) = args(src, open) else { continue };
            for w in fs.windows(2) {
                let (x, y) = (w[0].0, w[1].0);
                let (Some(nx), Some(ny)) = (src.ident(x), src.ident(y)) else { continue };
                out.push(Mutant {
                    id: format!("{}:field-swap", src.pos(x)),
                    desc: format!("{label}: fields `{nx}` and `{ny}` swapped (refinements kept in place)"),
                    edits: vec![(src.s(x), src.e(x), ny.to_string()), (src.s(y), src.e(y), nx.to_string())],
                });
            }
        }
    }
}
