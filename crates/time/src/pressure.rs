//! Friction bounds that change in time: surface k's nodes carry
//! g_J(t) = g_J θ_k(t), with g_J the bound the surface was built with
//! (μ·p·profile(s_J)) and θ_k its pressure history (METHOD.md §3, g = μ F_n
//! with F_n = p(s, t)).

use stickslip_contact::ContactSurface;

use crate::history::History;

/// The histories of `surface`'s parts (one per part, in part order) that
/// change after t = 0 (constant and step histories are 1 for t ≥ 0), and
/// each node's index into them (`None` on a part that keeps its value);
/// `None` when no part changes.
pub(crate) fn changing_parts(
    surface: &ContactSurface,
    histories: &[History],
) -> Option<(Vec<Option<usize>>, Vec<History>)> {
    let mut kept = Vec::new();
    let mut node_history = vec![None; surface.len()];
    for (part, history) in surface.parts.iter().zip(histories) {
        if matches!(history, History::Constant | History::Step) {
            continue;
        }
        node_history[part.nodes.clone()]
            .iter_mut()
            .for_each(|h| *h = Some(kept.len()));
        kept.push(history.clone());
    }
    (!kept.is_empty()).then_some((node_history, kept))
}

/// The histories of the surfaces whose pressure changes, and the bounds at
/// θ = 1.
#[derive(Clone, Debug)]
pub(crate) struct BoundHistories {
    /// Each node's bound at θ = 1.
    base: Vec<f64>,
    /// Per node, its surface's entry in `histories`, or `None` for a
    /// surface whose pressure is constant.
    node_history: Vec<Option<usize>>,
    histories: Vec<History>,
    /// θ_k at the time the bounds were last set.
    thetas: Vec<f64>,
}

impl BoundHistories {
    /// The histories of `surface`'s parts (one per part, in order), or
    /// `None` when none changes after t = 0 (constant and step histories
    /// are 1 for t ≥ 0): such a run keeps its bounds and forms nothing
    /// per step.
    pub fn new(surface: &ContactSurface, histories: &[History]) -> Option<BoundHistories> {
        let (node_history, kept) = changing_parts(surface, histories)?;
        Some(BoundHistories {
            base: surface.nodes.iter().map(|n| n.bound).collect(),
            node_history,
            thetas: vec![f64::NAN; kept.len()],
            histories: kept,
        })
    }

    /// Sets the bounds of `surface` to their values at `t` (nothing is
    /// written, and the surface's revision stays, when no θ moved).
    pub fn apply(&mut self, t: f64, surface: &mut ContactSurface) {
        let mut moved = false;
        for (theta, h) in self.thetas.iter_mut().zip(&self.histories) {
            let value = h.value(t);
            moved |= value.to_bits() != theta.to_bits();
            *theta = value;
        }
        if !moved {
            return;
        }
        // A negative factor would make g < 0: the pressure lifts off, and
        // a surface out of contact carries no friction.
        let (base, thetas, node_history) = (&self.base, &self.thetas, &self.node_history);
        surface.set_bounds(|j| match node_history[j] {
            Some(k) => base[j] * thetas[k].max(0.0),
            None => base[j],
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stickslip_contact::ContactNode;

    fn surface() -> ContactSurface {
        let node = |j: usize| ContactNode {
            node: j,
            dofs: [Some(j), None],
            weight: 0.5,
            tangent: [1.0, 0.0],
            s: j as f64,
            bound: 0.3 * (j + 1) as f64,
        };
        let a = ContactSurface::from_nodes("a", vec![node(0), node(1)], 1e-3).unwrap();
        let b = ContactSurface::from_nodes("b", vec![node(2)], 1e-3).unwrap();
        ContactSurface::join(vec![a, b]).unwrap()
    }

    #[test]
    fn constant_histories_form_nothing() {
        let s = surface();
        assert!(BoundHistories::new(&s, &[History::Constant, History::Step]).is_none());
    }

    #[test]
    fn a_table_scales_its_own_surface_only() {
        let mut s = surface();
        let table = History::Table(vec![(0.0, 1.0), (1.0, 0.0)]);
        let mut h = BoundHistories::new(&s, &[table, History::Constant]).unwrap();
        h.apply(0.25, &mut s);
        // θ(0.25) = 0.75 by the table's straight line; g_J = 0.3 (J + 1).
        let expected = [0.3 * 0.75, 0.6 * 0.75, 0.3 * 3.0];
        for (n, e) in s.nodes.iter().zip(expected) {
            assert!((n.bound - e).abs() < 1e-15, "{} vs {e}", n.bound);
        }
        assert_eq!(s.revision, 1);
        // The same time again changes nothing, and counts no revision.
        h.apply(0.25, &mut s);
        assert_eq!(s.revision, 1);
        // Past the table's end θ = 0: no friction on surface a.
        h.apply(2.0, &mut s);
        assert_eq!(s.nodes[0].bound, 0.0);
        assert_eq!(s.nodes[2].bound, 0.3 * 3.0);
    }
}
