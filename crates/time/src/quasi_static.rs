//! Quasi-static load increments with regularized friction: no inertia,
//! each increment over [t_{K−1}, t_K] the static problem
//!
//!   K r_K + J((r_K − r_{K−1})/Δt) = R(t_K)
//!
//! (the paper's law on the increment's rate, as Campos, Oden and Kikuchi's
//! static analysis the paper's Fig. 5 compares with). With ṙ_K = (r_K −
//! r_{K−1})/Δt it is Newmark's velocity equation with M = 0 and β/γ = 1:
//! (Δt K + C) ṙ_K = R(t_K) − K r_{K−1} − F, solved by the same
//! [`ImplicitFriction`] (the iteration of §5 with Remark 4.2, the Schur
//! complement on the contact DOFs with Δt K factorized once per distinct
//! Δt). ε keeps its unit of a velocity: a stuck node creeps at most ε per
//! unit of time, so the time scale of the loading matters as in dynamics.
//!
//! The energy ledger (METHOD.md §6) with nothing kinetic: the trapezoid
//! rule for the loads' work, ½(R_K + R_{K−1})·Δr, and for friction's,
//! ½(J_K + J_{K−1})·Δr, so that ½r_KᵀKr_K − ½r_{K−1}ᵀKr_{K−1} = ½(r_K +
//! r_{K−1})ᵀK Δr closes the balance to round-off whenever the previous
//! increment was in equilibrium; hence R_0 is the load of the initial
//! static state (R(0⁻), Remark 4.1), and a load switched on at t = 0 enters
//! with the first increment.
//!
//! A compliant foundation (METHOD.md §10) joins each increment as in
//! Newmark's step (`newmark/compliance.rs`) with the predictor r_{K−1} and
//! c3 = Δt: its forces are those of the end point, f_n(r_K), so that
//! K r_K + f_n(r_K) + J(ṙ_K) = R(t_K) holds (statics in equilibrium, not a
//! lagged approach). The start is the compliant static preload
//! (`preload_compliance.rs`). The ledger gains the foundation's stored
//! energy Σ w_J c_n δ_J^{m_n+1}/(m_n+1), and the trapezoid rule books its
//! work: with the previous increment in equilibrium the balance moves by
//! ΔU_f + ½(F_K + F_{K−1})·Δr per increment (F the foundation's nodal
//! forces), zero for m_n = 1 while the nodes in contact stay in contact
//! (a linear spring); a node that enters or leaves contact adds, for m_n =
//! 1, ½ w c_n (δ_{K−1} g_K⁺ − δ_K g_{K−1}⁺) (g its gap), and m_n > 1 the trapezoid
//! rule's error on the spring's work, of third order in the increment of
//! the approach: the balance is not round-off there.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{stick_events, ContactSurface};
use stickslip_linalg::chunks;
use stickslip_linalg::csr::{quadratic_form, spmv};

use stickslip_fem::SetupTimes;

use crate::dynamics::{Dynamics, Loads};
use crate::initial::Mass;
use crate::newmark::{ImplicitFriction, Operator};
use crate::settings::{InitialState, MassKind, Settings, TimeError};
use crate::state::{State, StepEnergies, StepInfo};
use crate::stepper::{Run, Stepper};

/// The quasi-static stepper.
pub(crate) struct QuasiStatic {
    k: CsrMatrix<f64>,
    friction: ImplicitFriction,
    /// R(t_K) − K r_{K−1}.
    b: Vec<f64>,
    partials: Vec<[f64; 2]>,
}

