//! The semi-discrete system M r̈ + J(ṙ) + K r = R(t) on free DOFs
//! (METHOD.md §3), as the schemes receive it.

use nalgebra_sparse::CsrMatrix;
use stickslip_fem::{Model, RigidMode};
use stickslip_linalg::FillOrder;

use crate::history::History;

/// K, M (consistent, with K's sparsity pattern, where assembled), the HRZ
/// lumped mass, and a load that never changes (the lifting of nonzero
/// prescribed displacements).
#[derive(Clone, Debug)]
pub struct Dynamics {
    /// Stiffness K.
    pub stiffness: CsrMatrix<f64>,
    /// Consistent mass M, same pattern as K; `None` where the model was
    /// built without it (only Newmark with the consistent mass reads it).
    pub consistent_mass: Option<CsrMatrix<f64>>,
    /// Lumped mass, one value per free DOF.
    pub lumped_mass: Vec<f64>,
    /// A load acting at all times, also before t = 0.
    pub constant_load: Vec<f64>,
    /// Whether the explicit step may form K·x from K's stencil types
    /// (`stickslip_linalg::Stencils`: on structured meshes, within 1e-10 ·
    /// max |K_ij| · Σ|x_j| of the assembled product). Default true; false
    /// keeps the assembled K's bits.
    pub stencils: bool,
    /// The ordering of the factors of K, A₀ and M ([`Model::fill_order`]).
    pub fill_order: FillOrder,
    /// The rigid motions the supports leave free (K's null space; empty
    /// for a held body): the static preload is solved on their complement.
    pub rigid_modes: Vec<RigidMode>,
}

impl Dynamics {
    /// The system of a finite-element model.
    pub fn from_model(model: &Model) -> Dynamics {
        Dynamics {
            stiffness: model.stiffness.clone(),
            consistent_mass: model.mass.clone(),
            lumped_mass: model.lumped_mass.clone(),
            constant_load: model.dirichlet_load.clone(),
            stencils: true,
            fill_order: model.fill_order.clone(),
            rigid_modes: model.dofs.rigid_modes().to_vec(),
        }
    }

    /// The system of a finite-element model, taking its matrices without a
    /// copy (K and M are the largest objects of a run).
    pub fn from_model_owned(model: Model) -> Dynamics {
        Dynamics {
            stiffness: model.stiffness,
            consistent_mass: model.mass,
            lumped_mass: model.lumped_mass,
            constant_load: model.dirichlet_load,
            stencils: true,
            rigid_modes: model.dofs.rigid_modes().to_vec(),
            fill_order: model.fill_order,
        }
    }

    /// With or without stencil types (see [`Dynamics::stencils`]).
    pub fn with_stencils(mut self, stencils: bool) -> Dynamics {
        self.stencils = stencils;
        self
    }

    /// Number of free DOFs.
    pub fn n(&self) -> usize {
        self.lumped_mass.len()
    }
}

/// A load vector on free DOFs scaled by a history θ(t).
#[derive(Clone, Debug)]
pub struct Load {
    /// The load at θ = 1.
    pub vector: Vec<f64>,
    /// θ(t).
    pub history: History,
}

/// The loads of a run: R(t) = constant + Σ θ_l(t) load_l.
#[derive(Clone, Debug)]
pub(crate) struct Loads {
    pub constant: Vec<f64>,
    pub loads: Vec<Load>,
}

impl Loads {
    /// R(t) into `out`.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.constant);
        for l in &self.loads {
            let theta = l.history.value(t);
            if theta != 0.0 {
                for (o, f) in out.iter_mut().zip(&l.vector) {
                    *o += theta * f;
                }
            }
        }
    }

    /// R(0⁻): the loads acting before the start (Remark 4.1's preload).
    pub fn before_start(&self) -> Vec<f64> {
        let mut r = self.constant.clone();
        for l in &self.loads {
            let theta = l.history.before_start();
            for (s, f) in r.iter_mut().zip(&l.vector) {
                *s += theta * f;
            }
        }
        r
    }
}
