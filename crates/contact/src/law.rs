//! The regularized friction law (METHOD.md §2; paper eqs. (2.6)-(2.8)) and
//! the scalar nodal equation it gives a node of a diagonal system.

/// The regularization of |v| by ψ_ε and its derivative φ_ε, for ε > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLaw {
    /// Regularization parameter ε (a velocity): below it a node is a stiff
    /// viscous damper g/ε, above it the friction force has magnitude g.
    pub eps: f64,
}

/// The class of a contact node in the stick/slip iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(i8)]
pub enum SlipState {
    /// |v_T| ≤ ε: contributes the damping w g/ε ττᵀ to C.
    Stuck = 0,
    /// v_T > ε: contributes the constant force +w g τ to F.
    SlipPositive = 1,
    /// v_T < −ε: contributes the constant force −w g τ to F.
    SlipNegative = -1,
}

impl SlipState {
    /// 0 stuck, +1 / −1 slipping (the HDF5 `contact/state` code).
    pub fn code(self) -> i8 {
        self as i8
    }
    /// Sign of the slip, 0 when stuck.
    #[inline]
    pub fn sign(self) -> f64 {
        f64::from(self.code())
    }
    /// True when stuck.
    #[inline]
    pub fn is_stuck(self) -> bool {
        self == SlipState::Stuck
    }
    /// True when a node of class `old` at the last step is stuck now: a
    /// slip → stick event (what Remark 4.3's step reduction follows).
    #[inline]
    pub fn sticks_after(self, old: SlipState) -> bool {
        self.is_stuck() && !old.is_stuck()
    }
    /// True when `old` → `self` reverses the slip direction (Remark 4.2).
    #[inline]
    pub fn reverses(self, old: SlipState) -> bool {
        matches!(
            (old, self),
            (SlipState::SlipPositive, SlipState::SlipNegative)
                | (SlipState::SlipNegative, SlipState::SlipPositive)
        )
    }
}

impl FrictionLaw {
    /// ψ_ε(|v|): s − ε/2 for s > ε, s²/(2ε) otherwise (METHOD.md §2).
    pub fn psi(&self, v: f64) -> f64 {
        let s = v.abs();
        if s > self.eps {
            s - 0.5 * self.eps
        } else {
            s * s / (2.0 * self.eps)
        }
    }

    /// φ_ε(v) = ψ_ε'(v): v/|v| when |v| > ε, v/ε otherwise. |φ_ε| ≤ 1.
    #[inline]
    pub fn phi(&self, v: f64) -> f64 {
        self.class_and_phi(v).1
    }

    /// Class of a node moving with tangential velocity `v`.
    #[inline]
    pub fn classify(&self, v: f64) -> SlipState {
        self.branches(v, |v| v).0
    }

    /// The class of a node moving with tangential velocity `v` and φ_ε(v),
    /// from one comparison of |v| with ε.
    #[inline]
    pub fn class_and_phi(&self, v: f64) -> (SlipState, f64) {
        self.branches(v, |v| v / self.eps)
    }

    /// [`FrictionLaw::class_and_phi`] with the stuck branch v·(1/ε) by a
    /// stored `inv_eps` = 1/ε, for loops that must not divide; it rounds
    /// differently from v/ε, within one rounding of it.
    #[inline]
    pub fn class_and_phi_by_reciprocal(&self, v: f64, inv_eps: f64) -> (SlipState, f64) {
        self.branches(v, |v| v * inv_eps)
    }

    /// The law's three branches: slipping forward (φ = 1) above ε,
    /// backward (φ = −1) below −ε, stuck (φ = `stuck(v)`, v/ε) between.
    #[inline(always)]
    fn branches(&self, v: f64, stuck: impl FnOnce(f64) -> f64) -> (SlipState, f64) {
        if v > self.eps {
            (SlipState::SlipPositive, 1.0)
        } else if v < -self.eps {
            (SlipState::SlipNegative, -1.0)
        } else {
            (SlipState::Stuck, stuck(v))
        }
    }

