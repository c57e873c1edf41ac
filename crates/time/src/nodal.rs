//! The explicit step's closed-form nodal friction (METHOD.md §4, the
//! central-difference scheme) with its constants formed once per Δt.
//!
//! Per contact node J, with D = M_L/(γΔt) (diagonal) and τ its tangent,
//! t = τ·ṙ_K solves t + c φ_ε(t) = p, p = τᵀD⁻¹b, c = w_J g_J τᵀD⁻¹τ, and
//! then ṙ_K = D⁻¹(b − w_J g_J φ_ε(t) τ) at the node's DOFs. Everything but
//! b is fixed while Δt is: D⁻¹, τ/d, w g τ/d, c and the stuck factor
//! 1/(1 + c/ε) are formed here once per Δt, so that a step does no division
//! at all (before, nine per node: the paper mesh's explicit step took 1.394
//! µs with them, 1.275 µs without, medians of ten alternating bench_step
//! runs, 2026-11-24). Products by reciprocals round differently from the
//! quotients, within rounding; the test against the iterated friction
//! (`tests/paper.rs`) holds the two to 1e-12.

use stickslip_contact::{ContactSurface, SlipState};

use stickslip_linalg::Product;

/// The constants of one contact node for one Δt.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Free DOFs of the node (`None` = fixed).
    dofs: [Option<usize>; 2],
    /// τ_c/d_c (p = Σ a_c b_c).
    a: [f64; 2],
    /// 1/d_c.
    inv_d: [f64; 2],
    /// w g τ_c/d_c.
    w: [f64; 2],
    /// c = w g τᵀD⁻¹τ.
    c: f64,
    /// 1/(1 + c/ε): the stuck root is p times this.
    stuck: f64,
    /// τ and w g, for the classes, forces and dissipation (`ledger`).
    tangent: [f64; 2],
    force_scale: f64,
}

/// The closed-form nodal friction of the explicit step.
#[derive(Clone, Debug, Default)]
pub(crate) struct NodalFriction {
    /// The bits of 1/(γΔt) the constants are for (None: not formed).
    scale: Option<u64>,
    eps: f64,
    inv_eps: f64,
    nodes: Vec<Node>,
    /// The nodes' free DOFs in the order [`NodalFriction::velocities`]
    /// asks `b` for them, and a slot per DOF for K r_K there
    /// ([`NodalFriction::products`]).
    dofs: Vec<usize>,
    ku: Vec<f64>,
}

impl NodalFriction {
    /// Forms the constants for D = `mass`·`scale` unless they are formed
    /// for this scale already.
    pub(crate) fn prepare(&mut self, contact: &ContactSurface, mass: &[f64], scale: f64) {
        if self.scale == Some(scale.to_bits()) && self.nodes.len() == contact.nodes.len() {
            return;
        }
        let eps = contact.law.eps;
        self.eps = eps;
        self.inv_eps = 1.0 / eps;
        self.nodes.clear();
        self.dofs.clear();
        for node in &contact.nodes {
            self.dofs.extend(node.dofs.iter().flatten());
            let wg = node.force_scale();
            let (mut a, mut inv_d, mut w, mut q) = ([0.0; 2], [0.0; 2], [0.0; 2], 0.0);
            for c in 0..2 {
                if let Some(i) = node.dofs[c] {
                    inv_d[c] = 1.0 / (mass[i] * scale);
                    a[c] = node.tangent[c] * inv_d[c];
                    w[c] = wg * a[c];
                    q += node.tangent[c] * a[c];
                }
            }
            let c = wg * q;
            self.nodes.push(Node {
                dofs: node.dofs,
                a,
                inv_d,
                w,
                c,
                stuck: 1.0 / (1.0 + c / eps),
                tangent: node.tangent,
                force_scale: wg,
            });
        }
        self.ku.resize(self.dofs.len(), 0.0);
        self.scale = Some(scale.to_bits());
    }

    /// K x at the contact nodes' free DOFs (`b`'s k-th call in
    /// [`NodalFriction::velocities`] is for `self.products()[k]`), with the
    /// bits the product's batches give them. [`NodalFriction::prepare`]
    /// first.
    pub(crate) fn form_products(&mut self, k: &Product, x: &[f64]) {
        for (o, &i) in self.ku.iter_mut().zip(&self.dofs) {
            *o = k.row(i, x);
        }
    }

    /// What [`NodalFriction::form_products`] formed.
    pub(crate) fn products(&self) -> &[f64] {
        &self.ku
    }

