//! The Newmark family in velocity form with friction (paper §4.1-4.2).

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{
    iterate, stick_events, ContactSurface, DiagonalStep, IterationFailure, IterationOptions,
    SlipState,
};
use stickslip_fem::{ElementClasses, FillOrder, Model, SolverError, SparseCholesky};

use crate::history::History;
use crate::implicit::{ImplicitOperator, ImplicitStep};
use crate::kernels::{self, Lanes, RowProduct};
use crate::linalg::{
    self, dot, load_minus_k_plus_m, quadratic_form, row_chunks, same_pattern, spmv, two_forms,
    PairBlocks,
};
use crate::modal::{self, ModalState, Modes, MODAL_MAX_DOFS};
use crate::nodal::NodalFriction;
use crate::schur::{ImplicitSolver, SchurOperator};
use crate::stability::{critical_step, critical_step_with};

/// The semi-discrete system on free DOFs: K, M (consistent, with K's
/// sparsity pattern), the HRZ lumped mass, and loads that never change
/// (e.g. the lifting of nonzero prescribed displacements).
#[derive(Clone, Debug)]
pub struct Dynamics {
    /// Stiffness K.
    pub stiffness: CsrMatrix<f64>,
    /// Consistent mass M, same pattern as K.
    pub consistent_mass: CsrMatrix<f64>,
    /// Lumped mass, one value per free DOF.
    pub lumped_mass: Vec<f64>,
    /// A load acting at all times, also before t = 0.
    pub constant_load: Vec<f64>,
    /// K's cells in classes of alike geometry ([`ElementClasses`], from the
    /// mesh): when present the explicit step forms K·x from them, matrix-free,
    /// instead of streaming the assembled K (`kernels::Classes`). Not the
    /// assembled K's bits (within 1e-12 of the row's Σ|K_ij x_j|).
    pub element_classes: Option<ElementClasses>,
    /// Whether the explicit step may form K·x from K's stencil types
    /// (`kernels::Stencils`: node rows alike to 1e-12 of max |K_ij| share
    /// one copy; on structured meshes numbered row by row). Default true;
    /// false keeps the assembled K's bits (the compact form's products).
    pub stencils: bool,
    /// The ordering of the factors of K, A₀ and M ([`Model::fill_order`]).
    pub fill_order: FillOrder,
}

impl Dynamics {
    /// The system of a finite-element model.
    pub fn from_model(model: &Model) -> Dynamics {
        Dynamics {
            stiffness: model.stiffness.clone(),
            consistent_mass: model.mass.clone(),
            lumped_mass: model.lumped_mass.clone(),
            constant_load: model.dirichlet_load.clone(),
            element_classes: None,
            stencils: true,
            fill_order: model.fill_order.clone(),
        }
    }

    /// The system of a finite-element model, taking its matrices without a
    /// copy (the model's K and M are the largest objects of a run; holding
    /// them twice doubles its memory).
    pub fn from_model_owned(model: Model) -> Dynamics {
        Dynamics {
            stiffness: model.stiffness,
            consistent_mass: model.mass,
            lumped_mass: model.lumped_mass,
            constant_load: model.dirichlet_load,
            element_classes: None,
            stencils: true,
            fill_order: model.fill_order,
        }
    }

    /// With the element classes of the model's mesh (see
    /// [`Dynamics::element_classes`]; `None` leaves the assembled K).
    pub fn with_element_classes(mut self, classes: Option<ElementClasses>) -> Dynamics {
        self.element_classes = classes;
        self
    }

    /// With or without stencil types (see [`Dynamics::stencils`]).
    pub fn with_stencils(mut self, stencils: bool) -> Dynamics {
        self.stencils = stencils;
        self
    }

    /// Number of free DOFs.
    pub fn n(&self) -> usize {
        self.lumped_mass.len()
    }
}

/// A load vector on free DOFs scaled by a history θ(t).
#[derive(Clone, Debug)]
pub struct Load {
    /// The load at θ = 1.
    pub vector: Vec<f64>,
    /// θ(t).
    pub history: History,
}

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
}

impl Scheme {
    /// (β, γ).
    pub fn parameters(self) -> (f64, f64) {
        match self {
            Scheme::CentralDifference => (0.0, 0.5),
            Scheme::Newmark { beta, gamma } => (beta, gamma),
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
    /// ṙ₀ (default zero).
    pub initial_velocity: Option<Vec<f64>>,
    /// How often the caller reads the state (`Some(1)`: after every
    /// step; `None`: seldom), for the implicit solver's choice: the modal
    /// step ([`MODAL_MAX_DOFS`]) pays 3n² for each read, so it is the
    /// default only where reads come every second step or less often.
    pub reads_every: Option<u64>,
    /// The state will come from a checkpoint ([`Integrator::restore`]):
    /// the initial static solve (Remark 4.1), whose factor of K was half a
    /// restart's setup and most of its peak memory (Q1 501k DOFs: about
    /// 1.8 s and 560 MB), is skipped and r₀ left 0 until the restore.
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
            initial_velocity: None,
            reads_every: None,
            restoring: false,
        }
    }
}

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
    /// The initial static solve failed (rigid-body motion left free).
    #[error(
        "the initial static solve failed: {0}; the supports leave a rigid-body motion free: \
         add Dirichlet conditions that fix translation in x and y and rotation"
    )]
    Static(SolverError),
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
         or reduce time.dt"
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
}

/// The energy ledger (METHOD.md §6), all at the current time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// ½ ṙᵀMṙ with the mass the scheme uses.
    pub kinetic: f64,
    /// ½ rᵀKr.
    pub strain: f64,
    /// ∫ R·ṙ dt, trapezoidal rule: Σ ½(R_K + R_{K−1})·(r_K − r_{K−1}).
    pub external_work: f64,
    /// ∫ J·ṙ dt, trapezoidal rule: Σ ½(J_K + J_{K−1})·½Δt(ṙ_K + ṙ_{K−1}),
    /// ≥ 0 step by step since φ_ε is odd and increasing.
    pub dissipated: f64,
    /// kinetic + strain − rᵀR(t): the paper's total energy (Fig. 9).
    pub total: f64,
    /// kinetic + strain − initial − work + dissipated; zero up to round-off
    /// for the trapezoidal rule (Newmark ¼, ½).
    pub balance: f64,
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// The step size used.
    pub dt: f64,
    /// Linear solves (implicit) or iterations (explicit) of the stick/slip
    /// iteration; 1 without contact.
    pub iterations: usize,
    /// Nodes that went from slip to stick in this step.
    pub stick_events: usize,
}

/// Everything needed to continue a run bit-identically
/// ([`Integrator::checkpoint`], [`Integrator::restore`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// Time reached.
    pub t: f64,
    /// Steps completed.
    pub steps: u64,
    /// r on free DOFs.
    pub displacement: Vec<f64>,
    /// ṙ on free DOFs.
    pub velocity: Vec<f64>,
    /// r̈ on free DOFs.
    pub acceleration: Vec<f64>,
    /// [`SlipState::code`] per contact node.
    pub classes: Vec<i8>,
    /// Nodal friction forces f_J of the last step (the energy ledger's
    /// trapezoidal rule needs them).
    pub forces: Vec<f64>,
    /// The energy ledger.
    pub energy: Energy,
    /// Kinetic + strain energy at t = 0 (for the balance).
    pub initial_mechanical: f64,
    /// Remark 4.3 step-reduction counter.
    pub reduced_remaining: u64,
    /// The clock ([`Clock`]): t₀, Δt and steps of the current run of
    /// equal steps (`None` in files written before it: the continued run
    /// then starts a new run of steps at `t`).
    pub clock: Option<(f64, f64, u64)>,
    /// Stick/slip iterations so far.
    pub total_iterations: u64,
    /// Numeric factorizations so far.
    pub factorizations: u64,
    /// The modal step's own state (`modal.rs`), for a bit-identical
    /// continuation: q, q̇, q̈ (n each) and the contact nodes' tangential
    /// velocities; empty from other solvers (a modal run then projects the
    /// physical state).
    pub modal: Vec<f64>,
}

/// The time of each step without drift: over a run of steps of one Δt
/// (Remark 4.3's reduced step starts another), t_k = t₀ + k Δt, one
/// rounding a step. Summing Δt step by step drifted (1.8e-10 over 300,000
/// steps of 1e-3) and left a sliver of a last step to reach t_end, which
/// cost Newmark a second factorization for a Δt of 1e-11.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Clock {
    t0: f64,
    dt: f64,
    k: u64,
}

/// A step that ends within this fraction of its Δt of t_end ends on t_end
/// with its Δt unchanged (rounding of t, not a step of its own).
const END_SLACK: f64 = 1e-6;

impl Clock {
    fn new(t0: f64, dt: f64) -> Clock {
        Clock { t0, dt, k: 0 }
    }

    /// The time after one more step of `dt` from `t`.
    fn after(&self, t: f64, dt: f64) -> f64 {
        if dt == self.dt {
            self.t0 + (self.k + 1) as f64 * dt
        } else {
            t + dt
        }
    }

    /// One step of `dt` from `t` was taken.
    fn tick(&mut self, t: f64, dt: f64) {
        if dt == self.dt {
            self.k += 1;
        } else {
            *self = Clock { t0: t, dt, k: 1 };
        }
    }
}

