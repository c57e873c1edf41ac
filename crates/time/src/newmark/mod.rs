//! Newmark (β, γ) in the paper's velocity form (METHOD.md §4): ṙ_K the
//! only unknown of [(β/γ)ΔtK + M/(γΔt) + C_K] ṙ_K = R̂_K − F_K, with the
//! stick/slip iteration of §5 on the friction. Two ways to solve a step:
//! the Schur complement on the contact DOFs with A₀ factorized once per Δt
//! (`schur.rs`, the default), or A₀ + C refactorized per stuck set
//! (`direct.rs`, the reference).

mod direct;
mod schur;

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{iterate, stick_events, ContactSurface, SlipState};
use stickslip_linalg::chunks;
use stickslip_linalg::csr::{load_minus_k_plus_m, same_pattern, two_forms};

use crate::dynamics::{Dynamics, Loads};
use crate::initial::{initial_state, Mass};
use crate::settings::{ImplicitSolver, MassKind, Settings, TimeError};
use crate::state::{State, StepEnergies, StepInfo};
use crate::stepper::{Run, Stepper};

use direct::{DirectOperator, ImplicitStep};
use schur::SchurOperator;

/// How a step solves.
enum Solver {
    Schur(SchurOperator),
    Direct(DirectOperator),
}

/// The Newmark stepper.
pub(crate) struct Newmark {
    beta: f64,
    gamma: f64,
    mass_kind: MassKind,
    k: CsrMatrix<f64>,
    /// The scheme's mass on K's pattern (the lumped one on the diagonal).
    m: CsrMatrix<f64>,
    solver: Solver,
    /// The Schur path's nodal tangential velocities.
    nodal_velocity: Vec<f64>,
    /// R̂_K, and M's vector of it.
    b: Vec<f64>,
    tmp: Vec<f64>,
    partials: Vec<[f64; 2]>,
    iter_scratch: Vec<SlipState>,
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
) -> Result<(Box<dyn Stepper>, State), TimeError> {
    let Dynamics {
        stiffness: k,
        consistent_mass,
        lumped_mass,
        fill_order,
        ..
    } = dynamics;
    let n = k.nrows();
    let m = match mass_kind {
        MassKind::Consistent => consistent_mass,
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
    let use_paths = match settings.implicit_solver {
        ImplicitSolver::SchurPaths => Some(true),
        ImplicitSolver::SchurReach => Some(false),
        _ => None,
    };
    let solver = match settings.implicit_solver {
        ImplicitSolver::Schur | ImplicitSolver::SchurPaths | ImplicitSolver::SchurReach => {
            Solver::Schur(
                SchurOperator::new(&k, &fill_order, contact, use_paths)
                    .map_err(TimeError::Static)?,
            )
        }
        ImplicitSolver::Direct => Solver::Direct(
            DirectOperator::new(&k, &fill_order, contact).map_err(TimeError::Static)?,
        ),
    };
    let mass = match mass_kind {
        MassKind::Consistent => Mass::Consistent(&m),
        MassKind::Lumped => Mass::Lumped(&lumped_mass),
    };
    let state = initial_state(&k, mass, &fill_order, contact, loads, settings)?;
    let n_c = contact.map_or(0, |c| c.len());
    let stepper = Newmark {
        beta,
        gamma,
        mass_kind,
        k,
        m,
        solver,
        nodal_velocity: vec![0.0; n_c],
        b: vec![0.0; n],
        tmp: vec![0.0; n],
        partials: chunks::partials(n),
        iter_scratch: vec![SlipState::Stuck; n_c],
    };
    Ok((Box::new(stepper), state))
}

impl Newmark {
    /// ṙ_K into `v_new` for R̂_K in `b`: the iteration of §5 with the
    /// step's solver. Returns the linear solves made.
    fn velocity(
        &mut self,
        run: &Run,
        dt: f64,
        (classes_new, v_new): (&mut [SlipState], &mut [f64]),
        (step, t): (u64, f64),
    ) -> Result<usize, TimeError> {
        let (c_k, c_m) = (self.beta / self.gamma * dt, 1.0 / (self.gamma * dt));
        let options = run.settings.iteration;
        let failed = |f| {
            TimeError::from_iteration(f, (step, t, options.remark_4_2), |source| {
                TimeError::Solve { step, t, source }
            })
        };
        match &mut self.solver {
            Solver::Schur(op) => {
                op.set_dt(dt, c_k, &self.k, c_m, &self.m)
                    .map_err(|source| TimeError::Solve { step, t, source })?;
                if run.contact.is_none() {
                    op.solve_plain(&self.b, v_new);
                    return Ok(1);
                }
                op.begin(&self.b);
                let mut reduced = op
                    .reduced
                    .take()
                    .expect("a contact surface has its nodal surface");
                if let Some(c) = run
                    .contact
                    .as_ref()
                    .filter(|c| c.revision != reduced.revision)
                {
                    reduced.set_bounds(|j| c.nodes[j].bound);
                    reduced.revision = c.revision;
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
                op.set_dt(dt, c_k, &self.k, c_m, &self.m);
                let Some(contact) = &run.contact else {
                    op.solve_plain(&self.b, v_new)
                        .map_err(|source| TimeError::Solve { step, t, source })?;
                    return Ok(1);
                };
                let mut system = ImplicitStep {
                    operator: op,
                    b: &self.b,
                };
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
}

impl Stepper for Newmark {
    fn step(&mut self, run: &Run, state: &mut State) -> Result<StepInfo, TimeError> {
        let settings = &run.settings;
        let (dt, t_new) = state.next_step(settings);
        let step = state.steps + 1;
        let (beta, gamma) = (self.beta, self.gamma);
        run.loads.at(t_new, &mut state.load_new);
        // Predictor: r_K = r_pred + (β/γ)Δt ṙ_K; and for R̂_K = R_K − K
        // r_pred + M[ṙ/(γΔt) + (1/γ − 1) r̈] the bracket, in one pass.
        let c1 = dt * (1.0 - beta / gamma);
        let c2 = 0.5 * dt * dt * (1.0 - 2.0 * beta / gamma);
        let cv = 1.0 / (gamma * dt);
        let ca = 1.0 / gamma - 1.0;
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
        load_minus_k_plus_m(
            &state.load_new,
            &self.k,
            &state.r_new,
            &self.m,
            &self.tmp,
            &mut self.b,
        );
        state.classes_new.copy_from_slice(&state.classes);
        let mut v_new = std::mem::take(&mut state.v_new);
        let result = self.velocity(run, dt, (&mut state.classes_new, &mut v_new), (step, t_new));
        state.v_new = v_new;
        let iterations = result?;

        // Corrector and r̈_K, with the finiteness check (a flag, not a
        // branch per entry).
        let c3 = beta / gamma * dt;
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
        let (mut work, mut load_dot) = (0.0, 0.0);
        for k in 0..state.r.len() {
            work += 0.5 * (state.load_new[k] + state.load[k]) * (state.r_new[k] - state.r[k]);
            load_dot += state.r_new[k] * state.load_new[k];
        }
        let (dissipated, stick_events) = match &run.contact {
            Some(c) => friction_ledger(c, state, dt),
            None => (0.0, 0),
        };
        state.commit(dt, t_new, iterations);
        let (rkr, vmv) = two_forms(&self.k, &state.r, &self.m, &state.v, &mut self.partials);
        let energies = StepEnergies {
            kinetic: 0.5 * vmv,
            strain: 0.5 * rkr,
            work,
            dissipated,
            load_dot,
        };
        Ok(state.close_step(energies, settings, dt, iterations, stick_events))
    }

    fn is_explicit(&self) -> bool {
        false
    }

    fn mass_kind(&self) -> MassKind {
        self.mass_kind
    }

    fn stiffness_product(&self) -> &'static str {
        "assembled CSR"
    }

    fn factorizations(&self) -> u64 {
        match &self.solver {
            Solver::Schur(op) => op.factorizations,
            Solver::Direct(op) => op.factorizations,
        }
    }

    fn set_factorizations(&mut self, count: u64) {
        match &mut self.solver {
            Solver::Schur(op) => op.factorizations = count,
            Solver::Direct(op) => op.factorizations = count,
        }
    }

    fn factor_len(&self) -> usize {
        match &self.solver {
            Solver::Schur(op) => op.factor_len(),
            Solver::Direct(_) => 0,
        }
    }

    fn paths_len(&self) -> (usize, usize) {
        match &self.solver {
            Solver::Schur(op) => op.paths_len(),
            Solver::Direct(_) => (0, 0),
        }
    }
}

/// Friction dissipation of the step and the number of nodes that went
/// from slip to stick, from the new velocity; fills `forces_new`
/// (`ContactSurface::step_dissipation`).
fn friction_ledger(c: &ContactSurface, state: &mut State, dt: f64) -> (f64, usize) {
    let dissipated = c.step_dissipation(
        &state.v_new,
        &state.v,
        dt,
        &state.forces,
        &mut state.forces_new,
    );
    (dissipated, stick_events(&state.classes, &state.classes_new))
}
