//! Isotropic linear elasticity in plane strain or plane stress (unit
//! thickness), METHOD.md §1.

use crate::error::FemError;

/// The 2-D reduction of 3-D elasticity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Hypothesis {
    /// ε_zz = 0 (the paper's choice, and the default).
    #[default]
    PlaneStrain,
    /// σ_zz = 0.
    PlaneStress,
}

/// An isotropic material: E, ν, ρ and the plane hypothesis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus E (> 0).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν in (-1, 1/2).
    pub poisson_ratio: f64,
    /// Mass density ρ (> 0), per unit area for unit thickness.
    pub density: f64,
    /// Plane strain or plane stress.
    pub hypothesis: Hypothesis,
}

impl Material {
    /// A checked material.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] when E ≤ 0, ρ ≤ 0, ν outside (-1, 1/2),
    /// or any of them is not finite.
    pub fn new(
        youngs_modulus: f64,
        poisson_ratio: f64,
        density: f64,
        hypothesis: Hypothesis,
    ) -> Result<Material, FemError> {
        if !(youngs_modulus.is_finite() && youngs_modulus > 0.0) {
            return Err(FemError::InvalidMaterial {
                parameter: "Young's modulus E",
                value: youngs_modulus,
                requirement: "must be a positive finite number; give E > 0",
            });
        }
        if !(poisson_ratio.is_finite() && poisson_ratio > -1.0 && poisson_ratio < 0.5) {
            return Err(FemError::InvalidMaterial {
                parameter: "Poisson's ratio nu",
                value: poisson_ratio,
                requirement: "must lie strictly between -1 and 0.5 (0.5 is incompressible, which this displacement formulation cannot represent); give -1 < nu < 0.5",
            });
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(FemError::InvalidMaterial {
                parameter: "density rho",
                value: density,
                requirement: "must be a positive finite number; give rho > 0",
            });
        }
        Ok(Material {
            youngs_modulus,
            poisson_ratio,
            density,
            hypothesis,
        })
    }

    /// Lamé's first parameter λ and shear modulus μ of the 3-D material.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// The elasticity matrix D in Voigt notation (xx, yy, xy with engineering
    /// shear γ_xy = 2ε_xy): σ = D ε.
    pub fn elasticity(&self) -> [[f64; 3]; 3] {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        match self.hypothesis {
            Hypothesis::PlaneStrain => {
                let (l, m) = self.lame();
                [[l + 2.0 * m, l, 0.0], [l, l + 2.0 * m, 0.0], [0.0, 0.0, m]]
            }
            Hypothesis::PlaneStress => {
                let c = e / (1.0 - nu * nu);
                [
                    [c, c * nu, 0.0],
                    [c * nu, c, 0.0],
                    [0.0, 0.0, c * (1.0 - nu) / 2.0],
                ]
            }
        }
    }

    /// The out-of-plane stress σ_zz for an in-plane stress (σ_xx, σ_yy, σ_xy):
    /// ν(σ_xx + σ_yy) in plane strain, 0 in plane stress.
    pub fn out_of_plane_stress(&self, stress: [f64; 3]) -> f64 {
        match self.hypothesis {
            Hypothesis::PlaneStrain => self.poisson_ratio * (stress[0] + stress[1]),
            Hypothesis::PlaneStress => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_parameters_are_refused_with_the_parameter_named() {
        let cases = [
            (0.0, 0.3, 1.0, "Young's modulus"),
            (-5.0, 0.3, 1.0, "Young's modulus"),
            (f64::NAN, 0.3, 1.0, "Young's modulus"),
            (1000.0, 0.5, 1.0, "Poisson's ratio"),
            (1000.0, -1.0, 1.0, "Poisson's ratio"),
            (1000.0, 0.7, 1.0, "Poisson's ratio"),
            (1000.0, 0.3, 0.0, "density"),
            (1000.0, 0.3, -2.0, "density"),
            (1000.0, 0.3, f64::INFINITY, "density"),
        ];
        for (e, nu, rho, what) in cases {
            for h in [Hypothesis::PlaneStrain, Hypothesis::PlaneStress] {
                let err = Material::new(e, nu, rho, h).unwrap_err();
                let msg = err.to_string();
                assert!(msg.contains(what), "{msg}");
                assert!(matches!(err, FemError::InvalidMaterial { .. }));
            }
        }
        assert!(Material::new(1000.0, -0.99, 1.0, Hypothesis::PlaneStrain).is_ok());
        assert!(Material::new(1000.0, 0.49, 1.0, Hypothesis::PlaneStress).is_ok());
    }

    /// Expected: uniaxial plane-strain compliance. Under σ_yy = -300 alone
    /// (σ_xx = 0), ε_xx = -ν(1+ν)/E σ_yy = 0.117 and ε_yy = (1-ν²)/E σ_yy =
    /// -0.273 for E = 1000, ν = 0.3 (BENCHMARK.md's slab); plane stress gives
    /// ε_xx = -ν σ_yy / E, ε_yy = σ_yy / E.
    #[test]
    fn elasticity_matrices_match_closed_form_compliances() {
        let solve = |d: [[f64; 3]; 3], syy: f64| {
            // [d00 d01; d10 d11] (exx, eyy) = (0, syy)
            let det = d[0][0] * d[1][1] - d[0][1] * d[1][0];
            ((-d[0][1] * syy) / det, (d[0][0] * syy) / det)
        };
        let m = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let (exx, eyy) = solve(m.elasticity(), -300.0);
        assert!((exx - 0.117).abs() < 1e-14 && (eyy + 0.273).abs() < 1e-14);
        let m = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStress).unwrap();
        let (exx, eyy) = solve(m.elasticity(), -300.0);
        assert!((exx - 0.09).abs() < 1e-14 && (eyy + 0.3).abs() < 1e-14);
        assert!((m.elasticity()[2][2] - 1000.0 / 2.6).abs() < 1e-12);
    }
}
