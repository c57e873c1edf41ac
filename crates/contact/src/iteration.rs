//! The successive-approximation stick/slip iteration (paper §4.2,
//! METHOD.md §5), independent of the time-stepping scheme.

use crate::law::SlipState;
use crate::surface::ContactSurface;

/// The linear part of one time step, provided by the integrator: for given
/// node classes it solves (A + C(classes)) ṙ = b − F(classes).
pub trait StepSystem {
    /// Error of a linear solve (e.g. a failed factorization).
    type Error;
    /// Solves for the velocity with the damping/slip forces of `classes`,
    /// writing the free-DOF velocity into `velocity`.
    ///
    /// # Errors
    /// Whatever the linear solve reports.
    fn solve(
        &mut self,
        surface: &ContactSurface,
        classes: &[SlipState],
        velocity: &mut [f64],
    ) -> Result<(), Self::Error>;
}

/// Settings of the iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IterationOptions {
    /// Apply Remark 4.2: a node whose slip direction would reverse between
    /// two iterations is set to stuck instead. On by default; without it the
    /// iteration can cycle between the two directions on unloading.
    pub remark_4_2: bool,
    /// Iterations allowed per step before giving up.
    pub max_iterations: usize,
}

impl Default for IterationOptions {
    fn default() -> Self {
        IterationOptions {
            remark_4_2: true,
            max_iterations: 100,
        }
    }
}

/// What a converged iteration did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IterationReport {
    /// Linear solves performed (≥ 1).
    pub iterations: usize,
}

/// Why the iteration stopped without converging.
#[derive(Clone, Debug, PartialEq)]
pub enum IterationFailure<E> {
    /// The cap was reached; `changing` nodes still changed class in the last
    /// iteration (typically cycling between slip directions).
    Cap {
        /// Iterations performed.
        iterations: usize,
        /// Nodes whose class changed in the last iteration.
        changing: usize,
    },
    /// A linear solve failed.
    Solve(E),
}

/// Runs the iteration of METHOD.md §5 for one step.
///
/// On entry `classes` holds the classes of the converged previous step
/// (step 1 of §5) and `scratch` has the same length; on success `classes`
/// and `velocity` hold the converged step, for which the regularized
/// equation holds exactly (every node's class is that of its velocity).
///
/// # Errors
/// [`IterationFailure::Cap`] when `max_iterations` solves did not settle the
/// classes, [`IterationFailure::Solve`] when a solve failed.
pub fn iterate<S: StepSystem>(
    surface: &ContactSurface,
    system: &mut S,
    classes: &mut [SlipState],
    scratch: &mut [SlipState],
    velocity: &mut [f64],
    options: IterationOptions,
) -> Result<IterationReport, IterationFailure<S::Error>> {
    let mut changing = 0;
    for iteration in 1..=options.max_iterations {
        system
            .solve(surface, classes, velocity)
            .map_err(IterationFailure::Solve)?;
        // Step 2: reclassify every node from the new velocity.
        surface.classify(velocity, scratch);
        if options.remark_4_2 {
            for (new, old) in scratch.iter_mut().zip(classes.iter()) {
                if new.reverses(*old) {
                    *new = SlipState::Stuck;
                }
            }
        }
        // Step 3: converged when no node changed class.
        changing = scratch
            .iter()
            .zip(classes.iter())
            .filter(|(a, b)| a != b)
            .count();
        if changing == 0 {
            return Ok(IterationReport {
                iterations: iteration,
            });
        }
        classes.copy_from_slice(scratch);
    }
    Err(IterationFailure::Cap {
        iterations: options.max_iterations,
        changing,
    })
}
