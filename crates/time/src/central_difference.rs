//! Central difference (β = 0, γ = ½) with the lumped mass: every step
//! explicit, the friction solved node by node in closed form (METHOD.md
//! §4), K·x by stencil types where the mesh has them; stable below
//! Δt_crit = 2/ω_max.

use stickslip_contact::{iterate, ContactSurface, DiagonalStep, Foundation, SlipState};
use stickslip_linalg::chunks;
use stickslip_linalg::{csr, Analysis, FillOrder, Formed, Product};

use stickslip_fem::SetupTimes;

use crate::dynamics::{Dynamics, Loads};
use crate::initial::{initial_state, Mass, Statics, SINGLE_MIN};
use crate::nodal::NodalFriction;
use crate::settings::{ExplicitFriction, MassKind, Settings, TimeError, MAX_STABLE_STEPS};
use crate::stability::{critical_step_with, gershgorin_bound};
use crate::state::{State, StepEnergies, StepInfo};
use crate::stepper::{Run, Stepper};
use crate::sweep::{loads_at, predict, sweep, Damped, Partials, SparseLoads, StepData, Sums};

/// γ of central difference.
const GAMMA: f64 = 0.5;

/// The explicit stepper.
pub(crate) struct CentralDifference {
    /// K as the step reads it.
    product: Product,
    /// An empty product standing in for `product` while a step reads it.
    idle: Option<Product>,
    mass: Vec<f64>,
    dt_crit: f64,
    /// The constant load and the loads on their nonzero rows.
    sparse_loads: SparseLoads,
    /// θ_l(t) of each load for the step being taken.
    thetas: Vec<f64>,
    partials: Partials,
    /// The closed-form nodal friction's constants for the last Δt.
    nodal: NodalFriction,
    /// (DOF, ṙ_K) at the contact DOFs, sorted by DOF: the friction's
    /// velocities handed to the sweep.
    friction: Vec<(usize, f64)>,
    /// Per contact node and component, its entry of `friction`.
    friction_slots: Vec<[Option<usize>; 2]>,
    /// The iterated friction's R̂_K and diagonal ([`ExplicitFriction::Iterate`]).
    b: Vec<f64>,
    diagonal: Vec<f64>,
    iter_scratch: Vec<SlipState>,
    /// The predictor the sweep wrote for the step after it.
    r_next: Vec<f64>,
    /// (steps, Δt bits) of the state `r_next` went into `r_new` for: the
    /// next step, if of that Δt, skips [`predict`].
    predicted: Option<(u64, u64)>,
    /// With Rayleigh damping: K r at the current state (for the stiffness
    /// part's half-step velocity) and K r_K the sweep writes; empty
    /// without damping.
    ku: Vec<f64>,
    ku_new: Vec<f64>,
    /// `ku` is not K r of the current state (before the first step, after
    /// a restore): the next step forms it first.
    ku_stale: bool,
    /// A compliant foundation's nodal forces at r_K, per contact DOF in the
    /// closed form's order (empty without one), and what else it found.
    normal: Vec<f64>,
    foundation: Foundation,
}

