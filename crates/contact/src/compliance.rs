//! Normal compliance against a rigid straight foundation (METHOD.md §10,
//! Oden and Martins 1985): the foundation pushes a node back with the
//! normal traction c_n δ^{m_n} and bounds its friction by c_T δ^{m_T}, δ
//! the node's approach into the foundation. The normal force depends on
//! the displacement only, so the explicit scheme adds it to the step's
//! force from the known r_K and sets the friction bound from the same δ.

use stickslip_fem::{boundary_quadrature, DofMap};
use stickslip_mesh::Mesh;

use crate::law::FrictionLaw;
use crate::surface::{ContactError, ContactNode, ContactSurface, SurfacePart};

/// The compliance law's constants: σ_n = c_n δ^{m_n}, g = c_T δ^{m_T}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compliance {
    /// c_n > 0.
    pub cn: f64,
    /// m_n ≥ 1.
    pub mn: f64,
    /// c_T ≥ 0.
    pub ct: f64,
    /// m_T ≥ 1.
    pub mt: f64,
}

/// x^m for x ≥ 0, with the common exponent 1 exact (no `powf` rounding) and
/// 0^m = 0.
#[inline]
fn power(x: f64, m: f64) -> f64 {
    if m == 1.0 {
        x
    } else if x == 0.0 {
        0.0
    } else {
        x.powf(m)
    }
}

impl Compliance {
    /// The normal traction c_n δ^{m_n} at approach `delta` ≥ 0.
    #[inline]
    pub fn traction(&self, delta: f64) -> f64 {
        self.cn * power(delta, self.mn)
    }

    /// The friction bound c_T δ^{m_T} at approach `delta` ≥ 0.
    #[inline]
    pub fn bound(&self, delta: f64) -> f64 {
        self.ct * power(delta, self.mt)
    }

    /// The tangent stiffness dσ_n/dδ = c_n m_n δ^{m_n−1} (per unit length),
    /// c_n at every δ for m_n = 1.
    #[inline]
    pub fn stiffness(&self, delta: f64) -> f64 {
        if self.mn == 1.0 {
            self.cn
        } else {
            self.cn * self.mn * power(delta, self.mn - 1.0)
        }
    }

    /// The friction bound's slope dg/dδ = c_T m_T δ^{m_T−1}, c_T at every
    /// δ for m_T = 1 (the implicit step's Newton matrix needs it).
    #[inline]
    pub fn bound_slope(&self, delta: f64) -> f64 {
        if self.mt == 1.0 {
            self.ct
        } else {
            self.ct * self.mt * power(delta, self.mt - 1.0)
        }
    }

    /// The stored energy per unit length, c_n δ^{m_n+1}/(m_n+1).
    #[inline]
    pub fn energy(&self, delta: f64) -> f64 {
        self.cn * power(delta, self.mn + 1.0) / (self.mn + 1.0)
    }

    /// The energy-consistent normal traction of a step (METHOD.md §10, the
    /// discrete gradient of Armero–Petocz and Laursen–Chawla) in the form
    /// the trapezoidal rule needs: for the signed approaches `a0` at the
    /// step's start and `a1` at its end (−(g₀ + ν·r), negative off the
    /// foundation), σ_dg = (Φ(a1₊) − Φ(a0₊))/(a1 − a0), Φ the stored energy
    /// per length, returns the trapezoid's defect D = 2σ_dg − σ(a0₊) −
    /// σ(a1₊) and 2∂σ_dg/∂a1 (the slope of σ(a1₊) + D). With D the mean of
    /// σ(a0₊) + … and σ(a1₊) + D is σ_dg, whose work over a1 − a0 is Φ's
    /// change exactly. D is 0 exactly off the foundation at both ends and
    /// for m_n = 1 in contact at both (σ linear there); a step short
    /// against its approach takes σ at the midpoint, as the divided
    /// difference would lose its digits to cancellation.
    pub fn energy_consistent(&self, a0: f64, a1: f64) -> (f64, f64) {
        let (d0, d1) = (a0.max(0.0), a1.max(0.0));
        if d0 == 0.0 && d1 == 0.0 {
            return (0.0, 0.0);
        }
        if self.mn == 1.0 && d0 > 0.0 && d1 > 0.0 {
            return (0.0, self.cn);
        }
        let step = a1 - a0;
        if step.abs() <= MIDPOINT * a0.abs().max(a1.abs()) {
            let mid = 0.5 * (d0 + d1);
            let defect = 2.0 * self.traction(mid) - self.traction(d0) - self.traction(d1);
            return (defect, self.stiffness(mid));
        }
        let mean = (self.energy(d1) - self.energy(d0)) / step;
        let defect = 2.0 * mean - self.traction(d0) - self.traction(d1);
        (defect, 2.0 * (self.traction(d1) - mean) / step)
    }
}

