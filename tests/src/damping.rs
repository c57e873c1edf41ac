//! Rayleigh damping C = αM + βK on a 4 × 1 block of Q1 8 × 2 cells (E =
//! 1000, ν = 0.3, ρ = 1, plane strain), the runs the time crate's tests
//! and verify's analytic suite check against closed forms:
//!
//! * a free block (no support) launched at v₀ in x with αM: every node's
//!   velocity is v₀e^{−αt}; both schemes take αM by the trapezoidal rule,
//!   ṙ_K = ṙ(1 − αΔt/2)/(1 + αΔt/2), whose log per step is −αΔt −
//!   (αΔt)³/12 + O(Δt⁵), so after t the relative error is αt(αΔt)²/12;
//! * the block held at its left end, started in its lowest mode (ṙ₀ = φ)
//!   with βK: C is diagonal in the modes, the modal amplitude q = φᵀM_L r
//!   is a damped oscillator A e^{−ξωt} sin(ω_d t), ξ = βω/2, and the slope
//!   of ln q at its maxima is −ξω;
//! * central difference's stability threshold with βK, bisected as the
//!   undamped one is, against (2/ω_max)(√(1+ξ²) − ξ), ξ = βω_max/2.

use stickslip_fem::{Dirichlet, Hypothesis, Material};
use stickslip_linalg::csr::{dot, spmv};
use stickslip_linalg::SparseCholesky;
use stickslip_mesh::CellKind;
use stickslip_time::{MassKind, Rayleigh, Scheme, Settings, TimeError};

use crate::grid::rectangle;
use crate::scene::{SceneError, Slab};

/// The block with `conditions`.
fn block(conditions: &[Dirichlet]) -> Slab {
    let mesh = rectangle(CellKind::Quad4, 8, 2, [0.0, 0.0], [4.0, 1.0]);
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).expect("valid");
    Slab::assemble(mesh, &material, conditions, &[], None).expect("the block builds")
}

/// The block with no support: every rigid motion free.
pub fn free_block() -> Slab {
    block(&[])
}

/// The block held at its left end (u_x = u_y = 0 there).
pub fn cantilever() -> Slab {
    block(&[
        Dirichlet::new("left", 0, 0.0),
        Dirichlet::new("left", 1, 0.0),
    ])
}

/// Settings with damping and the lumped mass for both schemes (one
/// discrete system for both).
pub fn settings(scheme: Scheme, dt: f64, t_end: f64, damping: Rayleigh) -> Settings {
    let mut s = Settings::new(scheme, dt, t_end);
    s.damping = damping;
    s.mass = Some(MassKind::Lumped);
    s
}

/// The free block launched at v₀ = 0.5 in x with αM, run to `t_end`:
/// (the largest relative error of a node's velocity against v₀e^{−αt},
/// the prediction αt(αΔt)²/12, the ledger's |balance| over the initial
/// kinetic energy, the damped energy over it).
///
/// # Errors
/// The integrator's.
pub fn translation_decay(
    scheme: Scheme,
    dt: f64,
    alpha: f64,
    t_end: f64,
) -> Result<[f64; 4], SceneError> {
    let s = free_block();
    let v0 = 0.5;
    let mut v = vec![0.0; s.n_free()];
    for node in 0..s.mesh.nodes.len() {
        if let Some(d) = s.dof(node, 0) {
            v[d] = v0;
        }
    }
    let mut set = settings(scheme, dt, t_end, Rayleigh { alpha, beta: 0.0 });
    set.initial_velocity = Some(v);
    let mut i = s.integrator(set)?;
    let kinetic0 = i.energy().kinetic;
    while !i.done() {
        i.step()?;
    }
    let t = i.time();
    let exact = v0 * (-alpha * t).exp();
    let worst = (0..s.mesh.nodes.len())
        .filter_map(|node| s.dof(node, 0))
        .map(|d| (exact - i.velocity()[d]) / exact)
        .fold(0.0f64, |w, e| if e.abs() > w.abs() { e } else { w });
    let e = i.energy();
    Ok([
        worst,
        alpha * t * (alpha * dt).powi(2) / 12.0,
        e.balance.abs() / kinetic0,
        e.damped / kinetic0,
    ])
}

/// The lowest mode φ (M_L-normalized) of a scene and its ω, by inverse
/// iteration on K φ = ω² M_L φ.
pub fn lowest_mode(s: &Slab) -> (Vec<f64>, f64) {
    let k = &s.model.stiffness;
    let m = &s.model.lumped_mass;
    let mut solver = SparseCholesky::analyze(k, &s.model.fill_order).expect("K analyses");
    solver.factorize(k).expect("K is definite");
    let mut x: Vec<f64> = (0..m.len()).map(|i| 1.0 + (i % 3) as f64).collect();
    for _ in 0..200 {
        let mut y: Vec<f64> = x.iter().zip(m).map(|(x, m)| x * m).collect();
        solver.solve_in_place(&mut y);
        let norm = y.iter().zip(m).map(|(y, m)| m * y * y).sum::<f64>().sqrt();
        x = y.iter().map(|y| y / norm).collect();
    }
    let mut kx = vec![0.0; x.len()];
    spmv(k, &x, &mut kx);
    let omega = dot(&x, &kx).sqrt();
    (x, omega)
}

