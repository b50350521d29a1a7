//! Who occurs where in a global type, computed once for all roles: `pt{G}` of Def 4.8
//! (4) for every node, and for each `*` the side each participant is on (Def 4.8 (7)).

use crate::hir::node::NodeRef;
use crate::hir::*;
use fixedbitset::FixedBitSet;
use std::collections::HashMap;

/// The participants of every node of a global type, and for each `*` the side each
/// participant is on. Keyed by node ([`NodeRef`]): equal subterms at two places of the
/// type are two nodes (the same `*` written twice has its sides looked up per place).
pub(super) struct Occurs<'g> {
    pt: HashMap<NodeRef<&'g Global>, FixedBitSet>,
    sides: HashMap<NodeRef<&'g Global>, HashMap<RoleId, Vec<usize>>>,
    /// Every payload field of the type by its value: what a receiver may learn of a value
    /// it never holds (`knows.rs`).
    fields: HashMap<ValueId, &'g Field>,
}

impl<'g> Occurs<'g> {
    pub(super) fn new(prog: &Program, g: &'g Global) -> Occurs<'g> {
        let mut o = Occurs { pt: HashMap::new(), sides: HashMap::new(), fields: HashMap::new() };
        o.fill(g, prog.roles.len());
        o
    }

    fn fill(&mut self, g: &'g Global, n: usize) -> FixedBitSet {
        let mut set = FixedBitSet::with_capacity(n);
        crate::stack::deep(|| match g {
            Global::Msg(m) => {
                set.insert(m.from.idx());
                set.insert(m.to.idx());
                self.fields.extend(m.payload.iter().map(|f| (f.value, f)));
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| set.insert(r.idx())),
            Global::After(a) => set.insert(a.by.idx()),
            Global::Seq(gs, _) | Global::Choice(gs, _) => gs.iter().for_each(|c| set.union_with(&self.fill(c, n))),
            Global::Par(gs, _) => {
                let mut side_of: HashMap<RoleId, Vec<usize>> = HashMap::new();
                for (i, c) in gs.iter().enumerate() {
                    let sub = self.fill(c, n);
                    for r in sub.ones() {
                        side_of.entry(RoleId(r as u32)).or_default().push(i);
                    }
                    set.union_with(&sub);
                }
                self.sides.insert(NodeRef::new(g), side_of);
            }
            Global::Rec { body, .. } => set = self.fill(body, n),
            Global::Var(_) | Global::End(_) => {}
        });
        self.pt.insert(NodeRef::new(g), set.clone());
        set
    }

    pub(super) fn contains(&self, g: &Global, r: RoleId) -> bool {
        match self.pt.get(&NodeRef::new(g)) {
            Some(set) => set.contains(r.idx()),
            None => {
                // Not a node of the type `Occurs` was built for: compute directly.
                let mut pt = Vec::new();
                g.participants(&mut pt);
                pt.contains(&r)
            }
        }
    }

    /// The payload field that binds `v`, if `v` is one.
    pub(super) fn field(&self, v: ValueId) -> Option<&'g Field> {
        self.fields.get(&v).copied()
    }

    /// For a `*` node of the type, the sides each participant occurs on.
    pub(super) fn sides<'s>(&'s self, g: &'s Global) -> Option<&'s HashMap<RoleId, Vec<usize>>> {
        self.sides.get(&NodeRef::new(g))
    }
}
