//! Expressions (LANGUAGE.md, Sorts and Expressions): resolves an expression, infers its
//! sort and reports a sort error (E0208) where an operator, a builtin or a position
//! expects another sort. Ints promote to reals; `point - point` is a vector, `point +
//! vector` a point.

use super::*;

impl Lowerer {
    /// Resolves a predicate and checks that it is boolean.
    pub(super) fn pred(&mut self, e: &ast::Expr, env: &Env, what: &str) -> Expr {
        let r = self.expr(e, env);
        self.expect_sort(&r, &Sort::Bool, what);
        r
    }

    pub(super) fn expect_sort(&mut self, e: &Expr, want: &Sort, what: &str) {
        if !e.sort.fits(want) {
            self.err(
                Code::SortMismatch,
                e.loc.0,
                format!("{what} must be of sort `{want}`, this is `{}`", e.sort),
                match want {
                    Sort::Bool => "write a comparison or a boolean combination".to_string(),
                    Sort::Int if e.sort == Sort::Real => {
                        "write an integer term: a literal with a decimal point, a division or a `real` variable is a real, and an `int` is never rounded to one".to_string()
                    }
                    Sort::Real | Sort::Int => "write a numeric term".to_string(),
                    _ => format!("write a term of sort `{want}`"),
                },
            );
        }
    }

    pub(super) fn expr(&mut self, e: &ast::Expr, env: &Env) -> Expr {
        crate::stack::deep(|| self.expr_inner(e, env))
    }

    fn expr_inner(&mut self, e: &ast::Expr, env: &Env) -> Expr {
        let loc = Loc(e.span);
        let mk = |kind, sort| Expr { kind, sort, loc };
        match &e.kind {
            ast::ExprKind::Int(i) => mk(ExprKind::Int(*i), Sort::Int),
            ast::ExprKind::Real(r) => mk(ExprKind::Real(r.clone()), Sort::Real),
            ast::ExprKind::Bool(b) => mk(ExprKind::Bool(*b), Sort::Bool),
            ast::ExprKind::Str(s) => self.string(s, loc),
            // The parser reported it.
            ast::ExprKind::Error => Expr::error(loc),
            ast::ExprKind::Var(name) => self.var(name, e.span, env),
            ast::ExprKind::Dot(base, field) => self.dot(base, field, e.span, env),
            ast::ExprKind::Call(f, args) if f.name == "old" => self.old(f, args, e.span, env),
            ast::ExprKind::Call(f, args) => self.call(f, args, e.span, env),
            ast::ExprKind::Unary(op, a) => self.unary(*op, a, loc, env),
            ast::ExprKind::Binary(op, a, b) => {
                let a = self.expr(a, env);
                let b = self.expr(b, env);
                if a.is_error() || b.is_error() {
                    return Expr::error(loc);
                }
                match self.binary_sort(*op, &a, &b) {
                    Sort::Error => Expr::error(loc),
                    sort => mk(ExprKind::Binary(*op, Box::new(a), Box::new(b)), sort),
                }
            }
            ast::ExprKind::If(c, a, b) => self.conditional(c, a, b, loc, env),
            ast::ExprKind::Tuple(items) => {
                let items: Vec<Expr> = items.iter().map(|a| self.expr(a, env)).collect();
                if items.iter().any(Expr::is_error) {
                    return Expr::error(loc);
                }
                let sort = Sort::Product(items.iter().map(|i| i.sort.clone()).collect());
                mk(ExprKind::Tuple(items), sort)
            }
        }
    }

