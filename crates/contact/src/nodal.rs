//! The nodal friction of a step whose operator is diagonal, D = m·s with m
//! the lumped mass and s a scale (1/(γΔt) for the explicit scheme, METHOD.md
//! §4): solved in closed form node by node, and as the linear system that
//! the iteration of §5 solves for given classes.
//!
//! Per contact node J with tangent τ, t = τ·ṙ solves t + c φ_ε(t) = p, with
//! p = τᵀD⁻¹b and c = w_J g_J τᵀD⁻¹τ ([`FrictionLaw::solve_nodal`]), and
//! then ṙ = D⁻¹(b − w_J g_J φ_ε(t) τ) at the node's DOFs. Everything but b
//! is fixed while D is: D⁻¹, τ/d, w g τ/d, c and the stuck factor
//! 1/(1 + c/ε) are formed once per D, so that a step divides nowhere.
//! Products by these reciprocals round differently from the quotients, to
//! within rounding.

use crate::foundation::split_work;
use crate::iteration::StepSystem;
use crate::law::{FrictionLaw, SlipState};
use crate::surface::{ContactNode, ContactSurface};

/// The constants of one contact node for one D.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// The node (DOFs, tangent, w g for the ledger).
    node: ContactNode,
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
    /// The foundation's speed V (METHOD.md §9), 0 at rest.
    foundation: f64,
    /// The fall of μ with the slip speed, `None` for the constant law.
    weakening: Option<crate::Weakening>,
    /// The law with the node's ε, and 1/ε.
    law: FrictionLaw,
    inv_eps: f64,
}

/// The closed-form nodal friction of a diagonal step, its constants formed
/// for the last D.
#[derive(Clone, Debug, Default)]
pub struct NodalClosedForm {
    /// The bits of the scale and the surface's bounds revision the
    /// constants are for (None: not formed).
    scale: Option<(u64, u64)>,
    nodes: Vec<Node>,
    /// The nodes' free DOFs in the order [`NodalClosedForm::velocities`]
    /// asks for b there.
    dofs: Vec<usize>,
}

impl NodalClosedForm {
    /// Forms the constants for D = `mass`·`scale` (`mass` per free DOF)
    /// unless they are formed for this scale and these bounds already (a
    /// bound that changes in time forms them again at each change only).
    pub fn prepare(&mut self, surface: &ContactSurface, mass: &[f64], scale: f64) {
        let key = (scale.to_bits(), surface.revision);
        if self.scale == Some(key) && self.nodes.len() == surface.nodes.len() {
            // A foundation's speed may change every step; it forms nothing.
            if !surface.foundation.is_empty() {
                for (j, node) in self.nodes.iter_mut().enumerate() {
                    node.foundation = surface.foundation_speed(j);
                }
            }
            return;
        }
        self.nodes.clear();
        self.dofs.clear();
        for (j, node) in surface.nodes.iter().enumerate() {
            let law = surface.law_of(j);
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
                node: *node,
                a,
                inv_d,
                w,
                c,
                stuck: law.stuck_factor(c),
                foundation: surface.foundation_speed(j),
                weakening: surface.weakening_of(j),
                law,
                inv_eps: 1.0 / law.eps,
            });
        }
        self.scale = Some(key);
    }

    /// The contact nodes' free DOFs, node by node: the k-th is the one
    /// [`NodalClosedForm::velocities`] asks b for in its k-th call.
    pub fn dofs(&self) -> &[usize] {
        &self.dofs
    }

    /// Calls `out(node, component, dof, ṙ)` for every free DOF of every
    /// contact node, given `b(dof, k)` = b there, the k-th contact DOF in
    /// node order. [`NodalClosedForm::prepare`] first.
    #[inline]
    pub fn velocities(
        &self,
        mut b: impl FnMut(usize, usize) -> f64,
        mut out: impl FnMut(usize, usize, usize, f64),
    ) {
        let mut k = 0;
        for (j, node) in self.nodes.iter().enumerate() {
            let law = node.law;
            let dofs = &node.node.dofs;
            let mut bj = [0.0; 2];
            let mut p = 0.0;
            for c in 0..2 {
                if let Some(i) = dofs[c] {
                    bj[c] = b(i, k);
                    k += 1;
                    p += node.a[c] * bj[c];
                }
            }
            // The slip w = t − V solves w + c φ_ε(w) = p − V (METHOD.md §9);
            // p − 0 is p, so a foundation at rest moves no bit.
            let phi = match node.weakening {
                None => {
                    let w = law.solve_nodal_by(p - node.foundation, node.c, node.stuck);
                    law.class_and_phi_by_reciprocal(w, node.inv_eps).1
                }
                // μ(|w|)/μs times φ_ε(w), on the root mu_speed.rs chooses.
                Some(k) => {
                    let w = k.solve_nodal(&law, p - node.foundation, node.c);
                    law.phi(w) * k.factor(w.abs())
                }
            };
            for c in 0..2 {
                if let Some(i) = dofs[c] {
                    out(j, c, i, bj[c] * node.inv_d[c] - phi * node.w[c]);
                }
            }
        }
    }

    /// The step's friction ledger in one pass over the nodes, with the bits
    /// of [`ContactSurface::classify`], [`ContactSurface::step_dissipation`]
    /// and [`stick_events`](crate::stick_events): the classes of `v_new`
    /// into `classes`, the forces f_J into `forces`, and (the work
    /// dissipated from `v` to `v_new` over `dt`, the foundation's work over
    /// it, the slip → stick events against `old`).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn ledger(
        &self,
        v_new: &[f64],
        v: &[f64],
        dt: f64,
        old: &[SlipState],
        classes: &mut [SlipState],
        forces_old: &[f64],
        forces: &mut [f64],
    ) -> (f64, f64, usize) {
        let (mut dissipated, mut foundation, mut events) = (0.0, 0.0, 0);
        for ((((node, class), f), f_old), was) in self
            .nodes
            .iter()
            .zip(classes.iter_mut())
            .zip(forces.iter_mut())
            .zip(forces_old)
            .zip(old)
        {
            let (vt, increment) = node.node.motion(v_new, v, dt);
            let w = vt - node.foundation;
            (*class, *f) = node.node.class_and_force(&node.law, w);
            if let Some(k) = node.weakening {
                *f *= k.factor(w.abs());
            }
            let (d, w) = split_work(*f, *f_old, increment, node.foundation, dt);
            dissipated += d;
            foundation += w;
            events += usize::from(class.sticks_after(*was));
        }
        (dissipated, foundation, events)
    }
}

