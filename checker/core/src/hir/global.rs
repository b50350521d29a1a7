//! Global types (Def 4.1): `G ::= g.G | t | mu t.G` with prefixes
//! `g ::= dt<(p_i : a_i)> | p -> q : [P] l({v : S | P'}) | g.g | g + g | g * g`,
//! plus `end` and parameterised recursion for refined sessions.

use super::{Expr, Loc, PrimId, RoleId, Sort, ValueId};

#[derive(Clone, Debug, PartialEq)]
pub enum Global {
    Msg(Msg),
    Motion(Motion),
    Seq(Vec<Global>, Loc),
    /// Branches each start with a message from the same sender to the same receiver.
    Choice(Vec<Global>, Loc),
    /// The separating conjunction `*`.
    Par(Vec<Global>, Loc),
    Rec {
        var: String,
        params: Vec<RecParam>,
        /// The termination measure of `mu t(...) decreases E. G` (an `int` over the
        /// parameters, values bound before the loop and constants): at every jump `t(a)`,
        /// `E >= 0` and `E[a/params] < E` (E0416, E0417).
        decreases: Option<Expr>,
        body: Box<Global>,
        loc: Loc,
    },
    Var(RecVar),
    End(Loc),
    /// `after T ms by R`: the head of the timeout branch of the choice it starts (lowering
    /// admits it nowhere else, E0320). Nothing is sent and nothing is learnt: `R` takes
    /// the branch when no message of the other branches reached it within `T`.
    After(After),
}

/// The head of a timeout branch, `after T ms by R` (LANGUAGE.md, Timeouts).
#[derive(Clone, Debug, PartialEq)]
pub struct After {
    /// The bound in milliseconds, positive (E0247 otherwise).
    pub ms: i64,
    /// The bound as written (an integer constant expression).
    pub bound: Expr,
    /// The waiting participant: the receiver of the choice's other branches (E0322).
    pub by: RoleId,
    pub loc: Loc,
}

impl Global {
    /// The head of a timeout branch: `after` alone or first in a sequence.
    pub fn timeout_head(&self) -> Option<&After> {
        match self {
            Global::After(a) => Some(a),
            Global::Seq(items, _) => items.first().and_then(Global::timeout_head),
            _ => None,
        }
    }
}

impl Global {
    pub fn loc(&self) -> Loc {
        match self {
            Global::Msg(m) => m.loc,
            Global::Motion(m) => m.loc,
            Global::Seq(_, l) | Global::Choice(_, l) | Global::Par(_, l) | Global::End(l) => *l,
            Global::Rec { loc, .. } => *loc,
            Global::Var(v) => v.loc,
            Global::After(a) => a.loc,
        }
    }

    /// Collects `r`'s possible first primitives in `self` (one per path, deduplicated);
    /// returns whether every path has one, so that nothing after `self` can be first.
    pub fn first_primitives(&self, r: RoleId, out: &mut Vec<PrimApp>) -> bool {
        match self {
            Global::Motion(m) => match m.parts.iter().find(|(p, _)| *p == r) {
                Some((_, app)) => {
                    if !out.contains(app) {
                        out.push(app.clone());
                    }
                    true
                }
                None => false,
            },
            Global::Msg(_) | Global::Var(_) | Global::End(_) | Global::After(_) => false,
            Global::Seq(items, _) => items.iter().any(|i| i.first_primitives(r, out)),
            Global::Choice(bs, _) => {
                // Every branch is visited (no short circuit): each may contribute.
                let mut all = true;
                for b in bs {
                    all &= b.first_primitives(r, out);
                }
                all
            }
            Global::Par(sides, _) => sides.iter().any(|s| s.first_primitives(r, out)),
            Global::Rec { body, .. } => body.first_primitives(r, out),
        }
    }

    /// `pt{G}` as a new list.
    pub fn participant_list(&self) -> Vec<RoleId> {
        let mut out = Vec::new();
        self.participants(&mut out);
        out
    }

    /// The participants of a global type, `pt{G}` (Sec 4.1), in order of appearance.
    pub fn participants(&self, out: &mut Vec<RoleId>) {
        let add = |r: RoleId, out: &mut Vec<RoleId>| {
            if !out.contains(&r) {
                out.push(r)
            }
        };
        match self {
            Global::Msg(m) => {
                add(m.from, out);
                add(m.to, out);
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| add(*r, out)),
            Global::After(a) => add(a.by, out),
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
                gs.iter().for_each(|g| g.participants(out))
            }
            Global::Rec { body, .. } => body.participants(out),
            Global::Var(_) | Global::End(_) => {}
        }
    }
}

