//! Newmark (β, γ) in the paper's velocity form (METHOD.md §4): ṙ_K the
//! only unknown of [(β/γ)ΔtK + M/(γΔt) + C_K] ṙ_K = R̂_K − F_K, with the
//! stick/slip iteration of §5 on the friction. Two ways to solve a step:
//! the Schur complement on the contact DOFs with A₀ factorized once per Δt
//! (`schur.rs`, the default), or A₀ + C refactorized per stuck set
//! (`direct.rs`, the reference). [`ImplicitFriction`] is that solve of a
//! step's velocity with its friction, which the quasi-static increments
//! share (`quasi_static.rs`: the same system with M = 0).

mod algorithmic;
mod compliance;
mod direct;
mod schur;

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{iterate, stick_events, ContactSurface, SlipState};
use stickslip_linalg::csr::same_pattern;
use stickslip_linalg::PairedKm;
use stickslip_linalg::{chunks, Analysis, FillOrder};

use stickslip_fem::SetupTimes;

use crate::dynamics::{Dynamics, Loads};
use crate::initial::{initial_state, Mass, SharedAnalysis, Statics};
use crate::settings::{ImplicitSolver, MassKind, Rayleigh, Settings, TimeError};
use crate::state::{State, StepEnergies, StepInfo};
use crate::stepper::{Run, Stepper};

use algorithmic::AlgorithmicNormal;
use compliance::{CompliantSolve, CompliantStep, NormalForm};
use direct::{DirectOperator, ImplicitStep};
use schur::SchurOperator;

/// How a step solves (each operator boxed: they are large and of unlike
/// sizes, and one is made per run).
enum Solver {
    Schur(Box<SchurOperator>),
    Direct(Box<DirectOperator>),
}

/// The velocity of an implicit step with its friction: for R̂ = b, the
/// stick/slip iteration of §5 on (c_K K + c_M M + C) ṙ = b − F by the
/// run's solver.
pub(crate) struct ImplicitFriction {
    solver: Solver,
    /// Where μ falls with the slip speed: the surface with μ at each
    /// node's slip of the last step, on which the step iterates
    /// (`stickslip_contact`'s `lagged_mu.rs`).
    lagged: Option<ContactSurface>,
    /// The Schur path's nodal tangential velocities.
    nodal_velocity: Vec<f64>,
    iter_scratch: Vec<SlipState>,
    /// A compliant foundation's Newton solve (Schur path; `None` without
    /// one).
    compliant: Option<Box<CompliantSolve>>,
}

/// The Newmark stepper.
pub(crate) struct Newmark {
    beta: f64,
    gamma: f64,
    mass_kind: MassKind,
    k: CsrMatrix<f64>,
    /// The scheme's mass on K's pattern (the lumped one on the diagonal).
    m: CsrMatrix<f64>,
    /// K and this M by node blocks, for the passes of every step.
    km: PairedKm,
    /// The lumped mass by DOF, where it is the scheme's.
    lumped: Option<Vec<f64>>,
    friction: ImplicitFriction,
    /// R̂_K, and M's vector of it.
    b: Vec<f64>,
    tmp: Vec<f64>,
    /// K r_pred and M[ṙ/(γΔt) + (1/γ − 1) r̈] of the next step, formed in
    /// the last step's pass for its energies (the predictor into
    /// `State::r_new`), for the Δt of that step.
    next_products: [Vec<f64>; 2],
    /// (steps, Δt bits) of the state `next_products` were formed for: a
    /// next step of that Δt reads them instead of K and M.
    predicted: Option<(u64, u64)>,
    partials: Vec<[f64; 2]>,
    /// Newmark ¼, ½ on a compliant foundation: the energy-consistent
    /// normal force's part of the step (`algorithmic.rs`); `None` where
    /// the step takes the end-point force.
    algorithmic: Option<Box<AlgorithmicNormal>>,
}

