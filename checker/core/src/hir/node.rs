//! Node identity: one node of a type or process, as opposed to an equal one elsewhere.
//!
//! The HIR's equality is structural ([`Loc`](super::Loc) never takes part in it), which is
//! what the checks mean by "the same term". Some walks need the other notion: *this*
//! node, met again. Projection records who occurs in each node of a global type
//! (`project/occurs.rs`); process typing remembers which (process loop body, local type
//! node) pairs it has checked under which context (`typeck/rec.rs`, the coinduction of
//! [T-REC]); comparing, renaming and measuring local types memoise per node because
//! shared tails make a local type a DAG (`project/equal.rs`, `project/merge.rs`,
//! `hir/print.rs`). Two equal nodes at different places must stay apart there: two
//! loops with equal bodies are two loops.
//!
//! The HIR has no node ids (lowering would have to assign them), so a node is known by
//! its address. [`NodeRef`] is that convention made a type, with its contract:
//!
//! - it is made from a pointer that keeps the node alive for as long as the `NodeRef`
//!   exists: a shared reference `&'a T` (the borrow checker keeps the node alive and in
//!   place) or an `Arc<T>` (the `NodeRef` owns a count). So an address in a map is never
//!   the address of a freed node reused by another one, which would make a node
//!   "already checked" that never was;
//! - equality and hashing are by address only; nothing is read through it for them.
//!
//! Raw addresses (`as *const T as usize`) as keys do not have the first property: a
//! node built during a walk and dropped before the map is, such as an unfolded or
//! renamed local type, could lend its address to a later node.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

/// A node known by its address; see the module documentation for the contract.
#[derive(Clone, Debug)]
pub struct NodeRef<P>(P);

/// A pointer that keeps its node alive and in place while it exists.
pub trait Pointer {
    fn addr(&self) -> *const ();
}

impl<T> Pointer for &T {
    fn addr(&self) -> *const () {
        *self as *const T as *const ()
    }
}

impl<T> Pointer for Arc<T> {
    fn addr(&self) -> *const () {
        Arc::as_ptr(self) as *const ()
    }
}

impl<P: Pointer> NodeRef<P> {
    pub fn new(p: P) -> NodeRef<P> {
        NodeRef(p)
    }

    /// The node.
    pub fn get(&self) -> &P {
        &self.0
    }
}

impl<T> From<&Arc<T>> for NodeRef<Arc<T>> {
    fn from(a: &Arc<T>) -> NodeRef<Arc<T>> {
        NodeRef(a.clone())
    }
}

impl<P: Pointer> PartialEq for NodeRef<P> {
    fn eq(&self, other: &NodeRef<P>) -> bool {
        std::ptr::eq(self.0.addr(), other.0.addr())
    }
}

impl<P: Pointer> Eq for NodeRef<P> {}

impl<P: Pointer> Hash for NodeRef<P> {
    fn hash<H: Hasher>(&self, h: &mut H) {
        (self.0.addr() as usize).hash(h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn equal_nodes_at_two_places_are_two_nodes() {
        let (a, b) = (Arc::new(7u32), Arc::new(7u32));
        assert_eq!(a, b, "structurally equal");
        assert_ne!(NodeRef::from(&a), NodeRef::from(&b));
        assert_eq!(NodeRef::from(&a), NodeRef::new(a.clone()));
        let mut seen = HashSet::new();
        assert!(seen.insert(NodeRef::new(&*a)));
        assert!(seen.insert(NodeRef::new(&*b)));
        assert!(!seen.insert(NodeRef::new(&*a)));
    }

    /// A key keeps its node alive: the address of a node whose last other owner is gone
    /// cannot be taken by a new node while the key exists.
    #[test]
    fn a_key_keeps_its_node_alive() {
        let mut keys = HashSet::new();
        for i in 0..100u64 {
            let node = Arc::new(i);
            assert!(keys.insert(NodeRef::from(&node)), "address reused at {i}");
            drop(node);
        }
        assert_eq!(keys.len(), 100);
    }
}
