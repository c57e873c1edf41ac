//! The state every scheme advances: r, ṙ, r̈, the loads, the contact
//! nodes' classes and forces, the energy ledger (METHOD.md §6), the clock
//! and Remark 4.3's count; and what a checkpoint holds of it.

use stickslip_contact::SlipState;

use crate::settings::{Settings, TimeError};

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
    /// ∫ ṙᵀCṙ dt of Rayleigh damping (METHOD.md §8), ≥ 0 step by step:
    /// Newmark Σ Δt ṙ̄ᵀCṙ̄ with ṙ̄ = ½(ṙ_K + ṙ_{K−1}); central difference
    /// its mass part so, its stiffness part as the force it applies,
    /// (β/Δt)K(r_K − r_{K−1}), times r_K − r_{K−1}. 0 without damping.
    pub damped: f64,
    /// Σ w_J c_n δ_J^{m_n+1}/(m_n+1): the energy a compliant foundation
    /// stores (METHOD.md §10); 0 without one.
    pub foundation_stored: f64,
    /// kinetic + strain + foundation_stored − rᵀR(t): the paper's total
    /// energy (Fig. 9).
    pub total: f64,
    /// kinetic + strain + foundation_stored − initial − work +
    /// dissipated + damped − foundation; zero up to round-off for the
    /// trapezoidal rule (Newmark ¼, ½).
    pub balance: f64,
    /// W_f, the work a moving foundation did on the body through friction
    /// (METHOD.md §9): Σ −½(f_K + f_{K−1}) V Δt per node, `dissipated`
    /// then counting the work on the slip only. 0 on a foundation at rest.
    pub foundation: f64,
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
/// ([`crate::Integrator::checkpoint`], [`crate::Integrator::restore`]).
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
    /// Kinetic + strain + a compliant foundation's stored energy at t = 0
    /// (for the balance).
    pub initial_mechanical: f64,
    /// Remark 4.3 step-reduction counter.
    pub reduced_remaining: u64,
    /// The drift-free clock (t = t₀ + k Δt): t₀, Δt and steps k of the
    /// current run of equal steps (`None` in files written before it: the
    /// continued run then starts a new run of steps at `t`).
    pub clock: Option<(f64, f64, u64)>,
    /// Stick/slip iterations so far.
    pub total_iterations: u64,
    /// Numeric factorizations so far.
    pub factorizations: u64,
    /// Newton iterations of a compliant foundation's implicit solves so
    /// far (0 in files written before them).
    pub normal_iterations: u64,
    /// The energy-consistent normal force's excess over the end-point
    /// one per compliant node, φ̃ − w σ (Newmark ¼, ½; empty otherwise, and
    /// in files written before it: 0 then).
    pub normal_excess: Vec<f64>,
}

/// The time of each step without drift: over a run of steps of one Δt
/// (Remark 4.3's reduced step starts another), t_k = t₀ + k Δt, one
/// rounding a step. Summing Δt step by step drifts and leaves a sliver of a
/// last step to reach t_end, which would cost Newmark a factorization of
/// its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Clock {
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

/// The state at the current time, and the next step's vectors while a
/// scheme forms them (`*_new`: swapped in by [`State::commit`]).
#[derive(Clone, Debug)]
pub(crate) struct State {
    pub t: f64,
    clock: Clock,
    pub steps: u64,
    pub r: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    /// R(t).
    pub load: Vec<f64>,
    pub classes: Vec<SlipState>,
    /// Nodal friction forces f_J = w_J g_J φ_ε(v_TJ).
    pub forces: Vec<f64>,
    /// Newmark ¼, ½ with a compliant foundation: per compliant node the
    /// excess e = φ̃ − w σ of the step's energy-consistent normal force
    /// over the end-point one (`newmark/algorithmic.rs`); empty otherwise.
    pub normal_excess: Vec<f64>,
    pub energy: Energy,
    pub initial_mechanical: f64,
    pub reduced_remaining: usize,
    pub total_iterations: u64,
    /// Steps of this process that ran friction code (the nodal closed
    /// form or the stick/slip iteration); not checkpointed: it counts
    /// work, not state.
    pub friction_passes: u64,
    pub r_new: Vec<f64>,
    pub v_new: Vec<f64>,
    pub a_new: Vec<f64>,
    pub load_new: Vec<f64>,
    pub classes_new: Vec<SlipState>,
    pub forces_new: Vec<f64>,
    pub normal_excess_new: Vec<f64>,
}