/// A step shorter than this fraction of its approach takes the traction at
/// its midpoint for the divided difference: the two differ by (Δ/a)² of
/// the traction, the divided difference's cancellation costs ε·a/Δ of it,
/// and the two meet near ε^{1/3}.
const MIDPOINT: f64 = 1e-5;

/// A node of a compliance surface: where it stands against the foundation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompliantNode {
    /// Its index in [`ContactSurface::nodes`].
    pub index: usize,
    /// The foundation's unit normal ν, pointing towards the body.
    pub normal: [f64; 2],
    /// The initial gap g₀ = (X_J − P)·ν (< 0: the node starts inside the
    /// foundation, an interference only a static start settles).
    pub gap: f64,
    /// The law.
    pub law: Compliance,
}

impl CompliantNode {
    /// The approach δ = max(0, −(g₀ + ν·r_J)) at free-DOF displacement `r`
    /// (a fixed component does not move).
    #[inline]
    pub fn approach(&self, node: &ContactNode, r: &[f64]) -> f64 {
        self.signed_approach(node, r).max(0.0)
    }

    /// ν·z_J: the share of the motion `z` (on free DOFs) along the
    /// foundation's normal at `node` (a fixed component does not move).
    #[inline]
    pub fn along_normal(&self, node: &ContactNode, z: &[f64]) -> f64 {
        // From −0.0, as a sum of no terms (a fixed node) is.
        self.plus_along_normal(-0.0, node, z)
    }

    /// −(g₀ + ν·r_J): the approach, negative off the foundation (by the
    /// gap).
    #[inline]
    pub fn signed_approach(&self, node: &ContactNode, r: &[f64]) -> f64 {
        -self.plus_along_normal(self.gap, node, r)
    }

    /// start + ν·z_J, the terms added to `start` in turn.
    #[inline]
    fn plus_along_normal(&self, start: f64, node: &ContactNode, z: &[f64]) -> f64 {
        let mut g = start;
        for c in 0..2 {
            if let Some(d) = node.dofs[c] {
                g += self.normal[c] * z[d];
            }
        }
        g
    }
}

/// What [`ContactSurface::comply`] found at one displacement.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Foundation {
    /// The stored energy Σ w_J c_n δ_J^{m_n+1}/(m_n+1).
    pub stored: f64,
    /// The largest nodal stiffness over mass of the step's operator,
    /// max_J w_J c_n m_n δ_J^{m_n−1} νᵀM_J⁻¹ν (0 where no mass is given):
    /// the term the contact adds to ω_max² at most (Weyl's inequality).
    pub stiffness_over_mass: f64,
    /// The node (index into [`ContactSurface::nodes`]) where it is largest.
    pub stiffest: usize,
    /// The largest approach.
    pub deepest: f64,
}

