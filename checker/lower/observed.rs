//! Streams and observed state (LANGUAGE.md, "Observed state"). A `stream FROM -> TO, ...:
//! LABEL(fields);` of the system is lowered once into a [`Stream`] whose fields are
//! templates (values of origin [`ValueOrigin::Stream`]). Wherever a participant decides,
//! at a message's guard and refinements (the first messages of a choice together), the
//! fields of every stream it sees are in scope as *snapshots*: fresh values (origin
//! [`ValueOrigin::Observed`]) with the template's refinement (wire range, enum and float
//! model, the stream's invariant) and nothing else. The snapshots leave scope after the
//! message, so no two steps read the same snapshot: nothing can be proved from two reads
//! at different steps being equal. A message keeps the snapshots it reads in
//! [`Msg::observed`] (a send of a local type in [`SendBranch::observed`]).

use super::*;

impl Lowerer {
    /// Lowers the streams of a system (after its participants).
    pub(super) fn streams(&mut self, s: &ast::SystemDecl) {
        for st in &s.streams {
            let Some(from) = self.role(&st.from) else { continue };
            let mut to = Vec::new();
            for t in &st.to {
                let Some(r) = self.role(t) else { continue };
                if r == from {
                    self.err(
                        Code::SelfMessage,
                        t.span,
                        format!("`{}` streams to itself", t.name),
                        "a stream goes from its sender to other participants: name them after `->`",
                    );
                } else if to.contains(&r) {
                    self.err(
                        Code::Duplicate,
                        t.span,
                        format!("`{}` is named twice as a receiver of this stream", t.name),
                        "name each receiver once",
                    );
                } else {
                    to.push(r);
                }
            }
            let idx = self.prog.streams.len() as u32;
            let mut values = Vec::new();
            let origin = ValueOrigin::Stream { stream: idx };
            let fields = self.message(&st.label, &st.payload, from, origin, &mut values);
            // The invariant is what every value of the stream satisfies: it reads the fields
            // of the stream's message and constants only.
            for f in &fields {
                let Some(r) = &f.refinement else { continue };
                let mut bad: Vec<Loc> = Vec::new();
                r.visit_vars(&mut |v, loc| match v {
                    Var::Value(id, _) if values.contains(id) => {}
                    Var::Const(_) => {}
                    _ => bad.push(loc),
                });
                if let Some(loc) = bad.first() {
                    self.err(
                        Code::VariableNotAllowed,
                        loc.0,
                        "a stream's invariant reads only the fields of its message and constants",
                        "the invariant is what every message of the stream satisfies, at any time: state it over the stream's own fields",
                    );
                }
            }
            for (name, span) in fields.iter().zip(&st.payload).map(|(f, a)| (f.name.clone(), a.bound().span)) {
                if let Some((k, _)) = self.observed_name(&name).filter(|(k, _)| *k != idx) {
                    let first = self.prog.streams[k as usize].loc.0;
                    self.diags.push(
                        Diagnostic::error(
                            Code::Duplicate,
                            span,
                            format!("`{name}` is observed from two streams"),
                        )
                        .with_label(first, "the other stream")
                        .with_help(format!("name one of them apart: `FIELD as NAME` (`{name} as other_{name}`)")),
                    );
                }
            }
            self.prog.streams.push(Stream {
                from,
                to,
                label: st.label.name.clone(),
                fields,
                loc: Loc(st.span),
            });
        }
    }

    /// The stream and field that observe `name`, if any.
    pub(super) fn observed_name(&self, name: &str) -> Option<(u32, u32)> {
        self.prog.streams.iter().enumerate().find_map(|(k, s)| {
            s.fields.iter().position(|f| f.name == name).map(|j| (k as u32, j as u32))
        })
    }

