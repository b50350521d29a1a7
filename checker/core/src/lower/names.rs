//! Name resolution inside expressions (LANGUAGE.md, Name resolution and What a
//! participant may read): an unqualified name is, innermost first, a value variable, a
//! primitive parameter, a footprint's point coordinate, `clock`, the robot's own state
//! or input variable, or a constant; `Cart.x` reads a participant's variable and
//! `old(x)` a state variable at the start of the motion. Which of these a contract part
//! may read is Def 3.4's (E0211).

use super::*;

impl Lowerer {
    /// Whether `name` denotes something other than a participant in this environment.
    pub(super) fn is_local_name(&self, name: &str, env: &Env) -> bool {
        env.values.iter().any(|v| self.prog.value(*v).name == name)
            || env.params.iter().any(|(n, _)| n == name)
            || env.point.is_some_and(|p| p.iter().any(|n| n == name))
    }

    /// Whether an unqualified name resolves to anything in `env`.
    pub(super) fn resolves(&self, name: &str, env: &Env) -> bool {
        if self.is_local_name(name, env) || self.consts.contains_key(name) || (name == "clock" && env.part.is_some()) {
            return true;
        }
        if self.prog.dialect.is_some_and(|d| d.entry(name).is_some()) {
            return true;
        }
        self.own_kind(env).is_some_and(|k| self.prog.kind(k).slot(name).is_some())
    }

    pub(super) fn own_kind(&self, env: &Env) -> Option<KindId> {
        match env.who {
            Who::Kind(k) => Some(k),
            Who::Role(r) => Some(self.prog.role(r).kind),
            Who::Nobody => None,
        }
    }

    pub(super) fn var(&mut self, name: &str, span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let mk = |v: Var, sort: Sort| Expr { kind: ExprKind::Var(v), sort, loc };
        if let Some(v) = env.values.iter().rev().find(|v| self.prog.value(**v).name == name) {
            let vv = self.prog.value(*v);
            return mk(Var::Value(*v, vv.name.clone()), vv.sort.clone());
        }
        if let Some(i) = env.params.iter().position(|(n, _)| n == name) {
            return mk(Var::Param(i), env.params[i].1.clone());
        }
        if let Some(i) = env.point.and_then(|p| p.iter().position(|n| n == name)) {
            return mk(Var::Point(i), Sort::Real);
        }
        if name == "clock" && env.part.is_some() {
            if !env.clock {
                self.not_allowed(span, "`clock`", env);
            }
            return mk(Var::Clock, Sort::Real);
        }
        if let Some(kind) = self.own_kind(env) {
            if let Some((slot, sort)) = self.prog.kind(kind).slot(name) {
                let sort = sort.clone();
                let allowed = match slot {
                    Slot::State(_) => env.state,
                    Slot::Input(_) => env.input,
                };
                if !allowed {
                    let what = match slot {
                        Slot::State(_) => format!("state variable `{name}`"),
                        Slot::Input(_) => format!("input variable `{name}`"),
                    };
                    self.not_allowed(span, &what, env);
                }
                return match env.who {
                    Who::Role(r) => mk(Var::Role(r, slot), sort),
                    _ => mk(Var::Own(slot), sort),
                };
            }
        }
        if let Some(&c) = self.consts.get(name) {
            return mk(Var::Const(c), self.prog.consts[c.idx()].sort.clone());
        }
        // An enum entry of the dialect: an `int` constant (after the user's, which cannot
        // share its name: E0206).
        if let Some(c) = self.entry_const(name) {
            return mk(Var::Const(c), Sort::Int);
        }
        if self.observed_elsewhere(name, span).is_some() {
            return Expr::error(loc);
        }
        let mut help = "declare it as a `const`, a parameter, a robot variable, or bind it in a message".to_string();
        if let Some(d) = self.prog.dialect {
            let close =
                crate::dialect::suggest(name, d.enums.iter().flat_map(|e| e.entries.iter().map(|x| x.name.as_str())));
            if !close.is_empty() {
                let names: Vec<String> = close.iter().map(|n| format!("`{n}`")).collect();
                help = format!("did you mean the enum entry {}?", names.join(" or "));
            }
        }
        if self.prog.role_by_name(name).is_some() {
            help = format!("`{name}` is a participant; write `{name}.var` for one of its variables");
        } else if let Who::Role(r) = env.who {
            let owners: Vec<_> = self
                .prog
                .role_ids()
                .filter(|q| {
                    self.prog.kind_of(*q).state.iter().chain(&self.prog.kind_of(*q).inputs).any(|(n, _)| n == name)
                })
                .map(|q| format!("`{}.{name}`", self.prog.role_name(q)))
                .collect();
            if !owners.is_empty() {
                help = format!(
                    "`{}` has no variable `{name}`; did you mean {}?",
                    self.prog.role_name(r),
                    owners.join(" or ")
                );
            }
        }
        self.err(Code::UnknownVariable, span, format!("unknown variable `{name}`"), help);
        Expr::error(loc)
    }