impl ContactSurface {
    /// Builds the surface of a named line group held by the straight rigid
    /// foundation through `point` with unit normal `normal` (towards the
    /// body). Each node's gap g₀ is its signed distance to the foundation
    /// line; friction acts along that line, oriented as the surface's
    /// tangent; every node with a free DOF takes part (a node whose
    /// tangential motion is held still feels the normal force). Bounds
    /// start at 0 ([`ContactSurface::comply`] sets them).
    ///
    /// # Errors
    /// A missing or non-line group, a normal that is not a unit vector,
    /// ε ≤ 0, or a law out of range (c_n ≤ 0, m_n < 1, c_T < 0, m_T < 1).
    pub fn on_foundation(
        mesh: &Mesh,
        dofs: &DofMap,
        group: &str,
        (point, normal): ([f64; 2], [f64; 2]),
        law: Compliance,
        eps: f64,
    ) -> Result<ContactSurface, ContactError> {
        let bad = |m: String| Err(ContactError::Parameter(m));
        let length = normal[0].hypot(normal[1]);
        if (length - 1.0).abs() >= 1e-12 || length.is_nan() {
            return bad(format!("foundation normal {normal:?} is not a unit vector"));
        }
        let Compliance { cn, mn, ct, mt } = law;
        if !(cn > 0.0 && cn.is_finite() && mn >= 1.0 && mn.is_finite()) {
            return bad(format!("cn = {cn}, mn = {mn}: need cn > 0 and mn >= 1"));
        }
        if !(ct >= 0.0 && ct.is_finite() && mt >= 1.0 && mt.is_finite()) {
            return bad(format!("ct = {ct}, mt = {mt}: need ct >= 0 and mt >= 1"));
        }
        let mut s = ContactSurface::from_nodes(group, Vec::new(), eps)?;
        let quadrature = boundary_quadrature(mesh, group).map_err(|e| ContactError::Group {
            group: group.to_string(),
            source: Box::new(e),
        })?;
        // The foundation line's direction with ν on its left, as τ has the
        // body on its left.
        let along = [normal[1], -normal[0]];
        for b in &quadrature {
            let node_dofs = [dofs.free(b.node, 0), dofs.free(b.node, 1)];
            if node_dofs == [None, None] {
                s.excluded.push(b.node);
                continue;
            }
            let sign = if along[0] * b.tangent[0] + along[1] * b.tangent[1] < 0.0 {
                -1.0
            } else {
                1.0
            };
            let x = mesh.nodes[b.node];
            s.compliance.push(CompliantNode {
                index: s.nodes.len(),
                normal,
                gap: (x[0] - point[0]) * normal[0] + (x[1] - point[1]) * normal[1],
                law,
            });
            s.nodes.push(ContactNode {
                node: b.node,
                dofs: node_dofs,
                weight: b.weight,
                tangent: [sign * along[0], sign * along[1]],
                s: b.s,
                bound: 0.0,
            });
        }
        s.parts = vec![SurfacePart {
            group: group.to_string(),
            nodes: 0..s.nodes.len(),
        }];
        s.law = FrictionLaw { eps };
        Ok(s)
    }

    /// True when some node is held by a compliant foundation.
    pub fn is_compliant(&self) -> bool {
        !self.compliance.is_empty()
    }

    /// Sets the compliant nodes' friction bounds g_J = c_T δ_J^{m_T} for the
    /// displacement `r` (a revision counted when one changed), and writes
    /// the foundation's nodal forces w_J c_n δ_J^{m_n} ν, per free DOF of
    /// every contact node in node order (the order of
    /// [`NodalClosedForm::dofs`](crate::NodalClosedForm::dofs); 0 at the
    /// nodes of other surfaces), into `forces`, resized to fit. `mass` (per
    /// free DOF, may be empty) weighs the stiffness in the result.
    pub fn comply(&mut self, r: &[f64], mass: &[f64], forces: &mut Vec<f64>) -> Foundation {
        let dofs = self.nodes.iter().map(|n| n.dofs.iter().flatten().count());
        forces.resize(dofs.sum(), 0.0);
        forces.iter_mut().for_each(|f| *f = 0.0);
        let mut out = Foundation::default();
        let mut changed = false;
        // The compliant nodes come in node order: walk the DOF list once.
        let (mut k, mut next) = (0, 0);
        for (j, node) in self.nodes.iter_mut().enumerate() {
            let first = k;
            k += node.dofs.iter().flatten().count();
            let Some(c) = self.compliance.get(next).filter(|c| c.index == j) else {
                continue;
            };
            next += 1;
            let delta = c.approach(node, r);
            changed |= set_bound(node, c.law.bound(delta));
            out.stored += node.weight * c.law.energy(delta);
            out.deepest = out.deepest.max(delta);
            let f = node.weight * c.law.traction(delta);
            let (mut at, mut inv_m) = (first, 0.0);
            for comp in 0..2 {
                if let Some(d) = node.dofs[comp] {
                    forces[at] = f * c.normal[comp];
                    at += 1;
                    if let Some(m) = mass.get(d) {
                        inv_m += c.normal[comp] * c.normal[comp] / m;
                    }
                }
            }
            let s = node.weight * c.law.stiffness(delta) * inv_m;
            if delta > 0.0 && s > out.stiffness_over_mass {
                out.stiffness_over_mass = s;
                out.stiffest = j;
            }
        }
        if changed {
            self.revision += 1;
        }
        out
    }