    /// `base.field`: a participant's variable (`Cart.x`, unless `Cart` is a local name)
    /// or a component `.x`, `.y`, `.z` of a point or vector.
    fn dot(&mut self, base: &ast::Expr, field: &ast::Ident, span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let mk = |kind, sort| Expr { kind, sort, loc };
        if let ast::ExprKind::Var(b) = &base.kind {
            if !self.is_local_name(b, env) {
                if let Some(r) = self.prog.role_by_name(b) {
                    return self.role_var(r, field, span, env);
                }
                if !self.resolves(b, env) && env.part.is_some_and(super::body::is_body_place) {
                    // Kinds and primitives are lowered before the participants exist: a
                    // body reading `Cart.x` is reading another robot, whatever `Cart` is.
                    let what = format!("`{b}.{}`, another robot's variable", field.name);
                    self.not_allowed(span, &what, env);
                    return Expr::error(loc);
                }
                if !self.resolves(b, env) {
                    if !self.poisoned.contains(b) && !self.obstacle_as_role(b, base.span) {
                        let names: Vec<_> = self.prog.roles.iter().map(|p| format!("`{}`", p.name)).collect();
                        self.err(
                            Code::UnknownParticipant,
                            base.span,
                            format!("unknown participant `{b}` in `{b}.{}`", field.name),
                            if names.is_empty() {
                                "declare participants in the `system` block".to_string()
                            } else {
                                format!("the participants are {}", names.join(", "))
                            },
                        );
                    }
                    return Expr::error(loc);
                }
            }
        }
        let b = self.expr(base, env);
        if b.is_error() {
            return Expr::error(loc);
        }
        let axis = match field.name.as_str() {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        match axis {
            Some(i) if b.sort.is_spatial() => mk(ExprKind::Component(Box::new(b), i), Sort::Real),
            _ => {
                self.err(
                    Code::SortMismatch,
                    field.span,
                    format!("`.{}` needs a point or a vector, this is `{}`", field.name, b.sort),
                    "components are `.x`, `.y`, `.z` of a `point` or `vector`; `Name.var` reads a participant's variable",
                );
                Expr::error(loc)
            }
        }
    }

    /// A builtin function applied to its arguments (LANGUAGE.md, Expressions).
    fn call(&mut self, f: &ast::Ident, args: &[ast::Expr], span: Span, env: &Env) -> Expr {
        let loc = Loc(span);
        let mk = |kind, sort| Expr { kind, sort, loc };
        let args: Vec<Expr> = args.iter().map(|a| self.expr(a, env)).collect();
        let Some(b) = Builtin::from_name(&f.name) else {
            self.err(
                Code::UnknownVariable,
                f.span,
                format!("unknown function `{}`", f.name),
                "functions are sqrt, min, max, abs, sin, cos, old, point, vector, dot, norm2, has_flag",
            );
            return Expr::error(loc);
        };
        if args.len() != b.arity() {
            self.err(
                Code::ArityMismatch,
                span,
                format!("`{}` takes {} argument(s), found {}", f.name, b.arity(), args.len()),
                "see LANGUAGE.md, Expressions",
            );
            return Expr::error(loc);
        }
        if args.iter().any(Expr::is_error) {
            return Expr::error(loc);
        }
        let sort = match b {
            Builtin::Dot | Builtin::Norm2 => {
                for a in &args {
                    self.expect_sort_spatial(a);
                }
                Sort::Real
            }
            Builtin::Point | Builtin::Vector => {
                for a in &args {
                    self.expect_sort(a, &Sort::Real, "a coordinate");
                }
                if b == Builtin::Point {
                    Sort::Point
                } else {
                    Sort::Vector
                }
            }
            Builtin::Abs | Builtin::Min | Builtin::Max => {
                for a in &args {
                    self.expect_sort(a, &Sort::Real, &format!("an argument of `{}`", f.name));
                }
                if args.iter().all(|a| a.sort == Sort::Int) {
                    Sort::Int
                } else {
                    Sort::Real
                }
            }
            Builtin::Sqrt | Builtin::Sin | Builtin::Cos => {
                self.expect_sort(&args[0], &Sort::Real, &format!("the argument of `{}`", f.name));
                Sort::Real
            }
            // Only lowering of a MAVLink float field makes these (no name reaches them).
            Builtin::Float32 | Builtin::Float64 => Sort::Bool,
            // Only the parser makes this call (`pi` is reserved, `pi()` does not parse).
            Builtin::Pi => Sort::Real,
            Builtin::HasFlag => {
                if !self.has_flag(&args, span) {
                    return Expr::error(loc);
                }
                Sort::Bool
            }
        };
        mk(ExprKind::Call(b, args), sort)
    }

    fn unary(&mut self, op: UnOp, a: &ast::Expr, loc: Loc, env: &Env) -> Expr {
        let a = self.expr(a, env);
        if a.is_error() {
            return Expr::error(loc);
        }
        let sort = match op {
            UnOp::Not => {
                self.expect_sort(&a, &Sort::Bool, "the operand of `!`");
                Sort::Bool
            }
            UnOp::Neg if a.sort == Sort::Vector => Sort::Vector,
            UnOp::Neg => {
                self.expect_sort(&a, &Sort::Real, "the operand of `-`");
                a.sort.clone()
            }
        };
        Expr { kind: ExprKind::Unary(op, Box::new(a)), sort, loc }
    }

    /// `if c then a else b`: the branches have one sort (ints promote).
    fn conditional(&mut self, c: &ast::Expr, a: &ast::Expr, b: &ast::Expr, loc: Loc, env: &Env) -> Expr {
        let c = self.pred(c, env, "a condition");
        let a = self.expr(a, env);
        let b = self.expr(b, env);
        if c.is_error() || a.is_error() || b.is_error() {
            return Expr::error(loc);
        }
        let sort = if a.sort.fits(&b.sort) {
            b.sort.clone()
        } else if b.sort.fits(&a.sort) {
            a.sort.clone()
        } else {
            self.err(
                Code::SortMismatch,
                b.loc.0,
                format!("the branches of `if` have sorts `{}` and `{}`", a.sort, b.sort),
                "both branches must have the same sort",
            );
            return Expr::error(loc);
        };
        Expr { kind: ExprKind::If(Box::new(c), Box::new(a), Box::new(b)), sort, loc }
    }

    pub(super) fn expect_sort_spatial(&mut self, a: &Expr) {
        if !a.sort.is_spatial() {
            self.err(
                Code::SortMismatch,
                a.loc.0,
                format!("expected a `point` or `vector`, this is `{}`", a.sort),
                "build one with `point(x, y, z)` or `vector(x, y, z)`",
            );
        }
    }

    pub(super) fn binary_sort(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Sort {
        use BinOp::*;
        match op {
            And | Or | Implies => {
                self.expect_sort(a, &Sort::Bool, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Bool, &format!("the right operand of `{}`", op.symbol()));
                Sort::Bool
            }
            Eq | Ne => {
                if !a.sort.fits(&b.sort) && !b.sort.fits(&a.sort) {
                    self.err(
                        Code::SortMismatch,
                        b.loc.0,
                        format!("cannot compare `{}` with `{}`", a.sort, b.sort),
                        "both sides of `==` must have the same sort",
                    );
                } else {
                    self.string_fits(a, b);
                }
                Sort::Bool
            }
            Lt | Le | Gt | Ge => {
                self.expect_sort(a, &Sort::Real, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Real, &format!("the right operand of `{}`", op.symbol()));
                Sort::Bool
            }
            Pow => {
                self.expect_sort(a, &Sort::Real, "the base of `^`");
                if !matches!(b.kind, ExprKind::Int(n) if (0..=64).contains(&n)) {
                    self.err(
                        Code::SortMismatch,
                        b.loc.0,
                        "the exponent of `^` must be an integer literal between 0 and 64",
                        "use `sqrt` for square roots; other powers are not supported",
                    );
                }
                a.sort.clone()
            }
            // Points and vectors, or a binder whose sort is still open beside one.
            Add | Sub if a.sort.is_spatial() && b.sort.is_spatial() && (a.sort != Sort::Any || b.sort != Sort::Any) => {
                match (op, &a.sort, &b.sort) {
                    (Sub, Sort::Point, Sort::Point) => Sort::Vector,
                    (_, Sort::Point, Sort::Vector) => Sort::Point,
                    (_, Sort::Vector, Sort::Vector) => Sort::Vector,
                    (_, Sort::Any, _) | (_, _, Sort::Any) => Sort::Any,
                    _ => {
                        self.err(
                            Code::SortMismatch,
                            b.loc.0,
                            format!("cannot apply `{}` to `{}` and `{}`", op.symbol(), a.sort, b.sort),
                            "point - point is a vector; point + vector is a point; vectors add",
                        );
                        Sort::Error
                    }
                }
            }
            Mul if a.sort.is_numeric() && b.sort == Sort::Vector => Sort::Vector,
            Mul if a.sort == Sort::Vector && b.sort.is_numeric() => Sort::Vector,
            Add | Sub | Mul | Div => {
                self.expect_sort(a, &Sort::Real, &format!("the left operand of `{}`", op.symbol()));
                self.expect_sort(b, &Sort::Real, &format!("the right operand of `{}`", op.symbol()));
                if op == Div || a.sort == Sort::Real || b.sort == Sort::Real {
                    Sort::Real
                } else if a.sort == Sort::Any || b.sort == Sort::Any {
                    Sort::Any
                } else {
                    Sort::Int
                }
            }
        }
    }
}
