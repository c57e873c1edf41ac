//! The energy-consistent normal force of a compliant foundation in Newmark
//! ¼, ½ (METHOD.md §10; Armero and Petocz, Laursen and Chawla).
//!
//! Newmark ¼, ½ uses the acceleration only through the step's mean
//! ½(r̈_K + r̈_{K−1}), so the trapezoidal rule does the work ½(φ_K +
//! φ_{K−1})·(ν·Δr) of a normal force φ, which is the stored energy's
//! change only where φ is linear in the approach: not on a step where a
//! node touches or leaves, nor for m_n > 1. The step instead carries per
//! compliant node an algorithmic force φ̃ (the acceleration it gives, r̈̃,
//! is the one the scheme advances) with
//!
//! ```text
//! φ̃_K = 2 w σ_dg(a_{K−1}, a_K) − φ̃_{K−1},  σ_dg = ΔΦ/Δa,
//! ```
//!
//! so that the mean ½(φ̃_K + φ̃_{K−1}) is w σ_dg, whose work is the stored
//! energy's change exactly: frictionless, the ledger closes to round-off
//! on every step. The state holds the excess e = φ̃ − w σ(a₊) over the
//! end-point force: φ̃_K = w(σ(a_K₊) + D) − e_{K−1}, D the trapezoid's
//! defect ([`stickslip_contact::Compliance::energy_consistent`]), 0
//! exactly for m_n = 1 while the contact set stays, where e stays 0 and
//! the step is the end-point one bit for bit. After a release D = 0 but e
//! keeps its sign's alternation (e_K = −e_{K−1}): the force the scheme
//! carries alternates, its mean (the dynamics) does not.
//!
//! What the run reports stays physical: the normal traction from r_K (the
//! friction bound too, never from φ̃), and the acceleration r̈ = r̈̃ −
//! M⁻¹ν e, which satisfies M r̈ + K r = R + ν w σ(a₊) + friction at every
//! step. The state keeps that r̈ and e (checkpointed), and the step forms
//! what it needs of r̈̃ from them: M r̈̃_{K−1} = M r̈_{K−1} + ν e_{K−1} on
//! the right-hand side (local to the compliant nodes), and r̈_K = r̈̃_K −
//! M⁻¹ν e_K with r̈̃_K = (ṙ_K − ṙ_{K−1})/(γΔt) − (1/γ − 1) r̈̃_{K−1}, which
//! asks M⁻¹ν((1/γ − 1) e_{K−1} + e_K), at γ = ½ M⁻¹ν w D: only on steps
//! where D ≠ 0. The lumped mass divides there; the consistent mass is
//! factorized at the first such step and solved with on each.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::ContactSurface;
use stickslip_linalg::csr::diagonal;
use stickslip_linalg::{FillOrder, SolverError, SparseCholesky};

use crate::settings::MassKind;

/// M⁻¹ as the reported acceleration's correction needs it.
enum MassInverse {
    /// The lumped mass, per free DOF.
    Lumped(Vec<f64>),
    /// The consistent mass's factor, made at the first step that needs it.
    Consistent {
        fill_order: FillOrder,
        factor: Option<Box<SparseCholesky>>,
    },
}

/// The step's part of the energy-consistent normal force beside the
/// compliant Newton solve, which forms φ̃ (`compliance.rs`).
pub(crate) struct AlgorithmicNormal {
    mass: MassInverse,
    /// M⁻¹'s right-hand side.
    rhs: Vec<f64>,
}

impl AlgorithmicNormal {
    /// For the scheme's mass `m` (`kind`; the lumped one on `m`'s
    /// diagonal).
    pub(crate) fn new(m: &CsrMatrix<f64>, kind: MassKind, fill_order: &FillOrder) -> Self {
        let mass = match kind {
            MassKind::Lumped => MassInverse::Lumped(diagonal(m)),
            MassKind::Consistent => MassInverse::Consistent {
                fill_order: fill_order.clone(),
                factor: None,
            },
        };
        AlgorithmicNormal {
            mass,
            rhs: Vec::new(),
        }
    }

    /// b += c ν e per compliant node (c = 1/γ − 1, the weight of r̈_{K−1}
    /// in R̂_K): R̂ with M r̈̃ = M r̈ + ν e in place of M r̈.
    pub(crate) fn correct_rhs(contact: &ContactSurface, excess: &[f64], c: f64, b: &mut [f64]) {
        for (k, &e) in contact.compliance.iter().zip(excess) {
            if e != 0.0 {
                add_along_normal(contact, k, c * e, b);
            }
        }
    }

    /// r̈_K −= M⁻¹ Σ ν (c e_{K−1} + e_K) over the compliant nodes (c = 1/γ
    /// − 1): the reported acceleration from the scheme's; nothing where
    /// every such sum is 0.
    ///
    /// # Errors
    /// The consistent mass's factorization.
    pub(crate) fn correct_acceleration(
        &mut self,
        contact: &ContactSurface,
        m: &CsrMatrix<f64>,
        (c, before, after): (f64, &[f64], &[f64]),
        a: &mut [f64],
    ) -> Result<(), SolverError> {
        let jump = |k: usize| c * before[k] + after[k];
        if (0..before.len()).all(|k| jump(k) == 0.0) {
            return Ok(());
        }
        self.rhs.clear();
        self.rhs.resize(a.len(), 0.0);
        for (k, node) in contact.compliance.iter().enumerate() {
            let s = jump(k);
            if s != 0.0 {
                add_along_normal(contact, node, s, &mut self.rhs);
            }
        }
        match &mut self.mass {
            MassInverse::Lumped(diag) => {
                for ((a, r), m) in a.iter_mut().zip(&self.rhs).zip(diag.iter()) {
                    if *r != 0.0 {
                        *a -= r / m;
                    }
                }
            }
            MassInverse::Consistent { fill_order, factor } => {
                let solver = match factor {
                    Some(f) => f,
                    None => {
                        let mut f = SparseCholesky::analyze(m, fill_order)?;
                        f.factorize(m)?;
                        factor.insert(Box::new(f))
                    }
                };
                solver.solve_in_place(&mut self.rhs);
                for (a, r) in a.iter_mut().zip(&self.rhs) {
                    *a -= r;
                }
            }
        }
        Ok(())
    }
}

/// x += s ν at compliant node `k`'s free DOFs.
fn add_along_normal(
    contact: &ContactSurface,
    k: &stickslip_contact::CompliantNode,
    s: f64,
    x: &mut [f64],
) {
    for (d, n) in contact.nodes[k.index].dofs.iter().zip(k.normal) {
        if let Some(d) = d {
            x[*d] += s * n;
        }
    }
}