/// Integrates from the initial state to `t_end`, one step per call.
pub struct Integrator {
    dynamics: Dynamics,
    contact: Option<ContactSurface>,
    loads: Vec<Load>,
    settings: Settings,
    beta: f64,
    gamma: f64,
    mass_kind: MassKind,
    explicit: bool,
    dt_crit: Option<f64>,
    /// Mass as a CSR matrix with K's pattern (a diagonal one when lumped).
    mass_matrix: CsrMatrix<f64>,
    /// The direct path (A₀ + C refactorized per stuck set), when chosen.
    implicit: Option<ImplicitOperator>,
    /// The Schur-complement path (the default for implicit schemes).
    schur: Option<SchurOperator>,
    solver: ImplicitSolver,
    /// Nodal tangential velocities of the Schur path's iteration.
    nodal_velocity: Vec<f64>,
    /// The modal step (`modal.rs`): `r`, `v`, `a`, `load`, `load_new`
    /// and the step's vectors then hold modal coordinates.
    modal: Option<ModalState>,
    // State at the current time.
    t: f64,
    clock: Clock,
    steps: u64,
    r: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    load: Vec<f64>,
    classes: Vec<SlipState>,
    forces: Vec<f64>,
    energy: Energy,
    initial_mechanical: f64,
    reduced_remaining: usize,
    total_iterations: u64,
    // Scratch, reused every step.
    r_new: Vec<f64>,
    v_new: Vec<f64>,
    load_new: Vec<f64>,
    b: Vec<f64>,
    tmp: Vec<f64>,
    diagonal: Vec<f64>,
    /// The classes being iterated on in this step.
    scratch_classes: Vec<SlipState>,
    /// The iteration's own scratch classes.
    iter_scratch: Vec<SlipState>,
    /// Per-chunk partial sums of the energies' quadratic forms.
    row_partials: Vec<f64>,
    /// K and the consistent M store one pattern: the implicit step's
    /// products with both run as one pass.
    shared_pattern: bool,
    /// K and the consistent M as 2×2 blocks (`linalg::PairBlocks`), for
    /// the implicit step's two products per step; small systems only.
    pair_blocks: Option<PairBlocks>,
    /// K and the consistent M by stencil types for the implicit step's
    /// products, on large structured meshes (`Dynamics::stencils`).
    implicit_products: Option<ImplicitProducts>,
    forces_new: Vec<f64>,
    /// θ_l(t) of each load for the step being taken.
    thetas: Vec<f64>,
    /// Per-chunk partial sums of the explicit passes.
    partials: kernels::Partials,
    /// The next explicit step's predictor, written by the sweep
    /// (`kernels::fused_step`), swapped into `r_new` after the step.
    r_next: Vec<f64>,
    /// The Δt `r_new` holds the predictor for (set by a completed sweep;
    /// a step of another Δt, a restore or a failed step forms it anew),
    /// and that sweep's Σ |ṙ_K| + |r̈_K| + |r_{K+1}| (`kernels::Sums::bound`).
    predicted: Option<(f64, f64)>,
    /// What bounds a sweep's entries by its inputs' ([`SweepBounds`]),
    /// explicit runs of more than one chunk.
    sweep_bounds: Option<SweepBounds>,
    /// Explicit steps swept in place since the integrator was made.
    in_place_steps: u64,
    /// K as the explicit step reads it (`kernels::Product`: the compact
    /// form or the element classes); the CSR K is then no longer held.
    product: Option<kernels::Product>,
    /// (DOF, ṙ_K) at the contact DOFs, sorted by DOF: the closed-form
    /// friction's velocities handed to `kernels::fused_step`.
    friction: Vec<(usize, f64)>,
    /// Per contact node and component, the entry of `friction`.
    friction_slots: Vec<[Option<usize>; 2]>,
    /// The closed-form nodal friction's constants for the last Δt.
    nodal: NodalFriction,
    /// The constant load and the loads on their nonzero rows (explicit
    /// runs: pass A forms R_K there only).
    sparse_loads: kernels::SparseLoads,
}

/// What bounds an explicit sweep's entries by its inputs', for the choice
/// to sweep in place (`kernels::fused_step`): a sweep in place writes ṙ_K
/// and r̈_K over ṙ_{K−1} and r̈_{K−1}, so it must not fail half way (a
/// failed step leaves the state at the last completed step). From the
/// last sweep's Σ |ṙ| + |r̈| + |r_{K+1}| (≥ every entry of r_K, ṙ_{K−1},
/// r̈_{K−1}, and finite only if they all are), the row sums of |K| and the
/// lumped mass, every quantity the sweep forms is bounded; finite bounds
/// with room for the roundings (4×) mean no entry can overflow and none
/// can be NaN (that needs ∞ or 0/0, and m·scale > 0).
///
/// The in-place sweep stores into lines it has just read; apart, 2 of its
/// 3 outputs are stores to lines not in cache, which the core reads
/// first. `sweep_lab` ("sweep" against "sweep in place", alternating in
/// one process), 2026-11-25, 1M DOFs, 2 threads, medians of 20, three
/// runs: Q1 0.87, 0.90, 0.94 of the time apart (1.65-1.75 ms); Q2 0.98,
/// 1.00, 0.98 (2.53-2.61 ms), whose sums keep the core busier than its
/// stores do.
#[derive(Clone, Copy, Debug)]
struct SweepBounds {
    /// max_i Σ_j |K_ij|.
    k_abs: f64,
    /// Least and largest lumped mass.
    m_min: f64,
    m_max: f64,
}

impl SweepBounds {
    fn new(k: &CsrMatrix<f64>, mass: &[f64]) -> SweepBounds {
        let k_abs = k
            .row_iter()
            .map(|row| row.values().iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        SweepBounds {
            k_abs,
            m_min: mass.iter().copied().fold(f64::INFINITY, f64::min),
            m_max: mass.iter().copied().fold(0.0, f64::max),
        }
    }

    /// Whether a sweep of `s`'s coefficients (γ > 0, Δt > 0) forms only
    /// finite entries from r_K, ṙ_{K−1}, r̈_{K−1} bounded by `bound`, loads
    /// by `loads` and the friction's velocities by `friction` (sums of
    /// magnitudes: ∞ or NaN if any is not finite).
    fn finite(&self, bound: f64, loads: f64, friction: f64, s: &kernels::StepData) -> bool {
        // Stencil types hold K's blocks to 1e-10 of max |K_ij|: the 4×
        // covers them with the roundings.
        let ku = self.k_abs * bound;
        let b = loads + ku + self.m_max * (s.cv.abs() + s.ca.abs()) * bound;
        let vn = (b / (self.m_min * s.scale)).max(friction);
        let an = (vn + bound) * s.scale + s.ratio.abs() * bound;
        let rx = bound + s.next.0.abs() * vn + s.next.1.abs() * an;
        self.m_min > 0.0
            && s.scale > 0.0
            && [bound, loads, friction, ku, b, vn, an, rx]
                .iter()
                .all(|x| (4.0 * x).is_finite())
    }
}

/// The stick/slip iteration's failure as the step's error: the cap, or
/// the failed solve as `solve` maps it.
fn iteration_error<E>(
    failure: IterationFailure<E>,
    (step, t, remark_4_2): (u64, f64, bool),
    solve: impl FnOnce(E) -> TimeError,
) -> TimeError {
    match failure {
        IterationFailure::Cap {
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
        IterationFailure::Solve(e) => solve(e),
    }
}

/// K and M by stencil types for the implicit step (see
/// `Integrator::implicit_products`), and a vector for their products.
#[derive(Clone, Debug)]
struct ImplicitProducts {
    k: kernels::Stencils,
    /// The consistent M's; `None` with the lumped mass.
    m: Option<kernels::Stencils>,
    scratch: Vec<f64>,
}

impl ImplicitProducts {
    /// Both products by stencil types, or `None` where either declines.
    fn new(k: &CsrMatrix<f64>, mass_kind: MassKind, m: &CsrMatrix<f64>) -> Option<Self> {
        let ks = kernels::Stencils::new(k)?;
        let ms = match mass_kind {
            MassKind::Consistent => Some(kernels::Stencils::new(m)?),
            MassKind::Lumped => None,
        };
        Some(ImplicitProducts {
            k: ks,
            m: ms,
            scratch: vec![0.0; k.nrows()],
        })
    }
}

/// xᵀ M_L x with the lumped mass m.
fn lumped_form(m: &[f64], x: &[f64]) -> f64 {
    x.iter().zip(m).map(|(v, m)| m * v * v).sum()
}

impl std::fmt::Debug for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Integrator")
            .field("n", &self.dynamics.n())
            .field("t", &self.t)
            .field("steps", &self.steps)
            .field("scheme", &self.settings.scheme)
            .finish()
    }
}

