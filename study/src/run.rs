//! One run of the slab with a chosen method: the paper's case file with
//! another mesh, method, Δt and ε, run by stickslip-case's pilot runner
//! (the one `stickslip advise` uses), recording the outputs the studies
//! compare: u_x at (8, 0) and (8, 1), σ_T at (7, 0), the energy.

use std::path::Path;

use stickslip_case::pilot::{Pilot, Probe, Trace};
use stickslip_case::{Case, Method};
use stickslip_time::Scheme;

use crate::slab::LoadKind;

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

/// [`Trace::values`] of [`timed_run`]: u_x at (8, 0) (node 81).
pub const UX_8_0: usize = 0;
/// u_x at (8, 1) (node 85).
pub const UX_8_1: usize = 1;
/// σ_T at (7, 0) (node 71).
pub const SIGMA_7_0: usize = 2;

/// The paper's case file of a load history (cases/martins-oden): every
/// run of the chart is it with another mesh, method, Δt and ε.
///
/// # Errors
/// The file does not load (names it and the problem).
pub fn paper_case(load: LoadKind) -> Result<Case, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../cases/martins-oden")
        .join(load.case_file());
    stickslip_case::load(&path, &[]).map_err(|e| e.to_string())
}

/// `case` on the committed mesh `mesh` with `method`, Δt, ε and t_end.
pub fn configured(case: &Case, mesh: &str, method: Method, dt: f64, eps: f64, t_end: f64) -> Case {
    let mesh = crate::slab::meshes_dir().join(mesh);
    let mut c = method.configure(case, &mesh, dt, eps);
    c.time.t_end = t_end;
    c
}

/// Builds and runs `case` once (assembly included in the time, as
/// [`Trace::secs`]), recording [`UX_8_0`], [`UX_8_1`] and [`SIGMA_7_0`].
///
/// # Errors
/// An input problem, a slab without those points, or a failed step.
pub fn timed_run(case: &Case) -> Result<Trace, String> {
    let pilot = Pilot::new(case).map_err(|e| e.to_string())?;
    let p = &pilot.prepared;
    let node_at = |x: f64, y: f64| {
        p.mesh
            .nodes
            .iter()
            .position(|q| (q[0] - x).powi(2) + (q[1] - y).powi(2) < 1e-12)
            .ok_or_else(|| format!("{}: no node at ({x}, {y})", case.mesh.file.display()))
    };
    let ux = |x: f64, y: f64| -> Result<Probe, String> {
        p.model
            .dofs
            .free(node_at(x, y)?, 0)
            .map(Probe::Dof)
            .ok_or_else(|| format!("u_x at ({x}, {y}) is held"))
    };
    let n71 = node_at(7.0, 0.0)?;
    let c71 = p
        .integrator
        .contact()
        .and_then(|c| c.nodes.iter().position(|n| n.node == n71))
        .ok_or("(7, 0) is no friction node")?;
    let probes = [ux(8.0, 0.0)?, ux(8.0, 1.0)?, Probe::Contact(c71)];
    pilot.run(&probes).map_err(|e| e.to_string())
}
