//! Regularized Coulomb friction on a contact line (Martins & Oden 1983).
//!
//! This crate owns every formula of the friction law, so that the
//! integrators only call it: the regularized law ψ_ε/φ_ε (METHOD.md §2) and
//! the stick/slip classification; the contact surface as the nodes of a
//! named line group with their nodal quadrature weights, unit tangents and
//! friction bounds g = μ·F_n (§3), and per node the stuck damping w g/ε,
//! the slip force w g sign(v) and the friction force; the closed-form
//! nodal solve of a step whose operator is diagonal (the lumped mass over
//! γΔt of the explicit scheme, §4), with its constants formed once per Δt;
//! the successive approximation of §5 with the Remark 4.2 rule; and the
//! friction's share of the energy ledger (§6). It knows nothing about time
//! stepping schemes or how a stiffness product is formed: the iteration
//! asks a [`StepSystem`] to solve the linear system for given classes, the
//! closed form takes the right-hand side at the contact DOFs from its
//! caller, and the time crate provides both.
//!
//! Nodal quadrature on Γ_C means friction couples no two nodes, so a node's
//! friction lives on its own two DOFs only; every routine here is per node.

#![forbid(unsafe_code)]

mod compliance;
mod foundation;
mod iteration;
mod lagged_mu;
mod law;
mod ledger;
mod mu_speed;
mod nodal;
mod regularization;
mod surface;

pub use compliance::{Compliance, CompliantNode, Foundation};
pub use iteration::{iterate, IterationFailure, IterationOptions, IterationReport, StepSystem};
pub use law::{FrictionLaw, SlipState};
pub use ledger::stick_events;
pub use mu_speed::Weakening;
pub use nodal::{DiagonalStep, NodalClosedForm};
pub use surface::{ContactError, ContactNode, ContactSurface, SurfacePart};