/// Builds the stepper and the initial state. The critical step is
/// estimated on the step's own product before the preload's factorization,
/// so that a Δt above it is refused before any; where no Δt can be refused
/// ([`beside_the_preload`]), during it, except where the dissection's
/// halves are known (the preload by halves takes both threads).
///
/// # Errors
/// Δt above the critical step (unless allowed), or a singular static
/// problem.
pub(crate) fn start(
    dynamics: Dynamics,
    contact: Option<&ContactSurface>,
    loads: &Loads,
    settings: &Settings,
    times: &mut SetupTimes,
) -> Result<(Box<dyn Stepper>, State), TimeError> {
    let Dynamics {
        stiffness: k,
        lumped_mass: mass,
        fill_order,
        stencils,
        rigid_modes,
        ..
    } = dynamics;
    // The step's own product, made before the critical step so that
    // Lanczos streams the same (and the smaller) matrix the steps do.
    let formed = times.time("operators", || Product::without_csr(&k, stencils));
    // A compliant foundation with m_n = 1 is a spring w c_n ννᵀ at every
    // node in contact; with all of them in contact ω_max is largest
    // (a positive semi-definite term raises every eigenvalue), so that
    // bound holds whatever the contact does. Stiffer-with-depth nodes
    // (m_n > 1) are checked step by step (`contact_stable`).
    // Gershgorin's bound on K's ω_max² caps the estimate and decides what
    // no Δt can be refused for, made once by whichever asks first; a
    // compliant foundation's springs are not in it, so there is none with
    // them.
    let springs = contact.is_some_and(ContactSurface::is_compliant);
    let k_bound = std::sync::OnceLock::new();
    let bound = || (!springs).then(|| *k_bound.get_or_init(|| gershgorin_bound(&k, &mass)));
    let critical = || {
        critical_step_with(
            |x, y| {
                match &formed {
                    Some(p) => p.spmv(x, y),
                    None => csr::spmv(&k, x, y),
                }
                if let Some(c) = contact.filter(|c| c.is_compliant()) {
                    c.add_linear_stiffness(x, y);
                }
            },
            &mass,
            bound(),
        )
    };
    let initial = |times: &mut SetupTimes, analyzed| {
        initial_state(
            &k,
            Mass::Lumped(&mass),
            Statics {
                fill_order: &fill_order,
                modes: &rigid_modes,
                times,
                single_factor: true,
                analysis: None,
            },
            contact,
            loads,
            settings,
            analyzed,
        )
    };
    // A preload factorized by halves keeps both threads busy (`split.rs`):
    // the estimate is made before it, on both too. Where the halves then
    // prove unusable (`SplitSingle::analyze`, or their f32 factor), only
    // the overlap is lost.
    let split = || {
        !springs && mass.len() >= SINGLE_MIN && {
            fill_order.keep_dissection();
            fill_order.halves().is_some()
        }
    };
    let beside = beside_the_preload(bound, split, mass.len(), &rigid_modes, loads, settings);
    let (dt_crit, state) = match beside {
        Beside::Nothing => {
            let dt_crit = times.time("critical step", critical);
            let dt_crit = damped_critical_step(dt_crit, settings)?;
            (dt_crit, initial(times, None)?)
        }
        beside => {
            // Lanczos on its own thread while this one analyses K for the
            // preload, or (where no Δt can be refused) forms its whole
            // initial state; they share only K. The critical step's part
            // is the wall time it adds after that work, so that the parts
            // still add up to the setup.
            fill_order.keep_dissection();
            let (done, (dt_crit, added)) = std::thread::scope(|s| {
                let lanczos = s.spawn(critical);
                let done = if beside == Beside::Preload {
                    Done::State(Box::new(initial(times, None)))
                } else {
                    // Not by halves here (`split`): K's whole analysis.
                    match times.time("preload ordering", || Analysis::of(&k, &fill_order)) {
                        Ok(analysis) => Done::Analysis(Box::new(analysis)),
                        Err(e) => Done::State(Box::new(Err(TimeError::Static(e)))),
                    }
                };
                let waited = std::time::Instant::now();
                let dt_crit = lanczos.join().expect("the critical step's thread");
                (done, (dt_crit, waited.elapsed().as_secs_f64()))
            });
            times.add("critical step", added);
            let dt_crit = damped_critical_step(dt_crit, settings)?;
            let state = match done {
                Done::State(state) => (*state)?,
                Done::Analysis(analysis) => initial(times, Some(*analysis))?,
            };
            (dt_crit, state)
        }
    };
    let product = formed.unwrap_or(Product::Csr(k));
    let n = mass.len();
    let vectors: Vec<&[f64]> = loads.loads.iter().map(|l| &l.vector[..]).collect();
    let (mut friction, mut friction_slots) = (Vec::new(), Vec::new());
    if let Some(c) = contact {
        let mut dofs: Vec<usize> = c.nodes.iter().flat_map(|n| n.dofs).flatten().collect();
        dofs.sort_unstable();
        dofs.dedup();
        friction_slots = c
            .nodes
            .iter()
            .map(|n| {
                n.dofs
                    .map(|d| d.map(|i| dofs.binary_search(&i).expect("listed")))
            })
            .collect();
        friction = dofs.into_iter().map(|i| (i, 0.0)).collect();
    }
    let iterated = settings.explicit_friction == ExplicitFriction::Iterate;
    let damped = settings.damping.is_on();
    let n_c = contact.map_or(0, |c| c.len());
    let stepper = CentralDifference {
        product,
        idle: Some(Product::default()),
        dt_crit,
        sparse_loads: SparseLoads::new(&loads.constant, &vectors),
        thetas: vec![0.0; loads.loads.len()],
        partials: chunks::partials(n),
        nodal: NodalFriction::default(),
        friction,
        friction_slots,
        b: if iterated { vec![0.0; n] } else { Vec::new() },
        diagonal: if iterated { vec![0.0; n] } else { Vec::new() },
        iter_scratch: vec![SlipState::Stuck; n_c],
        mass,
        r_next: vec![0.0; n],
        predicted: None,
        ku: if damped { vec![0.0; n] } else { Vec::new() },
        ku_new: if damped { vec![0.0; n] } else { Vec::new() },
        ku_stale: true,
        normal: Vec::new(),
        foundation: Foundation::default(),
    };
    Ok((Box::new(stepper), state))
}

