//! Violations and summaries: recording what broke, and saying it in words.

use super::automaton::{Automaton, StateKind};
use super::code::{self, Val};
use super::{Fail, Monitor, Session, SessionSummary, Violation};
use crate::mavio::Frame;

impl Monitor {
    pub(super) fn record(
        &mut self,
        slot: Option<usize>,
        state: Option<u32>,
        f: &Frame,
        index: u64,
        fail: Fail,
    ) -> usize {
        self.stats.violations += 1;
        let s = slot.map(|i| &self.slots[i]);
        let field = match (s, fail.edge, fail.field) {
            (Some(s), Some(e), Some(i)) => {
                self.protos[s.proto].edges[e as usize].fields.get(i as usize).map(|fr| fr.name.clone())
            }
            _ => None,
        };
        self.violations.push(Violation {
            frame: index,
            time_us: f.time_us,
            kind: fail.kind,
            protocol: s.map(|s| s.proto),
            session: s.map(|s| s.id),
            state: state.unwrap_or(0),
            edge: fail.edge,
            pred: fail.pred,
            field,
            why: fail.why,
            msgid: f.msgid,
            from: (f.sysid, f.compid),
            regs: s.map(|s| s.regs.clone()).unwrap_or_default(),
            strs: s.map(|s| s.strs.clone()).unwrap_or_default(),
            roles: s.map(|s| s.roles.clone()).unwrap_or_default(),
        });
        self.taken_violations + self.violations.len() - 1
    }

    /// A violation in words: what broke, where in the source, the values involved, and each
    /// role's local state (its binding and the values it knows).
    pub fn describe(&self, db: &crate::source::SourceDb, i: usize) -> String {
        let Some(v) = self.violation(i) else { return String::new() };
        let mut out = format!("frame {}", v.frame);
        if let Some(t) = v.time_us {
            out += &format!(" (t = {t} us)");
        }
        out += &format!(": message {} from {}/{}: {}", v.msgid, v.from.0, v.from.1, v.kind.as_str());
        let Some(p) = v.protocol else {
            return out;
        };
        let a = &self.protos[p];
        out += &format!(" in `{}` (session {}, state {})", a.name, v.session.unwrap_or(0), v.state);
        if let Some(e) = v.edge.and_then(|e| a.edges.get(e as usize)) {
            out += &format!(", at `{} -> {} : {}`", a.roles[e.from.idx()], a.roles[e.to.idx()], e.label);
        }
        if let Some(f) = &v.field {
            out += &format!(", field `{f}`");
        }
        if let Some(why) = v.why {
            out += &format!(": {why}");
        }
        if let Some(code) = v.pred.and_then(|id| find_code(a, id)) {
            let (file, line, col) = db.location(code.expr.loc.0);
            let text = crate::hir::print::expr(&a.prog, None, &code.expr);
            out += &format!("\n  {file}:{line}:{col}: `{text}`");
            let mut names = Vec::new();
            code.expr.visit_vars(&mut |var, _| {
                if let crate::hir::Var::Value(id, name) = var {
                    if let Some(r) = a.arena.reg_of.get(id) {
                        if !names.iter().any(|(n, _): &(String, u16)| n == name) {
                            names.push((name.clone(), *r));
                        }
                    }
                }
            });
            for (n, r) in names {
                out += &format!("\n  {n} = {}", show(a, &v.regs, &v.strs, r));
            }
        }
        for (k, role) in a.roles.iter().enumerate() {
            let b = v.roles.get(k).copied().unwrap_or_default();
            let end = |x: Option<u8>| x.map_or("?".to_string(), |x| x.to_string());
            out += &format!("\n  role {role} ({}/{}) knows:", end(b.sys), end(b.comp));
            for (r, info) in a.arena.regs.iter().enumerate() {
                if info.knowers >> k & 1 == 1 && !matches!(v.regs.get(r), None | Some(Val::Unset)) {
                    out += &format!(" {} = {};", info.name, show(a, &v.regs, &v.strs, r as u16));
                }
            }
        }
        out
    }
}

fn find_code(a: &Automaton, id: u32) -> Option<&code::Code> {
    for e in &a.edges {
        for c in e
            .guard
            .iter()
            .chain(e.fields.iter().flat_map(|f| f.refinement.iter().chain(f.entry.iter().map(|(c, _)| c))))
        {
            if c.id == id {
                return Some(c);
            }
        }
    }
    for st in &a.streams {
        for f in &st.fields {
            for c in f.refinement.iter().chain(f.entry.iter().map(|(c, _)| c)) {
                if c.id == id {
                    return Some(c);
                }
            }
        }
    }
    for s in &a.states {
        if let StateKind::Assign { assigns, checks, .. } = s {
            for (_, c) in assigns.iter().chain(checks) {
                if c.id == id {
                    return Some(c);
                }
            }
        }
    }
    None
}

fn show(a: &Automaton, regs: &[Val], strs: &[u8], r: u16) -> String {
    match regs.get(r as usize).copied().unwrap_or(Val::Unset) {
        Val::Unset => "(not set)".into(),
        Val::Bool(b) => b.to_string(),
        Val::Num(q) => crate::exact::decimal(&code::q_to_rat(q)),
        Val::Wide(x) => format!("{x:e}"),
        Val::Lit(c) => format!("{:?}", a.prog.strings.get(c as usize).map_or("", String::as_str)),
        Val::Str(reg) => {
            let info = &a.arena.regs[reg as usize];
            let bytes = strs.get(info.str_at as usize..info.str_at as usize + info.str_cap as usize).unwrap_or(&[]);
            format!("{:?}", String::from_utf8_lossy(code::cut(bytes)))
        }
    }
}

pub(super) fn summary(s: &Session, conformant: bool) -> SessionSummary {
    SessionSummary {
        session: s.id,
        protocol: s.proto,
        conformant,
        state: s.state,
        first_frame: s.first_frame,
        last_frame: s.last_frame,
        violations: s.violations,
        roles: s.roles.clone(),
        visited: s.visited.clone(),
        taken: s.taken.clone(),
        evaluated: s.evaluated.clone(),
    }
}
