//! What the caller asks of a run: the scheme and its parameters, the step,
//! the end time, the options; and why a run could not start or a step
//! failed.

use stickslip_contact::IterationOptions;
use stickslip_fem::RigidMotion;
use stickslip_linalg::SolverError;

/// The time-stepping scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// β = 0, γ = ½ with the lumped mass: explicit, Δt < Δt_crit.
    CentralDifference,
    /// Newmark (β, γ): unconditionally stable for 2β ≥ γ ≥ ½.
    Newmark {
        /// β.
        beta: f64,
        /// γ.
        gamma: f64,
    },
    /// Load increments without inertia (`quasi_static.rs`): each step the
    /// static problem with friction on the increment's rate.
    QuasiStatic,
}

impl Scheme {
    /// (β, γ); NaN for quasi-static increments, which have none.
    pub fn parameters(self) -> (f64, f64) {
        match self {
            Scheme::CentralDifference => (0.0, 0.5),
            Scheme::Newmark { beta, gamma } => (beta, gamma),
            Scheme::QuasiStatic => (f64::NAN, f64::NAN),
        }
    }
}

/// Which mass matrix the scheme uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MassKind {
    /// Consistent mass (the paper's choice for Newmark).
    Consistent,
    /// HRZ lumped mass (the paper's choice for central difference).
    Lumped,
}

/// How the explicit scheme solves the friction of a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExplicitFriction {
    /// Each node's piecewise-linear monotone equation in closed form.
    ClosedForm,
    /// The stick/slip iteration of §5 (to check the closed form).
    Iterate,
}

/// How implicit steps solve their linear systems.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ImplicitSolver {
    /// A₀ factorized once per Δt, friction on the contact DOFs through the
    /// Schur complement (`newmark/schur.rs`), its restricted solves by
    /// W = L⁻¹Pᵀ or on the factor's paths, whichever reads fewer bytes.
    #[default]
    Schur,
    /// As [`ImplicitSolver::Schur`], always by W.
    SchurPaths,
    /// As [`ImplicitSolver::Schur`], always by solves on the paths.
    SchurReach,
    /// A₀ + C refactorized whenever Δt or the stuck set changes, the
    /// iteration on the full system (the reference).
    Direct,
}

/// Where a run starts (the case's `[initial] state`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum InitialState {
    /// Remark 4.1: r₀ the frictionless static equilibrium under the loads
    /// present at t = 0⁻.
    #[default]
    Static,
    /// r₀ = 0: every load acts from t = 0 on, nothing before.
    Rest,
}

/// Rayleigh damping C = αM + βK (METHOD.md §8), M the scheme's mass.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Rayleigh {
    /// α, the mass-proportional coefficient (1/time).
    pub alpha: f64,
    /// β, the stiffness-proportional coefficient (time).
    pub beta: f64,
}

impl Rayleigh {
    /// True when C ≠ 0.
    pub fn is_on(&self) -> bool {
        self.alpha != 0.0 || self.beta != 0.0
    }
}

/// Remark 4.3: after a step in which a node went from slip to stick, the
/// next `steps` steps use `dt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StickReduction {
    /// The reduced step.
    pub dt: f64,
    /// How many steps use it after each sticking event.
    pub steps: usize,
}

/// Everything about the time discretization.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Scheme.
    pub scheme: Scheme,
    /// Mass; `None` = the paper's (lumped for central difference, consistent
    /// for Newmark).
    pub mass: Option<MassKind>,
    /// Normal time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Step reduction after sticking.
    pub stick_reduction: Option<StickReduction>,
    /// Stick/slip iteration settings.
    pub iteration: IterationOptions,
    /// Run an explicit scheme above its critical step anyway.
    pub allow_unstable: bool,
    /// Closed-form or iterated friction in explicit steps.
    pub explicit_friction: ExplicitFriction,
    /// How implicit steps solve.
    pub implicit_solver: ImplicitSolver,
    /// r₀: Remark 4.1's static state (default) or rest.
    pub initial_state: InitialState,
    /// ṙ₀ (default zero).
    pub initial_velocity: Option<Vec<f64>>,
    /// Rayleigh damping (default none).
    pub damping: Rayleigh,
    /// The state will come from a checkpoint ([`crate::Integrator::restore`]):
    /// the initial static solve (Remark 4.1), whose factor of K would be
    /// most of a large restart's setup and peak memory, is skipped and r₀
    /// left 0 until the restore.
    pub restoring: bool,
}

