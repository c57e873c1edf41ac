//! One run of the slab with a chosen method, recording the outputs the
//! studies compare: u_x at (8, 0) and (8, 1), σ_T at (7, 0), the energy.

use std::time::Instant;

use stickslip_mesh::Mesh;
use stickslip_time::{Scheme, Settings};

use crate::slab::{self, LoadKind, Slab};

/// Remark 4.3 as the paper did it: Δt = 1e-7 for 10 steps after sticking.
pub use stickslip_time::scenes::PAPER_REDUCTION as REDUCTION;
/// Newmark β = ¼, γ = ½ (trapezoidal rule).
pub const TRAPEZOIDAL: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};
/// Newmark β = 0.3025, γ = 0.6 (numerical damping).
pub const DAMPED: Scheme = Scheme::Newmark {
    beta: 0.3025,
    gamma: 0.6,
};

pub use stickslip_time::scenes::Method;

/// Longer name of a method for legends.
pub fn label(method: Method) -> &'static str {
    match method {
        Method::CentralDifference => "central difference",
        Method::Trapezoidal => "Newmark ¼,½",
        Method::TrapezoidalReduced => "Newmark ¼,½ + reduction",
        Method::Damped => "Newmark 0.3025,0.6",
    }
}

/// Time histories of the compared outputs, one entry per step (and t = 0).
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// Times.
    pub t: Vec<f64>,
    /// Total u_x at (8, 0) (node 81).
    pub ux81: Vec<f64>,
    /// Total u_x at (8, 1) (node 85).
    pub ux85: Vec<f64>,
    /// σ_T at (7, 0) (node 71).
    pub sigma71: Vec<f64>,
    /// Total energy (METHOD.md §6) at t = 0.
    pub energy0: f64,
    /// Total energy at the end.
    pub energy_end: f64,
    /// Steps taken.
    pub steps: u64,
    /// Stick/slip iterations summed over the steps.
    pub iterations: u64,
    /// Numeric factorizations.
    pub factorizations: u64,
    /// Free DOFs.
    pub dofs: usize,
    /// The explicit scheme's estimated critical step.
    pub dt_crit: Option<f64>,
}

/// Runs `method` on `slab` to `t_end`, recording the trace.
///
/// # Errors
/// A failed step or settings the time crate refuses.
pub fn run_slab(slab: &Slab, settings: Settings) -> Result<Trace, String> {
    let n81 = slab.node_at(8.0, 0.0).map_err(|e| e.to_string())?;
    let n85 = slab.node_at(8.0, 1.0).map_err(|e| e.to_string())?;
    let n71 = slab.node_at(7.0, 0.0).map_err(|e| e.to_string())?;
    let (d81, d85) = (slab.dof(n81, 0), slab.dof(n85, 0));
    let c71 = slab.contact_index(n71);
    let n_c = slab.contact.as_ref().map_or(0, |c| c.len());
    let mut stress = vec![0.0; n_c];
    let mut i = slab.integrator(settings).map_err(|e| e.to_string())?;
    let steps_hint = (i.t_end() / 1e-4) as usize + 2;
    let mut tr = Trace {
        dofs: slab.n_free(),
        dt_crit: i.dt_crit(),
        energy0: i.energy().total,
        ..Trace::default()
    };
    for v in [&mut tr.t, &mut tr.ux81, &mut tr.ux85, &mut tr.sigma71] {
        v.reserve(steps_hint.min(1 << 20));
    }
    let mut record = |i: &stickslip_time::Integrator, tr: &mut Trace| {
        let r = i.displacement();
        tr.t.push(i.time());
        tr.ux81.push(d81.map_or(0.0, |d| r[d]));
        tr.ux85.push(d85.map_or(0.0, |d| r[d]));
        i.friction_stress(&mut stress);
        tr.sigma71.push(c71.map_or(0.0, |c| stress[c]));
    };
    record(&i, &mut tr);
    while !i.done() {
        i.step().map_err(|e| e.to_string())?;
        record(&i, &mut tr);
    }
    tr.energy_end = i.energy().total;
    tr.steps = i.steps();
    tr.iterations = i.total_iterations();
    tr.factorizations = i.factorizations();
    Ok(tr)
}

/// Builds the model (assembly included in the time) and runs it once;
/// returns the trace and the wall time in seconds.
///
/// # Errors
/// As [`run_slab`].
pub fn timed_run(
    mesh: &Mesh,
    eps: f64,
    load: LoadKind,
    settings: Settings,
) -> Result<(Trace, f64), String> {
    let start = Instant::now();
    let slab = slab::paper(mesh, eps, load, true)?;
    let trace = run_slab(&slab, settings)?;
    Ok((trace, start.elapsed().as_secs_f64()))
}

/// Linear interpolation of (t, y) at the sorted times `grid`.
pub fn sample(t: &[f64], y: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grid.len());
    let mut k = 0;
    for &g in grid {
        while k + 2 < t.len() && t[k + 1] < g {
            k += 1;
        }
        if t.len() < 2 {
            out.push(y.first().copied().unwrap_or(0.0));
            continue;
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