/// Builds the stepper and the initial state.
///
/// # Errors
/// A singular static problem or operator.
pub(crate) fn start(
    dynamics: Dynamics,
    (beta, gamma): (f64, f64),
    mass_kind: MassKind,
    contact: Option<&ContactSurface>,
    loads: &Loads,
    settings: &Settings,
    times: &mut SetupTimes,
) -> Result<(Box<dyn Stepper>, State), TimeError> {
    let Dynamics {
        stiffness: k,
        consistent_mass,
        lumped_mass,
        fill_order,
        rigid_modes,
        ..
    } = dynamics;
    let n = k.nrows();
    let m = match mass_kind {
        MassKind::Consistent => consistent_mass.ok_or_else(|| {
            TimeError::Settings(
                "Newmark with the consistent mass on a model built without it \
                 (stickslip_fem::Model::without_consistent_mass): build it with Model::new, \
                 or set time.mass = \"lumped\""
                    .into(),
            )
        })?,
        MassKind::Lumped => {
            drop(consistent_mass);
            let mut m = k.clone();
            let (offsets, cols, values) = m.csr_data_mut();
            for i in 0..n {
                for p in offsets[i]..offsets[i + 1] {
                    values[p] = if cols[p] == i { lumped_mass[i] } else { 0.0 };
                }
            }
            m
        }
    };
    assert!(same_pattern(&k, &m), "K and M share one pattern (fem)");
    let km = PairedKm::new(&k, &m).ok_or_else(|| {
        TimeError::Settings(format!(
            "{n} free DOFs: Newmark's products index them with 32 bits; \
             split the model or use central difference"
        ))
    })?;
    let mass = match mass_kind {
        MassKind::Consistent => Mass::Consistent(&m),
        MassKind::Lumped => Mass::Lumped(&lumped_mass),
    };
    // The first step's operator, as the step will form it.
    let dt = State::first_dt(settings);
    let first = Operator::newmark((beta, gamma), dt, settings.damping, (&k, &m));
    let (mut state, friction) = ImplicitFriction::with_initial_state(
        &k,
        mass,
        (&fill_order, &rigid_modes, times),
        contact,
        loads,
        settings,
        Some(first),
    )?;
    // The energy-consistent normal force where the scheme is the
    // trapezoidal rule (METHOD.md §10): its excess starts at 0, r̈₀ being
    // the end-point force's.
    let algorithmic = match contact.filter(|c| c.is_compliant()) {
        Some(c) if (beta, gamma) == (0.25, 0.5) && friction.compliant.is_some() => {
            state.normal_excess = vec![0.0; c.compliance.len()];
            state.normal_excess_new = vec![0.0; c.compliance.len()];
            Some(Box::new(AlgorithmicNormal::new(&m, mass_kind, &fill_order)))
        }
        _ => None,
    };
    let lumped = (mass_kind == MassKind::Lumped).then_some(lumped_mass);
    let stepper = Newmark {
        beta,
        gamma,
        mass_kind,
        k,
        m,
        km,
        lumped,
        friction,
        b: vec![0.0; n],
        tmp: vec![0.0; n],
        next_products: [vec![0.0; n], vec![0.0; n]],
        predicted: None,
        partials: chunks::partials(n),
        algorithmic,
    };
    Ok((Box::new(stepper), state))
}

/// A step's operator A₀ = c_K K + c_M M of Δt `dt` (M has K's pattern),
/// as the solvers factorize it: once per Δt (`schur.rs`), or per stuck
/// set (`direct.rs`).
#[derive(Clone, Copy)]
pub(crate) struct Operator<'a> {
    pub dt: f64,
    pub c_k: f64,
    pub k: &'a CsrMatrix<f64>,
    pub c_m: f64,
    pub m: &'a CsrMatrix<f64>,
}

