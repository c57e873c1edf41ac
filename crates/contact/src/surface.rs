//! The contact surface Γ_C: its friction-carrying nodes, their nodal
//! quadrature weights, tangents and friction bounds (METHOD.md §3).

use stickslip_fem::{boundary_quadrature, DofMap, FemError};
use stickslip_mesh::Mesh;

use crate::compliance::CompliantNode;
use crate::law::{FrictionLaw, SlipState};

/// Why a contact surface could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    /// The group is missing, not a line, or not a chain of edges.
    #[error("contact group {group:?}: {source}")]
    Group {
        /// The group name from the case.
        group: String,
        /// What the fem crate found wrong.
        source: Box<FemError>,
    },
    /// A parameter out of range.
    #[error("contact: {0}")]
    Parameter(String),
    /// A node on two surfaces.
    #[error(
        "node {node} is on contact surfaces {first:?} and {second:?}: a node carries the friction \
         of one surface only; make the groups disjoint (end one line a node short, or merge them \
         into one group with one pressure and μ)"
    )]
    Overlap {
        /// Mesh node index (0-based).
        node: usize,
        /// The first surface's group.
        first: String,
        /// The second surface's group.
        second: String,
    },
}

/// One node of Γ_C that carries friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactNode {
    /// Mesh node index.
    pub node: usize,
    /// Free DOF indices of the node's x and y components (`None` = fixed).
    pub dofs: [Option<usize>; 2],
    /// Nodal quadrature weight w_J (trapezoid for Q1, Simpson for Q2).
    pub weight: f64,
    /// Unit tangent τ_J, counter-clockwise along the boundary.
    pub tangent: [f64; 2],
    /// Arc length along the surface.
    pub s: f64,
    /// Friction bound g_J = μ·|F_n| (a traction).
    pub bound: f64,
}

impl ContactNode {
    /// Whether a Dirichlet condition holds the node's tangential motion:
    /// the tangent has no component along a free DOF, so the node carries
    /// no friction (BENCHMARK.md, the slab's corner (0, 0)).
    pub fn tangent_held(&self) -> bool {
        let free: f64 = (0..2)
            .filter(|&c| self.dofs[c].is_some())
            .map(|c| self.tangent[c] * self.tangent[c])
            .sum();
        free < 1e-20
    }

    /// Tangential velocity v_T = τ·ṙ_J from a free-DOF velocity vector
    /// (fixed components are prescribed constants, so their velocity is 0).
    #[inline]
    pub fn tangential(&self, free: &[f64]) -> f64 {
        let mut v = 0.0;
        for c in 0..2 {
            if let Some(d) = self.dofs[c] {
                v += self.tangent[c] * free[d];
            }
        }
        v
    }

    /// w_J g_J: the magnitude of the nodal slip force, and ε times the
    /// nodal damping coefficient.
    #[inline]
    pub fn force_scale(&self) -> f64 {
        self.weight * self.bound
    }

    /// The damping coefficient w_J g_J/ε of the node when stuck: C gains
    /// it times τ_J τ_Jᵀ (METHOD.md §3).
    #[inline]
    pub fn stuck_damping(&self, law: &FrictionLaw) -> f64 {
        law.stuck_damping(self.force_scale())
    }

    /// The constant slip force w_J g_J sign(v_TJ) along τ_J that F gains
    /// for a node of class `class` (0 when stuck; METHOD.md §3).
    #[inline]
    pub fn slip_force(&self, class: SlipState) -> f64 {
        self.force_scale() * class.sign()
    }

    /// The nodal friction force f_J = w_J g_J φ_ε(v_T) along τ_J at
    /// tangential velocity `v_t` (paper eq. (4.5)).
    #[inline]
    pub fn force(&self, law: &FrictionLaw, v_t: f64) -> f64 {
        self.class_and_force(law, v_t).1
    }

    /// The node's class at tangential velocity `v_t` and its force
    /// [`ContactNode::force`].
    #[inline]
    pub fn class_and_force(&self, law: &FrictionLaw, v_t: f64) -> (SlipState, f64) {
        let (class, phi) = law.class_and_phi(v_t);
        (class, self.force_scale() * phi)
    }

