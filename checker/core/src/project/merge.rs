//! The merge `T1 ⊓ T2` of Def 4.7, used by Def 4.8 (3) for a role that takes no part in
//! the choosing message (seeds README, known error 3: `∏` there is this merge). External
//! choices from one sender merge into their union, shared labels merging their
//! continuations (read in terms of one branch's binders); default motions merge into
//! the meet of their primitives (Def 3.4 (6): same interruptibility); anything else
//! merges only when equal (`equal.rs`). Failures are E0601.

use super::equal::{equal, first_difference, Differ};
use super::Projector;
use crate::diag::{Code, Diagnostic};
use crate::hir::node::NodeRef;
use crate::hir::print::{self, describe, motion_text, print_bounded, NOTE_NODES};
use crate::hir::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Why two branch projections could not be merged: the two nodes that differ.
pub(super) struct Clash {
    left: Loc,
    left_text: String,
    right: Loc,
    right_text: String,
    why: Option<String>,
}

impl Projector<'_> {
    /// E0601. `left` and `right` are the labels of the branches with their projections.
    pub(super) fn unmergeable(
        &self,
        choice: &Msg,
        left: (&str, &LocalArc),
        right: (&str, &LocalArc),
        c: Clash,
    ) -> Diagnostic {
        let r = self.name();
        let (p, q) = (self.prog.role_name(choice.from), self.prog.role_name(choice.to));
        let ((left, lt), (right, rt)) = (left, right);
        let mut d = Diagnostic::error(
            Code::Unmergeable,
            choice.loc.0,
            format!("cannot merge the projections onto `{r}` of two branches"),
        )
        .with_label(c.left.0, format!("after {left}, `{r}` does `{}`", c.left_text))
        .with_label(c.right.0, format!("after {right}, `{r}` does `{}`", c.right_text));
        if let Some(why) = c.why {
            d = d.with_note(why);
        }
        d.with_note(format!(
            "`{r}` takes no part in `{p} -> {q}`, so it cannot tell the branches apart (Def 4.8 (3), merge of Def 4.7); its projections are\nafter {left}: {}\nafter {right}: {}",
            print_bounded(self.prog, lt, NOTE_NODES),
            print_bounded(self.prog, rt, NOTE_NODES)
        ))
        .with_help(format!(
            "inform `{r}` of the choice: start each branch's part for `{r}` with a message to it (e.g. `{p} -> {r} : ...` or `{q} -> {r} : ...` with distinct labels)"
        ))
    }

    /// The merge `T1 ⊓ T2` of Def 4.7.
    pub(super) fn merge(&self, a: &LocalArc, b: &LocalArc) -> Result<LocalArc, Clash> {
        crate::stack::deep(|| self.merge_inner(a, b))
    }

    pub(super) fn merge_inner(&self, a: &LocalArc, b: &LocalArc) -> Result<LocalArc, Clash> {
        if equal(a, b) {
            return Ok(a.clone());
        }
        match (&**a, &**b) {
            (
                Local::Recv { branches: b1, default: d1, timeout: t1, loc },
                Local::Recv { branches: b2, default: d2, timeout: t2, .. },
            ) => {
                // A timeout merges only with the same timeout: a role that gives up after
                // one branch and waits on after the other could not tell which it is in.
                let timeout = match (t1, t2) {
                    (None, None) => None,
                    (Some(x), Some(y))
                        if x.after.ms == y.after.ms && x.after.by == y.after.by && equal(&x.cont, &y.cont) =>
                    {
                        Some(x.clone())
                    }
                    _ => {
                        let why = "a timeout merges only with the same timeout and continuation (Def 4.7 extended to timeouts)".to_string();
                        return Err(self.clash(a, b, Some(why)));
                    }
                };
                let branches = self.union(b1, b2)?;
                let default = match (d1, d2) {
                    (None, None) => None,
                    (Some(d), None) | (None, Some(d)) => Some(d.clone()),
                    (Some((p1, c1)), Some((p2, c2))) => Some(self.merge_default(p1, c1, p2, c2)?),
                };
                Ok(Arc::new(Local::Recv { branches, default, timeout, loc: *loc }))
            }
            (Local::Motion { prims, cont, .. }, Local::Recv { branches, default, timeout: None, loc }) => {
                let default = match default {
                    None => (prims.clone(), cont.clone()),
                    Some((p2, c2)) => self.merge_default(prims, cont, p2, c2)?,
                };
                Ok(Arc::new(Local::Recv {
                    branches: branches.clone(),
                    default: Some(default),
                    timeout: None,
                    loc: *loc,
                }))
            }
            (Local::Recv { branches, default, timeout: None, loc }, Local::Motion { prims, cont, .. }) => {
                let default = match default {
                    None => (prims.clone(), cont.clone()),
                    Some((p1, c1)) => self.merge_default(p1, c1, prims, cont)?,
                };
                Ok(Arc::new(Local::Recv {
                    branches: branches.clone(),
                    default: Some(default),
                    timeout: None,
                    loc: *loc,
                }))
            }
            _ => Err(self.clash(a, b, None)),
        }
    }

    pub(super) fn clash(&self, a: &Local, b: &Local, why: Option<String>) -> Clash {
        Clash {
            left: a.loc(),
            left_text: describe(self.prog, a),
            right: b.loc(),
            right_text: describe(self.prog, b),
            why,
        }
    }

    /// `dt<a ⊓ a'>.T'` from two default motions with the same continuation `T'`.
    pub(super) fn merge_default(
        &self,
        p1: &[PrimApp],
        c1: &LocalArc,
        p2: &[PrimApp],
        c2: &LocalArc,
    ) -> Result<(Vec<PrimApp>, LocalArc), Clash> {
        if !equal(c1, c2) {
            let why = "the default motions of the two branches continue differently; Def 4.7 merges them only when the continuations are equal".to_string();
            let (l, r) = first_difference(c1, c2).unwrap_or((c1.loc(), c2.loc()));
            return Err(Clash {
                left: l,
                left_text: format!("{}. {}", motion_text(self.prog, p1), describe(self.prog, c1)),
                right: r,
                right_text: format!("{}. {}", motion_text(self.prog, p2), describe(self.prog, c2)),
                why: Some(why),
            });
        }
        Ok((self.meet(p1, p2)?, c1.clone()))
    }

    /// The motion merge `a ⊓ a'`: the list of both primitives, which the refinement
    /// obligations read as their meet. Def 3.4 (6): a primitive refining both must
    /// have the interruptibility of each, so they must agree.
    pub(super) fn meet(&self, p1: &[PrimApp], p2: &[PrimApp]) -> Result<Vec<PrimApp>, Clash> {
        let mut out: Vec<PrimApp> = p1.to_vec();
        for a in p2 {
            if !out.contains(a) {
                out.push(a.clone());
            }
        }
        let first = out.first().map(|a| self.prog.prim(a.prim));
        if let Some(bad) = out.iter().find(|a| {
            let p = self.prog.prim(a.prim);
            first.is_some_and(|f| f.interruptible != p.interruptible || f.kind != p.kind)
        }) {
            let anchor = p1.first().map(|a| a.loc).unwrap_or(bad.loc);
            return Err(Clash {
                left: anchor,
                left_text: motion_text(self.prog, p1),
                right: bad.loc,
                right_text: motion_text(self.prog, p2),
                why: Some(
                    "Def 3.4 (6): a motion refining both primitives must have the interruptibility of each, and one is interruptible while the other is not"
                        .to_string(),
                ),
            });
        }
        Ok(out)
    }

    /// The union of two external choices from the same sender; shared labels merge
    /// their continuations and must carry equal payloads.
    pub(super) fn union(&self, b1: &[RecvBranch], b2: &[RecvBranch]) -> Result<Vec<RecvBranch>, Clash> {
        let mut out: Vec<RecvBranch> = b1.to_vec();
        let sender = b1.first().map(|b| b.from);
        for b in b2 {
            if let Some(s) = sender.filter(|s| *s != b.from) {
                let first = b1.first().map(|x| x.loc).unwrap_or(b.loc);
                return Err(Clash {
                    left: first,
                    left_text: format!("{}?...", self.prog.role_name(s)),
                    right: b.loc,
                    right_text: format!("{}?{}", self.prog.role_name(b.from), b.label),
                    why: Some("Def 4.7 merges receptions only from the same sender".to_string()),
                });
            }
            // A MAVLink command with its command fixed and the same message without: one
            // message on the wire, so the receiver could not tell which branch follows.
            if let Some(x) = out.iter().find(|x| x.label != b.label && labels_overlap(&x.label, &b.label)) {
                return Err(Clash {
                    left: x.loc,
                    left_text: recv_text(self.prog, x),
                    right: b.loc,
                    right_text: recv_text(self.prog, b),
                    why: Some(format!(
                        "`{}` and `{}` are one MAVLink message: the one without a fixed command may carry the other's",
                        x.label, b.label
                    )),
                });
            }
            match out.iter_mut().find(|x| x.label == b.label) {
                None => out.push(b.clone()),
                Some(x) => {
                    if payloads_differ(&x.payload, &b.payload) {
                        let same_text = fields_text(self.prog, &x.payload) == fields_text(self.prog, &b.payload);
                        let why = if same_text {
                            format!(
                                "the two branches receive `{}` with payloads that read alike, but a name in them stands for different values (a value is where it is bound, not its name)",
                                b.label
                            )
                        } else {
                            format!("the two branches receive `{}` with different payloads", b.label)
                        };
                        return Err(Clash {
                            left: x.loc,
                            left_text: recv_text(self.prog, x),
                            right: b.loc,
                            right_text: recv_text(self.prog, b),
                            why: Some(why),
                        });
                    }
                    // `b`'s continuation speaks of `b`'s binders of this message: read it
                    // in terms of `x`'s (the same message, so the same values).
                    let map: HashMap<ValueId, (ValueId, String)> = b
                        .payload
                        .iter()
                        .zip(&x.payload)
                        .filter(|(y, x)| y.value != x.value)
                        .map(|(y, x)| (y.value, (x.value, x.name.clone())))
                        .collect();
                    let cont = rename_local(&b.cont, &map, &mut HashMap::new());
                    x.cont = self.merge(&x.cont, &cont)?;
                }
            }
        }
        Ok(out)
    }
}