    /// The damping coefficient of a stuck node whose slip force has
    /// magnitude `force_scale` = w g: w g/ε (METHOD.md §3, the C of
    /// J = C ṙ + F).
    #[inline]
    pub fn stuck_damping(&self, force_scale: f64) -> f64 {
        force_scale / self.eps
    }

    /// 1/(1 + c/ε): the stuck root of t + c φ_ε(t) = p is p times this
    /// ([`FrictionLaw::solve_nodal_by`]); formed once where c is fixed, so
    /// that each solve is a product.
    pub fn stuck_factor(&self, c: f64) -> f64 {
        1.0 / (1.0 + c / self.eps)
    }

    /// Solves the scalar nodal equation t + c·φ_ε(t) = p for t, with c ≥ 0.
    ///
    /// The left side is continuous, piecewise linear and strictly increasing
    /// in t, so there is exactly one root, found in closed form: stuck if
    /// p/(1 + c/ε) lies in [−ε, ε], otherwise t = p ∓ c. This is one node's
    /// friction in a step whose operator is diagonal (the explicit scheme).
    pub fn solve_nodal(&self, p: f64, c: f64) -> f64 {
        self.solve_nodal_by(p, c, self.stuck_factor(c))
    }

    /// [`FrictionLaw::solve_nodal`] with `stuck_factor` =
    /// [`FrictionLaw::stuck_factor`]`(c)` given.
    #[inline]
    pub fn solve_nodal_by(&self, p: f64, c: f64, stuck_factor: f64) -> f64 {
        let stuck = p * stuck_factor;
        if stuck.abs() <= self.eps {
            stuck
        } else {
            p - c * p.signum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_is_c1_and_phi_is_its_derivative() {
        let law = FrictionLaw { eps: 0.25 };
        // Continuity of ψ and of φ at s = ε (METHOD.md §2 definitions).
        let e = law.eps;
        assert!((law.psi(e) - e / 2.0).abs() < 1e-15);
        assert!((law.phi(e) - 1.0).abs() < 1e-15);
        // φ = dψ/dv by central differences away from the kinks.
        for &v in &[-2.0, -0.2, -0.01, 0.0, 0.1, 0.24, 0.3, 5.0] {
            let h = 1e-6;
            let fd = (law.psi(v + h) - law.psi(v - h)) / (2.0 * h);
            assert!(
                (fd - law.phi(v)).abs() < 1e-6,
                "v = {v}: {fd} vs {}",
                law.phi(v)
            );
        }
    }

    #[test]
    fn nodal_solution_satisfies_its_equation() {
        let law = FrictionLaw { eps: 1e-3 };
        for &c in &[0.0, 1e-4, 0.5, 3.0] {
            for i in -50..=50 {
                let p = f64::from(i) * 0.1;
                let t = law.solve_nodal(p, c);
                let residual = t + c * law.phi(t) - p;
                assert!(
                    residual.abs() < 1e-12,
                    "p = {p}, c = {c}: residual {residual}"
                );
            }
        }
    }

    /// φ_ε(v) → sign(v) for v ≠ 0 as ε → 0: exactly ±1 once ε < |v|, the
    /// definition of METHOD.md §2 (no rounding enters the slip branch).
    #[test]
    fn phi_tends_to_the_sign() {
        for v in [-3.0, -1e-3, -1e-9, 2e-12, 1e-6, 0.5, 40.0] {
            for k in 0..=40 {
                let eps = 10f64.powi(-k / 2);
                let phi = FrictionLaw { eps }.phi(v);
                if eps < v.abs() {
                    assert_eq!(phi, v.signum(), "v = {v}, ε = {eps}");
                } else {
                    // Still on the viscous branch: |φ| ≤ 1 and of v's sign.
                    assert!(phi.abs() <= 1.0 && phi * v > 0.0, "v = {v}, ε = {eps}");
                }
            }
            assert_eq!(FrictionLaw { eps: 1e-20 }.phi(v), v.signum(), "v = {v}");
        }
        // φ_ε(0) = 0 for every ε: the limit of v/|v| does not exist there.
        assert_eq!(FrictionLaw { eps: 1e-12 }.phi(0.0), 0.0);
    }

    /// ψ_ε(s) → |s| with 0 ≤ |s| − ψ_ε(s) ≤ ε/2, an exact bound: from
    /// METHOD.md §2's two branches, |s| − ψ_ε = ε/2 for |s| > ε and
    /// |s|(1 − |s|/(2ε)) ∈ [0, ε/2] for |s| ≤ ε, ε/2 at |s| = ε. Tolerance:
    /// four ulps of max(|s|, ε), the rounding of one subtraction and one
    /// quotient.
    #[test]
    fn psi_tends_to_the_absolute_value_within_half_eps() {
        let samples: [f64; 8] = [0.0, 1e-12, 3e-7, -2e-4, 0.01, -0.7, 1.0, 25.0];
        for k in 0..=24 {
            let eps = 10f64.powi(-k / 2) * if k % 2 == 0 { 1.0 } else { 0.3 };
            let law = FrictionLaw { eps };
            for &s in &samples {
                let gap = s.abs() - law.psi(s);
                let ulps = 4.0 * f64::EPSILON * s.abs().max(eps);
                assert!(gap >= -ulps, "s = {s}, ε = {eps}: ψ above |s| by {gap}");
                assert!(
                    gap <= 0.5 * eps + ulps,
                    "s = {s}, ε = {eps}: |s| − ψ = {gap} > ε/2"
                );
                if s.abs() > eps {
                    // The bound is exact on the slip branch.
                    assert!((gap - 0.5 * eps).abs() <= ulps, "s = {s}, ε = {eps}");
                }
            }
            // ... and attained at s = ε (both branches meet there).
            assert!((eps - law.psi(eps) - 0.5 * eps).abs() <= 4.0 * f64::EPSILON * eps);
        }
    }

    /// The nodal closed form's stuck set is |p| ≤ ε(1 + c/ε) = ε + c, which
    /// shrinks to the true Coulomb stuck set |p| ≤ c as ε → 0; and its root
    /// tends to the Coulomb nodal solution t = 0 for |p| ≤ c, t = p − c
    /// sign(p) otherwise (the root of t + c ∂|t| ∋ p, written here), with
    /// |t − t₀| ≤ ε: the stuck root is p/(1 + c/ε), at most ε in size, and
    /// the slip root is exactly the Coulomb one.
    #[test]
    fn nodal_solution_tends_to_coulombs() {
        let coulomb = |p: f64, c: f64| {
            if p.abs() <= c {
                0.0
            } else {
                p - c * p.signum()
            }
        };
        let c = 0.8;
        for &p in &[
            -2.0, -0.8000001, -0.8, -0.3, 0.0, 1e-9, 0.5, 0.79999, 0.8000001, 3.0,
        ] {
            for k in 0..=30 {
                let eps = 10f64.powi(-k / 2);
                let law = FrictionLaw { eps };
                let t = law.solve_nodal(p, c);
                let stuck = law.classify(t).is_stuck();
                // Stuck set: |p| ≤ ε + c up to the rounding of p/(1 + c/ε).
                let edge = eps + c;
                if p.abs() < edge * (1.0 - 1e-12) {
                    assert!(stuck, "p = {p}, ε = {eps}: t = {t} not stuck");
                } else if p.abs() > edge * (1.0 + 1e-12) {
                    assert!(!stuck, "p = {p}, ε = {eps}: t = {t} stuck");
                }
                let t0 = coulomb(p, c);
                assert!(
                    (t - t0).abs() <= eps * (1.0 + 1e-12) + 4.0 * f64::EPSILON * p.abs(),
                    "p = {p}, ε = {eps}: {t} vs Coulomb {t0}"
                );
            }
            // At ε = 1e-15 the stuck set is Coulomb's, |p| ≤ c, widened by
            // ε (p = ±c, at its edge, stays stuck: c/(1 + c/ε) < ε).
            let law = FrictionLaw { eps: 1e-15 };
            let t = law.solve_nodal(p, c);
            assert_eq!(law.classify(t).is_stuck(), p.abs() <= c + 1e-15, "p = {p}");
        }
    }
}
