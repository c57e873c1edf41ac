//! Rayleigh damping C = αM + βK against closed forms: a floating part's
//! translation decays as v₀e^{−αt}, a mode as e^{−ξωt} with ξ = βω/2; the
//! ledger's damped energy closes the balance; bad coefficients and a step
//! above the damped critical step are refused.

use stickslip_fem::{Hypothesis, Material};
use stickslip_linalg::csr::{dot, spmv};
use stickslip_linalg::SparseCholesky;
use stickslip_mesh::CellKind;
use stickslip_testkit::{rectangle, Slab};
use stickslip_time::{MassKind, Rayleigh, Scheme, Settings, TimeError};

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

fn material() -> Material {
    Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap()
}

/// A 4 × 1 block (Q1 8 × 2) with no support, load or friction: every
/// rigid motion free.
fn free_block() -> Slab {
    let mesh = rectangle(CellKind::Quad4, 8, 2, [0.0, 0.0], [4.0, 1.0]);
    Slab::assemble(mesh, &material(), &[], &[], None).unwrap()
}

/// The same block held at its left end (u_x = u_y = 0 there).
fn cantilever() -> Slab {
    let mesh = rectangle(CellKind::Quad4, 8, 2, [0.0, 0.0], [4.0, 1.0]);
    let held = [
        stickslip_fem::Dirichlet::new("left", 0, 0.0),
        stickslip_fem::Dirichlet::new("left", 1, 0.0),
    ];
    Slab::assemble(mesh, &material(), &held, &[], None).unwrap()
}

fn settings(scheme: Scheme, dt: f64, t_end: f64, damping: Rayleigh) -> Settings {
    let mut s = Settings::new(scheme, dt, t_end);
    s.damping = damping;
    // The lumped mass for both, so that both integrate one discrete system.
    s.mass = Some(MassKind::Lumped);
    s
}

/// Mass-proportional damping on a free block launched at v₀ in x: each
/// node's velocity is v₀e^{−αt} in the continuum. Both schemes treat αM
/// by the trapezoidal rule, ṙ_K = ṙ(1 − αΔt/2)/(1 + αΔt/2), whose log per
/// step is −αΔt − (αΔt)³/12 + O(Δt⁵): after time t the relative error is
/// αt(αΔt)²/12, second order in Δt. Checked to 2% of that prediction at
/// two Δt (so the error's order is the scheme's), and the ledger: the
/// damped energy is what the kinetic energy lost.
#[test]
fn mass_proportional_damping_decays_a_translation_as_exp_minus_alpha_t() {
    let s = free_block();
    let (v0, alpha, t_end) = (0.5, 4.0, 0.5);
    let mut v = vec![0.0; s.n_free()];
    for node in 0..s.mesh.nodes.len() {
        v[s.dof(node, 0).unwrap()] = v0;
    }
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        for dt in [1e-3, 5e-4] {
            let mut set = settings(scheme, dt, t_end, Rayleigh { alpha, beta: 0.0 });
            set.initial_velocity = Some(v.clone());
            let mut i = s.integrator(set).unwrap();
            let kinetic0 = i.energy().kinetic;
            while !i.done() {
                i.step().unwrap();
            }
            let t = i.time();
            let exact = v0 * (-alpha * t).exp();
            let predicted = alpha * t * (alpha * dt).powi(2) / 12.0;
            for node in 0..s.mesh.nodes.len() {
                let vx = i.velocity()[s.dof(node, 0).unwrap()];
                let error = (exact - vx) / exact;
                assert!(
                    (error / predicted - 1.0).abs() < 0.02,
                    "{scheme:?} Δt = {dt}: error {error:e}, predicted {predicted:e}"
                );
            }
            let e = i.energy();
            assert!(
                e.balance.abs() <= 1e-9 * kinetic0,
                "{scheme:?}: balance {} (kinetic {} + damped {} from {kinetic0})",
                e.balance,
                e.kinetic,
                e.damped
            );
            assert!(e.damped > 0.0);
        }
    }
}

/// The cantilever's lowest mode φ (inverse iteration on K φ = ω² M_L φ)
/// and ω.
fn lowest_mode(s: &Slab) -> (Vec<f64>, f64) {
    let k = &s.model.stiffness;
    let m = &s.model.lumped_mass;
    let mut solver = SparseCholesky::analyze(k, &s.model.fill_order).unwrap();
    solver.factorize(k).unwrap();
    let mut x: Vec<f64> = (0..m.len()).map(|i| 1.0 + (i % 3) as f64).collect();
    for _ in 0..200 {
        let mut y: Vec<f64> = x.iter().zip(m).map(|(x, m)| x * m).collect();
        solver.solve_in_place(&mut y);
        let norm = y.iter().zip(m).map(|(y, m)| m * y * y).sum::<f64>().sqrt();
        x = y.iter().map(|y| y / norm).collect();
    }
    let mut kx = vec![0.0; x.len()];
    spmv(k, &x, &mut kx);
    (x.clone(), dot(&x, &kx).sqrt())
}