impl CentralDifference {
    /// The friction's velocities at the contact DOFs into `friction`:
    /// node by node in closed form (from R̂_K there), or by the iteration
    /// of §5 on the whole diagonal system (the reference; it leaves its
    /// classes in `classes_new` and its velocities in `v_new`). Returns the
    /// iterations.
    fn friction_velocities(
        &mut self,
        k: &Formed,
        contact: &ContactSurface,
        data: &StepData,
        settings: &Settings,
        (classes, classes_new, v_new): (&[SlipState], &mut [SlipState], &mut [f64]),
        (step, t): (u64, f64),
    ) -> Result<usize, TimeError> {
        self.nodal.prepare(contact, data.mass, data.dscale);
        if settings.explicit_friction == ExplicitFriction::ClosedForm {
            self.nodal.form_products(k);
            let (ku, friction, slots) = (
                self.nodal.products(),
                &mut self.friction,
                &self.friction_slots,
            );
            let mut out = |j: usize, c: usize, _, v| {
                if let Some(slot) = slots[j][c] {
                    friction[slot].1 = v;
                }
            };
            // The foundation's force at the known r_K joins R̂_K (METHOD.md
            // §10); without one R̂_K keeps its bits.
            let closed_form = self.nodal.closed_form();
            if self.normal.is_empty() {
                closed_form.velocities(|i, k| data.rhs(i, ku[k]), &mut out);
            } else {
                let normal = &self.normal;
                closed_form.velocities(|i, k| data.rhs(i, ku[k]) + normal[k], &mut out);
            }
            return Ok(1);
        }
        k.spmv(&mut self.b);
        for (i, b) in self.b.iter_mut().enumerate() {
            *b = data.rhs(i, *b);
        }
        let dofs = contact.nodes.iter().flat_map(|n| n.dofs).flatten();
        for (i, f) in dofs.zip(&self.normal) {
            self.b[i] += f;
        }
        for (d, m) in self.diagonal.iter_mut().zip(data.mass) {
            *d = m * data.dscale;
        }
        let mut system = DiagonalStep {
            diagonal: &self.diagonal,
            b: &self.b,
        };
        classes_new.copy_from_slice(classes);
        let report = iterate(
            contact,
            &mut system,
            classes_new,
            &mut self.iter_scratch,
            v_new,
            settings.iteration,
        )
        .map_err(|f| {
            TimeError::from_iteration(f, (step, t, settings.iteration.remark_4_2), |never| {
                match never {}
            })
        })?;
        for (i, vi) in self.friction.iter_mut() {
            *vi = v_new[*i];
        }
        Ok(report.iterations)
    }

    /// The step's velocities, accelerations, sums and the next step's
    /// predictor from the predictor in `state.r_new` (the outputs apart
    /// from `state`, which is read).
    fn velocities(
        &mut self,
        run: &Run,
        state: &State,
        dt: f64,
        at: (u64, f64),
        outputs: Outputs,
    ) -> Result<(Sums, usize), TimeError> {
        // The mass and the load rows are read by the step's data while the
        // friction's parts are written: moved out for the step.
        let mass = std::mem::take(&mut self.mass);
        let loads = std::mem::take(&mut self.sparse_loads);
        let ku = std::mem::take(&mut self.ku);
        // K r_K, formed before the rows are read (whole where the product
        // needs it).
        // The product moves out for the step, an empty one (made once,
        // so that a step allocates nothing) in its place.
        let empty = self.idle.take().unwrap_or_default();
        let mut product = std::mem::replace(&mut self.product, empty);
        let formed = product.form(&state.r_new);
        let result = self.velocities_with(
            run,
            state,
            (&formed, &mass, loads.rows(), &ku),
            dt,
            at,
            outputs,
        );
        (self.mass, self.sparse_loads, self.ku) = (mass, loads, ku);
        self.idle = Some(std::mem::replace(&mut self.product, product));
        result
    }