    /// Sets the compliant nodes' friction bounds for the displacement `r`
    /// as [`ContactSurface::comply`] does and returns the stored energy,
    /// without the nodal forces: what the implicit step's ledger needs,
    /// whose forces are the step's own.
    pub fn comply_bounds(&mut self, r: &[f64]) -> f64 {
        let (mut stored, mut changed) = (0.0, false);
        for c in &self.compliance {
            let node = &mut self.nodes[c.index];
            let delta = c.approach(node, r);
            changed |= set_bound(node, c.law.bound(delta));
            stored += node.weight * c.law.energy(delta);
        }
        if changed {
            self.revision += 1;
        }
        stored
    }

    /// Adds the stiffness w_J c_n ννᵀ of each compliant node with m_n = 1
    /// (its stiffness at every approach) at free-DOF displacement `x` to
    /// `y` (y += K_c x): the product whose largest eigenvalue bounds the
    /// explicit step where every such node is in contact.
    pub fn add_linear_stiffness(&self, x: &[f64], y: &mut [f64]) {
        for c in self.compliance.iter().filter(|c| c.law.mn == 1.0) {
            let node = &self.nodes[c.index];
            let k = node.weight * c.law.cn;
            let mut nx = 0.0;
            for comp in 0..2 {
                if let Some(d) = node.dofs[comp] {
                    nx += c.normal[comp] * x[d];
                }
            }
            for comp in 0..2 {
                if let Some(d) = node.dofs[comp] {
                    y[d] += k * c.normal[comp] * nx;
                }
            }
        }
    }

    /// True when some compliant node's stiffness grows with its approach
    /// (m_n > 1): the explicit step's stability then depends on the
    /// state, and is checked step by step.
    pub fn has_nonlinear_compliance(&self) -> bool {
        self.compliance.iter().any(|c| c.law.mn != 1.0)
    }

    /// The normal traction c_n δ^{m_n} of every node at displacement `r`
    /// (0 at the nodes of prescribed-pressure surfaces), for observers.
    pub fn normal_tractions(&self, r: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for c in &self.compliance {
            out[c.index] = c.law.traction(c.approach(&self.nodes[c.index], r));
        }
    }
}

