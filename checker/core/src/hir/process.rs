//! Processes of the motion session calculus (Sec 3.1):
//! `P ::= q!l<e>.P | Σ p?l_i(x_i).P_i | Σ p?l_i(x_i).P_i + dt<a>.P | if e then P else Q | dt<a>.P | mu x.P | x`
//! plus `end`, and internal sums of outputs as written in Example 3.1.

use super::{Expr, Loc, PrimApp, RecParam, RoleId, ValueId};

#[derive(Clone, Debug, PartialEq)]
pub enum Process {
    Send {
        to: RoleId,
        label: String,
        args: Vec<Expr>,
        cont: Box<Process>,
        loc: Loc,
    },
    /// External choice on messages from `from`, with an optional default motion.
    Recv {
        from: RoleId,
        branches: Vec<RecvArm>,
        default: Option<(PrimApp, Box<Process>)>,
        loc: Loc,
    },
    /// Internal choice among outputs (`Cart!green.P + Cart!red.Q`).
    Choose {
        branches: Vec<Process>,
        loc: Loc,
    },
    If {
        cond: Expr,
        then: Box<Process>,
        els: Box<Process>,
        loc: Loc,
    },
    Motion {
        prim: PrimApp,
        cont: Box<Process>,
        loc: Loc,
    },
    Rec {
        var: String,
        params: Vec<RecParam>,
        body: Box<Process>,
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
pub struct RecvArm {
    pub label: String,
    pub binders: Vec<ValueId>,
    pub cont: Process,
    pub loc: Loc,
}

impl Process {
    pub fn loc(&self) -> Loc {
        match self {
            Process::Send { loc, .. }
            | Process::Recv { loc, .. }
            | Process::Choose { loc, .. }
            | Process::If { loc, .. }
            | Process::Motion { loc, .. }
            | Process::Rec { loc, .. }
            | Process::Var { loc, .. }
            | Process::End(loc) => *loc,
        }
    }
}
