//! Regularized Coulomb friction on a contact line (Martins & Oden 1983).
//!
//! This crate owns the friction part of the problem: the regularized law
//! ψ_ε/φ_ε (METHOD.md §2), the contact surface as the nodes of a named line
//! group with their nodal quadrature weights, unit tangents and friction
//! bounds g = μ·F_n (§3), the stick/slip classification of each node, the
//! damping and slip-force contributions C and F, and the successive
//! approximation of §5 with the Remark 4.2 rule. It knows nothing about time
//! stepping schemes: the iteration asks a [`StepSystem`] to solve the linear
//! system for given classes, and the time crate provides it.
//!
//! Nodal quadrature on Γ_C means friction couples no two nodes, so a node's
//! friction lives on its own two DOFs only; every routine here is per node.

mod iteration;
mod law;
mod ledger;
mod surface;

pub use iteration::{iterate, IterationFailure, IterationOptions, IterationReport, StepSystem};
pub use law::{FrictionLaw, SlipState};
pub use ledger::stick_events;
pub use surface::{ContactError, ContactNode, ContactSurface};
