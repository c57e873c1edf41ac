//! The regularization ε per node: surfaces joined with different ε keep
//! each its own (METHOD.md §9, ε_S per surface), every formula of the law
//! taking node j's from [`ContactSurface::law_of`]. A surface of one ε
//! keeps none per node, and its law is [`ContactSurface::law`] itself.

use crate::law::FrictionLaw;
use crate::surface::ContactSurface;

impl ContactSurface {
    /// The law at node j: its own ε where the surfaces differ, else the
    /// surface's.
    #[inline]
    pub fn law_of(&self, j: usize) -> FrictionLaw {
        match self.node_eps.get(j) {
            Some(&eps) => FrictionLaw { eps },
            None => self.law,
        }
    }

    /// Appends `other`'s nodes' ε after this surface's, keeping ε per node
    /// only once two of them differ.
    pub(crate) fn join_eps(&mut self, other: &ContactSurface) {
        let differs =
            other.law.eps.to_bits() != self.law.eps.to_bits() || !other.node_eps.is_empty();
        if self.node_eps.is_empty() && !differs {
            return;
        }
        if self.node_eps.is_empty() {
            self.node_eps = vec![self.law.eps; self.nodes.len()];
        }
        self.node_eps
            .extend((0..other.nodes.len()).map(|j| other.law_of(j).eps));
    }
}