/// The energies of a step, for [`State::close_step`].
pub(crate) struct StepEnergies {
    /// ½ṙ_Kᵀ M ṙ_K.
    pub kinetic: f64,
    /// ½r_Kᵀ K r_K.
    pub strain: f64,
    /// The work of the loads over the step.
    pub work: f64,
    /// The friction's dissipation over the step.
    pub dissipated: f64,
    /// The damping's dissipation over the step.
    pub damped: f64,
    /// The foundation's work over the step.
    pub foundation: f64,
    /// A compliant foundation's stored energy at r_K.
    pub foundation_stored: f64,
    /// r_K · R_K.
    pub load_dot: f64,
}

impl State {
    /// The state at t = 0 of `n` free DOFs and `n_c` contact nodes.
    pub fn new(n: usize, n_c: usize, dt: f64) -> State {
        State {
            t: 0.0,
            clock: Clock::new(0.0, dt),
            steps: 0,
            r: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
            load: vec![0.0; n],
            classes: vec![SlipState::Stuck; n_c],
            forces: vec![0.0; n_c],
            normal_excess: Vec::new(),
            energy: Energy::default(),
            initial_mechanical: 0.0,
            reduced_remaining: 0,
            total_iterations: 0,
            friction_passes: 0,
            r_new: vec![0.0; n],
            v_new: vec![0.0; n],
            a_new: vec![0.0; n],
            load_new: vec![0.0; n],
            classes_new: vec![SlipState::Stuck; n_c],
            forces_new: vec![0.0; n_c],
            normal_excess_new: Vec::new(),
        }
    }

    /// The first step's Δt from a fresh start, as [`State::next_step`]
    /// takes it (shortened where t_end comes first): the implicit schemes
    /// factorize its operator during their setup.
    pub fn first_dt(settings: &Settings) -> f64 {
        State::new(0, 0, settings.dt).next_step(settings).0
    }

    /// The size of the next step and the time it ends at: Remark 4.3's
    /// reduced step while its count runs ([`Clock`]); the last step lands
    /// on t_end, shortened where t_end is not within [`END_SLACK`] of a
    /// whole step (so a constant Δt keeps one factorization).
    pub fn next_step(&self, settings: &Settings) -> (f64, f64) {
        let dt = match settings.stick_reduction {
            Some(r) if self.reduced_remaining > 0 => r.dt,
            _ => settings.dt,
        };
        let t_end = settings.t_end;
        let t_new = self.clock.after(self.t, dt);
        if t_new < t_end - END_SLACK * dt {
            (dt, t_new)
        } else if t_new <= t_end + END_SLACK * dt {
            (dt, t_end)
        } else {
            (t_end - self.t, t_end)
        }
    }

    /// The loads' work over the step by the trapezoid rule, Σ ½(R_K +
    /// R_{K−1})(r_K − r_{K−1}), and r_K·R_K (METHOD.md §6), before
    /// [`State::commit`].
    pub fn load_work(&self) -> (f64, f64) {
        let (mut work, mut load_dot) = (0.0, 0.0);
        for k in 0..self.r.len() {
            work += 0.5 * (self.load_new[k] + self.load[k]) * (self.r_new[k] - self.r[k]);
            load_dot += self.r_new[k] * self.load_new[k];
        }
        (work, load_dot)
    }

    /// Makes the new state current at t_new, a step of `dt` on: r, ṙ, r̈,
    /// R, the classes and forces.
    pub fn commit(&mut self, dt: f64, t_new: f64, iterations: usize) {
        std::mem::swap(&mut self.r, &mut self.r_new);
        std::mem::swap(&mut self.v, &mut self.v_new);
        std::mem::swap(&mut self.a, &mut self.a_new);
        std::mem::swap(&mut self.load, &mut self.load_new);
        std::mem::swap(&mut self.forces, &mut self.forces_new);
        std::mem::swap(&mut self.normal_excess, &mut self.normal_excess_new);
        self.classes.copy_from_slice(&self.classes_new);
        self.clock.tick(self.t, dt);
        self.t = t_new;
        self.steps += 1;
        self.total_iterations += iterations as u64;
    }