impl<'a> Operator<'a> {
    /// Newmark (β, γ)'s: (β/γ)Δt K + M/(γΔt) (METHOD.md §4), Rayleigh
    /// damping C = αM + βK joining it (METHOD.md §8).
    fn newmark(
        (beta, gamma): (f64, f64),
        dt: f64,
        damping: Rayleigh,
        (k, m): (&'a CsrMatrix<f64>, &'a CsrMatrix<f64>),
    ) -> Operator<'a> {
        let (mut c_k, mut c_m) = (beta / gamma * dt, 1.0 / (gamma * dt));
        if damping.is_on() {
            (c_k, c_m) = (c_k + damping.beta, c_m + damping.alpha);
        }
        Operator { dt, c_k, k, c_m, m }
    }

    /// A₀'s values on K's pattern, c_K k + c_M m value by value.
    pub(crate) fn values(&self) -> impl Iterator<Item = f64> + '_ {
        let (c_k, c_m) = (self.c_k, self.c_m);
        self.k
            .values()
            .iter()
            .zip(self.m.values())
            .map(move |(k, m)| c_k * k + c_m * m)
    }

    /// A quasi-static increment's: Δt K + 0·K, Newmark's with β/γ = 1 and
    /// no mass.
    pub(crate) fn increment(dt: f64, k: &'a CsrMatrix<f64>) -> Operator<'a> {
        Operator {
            dt,
            c_k: dt,
            k,
            c_m: 0.0,
            m: k,
        }
    }
}

impl ImplicitFriction {
    /// The initial state with `mass` and the solver of the steps, on one
    /// analysis of K's pattern for the run (K, M and the step's operator
    /// share it): the one the preload or the consistent mass's factor
    /// made, else the solver's own. The tuple: the factors' ordering, the
    /// free rigid motions, where the setup's times go.
    ///
    /// With `first` on a fresh start the analysis comes first, and the
    /// Schur solver factorizes the first step's operator on a thread of
    /// its own while this one forms the initial state (its factorizations
    /// too run on their calling thread, faer's kernels: `cholesky.rs`);
    /// the operator's S and W, on the pool, follow. The step finds them in
    /// its solver's cache; where the factorization fails, the step meets
    /// the failure and reports it. An initial state that fails is reported
    /// once that factorization has ended.
    ///
    /// # Errors
    /// As [`initial_state`] and [`ImplicitFriction::new`].
    pub(crate) fn with_initial_state(
        k: &CsrMatrix<f64>,
        mass: Mass,
        (fill_order, modes, times): (&FillOrder, &[stickslip_fem::RigidMode], &mut SetupTimes),
        contact: Option<&ContactSurface>,
        loads: &Loads,
        settings: &Settings,
        first: Option<Operator>,
    ) -> Result<(State, ImplicitFriction), TimeError> {
        let first = first.filter(|f| !settings.restoring && f.dt > 0.0);
        let (mut shared, mut friction) = (None, None);
        if first.is_some() {
            let analysis = times
                .time("analysis", || Analysis::of(k, fill_order))
                .map_err(TimeError::Static)?;
            let solver =
                ImplicitFriction::new(k, fill_order, Some(analysis.clone()), contact, settings)?;
            (shared, friction) = (Some(analysis), Some(solver));
        }
        let analyzed = shared.clone();
        let statics = Statics {
            fill_order,
            modes,
            times,
            single_factor: false,
            analysis: Some(&mut shared),
        };
        let (state, factored) = std::thread::scope(|s| {
            let ahead = friction
                .as_mut()
                .zip(first.as_ref())
                .map(|(f, &first)| s.spawn(move || f.factorize_ahead(first)));
            let state = initial_state(k, mass, statics, contact, loads, settings, analyzed);
            let factored =
                ahead.is_some_and(|h| h.join().expect("the first step's operator thread"));
            (state, factored)
        });
        let state = state?;
        let friction = match (friction, first) {
            (Some(mut friction), Some(first)) => {
                if factored {
                    friction.finish_ahead(first);
                }
                friction
            }
            _ => ImplicitFriction::new(k, fill_order, shared, contact, settings)?,
        };
        Ok((state, friction))
    }

