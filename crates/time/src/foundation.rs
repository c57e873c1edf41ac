//! Foundations whose speed changes in time: surface k's nodes move under
//! the body at V_J(t) = V_J θ_k(t), with V_J the speed the surface was built
//! with (METHOD.md §9, the slip w_T = v_T − V).

use stickslip_contact::ContactSurface;

use crate::history::History;
use crate::pressure::changing_parts;

/// The foundation speeds' histories of a run's surfaces, applied before
/// each step for the time it ends at.
#[derive(Clone, Debug)]
pub(crate) struct FoundationHistories {
    /// V_J as built.
    base: Vec<f64>,
    /// Each node's history (index into `histories`), `None` for constant.
    node_history: Vec<Option<usize>>,
    histories: Vec<History>,
    /// θ_k at the last time applied.
    thetas: Vec<f64>,
}

impl FoundationHistories {
    /// The histories of `surface`'s parts that change in time (one per
    /// part, in part order), `None` when none does or no foundation moves.
    pub fn new(surface: &ContactSurface, histories: &[History]) -> Option<FoundationHistories> {
        if !surface.foundation_moves() {
            return None;
        }
        let (node_history, kept) = changing_parts(surface, histories)?;
        Some(FoundationHistories {
            base: surface.foundation.clone(),
            node_history,
            thetas: vec![0.0; kept.len()],
            histories: kept,
        })
    }

    /// Sets the speeds at time `t`. Nothing formed from the bounds depends
    /// on them, so no revision is counted.
    pub fn apply(&mut self, t: f64, surface: &mut ContactSurface) {
        for (theta, h) in self.thetas.iter_mut().zip(&self.histories) {
            *theta = h.value(t);
        }
        let (base, node_history, thetas) = (&self.base, &self.node_history, &self.thetas);
        surface.set_foundation(|j| match node_history[j] {
            Some(k) => base[j] * thetas[k],
            None => base[j],
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stickslip_contact::ContactNode;

    #[test]
    fn a_table_scales_its_own_surface_only() {
        let node = |j: usize| ContactNode {
            node: j,
            dofs: [Some(j), None],
            weight: 0.5,
            tangent: [1.0, 0.0],
            s: j as f64,
            bound: 1.0,
        };
        let a = ContactSurface::from_nodes("a", vec![node(0), node(1)], 1e-3).unwrap();
        let b = ContactSurface::from_nodes("b", vec![node(2)], 1e-3).unwrap();
        let mut s = ContactSurface::join(vec![a, b]).unwrap();
        s.set_foundation(|j| [2.0, 2.0, -1.0][j]);
        let table = History::Table(vec![(0.0, 0.0), (1.0, 1.0)]);
        let mut h = FoundationHistories::new(&s, &[table, History::Constant]).unwrap();
        h.apply(0.25, &mut s);
        // θ(0.25) = 0.25 on the table's straight line: V = 2·0.25 on a.
        assert_eq!(s.foundation, vec![0.5, 0.5, -1.0]);
        assert_eq!(s.revision, 0);
        assert!(FoundationHistories::new(&s, &[History::Step, History::Constant]).is_none());
    }
}