fn recv_text(prog: &Program, b: &RecvBranch) -> String {
    let fields: Vec<String> = b.payload.iter().map(|f| format!("{}: {}", f.name, f.sort)).collect();
    if fields.is_empty() {
        format!("{}?{}", prog.role_name(b.from), b.label)
    } else {
        format!("{}?{}({})", prog.role_name(b.from), b.label, fields.join(", "))
    }
}

/// The payload as printed (to tell "different" from "reads alike, means otherwise").
fn fields_text(prog: &Program, fs: &[Field]) -> Vec<String> {
    fs.iter()
        .map(|f| {
            let r = f.refinement.as_ref().map(|r| print::expr(prog, None, r)).unwrap_or_default();
            format!("{}: {} {{{r}}}", f.name, f.sort)
        })
        .collect()
}

/// Whether two payloads of one message differ, up to the renaming of their binders.
fn payloads_differ(a: &[Field], b: &[Field]) -> bool {
    !Differ::new().bind_fields(a, b)
}

/// `t` with the value variables `map` renamed (occurrences only; binders inside `t` keep
/// their identity). Used by the merge to read one branch's continuation in terms of
/// the other branch's binders of the same message. Shared tails stay shared.
fn rename_local<'t>(
    t: &'t LocalArc,
    map: &HashMap<ValueId, (ValueId, String)>,
    memo: &mut HashMap<NodeRef<&'t Local>, LocalArc>,
) -> LocalArc {
    if map.is_empty() {
        return t.clone();
    }
    if let Some(r) = memo.get(&NodeRef::new(&**t)) {
        return r.clone();
    }
    let e = |x: &Expr| {
        crate::hir::expr::map_vars(x, &mut |v, sort| match v {
            Var::Value(id, _) => map.get(id).map(|(to, name)| Expr {
                kind: ExprKind::Var(Var::Value(*to, name.clone())),
                sort: sort.clone(),
                loc: Loc::default(),
            }),
            _ => None,
        })
    };
    let app = |a: &PrimApp| PrimApp { prim: a.prim, args: a.args.iter().map(e).collect(), loc: a.loc };
    // A binder of a renamed value (were its site met again inside `t`) is renamed too,
    // so that binders and occurrences stay consistent.
    let to = |v: ValueId| map.get(&v).map(|(to, _)| *to).unwrap_or(v);
    let fields = |fs: &[Field]| -> Vec<Field> {
        fs.iter().map(|f| Field { value: to(f.value), refinement: f.refinement.as_ref().map(e), ..f.clone() }).collect()
    };
    let out = crate::stack::deep(|| match &**t {
        Local::Motion { prims, cont, loc } => {
            Local::Motion { prims: prims.iter().map(app).collect(), cont: rename_local(cont, map, memo), loc: *loc }
        }
        Local::Send { branches, timeout, loc } => Local::Send {
            branches: branches
                .iter()
                .map(|b| SendBranch {
                    observed: b
                        .observed
                        .iter()
                        .map(|o| Observed { value: to(o.value), refinement: o.refinement.as_ref().map(e), ..o.clone() })
                        .collect(),
                    guard: b.guard.as_ref().map(e),
                    payload: fields(&b.payload),
                    cont: rename_local(&b.cont, map, memo),
                    ..b.clone()
                })
                .collect(),
            timeout: timeout
                .as_ref()
                .map(|t| Timeout { after: t.after.clone(), cont: rename_local(&t.cont, map, memo) }),
            loc: *loc,
        },
        Local::Recv { branches, default, timeout, loc } => Local::Recv {
            branches: branches
                .iter()
                .map(|b| RecvBranch {
                    payload: fields(&b.payload),
                    cont: rename_local(&b.cont, map, memo),
                    ..b.clone()
                })
                .collect(),
            default: default.as_ref().map(|(ps, c)| (ps.iter().map(app).collect(), rename_local(c, map, memo))),
            timeout: timeout
                .as_ref()
                .map(|t| Timeout { after: t.after.clone(), cont: rename_local(&t.cont, map, memo) }),
            loc: *loc,
        },
        Local::Rec { var, params, body, loc } => Local::Rec {
            var: var.clone(),
            params: params
                .iter()
                .map(|p| RecParam {
                    value: to(p.value),
                    refinement: p.refinement.as_ref().map(e),
                    init: e(&p.init),
                    ..p.clone()
                })
                .collect(),
            body: rename_local(body, map, memo),
            loc: *loc,
        },
        Local::Var { var, args, loc } => Local::Var { var: var.clone(), args: args.iter().map(e).collect(), loc: *loc },
        Local::End(loc) => Local::End(*loc),
    });
    let out = Arc::new(out);
    memo.insert(NodeRef::new(&**t), out.clone());
    out
}