fn check_settings(s: &Settings, n: usize) -> Result<(f64, f64, MassKind), TimeError> {
    let bad = |m: String| Err(TimeError::Settings(m));
    if !(s.dt > 0.0 && s.dt.is_finite()) {
        return bad(format!(
            "time.dt = {}: the time step must be positive",
            s.dt
        ));
    }
    if !(s.t_end > 0.0 && s.t_end.is_finite()) {
        return bad(format!(
            "time.t_end = {}: the end time must be positive",
            s.t_end
        ));
    }
    if let Some(r) = s.stick_reduction {
        if !(r.dt > 0.0 && r.dt <= s.dt) {
            return bad(format!(
                "time.stick_reduction.dt = {}: the reduced step must be positive and at most time.dt = {}",
                r.dt, s.dt
            ));
        }
    }
    if s.iteration.max_iterations == 0 {
        return bad("contact.max_iterations must be at least 1".into());
    }
    let (beta, gamma) = s.scheme.parameters();
    let mass = match (s.scheme, s.mass) {
        (Scheme::CentralDifference, Some(MassKind::Consistent)) => {
            return bad(
                "time.mass = \"consistent\" with central difference would need a linear solve per step; \
                 central difference uses the lumped mass: remove time.mass or set it to \"lumped\""
                    .into(),
            )
        }
        (Scheme::CentralDifference, _) => MassKind::Lumped,
        (Scheme::Newmark { .. }, m) => {
            if !(gamma >= 0.5 && 2.0 * beta >= gamma && beta.is_finite() && gamma.is_finite()) {
                return bad(format!(
                    "Newmark β = {beta}, γ = {gamma} is outside the unconditionally stable range 2β ≥ γ ≥ ½ \
                     (the paper uses β = 0.25, γ = 0.5 or β = 0.3025, γ = 0.6); for an explicit run use \
                     time.scheme = \"central_difference\""
                ));
            }
            m.unwrap_or(MassKind::Consistent)
        }
    };
    if let Some(v0) = &s.initial_velocity {
        if v0.len() != n {
            return bad(format!(
                "initial velocity has {} entries, the model {n} free DOFs",
                v0.len()
            ));
        }
    }
    Ok((beta, gamma, mass))
}

impl Integrator {
    /// Sets up the run and computes the initial state of Remark 4.1:
    /// r₀ the frictionless static equilibrium under the loads present at
    /// t = 0⁻, ṙ₀ = 0 (or given), r̈₀ from M r̈₀ = R(0) − K r₀.
    ///
    /// # Errors
    /// Settings out of range, Δt above the explicit critical step (unless
    /// allowed), or a singular static problem.
    pub fn new(
        mut dynamics: Dynamics,
        contact: Option<ContactSurface>,
        loads: Vec<Load>,
        settings: Settings,
    ) -> Result<Integrator, TimeError> {
        let n = dynamics.n();
        let (beta, gamma, mass_kind) = check_settings(&settings, n)?;
        // A scene without friction nodes runs no friction code.
        let contact = contact.filter(|c| !c.is_empty());
        let explicit = beta == 0.0 && mass_kind == MassKind::Lumped;
        // The explicit step reads K only through its stencil types
        // (structured numbering), its element classes (structured Q2 cells)
        // or its compact form (0.57× the CSR's bytes per step), the fastest
        // that applies (kernels.rs); built first, so that the critical
        // step's Lanczos runs on it too (its ~300 products were most of an
        // explicit run's setup on large meshes).
        let product = if explicit {
            let classes = dynamics.element_classes.take();
            (dynamics.stencils)
                .then(|| kernels::Stencils::new(&dynamics.stiffness))
                .flatten()
                .map(kernels::Product::Stencils)
                .or_else(|| {
                    classes
                        .and_then(kernels::Classes::new)
                        .map(kernels::Product::Classes)
                })
                .or_else(|| {
                    crate::sliced::Sliced::small(&dynamics.stiffness).map(kernels::Product::Sliced)
                })
                .or_else(|| {
                    kernels::Compact::new(&dynamics.stiffness).map(kernels::Product::Compact)
                })
        } else {
            None
        };
        let dt_crit = match (&product, explicit) {
            (Some(k), _) => Some(critical_step_with(
                |x, y| k.spmv(x, y),
                &dynamics.lumped_mass,
            )),
            (None, true) => Some(critical_step(&dynamics.stiffness, &dynamics.lumped_mass)),
            (None, false) => None,
        };
        if let Some(crit) = dt_crit {
            if settings.dt > crit && !settings.allow_unstable {
                return Err(TimeError::Unstable {
                    dt: settings.dt,
                    dt_crit: crit,
                });
            }
        }
        // The consistent mass is held once: moved into `mass_matrix` when the
        // scheme uses it, dropped otherwise; the explicit scheme needs no
        // mass matrix.
        // (0 × 0 placeholders: an n × n empty CSR would still hold n + 1
        // row offsets.)
        let consistent_mass =
            std::mem::replace(&mut dynamics.consistent_mass, CsrMatrix::zeros(0, 0));
        let mass_matrix = match mass_kind {
            MassKind::Consistent => consistent_mass,
            MassKind::Lumped if explicit => CsrMatrix::zeros(0, 0),
            MassKind::Lumped => {
                let mut m = dynamics.stiffness.clone();
                let (offsets, cols, values) = m.csr_data_mut();
                for i in 0..n {
                    for k in offsets[i]..offsets[i + 1] {
                        values[k] = if cols[k] == i {
                            dynamics.lumped_mass[i]
                        } else {
                            0.0
                        };
                    }
                }
                m
            }
        };
        let schur = if explicit {
            None
        } else {
            Some(
                SchurOperator::new(
                    &dynamics.stiffness,
                    &dynamics.fill_order,
                    contact.as_ref(),
                    ImplicitSolver::Schur,
                )
                .map_err(TimeError::Static)?,
            )
        };

        // Remark 4.1: r₀ from K r₀ = R(0⁻), frictionless.
        let mut static_load = dynamics.constant_load.clone();
        for l in &loads {
            let theta = l.history.before_start();
            for (s, f) in static_load.iter_mut().zip(&l.vector) {
                *s += theta * f;
            }
        }
        // No preload (step and sine histories, no constant load): r₀ = 0,
        // the solve's own answer (+0 through both triangular solves), with
        // no factorization of K. On large explicit runs that factor was
        // most of the setup and of the peak memory (Q1 246k DOFs, 1000
        // steps: 1.2 s of 3.6 s).
        let mut r = static_load;
        if settings.restoring {
            r.fill(0.0);
        } else if r.iter().any(|&x| x != 0.0) {
            let mut static_solver =
                SparseCholesky::analyze(&dynamics.stiffness, &dynamics.fill_order)
                    .map_err(TimeError::Static)?;
            static_solver
                .factorize(&dynamics.stiffness)
                .map_err(TimeError::Static)?;
            static_solver.solve_in_place(&mut r);
        }

        let v = settings
            .initial_velocity
            .clone()
            .unwrap_or_else(|| vec![0.0; n]);
        let n_c = contact.as_ref().map_or(0, |c| c.len());
        let shared_pattern = same_pattern(&dynamics.stiffness, &mass_matrix);
        // The block copy of K and M where the products run from cache
        // (release build, 2026-11-22, Newmark step with / without:
        // 148 DOFs 11.0 / 12.8 µs, 552: 43 / 53 µs, 8,352 (Q1, Q2):
        // 0.83-0.90 / 0.92-1.05 ms); from memory it was no faster (Q1
        // 251k: 60-63 / 60-64 ms) and would add 68 bytes per block to
        // the run's memory (peak 1.27 -> 1.52x its need).
        let small = 17 * dynamics.stiffness.nnz() <= linalg::PAIR_BLOCKS_MAX_BYTES;
        let pair_blocks = if !explicit && mass_kind == MassKind::Consistent && small {
            PairBlocks::new(&dynamics.stiffness, &mass_matrix)
        } else {
            None
        };
        // Larger systems read K and M from memory four times a step (R̂'s
        // two products, the energies' two forms): by stencil types where
        // the mesh has them, 8 bytes per node pair instead of 24 per entry
        // (Q2 249k: 380 MB a step of the CSRs' values and columns).
        let implicit_products = if !explicit && pair_blocks.is_none() && dynamics.stencils {
            ImplicitProducts::new(&dynamics.stiffness, mass_kind, &mass_matrix)
        } else {
            None
        };
        let mut this = Integrator {
            beta,
            gamma,
            mass_kind,
            explicit,
            dt_crit,
            mass_matrix,
            implicit: None,
            schur,
            solver: ImplicitSolver::Schur,
            nodal_velocity: vec![0.0; n_c],
            modal: None,
            t: 0.0,
            clock: Clock::new(0.0, settings.dt),
            steps: 0,
            a: vec![0.0; n],
            load: vec![0.0; n],
            classes: vec![SlipState::Stuck; n_c],
            forces: vec![0.0; n_c],
            energy: Energy::default(),
            initial_mechanical: 0.0,
            reduced_remaining: 0,
            total_iterations: 0,
            r_new: vec![0.0; n],
            v_new: vec![0.0; n],
            load_new: vec![0.0; n],
            b: vec![0.0; n],
            tmp: vec![0.0; n],
            diagonal: vec![0.0; n],
            scratch_classes: vec![SlipState::Stuck; n_c],
            iter_scratch: vec![SlipState::Stuck; n_c],
            row_partials: vec![0.0; 2 * row_chunks(n)],
            shared_pattern,
            pair_blocks,
            implicit_products,
            forces_new: vec![0.0; n_c],
            thetas: vec![0.0; loads.len()],
            partials: kernels::partials(n),
            r_next: Vec::new(),
            predicted: None,
            sweep_bounds: None,
            in_place_steps: 0,
            product: None,
            friction: Vec::new(),
            friction_slots: Vec::new(),
            nodal: NodalFriction::default(),
            sparse_loads: kernels::SparseLoads::new(&[], &[]),
            r,
            v,
            dynamics,
            contact,
            loads,
            settings,
        };
        this.load_at(0.0, false);
        // r̈₀ from M r̈₀ = R(0) − K r₀, without friction (Remark 4.1).
        spmv(&this.dynamics.stiffness, &this.r, &mut this.tmp);
        for i in 0..n {
            this.tmp[i] = this.load[i] - this.tmp[i];
        }
        match this.mass_kind {
            MassKind::Lumped => {
                for i in 0..n {
                    this.a[i] = this.tmp[i] / this.dynamics.lumped_mass[i];
                }
            }
            MassKind::Consistent => {
                let mut m = SparseCholesky::analyze(&this.mass_matrix, &this.dynamics.fill_order)
                    .map_err(TimeError::Static)?;
                m.factorize(&this.mass_matrix).map_err(TimeError::Static)?;
                this.a.copy_from_slice(&this.tmp);
                m.solve_in_place(&mut this.a);
            }
        }
        if let Some(c) = &this.contact {
            c.classify(&this.v, &mut this.classes);
            c.nodal_forces(&this.v, &mut this.forces);
        }
        let v = std::mem::take(&mut this.v);
        let kinetic = 0.5 * this.mass_product(&v);
        this.v = v;
        let strain =
            0.5 * quadratic_form(&this.dynamics.stiffness, &this.r, &mut this.row_partials);
        this.initial_mechanical = kinetic + strain;
        this.energy = Energy {
            kinetic,
            strain,
            external_work: 0.0,
            dissipated: 0.0,
            total: kinetic + strain - dot(&this.r, &this.load),
            balance: 0.0,
        };
        if !this.explicit && n <= MODAL_MAX_DOFS && this.settings.reads_every.is_none_or(|k| k >= 2)
        {
            this.enter_modal()?;
            this.solver = ImplicitSolver::Modal;
        }
        if this.explicit {
            // From here on the explicit step reads K only through its
            // product (built above), and the CSR's memory is returned.
            this.product = product;
            if this.product.is_some() {
                if kernels::chunks(n) > 1 {
                    this.sweep_bounds = Some(SweepBounds::new(
                        &this.dynamics.stiffness,
                        &this.dynamics.lumped_mass,
                    ));
                }
                this.dynamics.stiffness = CsrMatrix::zeros(0, 0);
                this.r_next = vec![0.0; n];
            }
            let loads: Vec<&[f64]> = this.loads.iter().map(|l| &l.vector[..]).collect();
            this.sparse_loads = kernels::SparseLoads::new(&this.dynamics.constant_load, &loads);
            if let Some(c) = &this.contact {
                let mut dofs: Vec<usize> = c.nodes.iter().flat_map(|n| n.dofs).flatten().collect();
                dofs.sort_unstable();
                dofs.dedup();
                this.friction_slots = c
                    .nodes
                    .iter()
                    .map(|n| n.dofs.map(|d| d.map(|i| dofs.binary_search(&i).unwrap())))
                    .collect();
                this.friction = dofs.into_iter().map(|i| (i, 0.0)).collect();
            }
        }
        // The setup's temporaries are gone: their memory back to the system.
        crate::memory::release_free_memory();
        Ok(this)
    }

