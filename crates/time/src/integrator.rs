//! The run as callers see it: one scheme's stepper, the shared state, and
//! what an observer reads after each step.

use stickslip_contact::{ContactSurface, SlipState};
use stickslip_fem::SetupTimes;
use stickslip_linalg::FillOrder;

use crate::dynamics::{Dynamics, Load, Loads};
use crate::foundation::FoundationHistories;
use crate::history::History;
use crate::newmark::ImplicitFriction;
use crate::pressure::BoundHistories;
use crate::settings::{ImplicitSolver, InitialState, MassKind, Scheme, Settings, TimeError};
use crate::state::{Checkpoint, Energy, State, StepInfo};
use crate::stepper::{Run, Stepper};
use crate::{central_difference, newmark, quasi_static};

/// Integrates from the initial state to `t_end`, one step per call.
pub struct Integrator {
    run: Run,
    /// The contact surface the scheme runs without, where it carries no
    /// friction (kept for the observers: slip velocities, stresses);
    /// otherwise the surface is `run.contact`, whose bounds the steps set.
    surface: Option<ContactSurface>,
    state: State,
    stepper: Box<dyn Stepper>,
    fill_order: FillOrder,
    /// The friction bounds' histories, where a surface's pressure changes.
    bounds: Option<BoundHistories>,
    /// The foundations' speeds that change in time.
    foundations: Option<FoundationHistories>,
    /// How long the setup's parts took (the preload, the critical step,
    /// the step's operators).
    setup: SetupTimes,
}

impl std::fmt::Debug for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Integrator")
            .field("n", &self.state.r.len())
            .field("t", &self.state.t)
            .field("steps", &self.state.steps)
            .field("scheme", &self.run.settings.scheme)
            .finish()
    }
}

impl Integrator {
    /// Sets up the run and computes the initial state of Remark 4.1:
    /// r₀ the frictionless static equilibrium under the loads present at
    /// t = 0⁻, ṙ₀ = 0 (or given), r̈₀ from M r̈₀ = R(0) − K r₀ − C ṙ₀ −
    /// J(ṙ₀) (initial.rs).
    ///
    /// A scheme is a `Stepper` (the crate's internal trait) made by its
    /// module's `start`; this match is the one place that names them.
    ///
    /// # Errors
    /// Settings out of range, Δt above the explicit critical step (unless
    /// allowed), or a singular static problem.
    pub fn new(
        dynamics: Dynamics,
        contact: Option<ContactSurface>,
        loads: Vec<Load>,
        settings: Settings,
    ) -> Result<Integrator, TimeError> {
        let mass_kind = settings.check(dynamics.n())?;
        // μ falling with the slip speed: the explicit closed form solves
        // each node's equation, the implicit steps iterate with μ lagged
        // by a step; the explicit iteration, the closed form's reference
        // for the constant law, has neither.
        let iterated = settings.scheme == Scheme::CentralDifference
            && settings.explicit_friction == crate::settings::ExplicitFriction::Iterate;
        if contact.as_ref().is_some_and(ContactSurface::weakens) && iterated {
            return Err(TimeError::Settings(
                "a friction coefficient that falls with the slip speed (mu = { static, kinetic, speed }) \
                 runs with central difference's nodal closed form, not its iteration"
                    .into(),
            ));
        }
        // A compliant node's bound is c_T δ^{m_T} (METHOD.md §10): μ
        // falling with the slip speed is not built there, so a scene
        // refuses it as case files do rather than run something else.
        if let Some(c) = contact.as_ref() {
            if let Some(k) = c
                .compliance
                .iter()
                .find(|k| c.weakening_of(k.index).is_some())
            {
                return Err(TimeError::Settings(format!(
                    "surface {} has law = \"compliance\" at node {} with a friction coefficient \
                     that falls with the slip speed; a compliant foundation takes a constant mu",
                    c.names(),
                    c.nodes[k.index].node
                )));
            }
        }
        // A scene without friction nodes runs no friction code; nor does
        // one whose nodes carry none (μ = 0 or no pressure: w g = 0 at
        // every node), which then steps as a scene without a contact
        // surface, the surface kept for the observers.
        // A compliant foundation's bounds follow the approach, so its
        // surface runs the friction code whatever its bounds at t = 0.
        let (contact, surface) = match contact.filter(|c| !c.is_empty()) {
            Some(c) if c.carries_friction() || c.is_compliant() => (Some(c), None),
            other => (None, other),
        };
        let loads = Loads {
            constant: dynamics.constant_load.clone(),
            loads,
        };
        let fill_order = dynamics.fill_order.clone();
        let mut setup = SetupTimes::default();
        let started = std::time::Instant::now();
        let times = &mut setup;
        let (stepper, state) = match settings.scheme {
            Scheme::CentralDifference => {
                central_difference::start(dynamics, contact.as_ref(), &loads, &settings, times)?
            }
            Scheme::Newmark { beta, gamma } => newmark::start(
                dynamics,
                (beta, gamma),
                mass_kind,
                contact.as_ref(),
                &loads,
                &settings,
                times,
            )?,
            Scheme::QuasiStatic => {
                quasi_static::start(dynamics, contact.as_ref(), &loads, &settings, times)?
            }
        };
        // What a scheme's start did beside its timed parts: its step's
        // operators (stencil types, factors, friction's constants).
        let rest = started.elapsed().as_secs_f64() - setup.total();
        setup.add("operators", rest.max(0.0));
        let mut integrator = Integrator {
            surface,
            run: Run {
                contact,
                loads,
                settings,
            },
            state,
            stepper,
            fill_order,
            bounds: None,
            foundations: None,
            setup,
        };
        // A static preload pressed the part into a compliant foundation:
        // its bounds follow that approach from t = 0.
        if integrator.run.settings.initial_state == InitialState::Static {
            integrator.comply_at_state();
            if integrator
                .run
                .contact
                .as_ref()
                .is_some_and(ContactSurface::is_compliant)
            {
                integrator.forces_at_start()?;
            }
        }
        Ok(integrator)
    }