    /// Books the step in the energy ledger and advances Remark 4.3's count.
    pub fn close_step(
        &mut self,
        e: StepEnergies,
        settings: &Settings,
        dt: f64,
        iterations: usize,
        stick_events: usize,
    ) -> StepInfo {
        let l = &mut self.energy;
        l.kinetic = e.kinetic;
        l.strain = e.strain;
        l.external_work += e.work;
        l.dissipated += e.dissipated;
        l.damped += e.damped;
        l.foundation += e.foundation;
        l.foundation_stored = e.foundation_stored;
        // kinetic + strain ≥ +0, so adding a compliant foundation's +0
        // keeps its bits.
        let mechanical = e.kinetic + e.strain + e.foundation_stored;
        l.total = mechanical - e.load_dot;
        // Without damping `+ l.damped` adds +0, and on a foundation at rest
        // `- l.foundation` subtracts +0 (+0 plus ±0 is +0): the same bits
        // as before.
        l.balance =
            mechanical - self.initial_mechanical - l.external_work + l.dissipated + l.damped
                - l.foundation;
        if let Some(r) = settings.stick_reduction {
            if stick_events > 0 {
                self.reduced_remaining = r.steps;
            } else if self.reduced_remaining > 0 && dt <= r.dt * (1.0 + 1e-12) {
                self.reduced_remaining -= 1;
            }
        }
        StepInfo {
            dt,
            iterations,
            stick_events,
        }
    }

    /// The checkpoint of this state, the scheme's factorization and
    /// compliance Newton counts beside it.
    pub fn checkpoint(&self, (factorizations, normal_iterations): (u64, u64)) -> Checkpoint {
        Checkpoint {
            t: self.t,
            steps: self.steps,
            displacement: self.r.clone(),
            velocity: self.v.clone(),
            acceleration: self.a.clone(),
            classes: self.classes.iter().map(|c| c.code()).collect(),
            forces: self.forces.clone(),
            energy: self.energy,
            initial_mechanical: self.initial_mechanical,
            reduced_remaining: self.reduced_remaining as u64,
            clock: Some((self.clock.t0, self.clock.dt, self.clock.k)),
            total_iterations: self.total_iterations,
            factorizations,
            normal_iterations,
            normal_excess: self.normal_excess.clone(),
        }
    }

    /// Replaces this state by the checkpoint's (R(t) is the caller's to
    /// recompute).
    ///
    /// # Errors
    /// [`TimeError::Settings`] when a vector length does not match the model
    /// or the contact surface, a class code is not −1, 0 or 1, or a value is
    /// not finite.
    pub fn restore(&mut self, c: &Checkpoint, dt: f64) -> Result<(), TimeError> {
        let n = self.r.len();
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
        let excess = c.normal_excess.len();
        if excess != 0 && excess != self.normal_excess.len() {
            return bad(format!(
                "normal_excess has {excess} entries, the run has {} compliant nodes of Newmark ¼, ½: \
                 restart from a checkpoint of the same case (contact and scheme)",
                self.normal_excess.len()
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
            .chain(&c.normal_excess)
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
            None => Clock::new(c.t, dt),
        };
        self.steps = c.steps;
        self.r.copy_from_slice(&c.displacement);
        self.v.copy_from_slice(&c.velocity);
        self.a.copy_from_slice(&c.acceleration);
        self.classes.copy_from_slice(&classes);
        self.forces.copy_from_slice(&c.forces);
        // A checkpoint without the excess (an older file): the end-point
        // force, whose excess is 0, as at t = 0.
        if excess == 0 {
            self.normal_excess.fill(0.0);
        } else {
            self.normal_excess.copy_from_slice(&c.normal_excess);
        }
        self.energy = c.energy;
        self.initial_mechanical = c.initial_mechanical;
        self.reduced_remaining = usize::try_from(c.reduced_remaining).unwrap_or(usize::MAX);
        self.total_iterations = c.total_iterations;
        Ok(())
    }
}