    /// R(t) into `load` (or `load_new`).
    fn load_at(&mut self, t: f64, new: bool) {
        let out = if new {
            &mut self.load_new
        } else {
            &mut self.load
        };
        // The modal step's loads are Φᵀ of the physical ones.
        let modal = self.modal.as_ref();
        out.copy_from_slice(modal.map_or(&self.dynamics.constant_load, |m| &m.constant_load));
        for (k, l) in self.loads.iter().enumerate() {
            let vector = modal.map_or(&l.vector, |m| &m.loads[k]);
            let theta = l.history.value(t);
            if theta != 0.0 {
                for (o, f) in out.iter_mut().zip(vector) {
                    *o += theta * f;
                }
            }
        }
    }

    /// Moves the state into the modes of (K, M) (`modal.rs`): the modes,
    /// the loads' and the state's modal coordinates, the Schur operator's
    /// modal mode.
    fn enter_modal(&mut self) -> Result<(), TimeError> {
        let modes = Modes::new(&self.dynamics.stiffness, &self.mass_matrix)
            .map_err(|m| TimeError::Static(SolverError::Analysis(m)))?;
        let nodes = self.contact.as_ref().map_or(&[][..], |c| &c.nodes[..]);
        let mut m = ModalState::new(modes, nodes);
        m.constant_load = vec![0.0; self.r.len()];
        m.modes
            .project(&self.dynamics.constant_load, &mut m.constant_load);
        m.loads = self
            .loads
            .iter()
            .map(|l| {
                let mut out = vec![0.0; self.r.len()];
                m.modes.project(&l.vector, &mut out);
                out
            })
            .collect();
        if let Some(op) = self.schur.as_mut() {
            op.set_modal(m.modes.tangential_rows(nodes), m.modes.lambda().to_vec());
        }
        self.modal = Some(m);
        self.project_state();
        self.load_at(self.t, false);
        Ok(())
    }

    /// The physical r, ṙ, r̈ in `r`, `v`, `a` into the modes: q = ΦᵀM r,
    /// likewise q̇ and q̈, and the contact nodes' velocities P ṙ.
    fn project_state(&mut self) {
        let m = self.modal.as_mut().expect("the modal step");
        if let Some(c) = &self.contact {
            for (o, node) in m.contact_v.iter_mut().zip(&c.nodes) {
                *o = node.tangential(&self.v);
            }
        }
        for x in [&mut self.r, &mut self.v, &mut self.a] {
            spmv(&self.mass_matrix, x, &mut self.tmp);
            m.modes.project(&self.tmp, x);
        }
    }

    /// Back from the modes to the physical state (another solver chosen).
    fn leave_modal(&mut self) {
        let Some(m) = self.modal.take() else {
            return;
        };
        for x in [&mut self.r, &mut self.v, &mut self.a] {
            m.modes.expand([x], [&mut self.tmp]);
            x.copy_from_slice(&self.tmp);
        }
        self.load_at(self.t, false);
    }

    /// xᵀ M x with the scheme's mass.
    /// (½ṙᵀMṙ, ½rᵀKr) of the current state; one pass over K and M when
    /// they share their pattern.
    fn kinetic_and_strain(&mut self) -> (f64, f64) {
        if let Some(p) = &mut self.implicit_products {
            p.k.spmv(&self.r, &mut p.scratch);
            let rkr = dot(&self.r, &p.scratch);
            let vmv = match &p.m {
                Some(m) => {
                    m.spmv(&self.v, &mut p.scratch);
                    dot(&self.v, &p.scratch)
                }
                None => lumped_form(&self.dynamics.lumped_mass, &self.v),
            };
            return (0.5 * vmv, 0.5 * rkr);
        }
        if let Some(blocks) = &self.pair_blocks {
            let (rkr, vmv) = blocks.two_forms(&self.r, &self.v, &mut self.row_partials);
            return (0.5 * vmv, 0.5 * rkr);
        }
        if self.mass_kind == MassKind::Consistent && self.shared_pattern {
            let (rkr, vmv) = two_forms(
                &self.dynamics.stiffness,
                &self.r,
                &self.mass_matrix,
                &self.v,
                &mut self.row_partials,
            );
            return (0.5 * vmv, 0.5 * rkr);
        }
        let v = std::mem::take(&mut self.v);
        let kinetic = 0.5 * self.mass_product(&v);
        self.v = v;
        let strain =
            0.5 * quadratic_form(&self.dynamics.stiffness, &self.r, &mut self.row_partials);
        (kinetic, strain)
    }

    fn mass_product(&mut self, x: &[f64]) -> f64 {
        match self.mass_kind {
            MassKind::Lumped => lumped_form(&self.dynamics.lumped_mass, x),
            MassKind::Consistent => quadratic_form(&self.mass_matrix, x, &mut self.row_partials),
        }
    }

    /// The size of the next step and the time it ends at: Remark 4.3's
    /// reduced step while its count runs ([`Clock`]); the last step lands
    /// on t_end, shortened where t_end is not within [`END_SLACK`] of a
    /// whole step (so a constant Δt keeps one factorization).
    fn next_step(&self) -> (f64, f64) {
        let dt = match self.settings.stick_reduction {
            Some(r) if self.reduced_remaining > 0 => r.dt,
            _ => self.settings.dt,
        };
        let t_end = self.settings.t_end;
        let t_new = self.clock.after(self.t, dt);
        if t_new < t_end - END_SLACK * dt {
            (dt, t_new)
        } else if t_new <= t_end + END_SLACK * dt {
            (dt, t_end)
        } else {
            (t_end - self.t, t_end)
        }
    }

    /// True once t_end is reached.
    pub fn done(&self) -> bool {
        self.t >= self.settings.t_end * (1.0 - 1e-14)
    }

    /// Advances one step.
    ///
    /// # Errors
    /// A failed linear solve, a stick/slip iteration that hits its cap, or a
    /// non-finite state. The state is left at the last completed step.
    pub fn step(&mut self) -> Result<StepInfo, TimeError> {
        if self.explicit {
            return self.explicit_step();
        }
        let n = self.dynamics.n();
        let (dt, t_new) = self.next_step();
        let (beta, gamma) = (self.beta, self.gamma);
        let step_number = self.steps + 1;
        self.load_at(t_new, true);

        // Predictor: r_K = r_pred + (β/γ)Δt ṙ_K (METHOD.md §4); and for
        // R̂_K = R_K − K r_pred + M[ṙ/(γΔt) + (1/γ − 1) r̈] the bracket,
        // in one pass (zipped slices: no bounds checks, SIMD).
        let c1 = dt * (1.0 - beta / gamma);
        let c2 = 0.5 * dt * dt * (1.0 - 2.0 * beta / gamma);
        let cv = 1.0 / (gamma * dt);
        let ca = 1.0 / gamma - 1.0;
        if let Some(m) = &self.modal {
            // In the modes K = Λ and M = I (`modal.rs`): one pass.
            modal::predict(
                [c1, c2, cv, ca],
                [m.modes.lambda(), &self.r, &self.v, &self.a, &self.load_new],
                [&mut self.r_new, &mut self.tmp, &mut self.b],
            );
        } else {
            for (((rn, t), r), (v, a)) in self
                .r_new
                .iter_mut()
                .zip(self.tmp.iter_mut())
                .zip(&self.r)
                .zip(self.v.iter().zip(&self.a))
            {
                *rn = r + c1 * v + c2 * a;
                *t = cv * v + ca * a;
            }
            self.rhs(n);
        }

        self.scratch_classes.copy_from_slice(&self.classes);
        // (The explicit scheme took `explicit_step` above.)
        let iterations = self.implicit_velocity(dt, step_number, t_new)?;
        self.implicit_close(dt, cv, t_new, step_number, iterations)
    }