    /// The friction at t = 0 again, for the contact as it now is (its
    /// bounds or foundation speeds set for t = 0 after the start), and
    /// r̈₀ with it: M r̈₀ = R(0) − K r₀ − C ṙ₀ − J₀ (initial.rs) gains
    /// J₀ − J₀'. Nothing changes where the forces do not (at rest on a
    /// foundation at rest they are zero), nor where the start carries no
    /// friction (quasi-static increments).
    fn forces_at_start(&mut self) -> Result<(), TimeError> {
        let Some(contact) = self.run.contact.as_ref() else {
            return Ok(());
        };
        if !self.friction_at_start() {
            return Ok(());
        }
        let before = self.state.forces.clone();
        contact.classify(&self.state.v, &mut self.state.classes);
        contact.nodal_forces(&self.state.v, &mut self.state.forces);
        if before == self.state.forces {
            return Ok(());
        }
        let change: Vec<f64> = self
            .state
            .forces
            .iter()
            .zip(&before)
            .map(|(new, old)| new - old)
            .collect();
        let mut da = vec![0.0; self.state.a.len()];
        contact.subtract_forces(&change, &mut da);
        self.stepper.solve_mass(&mut da, &self.fill_order)?;
        for (a, d) in self.state.a.iter_mut().zip(&da) {
            *a += d;
        }
        // A step formed ahead from r̈₀ must form again.
        self.stepper.state_replaced();
        Ok(())
    }

    /// How long the setup's parts took: the preload's ordering, factor
    /// and solve (an implicit scheme's `analysis` of K's pattern where it
    /// comes first, for its step's operator too), the critical step, the
    /// step's operators.
    pub fn setup_times(&self) -> &SetupTimes {
        &self.setup
    }

