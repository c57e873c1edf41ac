//! Time integration of M r̈ + J(ṙ) + K r = R(t) with regularized friction.
//!
//! This crate owns the time-stepping schemes of the paper (§4.1, METHOD.md
//! §4): Newmark (β, γ) written with the velocity as the unknown, central
//! difference (β = 0, γ = ½) with the lumped mass as a truly explicit scheme
//! whose nodal friction is solved in closed form, the consistent initial
//! state (Remark 4.1), the step reduction after sticking (Remark 4.3), the
//! critical step of the explicit scheme, and the energy ledger. It works on
//! free-DOF vectors and CSR matrices ([`Dynamics`]); it knows nothing of
//! files, meshes or the terminal. Output is the caller's business: it calls
//! [`Integrator::step`] and reads the state after each step.
//!
//! Work done is what the scene needs: no contact surface means no friction
//! code runs; the explicit scheme solves no linear system; the implicit
//! operator A₀ is analysed once and factorized once per distinct Δt, the
//! friction handled by a Schur complement on the contact DOFs
//! ([`ImplicitSolver::Schur`], the default; [`ImplicitSolver::Direct`]
//! refactorizes A₀ + C per stuck set and is kept as the reference). On
//! systems of up to [`MODAL_MAX_DOFS`] free DOFs the implicit state is held
//! in the modes of (K, M) instead ([`ImplicitSolver::Modal`]): A₀ is
//! diagonal there and a step forms no product with K or M.

mod history;
mod implicit;
mod integrator;
mod kernels;
pub mod linalg;
mod memory;
mod modal;
mod nodal;
pub mod scenes;
mod schur;
mod sliced;
mod small_solve;
pub mod stability;
mod stencils;

pub use history::History;
pub use integrator::{
    Checkpoint, Dynamics, Energy, ExplicitFriction, Integrator, Load, MassKind, Scheme, Settings,
    StepInfo, StickReduction, TimeError,
};
pub use kernels::{CHUNK, PARALLEL_MIN};
pub use modal::MODAL_MAX_DOFS;
pub use schur::ImplicitSolver;
