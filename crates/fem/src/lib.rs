//! Q1/Q2 plane elasticity on a [`stickslip_mesh::Mesh`]: the matrices and
//! vectors of METHOD.md §3 and the constraint bookkeeping.
//!
//! This crate owns the reference elements ([`mod@reference`], shape functions
//! into caller buffers), Gauss rules ([`quadrature`]), the isoparametric map
//! ([`geometry`]), the material ([`Material`]), element operators
//! ([`element`]: stiffness, consistent and HRZ-lumped mass, body force), the
//! DOF map with Dirichlet conditions on named groups ([`DofMap`]), assembly
//! into `nalgebra-sparse` CSR with a pattern built once and values filled in
//! place ([`Model`], K and M sharing one pattern), consistent loads
//! ([`traction_load`], [`body_force_load`]), nodal quadrature on boundary
//! lines ([`boundary_quadrature`], on which `contact` builds), the nested
//! dissection that orders its factors ([`ordering`]), the static solve and
//! stress recovery (the sparse Cholesky is `stickslip-linalg`'s). It
//! knows nothing of friction or time stepping; boundaries are reached by
//! physical group name only.

#![forbid(unsafe_code)]

mod assembly;
pub mod boundary;
mod cut;
pub mod dofs;
pub mod element;
mod error;
pub mod geometry;
pub mod loads;
pub mod material;
pub mod model;
pub mod ordering;
mod pattern;
pub mod quadrature;
pub mod reference;
mod setup_times;
pub mod statics;

pub use boundary::{boundary_quadrature, BoundaryNode};
pub use dofs::{Dirichlet, DofMap, NodeOrder, RigidMode, RigidMotion};
pub use error::FemError;
pub use loads::{
    body_force_load, body_force_load_with, traction_load, traction_load_with, Traction,
};
pub use material::{Hypothesis, Material};
pub use model::Model;
pub use pattern::{free_dof_pattern, node_adjacency, Adjacency};
pub use setup_times::SetupTimes;
pub use statics::{
    gauss_point_stresses, nodal_stresses, static_solve, stress_at_node, von_mises, GaussPointStress,
};

/// The physical group `name` of `mesh`, wanted for `purpose`.
pub(crate) fn find_group<'m>(
    mesh: &'m stickslip_mesh::Mesh,
    name: &str,
    purpose: &str,
) -> Result<&'m stickslip_mesh::Group, FemError> {
    mesh.group(name).map_err(|_| FemError::UnknownGroup {
        name: name.to_string(),
        purpose: purpose.to_string(),
        available: mesh.group_names().iter().map(|s| s.to_string()).collect(),
    })
}