/// The linear system of a diagonal step for given classes, (D + C) ṙ = b − F
/// with D diagonal: solved node by node, a stuck node's 2×2 block
/// D + k ττᵀ by Sherman-Morrison. The iteration of §5 on it converges to
/// what [`NodalClosedForm`] finds directly.
#[derive(Debug)]
pub struct DiagonalStep<'a> {
    /// D per free DOF.
    pub diagonal: &'a [f64],
    /// b, the right-hand side without friction.
    pub b: &'a [f64],
}

impl StepSystem for DiagonalStep<'_> {
    type Error = std::convert::Infallible;

    fn solve(
        &mut self,
        surface: &ContactSurface,
        classes: &[SlipState],
        velocity: &mut [f64],
    ) -> Result<(), Self::Error> {
        velocity.copy_from_slice(self.b);
        surface.subtract_slip_forces(classes, velocity);
        for (v, d) in velocity.iter_mut().zip(self.diagonal) {
            *v /= d;
        }
        for (j, (n, c)) in surface.nodes.iter().zip(classes).enumerate() {
            if !c.is_stuck() {
                continue;
            }
            let k = n.stuck_damping(&surface.law_of(j));
            // (D + k ττᵀ)⁻¹ r = D⁻¹r − D⁻¹τ k (τᵀD⁻¹r) / (1 + k τᵀD⁻¹τ).
            let mut t_dinv_r = 0.0;
            let mut t_dinv_t = 0.0;
            for a in 0..2 {
                if let Some(i) = n.dofs[a] {
                    t_dinv_r += n.tangent[a] * velocity[i];
                    t_dinv_t += n.tangent[a] * n.tangent[a] / self.diagonal[i];
                }
            }
            let factor = k * t_dinv_r / (1.0 + k * t_dinv_t);
            for a in 0..2 {
                if let Some(i) = n.dofs[a] {
                    velocity[i] -= factor * n.tangent[a] / self.diagonal[i];
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{iterate, stick_events, IterationOptions};

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

    /// A small deterministic generator (SplitMix64), so the random cases
    /// are the same on every run.
    struct Random(u64);

    impl Random {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// Uniform in [0, 1).
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
        /// Uniform in [lo, hi).
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        /// 10^x for x uniform in [lo, hi).
        fn log(&mut self, lo: f64, hi: f64) -> f64 {
            10f64.powf(self.range(lo, hi))
        }
    }

    /// The ledger against the surface's own passes, bit for bit: the
    /// classes (`classify`), the forces and dissipation
    /// (`step_dissipation`, and the sum written out here) and the slip →
    /// stick events (`stick_events`), on stuck and slipping nodes of both
    /// signs, a fixed component, tilted tangents, and old classes that make
    /// events and not.
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
        let mut nodal = NodalClosedForm::default();
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
                let mut surface_forces = vec![0.0; 5];
                let (surface_dissipated, _) =
                    contact.step_dissipation(&v_new, &v, dt, &forces_old, &mut surface_forces);
                assert_eq!(surface_dissipated.to_bits(), dissipated.to_bits());
                assert_eq!(surface_forces, forces);
                let events = classes
                    .iter()
                    .zip(&old)
                    .filter(|(c, o)| c.is_stuck() && !o.is_stuck())
                    .count();
                assert_eq!(stick_events(&old, &classes), events);
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
                assert_eq!(got.1.to_bits(), 0f64.to_bits(), "amp {amp}");
                assert_eq!(got.2, events, "amp {amp}");
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

    /// The stored-constant form against the closed form written with
    /// quotients (p/(1 + c/ε), v/ε, b/d), to 1e-14 of the terms it
    /// subtracts (a few roundings), on stuck and slipping nodes of both
    /// signs, a node with a fixed component and tilted tangents; and the
    /// constants formed anew when D changes.
    #[test]
    fn velocities_match_the_closed_form_by_quotients() {
        let (eps, n) = (1e-3, 8);
        let law = FrictionLaw { eps };
        let tilt = (0.6f64, 0.8f64);
        let nodes = vec![
            node(0, [Some(0), Some(1)], [1.0, 0.0]),
            node(1, [Some(2), None], [1.0, 0.0]),
            node(2, [Some(3), Some(4)], [tilt.0, tilt.1]),
            node(3, [Some(5), Some(6)], [-tilt.1, tilt.0]),
        ];
        let contact = ContactSurface::from_nodes("bottom", nodes, eps).unwrap();
        let mass: Vec<f64> = (0..n).map(|i| 0.25 + 0.05 * i as f64).collect();
        let mut nodal = NodalClosedForm::default();
        let (mut stuck, mut slip_pos, mut slip_neg) = (0, 0, 0);
        for dt in [1e-3, 5e-4, 1e-3] {
            let scale = 1.0 / (0.5 * dt);
            nodal.prepare(&contact, &mass, scale);
            // b from tiny (stuck) to large of either sign (slipping).
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
                    let c = wg * q;
                    let t = if (p / (1.0 + c / eps)).abs() <= eps {
                        p / (1.0 + c / eps)
                    } else {
                        p - c * p.signum()
                    };
                    let phi = if t.abs() <= eps { t / eps } else { t.signum() };
                    match law.classify(t) {
                        SlipState::Stuck => stuck += 1,
                        SlipState::SlipPositive => slip_pos += 1,
                        SlipState::SlipNegative => slip_neg += 1,
                    }
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

    /// The closed form against the iteration of §5 on the same diagonal
    /// system ([`DiagonalStep`]), on random surfaces: weights, bounds,
    /// tangents at any angle (a node with one component fixed among them),
    /// lumped masses, Δt, ε over 1e-6..1 and right-hand sides from deep in
    /// the stuck set to far beyond the slip bound, the iteration started
    /// from random classes. The regularized step has one solution
    /// (METHOD.md §5), so the two agree up to rounding: both form ṙ_i as
    /// b_i/d_i minus a friction term of size at most w g/d_i, in a handful
    /// of operations each (products by stored reciprocals against
    /// quotients and Sherman-Morrison), so 64 ulps of |b_i|/d_i + w g/d_i
    /// bounds their difference with room to spare. The closed form also
    /// satisfies the nodal equation D ṙ + w g φ_ε(τ·ṙ) τ = b, to the
    /// residual of a ṙ off by that tolerance (D + (w g/ε) ττᵀ times it on
    /// a stuck node, where φ_ε has slope 1/ε).
    #[test]
    fn closed_form_is_what_the_iteration_converges_to() {
        let mut rng = Random(0x5EED_CAFE);
        let (mut stuck, mut slipping) = (0, 0);
        for case in 0..400 {
            let n_nodes = 1 + (rng.next() % 6) as usize;
            let mut nodes = Vec::new();
            let mut n_dofs = 0;
            for j in 0..n_nodes {
                let angle = rng.range(-std::f64::consts::PI, std::f64::consts::PI);
                let tangent = [angle.cos(), angle.sin()];
                // One node in five has a component fixed (a roller), the
                // other one along the tangent by at least 0.2.
                let dofs = if rng.next().is_multiple_of(5) && tangent[0].abs() > 0.2 {
                    n_dofs += 1;
                    [Some(n_dofs - 1), None]
                } else {
                    n_dofs += 2;
                    [Some(n_dofs - 2), Some(n_dofs - 1)]
                };
                nodes.push(ContactNode {
                    node: j,
                    dofs,
                    weight: rng.log(-2.0, 0.0),
                    tangent,
                    s: j as f64,
                    bound: rng.log(-1.0, 2.0),
                });
            }
            let eps = rng.log(-6.0, 0.0);
            let surface = ContactSurface::from_nodes("random", nodes, eps).unwrap();
            let mass: Vec<f64> = (0..n_dofs).map(|_| rng.log(-3.0, 0.0)).collect();
            let dt = rng.log(-5.0, -2.0);
            let scale = 1.0 / (0.5 * dt);
            let diagonal: Vec<f64> = mass.iter().map(|m| m * scale).collect();
            // |b| against w g: ratios from 1e-8 (deeply stuck) to 1e3.
            let amp = rng.log(-8.0, 3.0);
            let wg_max = surface
                .nodes
                .iter()
                .map(ContactNode::force_scale)
                .fold(0.0, f64::max);
            let b: Vec<f64> = (0..n_dofs)
                .map(|_| amp * wg_max * rng.range(-1.0, 1.0))
                .collect();

            let mut closed = NodalClosedForm::default();
            closed.prepare(&surface, &mass, scale);
            let mut direct = vec![f64::NAN; n_dofs];
            closed.velocities(|i, _| b[i], |_, _, i, v| direct[i] = v);

            let mut classes: Vec<SlipState> = (0..n_nodes)
                .map(|_| match rng.next() % 3 {
                    0 => SlipState::Stuck,
                    1 => SlipState::SlipPositive,
                    _ => SlipState::SlipNegative,
                })
                .collect();
            let mut scratch = classes.clone();
            let mut iterated = vec![0.0; n_dofs];
            let mut system = DiagonalStep {
                diagonal: &diagonal,
                b: &b,
            };
            iterate(
                &surface,
                &mut system,
                &mut classes,
                &mut scratch,
                &mut iterated,
                IterationOptions::default(),
            )
            .unwrap_or_else(|e| panic!("case {case}: {e:?}"));

            for (n, class) in surface.nodes.iter().zip(&classes) {
                match class {
                    SlipState::Stuck => stuck += 1,
                    _ => slipping += 1,
                }
                let tol = n.dofs.map(|d| {
                    d.map_or(0.0, |i| {
                        64.0 * f64::EPSILON * (b[i].abs() + n.force_scale()) / diagonal[i]
                    })
                });
                for c in 0..2 {
                    let Some(i) = n.dofs[c] else { continue };
                    let gap = (direct[i] - iterated[i]).abs();
                    assert!(
                        gap <= tol[c],
                        "case {case}, dof {i}: closed form {} vs iterated {}",
                        direct[i],
                        iterated[i]
                    );
                }
                // The residual of ṙ off by tol: (D + k ττᵀ) tol with k the
                // stuck damping w g/ε (φ_ε's slope there), 0 slipping.
                let k = if class.is_stuck() {
                    n.stuck_damping(&surface.law)
                } else {
                    0.0
                };
                let spread = n.tangent[0].abs() * tol[0] + n.tangent[1].abs() * tol[1];
                let f = n.force(&surface.law, n.tangential(&direct));
                for c in 0..2 {
                    let Some(i) = n.dofs[c] else { continue };
                    let residual = diagonal[i] * direct[i] + f * n.tangent[c] - b[i];
                    let bound = diagonal[i] * tol[c] + k * n.tangent[c].abs() * spread;
                    assert!(
                        residual.abs() <= bound,
                        "case {case}, dof {i}: residual {residual} > {bound}"
                    );
                }
            }
        }
        // Both branches of the law, many times each.
        assert!(
            stuck > 100 && slipping > 100,
            "{stuck} stuck, {slipping} slipping"
        );
    }
}
