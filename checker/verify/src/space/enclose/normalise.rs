//! The body placed in the footprint's predicate, and the predicate normalised: affine
//! combinations collected with exact rational coefficients, so that the position cancels.

use super::*;

/// The box around the shape in its own frame, exactly (mochi's conventions: boxes,
/// cylinders and capsules stand on z = 0, centred in x and y; a sphere is centred on the
/// origin). `None` unless every size is a rational constant.
pub(super) fn shape_box(prog: &Program, shape: &Shape) -> Option<[(BigRational, BigRational); 3]> {
    let size = |e: &Expr| bounds::exact(prog, e).filter(|q| !q.is_negative());
    let two = BigRational::from_integer(BigInt::from(2));
    let sym = |h: BigRational| (-h.clone(), h);
    Some(match shape {
        Shape::Box([x, y, z]) => [sym(size(x)? / &two), sym(size(y)? / &two), (BigRational::zero(), size(z)?)],
        Shape::Sphere(r) => {
            let r = size(r)?;
            [sym(r.clone()), sym(r.clone()), sym(r)]
        }
        Shape::Cylinder(r, h) | Shape::Capsule(r, h) => {
            let r = size(r)?;
            [sym(r.clone()), sym(r), (BigRational::zero(), size(h)?)]
        }
        Shape::Urdf { .. } | Shape::Mesh { .. } => return None,
    })
}

/// `t + Rz(yaw) Ry(pitch) Rx(roll) q` for `pose(t, roll, pitch, yaw)`: the point `q` of the
/// part's frame in its owner's frame (the inverse of [`crate::space::region::to_part_frame`]). An
/// angle that is exactly 0 is skipped; a quarter turn rotates by 0 and ±1.
pub(super) fn place(prog: &Program, pose: &Pose, q: &[Expr; 3]) -> [Expr; 3] {
    let mut v = q.clone();
    // Roll about x (y, z), then pitch about y (z, x), then yaw about z (x, y).
    for (idx, (a, b)) in [(3usize, (1usize, 2usize)), (4, (2, 0)), (5, (0, 1))] {
        let angle = &pose.args[idx];
        if bounds::exact(prog, angle).is_some_and(|q| q.is_zero()) {
            continue;
        }
        let (c, s) = match bounds::quarter_turn(prog, angle) {
            Some((c, s)) => (int(c), int(s)),
            None => (call(Builtin::Cos, angle), call(Builtin::Sin, angle)),
        };
        let (x, y) = (v[a].clone(), v[b].clone());
        // x' = c x - s y, y' = s x + c y.
        v[a] = bin(BinOp::Sub, bin(BinOp::Mul, c.clone(), x.clone()), bin(BinOp::Mul, s.clone(), y.clone()));
        v[b] = bin(BinOp::Add, bin(BinOp::Mul, s, x), bin(BinOp::Mul, c, y));
    }
    for (k, c) in v.iter_mut().enumerate() {
        *c = bin(BinOp::Add, pose.args[k].clone(), c.clone());
    }
    v
}

pub(super) fn int(n: i64) -> Expr {
    Expr { kind: ExprKind::Int(n), sort: Sort::Int, loc: Loc::default() }
}

pub(super) fn call(f: Builtin, a: &Expr) -> Expr {
    Expr { kind: ExprKind::Call(f, vec![a.clone()]), sort: Sort::Real, loc: Loc::default() }
}

pub(super) fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
    let sort = if matches!(
        op,
        BinOp::And | BinOp::Or | BinOp::Implies | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne
    ) {
        Sort::Bool
    } else {
        Sort::Real
    };
    Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort, loc: Loc::default() }
}

/// `e` with every location erased, so that equal terms compare equal wherever written.
pub(super) fn strip(e: &Expr) -> Expr {
    e.map(&mut |n| Expr { loc: Loc::default(), ..n })
}

/// `c + Σ k_i · atom_i`: an atom is a variable or a term that is not a sum (a product of
/// two non-constant terms, a power, a call, ...), its own arguments normalised.
#[derive(Clone, Debug)]
pub(super) struct Lin {
    c: BigRational,
    terms: Vec<(Expr, BigRational)>,
}

impl Lin {
    pub(super) fn constant(c: BigRational) -> Lin {
        Lin { c, terms: Vec::new() }
    }

    pub(super) fn atom(e: Expr) -> Lin {
        Lin { c: BigRational::zero(), terms: vec![(e, BigRational::one())] }
    }

    pub(super) fn scale(mut self, k: &BigRational) -> Lin {
        self.c *= k;
        for (_, x) in &mut self.terms {
            *x *= k;
        }
        self.terms.retain(|(_, x)| !x.is_zero());
        self
    }

    pub(super) fn add(mut self, o: Lin) -> Lin {
        self.c += o.c;
        for (e, k) in o.terms {
            match self.terms.iter_mut().find(|(a, _)| *a == e) {
                Some((_, x)) => *x += k,
                None => self.terms.push((e, k)),
            }
        }
        self.terms.retain(|(_, x)| !x.is_zero());
        self
    }

    pub(super) fn as_const(&self) -> Option<&BigRational> {
        self.terms.is_empty().then_some(&self.c)
    }