    /// Calls `out(node, component, dof, ṙ_K)` for every free DOF of every
    /// contact node, given `b(dof, k)` = R̂_K there, the k-th contact DOF
    /// in node order. [`NodalFriction::prepare`] first.
    #[inline]
    pub(crate) fn velocities(
        &self,
        mut b: impl FnMut(usize, usize) -> f64,
        mut out: impl FnMut(usize, usize, usize, f64),
    ) {
        let (eps, inv_eps) = (self.eps, self.inv_eps);
        let mut k = 0;
        for (j, node) in self.nodes.iter().enumerate() {
            let mut bj = [0.0; 2];
            let mut p = 0.0;
            for c in 0..2 {
                if let Some(i) = node.dofs[c] {
                    bj[c] = b(i, k);
                    k += 1;
                    p += node.a[c] * bj[c];
                }
            }
            // FrictionLaw::solve_nodal and ::phi with the stored factors.
            let stuck = p * node.stuck;
            let t = if stuck.abs() <= eps {
                stuck
            } else {
                p - node.c * p.signum()
            };
            let phi = if t > eps {
                1.0
            } else if t < -eps {
                -1.0
            } else {
                t * inv_eps
            };
            for c in 0..2 {
                if let Some(i) = node.dofs[c] {
                    out(j, c, i, bj[c] * node.inv_d[c] - phi * node.w[c]);
                }
            }
        }
    }

