//! The single-DOF oscillator with Coulomb friction: m = 1, k = 100
//! (ω = 10), friction force g = 1 (weight 1, bound 1), step force P from
//! t = 0, at rest at 0.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_contact::{ContactNode, ContactSurface};
use stickslip_time::{Dynamics, History, Integrator, Load, Scheme, Settings};

use crate::scene::SceneError;

/// Spring stiffness.
pub const K: f64 = 100.0;
/// Friction force.
pub const G: f64 = 1.0;
/// Natural frequency √(k/m).
pub const OMEGA: f64 = 10.0;

/// Exact Coulomb displacement at time t: from rest at x_i the mass moves
/// if |P − k x_i| > g, along x_e + (x_i − x_e) cos ω(t − t_i) with
/// x_e = (P − s g)/k, s = sign(P − k x_i), for half a period π/ω, and is
/// at rest again at 2x_e − x_i.
pub fn closed_form(p: f64, t: f64) -> f64 {
    let half = std::f64::consts::PI / OMEGA;
    let (mut x, mut t0) = (0.0, 0.0);
    loop {
        let f = p - K * x;
        if f.abs() <= G + 1e-12 {
            return x; // stuck for good: the load is constant
        }
        let xe = (p - f.signum() * G) / K;
        if t <= t0 + half {
            return xe + (x - xe) * (OMEGA * (t - t0)).cos();
        }
        x = 2.0 * xe - x;
        t0 += half;
    }
}

/// The integrator of the oscillator.
///
/// # Errors
/// ε ≤ 0 or settings the integrator refuses.
pub fn integrator(
    p: f64,
    eps: f64,
    scheme: Scheme,
    dt: f64,
    t_end: f64,
) -> Result<Integrator, SceneError> {
    with_surface(p, surface(eps)?, Settings::new(scheme, dt, t_end))
}

/// The oscillator's one friction node (weight 1, bound g, tangent x) as a
/// surface of its own, for a test to give a foundation or a μ(w).
///
/// # Errors
/// ε ≤ 0.
pub fn surface(eps: f64) -> Result<ContactSurface, SceneError> {
    let node = ContactNode {
        node: 0,
        dofs: [Some(0), None],
        weight: 1.0,
        tangent: [1.0, 0.0],
        s: 0.0,
        bound: G,
    };
    Ok(ContactSurface::from_nodes("mass", vec![node], eps)?)
}

/// The oscillator with friction on `surface` and the step force P.
///
/// # Errors
/// Settings the integrator refuses.
pub fn with_surface(
    p: f64,
    surface: ContactSurface,
    settings: Settings,
) -> Result<Integrator, SceneError> {
    with_load(p, History::Step, surface, settings)
}

/// The oscillator with friction on `surface` and the force P·θ(t).
///
/// # Errors
/// Settings the integrator refuses.
pub fn with_load(
    p: f64,
    history: History,
    surface: ContactSurface,
    settings: Settings,
) -> Result<Integrator, SceneError> {
    let scalar = |v: f64| {
        let mut coo = CooMatrix::new(1, 1);
        coo.push(0, 0, v);
        CsrMatrix::from(&coo)
    };
    let dynamics = Dynamics {
        stiffness: scalar(K),
        consistent_mass: Some(scalar(1.0)),
        lumped_mass: vec![1.0],
        constant_load: vec![0.0],
        stencils: true,
        fill_order: Default::default(),
        rigid_modes: Vec::new(),
    };
    let loads = vec![Load {
        vector: vec![p],
        history,
    }];
    Ok(Integrator::new(dynamics, Some(surface), loads, settings)?)
}

/// (largest |x − x_exact| over [0, 1], x(1)).
///
/// # Errors
/// A refused setting or a failed step.
pub fn max_error(p: f64, eps: f64, scheme: Scheme, dt: f64) -> Result<(f64, f64), SceneError> {
    let mut i = integrator(p, eps, scheme, dt, 1.0)?;
    let mut err: f64 = 0.0;
    while !i.done() {
        i.step()?;
        err = crate::max_or_nan([err, (i.displacement()[0] - closed_form(p, i.time())).abs()]);
    }
    Ok((err, i.displacement()[0]))
}
