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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::surface::ContactNode;

    /// Nodes with one unknown each, m v = b − w g sign when slipping and
    /// (m + w g/ε) v = b when stuck: the system of METHOD.md §4 for a mass
    /// m on a frictional line, written out here.
    pub(crate) struct Masses {
        pub mass: Vec<f64>,
        pub b: Vec<f64>,
        pub solves: usize,
    }

    impl StepSystem for Masses {
        type Error = ();

        fn solve(
            &mut self,
            surface: &ContactSurface,
            classes: &[SlipState],
            velocity: &mut [f64],
        ) -> Result<(), ()> {
            self.solves += 1;
            for (j, (n, c)) in surface.nodes.iter().zip(classes).enumerate() {
                let wg = n.weight * n.bound;
                velocity[j] = match c {
                    SlipState::Stuck => self.b[j] / (self.mass[j] + wg / surface.law.eps),
                    SlipState::SlipPositive => (self.b[j] - wg) / self.mass[j],
                    SlipState::SlipNegative => (self.b[j] + wg) / self.mass[j],
                };
            }
            Ok(())
        }
    }

    /// Node j on unknown j, w = 1 and g = 1.
    pub(crate) fn unit_node(j: usize) -> ContactNode {
        ContactNode {
            node: j,
            dofs: [Some(j), None],
            weight: 1.0,
            tangent: [1.0, 0.0],
            s: j as f64,
            bound: 1.0,
        }
    }

    /// Remark 4.2 on a cycling case: node 0 (m = 1, b = 0.5, w g = 1, ε =
    /// 0.01) slipped forward at the last step and now unloads. Slipping
    /// forward gives v = b − w g = −0.5 (backward), slipping backward v =
    /// b + w g = 1.5 (forward): without the rule the iteration alternates
    /// between the two for ever, with node 1 (b = 5 > w g, slipping) settled,
    /// and stops at the cap with one node changing. With the rule the
    /// reversal makes node 0 stuck, v = b/(m + w g/ε) = 0.5/101 < ε, which
    /// the next solve confirms: converged in two solves, to the stuck
    /// solution (its value from that formula, to one rounding).
    #[test]
    fn remark_4_2_ends_a_cycle_between_slip_directions() {
        let eps = 0.01;
        let surface =
            ContactSurface::from_nodes("line", vec![unit_node(0), unit_node(1)], eps).unwrap();
        let cap = 50;
        // From forward slip at the last step, with and without the rule:
        // the outcome, the solves made, the classes and velocities left.
        let run = |remark_4_2: bool| {
            let mut masses = Masses {
                mass: vec![1.0, 1.0],
                b: vec![0.5, 5.0],
                solves: 0,
            };
            let mut classes = vec![SlipState::SlipPositive; 2];
            let (mut scratch, mut v) = (classes.clone(), vec![0.0; 2]);
            let options = IterationOptions {
                remark_4_2,
                max_iterations: cap,
            };
            let result = iterate(
                &surface,
                &mut masses,
                &mut classes,
                &mut scratch,
                &mut v,
                options,
            );
            (result, masses.solves, classes, v)
        };

        let (without, solves, classes, _) = run(false);
        assert_eq!(
            without,
            Err(IterationFailure::Cap {
                iterations: cap,
                changing: 1
            })
        );
        assert_eq!(solves, cap);
        // Still alternating at the cap: an even number of solves from
        // forward slip leaves node 0 classed forward again, node 1 unchanged.
        assert_eq!(classes, [SlipState::SlipPositive, SlipState::SlipPositive]);

        let (with, solves, classes, v) = run(true);
        assert_eq!(with, Ok(IterationReport { iterations: 2 }));
        assert_eq!(solves, 2);
        assert_eq!(classes, [SlipState::Stuck, SlipState::SlipPositive]);
        let stuck = 0.5 / 101.0;
        assert!(
            (v[0] - stuck).abs() <= f64::EPSILON * stuck,
            "{} vs {stuck}",
            v[0]
        );
        assert!(v[0] < eps);
        assert_eq!(v[1], 4.0);
    }
}