/// Stiffness-proportional damping on the cantilever started in its lowest
/// mode (ṙ₀ = φ): C = βK is diagonal in the modes, so the modal amplitude
/// q = φᵀM r is a damped oscillator, q = A e^{−ξωt} sin(ω_d t) with ξ =
/// βω/2, whose successive maxima fall by e^{−ξω T_d}: the slope of ln q at
/// its maxima against t is −ξω, measured within 1% by both schemes.
#[test]
fn stiffness_proportional_damping_decays_a_mode_as_exp_minus_xi_omega_t() {
    let s = cantilever();
    let (phi, omega) = lowest_mode(&s);
    let m = &s.model.lumped_mass;
    let xi = 0.02;
    let beta = 2.0 * xi / omega;
    let period = 2.0 * std::f64::consts::PI / omega;
    // Central difference's step is bounded by the damped critical step at
    // ω_max (the undamped run's estimate); half of it, or 400 a period.
    let undamped = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-6, 1e-3))
        .unwrap()
        .dt_crit()
        .unwrap();
    let xi_max = beta / undamped;
    let dt = (period / 400.0).min(0.5 * undamped * ((1.0 + xi_max * xi_max).sqrt() - xi_max));
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let mut set = settings(scheme, dt, 6.0 * period, Rayleigh { alpha: 0.0, beta });
        set.initial_velocity = Some(phi.clone());
        let mut i = s.integrator(set).unwrap();
        let q = |r: &[f64]| {
            r.iter()
                .zip(&phi)
                .zip(m)
                .map(|((r, p), m)| r * p * m)
                .sum::<f64>()
        };
        let (mut history, mut peaks) = (Vec::new(), Vec::new());
        while !i.done() {
            i.step().unwrap();
            history.push((i.time(), q(i.displacement())));
            let n = history.len();
            if n >= 3 && history[n - 2].1 > history[n - 3].1 && history[n - 2].1 >= history[n - 1].1
            {
                peaks.push(history[n - 2]);
            }
        }
        assert!(peaks.len() >= 5, "{scheme:?}: {} maxima", peaks.len());
        let (t0, q0) = peaks[0];
        let (t1, q1) = *peaks.last().unwrap();
        let rate = -(q1 / q0).ln() / (t1 - t0);
        assert!(
            (rate / (xi * omega) - 1.0).abs() < 0.01,
            "{scheme:?}: decay rate {rate}, ξω = {}",
            xi * omega
        );
        let e = i.energy();
        assert!(e.damped > 0.0);
        let e0 = 0.5 * phi.iter().zip(m).map(|(p, m)| m * p * p).sum::<f64>();
        // The ledger closes: what the mode lost is the damped energy,
        // to the schemes' usual level.
        assert!(
            e.balance.abs() < 1e-3 * e0,
            "{scheme:?}: balance {} of {e0}",
            e.balance
        );
    }
}

/// Central difference's critical step with βK: Δt_crit = (2/ω_max)(√(1+ξ²)
/// − ξ), ξ = βω_max/2, from the undamped 2/ω_max the same run reports;
/// α does not lower it. A Δt between the two is refused, naming damping.
#[test]
fn the_damped_critical_step_follows_the_closed_form() {
    let s = cantilever();
    let undamped = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-6, 1e-3))
        .unwrap()
        .dt_crit()
        .unwrap();
    let omega = 2.0 / undamped;
    for (alpha, beta) in [(0.0, 0.1 / omega), (50.0, 0.1 / omega), (50.0, 0.0)] {
        let xi = 0.5 * beta * omega;
        let exact = 2.0 / omega * ((1.0 + xi * xi).sqrt() - xi);
        let i = s
            .integrator(settings(
                Scheme::CentralDifference,
                0.5 * exact,
                1e-3,
                Rayleigh { alpha, beta },
            ))
            .unwrap();
        let got = i.dt_crit().unwrap();
        assert!((got / exact - 1.0).abs() < 1e-12, "{got} vs {exact}");
    }
    let beta = 0.1 / omega;
    let xi: f64 = 0.05;
    let between = 0.5 * (undamped + 2.0 / omega * ((1.0 + xi * xi).sqrt() - xi));
    let e = s
        .integrator(settings(
            Scheme::CentralDifference,
            between,
            1e-3,
            Rayleigh { alpha: 0.0, beta },
        ))
        .unwrap_err();
    assert!(matches!(e, TimeError::UnstableDamped { .. }), "{e}");
    assert!(e.to_string().contains("material.damping.beta"), "{e}");
    // Negative coefficients are refused.
    let e = s
        .integrator(settings(
            NEWMARK,
            1e-3,
            1e-2,
            Rayleigh {
                alpha: -1.0,
                beta: 0.0,
            },
        ))
        .unwrap_err();
    assert!(e.to_string().contains("must be finite and >= 0"), "{e}");
}