    fn velocities_with(
        &mut self,
        run: &Run,
        state: &State,
        (k, mass, load_rows, ku): (&Formed, &[f64], &[usize], &[f64]),
        dt: f64,
        at: (u64, f64),
        (v_new, a_new, r_next, classes_new): Outputs,
    ) -> Result<(Sums, usize), TimeError> {
        let scale = 1.0 / (GAMMA * dt);
        // Rayleigh damping (METHOD.md §8): αM centred, exact with the
        // lumped mass (M/(γΔt) + αM is diagonal); βK on the half-step
        // velocity (r_K − r_{K−1})/Δt, explicit.
        let c = run.settings.damping;
        let (dscale, damped) = if c.is_on() {
            (
                scale + c.alpha,
                Some(Damped {
                    ku_prev: ku,
                    bs: c.beta / dt,
                }),
            )
        } else {
            (scale, None)
        };
        let data = StepData {
            load_new: &state.load_new,
            load_rows,
            mass,
            r_new: &state.r_new,
            v: &state.v,
            a: &state.a,
            cv: scale,
            ca: 1.0 / GAMMA - 1.0,
            scale,
            dscale,
            damped,
            ratio: (1.0 - GAMMA) / GAMMA,
            next: [dt, 0.5 * dt * dt],
        };
        let mut iterations = 1;
        if let Some(contact) = &run.contact {
            iterations = self.friction_velocities(
                k,
                contact,
                &data,
                &run.settings,
                (&state.classes, classes_new, v_new),
                at,
            )?;
        }
        let ku_new = (!self.ku_new.is_empty()).then_some(&mut self.ku_new[..]);
        let sums = sweep(
            k,
            &data,
            &self.friction,
            [v_new, a_new, r_next],
            ku_new,
            &mut self.partials,
        );
        Ok((sums, iterations))
    }
}

/// ṙ_K, r̈_K, the next predictor and the classes a step writes.
type Outputs<'a> = (
    &'a mut [f64],
    &'a mut [f64],
    &'a mut [f64],
    &'a mut [SlipState],
);

impl Stepper for CentralDifference {
    fn step(&mut self, run: &mut Run, state: &mut State) -> Result<StepInfo, TimeError> {
        let settings = &run.settings;
        let (dt, t_new) = state.next_step(settings);
        let step = state.steps + 1;
        for (theta, l) in self.thetas.iter_mut().zip(&run.loads.loads) {
            *theta = l.history.value(t_new);
        }
        if self.thetas.iter().any(|t| !t.is_finite()) {
            return Err(self.non_finite(step, t_new));
        }
        // β = 0: r_K = r + Δt ṙ + ½Δt² r̈ is final (no corrector); the
        // last sweep wrote it if this step's Δt is the last one's.
        if self.predicted != Some((state.steps, dt.to_bits())) {
            predict(
                [&state.r, &state.v, &state.a],
                [dt, 0.5 * dt * dt],
                &mut state.r_new,
            );
        }
        self.predicted = None;
        if let Some(c) = run.contact.as_mut().filter(|c| c.is_compliant()) {
            self.foundation = c.comply(&state.r_new, &self.mass, &mut self.normal);
            if !run.settings.allow_unstable {
                self.contact_stable(c, dt, (step, t_new))?;
            }
        }
        let run = &*run;
        if self.ku_stale && !self.ku.is_empty() {
            self.product.spmv(&state.r, &mut self.ku);
        }
        self.ku_stale = false;
        let (work, load_dot) = loads_at(
            &self.sparse_loads,
            &self.thetas,
            [&state.r, &state.r_new],
            &state.load,
            &mut state.load_new,
        );
        let mut v_new = std::mem::take(&mut state.v_new);
        let mut a_new = std::mem::take(&mut state.a_new);
        let mut r_next = std::mem::take(&mut self.r_next);
        let mut classes_new = std::mem::take(&mut state.classes_new);
        let result = self.velocities(
            run,
            state,
            dt,
            (step, t_new),
            (&mut v_new, &mut a_new, &mut r_next, &mut classes_new),
        );
        (state.v_new, state.a_new, state.classes_new) = (v_new, a_new, classes_new);
        self.r_next = r_next;
        let (sums, iterations) = result?;
        if !sums.finite {
            return Err(self.non_finite(step, t_new));
        }
        let (dissipated, foundation, stick_events) = if run.contact.is_some() {
            state.friction_passes += 1;
            self.nodal.closed_form().ledger(
                &state.v_new,
                &state.v,
                dt,
                &state.classes,
                &mut state.classes_new,
                &state.forces,
                &mut state.forces_new,
            )
        } else {
            (0.0, 0.0, 0)
        };
        state.commit(dt, t_new, iterations);
        // r_new now holds r_{K−1}, free: the next predictor goes there.
        std::mem::swap(&mut state.r_new, &mut self.r_next);
        std::mem::swap(&mut self.ku, &mut self.ku_new);
        let c = settings.damping;
        let damped = c.alpha * dt * sums.damped[0] + c.beta * sums.damped[1];
        self.predicted = Some((state.steps, dt.to_bits()));
        let energies = StepEnergies {
            kinetic: sums.kinetic,
            strain: sums.strain,
            work,
            dissipated,
            damped,
            foundation,
            foundation_stored: self.foundation.stored,
            load_dot,
        };
        Ok(state.close_step(energies, settings, dt, iterations, stick_events))
    }