/// Gives `node` the bound `g`; true when its bits changed.
fn set_bound(node: &mut ContactNode, g: f64) -> bool {
    let changed = g.to_bits() != node.bound.to_bits();
    node.bound = g;
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(law: Compliance) -> ContactSurface {
        let node = |j: usize| ContactNode {
            node: j,
            dofs: [Some(2 * j), Some(2 * j + 1)],
            weight: 0.5,
            tangent: [1.0, 0.0],
            s: j as f64,
            bound: 0.0,
        };
        let mut s = ContactSurface::from_nodes("c", vec![node(0), node(1)], 1e-3).unwrap();
        s.compliance = (0..2)
            .map(|index| CompliantNode {
                index,
                normal: [0.0, 1.0],
                gap: 0.01 * index as f64,
                law,
            })
            .collect();
        s
    }

    /// Forces, bounds and energy against the law written out: node 0 (g₀ =
    /// 0) pushed 0.03 into the foundation, node 1 (g₀ = 0.01) 0.02 down,
    /// so 0.01 in.
    #[test]
    fn forces_bounds_and_energy_follow_the_law() {
        let law = Compliance {
            cn: 100.0,
            mn: 2.0,
            ct: 30.0,
            mt: 2.0,
        };
        let mut s = surface(law);
        let r = [0.0, -0.03, 0.0, -0.02];
        let mut forces = Vec::new();
        let f = s.comply(&r, &[1.0; 4], &mut forces);
        let (d0, d1) = (0.03_f64, 0.01_f64);
        let expected = [0.0, 0.5 * 100.0 * d0 * d0, 0.0, 0.5 * 100.0 * d1 * d1];
        for (g, e) in forces.iter().zip(expected) {
            assert!((g - e).abs() < 1e-15, "{forces:?}");
        }
        assert!((s.nodes[0].bound - 30.0 * d0 * d0).abs() < 1e-15);
        assert!((s.nodes[1].bound - 30.0 * d1 * d1).abs() < 1e-15);
        let stored = 0.5 * 100.0 * (d0.powi(3) + d1.powi(3)) / 3.0;
        assert!((f.stored - stored).abs() < 1e-15);
        // Stiffness w c_n m_n δ / m at the deeper node.
        assert!((f.stiffness_over_mass - 0.5 * 100.0 * 2.0 * d0).abs() < 1e-12);
        assert_eq!(f.stiffest, 0);
        assert_eq!(s.revision, 1);
        // Lifted off: no force, no bound.
        let f = s.comply(&[0.0; 4], &[1.0; 4], &mut forces);
        assert!(forces.iter().all(|&x| x == 0.0) && f.stored == 0.0);
        assert!(s.nodes.iter().all(|n| n.bound == 0.0));
    }

    /// The energy-consistent traction's defect against the stored energy
    /// written out: (σ(a0₊) + σ(a1₊) + D)/2 times a1 − a0 is Φ(a1₊) −
    /// Φ(a0₊), Φ = c_n d^{m_n+1}/(m_n+1) here, for touches, releases,
    /// steps in and out of contact and steps short against the approach;
    /// m_n = 1 in contact and off the foundation give D = 0 exactly; a
    /// release at m_n = 1 gives c_n a0 a1/(a0 − a1); the returned slope
    /// matches a central difference of σ(a1₊) + D.
    #[test]
    fn energy_consistent_traction_does_the_stored_energys_work() {
        for (cn, mn) in [(100.0, 1.0), (3e4, 2.0), (50.0, 1.5)] {
            let law = Compliance {
                cn,
                mn,
                ct: 0.0,
                mt: mn,
            };
            let phi = |a: f64| cn * a.max(0.0).powf(mn + 1.0) / (mn + 1.0);
            let sigma = |a: f64| cn * a.max(0.0).powf(mn);
            for (a0, a1) in [
                (-0.01, 0.02),
                (0.02, -0.01),
                (0.01, 0.03),
                (0.03, 0.01),
                (0.02, 0.02 * (1.0 + 1e-7)),
                (0.0, 0.01),
            ] {
                let (d, slope) = law.energy_consistent(a0, a1);
                let work = 0.5 * (sigma(a0) + sigma(a1) + d) * (a1 - a0);
                let change = phi(a1) - phi(a0);
                let scale = phi(a0).max(phi(a1));
                assert!(
                    (work - change).abs() <= 1e-13 * scale,
                    "m = {mn}, ({a0}, {a1}): work {work:e}, ΔΦ {change:e}"
                );
                let h = 1e-7 * a1.abs();
                let f = |a: f64| sigma(a) + law.energy_consistent(a0, a).0;
                let numeric = (f(a1 + h) - f(a1 - h)) / (2.0 * h);
                assert!(
                    (slope - numeric).abs() <= 1e-5 * numeric.abs().max(cn * 1e-6),
                    "m = {mn}, ({a0}, {a1}): slope {slope:e} vs {numeric:e}"
                );
            }
        }
        let law = Compliance {
            cn: 100.0,
            mn: 1.0,
            ct: 0.0,
            mt: 1.0,
        };
        assert_eq!(law.energy_consistent(0.01, 0.03), (0.0, 100.0));
        assert_eq!(law.energy_consistent(-0.01, -0.03), (0.0, 0.0));
        let (a0, a1) = (0.02, -0.01);
        let d = law.energy_consistent(a0, a1).0;
        let closed = 100.0 * a0 * a1 / (a0 - a1);
        assert!(
            (d - closed).abs() <= 1e-14 * closed.abs(),
            "{d} vs {closed}"
        );
    }

    /// `comply_bounds` sets the bounds and returns the stored energy of
    /// `comply`, bit for bit.
    #[test]
    fn bounds_alone_match_comply() {
        let law = Compliance {
            cn: 100.0,
            mn: 2.0,
            ct: 30.0,
            mt: 2.0,
        };
        let (mut a, mut b) = (surface(law), surface(law));
        let r = [0.0, -0.03, 0.0, -0.02];
        let stored = a.comply(&r, &[], &mut Vec::new()).stored;
        assert_eq!(b.comply_bounds(&r).to_bits(), stored.to_bits());
        assert_eq!(a.revision, b.revision);
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            assert_eq!(x.bound.to_bits(), y.bound.to_bits());
        }
    }

    /// K_c x for m_n = 1 is w c_n ν(ν·x) at each node.
    #[test]
    fn linear_stiffness_is_w_cn_nu_nu() {
        let law = Compliance {
            cn: 7.0,
            mn: 1.0,
            ct: 0.0,
            mt: 1.0,
        };
        let s = surface(law);
        let mut y = [1.0; 4];
        s.add_linear_stiffness(&[2.0, 3.0, 4.0, 5.0], &mut y);
        assert_eq!(y, [1.0, 1.0 + 3.5 * 3.0, 1.0, 1.0 + 3.5 * 5.0]);
    }
}
