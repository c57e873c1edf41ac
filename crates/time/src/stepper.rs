//! What every scheme implements: one step from the state at t to t + Δt,
//! and what it can say about its own work. The schemes share the state
//! ([`State`]), the loads, the contact surface and the settings ([`Run`]);
//! everything else is their own.

use stickslip_contact::ContactSurface;

use crate::dynamics::Loads;
use crate::settings::{MassKind, Settings, TimeError};
use crate::state::{State, StepInfo};

/// What a run holds besides its state and its scheme.
#[derive(Debug)]
pub(crate) struct Run {
    /// The friction surface; `None` when the scene has no friction node.
    pub contact: Option<ContactSurface>,
    /// R(t).
    pub loads: Loads,
    /// The settings the run was made with (t_end may change on a restart).
    pub settings: Settings,
}

/// A time-stepping scheme (see [`crate::Integrator::new`] for where each is
/// made).
pub(crate) trait Stepper: Send {
    /// Advances `state` by one step. A failed step leaves `state` at the
    /// last completed step.
    ///
    /// # Errors
    /// A failed linear solve, a stick/slip iteration that hits its cap, or
    /// a non-finite state.
    fn step(&mut self, run: &Run, state: &mut State) -> Result<StepInfo, TimeError>;

    /// The estimated critical step, for a conditionally stable scheme.
    fn dt_crit(&self) -> Option<f64> {
        None
    }

    /// True when a step solves no linear system.
    fn is_explicit(&self) -> bool;

    /// The mass the scheme uses (`None`: no inertia).
    fn mass_kind(&self) -> Option<MassKind>;

    /// How a step forms its products with K (for messages and results).
    fn stiffness_product(&self) -> &'static str;

    /// K's stencil types, where the step forms K·x from them.
    fn stencil_types(&self) -> Option<usize> {
        None
    }

    /// Numeric factorizations so far.
    fn factorizations(&self) -> u64 {
        0
    }

    /// Continues the count of factorizations from a checkpoint's.
    fn set_factorizations(&mut self, _count: u64) {}

    /// The state was replaced (a checkpoint restored): forget what the
    /// stepper formed ahead from the old one.
    fn state_replaced(&mut self) {}

    /// Values stored per factor of the step's operator.
    fn factor_len(&self) -> usize {
        0
    }

    /// (values of W = L⁻¹Pᵀ the step uses, values of the factor on the
    /// contact DOFs' paths to the root).
    fn paths_len(&self) -> (usize, usize) {
        (0, 0)
    }

    /// Bytes of K one step streams.
    fn matrix_bytes(&self) -> usize {
        0
    }

    /// Bytes one step moves through memory (explicit schemes).
    fn bytes_per_step(&self) -> usize {
        0
    }
}