    /// Subtracts the force f τ_J from a right-hand side on free DOFs.
    #[inline]
    fn subtract_along_tangent(&self, f: f64, rhs: &mut [f64]) {
        for a in 0..2 {
            if let Some(i) = self.dofs[a] {
                rhs[i] -= f * self.tangent[a];
            }
        }
    }

    /// The node's tangential velocity at free-DOF velocity `v_new` and its
    /// tangential displacement over a step of `dt` from `v` to `v_new` by
    /// the trapezoid rule, (τ·ṙ_K, τ·½Δt(ṙ_K + ṙ_{K−1})), in one pass.
    #[inline]
    pub fn motion(&self, v_new: &[f64], v: &[f64], dt: f64) -> (f64, f64) {
        let (mut v_t, mut increment) = (0.0, 0.0);
        for c in 0..2 {
            if let Some(d) = self.dofs[c] {
                v_t += self.tangent[c] * v_new[d];
                increment += self.tangent[c] * (0.5 * dt * (v_new[d] + v[d]));
            }
        }
        (v_t, increment)
    }
}

/// One surface of a case's friction nodes: its group and where its nodes
/// are in [`ContactSurface::nodes`].
#[derive(Clone, Debug, PartialEq)]
pub struct SurfacePart {
    /// Name of the physical group.
    pub group: String,
    /// Its nodes' indices in [`ContactSurface::nodes`].
    pub nodes: std::ops::Range<usize>,
}

/// The friction surface: the nodes of one or several named line groups
/// that carry friction, each group's ordered along its line, and the
/// regularized law. Friction couples no two nodes, so several surfaces
/// are one set of nodes, each with its own bound.
#[derive(Clone, Debug)]
pub struct ContactSurface {
    /// Name of the (first) physical group.
    pub group: String,
    /// Friction-carrying nodes in order along the surface, surface by
    /// surface.
    pub nodes: Vec<ContactNode>,
    /// The surfaces the nodes belong to, in order; their ranges tile
    /// `nodes`.
    pub parts: Vec<SurfacePart>,
    /// Counts changes of the bounds after the surface was built
    /// ([`ContactSurface::set_bounds`]): whatever was formed from the
    /// bounds is formed again when it moves.
    pub revision: u64,
    /// Mesh nodes of the group left out because a Dirichlet condition fixes
    /// their tangential motion (e.g. the slab's corner (0, 0)).
    pub excluded: Vec<usize>,
    /// The regularized law with its ε.
    pub law: FrictionLaw,
    /// Each node's foundation speed V_J along τ_J (METHOD.md §9); empty
    /// while the foundation is at rest (`foundation.rs`).
    pub foundation: Vec<f64>,
    /// Each node's fall of μ with the slip speed (METHOD.md §9), `None`
    /// for the constant law; empty where every node's μ is constant
    /// (`mu_speed.rs`).
    pub weakening: Vec<Option<crate::Weakening>>,
    /// Each node's ε where joined surfaces have different ones, empty
    /// where all share `law.eps` (`regularization.rs`).
    pub node_eps: Vec<f64>,
    /// The nodes a compliant foundation holds (METHOD.md §10), in node
    /// order; their bounds follow the approach. Empty where every surface
    /// has a prescribed pressure.
    pub compliance: Vec<CompliantNode>,
}

impl ContactSurface {
    /// Builds Γ_C from a named line group of `mesh`, with a uniform normal
    /// pressure `pressure` (F_n) and friction coefficient `mu`.
    ///
    /// # Errors
    /// A missing or non-line group, ε ≤ 0, μ < 0, or a non-finite value.
    pub fn from_group(
        mesh: &Mesh,
        dofs: &DofMap,
        group: &str,
        pressure: f64,
        mu: f64,
        eps: f64,
    ) -> Result<ContactSurface, ContactError> {
        check_parameters(pressure, mu, eps)?;
        let quadrature = boundary_quadrature(mesh, group).map_err(|e| ContactError::Group {
            group: group.to_string(),
            source: Box::new(e),
        })?;
        let bound = mu * pressure.abs();
        let mut nodes = Vec::with_capacity(quadrature.len());
        let mut excluded = Vec::new();
        for b in &quadrature {
            let node = ContactNode {
                node: b.node,
                dofs: [dofs.free(b.node, 0), dofs.free(b.node, 1)],
                weight: b.weight,
                tangent: b.tangent,
                s: b.s,
                bound,
            };
            if node.tangent_held() {
                excluded.push(b.node);
                continue;
            }
            nodes.push(node);
        }
        Ok(ContactSurface {
            group: group.to_string(),
            parts: vec![SurfacePart {
                group: group.to_string(),
                nodes: 0..nodes.len(),
            }],
            nodes,
            excluded,
            revision: 0,
            law: FrictionLaw { eps },
            foundation: Vec::new(),
            weakening: Vec::new(),
            node_eps: Vec::new(),
            compliance: Vec::new(),
        })
    }