    fn state_replaced(&mut self) {
        self.predicted = None;
        self.ku_stale = true;
    }

    fn dt_crit(&self) -> Option<f64> {
        Some(self.dt_crit)
    }

    fn is_explicit(&self) -> bool {
        true
    }

    fn solve_mass(&self, x: &mut [f64], fill_order: &FillOrder) -> Result<(), TimeError> {
        Mass::Lumped(&self.mass)
            .solve_in_place(x, fill_order, None)
            .map(drop)
    }

    fn mass_kind(&self) -> Option<MassKind> {
        Some(MassKind::Lumped)
    }

    fn stiffness_product(&self) -> &'static str {
        self.product.name()
    }

    fn stencil_types(&self) -> Option<usize> {
        match &self.product {
            Product::Stencils(s) => Some(s.types()),
            Product::Symmetric(_) | Product::Csr(_) => None,
        }
    }

    fn matrix_bytes(&self) -> usize {
        self.product.bytes()
    }

    /// K, and 7 vector streams: the sweep reads r_K, m, ṙ, r̈ and writes
    /// ṙ_K, r̈_K and the next predictor (a step of the last one's Δt skips
    /// the predictor's pass); and the loads at their rows.
    fn bytes_per_step(&self) -> usize {
        // A damped sweep also reads K r_{K−1} and R_K and writes K r_K.
        let streams = if self.ku.is_empty() { 7 } else { 10 };
        self.product.bytes() + 8 * streams * self.mass.len() + self.sparse_loads.bytes()
    }
}

/// Free DOFs from which the critical step's Lanczos runs beside the
/// preload: below, a thread costs more than it saves.
const BESIDE_MIN: usize = 100_000;

/// What the critical step's Lanczos runs beside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Beside {
    /// Nothing: it runs first.
    Nothing,
    /// The preload's analysis (its ordering and symbolic factor): a Δt
    /// above the critical step is still refused before any factorization.
    Analysis,
    /// The whole initial state, its factorization included.
    Preload,
}

/// The work the critical step's thread has run beside.
enum Done {
    State(Box<Result<State, TimeError>>),
    Analysis(Box<Analysis>),
}

/// What the critical step may be estimated beside: for a large model
/// (from [`BESIDE_MIN`] free DOFs) whose initial state factorizes K
/// (loads before t = 0, no free rigid motion, a fresh start) on one
/// thread (not by the dissection's halves: `split`), the
/// preload's analysis, or its whole initial state where no estimate can
/// refuse the run's Δt (allowed above it, or within Gershgorin's bound on
/// ω_max, [`gershgorin_bound`]), so that no factorization is spent on a
/// run refused for its Δt. That bound (`bound`) is K's alone: with a
/// compliant foundation, whose springs the estimate adds, there is none
/// and any Δt may be refused.
fn beside_the_preload(
    bound: impl FnOnce() -> Option<f64>,
    split: impl FnOnce() -> bool,
    n: usize,
    modes: &[stickslip_fem::RigidMode],
    loads: &Loads,
    settings: &Settings,
) -> Beside {
    use crate::settings::InitialState;
    let preload = !settings.restoring
        && settings.initial_state != InitialState::Rest
        && modes.is_empty()
        && loads.before_start().iter().any(|&x| x != 0.0);
    if !preload || n < BESIDE_MIN || split() {
        return Beside::Nothing;
    }
    let refusable = !settings.allow_unstable
        && bound()
            .is_none_or(|b| !(b > 0.0 && damped_critical_step(2.0 / b.sqrt(), settings).is_ok()));
    if refusable {
        Beside::Analysis
    } else {
        Beside::Preload
    }
}