    /// R̂ = R_K − K r_pred + M tmp into `b` from the predictor in `r_new`
    /// and M's vector in `tmp`, by the products the system has.
    fn rhs(&mut self, n: usize) {
        if let Some(p) = &self.implicit_products {
            p.k.spmv(&self.r_new, &mut self.b);
        } else if self.mass_kind != MassKind::Consistent || !self.shared_pattern {
            spmv(&self.dynamics.stiffness, &self.r_new, &mut self.b);
        }
        match self.mass_kind {
            MassKind::Consistent if self.implicit_products.is_some() => {
                let p = self.implicit_products.as_mut().expect("checked");
                let m = p.m.as_ref().expect("consistent mass: M's stencils");
                m.spmv(&self.tmp, &mut p.scratch);
                for i in 0..n {
                    self.b[i] = self.load_new[i] - self.b[i] + p.scratch[i];
                }
            }
            MassKind::Consistent if self.pair_blocks.is_some() => {
                let blocks = self.pair_blocks.as_ref().expect("checked");
                blocks.load_minus_k_plus_m(&self.load_new, &self.r_new, &self.tmp, &mut self.b);
            }
            MassKind::Lumped => {
                for i in 0..n {
                    self.b[i] =
                        self.load_new[i] - self.b[i] + self.dynamics.lumped_mass[i] * self.tmp[i];
                }
            }
            MassKind::Consistent if self.shared_pattern => load_minus_k_plus_m(
                &self.load_new,
                &self.dynamics.stiffness,
                &self.r_new,
                &self.mass_matrix,
                &self.tmp,
                &mut self.b,
            ),
            MassKind::Consistent => {
                let b = std::mem::take(&mut self.b);
                spmv(&self.mass_matrix, &self.tmp, &mut self.v_new);
                self.b = b;
                for i in 0..n {
                    self.b[i] = self.load_new[i] - self.b[i] + self.v_new[i];
                }
            }
        }
    }

    /// The implicit step after its velocity: corrector, ledger, commit,
    /// energy.
    fn implicit_close(
        &mut self,
        dt: f64,
        cv: f64,
        t_new: f64,
        step_number: u64,
        iterations: usize,
    ) -> Result<StepInfo, TimeError> {
        let (beta, gamma) = (self.beta, self.gamma);
        // Corrector, with the finiteness check (a flag, not a branch per
        // entry), and r̈_K (into `tmp`, free since the bracket: the state
        // stays whole if the step fails).
        let c3 = beta / gamma * dt;
        let ka = (1.0 - gamma) / gamma;
        // (The work of the step, r_K·R_K and, in the modes, the energies.)
        let (finite, work, load_dot, forms) = if let Some(m) = &self.modal {
            // In the modes: the corrector, the ledger's sums and the
            // energies in one pass (`modal::close`).
            let (finite, [work, load_dot, vv, rkr]) = modal::close(
                [c3, cv, ka],
                [
                    m.modes.lambda(),
                    &self.r,
                    &self.v,
                    &self.a,
                    &self.v_new,
                    &self.load,
                    &self.load_new,
                ],
                &mut self.r_new,
                &mut self.tmp,
            );
            (finite, work, load_dot, Some((0.5 * vv, 0.5 * rkr)))
        } else {
            let mut finite = true;
            for ((r, v_new), (a_new, (v, a))) in self
                .r_new
                .iter_mut()
                .zip(&self.v_new)
                .zip(self.tmp.iter_mut().zip(self.v.iter().zip(&self.a)))
            {
                *r += c3 * v_new;
                finite &= r.is_finite() & v_new.is_finite();
                *a_new = (v_new - v) * cv - ka * a;
            }
            // Energy ledger, before the state is overwritten: the work and
            // r_K·R_K in four lanes each, not one chain of additions per
            // sum (with the fused loop above: the paper mesh's Newmark
            // step 4.18 → 4.05 µs, medians of ten alternating runs).
            let (mut work, mut load_dot) = (Lanes::default(), Lanes::default());
            let n = self.r_new.len();
            let (rn, r) = (&self.r_new[..n], &self.r[..n]);
            let (ln, l) = (&self.load_new[..n], &self.load[..n]);
            work.add_rows(0, n, |k| 0.5 * (ln[k] + l[k]) * (rn[k] - r[k]));
            load_dot.add_rows(0, n, |k| rn[k] * ln[k]);
            (finite, work.total(), load_dot.total(), None)
        };
        if !finite {
            return Err(self.non_finite(step_number, t_new));
        }
        let (dissipated, stick_events) = self.friction_ledger(dt);

        // Commit the step.
        std::mem::swap(&mut self.a, &mut self.tmp);
        self.commit(dt, t_new, step_number, iterations);

        // ½ṙᵀMṙ and ½rᵀKr of the new state, unless the modal pass formed them.
        let (kinetic, strain) = forms.unwrap_or_else(|| self.kinetic_and_strain());
        Ok(self.close_step(
            [kinetic, strain, work, dissipated, load_dot],
            dt,
            iterations,
            stick_events,
        ))
    }

    /// Makes the new state current (r̈ is already in place) at t_new, a
    /// step of `dt` on ([`Integrator::next_step`]).
    fn commit(&mut self, dt: f64, t_new: f64, step_number: u64, iterations: usize) {
        std::mem::swap(&mut self.r, &mut self.r_new);
        std::mem::swap(&mut self.v, &mut self.v_new);
        std::mem::swap(&mut self.load, &mut self.load_new);
        std::mem::swap(&mut self.forces, &mut self.forces_new);
        self.classes.copy_from_slice(&self.scratch_classes);
        if let Some(m) = &mut self.modal {
            std::mem::swap(&mut m.contact_v, &mut m.contact_v_new);
            m.invalidate();
        }
        self.clock.tick(self.t, dt);
        self.t = t_new;
        self.steps = step_number;
        self.total_iterations += iterations as u64;
    }

    /// Books the step in the energy ledger from [kinetic, strain, work of
    /// the step, dissipation of the step, rᵀR] and advances the Remark 4.3
    /// count.
    fn close_step(
        &mut self,
        [kinetic, strain, work, dissipated, load_dot]: [f64; 5],
        dt: f64,
        iterations: usize,
        stick_events: usize,
    ) -> StepInfo {
        let e = &mut self.energy;
        e.kinetic = kinetic;
        e.strain = strain;
        e.external_work += work;
        e.dissipated += dissipated;
        e.total = kinetic + strain - load_dot;
        e.balance = kinetic + strain - self.initial_mechanical - e.external_work + e.dissipated;
        self.count_reduced_steps(dt, stick_events);
        StepInfo {
            dt,
            iterations,
            stick_events,
        }
    }

    /// Remark 4.3: a sticking restarts the reduced-step count.
    fn count_reduced_steps(&mut self, dt: f64, stick_events: usize) {
        if let Some(r) = self.settings.stick_reduction {
            if stick_events > 0 {
                self.reduced_remaining = r.steps;
            } else if self.reduced_remaining > 0 && dt <= r.dt * (1.0 + 1e-12) {
                self.reduced_remaining -= 1;
            }
        }
    }

