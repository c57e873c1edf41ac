//! The pilot runner of `stickslip advise` and the work-precision study: a
//! case built and run to t_end, recording chosen outputs at t = 0 and after
//! every step, timed from the start of the build (assembly is part of
//! what a configuration costs). Also the measures both take of the
//! histories: sampling on a uniform grid and the relative L2-in-time norm.

use std::time::Instant;

use stickslip_time::{Integrator, TimeError};

use crate::build::{prepare, Prepared};
use crate::error::InputError;
use crate::schema::Case;

/// An output recorded at every step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Probe {
    /// The displacement at this free DOF (total: the static state included).
    Dof(usize),
    /// The friction stress σ_T at this contact node (index along Γ_C).
    Contact(usize),
}

/// What a pilot recorded.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// Times (t = 0 and each step).
    pub t: Vec<f64>,
    /// One history per probe, at the times `t`.
    pub values: Vec<Vec<f64>>,
    /// Total energy (METHOD.md §6) at t = 0.
    pub energy0: f64,
    /// Total energy at t_end.
    pub energy_end: f64,
    /// Steps taken.
    pub steps: u64,
    /// Stick/slip iterations summed over the steps.
    pub iterations: u64,
    /// Numeric factorizations.
    pub factorizations: u64,
    /// Free DOFs.
    pub dofs: usize,
    /// Stored entries of K: the work of one K·r, the deterministic part of
    /// a step's cost.
    pub nnz: usize,
    /// The explicit scheme's critical step, where the integrator estimated it.
    pub dt_crit: Option<f64>,
    /// Wall time, the model's assembly included, seconds.
    pub secs: f64,
}

/// A step that failed, with the integrator's reason.
#[derive(Debug, thiserror::Error)]
#[error("step {step} failed: {source}")]
pub struct StepFailed {
    /// The step's number (1 for the first).
    pub step: u64,
    /// Why.
    pub source: TimeError,
}

/// A case prepared to run, its clock started before the build.
#[derive(Debug)]
pub struct Pilot {
    /// The mesh, the model and the integrator at t = 0 (probes are chosen
    /// on them).
    pub prepared: Prepared,
    started: Instant,
    /// The steps to t_end at the case's Δt (what the histories reserve).
    steps_hint: usize,
}

impl Pilot {
    /// Builds the case's model and integrator.
    ///
    /// # Errors
    /// The case's input problems, as [`crate::prepare`].
    pub fn new(case: &Case) -> Result<Pilot, InputError> {
        let started = Instant::now();
        let prepared = prepare(case)?;
        Ok(Pilot {
            prepared,
            started,
            steps_hint: ((case.time.t_end / case.time.dt) as usize + 2).min(1 << 22),
        })
    }

    /// Runs to t_end recording `probes` at t = 0 and after every step.
    ///
    /// # Errors
    /// A step that fails.
    pub fn run(self, probes: &[Probe]) -> Result<Trace, StepFailed> {
        let Prepared {
            model,
            mut integrator,
            ..
        } = self.prepared;
        let i = &mut integrator;
        let n_c = i.contact().map_or(0, |c| c.len());
        let mut stress = vec![0.0; n_c];
        let hint = self.steps_hint;
        let mut tr = Trace {
            t: Vec::with_capacity(hint),
            values: vec![Vec::with_capacity(hint); probes.len()],
            dofs: model.dofs.n_free(),
            nnz: model.stiffness.nnz(),
            energy0: i.energy().total,
            dt_crit: i.dt_crit(),
            ..Trace::default()
        };
        drop(model);
        let needs_stress = probes.iter().any(|p| matches!(p, Probe::Contact(_)));
        let mut record = |i: &Integrator, tr: &mut Trace| {
            if needs_stress {
                i.friction_stress(&mut stress);
            }
            tr.t.push(i.time());
            for (p, v) in probes.iter().zip(&mut tr.values) {
                v.push(match *p {
                    Probe::Dof(d) => i.displacement()[d],
                    Probe::Contact(k) => stress[k],
                });
            }
        };
        record(i, &mut tr);
        while !i.done() {
            i.step().map_err(|source| StepFailed {
                step: i.steps() + 1,
                source,
            })?;
            record(i, &mut tr);
        }
        tr.energy_end = i.energy().total;
        tr.steps = i.steps();
        tr.iterations = i.total_iterations();
        tr.factorizations = i.factorizations();
        tr.secs = self.started.elapsed().as_secs_f64();
        Ok(tr)
    }
}

/// `n` uniform times on [0, t_end].
pub fn grid(t_end: f64, n: usize) -> Vec<f64> {
    (0..n).map(|k| t_end * k as f64 / (n - 1) as f64).collect()
}

/// Linear interpolation of (t, y) at the sorted times `grid`.
pub fn sample(t: &[f64], y: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grid.len());
    let mut k = 0;
    for &g in grid {
        if t.len() < 2 {
            out.push(y.first().copied().unwrap_or(0.0));
            continue;
        }
        while k + 2 < t.len() && t[k + 1] < g {
            k += 1;
        }
        let (t0, t1) = (t[k], t[k + 1]);
        let s = if t1 > t0 {
            ((g - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        out.push(y[k] + s * (y[k + 1] - y[k]));
    }
    out
}

/// ‖a − b‖ / ‖b − offset‖ over a uniform grid (the discrete L2-in-time
/// norm; the grid spacing cancels).
pub fn relative_l2(a: &[f64], b: &[f64], offset: f64) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = b.iter().map(|y| (y - offset).powi(2)).sum();
    (num / den).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Expected values by hand: the line y = 2t sampled between its points,
    /// held constant before the first and after the last.
    #[test]
    fn sample_interpolates_and_holds_the_ends() {
        let t = [0.0, 1.0, 3.0];
        let y = [0.0, 2.0, 6.0];
        let s = sample(&t, &y, &[0.0, 0.5, 2.0, 3.0, 4.0]);
        assert_eq!(s, vec![0.0, 1.0, 4.0, 6.0, 6.0]);
        assert_eq!(sample(&[0.0], &[5.0], &[0.0, 1.0]), vec![5.0, 5.0]);
        assert_eq!(grid(0.5, 3), vec![0.0, 0.25, 0.5]);
    }

    /// ‖(1, 1) − (0, 2)‖ / ‖(0, 2) − 0‖ = √2 / 2.
    #[test]
    fn relative_l2_by_hand() {
        let r = relative_l2(&[1.0, 1.0], &[0.0, 2.0], 0.0);
        assert!((r - 0.5f64.sqrt()).abs() < 1e-15, "{r}");
    }
}
