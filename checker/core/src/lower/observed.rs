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
            let mut fields = self.message(&st.label, &st.payload, from, origin, &mut values);
            // A reading satisfies the invariant and can evaluate it: a partial operator
            // (`/`, `sqrt`) is applied within its domain (`hir::expr::definedness`). The
            // template's refinement says so itself, so that every reader of it (the
            // streams' satisfiability check, E0410; each snapshot; the monitor) asks the
            // same thing: an invariant `roll == 1.0 / 0.0` admits no reading, rather than
            // one with an arbitrary quotient that the steps' contexts (which conjoin the
            // definedness) then contradict.
            for f in &mut fields {
                if let Some(r) = f.refinement.take() {
                    f.refinement = Some(crate::hir::expr::defined_and(r));
                }
            }
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
                        Diagnostic::error(Code::Duplicate, span, format!("`{name}` is observed from two streams"))
                            .with_label(first, "the other stream")
                            .with_help(format!("name one of them apart: `FIELD as NAME` (`{name} as other_{name}`)")),
                    );
                }
            }
            self.prog.streams.push(Stream { from, to, label: st.label.name.clone(), fields, loc: Loc(st.span) });
        }
    }

    /// E0246: the step `from -> to: label` at `span` is also carried by a stream.
    pub(super) fn streamed_step(&mut self, from: RoleId, to: RoleId, label: &str, span: Span) {
        let Some(s) = self
            .prog
            .streams
            .iter()
            .find(|s| s.from == from && s.to.contains(&to) && crate::hir::labels_overlap(&s.label, label))
        else {
            return;
        };
        let loc = s.loc.0;
        let (f, t) = (self.prog.role_name(from).to_string(), self.prog.role_name(to).to_string());
        self.diags.push(
            Diagnostic::error(
                Code::StepIsStreamed,
                span,
                format!("`{f} -> {t}: {label}` is a step, and `{f}` also streams `{label}` to `{t}`"),
            )
            .with_label(loc, "the stream")
            .with_note("a stream's messages may come at any time: a monitor could not tell this step from them")
            .with_help(
                "read the stream's latest value in a guard instead of waiting for the message, or drop the stream",
            ),
        );
    }

    /// The stream and field that observe `name`, if any.
    pub(super) fn observed_name(&self, name: &str) -> Option<(u32, u32)> {
        self.prog
            .streams
            .iter()
            .enumerate()
            .find_map(|(k, s)| s.fields.iter().position(|f| f.name == name).map(|j| (k as u32, j as u32)))
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
                if let Some(n) = self.prog.str_width.get(&f.value).copied() {
                    self.prog.str_width.insert(id, n);
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

#[cfg(test)]
mod tests {
    use crate::diag::Code;
    use crate::hir::{Global, ValueOrigin};
    use crate::lower::tests::lower_src;

    const SYS: &str = "system S { participant P; participant Q; participant R;
        stream Q -> P, R: tick(h: int {0 <= h && h <= 100}, k: int); }";

    fn codes(chor: &str) -> Vec<(Code, String)> {
        let (_, d) = lower_src(&format!("{SYS} choreography G = {chor};"));
        d.into_iter().map(|d| (d.code, d.message)).collect()
    }

    fn messages(g: &Global, out: &mut Vec<crate::hir::Msg>) {
        match g {
            Global::Msg(m) => out.push(m.clone()),
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => gs.iter().for_each(|g| messages(g, out)),
            Global::Rec { body, .. } => messages(body, out),
            _ => {}
        }
    }

    #[test]
    fn a_stream_is_parsed_with_its_receivers_and_fields() {
        let (p, d) = lower_src(&format!("{SYS} choreography G = P -> Q: a. R -> Q: b. end;"));
        assert!(d.is_empty(), "{d:?}");
        let s = &p.streams[0];
        assert_eq!((p.role_name(s.from), s.to.len(), s.label.as_str()), ("Q", 2, "tick"));
        assert_eq!(s.fields.iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["h", "k"]);
        assert!(s.fields.iter().all(|f| matches!(p.value(f.value).origin, ValueOrigin::Stream { stream: 0 })));
    }

    #[test]
    fn a_malformed_stream_is_a_syntax_error_at_the_token() {
        let src = "system S { participant P; participant Q; stream Q P: tick; }";
        let mut db = crate::source::SourceDb::new();
        let id = db.add("t.chor", src);
        let (_, d) = crate::syntax::parser::parse(id, src);
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].span.start as usize, src.find("P: tick").unwrap());
    }

    #[test]
    fn each_message_reads_its_own_snapshot_and_a_choice_one() {
        let (p, d) = lower_src(&format!(
            "{SYS} choreography G = P -> Q: [h > 1] a. ( P -> Q: [h > 5] b. end + P -> Q: [h <= 5 && k == 0] c. R -> Q: [k > 0] e. end );"
        ));
        assert!(d.is_empty(), "{d:?}");
        let mut ms = Vec::new();
        messages(&p.choreography.as_ref().unwrap().body, &mut ms);
        let ids = |i: usize| ms[i].observed.iter().map(|o| (o.name.clone(), o.value)).collect::<Vec<_>>();
        assert_eq!(ids(0).len(), 1);
        assert_ne!(ids(0)[0].1, ids(1)[0].1, "a later message reads a new value");
        assert_eq!(ids(1)[0], ids(2)[0], "the branches of one choice share the reading of `h`");
        assert_eq!(ids(2).len(), 2);
        assert_eq!(ids(3).len(), 1);
        assert_ne!(ids(3)[0].1, ids(2)[1].1, "R's reading is R's");
        assert!(
            matches!(p.value(ids(3)[0].1).origin, ValueOrigin::Observed { reader, stream: 0 } if p.role_name(reader) == "R")
        );
        // Each reading carries the stream's refinement over itself.
        let r = ms[0].observed[0].refinement.as_ref().unwrap();
        assert!(crate::hir::expr::mentions(r, &|v| matches!(v, crate::hir::Var::Value(id, _) if *id == ids(0)[0].1)));
    }

    #[test]
    fn a_reading_is_only_where_its_reader_decides() {
        // Not a receiver: E0305, at the read.
        let c = codes("( Q -> P: [k > 0] a. end + Q -> P: [k <= 0] b. end )");
        assert!(c.is_empty(), "the stream's sender reads its own state: {c:?}");
        let (_, d) = lower_src(
            "system S { participant P; participant Q; participant R; stream Q -> P: tick(h: int); }
            choreography G = R -> Q: [h > 0] a. P -> R: b. end;",
        );
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), [Code::GuardNotLocal]);
        // Outside a message: E0245.
        for chor in [
            "mu t(n: int = h). P -> Q: a. t(n)",
            "mu t(n: int = 0) decreases k. P -> Q: a. t(n)",
            "mu t(n: int = 0). P -> Q: a. t(k)",
        ] {
            assert_eq!(
                codes(chor).into_iter().map(|c| c.0).collect::<Vec<_>>(),
                [Code::ObservedOutsideMessage],
                "{chor}"
            );
        }
        // A reading does not outlive its message.
        assert_eq!(codes("P -> Q: [h > 0] a. mu t(n: int = h). P -> Q: b. end").len(), 1);
    }

    #[test]
    fn a_payload_field_shadows_a_reading_in_its_own_refinements() {
        let (p, d) = lower_src(&format!("{SYS} choreography G = P -> Q: a(h: int {{h == 3}}). R -> Q: b. end;"));
        assert!(d.is_empty(), "{d:?}");
        let mut ms = Vec::new();
        messages(&p.choreography.as_ref().unwrap().body, &mut ms);
        assert!(ms[0].observed.is_empty(), "`h` is the field");
    }

    #[test]
    fn a_streams_invariant_reads_its_own_fields_and_constants() {
        let (_, d) = lower_src(
            "const C: int = 3; system S { participant P; participant Q;
             stream Q -> P: tick(h: int {h <= C}, k: int {k <= h}); } choreography G = P -> Q: a. end;",
        );
        assert!(d.is_empty(), "{d:?}");
        let (_, d) = lower_src(
            "system S { participant P; participant Q; stream Q -> P: tick(h: int); stream Q -> P: tock(h: int); }
             choreography G = P -> Q: a. end;",
        );
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), [Code::Duplicate]);
        let (_, d) = lower_src(
            "system S { participant P; participant Q; stream Q -> Q, P, P: tick(h: int); }
             choreography G = P -> Q: a. end;",
        );
        assert_eq!(d.iter().map(|d| d.code).collect::<Vec<_>>(), [Code::SelfMessage, Code::Duplicate]);
    }

    #[test]
    fn a_step_a_stream_carries_is_refused() {
        let c = codes("Q -> P: tick(h: int, k: int). R -> Q: a. end");
        assert_eq!(c.into_iter().map(|c| c.0).collect::<Vec<_>>(), [Code::StepIsStreamed]);
        // The other direction is another message.
        assert!(codes("P -> Q: tick(h: int, k: int). R -> Q: a. end").is_empty());
    }
}