    /// The explicit step (β = 0, lumped mass) in three fused, threaded
    /// passes (`kernels.rs`); the same arithmetic per entry as the general
    /// step, with one SpMV (K r_K serves R̂_K and the strain energy, since
    /// β = 0 leaves no corrector).
    fn explicit_step(&mut self) -> Result<StepInfo, TimeError> {
        let (dt, t_new) = self.next_step();
        let gamma = self.gamma;
        let step_number = self.steps + 1;
        for (theta, l) in self.thetas.iter_mut().zip(&self.loads) {
            *theta = l.history.value(t_new);
        }
        // The last sweep's predictor, if it was formed for this Δt.
        let predicted = self
            .predicted
            .take()
            .filter(|&(p, _)| p.to_bits() == dt.to_bits());
        // A non-finite θ made every entry of R_K, hence of ṙ_K, NaN in the
        // dense pass A; pass A over the load rows needs finite θ (kernels.rs).
        if self.thetas.iter().any(|t| !t.is_finite()) {
            return Err(self.non_finite(step_number, t_new));
        }
        // β = 0: r_K = r + Δt ṙ + ½Δt² r̈ is final (no corrector).
        let c1 = dt;
        let c2 = 0.5 * dt * dt;
        kernels::predict(
            &self.sparse_loads,
            &self.thetas,
            &self.r,
            &self.v,
            &self.a,
            c1,
            c2,
            &self.load,
            &mut self.load_new,
            &mut self.r_new,
            predicted.is_none(),
            &mut self.partials,
        );
        let scale = 1.0 / (gamma * dt);
        // The sweep's bound, when the step was one sweep.
        let mut swept = None;
        let mut in_place = false;
        let closed_form = self.settings.explicit_friction == ExplicitFriction::ClosedForm
            || self.contact.is_none();
        let (strain, sums, iterations) = match &self.product {
            Some(k) if closed_form => {
                // One chunk: K r_K first, for the friction and the sweep
                // (it stays in cache); else the friction's rows alone and
                // K r_K formed in the sweep.
                let one_chunk = kernels::chunks(self.r_new.len()) == 1;
                if one_chunk {
                    k.spmv(&self.r_new, &mut self.b);
                }
                let data = kernels::StepData {
                    load_new: &self.load_new,
                    load_rows: self.sparse_loads.rows(),
                    mass: &self.dynamics.lumped_mass,
                    r_new: &self.r_new,
                    v: &self.v,
                    a: &self.a,
                    in_place: false,
                    cv: 1.0 / (gamma * dt),
                    ca: 1.0 / gamma - 1.0,
                    scale,
                    ratio: (1.0 - gamma) / gamma,
                    // The next step's predictor for a step of the same Δt:
                    // pass A's c1 and c2 above.
                    next: (c1, c2),
                };
                if let Some(contact) = &self.contact {
                    // The nodal friction first, from R̂_K at the contact DOFs
                    // (the same bits as the sweep's), then one sweep.
                    self.nodal
                        .prepare(contact, &self.dynamics.lumped_mass, scale);
                    if !one_chunk {
                        self.nodal.form_products(k, &self.r_new);
                    }
                    let (ku, at_dofs) = (&self.b, self.nodal.products());
                    let (friction, slots) = (&mut self.friction, &self.friction_slots);
                    self.nodal.closed_form().velocities(
                        |i, n| {
                            let ku = if one_chunk { ku[i] } else { at_dofs[n] };
                            kernels::rhs_entry(&data, i, ku)
                        },
                        |j, c, _, v| {
                            if let Some(slot) = slots[j][c] {
                                friction[slot].1 = v;
                            }
                        },
                    );
                }
                // In place when the last sweep's bound and this step's
                // loads and friction show that no entry can overflow: a
                // failed step then never leaves a state half written.
                // (Both out of line: inlined into this function they cost
                // the paper mesh's step, which never takes them, 7-10%.)
                in_place = match (predicted, &self.sweep_bounds) {
                    (Some((_, bound)), Some(b)) => self.may_sweep_in_place(b, bound, &data),
                    _ => false,
                };
                let (strain, sums) = if in_place {
                    let coefficients = data.coefficients();
                    self.sweep_in_place(coefficients)
                } else {
                    kernels::fused_step(
                        k,
                        &data,
                        &self.friction,
                        one_chunk.then_some(&self.b[..]),
                        &mut self.v_new,
                        &mut self.tmp,
                        &mut self.r_next,
                        &mut self.partials,
                    )
                };
                swept = Some(sums.bound);
                (strain, sums, 1)
            }
            _ => {
                let strain = if let Some(k) = &self.product {
                    kernels::spmv_rhs_and_velocity(
                        k,
                        &self.load_new,
                        &self.dynamics.lumped_mass,
                        &self.r_new,
                        &self.v,
                        &self.a,
                        1.0 / (gamma * dt),
                        1.0 / gamma - 1.0,
                        scale,
                        &mut self.b,
                        &mut self.v_new,
                        &mut self.partials,
                    )
                } else {
                    kernels::spmv(&self.dynamics.stiffness, &self.r_new, &mut self.b);
                    kernels::rhs_and_velocity(
                        &self.load_new,
                        &self.dynamics.lumped_mass,
                        &self.r_new,
                        &self.v,
                        &self.a,
                        1.0 / (gamma * dt),
                        1.0 / gamma - 1.0,
                        scale,
                        &mut self.b,
                        &mut self.v_new,
                        &mut self.partials,
                    )
                };
                self.scratch_classes.copy_from_slice(&self.classes);
                let iterations = match &self.contact {
                    None => 1,
                    Some(contact) => match self.settings.explicit_friction {
                        ExplicitFriction::ClosedForm => {
                            self.nodal
                                .prepare(contact, &self.dynamics.lumped_mass, scale);
                            let (b, v_new) = (&self.b, &mut self.v_new);
                            self.nodal
                                .closed_form()
                                .velocities(|i, _| b[i], |_, _, i, v| v_new[i] = v);
                            contact.classify(&self.v_new, &mut self.scratch_classes);
                            1
                        }
                        ExplicitFriction::Iterate => {
                            self.explicit_velocity(dt, step_number, t_new)?
                        }
                    },
                };
                let ratio = (1.0 - gamma) / gamma;
                let sums = kernels::accelerate_and_sum(
                    &self.dynamics.lumped_mass,
                    &self.load,
                    &self.load_new,
                    &self.r,
                    &self.r_new,
                    &self.v,
                    &self.v_new,
                    &self.a,
                    scale,
                    ratio,
                    &mut self.tmp,
                    &mut self.partials,
                );
                (strain, sums, iterations)
            }
        };
        if !sums.finite {
            return Err(self.non_finite(step_number, t_new));
        }
        if in_place {
            // ṙ_K and r̈_K are in v and a; ṙ_{K−1} at the contact DOFs in
            // v_new: as in a step that wrote them apart.
            std::mem::swap(&mut self.v, &mut self.v_new);
            self.in_place_steps += 1;
        } else {
            std::mem::swap(&mut self.a, &mut self.tmp);
        }
        let (dissipated, stick_events) = match (&self.contact, swept) {
            // The closed-form friction's nodes: classes, forces and the
            // ledger in one pass (`NodalClosedForm::ledger`).
            (Some(_), Some(_)) => self.nodal.closed_form().ledger(
                &self.v_new,
                &self.v,
                dt,
                &self.classes,
                &mut self.scratch_classes,
                &self.forces,
                &mut self.forces_new,
            ),
            _ => self.friction_ledger(dt),
        };
        self.commit(dt, t_new, step_number, iterations);
        if let Some(bound) = swept {
            // r_new held r_K, now in r; the sweep's predictor takes its place.
            std::mem::swap(&mut self.r_new, &mut self.r_next);
            self.predicted = Some((dt, bound));
        }
        Ok(self.close_step(
            [sums.kinetic, strain, sums.work, dissipated, sums.load_dot],
            dt,
            iterations,
            stick_events,
        ))
    }

    /// Explicit step with the friction iterated (`ExplicitFriction::Iterate`,
    /// the reference for the closed form): d = M_L/(γΔt), then §5's
    /// iteration on the diagonal system.
    fn explicit_velocity(&mut self, dt: f64, step: u64, t: f64) -> Result<usize, TimeError> {
        let scale = 1.0 / (self.gamma * dt);
        for (d, m) in self.diagonal.iter_mut().zip(&self.dynamics.lumped_mass) {
            *d = m * scale;
        }
        for ((v, b), d) in self.v_new.iter_mut().zip(&self.b).zip(&self.diagonal) {
            *v = b / d;
        }
        let Some(contact) = &self.contact else {
            return Ok(1);
        };
        let mut system = DiagonalStep {
            diagonal: &self.diagonal,
            b: &self.b,
        };
        match iterate(
            contact,
            &mut system,
            &mut self.scratch_classes,
            &mut self.iter_scratch,
            &mut self.v_new,
            self.settings.iteration,
        ) {
            Ok(report) => Ok(report.iterations),
            Err(failure) => Err(iteration_error(
                failure,
                (step, t, self.settings.iteration.remark_4_2),
                |never| match never {},
            )),
        }
    }

    /// Implicit step by the Schur complement on the contact DOFs (see
    /// `schur.rs`): one solve, the iteration of §5 on the n_c nodal
    /// unknowns, the correction.
    fn schur_velocity(&mut self, dt: f64, step: u64, t: f64) -> Result<usize, TimeError> {
        let op = self
            .schur
            .as_mut()
            .expect("Schur operator exists for the Schur path");
        op.set_dt(
            dt,
            self.beta / self.gamma * dt,
            &self.dynamics.stiffness,
            1.0 / (self.gamma * dt),
            &self.mass_matrix,
        )
        .map_err(|source| TimeError::Solve { step, t, source })?;
        if self.contact.is_none() {
            op.solve_plain(&self.b, &mut self.v_new);
            return Ok(1);
        }
        op.begin(&self.b, &mut self.v_new);
        let reduced = op
            .reduced
            .take()
            .expect("a contact surface has its nodal surface");
        let result = iterate(
            &reduced,
            &mut op.nodal_system(),
            &mut self.scratch_classes,
            &mut self.iter_scratch,
            &mut self.nodal_velocity,
            self.settings.iteration,
        );
        op.reduced = Some(reduced);
        match result {
            Ok(report) => {
                op.finish(&mut self.v_new);
                Ok(report.iterations)
            }
            Err(failure) => Err(iteration_error(
                failure,
                (step, t, self.settings.iteration.remark_4_2),
                |source| TimeError::Solve { step, t, source },
            )),
        }
    }

