//! Who occurs where in a global type, computed once for all roles: `pt{G}` of Def 4.8
//! (4) for every node, and for each `*` the side each participant is on (Def 4.8 (7)).

use crate::hir::*;
use fixedbitset::FixedBitSet;
use std::collections::HashMap;

/// The participants of every node of a global type, keyed by the node's address, and
/// for each `*` the side each participant is on.
pub(super) struct Occurs {
    pub(super) pt: HashMap<*const Global, FixedBitSet>,
    pub(super) sides: HashMap<*const Global, HashMap<RoleId, Vec<usize>>>,
}

impl Occurs {
    pub(super) fn new(prog: &Program, g: &Global) -> Occurs {
        let mut o = Occurs { pt: HashMap::new(), sides: HashMap::new() };
        o.fill(g, prog.roles.len());
        o
    }

    pub(super) fn fill(&mut self, g: &Global, n: usize) -> FixedBitSet {
        let mut set = FixedBitSet::with_capacity(n);
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || match g {
            Global::Msg(m) => {
                set.insert(m.from.idx());
                set.insert(m.to.idx());
            }
            Global::Motion(m) => m.parts.iter().for_each(|(r, _)| set.insert(r.idx())),
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
                self.sides.insert(g as *const Global, side_of);
            }
            Global::Rec { body, .. } => set = self.fill(body, n),
            Global::Var(_) | Global::End(_) => {}
        });
        self.pt.insert(g as *const Global, set.clone());
        set
    }

    pub(super) fn contains(&self, g: &Global, r: RoleId) -> bool {
        match self.pt.get(&(g as *const Global)) {
            Some(set) => set.contains(r.idx()),
            None => {
                // Not a node of the type `Occurs` was built for: compute directly.
                let mut pt = Vec::new();
                g.participants(&mut pt);
                pt.contains(&r)
            }
        }
    }
}
