//! Sparse linear algebra for the solver: products with K and M in fixed
//! chunks of rows ([`chunks`], [`csr`], and by stencil types on structured
//! meshes, [`Stencils`], behind the explicit step's [`Product`]), the sparse
//! Cholesky factorization of symmetric positive definite operators (faer's
//! symbolic and numeric factorization, ordered by AMD or by a caller's
//! nested dissection), its one-column solves on the supernodal factor, and
//! solves restricted to a few rows ([`Supernodal`], [`PathOperator`]).
//!
//! It knows nothing of meshes, elements, friction or time stepping: only
//! matrices (nalgebra-sparse CSR with both triangles stored) and vectors.
//! Every product and sum gives the same bits on one thread and on many.

#![forbid(unsafe_code)]

mod cholesky;
pub mod chunks;
pub mod csr;
mod fill_order;
mod paired;
mod product;
mod refine;
pub mod simd;
mod split;
mod stencils;
mod supernodal;
mod symmetric;

pub use cholesky::{analyze_symbolic, csc_view, Analysis, SolverError, SparseCholesky};
pub use fill_order::{FillOrder, AMD_MARGIN};
pub use paired::PairedKm;
pub use product::{Formed, Product};
pub use refine::{backward_error, solve_by_diagonal, Refined, BACKWARD_ERROR, MAX_ITERATIONS};
pub use split::SplitSingle;
pub use stencils::{Stencils, BATCH, TOLERANCE};
pub use supernodal::{FactorValue, PathOperator, Supernodal};
pub use symmetric::Symmetric;