    /// Implicit step: (β/γ)ΔtK + M/(γΔt) + C, the iteration of §5.
    fn implicit_velocity(&mut self, dt: f64, step: u64, t: f64) -> Result<usize, TimeError> {
        if self.schur.is_some() {
            return self.schur_velocity(dt, step, t);
        }
        let op = self
            .implicit
            .as_mut()
            .expect("implicit operator exists for implicit schemes");
        op.set_dt(
            dt,
            self.beta / self.gamma * dt,
            &self.dynamics.stiffness,
            1.0 / (self.gamma * dt),
            &self.mass_matrix,
        );
        let Some(contact) = &self.contact else {
            op.solve_plain(&self.b, &mut self.v_new)
                .map_err(|source| TimeError::Solve { step, t, source })?;
            return Ok(1);
        };
        let mut system = ImplicitStep {
            operator: op,
            b: &self.b,
        };
        let result = iterate(
            contact,
            &mut system,
            &mut self.scratch_classes,
            &mut self.iter_scratch,
            &mut self.v_new,
            self.settings.iteration,
        );
        match result {
            Ok(report) => Ok(report.iterations),
            Err(failure) => Err(iteration_error(
                failure,
                (step, t, self.settings.iteration.remark_4_2),
                |source| TimeError::Solve { step, t, source },
            )),
        }
    }

    // ---- checkpoint / restart ----

    /// Everything needed to continue this run bit-identically
    /// ([`Integrator::restore`] on a fresh integrator of the same case).
    pub fn checkpoint(&self) -> Checkpoint {
        let modal = match &self.modal {
            Some(m) => [&self.r, &self.v, &self.a, &m.contact_v]
                .into_iter()
                .flatten()
                .copied()
                .collect(),
            None => Vec::new(),
        };
        Checkpoint {
            t: self.t,
            steps: self.steps,
            displacement: self.displacement().to_vec(),
            velocity: self.velocity().to_vec(),
            acceleration: self.acceleration().to_vec(),
            modal,
            classes: self.classes.iter().map(|c| c.code()).collect(),
            forces: self.forces.clone(),
            energy: self.energy,
            initial_mechanical: self.initial_mechanical,
            reduced_remaining: self.reduced_remaining as u64,
            clock: Some((self.clock.t0, self.clock.dt, self.clock.k)),
            total_iterations: self.total_iterations,
            factorizations: self.factorizations(),
        }
    }

    /// Replaces the state of a freshly built integrator (same case) by the
    /// checkpoint's. R(t) is recomputed from the loads at the checkpoint's
    /// time; factorizations are recomputed on demand (they are functions of
    /// Δt and the stuck set only, so the continued run is bit-identical to
    /// an uninterrupted one).
    ///
    /// # Errors
    /// [`TimeError::Settings`] when a vector length does not match the model
    /// or the contact surface, a class code is not −1, 0 or 1, or a value is
    /// not finite.
    pub fn restore(&mut self, c: &Checkpoint) -> Result<(), TimeError> {
        let n = self.dynamics.n();
        let n_c = self.classes.len();
        let bad = |m: String| Err(TimeError::Settings(format!("checkpoint: {m}")));
        for (name, len, want) in [
            ("displacement", c.displacement.len(), n),
            ("velocity", c.velocity.len(), n),
            ("acceleration", c.acceleration.len(), n),
        ] {
            if len != want {
                return bad(format!(
                    "{name} has {len} entries, the model {want} free DOFs: \
                     restart from a checkpoint of the same case (mesh and supports)"
                ));
            }
        }
        for (name, len) in [("classes", c.classes.len()), ("forces", c.forces.len())] {
            if len != n_c {
                return bad(format!(
                    "{name} has {len} entries, the contact surface {n_c} friction nodes: \
                     restart from a checkpoint of the same case (contact group and supports)"
                ));
            }
        }
        if self.modal.is_some() && !c.modal.is_empty() && c.modal.len() != 3 * n + n_c {
            return bad(format!(
                "modal has {} entries, the model {} (3 × {n} modal coordinates and {n_c} \
                 contact velocities): restart from a checkpoint of the same case",
                c.modal.len(),
                3 * n + n_c
            ));
        }
        if !(c.t.is_finite() && c.t >= 0.0) {
            return bad(format!("t = {} is not a time ≥ 0", c.t));
        }
        let finite = c
            .displacement
            .iter()
            .chain(&c.velocity)
            .chain(&c.acceleration)
            .chain(&c.forces)
            .chain(&c.modal)
            .all(|x| x.is_finite());
        if !finite {
            return bad("the state holds NaN or infinity".into());
        }
        let mut classes = Vec::with_capacity(n_c);
        for (k, &code) in c.classes.iter().enumerate() {
            classes.push(match code {
                0 => SlipState::Stuck,
                1 => SlipState::SlipPositive,
                -1 => SlipState::SlipNegative,
                other => {
                    return bad(format!(
                        "class code {other} at contact node {k}: expected −1, 0 or 1"
                    ))
                }
            });
        }
        self.t = c.t;
        self.clock = match c.clock {
            Some((t0, dt, k)) => Clock { t0, dt, k },
            None => Clock::new(c.t, self.settings.dt),
        };
        self.steps = c.steps;
        self.r.copy_from_slice(&c.displacement);
        self.v.copy_from_slice(&c.velocity);
        self.a.copy_from_slice(&c.acceleration);
        if let Some(m) = &mut self.modal {
            m.invalidate();
            if c.modal.len() == 3 * n + n_c {
                // The modal run's own coordinates: bit-identical.
                let (q, rest) = c.modal.split_at(n);
                let (qd, rest) = rest.split_at(n);
                let (qdd, u) = rest.split_at(n);
                self.r.copy_from_slice(q);
                self.v.copy_from_slice(qd);
                self.a.copy_from_slice(qdd);
                m.contact_v.copy_from_slice(u);
            } else {
                // Another solver's checkpoint.
                self.project_state();
            }
        }
        self.classes.copy_from_slice(&classes);
        self.forces.copy_from_slice(&c.forces);
        self.energy = c.energy;
        self.initial_mechanical = c.initial_mechanical;
        self.reduced_remaining = usize::try_from(c.reduced_remaining).unwrap_or(usize::MAX);
        self.total_iterations = c.total_iterations;
        // The state changed under the sweep's predictor: form it anew.
        self.predicted = None;
        if let Some(op) = self.implicit.as_mut() {
            op.factorizations = c.factorizations;
        }
        if let Some(op) = self.schur.as_mut() {
            op.factorizations = c.factorizations;
        }
        self.load_at(self.t, false);
        Ok(())
    }

    /// Extends (or shortens) the end time, e.g. for a restart with a later
    /// t_end. A run that already stopped at its old t_end had its last step
    /// shortened to land there, so continuing it is not bit-identical to a
    /// run that never stopped; a checkpoint taken before the end is.
    pub fn set_t_end(&mut self, t_end: f64) {
        self.settings.t_end = t_end;
    }

    /// Whether this step's sweep may go in place ([`SweepBounds`]): the
    /// last sweep's `bound`, the loads on their rows and the friction's
    /// velocities (formed before the sweep) bound all it can form.
    #[inline(never)]
    fn may_sweep_in_place(&self, b: &SweepBounds, bound: f64, data: &kernels::StepData) -> bool {
        let loads = self.sparse_loads.rows().iter();
        let l: f64 = loads.map(|&i| data.load_new[i].abs()).sum();
        let f: f64 = self.friction.iter().map(|&(_, v)| v.abs()).sum();
        b.finite(bound, l, f, data)
    }

    /// The closed-form step's sweep in place: ṙ_K and r̈_K over ṙ and r̈
    /// (`kernels::fused_step`), the step's `coefficients`; ṙ_{K−1} at the
    /// contact DOFs kept in `v_new` for the ledger.
    #[inline(never)]
    fn sweep_in_place(&mut self, coefficients: kernels::StepData<'static>) -> (f64, kernels::Sums) {
        let k = self.product.as_ref().expect("an explicit product");
        for &(i, _) in &self.friction {
            self.v_new[i] = self.v[i];
        }
        let data = kernels::StepData {
            load_new: &self.load_new,
            load_rows: self.sparse_loads.rows(),
            mass: &self.dynamics.lumped_mass,
            r_new: &self.r_new,
            v: &[],
            a: &[],
            in_place: true,
            ..coefficients
        };
        kernels::fused_step(
            k,
            &data,
            &self.friction,
            None,
            &mut self.v,
            &mut self.a,
            &mut self.r_next,
            &mut self.partials,
        )
    }

    /// The step's NaN/infinity error, with the critical step as advice for
    /// an explicit run.
    fn non_finite(&self, step: u64, t: f64) -> TimeError {
        let hint = match self.dt_crit {
            Some(c) => format!(" below the critical step Δt_crit = {c:.4e}"),
            None => String::new(),
        };
        TimeError::NonFinite { step, t, hint }
    }

    /// Friction dissipation of the step and the number of nodes that went
    /// from slip to stick, from the new velocity (before the state is
    /// overwritten); fills `forces_new` (`ContactSurface::step_dissipation`).
    fn friction_ledger(&mut self, dt: f64) -> (f64, usize) {
        let Some(c) = &self.contact else {
            return (0.0, 0);
        };
        let dissipated = if let Some(m) = &mut self.modal {
            // The nodes' tangential velocities are the iteration's (u = p
            // − S f at convergence), not formed from q̇.
            m.contact_v_new.copy_from_slice(&self.nodal_velocity);
            c.step_dissipation_tangential(
                &m.contact_v_new,
                &m.contact_v,
                dt,
                &self.forces,
                &mut self.forces_new,
            )
        } else {
            c.step_dissipation(&self.v_new, &self.v, dt, &self.forces, &mut self.forces_new)
        };
        (
            dissipated,
            stick_events(&self.classes, &self.scratch_classes),
        )
    }