    /// Makes each contact surface's pressure change in time: the bounds of
    /// surface k (`ContactSurface::parts[k]`) are their built values times
    /// `histories[k]`(t), set before each step for the time it ends at
    /// (the friction of a step acts at its end, METHOD.md §4). Constant
    /// and step histories change nothing after t = 0 and cost nothing.
    /// Call it on a fresh integrator, before [`Integrator::restore`].
    ///
    /// # Errors
    /// [`TimeError::Static`] where a consistent M fails to factorize for
    /// r̈₀ (where CG on its diagonal stalls, as at the start).
    pub fn set_pressure_histories(&mut self, histories: &[History]) -> Result<(), TimeError> {
        let Some(contact) = self.run.contact.as_mut() else {
            return Ok(());
        };
        self.bounds = BoundHistories::new(contact, histories);
        if let Some(b) = &mut self.bounds {
            b.apply(self.state.t, contact);
            // The initial forces are w g φ_ε(ṙ₀) with g at t = 0.
            self.forces_at_start()?;
        }
        Ok(())
    }

    /// Makes each contact surface's foundation speed (built into the
    /// surface, [`ContactSurface::set_foundation`]) change in time: V_J of
    /// surface k times `histories[k]`(t), set before each step for the time
    /// it ends at, as [`Integrator::set_pressure_histories`] sets the
    /// bounds. Nothing is kept where no foundation moves or every history
    /// is constant. Call it on a fresh integrator, before
    /// [`Integrator::restore`].
    ///
    /// # Errors
    /// As [`Integrator::set_pressure_histories`].
    pub fn set_foundation_histories(&mut self, histories: &[History]) -> Result<(), TimeError> {
        // A surface that carries no friction (μ = 0) is kept for the
        // observers, whose slip w = v_T − V needs the speeds all the same.
        let Some(contact) = self.run.contact.as_mut().or(self.surface.as_mut()) else {
            return Ok(());
        };
        self.foundations = FoundationHistories::new(contact, histories);
        if let Some(f) = &mut self.foundations {
            f.apply(self.state.t, contact);
            // The initial classes and forces act on the slip at t = 0.
            self.forces_at_start()?;
        }
        Ok(())
    }

    /// Sets the bounds and the foundation speeds for time `t`, where they
    /// change in time.
    fn bounds_at(&mut self, t: f64) {
        if let (Some(b), Some(c)) = (&mut self.bounds, &mut self.run.contact) {
            b.apply(t, c);
        }
        let surface = self.run.contact.as_mut().or(self.surface.as_mut());
        if let (Some(f), Some(c)) = (&mut self.foundations, surface) {
            f.apply(t, c);
        }
    }

    /// True once t_end is reached.
    pub fn done(&self) -> bool {
        self.state.t >= self.run.settings.t_end * (1.0 - 1e-14)
    }

    /// Advances one step.
    ///
    /// # Errors
    /// A failed linear solve, a stick/slip iteration that hits its cap, or a
    /// non-finite state. The state is left at the last completed step.
    pub fn step(&mut self) -> Result<StepInfo, TimeError> {
        if self.bounds.is_none() && self.foundations.is_none() {
            let result = self.stepper.step(&mut self.run, &mut self.state);
            if result.is_err() {
                self.comply_at_state();
            }
            return result;
        }
        let t_new = self.state.next_step(&self.run.settings).1;
        self.bounds_at(t_new);
        let result = self.stepper.step(&mut self.run, &mut self.state);
        if result.is_err() {
            self.bounds_at(self.state.t);
            self.comply_at_state();
        }
        result
    }

    /// Sets a compliant foundation's bounds for the current displacement
    /// (after a failed step or a restore, which leave the state a step
    /// earlier than the bounds' last setting).
    fn comply_at_state(&mut self) {
        if let Some(c) = self.run.contact.as_mut().filter(|c| c.is_compliant()) {
            self.state.energy.foundation_stored = c.comply_bounds(&self.state.r);
        }
    }