    pub(super) fn not_allowed(&mut self, span: Span, what: &str, env: &Env) {
        let part = env.part.unwrap_or("this expression");
        if super::body::is_body_place(part) {
            let help = match part {
                super::body::OBSTACLE => "an obstacle is static: its geometry and `at:` read constants only",
                super::body::GEOMETRIC_FOOTPRINT => {
                    "a geometric footprint is placed by its robot's state variables, `old(x)`, `clock`, the primitive's parameters and constants"
                }
                _ => "a body is placed by its own robot's state variables and constants only: it cannot depend on another robot (an input), a motion or time",
            };
            return self.err(Code::VariableNotAllowed, span, format!("{part} cannot read {what}"), help);
        }
        if part == "a partition" {
            return self.err(
                Code::VariableNotAllowed,
                span,
                format!("a partition's region cannot read {what}"),
                "a region is a fixed part of the world: it reads its point and constants only (Sec 3.4, ∃ FP1, FP2)",
            );
        }
        let reads = match part {
            "the precondition" => "state and input variables",
            "the assumption" => "input variables and `clock`",
            "the guarantee" => "state variables, `old(x)` and `clock`",
            "the postcondition" => "state and input variables and `old(x)`",
            "the footprint" => "state variables, `old(x)`, its point and `clock`",
            "the duration" => "parameters, constants and the initial state",
            _ => "parameters and constants",
        };
        self.err(
            Code::VariableNotAllowed,
            span,
            format!("{part} of a motion primitive cannot read {what}"),
            format!("Def 3.4: {part} reads {reads} (besides parameters and constants)"),
        );
    }

    pub(super) fn role_var(&mut self, r: RoleId, field: &ast::Ident, span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        if !env.qualified && env.part.is_some_and(super::body::is_body_place) {
            let what = format!("`{}.{}`, a participant's variable", self.prog.role_name(r), field.name);
            self.not_allowed(span, &what, env);
            return Expr::error(loc);
        }
        if !env.qualified {
            self.err(
                Code::UnknownVariable,
                span,
                format!(
                    "`{}.{}` names a participant's variable, which is not visible here",
                    self.prog.role_name(r),
                    field.name
                ),
                "contracts and initial states read their own robot's variables unqualified",
            );
            return Expr::error(loc);
        }
        let k = self.prog.kind_of(r);
        match k.slot(&field.name) {
            Some((slot, sort)) => Expr { kind: ExprKind::Var(Var::Role(r, slot)), sort: sort.clone(), loc },
            None => {
                let vars: Vec<_> = k.state.iter().chain(&k.inputs).map(|(n, _)| format!("`{n}`")).collect();
                let kname = k.name.clone();
                if self.prog.is_plain(r) {
                    let who = self.prog.role_name(r).to_string();
                    self.err(
                        Code::UnknownVariable,
                        field.span,
                        format!("`{who}` is a plain participant: it has no variable `{}`", field.name),
                        "a plain participant's state is what it sends and receives: read the payload's value, or keep it in a recursion parameter",
                    );
                    return Expr::error(loc);
                }
                self.err(
                    Code::UnknownVariable,
                    field.span,
                    format!("`{}` (a `{kname}`) has no variable `{}`", self.prog.role_name(r), field.name),
                    if vars.is_empty() {
                        format!("`{kname}` declares no variables")
                    } else {
                        format!("its variables are {}", vars.join(", "))
                    },
                );
                Expr::error(loc)
            }
        }
    }

    pub(super) fn old(&mut self, f: &ast::Ident, args: &[ast::Expr], span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let bad = Expr::error(loc);
        if !env.old {
            self.not_allowed(f.span, "`old(...)`", env);
            return bad;
        }
        let name = match args {
            [ast::Expr { kind: ast::ExprKind::Var(n), .. }] => n,
            _ => {
                self.err(
                    Code::ArityMismatch,
                    span,
                    "`old` takes one state variable",
                    "write `old(x)` for a state variable `x`",
                );
                return bad;
            }
        };
        let Some(kind) = self.own_kind(env) else { return bad };
        match self.prog.kind(kind).state.iter().position(|(n, _)| n == name) {
            Some(i) => Expr { kind: ExprKind::Var(Var::Old(i)), sort: self.prog.kind(kind).state[i].1.clone(), loc },
            None => {
                self.err(
                    Code::UnknownVariable,
                    args[0].span,
                    format!("`old({name})`: `{name}` is not a state variable of `{}`", self.prog.kind(kind).name),
                    "`old` reads the value a state variable had when the motion started",
                );
                bad
            }
        }
    }
}