/// The critical step with Rayleigh damping from the undamped one,
/// 2/ω_max: Δt_crit = (2/ω_max)(√(1+ξ²) − ξ), ξ = βω_max/2 (METHOD.md §8).
/// The mass part, centred, does not lower it: for a mode ω the step's
/// characteristic polynomial (1 + αΔt/2)z² − (2 − Ω² − 2ξΩ)z + 1 − αΔt/2
/// − 2ξΩ, Ω = ωΔt, has its root at z = −1 where Ω² + 4ξΩ = 4, whatever
/// α; the bound falls with ω, so ω_max sets it. Zero modes (a floating
/// part) bound nothing.
///
/// # Errors
/// Δt above it (unless allowed), or no usable stable step at all.
fn damped_critical_step(undamped: f64, settings: &Settings) -> Result<f64, TimeError> {
    let beta = settings.damping.beta;
    if beta == 0.0 {
        if settings.dt > undamped && !settings.allow_unstable {
            return Err(TimeError::Unstable {
                dt: settings.dt,
                dt_crit: undamped,
            });
        }
        return Ok(undamped);
    }
    let omega = 2.0 / undamped;
    let xi = 0.5 * beta * omega;
    // (√(1+ξ²) − ξ) = 1/(√(1+ξ²) + ξ), without the cancellation.
    let dt_crit = undamped / ((1.0 + xi * xi).sqrt() + xi);
    let steps = settings.t_end / dt_crit;
    let usable = dt_crit.is_normal() && steps <= MAX_STABLE_STEPS;
    if (settings.dt > dt_crit || !usable) && !settings.allow_unstable {
        return Err(TimeError::UnstableDamped {
            dt: settings.dt,
            dt_crit,
            undamped,
            omega,
            beta,
            xi,
            no_step: if usable {
                String::new()
            } else {
                format!(
                    ", so small that a stable run to t_end would take {steps:.1e} steps: central \
                     difference has no usable stable step"
                )
            },
        });
    }
    Ok(dt_crit)
}

impl CentralDifference {
    /// Stops a step whose foundation is stiffer than its Δt allows: m_n >
    /// 1 makes the stiffness w c_n m_n δ^{m_n−1} grow with the approach,
    /// and by Weyl's inequality ω_max² ≤ (2/Δt_crit)² + max_J k_J νᵀM_J⁻¹ν
    /// (Δt_crit with the m_n = 1 springs in), so the step is stable while
    /// that stays ≤ (2/Δt)². Nothing to check with m_n = 1 only.
    fn contact_stable(
        &self,
        contact: &ContactSurface,
        dt: f64,
        (step, t): (u64, f64),
    ) -> Result<(), TimeError> {
        let f = &self.foundation;
        if !contact.has_nonlinear_compliance() || f.stiffness_over_mass == 0.0 {
            return Ok(());
        }
        let omega2 = (2.0 / self.dt_crit).powi(2) + f.stiffness_over_mass;
        let limit = 2.0 / omega2.sqrt();
        if dt <= limit {
            return Ok(());
        }
        Err(TimeError::Settings(format!(
            "step {step} (t = {t:.6e}): the foundation's contact stiffness c_n m_n δ^(m_n−1) grows \
             with the approach δ for m_n > 1, and at mesh node {} (approach up to {:.4e}) it may \
             make time.dt = {dt:e} unstable: the critical step with it is bounded below by \
             {limit:.4e} (a bound, not the limit itself); reduce time.dt below that, lower cn, \
             or set time.allow_unstable = true to run anyway",
            contact.nodes[f.stiffest].node, f.deepest
        )))
    }

    /// The step's NaN/infinity error, with the critical step as advice.
    fn non_finite(&self, step: u64, t: f64) -> TimeError {
        TimeError::NonFinite {
            step,
            t,
            hint: format!(" below the critical step Δt_crit = {:.4e}", self.dt_crit),
        }
    }
}
