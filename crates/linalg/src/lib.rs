//! Sparse linear algebra for the solver: the sparse Cholesky factorization
//! of symmetric positive definite operators (faer's symbolic and numeric
//! factorization, ordered by AMD or by a caller's nested dissection), its
//! one-column solves on the supernodal factor, and solves restricted to a
//! few rows ([`Supernodal`], [`PathOperator`]).
//!
//! It knows nothing of meshes, elements, friction or time stepping: only
//! matrices (nalgebra-sparse CSR with both triangles stored) and vectors.

mod cholesky;
mod fill_order;
mod supernodal;

pub use cholesky::{analyze_symbolic, csc_view, SolverError, SparseCholesky};
pub use fill_order::{FillOrder, AMD_MARGIN};
pub use supernodal::{PathOperator, Supernodal};