    /// The run's analysis of K's pattern (which M and A₀ share).
    pub(crate) fn analysis(&self) -> SharedAnalysis {
        match &self.solver {
            Solver::Schur(op) => Some(op.analysis().clone()),
            Solver::Direct(op) => Some(op.analysis().clone()),
        }
    }

    /// The settings' solver for K's pattern (which M shares), analysed
    /// once for the run: `analysis` where the initial state made it.
    ///
    /// # Errors
    /// [`TimeError::Static`] when the analysis fails.
    pub(crate) fn new(
        k: &CsrMatrix<f64>,
        fill_order: &FillOrder,
        analysis: SharedAnalysis,
        contact: Option<&ContactSurface>,
        settings: &Settings,
    ) -> Result<ImplicitFriction, TimeError> {
        let use_paths = match settings.implicit_solver {
            ImplicitSolver::SchurPaths => Some(true),
            ImplicitSolver::SchurReach => Some(false),
            _ => None,
        };
        let solver = match settings.implicit_solver {
            ImplicitSolver::Schur | ImplicitSolver::SchurPaths | ImplicitSolver::SchurReach => {
                Solver::Schur(Box::new(
                    SchurOperator::new(k, fill_order, analysis, contact, use_paths)
                        .map_err(TimeError::Static)?,
                ))
            }
            ImplicitSolver::Direct => Solver::Direct(Box::new(
                DirectOperator::new(k, fill_order, analysis, contact).map_err(TimeError::Static)?,
            )),
        };
        let n_c = contact.map_or(0, |c| c.len());
        let compliant = match (&solver, contact.filter(|c| c.is_compliant())) {
            (Solver::Schur(_), Some(c)) => Some(Box::new(CompliantSolve::new(c))),
            (Solver::Direct(_), Some(c)) => {
                return Err(TimeError::Settings(format!(
                    "surface {} has law = \"compliance\", which the implicit schemes solve on the \
                     Schur complement only (ImplicitSolver::Schur, the case's), not the direct \
                     reference",
                    c.names()
                )))
            }
            _ => None,
        };
        Ok(ImplicitFriction {
            solver,
            lagged: contact.filter(|c| c.weakens()).map(ContactSurface::lagged),
            nodal_velocity: vec![0.0; n_c],
            iter_scratch: vec![SlipState::Stuck; n_c],
            compliant,
        })
    }

    /// Factorizes the first step's operator ahead of the step, into the
    /// Schur solver's cache of factors per Δt, on this thread: true where
    /// it did (false for the direct solver, which factorizes per stuck
    /// set). A failure leaves no factor: the step factorizes again and
    /// reports it with its step and time.
    fn factorize_ahead(&mut self, first: Operator) -> bool {
        match &mut self.solver {
            Solver::Schur(op) => op.factorize_dt(first).is_ok(),
            Solver::Direct(_) => false,
        }
    }

    /// S and W of the operator [`Self::factorize_ahead`] made (the cache
    /// holds its factor, so nothing is factorized again).
    fn finish_ahead(&mut self, first: Operator) {
        if let Solver::Schur(op) = &mut self.solver {
            let made = op.set_dt(first);
            debug_assert!(made.is_ok(), "the factor is in the cache");
        }
    }

    /// Takes μ at each node's slip at velocity `v` (the last step's)
    /// where it falls with the slip speed, for the next [`Self::velocity`].
    pub(crate) fn lag_mu(&mut self, run: &Run, v: &[f64]) {
        if let (Some(lagged), Some(c)) = (&mut self.lagged, &run.contact) {
            lagged.lag_bounds(c, v);
        }
    }

    /// A compliant foundation's bounds at the step's end `r` on `contact`
    /// (and on the lagged surface), for the ledger's friction forces;
    /// returns the foundation's stored energy, 0 without one.
    pub(crate) fn comply(&mut self, contact: Option<&mut ContactSurface>, r: &[f64]) -> f64 {
        match contact.filter(|c| c.is_compliant()) {
            Some(c) => {
                let stored = c.comply_bounds(r);
                self.follow_compliance(c);
                stored
            }
            None => 0.0,
        }
    }