impl Settings {
    /// Defaults for a scheme, Δt and end time.
    pub fn new(scheme: Scheme, dt: f64, t_end: f64) -> Settings {
        Settings {
            scheme,
            mass: None,
            dt,
            t_end,
            stick_reduction: None,
            iteration: IterationOptions::default(),
            allow_unstable: false,
            explicit_friction: ExplicitFriction::ClosedForm,
            implicit_solver: ImplicitSolver::Schur,
            initial_state: InitialState::Static,
            initial_velocity: None,
            damping: Rayleigh::default(),
            restoring: false,
        }
    }

    /// Checks the settings for a model of `n` free DOFs and returns the
    /// mass the scheme uses (quasi-static increments use none; the value
    /// is then unused).
    ///
    /// # Errors
    /// [`TimeError::Settings`] naming the setting and what to do.
    pub(crate) fn check(&self, n: usize) -> Result<MassKind, TimeError> {
        let bad = |m: String| Err(TimeError::Settings(m));
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return bad(format!(
                "time.dt = {}: the time step must be positive",
                self.dt
            ));
        }
        if !(self.t_end > 0.0 && self.t_end.is_finite()) {
            return bad(format!(
                "time.t_end = {}: the end time must be positive",
                self.t_end
            ));
        }
        if let Some(r) = self.stick_reduction {
            if !(r.dt > 0.0 && r.dt <= self.dt) {
                return bad(format!(
                    "time.stick_reduction.dt = {}: the reduced step must be positive and at most time.dt = {}",
                    r.dt, self.dt
                ));
            }
        }
        if self.iteration.max_iterations == 0 {
            return bad("contact.max_iterations must be at least 1".into());
        }
        let Rayleigh { alpha, beta } = self.damping;
        if !(alpha >= 0.0 && alpha.is_finite() && beta >= 0.0 && beta.is_finite()) {
            return bad(format!(
                "material.damping = {{ alpha = {alpha}, beta = {beta} }}: the Rayleigh coefficients \
                 must be finite and >= 0 (C = alpha M + beta K; 0 for none)"
            ));
        }
        if let Some(v0) = &self.initial_velocity {
            if v0.len() != n {
                return bad(format!(
                    "initial velocity has {} entries, the model {n} free DOFs",
                    v0.len()
                ));
            }
        }
        match (self.scheme, self.mass) {
            (Scheme::CentralDifference, Some(MassKind::Consistent)) => bad(
                "time.mass = \"consistent\" with central difference would need a linear solve per step; \
                 central difference uses the lumped mass: remove time.mass or set it to \"lumped\""
                    .into(),
            ),
            (Scheme::CentralDifference, _) => Ok(MassKind::Lumped),
            (Scheme::Newmark { beta, gamma }, m) => {
                if !(gamma >= 0.5 && 2.0 * beta >= gamma && beta.is_finite() && gamma.is_finite()) {
                    return bad(format!(
                        "Newmark β = {beta}, γ = {gamma} is outside the unconditionally stable range 2β ≥ γ ≥ ½ \
                         (the paper uses β = 0.25, γ = 0.5 or β = 0.3025, γ = 0.6); for an explicit run use \
                         time.scheme = \"central_difference\""
                    ));
                }
                Ok(m.unwrap_or(MassKind::Consistent))
            }
            (Scheme::QuasiStatic, _) if self.damping.is_on() => bad(
                "material.damping with time.scheme = \"quasi_static\": quasi-static increments have no \
                 inertia and no damping; remove material.damping"
                    .into(),
            ),
            (Scheme::QuasiStatic, _) if self.initial_velocity.is_some() => bad(
                "[initial] velocity with time.scheme = \"quasi_static\": quasi-static increments have no \
                 inertia, so no initial velocity; remove it"
                    .into(),
            ),
            (Scheme::QuasiStatic, None) => Ok(MassKind::Consistent),
            (Scheme::QuasiStatic, Some(_)) => bad(
                "time.mass with time.scheme = \"quasi_static\": quasi-static increments have no inertia; \
                 remove time.mass"
                    .into(),
            ),
        }
    }
}

/// More steps than a run could ever take (the case's bound on t_end/Δt):
/// a damped critical step that needs more to reach t_end leaves central
/// difference no usable stable step.
pub const MAX_STABLE_STEPS: f64 = 1e12;