    /// Back to a term: `Σ k_i · atom_i + c`.
    pub(super) fn expr(&self) -> Expr {
        let mut out: Option<Expr> = None;
        for (a, k) in &self.terms {
            let t = if k.is_one() {
                a.clone()
            } else if (-k).is_one() {
                Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(a.clone())), sort: Sort::Real, loc: Loc::default() }
            } else {
                bin(BinOp::Mul, rational(k), a.clone())
            };
            out = Some(match out {
                Some(s) => bin(BinOp::Add, s, t),
                None => t,
            });
        }
        match out {
            Some(s) if self.c.is_zero() => s,
            Some(s) => bin(BinOp::Add, s, rational(&self.c)),
            None => rational(&self.c),
        }
    }
}

pub(super) use crate::space::literal::rational;

pub(super) fn lin(prog: &Program, e: &Expr) -> Lin {
    crate::stack::deep(|| lin_inner(prog, e))
}

pub(super) fn lin_inner(prog: &Program, e: &Expr) -> Lin {
    if let Some(q) = bounds::exact(prog, e) {
        return Lin::constant(q);
    }
    match &e.kind {
        ExprKind::Unary(UnOp::Neg, a) => lin(prog, a).scale(&-BigRational::one()),
        ExprKind::Binary(BinOp::Add, a, b) => lin(prog, a).add(lin(prog, b)),
        ExprKind::Binary(BinOp::Sub, a, b) => lin(prog, a).add(lin(prog, b).scale(&-BigRational::one())),
        ExprKind::Binary(BinOp::Mul, a, b) => {
            let (x, y) = (lin(prog, a), lin(prog, b));
            match (x.as_const(), y.as_const()) {
                (Some(k), _) => {
                    let k = k.clone();
                    y.scale(&k)
                }
                (_, Some(k)) => {
                    let k = k.clone();
                    x.scale(&k)
                }
                _ => Lin::atom(bin(BinOp::Mul, x.expr(), y.expr())),
            }
        }
        ExprKind::Binary(BinOp::Div, a, b) => {
            let (x, y) = (lin(prog, a), lin(prog, b));
            match y.as_const() {
                Some(k) if !k.is_zero() => {
                    let k = k.recip();
                    x.scale(&k)
                }
                _ => Lin::atom(bin(BinOp::Div, x.expr(), y.expr())),
            }
        }
        ExprKind::Binary(BinOp::Pow, a, n) => Lin::atom(Expr {
            kind: ExprKind::Binary(BinOp::Pow, Box::new(lin(prog, a).expr()), n.clone()),
            ..e.clone()
        }),
        ExprKind::Call(f, args) if e.sort.is_numeric() => Lin::atom(Expr {
            kind: ExprKind::Call(
                *f,
                args.iter().map(|a| if a.sort.is_numeric() { lin(prog, a).expr() } else { a.clone() }).collect(),
            ),
            ..e.clone()
        }),
        _ => Lin::atom(e.clone()),
    }
}

/// A predicate with each comparison `a op b` written `a - b op 0`, normalised. A
/// comparison affine in the shape's point alone (`pz <= h`: the footprint's floor and
/// ceiling) is decided exactly over the shape's box `extent` (its extreme value over the
/// box, in rationals) and becomes `true` when it holds there: faces that touch exactly are
/// beyond any outward enclosure.
pub(super) fn normalise_bool(prog: &Program, e: &Expr, extent: &[(BigRational, BigRational); 3]) -> Expr {
    crate::stack::deep(|| match &e.kind {
        ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
            bin(*op, normalise_bool(prog, a, extent), normalise_bool(prog, b, extent))
        }
        ExprKind::Unary(UnOp::Not, a) => {
            Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(normalise_bool(prog, a, extent))), ..e.clone() }
        }
        ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
            if a.sort.is_numeric() && b.sort.is_numeric() =>
        {
            let d = lin(prog, a).add(lin(prog, b).scale(&-BigRational::one()));
            if holds_on_box(&d, *op, extent) {
                return Expr::bool(true, Loc::default());
            }
            bin(*op, d.expr(), int(0))
        }
        _ => e.clone(),
    })
}

/// Whether `d op 0` holds at every point of the box, `d` affine in the point's coordinates
/// only (exact: the extreme of an affine function over a box is at the corner its
/// coefficients' signs pick).
pub(super) fn holds_on_box(d: &Lin, op: BinOp, extent: &[(BigRational, BigRational); 3]) -> bool {
    let (mut lo, mut hi) = (d.c.clone(), d.c.clone());
    for (atom, k) in &d.terms {
        let ExprKind::Var(Var::Point(i)) = atom.kind else { return false };
        let Some((l, h)) = extent.get(i) else { return false };
        let (a, b) = (k * l, k * h);
        if a <= b {
            lo += a;
            hi += b;
        } else {
            lo += b;
            hi += a;
        }
    }
    let zero = BigRational::zero();
    match op {
        BinOp::Le => hi <= zero,
        BinOp::Lt => hi < zero,
        BinOp::Ge => lo >= zero,
        BinOp::Gt => lo > zero,
        _ => false,
    }
}