    // ---- read access for observers ----

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }
    /// Steps completed.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// Explicit steps this integrator swept in place since it was made
    /// ([`kernels::fused_step`]: ṙ_K and r̈_K written over ṙ_{K−1} and
    /// r̈_{K−1}; not part of a checkpoint, not reset by a restore).
    pub fn in_place_steps(&self) -> u64 {
        self.in_place_steps
    }
    /// End time.
    pub fn t_end(&self) -> f64 {
        self.settings.t_end
    }
    /// Displacement r on free DOFs.
    pub fn displacement(&self) -> &[f64] {
        if let Some(m) = &self.modal {
            return m.physical(0, [&self.r, &self.v, &self.a]);
        }
        &self.r
    }
    /// Velocity ṙ on free DOFs.
    pub fn velocity(&self) -> &[f64] {
        if let Some(m) = &self.modal {
            return m.physical(1, [&self.r, &self.v, &self.a]);
        }
        &self.v
    }
    /// Acceleration r̈ on free DOFs.
    pub fn acceleration(&self) -> &[f64] {
        if let Some(m) = &self.modal {
            return m.physical(2, [&self.r, &self.v, &self.a]);
        }
        &self.a
    }
    /// Stick/slip class of each contact node.
    pub fn classes(&self) -> &[SlipState] {
        &self.classes
    }
    /// The contact surface, if the scene has friction.
    pub fn contact(&self) -> Option<&ContactSurface> {
        self.contact.as_ref()
    }
    /// The energy ledger now.
    pub fn energy(&self) -> Energy {
        self.energy
    }
    /// Numeric factorizations of the implicit operator so far.
    pub fn factorizations(&self) -> u64 {
        self.implicit.as_ref().map_or(0, |op| op.factorizations)
            + self.schur.as_ref().map_or(0, |op| op.factorizations)
    }

    /// Values stored per factor of A₀ (Schur path; 0 otherwise): with 8
    /// bytes each, the memory of one Δt's factor (with its inverted blocks
    /// on small meshes, `small_solve.rs`).
    pub fn factor_len(&self) -> usize {
        self.modal.as_ref().map_or(0, |m| m.modes.len())
            + self.schur.as_ref().map_or(0, |op| op.factor_len())
    }

    /// Implicit runs with friction: (values of W = L⁻¹Pᵀ the step uses, 0
    /// when it solves on the reach instead; values of the factor on the
    /// contact DOFs' paths to the root). For the cost figures.
    pub fn paths_len(&self) -> (usize, usize) {
        self.schur.as_ref().map_or((0, 0), |op| op.paths_len())
    }

    /// Bytes of K one explicit step streams (its compact form, see
    /// `kernels.rs`, or with element classes their cells' DOFs and classes,
    /// the nodes' cell lists and the class matrices once; the CSR's values,
    /// column indices and row offsets when neither applies); 0 for implicit
    /// runs.
    pub fn explicit_matrix_bytes(&self) -> usize {
        match (&self.product, self.explicit) {
            (Some(k), _) => k.bytes(),
            (None, true) => {
                let k = &self.dynamics.stiffness;
                16 * k.nnz() + 8 * (k.nrows() + 1)
            }
            (None, false) => 0,
        }
    }

    /// Bytes one explicit step of the run's Δt moves through memory
    /// (closed-form friction, `kernels.rs`): K
    /// ([`Integrator::explicit_matrix_bytes`], or what the one sweep reads
    /// of it where that is less: the stencil types' unit runs, found once,
    /// and the groups outside them), the free-DOF vectors its
    /// passes read or write (7 of n f64 for the one sweep, whose previous
    /// run formed the predictor; 9 when it has one chunk and K r_K is
    /// stored for the friction; 20 for the compact product and passes B
    /// and C, 23 with the CSR's product) and the loads at their rows; 0 for
    /// implicit runs.
    pub fn explicit_bytes_per_step(&self) -> usize {
        if !self.explicit {
            return 0;
        }
        let n = self.dynamics.n();
        let streams = match &self.product {
            Some(_) if kernels::chunks(n) == 1 => 9,
            Some(_) => 7,
            None => 23,
        };
        let streams = if self.product.is_some()
            && self.contact.is_some()
            && self.settings.explicit_friction == ExplicitFriction::Iterate
        {
            20
        } else {
            streams
        };
        // The one sweep of several chunks may read less of K than a
        // product (RowProduct::sweep_bytes).
        let matrix = match &self.product {
            Some(k) if streams == 7 => k.sweep_bytes(n),
            _ => self.explicit_matrix_bytes(),
        };
        matrix + 8 * streams * n + self.sparse_loads.bytes()
    }

    /// (distinct blocks, stored blocks) of K's compact form when its values
    /// are a dictionary (`kernels.rs`), `None` otherwise.
    pub fn explicit_dictionary(&self) -> Option<(usize, usize)> {
        let Some(kernels::Product::Compact(k)) = &self.product else {
            return None;
        };
        (k.dictionary_len() > 0).then(|| (k.dictionary_len(), k.blocks()))
    }

    /// Classes of K's cells when the explicit step forms K·x from element
    /// classes (`kernels::Classes`), `None` otherwise.
    pub fn explicit_classes(&self) -> Option<usize> {
        match &self.product {
            Some(kernels::Product::Classes(k)) => Some(k.classes().classes()),
            _ => None,
        }
    }

    /// Distinct stencils of K when the explicit step forms K·x by stencil
    /// types (`kernels::Stencils`), `None` otherwise.
    pub fn explicit_stencils(&self) -> Option<usize> {
        match &self.product {
            Some(kernels::Product::Stencils(k)) => Some(k.types()),
            _ => None,
        }
    }

    /// How the run's sparse Cholesky factors (the initial static solve,
    /// A₀, M) are ordered, "AMD" or "nested dissection"
    /// ([`FillOrder::decided_name`]); `None` where the choice waits for a
    /// factorization the run never made (an explicit run from 100k DOFs
    /// without a preload, or any explicit restart from 100k DOFs).
    pub fn fill_order(&self) -> Option<&'static str> {
        self.dynamics.fill_order.decided_name()
    }

    /// How the step forms its products with K (and M): "stencil types",
    /// "element classes", "compact blocks", "2x2 blocks" or "assembled
    /// CSR" (the first two within 1e-12 of the assembled K's products, not
    /// their bits).
    pub fn stiffness_product(&self) -> &'static str {
        match (&self.product, self.explicit) {
            (Some(kernels::Product::Stencils(_)), _) => "stencil types",
            (Some(kernels::Product::Classes(_)), _) => "element classes",
            (Some(kernels::Product::Compact(_)), _) => "compact blocks",
            (Some(kernels::Product::Sliced(_)), _) => "sliced rows",
            (None, false) if self.modal.is_some() => "modes",
            (None, false) if self.implicit_products.is_some() => "stencil types",
            (None, false) if self.pair_blocks.is_some() => "2x2 blocks",
            (None, _) => "assembled CSR",
        }
    }

    /// How implicit steps solve their linear systems.
    pub fn implicit_solver(&self) -> ImplicitSolver {
        self.solver
    }

    /// Chooses how implicit steps solve their linear systems (default
    /// [`ImplicitSolver::Schur`]); meant before the first step. The
    /// factorization count carries over. Does nothing for an explicit run.
    ///
    /// # Errors
    /// [`TimeError::Static`] if the symbolic analysis fails.
    pub fn set_implicit_solver(&mut self, solver: ImplicitSolver) -> Result<(), TimeError> {
        if self.explicit || solver == self.solver {
            self.solver = solver;
            return Ok(());
        }
        let count = self.factorizations();
        self.leave_modal();
        self.implicit = None;
        self.schur = None;
        if solver == ImplicitSolver::Direct {
            let mut op = ImplicitOperator::new(
                &self.dynamics.stiffness,
                &self.dynamics.fill_order,
                self.contact.as_ref(),
            )
            .map_err(TimeError::Static)?;
            op.factorizations = count;
            self.implicit = Some(op);
        } else {
            let mut op = SchurOperator::new(
                &self.dynamics.stiffness,
                &self.dynamics.fill_order,
                self.contact.as_ref(),
                solver,
            )
            .map_err(TimeError::Static)?;
            op.factorizations = count;
            self.schur = Some(op);
        }
        self.solver = solver;
        if solver == ImplicitSolver::Modal {
            self.enter_modal()?;
        }
        Ok(())
    }
    /// Stick/slip iterations (linear solves) summed over all steps.
    pub fn total_iterations(&self) -> u64 {
        self.total_iterations
    }
    /// Estimated critical step of an explicit run.
    pub fn dt_crit(&self) -> Option<f64> {
        self.dt_crit
    }
    /// True when the run is explicit (no linear solves).
    pub fn is_explicit(&self) -> bool {
        self.explicit
    }
    /// The mass the scheme uses.
    pub fn mass_kind(&self) -> MassKind {
        self.mass_kind
    }
    /// Friction stress σ_T = −g φ_ε(v_T) at each contact node.
    pub fn friction_stress(&self, out: &mut [f64]) {
        if let Some(c) = &self.contact {
            match &self.modal {
                Some(m) => {
                    for ((s, node), u) in out.iter_mut().zip(&c.nodes).zip(&m.contact_v) {
                        *s = c.stress(node, *u);
                    }
                }
                None => c.friction_stress(&self.v, out),
            }
        }
    }
    /// Tangential (slip) velocity at each contact node.
    pub fn slip_velocity(&self, out: &mut [f64]) {
        if let Some(c) = &self.contact {
            match &self.modal {
                Some(m) => out[..m.contact_v.len()].copy_from_slice(&m.contact_v),
                None => {
                    for (o, n) in out.iter_mut().zip(&c.nodes) {
                        *o = n.tangential(&self.v);
                    }
                }
            }
        }
    }
}