/// The cantilever started in its lowest mode with βK for ξ = `xi` at its
/// frequency, over six periods: (the measured decay rate of q's maxima,
/// ξω, the ledger's |balance| over the initial kinetic energy). The step is
/// a period over 400, or half the damped critical step where that is
/// smaller (for central difference).
///
/// # Errors
/// The integrator's.
pub fn mode_decay(scheme: Scheme, xi: f64) -> Result<[f64; 3], SceneError> {
    let s = cantilever();
    let (phi, omega) = lowest_mode(&s);
    let m = &s.model.lumped_mass;
    let beta = 2.0 * xi / omega;
    let period = 2.0 * std::f64::consts::PI / omega;
    let undamped = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-6, 1e-3))?
        .dt_crit()
        .unwrap_or(f64::INFINITY);
    let xi_max = beta / undamped;
    let dt = (period / 400.0).min(0.5 * undamped * ((1.0 + xi_max * xi_max).sqrt() - xi_max));
    let mut set = settings(scheme, dt, 6.0 * period, Rayleigh { alpha: 0.0, beta });
    set.initial_velocity = Some(phi.clone());
    let mut i = s.integrator(set)?;
    let kinetic0 = i.energy().kinetic;
    let q = |r: &[f64]| -> f64 { r.iter().zip(&phi).zip(m).map(|((r, p), m)| r * p * m).sum() };
    // The last two samples (t, q): a maximum is a sample above the one
    // before and not below the one after.
    let (mut before, mut previous, mut peaks) = (
        (0.0, f64::NEG_INFINITY),
        (0.0, f64::NEG_INFINITY),
        Vec::new(),
    );
    while !i.done() {
        i.step()?;
        let now = (i.time(), q(i.displacement()));
        if previous.1 > before.1 && previous.1 >= now.1 {
            peaks.push(previous);
        }
        (before, previous) = (previous, now);
    }
    let rate = match (peaks.first(), peaks.last()) {
        (Some(&(t0, q0)), Some(&(t1, q1))) if t1 > t0 => -(q1 / q0).ln() / (t1 - t0),
        _ => f64::NAN,
    };
    Ok([rate, xi * omega, i.energy().balance.abs() / kinetic0])
}

/// Whether central difference on the cantilever with `damping` is stable at Δt
/// for 3000 steps from a velocity with every mode in it: its kinetic +
/// strain energy never exceeds ten times the initial (damping only lowers
/// it while stable; above the threshold the top mode grows by a factor
/// per step).
///
/// # Errors
/// The integrator's, other than the state leaving the floating-point range.
pub fn stable(damping: Rayleigh, dt: f64) -> Result<bool, SceneError> {
    let s = cantilever();
    let mut set = settings(Scheme::CentralDifference, dt, dt * 3000.5, damping);
    set.allow_unstable = true;
    set.initial_velocity = Some(
        (0..s.n_free())
            .map(|i| ((i as f64) * 0.618_033_988_75).fract() - 0.5)
            .collect(),
    );
    let mut i = s.integrator(set)?;
    let e0 = i.energy().kinetic;
    while !i.done() {
        match i.step() {
            Ok(_) => {}
            Err(TimeError::NonFinite { .. }) => return Ok(false),
            Err(e) => return Err(e.into()),
        }
        let e = i.energy();
        // NaN counts as unstable too.
        let grown = e.kinetic + e.strain;
        if grown.is_nan() || grown > 10.0 * e0 {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Central difference's damped stability threshold on the cantilever,
/// bisected to a relative width of 1e-3 between half and twice the
/// prediction: (threshold, prediction the integrator reports; NaN
/// threshold when those do not bracket it).
///
/// # Errors
/// The integrator's.
pub fn damped_threshold(damping: Rayleigh) -> Result<(f64, f64), SceneError> {
    let s = cantilever();
    let predicted = s
        .integrator(settings(Scheme::CentralDifference, 1e-6, 1e-3, damping))?
        .dt_crit()
        .unwrap_or(f64::NAN);
    let (mut lo, mut hi) = (0.5 * predicted, 2.0 * predicted);
    if !stable(damping, lo)? || stable(damping, hi)? {
        return Ok((f64::NAN, predicted));
    }
    while hi - lo > 1e-3 * lo {
        let mid = 0.5 * (lo + hi);
        if stable(damping, mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((0.5 * (lo + hi), predicted))
}
