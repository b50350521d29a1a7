//! Local types (Def 4.6):
//! `T ::= dt<a>.T | ⊕{[P_i] q!l_i(P'_i).T_i} | &{p?l_i(P_i).T_i} | &{p?l_i(P_i).T_i} & dt<a>.T | mu t.T | t`
//! plus `end`. Continuations are shared through [`Arc`], so the tail that projection pushes
//! into every branch of a choice is stored once.

use super::{Expr, Field, Loc, PrimApp, RecParam, RoleId};
use std::sync::Arc;

pub type LocalArc = Arc<Local>;

#[derive(Clone, Debug, PartialEq)]
pub enum Local {
    /// `dt<a>.T`; more than one primitive is the merge `a ⊓ a'` of Def 4.7.
    Motion {
        prims: Vec<PrimApp>,
        cont: LocalArc,
        loc: Loc,
    },
    Send {
        branches: Vec<SendBranch>,
        /// `after T by R. T_p`: the waiting peer `R` may give up instead of receiving; this
        /// role learns it from `T_p`'s first reception (or `T_p` is `end`).
        timeout: Option<Timeout>,
        loc: Loc,
    },
    Recv {
        branches: Vec<RecvBranch>,
        default: Option<(Vec<PrimApp>, LocalArc)>,
        /// `after T. T_R`: this role gives up waiting after `T` and continues as `T_R`.
        timeout: Option<Timeout>,
        loc: Loc,
    },
    Rec {
        var: String,
        params: Vec<RecParam>,
        body: LocalArc,
        loc: Loc,
    },
    Var {
        var: String,
        args: Vec<Expr>,
        loc: Loc,
    },
    End(Loc),
}

#[derive(Clone, Debug, PartialEq)]
pub struct SendBranch {
    /// The snapshots of observed values the guard and refinements read ([`super::Observed`]).
    pub observed: Vec<super::Observed>,
    pub guard: Option<Expr>,
    pub to: RoleId,
    pub label: String,
    pub payload: Vec<Field>,
    pub cont: LocalArc,
    pub loc: Loc,
}

/// The timeout alternative of a choice in a local type: the choice's `after T ms by R`
/// and the role's continuation in the timeout branch.
#[derive(Clone, Debug, PartialEq)]
pub struct Timeout {
    pub after: super::global::After,
    pub cont: LocalArc,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RecvBranch {
    pub from: RoleId,
    pub label: String,
    pub payload: Vec<Field>,
    pub cont: LocalArc,
    pub loc: Loc,
}

impl Local {
    pub fn loc(&self) -> Loc {
        match self {
            Local::Motion { loc, .. }
            | Local::Send { loc, .. }
            | Local::Recv { loc, .. }
            | Local::Rec { loc, .. }
            | Local::Var { loc, .. }
            | Local::End(loc) => *loc,
        }
    }

    /// Structural equality with a pointer shortcut for shared tails.
    pub fn same(a: &LocalArc, b: &LocalArc) -> bool {
        Arc::ptr_eq(a, b) || a == b
    }
}
