//! A 1-D wave: the slab mesh with ν = 0, rollers on top and bottom, held at
//! x = 0, a step traction −p at x = L, no friction. Every section moves as a
//! bar with c = √(E/ρ) (ν = 0 makes plane strain uniaxial), so d'Alembert
//! gives the end displacement: a triangle wave between 0 and −2pL/E with
//! period 4L/c, u(L, t) = −(p c/E)·t for t ≤ 2L/c, then back to 0 at 4L/c.

use stickslip_fem::{Dirichlet, Hypothesis, Material, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::{History, Scheme, Settings};

use crate::scene::{SceneError, Slab};

/// E (ρ = 1).
pub const E: f64 = 1000.0;
/// Bar length.
pub const L: f64 = 8.0;
/// End traction.
pub const P: f64 = 1.0;

/// d'Alembert's u_x(L, t).
pub fn exact_end_displacement(t: f64) -> f64 {
    let c = E.sqrt();
    let period = 4.0 * L / c;
    let tau = t.rem_euclid(period);
    let rise = if tau <= period / 2.0 {
        tau
    } else {
        period - tau
    };
    -P * c / E * rise
}

/// The bar on `mesh` (a slab mesh with groups "support", "contact",
/// "left", "load").
///
/// # Errors
/// A mesh without those groups.
pub fn scene(mesh: Mesh) -> Result<Slab, SceneError> {
    let material = Material::new(E, 0.0, 1.0, Hypothesis::PlaneStrain)?;
    let conditions = [
        Dirichlet::new("support", 1, 0.0),
        Dirichlet::new("contact", 1, 0.0),
        Dirichlet::new("left", 0, 0.0),
    ];
    let tractions = [("load", Traction::Vector([-P, 0.0]), History::Step)];
    Slab::assemble(mesh, &material, &conditions, &tractions, None)
}

/// Relative L2-in-time error of u_x(L, 0) over one period against
/// [`exact_end_displacement`].
///
/// # Errors
/// A mesh without the slab's groups or node (L, 0), settings refused
/// or a failed step.
pub fn end_error(mesh: Mesh, scheme: Scheme, dt: f64) -> Result<f64, SceneError> {
    let s = scene(mesh)?;
    let end = s.node_at(L, 0.0)?;
    let end_dof = s.dof(end, 0).ok_or(SceneError::NoNode { x: L, y: 0.0 })?;
    let period = 4.0 * L / E.sqrt();
    let mut i = s.integrator(Settings::new(scheme, dt, period))?;
    let (mut err2, mut ref2) = (0.0, 0.0);
    while !i.done() {
        i.step()?;
        let exact = exact_end_displacement(i.time());
        err2 += (i.displacement()[end_dof] - exact).powi(2);
        ref2 += exact * exact;
    }
    Ok((err2 / ref2).sqrt())
}