    /// Everything needed to continue this run bit-identically
    /// ([`Integrator::restore`] on a fresh integrator of the same case).
    pub fn checkpoint(&self) -> Checkpoint {
        self.state
            .checkpoint((self.factorizations(), self.normal_iterations()))
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
        // A run without friction on a surface keeps no classes or forces;
        // a checkpoint of a version that ran friction code on it (all
        // forces 0) has them.
        let n_c = self.contact().map_or(0, ContactSurface::len);
        let without_friction;
        let c = if self.run.contact.is_none() && n_c > 0 && c.classes.len() == n_c {
            without_friction = Checkpoint {
                classes: Vec::new(),
                forces: Vec::new(),
                ..c.clone()
            };
            &without_friction
        } else {
            c
        };
        self.state.restore(c, self.run.settings.dt)?;
        self.stepper.state_replaced();
        if let Some(f) = self.stepper.implicit_mut() {
            f.set_factorizations(c.factorizations);
            f.set_normal_iterations(c.normal_iterations);
        }
        self.run.loads.at(self.state.t, &mut self.state.load);
        self.bounds_at(self.state.t);
        self.comply_at_state();
        Ok(())
    }

    /// Extends (or shortens) the end time, e.g. for a restart with a later
    /// t_end. A run that already stopped at its old t_end had its last step
    /// shortened to land there, so continuing it is not bit-identical to a
    /// run that never stopped; a checkpoint taken before the end is.
    pub fn set_t_end(&mut self, t_end: f64) {
        self.run.settings.t_end = t_end;
    }

    // ---- read access for observers ----