    /// Where μ is lagged, gives the lagged surface the bounds `comply` has
    /// just set at r_K on `contact`'s compliant nodes: the ledger books the
    /// step's forces on the lagged surface, on which those nodes would
    /// otherwise keep the bounds at r_{K−1} (their μ is constant, so the
    /// lag takes their bounds as they are).
    fn follow_compliance(&mut self, contact: &ContactSurface) {
        let Some(lagged) = &mut self.lagged else {
            return;
        };
        let mut changed = false;
        for k in &contact.compliance {
            let (to, from) = (
                &mut lagged.nodes[k.index].bound,
                contact.nodes[k.index].bound,
            );
            changed |= to.to_bits() != from.to_bits();
            *to = from;
        }
        if changed {
            lagged.revision += 1;
        }
    }

    /// The surface the step's friction acts with: the run's, or where μ
    /// falls with the slip speed its lagged copy (the forces the step
    /// applied, for the ledger).
    pub(crate) fn surface<'a>(&'a self, run: &'a Run) -> Option<&'a ContactSurface> {
        self.lagged.as_ref().or(run.contact.as_ref())
    }

    /// ṙ into `v_new` for the right-hand side `b` and the operator
    /// c_K K + c_M M (+ C): the iteration of §5 with the step's solver,
    /// the operator's factor formed once per Δt. Returns the linear solves
    /// made.
    pub(crate) fn velocity(
        &mut self,
        run: &Run,
        operator: Operator,
        b: &[f64],
        (classes_new, v_new): (&mut [SlipState], &mut [f64]),
        (step, t): (u64, f64),
    ) -> Result<usize, TimeError> {
        let options = run.settings.iteration;
        let failed = |f| {
            TimeError::from_iteration(f, (step, t, options.remark_4_2), |source| {
                TimeError::Solve { step, t, source }
            })
        };
        let contact = self.lagged.as_ref().or(run.contact.as_ref());
        match &mut self.solver {
            Solver::Schur(op) => {
                op.set_dt(operator)
                    .map_err(|source| TimeError::Solve { step, t, source })?;
                if contact.is_none() {
                    op.solve_plain(b, v_new);
                    return Ok(1);
                }
                op.begin(b);
                let mut reduced = op
                    .reduced
                    .take()
                    .expect("a contact surface has its nodal surface");
                if let Some(c) = contact.filter(|c| c.revision != reduced.revision) {
                    reduced.set_bounds(|j| c.nodes[j].bound);
                    reduced.revision = c.revision;
                }
                if let Some(c) = contact.filter(|c| !c.foundation.is_empty()) {
                    reduced.foundation.clone_from(&c.foundation);
                }
                if let Some(solve) = self.compliant.as_deref_mut() {
                    let result = iterate(
                        &reduced,
                        &mut CompliantStep { op, solve },
                        classes_new,
                        &mut self.iter_scratch,
                        &mut self.nodal_velocity,
                        options,
                    );
                    op.reduced = Some(reduced);
                    let report = result.map_err(|f| {
                        TimeError::from_iteration(f, (step, t, options.remark_4_2), |e| {
                            e.into_error(step, t)
                        })
                    })?;
                    op.finish(v_new);
                    return Ok(report.iterations);
                }
                let result = iterate(
                    &reduced,
                    &mut op.nodal_system(),
                    classes_new,
                    &mut self.iter_scratch,
                    &mut self.nodal_velocity,
                    options,
                );
                op.reduced = Some(reduced);
                let report = result.map_err(failed)?;
                op.finish(v_new);
                Ok(report.iterations)
            }
            Solver::Direct(op) => {
                op.set_dt(operator);
                let Some(contact) = contact else {
                    op.solve_plain(b, v_new)
                        .map_err(|source| TimeError::Solve { step, t, source })?;
                    return Ok(1);
                };
                let mut system = ImplicitStep { operator: op, b };
                let report = iterate(
                    contact,
                    &mut system,
                    classes_new,
                    &mut self.iter_scratch,
                    v_new,
                    options,
                )
                .map_err(failed)?;
                Ok(report.iterations)
            }
        }
    }