/// Builds the stepper and the initial state: r₀ the frictionless static
/// state under R(0⁻) (Remark 4.1), ṙ₀ = r̈₀ = 0, no friction forces (the
/// ledger's J₀ = 0: K r₀ = R₀ holds without them) and every node stuck.
///
/// # Errors
/// A singular K (a rigid-body motion the supports leave free).
pub(crate) fn start(
    dynamics: Dynamics,
    contact: Option<&ContactSurface>,
    loads: &Loads,
    settings: &Settings,
    times: &mut SetupTimes,
) -> Result<(Box<dyn Stepper>, State), TimeError> {
    let Dynamics {
        stiffness: k,
        fill_order,
        rigid_modes,
        ..
    } = dynamics;
    if !rigid_modes.is_empty() {
        // Each increment factorizes Δt K, and nothing holds a free motion
        // without inertia (the case file refuses such a part earlier): a
        // compliant foundation's springs and friction's stuck damping act
        // on the Schur complement's nodal unknowns, not in that factor.
        let motions: Vec<&str> = rigid_modes.iter().map(|m| m.label.as_str()).collect();
        return Err(TimeError::Settings(format!(
            "quasi-static increments need supports that hold every rigid-body motion: each \
             factorizes dt K, which is singular along {} (neither friction nor a compliant \
             foundation enters that factor)",
            motions.join(", ")
        )));
    }
    let n = k.nrows();
    // Δt K has K's pattern: the preload's analysis is the increments'.
    // The first increment's operator, as the step forms it.
    let first = Operator::increment(State::first_dt(settings), &k);
    let (mut state, friction) = ImplicitFriction::with_initial_state(
        &k,
        Mass::Massless,
        (&fill_order, &rigid_modes, times),
        contact,
        loads,
        settings,
        Some(first),
    )?;
    if !settings.restoring {
        // The total stays the initial state's, strain − rᵀR(0) with R at
        // t = 0 itself (a load that switches on at t = 0 included, as the
        // dynamic schemes count it). The previous increment's load is the
        // one r₀ equilibrates: the loads before t = 0, or none for a start
        // at rest (r₀ = 0).
        state.load = match settings.initial_state {
            InitialState::Static => loads.before_start(),
            InitialState::Rest => vec![0.0; n],
        };
    }
    let stepper = QuasiStatic {
        k,
        friction,
        b: vec![0.0; n],
        partials: chunks::partials(n),
    };
    Ok((Box::new(stepper), state))
}

impl Stepper for QuasiStatic {
    fn step(&mut self, run: &mut Run, state: &mut State) -> Result<StepInfo, TimeError> {
        let settings = &run.settings;
        let (dt, t_new) = state.next_step(settings);
        let step = state.steps + 1;
        run.loads.at(t_new, &mut state.load_new);
        spmv(&self.k, &state.r, &mut self.b);
        for (b, l) in self.b.iter_mut().zip(&state.load_new) {
            *b = l - *b;
        }
        state.classes_new.copy_from_slice(&state.classes);
        self.friction.lag_mu(run, &state.v);
        // A compliant foundation at the end point: r_K = r_{K−1} + Δt ṙ_K.
        if let Some(c) = run.contact.as_ref().filter(|c| c.is_compliant()) {
            self.friction.predict_normal(c, &state.r, &state.v, dt);
        }
        let mut v_new = std::mem::take(&mut state.v_new);
        let result = self.friction.velocity(
            run,
            Operator::increment(dt, &self.k),
            &self.b,
            (&mut state.classes_new, &mut v_new),
            (step, t_new),
        );
        state.v_new = v_new;
        let iterations = result?;

        let mut finite = true;
        for (((r_new, r), v_new), a_new) in state
            .r_new
            .iter_mut()
            .zip(&state.r)
            .zip(&state.v_new)
            .zip(state.a_new.iter_mut())
        {
            *r_new = r + dt * v_new;
            finite &= r_new.is_finite() & v_new.is_finite();
            *a_new = 0.0;
        }
        if !finite {
            return Err(TimeError::NonFinite {
                step,
                t: t_new,
                hint: String::new(),
            });
        }
        // The compliant nodes' bounds at r_K for the ledger's friction
        // forces, and the foundation's stored energy.
        let foundation_stored = self.friction.comply(run.contact.as_mut(), &state.r_new);
        let settings = &run.settings;
        let (work, load_dot) = state.load_work();
        // Friction's work over the increment Δr = Δt ṙ_K: the ledger's
        // ½Δt(v + v_new) with both velocities the increment's rate.
        let ((dissipated, foundation), stick_events) = match self.friction.surface(run) {
            Some(c) => {
                state.friction_passes += 1;
                let d = c.step_dissipation(
                    &state.v_new,
                    &state.v_new,
                    dt,
                    &state.forces,
                    &mut state.forces_new,
                );
                (d, stick_events(&state.classes, &state.classes_new))
            }
            None => ((0.0, 0.0), 0),
        };
        state.commit(dt, t_new, iterations);
        let strain = 0.5 * quadratic_form(&self.k, &state.r, &mut self.partials);
        let energies = StepEnergies {
            kinetic: 0.0,
            strain,
            work,
            dissipated,
            damped: 0.0,
            foundation,
            foundation_stored,
            load_dot,
        };
        Ok(state.close_step(energies, settings, dt, iterations, stick_events))
    }

    fn is_explicit(&self) -> bool {
        false
    }

    fn mass_kind(&self) -> Option<MassKind> {
        None
    }

    fn stiffness_product(&self) -> &'static str {
        "assembled CSR"
    }

    fn implicit(&self) -> Option<&ImplicitFriction> {
        Some(&self.friction)
    }

    fn implicit_mut(&mut self) -> Option<&mut ImplicitFriction> {
        Some(&mut self.friction)
    }
}