    /// Fresh snapshots of every field of every stream `reader` sees, each with its template's
    /// refinement over the snapshots of the same stream.
    pub(super) fn snapshot(&mut self, reader: RoleId) -> Vec<Observed> {
        let mut out = Vec::new();
        for k in 0..self.prog.streams.len() {
            if !self.prog.streams[k].seen_by(reader) {
                continue;
            }
            let fields = self.prog.streams[k].fields.clone();
            let mut map: HashMap<ValueId, Expr> = HashMap::new();
            let mut ids = Vec::new();
            for f in &fields {
                let tv = self.prog.value(f.value).clone();
                let id = ValueId(self.prog.values.len() as u32);
                self.prog.values.push(ValueVar {
                    name: tv.name.clone(),
                    sort: tv.sort.clone(),
                    origin: ValueOrigin::Observed { reader, stream: k as u32 },
                    span: tv.span,
                });
                if let Some(b) = self.prog.wire_floats.get(&f.value).copied() {
                    self.prog.wire_floats.insert(id, b);
                }
                if let Some(n) = self.str_len.get(&f.value).copied() {
                    self.str_len.insert(id, n);
                }
                map.insert(f.value, crate::hir::expr::value_expr(id, &f.name, &f.sort));
                ids.push(id);
            }
            for (j, (f, id)) in fields.iter().zip(ids).enumerate() {
                out.push(Observed {
                    value: id,
                    name: f.name.clone(),
                    sort: f.sort.clone(),
                    stream: k as u32,
                    field: j as u32,
                    refinement: f.refinement.as_ref().map(|r| crate::hir::expr::subst_values(r, &map)),
                });
            }
        }
        out
    }

    /// After a message (or a send) lowered with the snapshots `snap` in scope: takes them out
    /// of `values` and keeps those its guard or refinements read.
    pub(super) fn snapshots_read(
        &self,
        snap: &[Observed],
        guard: Option<&Expr>,
        payload: &[Field],
        values: &mut Vec<ValueId>,
    ) -> Vec<Observed> {
        values.retain(|v| !snap.iter().any(|o| o.value == *v));
        let reads = |o: &Observed| {
            let hit = |v: &Var| matches!(v, Var::Value(id, _) if *id == o.value);
            guard.is_some_and(|g| crate::hir::expr::mentions(g, &hit))
                || payload.iter().filter_map(|f| f.refinement.as_ref()).any(|r| crate::hir::expr::mentions(r, &hit))
        };
        snap.iter().filter(|o| reads(o)).cloned().collect()
    }

    /// An unbound name that a stream observes: E0305 when the reader decides here but does
    /// not see the stream, E0245 where no snapshot is taken. `None` when no stream observes
    /// `name`.
    pub(super) fn observed_elsewhere(&mut self, name: &str, span: Span) -> Option<()> {
        let (k, _) = self.observed_name(name)?;
        let s = &self.prog.streams[k as usize];
        let text = format!(
            "stream {} -> {}: {}",
            self.prog.role_name(s.from),
            s.to.iter().map(|r| self.prog.role_name(*r)).collect::<Vec<_>>().join(", "),
            s.label
        );
        if self.in_process {
            self.diags.push(
                Diagnostic::error(
                    Code::ObservedInProcess,
                    span,
                    format!("not supported yet: a process reads `{name}`, observed from `{text}`"),
                )
                .with_note("processes do not read streams yet; their local types may (a guard over the latest reading)")
                .with_help("check the protocol alone (no `process` items), or let the process receive the reading in a payload field"),
            );
            return Some(());
        }
        match self.deciding {
            Some(r) => {
                let who = self.prog.role_name(r).to_string();
                self.diags.push(
                    Diagnostic::error(
                        Code::GuardNotLocal,
                        span,
                        format!("`{who}` reads `{name}`, observed from a stream it does not receive"),
                    )
                    .with_label(s.loc.0, format!("`{text}`"))
                    .with_note("a participant reads only the streams it sends or receives (LANGUAGE.md, \"Observed state\")")
                    .with_help(format!("add `{who}` to the stream's receivers, or send it the value in a message")),
                );
            }
            None => self.diags.push(
                Diagnostic::error(
                    Code::ObservedOutsideMessage,
                    span,
                    format!("`{name}` is observed (`{text}`): it is read only in a message's guard or refinements"),
                )
                .with_note("an observed value may change between any two steps; a snapshot is taken where a participant decides, at a message")
                .with_help(format!(
                    "send the reading in a payload field and use that value: `FIELD as h {{h == {name}}}`"
                )),
            ),
        }
        Some(())
    }
}