/// Why a run could not start or a step failed.
#[derive(Debug, thiserror::Error)]
pub enum TimeError {
    /// A setting out of range; says which and what to do.
    #[error("{0}")]
    Settings(String),
    /// Δt above the explicit scheme's critical step.
    #[error(
        "time.dt = {dt:e} is above the critical step of central difference, Δt_crit = {dt_crit:.6e} \
         (2/ω_max, ω_max² the largest eigenvalue of M⁻¹K): use time.dt < {dt_crit:.4e}, \
         or set time.allow_unstable = true to run anyway"
    )]
    Unstable {
        /// The step asked for.
        dt: f64,
        /// The estimated critical step.
        dt_crit: f64,
    },
    /// Δt above the explicit scheme's critical step with stiffness-
    /// proportional damping.
    #[error(
        "time.dt = {dt:e} is above the critical step of central difference with Rayleigh damping \
         beta = {beta:e}: at ω_max = {omega:.6e} (the largest of M⁻¹K) the damping ratio is \
         ξ = beta ω_max / 2 = {xi:.4e}, and Δt_crit = (2/ω_max)(√(1+ξ²) − ξ) = {dt_crit:.6e} \
         (undamped {undamped:.6e}){no_step}: use time.dt < {dt_crit:.4e}, lower material.damping.beta, \
         or use time.scheme = \"newmark\" (unconditionally stable with any damping)"
    )]
    UnstableDamped {
        /// The step asked for.
        dt: f64,
        /// The critical step with damping.
        dt_crit: f64,
        /// The critical step without damping, 2/ω_max.
        undamped: f64,
        /// ω_max.
        omega: f64,
        /// β.
        beta: f64,
        /// ξ at ω_max.
        xi: f64,
        /// Where Δt_crit is not a positive normal number or a stable run to
        /// t_end would take more than [`MAX_STABLE_STEPS`] steps, what
        /// says so ("so small that ..."), else "".
        no_step: String,
    },
    /// The initial static solve failed (rigid-body motion left free).
    #[error(
        "the initial static solve failed: {0}; the supports leave a rigid-body motion free: \
         add Dirichlet conditions that fix translation in x and y and rotation"
    )]
    Static(SolverError),
    /// The loads present before t = 0 do work along a rigid motion the
    /// supports leave free: the static preload has no solution.
    #[error(
        "the loads present before t = 0 (the \"constant\" histories, the contact pressure, the body \
         force) are not in equilibrium along the rigid motions the supports leave free, so the \
         initial static state (Remark 4.1) does not exist: {}; start at rest ([initial] state = \
         \"rest\": every load acts from t = 0 on), or balance the loads (or hold the part with \
         [[dirichlet]] conditions)",
        unbalanced_list(.0)
    )]
    Unbalanced(Vec<UnbalancedMotion>),
    /// A factorization failed during the run.
    #[error("step {step} (t = {t:.6e}): the linear solve failed: {source}")]
    Solve {
        /// Step number (1-based).
        step: u64,
        /// Time the step was going to.
        t: f64,
        /// The solver's error.
        source: SolverError,
    },
    /// The stick/slip iteration did not settle.
    #[error(
        "step {step} (t = {t:.6e}): the stick/slip iteration did not converge in {iterations} \
         iterations ({changing} nodes still changing class); {hint}raise contact.max_iterations, \
         reduce time.dt, or raise contact.eps (a regularization far below the slip speeds makes \
         the law a step that the iteration can cycle on)"
    )]
    IterationCap {
        /// Step number (1-based).
        step: u64,
        /// Time the step was going to.
        t: f64,
        /// Iterations performed.
        iterations: usize,
        /// Nodes still changing class.
        changing: usize,
        /// "enable Remark 4.2 (…), " where the run had it off, else "".
        hint: &'static str,
    },
    /// NaN or infinity in the state.
    #[error("step {step} (t = {t:.6e}): the solution is no longer finite; reduce time.dt{hint}")]
    NonFinite {
        /// Step number (1-based).
        step: u64,
        /// Time reached.
        t: f64,
        /// Extra advice (the critical step of an explicit run).
        hint: String,
    },
    /// The Newton solve of a compliant foundation's normal and friction
    /// forces did not converge (Newmark).
    #[error(
        "step {step} (t = {t:.6e}): the normal-compliance Newton solve did not converge in \
         {iterations} iterations (residual {residual:.3e} of scale {scale:.3e}); reduce time.dt, \
         soften the foundation (contact.cn), raise contact.eps, or ramp a load that comes in \
         whole at its first step (a table history from 0: no step is short enough for it)"
    )]
    NormalSolve {
        /// Step number (1-based).
        step: u64,
        /// Time the step was going to.
        t: f64,
        /// Newton iterations performed.
        iterations: usize,
        /// The largest residual left.
        residual: f64,
        /// The size the residual is measured against.
        scale: f64,
    },
}

