//! A thin elastic strip on a rough rigid base, pulled at one end by a
//! force P below the total friction bound: the shear-lag problem of
//! quasi-static friction, with its 1-D closed form.
//!
//! The strip [0, L] × [0, H] (plane strain, unit depth) rests on its base
//! y = 0 (u_y = 0 there, friction with bound g = μ F_n per unit length),
//! its far end x = 0 held in x, its end x = L pulled by the uniform
//! traction P/H·θ(t). As a 1-D bar with axial stiffness E* H (E* =
//! E/(1 − ν²): plane strain, σ_yy = 0 through a thin strip) on Coulomb
//! friction: the base slips, with friction g against the pull, over a
//! length a from the loaded end, and sticks beyond it, where nothing has
//! moved and so no force is left. Equilibrium of the slipping part gives
//! a = P/g; its axial force N(x) = g (x − (L − a)) gives u' = N/(E* H),
//! so u(x) = g (x − L + a)²/(2 E* H) and the end moves
//! u(L) = P²/(2 g E* H). The far end's support carries nothing while
//! a < L.

use stickslip_fem::{Dirichlet, Hypothesis, Material, Traction};
use stickslip_mesh::CellKind;
use stickslip_time::{History, Integrator};

use crate::grid::rectangle;
use crate::scene::{SceneError, Slab};

/// The strip's data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strip {
    /// Length L.
    pub length: f64,
    /// Thickness H.
    pub height: f64,
    /// Young's modulus E.
    pub e: f64,
    /// Poisson's ratio ν.
    pub nu: f64,
    /// Normal pressure F_n on the base (the bound g = μ F_n).
    pub pressure: f64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// The pull P (force per unit depth) at θ = 1.
    pub pull: f64,
}

impl Strip {
    /// L = 1, E = 1000, ν = 0.3, F_n = 100, μ = 0.3 (g = 30), P = 15 (a
    /// slip zone of half the length), thickness `height`.
    pub fn new(height: f64) -> Strip {
        Strip {
            length: 1.0,
            height,
            e: 1000.0,
            nu: 0.3,
            pressure: 100.0,
            mu: 0.3,
            pull: 15.0,
        }
    }

    /// The bound per unit length g = μ F_n.
    pub fn bound(&self) -> f64 {
        self.mu * self.pressure
    }

    /// The closed form's slip length a = P/g (module docs).
    pub fn slip_length(&self) -> f64 {
        self.pull / self.bound()
    }

    /// The closed form's end displacement P²/(2 g E* H), E* = E/(1 − ν²).
    pub fn end_displacement(&self) -> f64 {
        let e_star = self.e / (1.0 - self.nu * self.nu);
        self.pull * self.pull / (2.0 * self.bound() * e_star * self.height)
    }

    /// The strip on `nx × ny` cells of `kind`, ρ = 1, friction with
    /// regularization `eps`, the pull P·θ(t).
    ///
    /// # Errors
    /// Bad data (a material out of range, ε ≤ 0).
    pub fn scene(
        &self,
        kind: CellKind,
        (nx, ny): (usize, usize),
        eps: f64,
        theta: History,
    ) -> Result<Slab, SceneError> {
        let mesh = rectangle(kind, nx, ny, [0.0, 0.0], [self.length, self.height]);
        let material = Material::new(self.e, self.nu, 1.0, Hypothesis::PlaneStrain)?;
        let conditions = [
            Dirichlet::new("bottom", 1, 0.0),
            Dirichlet::new("left", 0, 0.0),
        ];
        let pull = [(
            "right",
            Traction::Vector([self.pull / self.height, 0.0]),
            theta,
        )];
        Slab::assemble(
            mesh,
            &material,
            &conditions,
            &pull,
            Some(("bottom", self.pressure, self.mu, eps)),
        )
    }

    /// The end displacement of a run of [`Strip::scene`]: the pull's
    /// conjugate, Σ f·r / P with f the end's nodal forces at θ = 1 (the
    /// 1-D model's u(L), the end face's mean).
    pub fn measured_end(&self, slab: &Slab, r: &[f64]) -> f64 {
        let f = &slab.loads[0].vector;
        f.iter().zip(r).map(|(f, r)| f * r).sum::<f64>() / self.pull
    }

    /// The slip length of a run of [`Strip::scene`] from the friction
    /// stress along the base: the distance from the loaded end to where
    /// |σ_T| first drops below g/2, linear between nodes (the closed
    /// form's stress jumps there from g to 0).
    pub fn measured_slip(&self, slab: &Slab, integrator: &Integrator) -> f64 {
        let Some(c) = integrator.contact() else {
            return 0.0;
        };
        let mut sigma = vec![0.0; c.len()];
        integrator.friction_stress(&mut sigma);
        let mut along: Vec<(f64, f64)> = c
            .nodes
            .iter()
            .zip(&sigma)
            .map(|(n, s)| (slab.mesh.nodes[n.node][0], s.abs()))
            .collect();
        along.sort_by(|a, b| b.0.total_cmp(&a.0));
        let half = 0.5 * self.bound();
        for w in along.windows(2) {
            let ((x1, s1), (x0, s0)) = (w[0], w[1]);
            if s0 < half {
                let x = if s1 > s0 {
                    x0 + (x1 - x0) * (half - s0) / (s1 - s0)
                } else {
                    x1
                };
                return self.length - x;
            }
        }
        self.length
    }
}
