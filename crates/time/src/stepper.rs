//! What every scheme implements: one step from the state at t to t + Δt,
//! and what it can say about its own work. The schemes share the state
//! ([`State`]), the loads, the contact surface and the settings ([`Run`]);
//! everything else is their own.

use stickslip_contact::ContactSurface;
use stickslip_linalg::FillOrder;

use crate::dynamics::Loads;
use crate::initial::Mass;
use crate::newmark::ImplicitFriction;
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
    fn step(&mut self, run: &mut Run, state: &mut State) -> Result<StepInfo, TimeError>;

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

    /// x = M⁻¹ x with the mass its steps use (no inertia: x = 0), for r̈₀
    /// where the friction at t = 0 changes after the start.
    ///
    /// # Errors
    /// [`TimeError::Static`] where a consistent M's factorization fails.
    fn solve_mass(&self, x: &mut [f64], fill_order: &FillOrder) -> Result<(), TimeError> {
        Mass::Massless.solve_in_place(x, fill_order, None).map(drop)
    }

    /// K's stencil types, where the step forms K·x from them.
    fn stencil_types(&self) -> Option<usize> {
        None
    }

    /// The step's implicit solve with friction, where it has one (its
    /// factorizations and the sizes of its factor).
    fn implicit(&self) -> Option<&ImplicitFriction> {
        None
    }

    /// [`Stepper::implicit`], to continue its count from a checkpoint's.
    fn implicit_mut(&mut self) -> Option<&mut ImplicitFriction> {
        None
    }

    /// The state was replaced (a checkpoint restored): forget what the
    /// stepper formed ahead from the old one.
    fn state_replaced(&mut self) {}

    /// Bytes of K one step streams.
    fn matrix_bytes(&self) -> usize {
        0
    }

    /// Bytes one step moves through memory (explicit schemes).
    fn bytes_per_step(&self) -> usize {
        0
    }
}