    /// Builds a surface from nodes given directly (tests, lumped models).
    ///
    /// # Errors
    /// ε ≤ 0 or a non-finite value.
    pub fn from_nodes(
        group: &str,
        nodes: Vec<ContactNode>,
        eps: f64,
    ) -> Result<ContactSurface, ContactError> {
        check_parameters(0.0, 0.0, eps)?;
        Ok(ContactSurface {
            group: group.to_string(),
            parts: vec![SurfacePart {
                group: group.to_string(),
                nodes: 0..nodes.len(),
            }],
            nodes,
            excluded: Vec::new(),
            revision: 0,
            law: FrictionLaw { eps },
            foundation: Vec::new(),
            weakening: Vec::new(),
            node_eps: Vec::new(),
            compliance: Vec::new(),
        })
    }

    /// Number of friction-carrying nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when no node carries friction.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// True when some node's friction can act: w_J g_J > 0. A surface
    /// where μ = 0 or the pressure is 0 carries none (σ_T = −g φ_ε(v_T) is
    /// 0 whatever v_T), and a run needs none of its friction code.
    pub fn carries_friction(&self) -> bool {
        self.nodes.iter().any(|n| n.force_scale() != 0.0)
    }

    /// True when every tangent is along x or y, so the damping matrix C is
    /// diagonal (DESIGN.md: a straight axis-aligned contact line keeps C
    /// diagonal).
    pub fn is_axis_aligned(&self) -> bool {
        self.nodes
            .iter()
            .all(|n| n.tangent[0].abs() < 1e-14 || n.tangent[1].abs() < 1e-14)
    }

    /// Classifies every node from a free-DOF velocity vector.
    pub fn classify(&self, velocity: &[f64], classes: &mut [SlipState]) {
        for (j, (n, c)) in self.nodes.iter().zip(classes.iter_mut()).enumerate() {
            *c = self
                .law_of(j)
                .classify(self.slip(j, n.tangential(velocity)));
        }
    }

    /// Nodal friction force magnitudes f_J = w_J g_J φ_ε(v_TJ) along τ_J
    /// (the friction force vector is J = Σ f_J τ_J, paper eq. (4.5)).
    pub fn nodal_forces(&self, velocity: &[f64], out: &mut [f64]) {
        for (j, (n, f)) in self.nodes.iter().zip(out.iter_mut()).enumerate() {
            let w = self.slip(j, n.tangential(velocity));
            *f = n.force(&self.law_of(j), w) * self.factor(j, w);
        }
    }

    /// Subtracts the friction force vector J = Σ f_J τ_J of nodal forces
    /// `forces` (as [`ContactSurface::nodal_forces`] gives them) from a
    /// right-hand side on free DOFs; nodes with f_J = 0 leave it as it was.
    pub fn subtract_forces(&self, forces: &[f64], rhs: &mut [f64]) {
        for (n, &f) in self.nodes.iter().zip(forces) {
            if f != 0.0 {
                n.subtract_along_tangent(f, rhs);
            }
        }
    }

    /// Friction stress σ_T = −g φ_ε(v_T) at each node (paper eq. (4.10)),
    /// by [`ContactSurface::stress`].
    pub fn friction_stress(&self, velocity: &[f64], out: &mut [f64]) {
        for (j, (n, s)) in self.nodes.iter().zip(out.iter_mut()).enumerate() {
            let w = self.slip(j, n.tangential(velocity));
            *s = self.stress(j, w) * self.factor(j, w);
        }
    }