/// A rigid motion the loads present before t = 0 do work along
/// ([`TimeError::Unbalanced`]).
#[derive(Clone, Debug, PartialEq)]
pub struct UnbalancedMotion {
    /// Its name: "translation in x", "rotation about (x, y)", ..., with
    /// the part of the mesh it moves where there are several.
    pub label: String,
    /// What the motion is (`None` for a combination that is no one
    /// motion).
    pub motion: Option<RigidMotion>,
    /// The loads' work along it: the net force along a unit translation,
    /// the moment about a rotation's centre.
    pub work: f64,
}

/// "translation in x: net force F_x = …; translation along (a, b): net
/// force along it F = …; rotation about (x, y): moment M = …": a unit
/// translation's work is the net force along it, a unit rotation's the
/// moment about its centre; any other combination of motions is given by
/// the loads' work along it. A unit translation in x or y names its axis.
fn unbalanced_list(motions: &[UnbalancedMotion]) -> String {
    motions
        .iter()
        .map(|m| {
            let (label, work) = (&m.label, m.work);
            match m.motion {
                Some(RigidMotion::Translation(d)) if d == [1.0, 0.0] || d == [0.0, 1.0] => {
                    let axis = if d[0] == 1.0 { "x" } else { "y" };
                    format!("{label}: net force F_{axis} = {work:.6e}")
                }
                Some(RigidMotion::Translation(_)) => {
                    format!("{label}: net force along it F = {work:.6e}")
                }
                Some(RigidMotion::Rotation(_)) => format!("{label}: moment M = {work:.6e}"),
                None => format!("{label}: the loads' work along it W = {work:.6e}"),
            }
        })
        .collect::<Vec<_>>()
        .join("; ")
}

impl TimeError {
    /// The stick/slip iteration's failure as the step's error: the cap, or
    /// the failed solve as `solve` maps it.
    pub(crate) fn from_iteration<E>(
        failure: stickslip_contact::IterationFailure<E>,
        (step, t, remark_4_2): (u64, f64, bool),
        solve: impl FnOnce(E) -> TimeError,
    ) -> TimeError {
        match failure {
            stickslip_contact::IterationFailure::Cap {
                iterations,
                changing,
            } => TimeError::IterationCap {
                step,
                t,
                iterations,
                changing,
                hint: if remark_4_2 {
                    ""
                } else {
                    "enable Remark 4.2 (contact.remark_4_2 = true, the default), "
                },
            },
            stickslip_contact::IterationFailure::Solve(e) => solve(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each motion's work is named by what the motion is: a net force
    /// along a unit axis (F_x, F_y), along another direction (F, the
    /// sign of (−1, 0) kept in the label's direction), a moment, or the
    /// work along a combination.
    #[test]
    fn an_unbalanced_motion_is_named_by_its_kind() {
        let motion = |label: &str, motion, work| UnbalancedMotion {
            label: label.into(),
            motion,
            work,
        };
        let list = unbalanced_list(&[
            motion(
                "translation in y",
                Some(RigidMotion::Translation([0.0, 1.0])),
                2.0,
            ),
            motion(
                "translation along (-1.000000, 0.000000)",
                Some(RigidMotion::Translation([-1.0, 0.0])),
                3.0,
            ),
            motion(
                "rotation about (0, 0)",
                Some(RigidMotion::Rotation([0.0, 0.0])),
                4.0,
            ),
            motion("a combination of a and b", None, 5.0),
        ]);
        assert_eq!(
            list,
            "translation in y: net force F_y = 2.000000e0; \
             translation along (-1.000000, 0.000000): net force along it F = 3.000000e0; \
             rotation about (0, 0): moment M = 4.000000e0; \
             a combination of a and b: the loads' work along it W = 5.000000e0"
        );
    }
}
