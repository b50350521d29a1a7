//! Equality of local types up to locations, the renaming of value binders
//! (alpha-equivalence) and the order of choice branches: what Def 4.7 means by "equal"
//! projections, and what E0602 compares a declared `local R = T` with (ARCHITECTURE.md,
//! "Values are binding sites").

use crate::hir::node::NodeRef;
use crate::hir::*;
use std::collections::HashSet;
use std::sync::Arc;

/// Whether two local types are equal up to locations, the renaming of value binders
/// (alpha-equivalence) and the order of choice branches.
pub fn equal(a: &LocalArc, b: &LocalArc) -> bool {
    first_difference(a, b).is_none()
}

/// Whether `a` and `b` are equal up to the renaming of their value binders, whatever
/// the binders are called (alpha-equivalence proper). `mochi project` prints a binder
/// that hides a value still read under a fresh name (`v_2`): what it prints reads back
/// to a type `alpha_equal` to the projection, though not [`equal`] to it.
pub fn alpha_equal(a: &LocalArc, b: &LocalArc) -> bool {
    Differ { names: false, ..Differ::new() }.diff(a, b).is_none()
}

/// The locations of the first pair of nodes where `a` and `b` differ, if any.
pub fn first_difference(a: &LocalArc, b: &LocalArc) -> Option<(Loc, Loc)> {
    Differ::new().diff(a, b)
}

/// Structural comparison of two local types up to the renaming of their value binders
/// (alpha-equivalence). A value is its binding site ([`ValueId`]); two types describe
/// the same protocol when they are equal once each binder of `b` (a payload field, a
/// recursion parameter) is renamed to the binder of `a` at the same position. The
/// renaming is scoped: it holds in the binder's message (its refinements may read the
/// fields) and in the continuation. Values free in both types (bound before them) must
/// be the same binding site; binders must also have the same names, so that the types
/// print the same. Pairs of nodes already found equal (or being compared) under the
/// same renaming are remembered, so shared tails are compared once.
/// A pair of nodes and the non-identity part of the renaming they were compared under.
type Compared<'t> = (NodeRef<&'t Local>, NodeRef<&'t Local>, Vec<(ValueId, ValueId)>);

pub(super) struct Differ<'t> {
    same: HashSet<Compared<'t>>,
    /// The binders in scope, outermost first: (binder of `a`, binder of `b`).
    ren: Vec<(ValueId, ValueId)>,
    /// Whether binders must also have the same names ([`equal`]) or not ([`alpha_equal`]).
    names: bool,
}