    /// A compliant foundation's step: its nodes' approach follows the
    /// predictor `r_pred` and r_K = r_pred + c3 ṙ_K; the Newton solve
    /// starts from the last velocity `v`. Nothing without one.
    pub(crate) fn predict_normal(
        &mut self,
        contact: &ContactSurface,
        r_pred: &[f64],
        v: &[f64],
        c3: f64,
    ) {
        if let Some(solve) = self.compliant.as_deref_mut() {
            solve.predict(contact, r_pred, v, c3);
        }
    }

    /// Makes the compliant solve's normal force `form` for this step
    /// (energy-consistent: from the step's starting displacement `r` and
    /// the excesses `excess`).
    fn normal_form(
        &mut self,
        form: NormalForm,
        contact: &ContactSurface,
        (r, excess): (&[f64], &[f64]),
    ) {
        if let Some(solve) = self.compliant.as_deref_mut() {
            solve.set_form(form, contact, (r, excess));
        }
    }

    /// The energy-consistent form's excess at the step's end per
    /// compliant node, into `out`.
    fn normal_excess(&self, contact: &ContactSurface, out: &mut [f64]) {
        if let Some(solve) = self.compliant.as_deref() {
            solve.excess_after(contact, out);
        }
    }

    /// Newton iterations of a compliant foundation's solves so far.
    pub(crate) fn normal_iterations(&self) -> u64 {
        self.compliant.as_deref().map_or(0, |s| s.newton)
    }

    /// Continues that count from a checkpoint's.
    pub(crate) fn set_normal_iterations(&mut self, count: u64) {
        if let Some(s) = self.compliant.as_deref_mut() {
            s.newton = count;
        }
    }

    /// Numeric factorizations so far.
    pub(crate) fn factorizations(&self) -> u64 {
        match &self.solver {
            Solver::Schur(op) => op.factorizations,
            Solver::Direct(op) => op.factorizations,
        }
    }

    /// Continues the count of factorizations from a checkpoint's.
    pub(crate) fn set_factorizations(&mut self, count: u64) {
        match &mut self.solver {
            Solver::Schur(op) => op.factorizations = count,
            Solver::Direct(op) => op.factorizations = count,
        }
    }

    /// Values stored per factor of A₀ (Schur path; 0 otherwise).
    pub(crate) fn factor_len(&self) -> usize {
        match &self.solver {
            Solver::Schur(op) => op.factor_len(),
            Solver::Direct(_) => 0,
        }
    }

    /// (values of W the step uses, values of the factor on the contact
    /// DOFs' paths to the root).
    pub(crate) fn paths_len(&self) -> (usize, usize) {
        match &self.solver {
            Solver::Schur(op) => op.paths_len(),
            Solver::Direct(_) => (0, 0),
        }
    }
}

impl Newmark {
    /// The predictor's and R̂_K's coefficients for a step of `dt`: r_pred =
    /// r + c1 ṙ + c2 r̈ and M's vector cv ṙ + ca r̈.
    fn coefficients(&self, dt: f64) -> [f64; 4] {
        let (beta, gamma) = (self.beta, self.gamma);
        [
            dt * (1.0 - beta / gamma),
            0.5 * dt * dt * (1.0 - 2.0 * beta / gamma),
            1.0 / (gamma * dt),
            1.0 / gamma - 1.0,
        ]
    }

    /// The predictor of a step of `dt` from the state into `state.r_new`,
    /// and M's vector of R̂_K into `tmp`, in one pass.
    fn predict(&mut self, state: &mut State, dt: f64) {
        let [c1, c2, cv, ca] = self.coefficients(dt);
        for (((rn, t), r), (v, a)) in state
            .r_new
            .iter_mut()
            .zip(self.tmp.iter_mut())
            .zip(&state.r)
            .zip(state.v.iter().zip(&state.a))
        {
            *rn = r + c1 * v + c2 * a;
            *t = cv * v + ca * a;
        }
    }