    /// The step's friction ledger in one pass over the nodes, with the bits
    /// of `ContactSurface::classify`, `::nodal_forces` and the integrator's
    /// dissipation sum (before, three passes through the surface; removing
    /// them altogether made the paper mesh's explicit step 7% faster, this
    /// pass 2.6%): the classes of ṙ_K into `classes`, the forces f_J into
    /// `forces`, and (Σ_J ½(f_J + f_J,old) τ_J·½Δt(ṙ_K + ṙ_{K−1}), the
    /// slip → stick events against `old`).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn ledger(
        &self,
        v_new: &[f64],
        v: &[f64],
        dt: f64,
        old: &[SlipState],
        classes: &mut [SlipState],
        forces_old: &[f64],
        forces: &mut [f64],
    ) -> (f64, usize) {
        let eps = self.eps;
        let (mut dissipated, mut events) = (0.0, 0);
        for ((((node, class), f), f_old), was) in self
            .nodes
            .iter()
            .zip(classes.iter_mut())
            .zip(forces.iter_mut())
            .zip(forces_old)
            .zip(old)
        {
            let (mut vt, mut increment) = (0.0, 0.0);
            for k in 0..2 {
                if let Some(i) = node.dofs[k] {
                    vt += node.tangent[k] * v_new[i];
                    increment += node.tangent[k] * (0.5 * dt * (v_new[i] + v[i]));
                }
            }
            // FrictionLaw::classify and ::phi.
            let (c, phi) = if vt > eps {
                (SlipState::SlipPositive, 1.0)
            } else if vt < -eps {
                (SlipState::SlipNegative, -1.0)
            } else {
                (SlipState::Stuck, vt / eps)
            };
            *class = c;
            *f = node.force_scale * phi;
            dissipated += 0.5 * (*f + f_old) * increment;
            events += usize::from(c.is_stuck() && !was.is_stuck());
        }
        (dissipated, events)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stickslip_contact::{ContactNode, SlipState};

    /// A test contact node: weight and bound vary with j.
    fn node(j: usize, dofs: [Option<usize>; 2], tangent: [f64; 2]) -> ContactNode {
        ContactNode {
            node: j,
            dofs,
            weight: 0.5 + 0.1 * j as f64,
            tangent,
            s: j as f64,
            bound: 2.0 + j as f64,
        }
    }

    /// `ledger` against the surface's own passes, bit for bit: the classes
    /// (`classify`), the forces (`nodal_forces`) and the dissipation and
    /// slip → stick events as `Integrator::friction_ledger` sums them, on
    /// stuck and slipping nodes of both signs, a fixed component, tilted
    /// tangents, and old classes that make events and not.
    #[test]
    fn ledger_matches_the_surfaces_passes() {
        let eps = 1e-3;
        let nodes = vec![
            node(0, [Some(0), Some(1)], [1.0, 0.0]),
            node(1, [Some(2), None], [1.0, 0.0]),
            node(2, [Some(3), Some(4)], [0.6, 0.8]),
            node(3, [None, Some(5)], [-0.8, 0.6]),
            node(4, [Some(6), Some(7)], [-0.8, 0.6]),
        ];
        let contact = ContactSurface::from_nodes("bottom", nodes, eps).unwrap();
        let mass = vec![1.0; 8];
        let mut nodal = NodalFriction::default();
        nodal.prepare(&contact, &mass, 2e3);
        let dt = 1e-3;
        let mut seen = [false; 3];
        for amp in [1e-5, 4e-4, 3e-3, -2e-3, 0.0] {
            let v_new: Vec<f64> = (0..8).map(|i| amp * (1.0 - 0.37 * i as f64)).collect();
            let v: Vec<f64> = (0..8).map(|i| 1e-3 * (0.2 * i as f64 - 0.5)).collect();
            let forces_old: Vec<f64> = (0..5).map(|j| 0.3 - 0.2 * j as f64).collect();
            for old in [
                SlipState::Stuck,
                SlipState::SlipPositive,
                SlipState::SlipNegative,
            ] {
                let old = vec![old; 5];
                let mut classes = vec![SlipState::Stuck; 5];
                contact.classify(&v_new, &mut classes);
                let mut forces = vec![0.0; 5];
                contact.nodal_forces(&v_new, &mut forces);
                let mut dissipated = 0.0;
                for ((n, f), f_old) in contact.nodes.iter().zip(&forces).zip(&forces_old) {
                    let mut increment = 0.0;
                    for k in 0..2 {
                        if let Some(i) = n.dofs[k] {
                            increment += n.tangent[k] * (0.5 * dt * (v_new[i] + v[i]));
                        }
                    }
                    dissipated += 0.5 * (f + f_old) * increment;
                }
                let events = classes
                    .iter()
                    .zip(&old)
                    .filter(|(c, o)| c.is_stuck() && !o.is_stuck())
                    .count();
                let (mut got_classes, mut got_forces) = (vec![SlipState::Stuck; 5], vec![0.0; 5]);
                let got = nodal.ledger(
                    &v_new,
                    &v,
                    dt,
                    &old,
                    &mut got_classes,
                    &forces_old,
                    &mut got_forces,
                );
                assert_eq!(got_classes, classes, "amp {amp}");
                assert_eq!(
                    got_forces.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                    forces.iter().map(|f| f.to_bits()).collect::<Vec<_>>(),
                    "amp {amp}"
                );
                assert_eq!(got.0.to_bits(), dissipated.to_bits(), "amp {amp}");
                assert_eq!(got.1, events, "amp {amp}");
                for c in &classes {
                    seen[match c {
                        SlipState::Stuck => 0,
                        SlipState::SlipPositive => 1,
                        SlipState::SlipNegative => 2,
                    }] = true;
                }
            }
        }
        assert_eq!(seen, [true; 3], "stuck and slipping nodes of both signs");
    }

    /// The stored-constant form against FrictionLaw's own closed form
    /// (quotients, solve_nodal, phi) to rounding, on stuck and slipping
    /// nodes of both signs, a node with a fixed component and tilted
    /// tangents; and the constants formed anew when Δt changes.
    #[test]
    fn velocities_match_the_laws_closed_form() {
        let (eps, n) = (1e-3, 8);
        let tilt = (0.6f64, 0.8f64);
        let nodes = vec![
            node(0, [Some(0), Some(1)], [1.0, 0.0]),
            node(1, [Some(2), None], [1.0, 0.0]),
            node(2, [Some(3), Some(4)], [tilt.0, tilt.1]),
            node(3, [Some(5), Some(6)], [-tilt.1, tilt.0]),
        ];
        let contact = ContactSurface::from_nodes("bottom", nodes, eps).unwrap();
        let mass: Vec<f64> = (0..n).map(|i| 0.25 + 0.05 * i as f64).collect();
        let mut nodal = NodalFriction::default();
        let (mut stuck, mut slip_pos, mut slip_neg) = (0, 0, 0);
        for dt in [1e-3, 5e-4, 1e-3] {
            let scale = 1.0 / (0.5 * dt);
            nodal.prepare(&contact, &mass, scale);
            // R̂ from tiny (stuck) to large of either sign (slipping).
            for amp in [1e-9, 1e-6, 1e-3, 1.0, -1.0, 30.0, -30.0] {
                let b: Vec<f64> = (0..n).map(|i| amp * (1.0 + 0.3 * i as f64)).collect();
                let mut got = vec![f64::NAN; n];
                nodal.velocities(|i, _| b[i], |_, _, i, v| got[i] = v);
                for node in &contact.nodes {
                    let (mut p, mut q) = (0.0, 0.0);
                    for c in 0..2 {
                        if let Some(i) = node.dofs[c] {
                            let d = mass[i] * scale;
                            p += node.tangent[c] * b[i] / d;
                            q += node.tangent[c] * node.tangent[c] / d;
                        }
                    }
                    let wg = node.force_scale();
                    let t = contact.law.solve_nodal(p, wg * q);
                    match contact.law.classify(t) {
                        SlipState::Stuck => stuck += 1,
                        SlipState::SlipPositive => slip_pos += 1,
                        SlipState::SlipNegative => slip_neg += 1,
                    }
                    let phi = contact.law.phi(t);
                    for c in 0..2 {
                        if let Some(i) = node.dofs[c] {
                            let want = (b[i] - wg * phi * node.tangent[c]) / (mass[i] * scale);
                            let tol = 1e-14 * (b[i].abs() + wg) / (mass[i] * scale);
                            assert!(
                                (got[i] - want).abs() <= tol,
                                "dt {dt}, amp {amp}, dof {i}: {} vs {want}",
                                got[i]
                            );
                        }
                    }
                }
                // DOFs of no contact node are left alone.
                assert!(got[7].is_nan());
            }
        }
        assert!(
            stuck > 0 && slip_pos > 0 && slip_neg > 0,
            "{stuck} {slip_pos} {slip_neg}"
        );
    }
}