impl<'t> Differ<'t> {
    pub(super) fn new() -> Differ<'t> {
        Differ { same: HashSet::new(), ren: Vec::new(), names: true }
    }

    /// Whether the renaming in scope is the identity (then equal ids mean equal values
    /// and identical nodes are equal).
    pub(super) fn renamed(&self) -> Vec<(ValueId, ValueId)> {
        self.ren.iter().filter(|(x, y)| x != y).copied().collect()
    }

    /// `x` (in `a`) and `y` (in `b`) are the same value: bound by corresponding binders,
    /// or both free and the same binding site.
    pub(super) fn value_eq(&self, x: ValueId, y: ValueId) -> bool {
        let by_b = self.ren.iter().rposition(|p| p.1 == y);
        let by_a = self.ren.iter().rposition(|p| p.0 == x);
        match (by_b, by_a) {
            (Some(i), Some(j)) => self.ren[i].0 == x && self.ren[j].1 == y,
            (None, None) => x == y,
            _ => false,
        }
    }

    pub(super) fn expr(&self, a: &Expr, b: &Expr) -> bool {
        if self.ren.iter().all(|(x, y)| x == y) {
            return a == b;
        }
        self.expr_renamed(a, b)
    }

    pub(super) fn expr_renamed(&self, a: &Expr, b: &Expr) -> bool {
        if a.sort != b.sort {
            return false;
        }
        crate::stack::deep(|| match (&a.kind, &b.kind) {
            (ExprKind::Var(Var::Value(x, n)), ExprKind::Var(Var::Value(y, m))) => {
                (n == m || !self.names) && self.value_eq(*x, *y)
            }
            (ExprKind::Var(Var::Value(..)), _) | (_, ExprKind::Var(Var::Value(..))) => false,
            (ExprKind::Unary(o, x), ExprKind::Unary(p, y)) => o == p && self.expr_renamed(x, y),
            (ExprKind::Component(x, i), ExprKind::Component(y, j)) => i == j && self.expr_renamed(x, y),
            (ExprKind::Binary(o, x1, x2), ExprKind::Binary(p, y1, y2)) => {
                o == p && self.expr_renamed(x1, y1) && self.expr_renamed(x2, y2)
            }
            (ExprKind::If(x1, x2, x3), ExprKind::If(y1, y2, y3)) => {
                self.expr_renamed(x1, y1) && self.expr_renamed(x2, y2) && self.expr_renamed(x3, y3)
            }
            (ExprKind::Call(f, xs), ExprKind::Call(g, ys)) => f == g && self.exprs(xs, ys),
            (ExprKind::Tuple(xs), ExprKind::Tuple(ys)) => self.exprs(xs, ys),
            (
                ExprKind::Unary(..)
                | ExprKind::Component(..)
                | ExprKind::Binary(..)
                | ExprKind::If(..)
                | ExprKind::Call(..)
                | ExprKind::Tuple(..),
                _,
            ) => false,
            // Literals and other variables: no value inside.
            _ => a.kind == b.kind,
        })
    }

    pub(super) fn exprs(&self, a: &[Expr], b: &[Expr]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| self.expr_renamed(x, y))
    }

    pub(super) fn opt_expr(&self, a: &Option<Expr>, b: &Option<Expr>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(x), Some(y)) => self.expr(x, y),
            _ => false,
        }
    }

    pub(super) fn app(&self, a: &PrimApp, b: &PrimApp) -> bool {
        a.prim == b.prim && a.args.len() == b.args.len() && a.args.iter().zip(&b.args).all(|(x, y)| self.expr(x, y))
    }

    /// The motion merge compares as a set.
    pub(super) fn prims(&self, a: &[PrimApp], b: &[PrimApp]) -> bool {
        a.len() == b.len()
            && a.iter().all(|x| b.iter().any(|y| self.app(x, y)))
            && b.iter().all(|y| a.iter().any(|x| self.app(x, y)))
    }

    /// Brings the fields' binders into scope, pairwise, and compares the fields (their
    /// refinements may read the message's fields). The caller truncates `ren`.
    pub(super) fn bind_fields(&mut self, a: &[Field], b: &[Field]) -> bool {
        if a.len() != b.len() {
            return false;
        }
        self.ren.extend(a.iter().zip(b).map(|(x, y)| (x.value, y.value)));
        a.iter().zip(b).all(|(x, y)| {
            (x.name == y.name || !self.names)
                && x.sort == y.sort
                && same_mav_field(x, y)
                && self.opt_expr(&x.refinement, &y.refinement)
        })
    }

    /// The snapshots of observed values two sends read: the same stream fields, in order,
    /// renamed like binders (each is a fresh value at its send).
    pub(super) fn bind_observed(&mut self, a: &[Observed], b: &[Observed]) -> bool {
        if a.len() != b.len() || a.iter().zip(b).any(|(x, y)| (x.stream, x.field) != (y.stream, y.field)) {
            return false;
        }
        self.ren.extend(a.iter().zip(b).map(|(x, y)| (x.value, y.value)));
        a.iter().zip(b).all(|(x, y)| x.sort == y.sort && self.opt_expr(&x.refinement, &y.refinement))
    }

    /// As [`Differ::bind_fields`] for recursion parameters; their initial values are
    /// read outside the binders.
    pub(super) fn bind_params(&mut self, a: &[RecParam], b: &[RecParam]) -> bool {
        if a.len() != b.len() || !a.iter().zip(b).all(|(x, y)| self.expr(&x.init, &y.init)) {
            return false;
        }
        self.ren.extend(a.iter().zip(b).map(|(x, y)| (x.value, y.value)));
        a.iter().zip(b).all(|(x, y)| {
            (x.name == y.name || !self.names) && x.sort == y.sort && self.opt_expr(&x.refinement, &y.refinement)
        })
    }

    pub(super) fn diff(&mut self, a: &'t LocalArc, b: &'t LocalArc) -> Option<(Loc, Loc)> {
        let renamed = self.renamed();
        if renamed.is_empty() && Arc::ptr_eq(a, b) {
            return None;
        }
        if !self.same.insert((NodeRef::new(&**a), NodeRef::new(&**b), renamed)) {
            return None;
        }
        crate::stack::deep(|| self.diff_inner(a, b))
    }

    pub(super) fn diff_inner(&mut self, a: &'t LocalArc, b: &'t LocalArc) -> Option<(Loc, Loc)> {
        let here = Some((a.loc(), b.loc()));
        let mark = self.ren.len();
        // The timeout alternatives: the same bound and waiting role, equal continuations.
        fn timeout_of(l: &Local) -> Option<&Timeout> {
            match l {
                Local::Send { timeout, .. } | Local::Recv { timeout, .. } => timeout.as_ref(),
                _ => None,
            }
        }
        match (timeout_of(a), timeout_of(b)) {
            (None, None) => {}
            (Some(x), Some(y)) if x.after.ms == y.after.ms && x.after.by == y.after.by => {
                if let Some(d) = self.diff(&x.cont, &y.cont) {
                    return Some(d);
                }
            }
            (x, y) => {
                let l = x.map(|t| t.after.loc).unwrap_or(a.loc());
                let r = y.map(|t| t.after.loc).unwrap_or(b.loc());
                return Some((l, r));
            }
        }
        match (&**a, &**b) {
            (Local::Motion { prims: p1, cont: c1, .. }, Local::Motion { prims: p2, cont: c2, .. }) => {
                if !self.prims(p1, p2) {
                    return here;
                }
                self.diff(c1, c2)
            }
            (Local::Send { branches: b1, .. }, Local::Send { branches: b2, .. }) => {
                if b1.len() != b2.len() {
                    return here;
                }
                for x in b1 {
                    let Some(y) = b2.iter().find(|y| y.to == x.to && y.label == x.label) else {
                        return Some((x.loc, b.loc()));
                    };
                    // The guard reads the values before the message.
                    if !self.bind_observed(&x.observed, &y.observed)
                        || !self.opt_expr(&x.guard, &y.guard)
                        || !self.bind_fields(&x.payload, &y.payload)
                    {
                        self.ren.truncate(mark);
                        return Some((x.loc, y.loc));
                    }
                    let d = self.diff(&x.cont, &y.cont);
                    self.ren.truncate(mark);
                    if d.is_some() {
                        return d;
                    }
                }
                None
            }
            (Local::Recv { branches: b1, default: d1, .. }, Local::Recv { branches: b2, default: d2, .. }) => {
                if b1.len() != b2.len() {
                    return here;
                }
                for x in b1 {
                    let Some(y) = b2.iter().find(|y| y.from == x.from && y.label == x.label) else {
                        return Some((x.loc, b.loc()));
                    };
                    if !self.bind_fields(&x.payload, &y.payload) {
                        self.ren.truncate(mark);
                        return Some((x.loc, y.loc));
                    }
                    let d = self.diff(&x.cont, &y.cont);
                    self.ren.truncate(mark);
                    if d.is_some() {
                        return d;
                    }
                }
                match (d1, d2) {
                    (None, None) => None,
                    (Some((p1, c1)), Some((p2, c2))) => {
                        if !self.prims(p1, p2) {
                            let l1 = p1.first().map(|p| p.loc).unwrap_or(a.loc());
                            let l2 = p2.first().map(|p| p.loc).unwrap_or(b.loc());
                            return Some((l1, l2));
                        }
                        self.diff(c1, c2)
                    }
                    _ => here,
                }
            }
            (Local::Rec { var: v1, params: p1, body: c1, .. }, Local::Rec { var: v2, params: p2, body: c2, .. }) => {
                if v1 != v2 || !self.bind_params(p1, p2) {
                    self.ren.truncate(mark);
                    return here;
                }
                let d = self.diff(c1, c2);
                self.ren.truncate(mark);
                d
            }
            (Local::Var { var: v1, args: a1, .. }, Local::Var { var: v2, args: a2, .. }) => {
                if v1 != v2 || a1.len() != a2.len() || !a1.iter().zip(a2).all(|(x, y)| self.expr(x, y)) {
                    return here;
                }
                None
            }
            (Local::End(_), Local::End(_)) => None,
            _ => here,
        }
    }
}

/// Two payload fields at one position are the same field of the MAVLink message (or both
/// are fields of a free label): binders are renamed, but `seq` is not `mission_type`.
pub(crate) fn same_mav_field(x: &Field, y: &Field) -> bool {
    x.mav.as_ref().map(|m| (&m.field, m.implicit, m.user)) == y.mav.as_ref().map(|m| (&m.field, m.implicit, m.user))
}