    /// (r_Kᵀ K r_K, ṙ_Kᵀ M ṙ_K) of the committed state; where a step
    /// follows (`more`), K and M are read once for these and for the next
    /// step's products as well, formed for a step of this `dt` (its
    /// predictor into `state.r_new`, which the commit freed).
    fn energy_pass(&mut self, state: &mut State, dt: f64, more: bool) -> (f64, f64) {
        if !more {
            return self.km.two_forms(&state.r, &state.v, &mut self.partials);
        }
        self.predict(state, dt);
        let [kr, mt] = &mut self.next_products;
        let forms = self.km.two_forms_and_products(
            [&state.r, &state.r_new],
            [&state.v, &self.tmp],
            [kr, mt],
            &mut self.partials,
        );
        self.predicted = Some((state.steps, dt.to_bits()));
        forms
    }

    /// The damping's dissipation over the step, Δt ṙ̄ᵀCṙ̄ with ṙ̄ = ½(ṙ_K +
    /// ṙ_{K−1}) (before the commit): ½(Cṙ_K + Cṙ_{K−1})·½Δt(ṙ_K + ṙ_{K−1}),
    /// the friction's trapezoidal rule, exact for Newmark ¼, ½. 0 without
    /// damping (no pass over the vectors).
    fn damped(&mut self, settings: &Settings, state: &State, dt: f64) -> f64 {
        let c = settings.damping;
        if !c.is_on() {
            return 0.0;
        }
        for ((t, v), vn) in self.tmp.iter_mut().zip(&state.v).zip(&state.v_new) {
            *t = 0.5 * (v + vn);
        }
        let (vkv, vmv) = self.km.two_forms(&self.tmp, &self.tmp, &mut self.partials);
        dt * (c.alpha * vmv + c.beta * vkv)
    }
}