    /// σ_T = −g φ_ε(w) of `node` at slip `w` (v_T where the foundation is
    /// at rest), +0 where w = 0 (−g · 0 is −0, which printed as "-0.000").
    pub fn stress(&self, j: usize, v_t: f64) -> f64 {
        -self.nodes[j].bound * self.law_of(j).phi(v_t) + 0.0
    }

    /// Adds the damping of stuck nodes, w g/ε ττᵀ (METHOD.md §3, C of
    /// J = C ṙ + F), through `add(j, a, b, value)` for node j's components
    /// a, b where both are free.
    pub fn add_damping(
        &self,
        classes: &[SlipState],
        mut add: impl FnMut(usize, usize, usize, f64),
    ) {
        for (j, (n, c)) in self.nodes.iter().zip(classes).enumerate() {
            if !c.is_stuck() {
                continue;
            }
            let k = n.stuck_damping(&self.law_of(j));
            for a in 0..2 {
                for b in 0..2 {
                    if n.dofs[a].is_some() && n.dofs[b].is_some() {
                        add(j, a, b, k * n.tangent[a] * n.tangent[b]);
                    }
                }
            }
        }
    }

    /// Subtracts the slip forces F = Σ w g sign(w) τ of slipping nodes from a
    /// right-hand side on free DOFs (F moves to the right as −F). A stuck
    /// node on a moving foundation has the force (w g/ε)(v_T − V) τ, whose
    /// part −(w g/ε) V τ is constant: it moves to the right as +(w g/ε) V τ.
    pub fn subtract_slip_forces(&self, classes: &[SlipState], rhs: &mut [f64]) {
        for (j, (n, c)) in self.nodes.iter().zip(classes).enumerate() {
            let f = if c.is_stuck() {
                let v = self.foundation_speed(j);
                if v == 0.0 {
                    continue;
                }
                -n.stuck_damping(&self.law_of(j)) * v
            } else {
                n.slip_force(*c)
            };
            n.subtract_along_tangent(f, rhs);
        }
    }

    /// The same nodes as unit nodes on n_c unknowns, one per node (node J's
    /// only DOF is J, its tangent x): the surface on which an iteration
    /// over the nodes' tangential velocities runs (the Schur complement
    /// step), with the same weights, bounds and law.
    pub fn on_tangential_unknowns(&self) -> ContactSurface {
        let nodes = self
            .nodes
            .iter()
            .enumerate()
            .map(|(j, node)| ContactNode {
                dofs: [Some(j), None],
                tangent: [1.0, 0.0],
                ..*node
            })
            .collect();
        ContactSurface {
            group: self.group.clone(),
            nodes,
            parts: self.parts.clone(),
            excluded: Vec::new(),
            revision: self.revision,
            law: self.law,
            foundation: self.foundation.clone(),
            weakening: self.weakening.clone(),
            node_eps: self.node_eps.clone(),
            compliance: self.compliance.clone(),
        }
    }

    /// Joins surfaces built apart into one set of friction nodes, surface
    /// after surface, each node keeping its own bound.
    ///
    /// # Errors
    /// No surface, or a node that carries friction on two surfaces
    /// (counted twice, and with two tangents). Surfaces of different ε
    /// keep each its own per node (`regularization.rs`).
    pub fn join(surfaces: Vec<ContactSurface>) -> Result<ContactSurface, ContactError> {
        let mut iter = surfaces.into_iter();
        let Some(mut joined) = iter.next() else {
            return Err(ContactError::Parameter("no contact surface to join".into()));
        };
        for s in iter {
            // Only nodes that carry friction count: a node a support holds
            // still on both surfaces carries none on either.
            let mine: std::collections::HashSet<usize> = s.nodes.iter().map(|n| n.node).collect();
            for part in &joined.parts {
                let theirs = &joined.nodes[part.nodes.clone()];
                if let Some(n) = theirs.iter().find(|n| mine.contains(&n.node)) {
                    return Err(ContactError::Overlap {
                        node: n.node,
                        first: part.group.clone(),
                        second: s.group.clone(),
                    });
                }
            }
            joined.join_eps(&s);
            let (start, added) = (joined.nodes.len(), s.nodes.len());
            join_per_node(&mut joined.foundation, start, &s.foundation, added, 0.0);
            join_per_node(&mut joined.weakening, start, &s.weakening, added, None);
            joined
                .compliance
                .extend(s.compliance.iter().map(|c| CompliantNode {
                    index: c.index + start,
                    ..*c
                }));
            joined.parts.push(SurfacePart {
                group: s.group,
                nodes: start..start + s.nodes.len(),
            });
            joined.nodes.extend(s.nodes);
            joined.excluded.extend(s.excluded);
        }
        Ok(joined)
    }