/// `from -> to : [guard] label(payload)`
#[derive(Clone, Debug, PartialEq)]
pub struct Msg {
    pub from: RoleId,
    pub to: RoleId,
    pub guard: Option<Expr>,
    pub label: String,
    pub payload: Vec<Field>,
    pub loc: Loc,
    /// Where the label is written (for duplicate-label diagnostics).
    pub label_loc: Loc,
    /// The snapshots of observed values the guard and refinements read (the sender's), in
    /// stream and field order; shared with the other first messages of a choice.
    pub observed: Vec<super::Observed>,
}

/// Whether two labels may be the same message on the wire, so that a receiver cannot tell
/// them apart: equal labels, or a MAVLink message with its key fixed (a command
/// `COMMAND_LONG[MAV_CMD_X]`, a name `PARAM_VALUE["MC_PITCH_P"]`) and the same message
/// without (`COMMAND_LONG`, whose `command` may be `MAV_CMD_X`). Two different keys of one
/// message are disjoint (the key field holds one value); a key is kept as the wire reads it
/// (up to its first NUL), so the same key is the same label text. Labels of a choice
/// (E0302), the receptions a merge joins (E0601) and a step beside a stream (E0246) must
/// not overlap. Without a dialect no label has a `[`.
pub fn labels_overlap(a: &str, b: &str) -> bool {
    let split = |l: &str| match l.split_once('[') {
        Some((m, _)) => (m.to_string(), true),
        None => (l.to_string(), false),
    };
    let ((ma, ca), (mb, cb)) = (split(a), split(b));
    a == b || (ma == mb && !(ca && cb))
}

/// A refined payload field `{v : S | P}`. Equality includes the value's id (its binding
/// site), as [`Var::Value`](super::Var) does; `project::equal` compares up to renaming.
#[derive(Clone, Debug)]
pub struct Field {
    pub value: ValueId,
    pub name: String,
    pub sort: Sort,
    pub refinement: Option<Expr>,
    /// Of a MAVLink message: which field of it this is, and what lowering added to the
    /// refinement. `None` for a field of a label that is not a MAVLink message.
    pub mav: Option<MavField>,
}

/// A payload field of a MAVLink message (LANGUAGE.md, MAVLink messages).
///
/// Lowering conjoins what the dialect says of the field (its wire range, and for a
/// command's `command` field the fixed command) to the user's refinement, as
/// `implicit && user`: `refinement` is `implicit` alone when `user` is false, `implicit &&
/// written` when both are true, and the written refinement alone when `implicit` is false.
/// The printer leaves the implicit part out, so what it prints lowers back to the same
/// field.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct MavField {
    /// The message's field (`param1` for a command parameter addressed by its label).
    pub field: String,
    /// As written: the field or the command parameter's label (`action`).
    pub written: String,
    pub implicit: bool,
    pub user: bool,
    /// The enum the field's values are entries of (`enum="MAV_BOOL"` of the field or of the
    /// command parameter it carries), when the dialect names one and the command does not
    /// fix the value: see [`EnumCheck`].
    pub entry: Option<EnumCheck>,
}

/// A payload field whose values are entries of an enum of the dialect (LANGUAGE.md,
/// "Enum-typed fields"). Without a user refinement, lowering conjoins the entry predicate
/// to the implicit part (the field's type is the enum); with one, the global walk asks the
/// refinement to imply it (`Rule::EnumEntry`, E0243). `lower::entry_predicate` builds the
/// predicate from the dialect.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct EnumCheck {
    /// The enum's name in the dialect (`MAV_BOOL`).
    pub enum_name: String,
    /// The field's wire type: a bitmask's bits are those of its width.
    pub wire: crate::dialect::Wire,
    /// The field's name where it is written (the obligation's span; `Loc`s compare equal).
    pub at: Loc,
}

/// `dt<(p_i : a_i)>`
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub parts: Vec<(RoleId, PrimApp)>,
    pub loc: Loc,
}

/// A primitive applied to arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimApp {
    pub prim: PrimId,
    pub args: Vec<Expr>,
    pub loc: Loc,
}

/// A parameter of a parameterised recursion (DATUM's `mu T(curr : Z {P}) <curr = 0>`).
/// Equality includes the value's id.
#[derive(Clone, Debug)]
pub struct RecParam {
    pub value: ValueId,
    pub name: String,
    pub sort: Sort,
    pub refinement: Option<Expr>,
    pub init: Expr,
}

/// An occurrence of a recursion variable with its arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct RecVar {
    pub var: String,
    pub args: Vec<Expr>,
    pub loc: Loc,
}

impl PartialEq for Field {
    fn eq(&self, o: &Field) -> bool {
        self.value == o.value
            && self.name == o.name
            && self.sort == o.sort
            && self.refinement == o.refinement
            && self.mav == o.mav
    }
}

impl PartialEq for RecParam {
    fn eq(&self, o: &RecParam) -> bool {
        self.value == o.value
            && self.name == o.name
            && self.sort == o.sort
            && self.refinement == o.refinement
            && self.init == o.init
    }
}
