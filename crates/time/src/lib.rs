//! Time integration of M r̈ + J(ṙ) + K r = R(t) with regularized friction.
//!
//! This crate owns the time-stepping schemes of the paper (§4.1, METHOD.md
//! §4), each a stepper of its own over one shared state (`state.rs`):
//! central difference (β = 0, γ = ½) with the lumped mass, truly explicit,
//! its nodal friction solved in closed form (`central_difference.rs`), and
//! Newmark (β, γ) written with the velocity as the unknown (`newmark/`),
//! its friction by the Schur complement on the contact DOFs or, as the
//! reference, by refactorizing A₀ + C per stuck set; and quasi-static load
//! increments (`quasi_static.rs`), the same solve without mass. Also the consistent
//! initial state (Remark 4.1, `initial.rs`), the step reduction after
//! sticking (Remark 4.3), the critical step of the explicit scheme
//! (`stability.rs`) and the energy ledger. It works on free-DOF vectors
//! and CSR matrices ([`Dynamics`]); it knows nothing of files, meshes or the
//! terminal. Output is the caller's business: it calls
//! [`Integrator::step`] and reads the state after each step.
//!
//! Work done is what the scene needs: no contact surface means no friction
//! code runs; the explicit scheme solves no linear system; the implicit
//! operator A₀ is analysed once and factorized once per distinct Δt.

#![forbid(unsafe_code)]

mod central_difference;
mod dynamics;
mod floating;
mod foundation;
mod history;
mod initial;
mod integrator;
mod newmark;
mod nodal;
mod preload_compliance;
mod pressure;
mod quasi_static;
mod settings;
pub mod stability;
mod state;
mod stepper;
mod sweep;

pub use dynamics::{Dynamics, Load};
pub use history::History;
pub use integrator::Integrator;
pub use settings::{
    ExplicitFriction, ImplicitSolver, InitialState, MassKind, Rayleigh, Scheme, Settings,
    StickReduction, TimeError, UnbalancedMotion, MAX_STABLE_STEPS,
};
pub use state::{Checkpoint, Energy, StepInfo};