    /// The surfaces' groups for a message: `"contact"`, or `"contact" +
    /// "support"` for several.
    pub fn names(&self) -> String {
        let names: Vec<String> = self
            .parts
            .iter()
            .map(|p| format!("{:?}", p.group))
            .collect();
        names.join(" + ")
    }

    /// The surface (index into [`ContactSurface::parts`]) of each node.
    pub fn part_of_nodes(&self) -> Vec<usize> {
        let mut out = vec![0; self.nodes.len()];
        for (k, p) in self.parts.iter().enumerate() {
            out[p.nodes.clone()].iter_mut().for_each(|o| *o = k);
        }
        out
    }

    /// Sets node j's bound g_J to `bound(j)` for every node, and counts a
    /// revision when any changed.
    pub fn set_bounds(&mut self, mut bound: impl FnMut(usize) -> f64) {
        let mut changed = false;
        for (j, n) in self.nodes.iter_mut().enumerate() {
            let g = bound(j);
            changed |= g.to_bits() != n.bound.to_bits();
            n.bound = g;
        }
        if changed {
            self.revision += 1;
        }
    }
}

fn check_parameters(pressure: f64, mu: f64, eps: f64) -> Result<(), ContactError> {
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(ContactError::Parameter(format!(
            "eps = {eps}: the regularization ε must be a positive velocity (the paper uses 1e-4 to 1)"
        )));
    }
    if !(mu >= 0.0 && mu.is_finite()) {
        return Err(ContactError::Parameter(format!(
            "mu = {mu}: the friction coefficient must be ≥ 0"
        )));
    }
    if !pressure.is_finite() {
        return Err(ContactError::Parameter(format!(
            "pressure = {pressure} is not finite"
        )));
    }
    Ok(())
}

/// Joins a per-node list that is empty where every node has `rest` (a
/// foundation at rest, a constant μ): `mine` of `my_len` nodes, then
/// `theirs` of `their_len`, kept empty where both are.
fn join_per_node<T: Clone>(
    mine: &mut Vec<T>,
    my_len: usize,
    theirs: &[T],
    their_len: usize,
    rest: T,
) {
    if mine.is_empty() && theirs.is_empty() {
        return;
    }
    mine.resize(my_len, rest.clone());
    if theirs.is_empty() {
        mine.resize(my_len + their_len, rest);
    } else {
        mine.extend_from_slice(theirs);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(group: &str, n: usize) -> ContactSurface {
        let nodes = (0..n)
            .map(|j| ContactNode {
                node: j + 10 * group.len(),
                dofs: [Some(2 * j), Some(2 * j + 1)],
                weight: 1.0,
                tangent: [1.0, 0.0],
                s: j as f64,
                bound: 1.0,
            })
            .collect();
        ContactSurface::from_nodes(group, nodes, 1e-3).unwrap()
    }

    /// A later surface's foundation speeds survive a join after one at
    /// rest, and an earlier one's are kept beside a later one at rest.
    #[test]
    fn joined_surfaces_keep_each_one_s_foundation_speeds() {
        let mut belt = surface("belt", 2);
        belt.set_foundation(|_| 0.5);
        let joined = ContactSurface::join(vec![surface("floor", 3), belt.clone()]).unwrap();
        assert_eq!(joined.foundation, vec![0.0, 0.0, 0.0, 0.5, 0.5]);
        let joined = ContactSurface::join(vec![belt, surface("floor", 3)]).unwrap();
        assert_eq!(joined.foundation, vec![0.5, 0.5, 0.0, 0.0, 0.0]);
        let rest = ContactSurface::join(vec![surface("a", 1), surface("bb", 1)]).unwrap();
        assert!(rest.foundation.is_empty() && rest.weakening.is_empty());
    }
}