impl Stepper for Newmark {
    fn step(&mut self, run: &mut Run, state: &mut State) -> Result<StepInfo, TimeError> {
        let settings = &run.settings;
        let (dt, t_new) = state.next_step(settings);
        let step = state.steps + 1;
        let (beta, gamma) = (self.beta, self.gamma);
        run.loads.at(t_new, &mut state.load_new);
        // Predictor: r_K = r_pred + (β/γ)Δt ṙ_K; and for R̂_K = R_K − K
        // r_pred + M[ṙ/(γΔt) + (1/γ − 1) r̈] the bracket, in one pass.
        let [_, _, cv, ca] = self.coefficients(dt);
        if self.predicted.take() == Some((state.steps, dt.to_bits())) {
            // The last step's energy pass formed the products (and the
            // predictor in r_new) for this Δt, with these operations.
            let [kr, mt] = &self.next_products;
            for (((b, l), kr), mt) in self.b.iter_mut().zip(&state.load_new).zip(kr).zip(mt) {
                *b = l - kr + mt;
            }
        } else {
            self.predict(state, dt);
            self.km
                .load_minus_k_plus_m(&state.load_new, &state.r_new, &self.tmp, &mut self.b);
        }
        let energy_consistent = match (&self.algorithmic, &run.contact) {
            (Some(_), Some(c)) => {
                AlgorithmicNormal::correct_rhs(c, &state.normal_excess, ca, &mut self.b);
                Some(c)
            }
            _ => None,
        };
        state.classes_new.copy_from_slice(&state.classes);
        self.friction.lag_mu(run, &state.v);
        let mut v_new = std::mem::take(&mut state.v_new);
        let c3 = beta / gamma * dt;
        if let Some(c) = run.contact.as_ref().filter(|c| c.is_compliant()) {
            self.friction.predict_normal(c, &state.r_new, &state.v, c3);
            if energy_consistent.is_some() {
                let form = NormalForm::EnergyConsistent;
                self.friction
                    .normal_form(form, c, (&state.r, &state.normal_excess));
            }
        }
        // Rayleigh damping joins A₀; R̂_K is unchanged, as ṙ_K is the
        // unknown.
        let operator =
            Operator::newmark((beta, gamma), dt, run.settings.damping, (&self.k, &self.m));
        let result = self.friction.velocity(
            run,
            operator,
            &self.b,
            (&mut state.classes_new, &mut v_new),
            (step, t_new),
        );
        state.v_new = v_new;
        let iterations = result?;
        if let Some(c) = energy_consistent {
            self.friction.normal_excess(c, &mut state.normal_excess_new);
        }

        // Corrector and r̈_K, with the finiteness check (a flag, not a
        // branch per entry).
        let ka = (1.0 - gamma) / gamma;
        let mut finite = true;
        for ((r, v_new), (a_new, (v, a))) in state
            .r_new
            .iter_mut()
            .zip(&state.v_new)
            .zip(state.a_new.iter_mut().zip(state.v.iter().zip(&state.a)))
        {
            *r += c3 * v_new;
            finite &= r.is_finite() & v_new.is_finite();
            *a_new = (v_new - v) * cv - ka * a;
        }
        if !finite {
            return Err(TimeError::NonFinite {
                step,
                t: t_new,
                hint: String::new(),
            });
        }
        if let (Some(alg), Some(c)) = (&mut self.algorithmic, energy_consistent) {
            let excess = (ca, &state.normal_excess[..], &state.normal_excess_new[..]);
            alg.correct_acceleration(c, &self.m, excess, &mut state.a_new)
                .map_err(|source| TimeError::Solve {
                    step,
                    t: t_new,
                    source,
                })?;
        }
        // The compliant nodes' bounds at r_K for the ledger's friction
        // forces, and the foundation's stored energy.
        let foundation_stored = self.friction.comply(run.contact.as_mut(), &state.r_new);
        let settings = &run.settings;
        let (work, load_dot) = state.load_work();
        let ((dissipated, foundation), stick_events) = match self.friction.surface(run) {
            Some(c) => {
                state.friction_passes += 1;
                friction_ledger(c, state, dt)
            }
            None => ((0.0, 0.0), 0),
        };
        let damped = self.damped(settings, state, dt);
        state.commit(dt, t_new, iterations);
        let (rkr, vmv) = self.energy_pass(state, dt, t_new < settings.t_end);
        let energies = StepEnergies {
            kinetic: 0.5 * vmv,
            strain: 0.5 * rkr,
            work,
            dissipated,
            damped,
            foundation,
            foundation_stored,
            load_dot,
        };
        Ok(state.close_step(energies, settings, dt, iterations, stick_events))
    }

    fn state_replaced(&mut self) {
        self.predicted = None;
    }

    fn is_explicit(&self) -> bool {
        false
    }

    fn mass_kind(&self) -> Option<MassKind> {
        Some(self.mass_kind)
    }

    fn solve_mass(&self, x: &mut [f64], fill_order: &FillOrder) -> Result<(), TimeError> {
        let mass = match &self.lumped {
            Some(m) => Mass::Lumped(m),
            None => Mass::Consistent(&self.m),
        };
        mass.solve_in_place(x, fill_order, self.friction.analysis())
            .map(drop)
    }

    fn stiffness_product(&self) -> &'static str {
        "paired node blocks"
    }

    fn implicit(&self) -> Option<&ImplicitFriction> {
        Some(&self.friction)
    }

    fn implicit_mut(&mut self) -> Option<&mut ImplicitFriction> {
        Some(&mut self.friction)
    }
}

/// Friction dissipation of the step and the number of nodes that went
/// from slip to stick, from the new velocity; fills `forces_new`
/// (`ContactSurface::step_dissipation`).
pub(crate) fn friction_ledger(
    c: &ContactSurface,
    state: &mut State,
    dt: f64,
) -> ((f64, f64), usize) {
    let work = c.step_dissipation(
        &state.v_new,
        &state.v,
        dt,
        &state.forces,
        &mut state.forces_new,
    );
    (work, stick_events(&state.classes, &state.classes_new))
}