    /// Current time.
    pub fn time(&self) -> f64 {
        self.state.t
    }
    /// Steps completed.
    pub fn steps(&self) -> u64 {
        self.state.steps
    }
    /// End time.
    pub fn t_end(&self) -> f64 {
        self.run.settings.t_end
    }
    /// Displacement r on free DOFs.
    pub fn displacement(&self) -> &[f64] {
        &self.state.r
    }
    /// Velocity ṙ on free DOFs.
    pub fn velocity(&self) -> &[f64] {
        &self.state.v
    }
    /// Acceleration r̈ on free DOFs.
    pub fn acceleration(&self) -> &[f64] {
        &self.state.a
    }
    /// Stick/slip class of each contact node.
    pub fn classes(&self) -> &[SlipState] {
        &self.state.classes
    }
    /// The contact surface, if the scene has friction-carrying nodes
    /// (whether their friction can act or not: [`Integrator::friction`]).
    pub fn contact(&self) -> Option<&ContactSurface> {
        self.run.contact.as_ref().or(self.surface.as_ref())
    }
    /// True when the steps run friction code: the scene has a contact
    /// surface and w g > 0 at some node of it.
    pub fn friction(&self) -> bool {
        self.run.contact.is_some()
    }
    /// Steps of this integrator that ran friction code (none where
    /// [`Integrator::friction`] is false).
    pub fn friction_passes(&self) -> u64 {
        self.state.friction_passes
    }
    /// Stick/slip state code of each contact node (0 stuck, ±1 slipping
    /// along ±τ): the step's classes, or where friction is off the law's
    /// class of the tangential velocity (no force acts either way).
    pub fn slip_states(&self, out: &mut [i8]) {
        match (&self.run.contact, &self.surface) {
            (Some(_), _) => {
                for (o, c) in out.iter_mut().zip(&self.state.classes) {
                    *o = c.code();
                }
            }
            (None, Some(c)) => {
                for (j, (o, n)) in out.iter_mut().zip(&c.nodes).enumerate() {
                    *o = c
                        .law_of(j)
                        .classify(c.slip(j, n.tangential(&self.state.v)))
                        .code();
                }
            }
            (None, None) => {}
        }
    }
    /// The energy ledger now.
    pub fn energy(&self) -> Energy {
        self.state.energy
    }
    /// Stick/slip iterations (linear solves) summed over all steps.
    pub fn total_iterations(&self) -> u64 {
        self.state.total_iterations
    }
    /// Newton iterations of a compliant foundation's implicit solves so
    /// far (0 for explicit runs and prescribed pressures).
    pub fn normal_iterations(&self) -> u64 {
        self.stepper
            .implicit()
            .map_or(0, ImplicitFriction::normal_iterations)
    }
    /// Numeric factorizations of the implicit operator so far.
    pub fn factorizations(&self) -> u64 {
        self.stepper
            .implicit()
            .map_or(0, ImplicitFriction::factorizations)
    }
    /// Values stored per factor of A₀ (Schur path; 0 otherwise): with 8
    /// bytes each, the memory of one Δt's factor.
    pub fn factor_len(&self) -> usize {
        self.stepper
            .implicit()
            .map_or(0, ImplicitFriction::factor_len)
    }
    /// Implicit runs with friction: (values of W = L⁻¹Pᵀ the step uses, 0
    /// when it solves on the reach instead; values of the factor on the
    /// contact DOFs' paths to the root). For the cost figures.
    pub fn paths_len(&self) -> (usize, usize) {
        self.stepper
            .implicit()
            .map_or((0, 0), ImplicitFriction::paths_len)
    }
    /// Bytes of K one explicit step streams; 0 for implicit runs.
    pub fn explicit_matrix_bytes(&self) -> usize {
        self.stepper.matrix_bytes()
    }
    /// Bytes one explicit step moves through memory; 0 for implicit runs.
    pub fn explicit_bytes_per_step(&self) -> usize {
        self.stepper.bytes_per_step()
    }
    /// Distinct stencils of K when the explicit step forms K·x by stencil
    /// types, `None` otherwise.
    pub fn explicit_stencils(&self) -> Option<usize> {
        self.stepper.stencil_types()
    }
    /// How the run's sparse Cholesky factors are ordered, "AMD" or "nested
    /// dissection" ([`FillOrder::decided_name`]); `None` where the choice
    /// waits for a factorization the run never made.
    pub fn fill_order(&self) -> Option<&'static str> {
        self.fill_order.decided_name()
    }
    /// How the step forms its products with K: "stencil types",
    /// "symmetric node blocks", "paired node blocks" (Newmark's K and M)
    /// or "assembled CSR".
    pub fn stiffness_product(&self) -> &'static str {
        self.stepper.stiffness_product()
    }
    /// How implicit steps solve their linear systems.
    pub fn implicit_solver(&self) -> ImplicitSolver {
        self.run.settings.implicit_solver
    }
    /// Estimated critical step of an explicit run.
    pub fn dt_crit(&self) -> Option<f64> {
        self.stepper.dt_crit()
    }
    /// True when the run is explicit (no linear solves).
    pub fn is_explicit(&self) -> bool {
        self.stepper.is_explicit()
    }
    /// The mass the scheme uses; `None` for quasi-static increments.
    pub fn mass_kind(&self) -> Option<MassKind> {
        self.stepper.mass_kind()
    }

    /// Whether the start carries the friction at the slip at t = 0 (in
    /// r̈₀, initial.rs): not without mass (quasi-static increments), whose
    /// start is the frictionless static state, the law first applied by
    /// the first increment.
    fn friction_at_start(&self) -> bool {
        self.stepper.mass_kind().is_some()
    }
    /// Friction stress σ_T = −g φ_ε(v_T) at each contact node: 0 in the
    /// start of quasi-static increments, which carries no friction.
    pub fn friction_stress(&self, out: &mut [f64]) {
        if let Some(c) = self.contact() {
            if self.state.steps == 0 && !self.friction_at_start() {
                out.iter_mut().take(c.len()).for_each(|o| *o = 0.0);
                return;
            }
            c.friction_stress(&self.state.v, out);
        }
    }
    /// The normal traction c_n δ^{m_n} a compliant foundation exerts at
    /// each contact node (0 on prescribed-pressure surfaces).
    pub fn normal_traction(&self, out: &mut [f64]) {
        if let Some(c) = self.contact() {
            c.normal_tractions(&self.state.r, out);
        }
    }

    /// The slip w = v_T − V at each contact node (v_T on a foundation at
    /// rest).
    pub fn slip_velocity(&self, out: &mut [f64]) {
        if let Some(c) = self.contact() {
            for (j, (o, n)) in out.iter_mut().zip(&c.nodes).enumerate() {
                *o = c.slip(j, n.tangential(&self.state.v));
            }
        }
    }
}
