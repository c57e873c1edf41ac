//! The friction at t = 0 in the initial acceleration: M r̈₀ = R(0) − K r₀
//! − J(ṙ₀), J acting on the slip ṙ₀ − V. At rest on a foundation at rest
//! J(0) = 0 and this is Remark 4.1's frictionless r̈₀; a part launched, or
//! a belt moving under it, feels the friction from the start. The single
//! mass of tests/sdof.rs (m = 1, k = 100, ω = 10, friction force g = 1),
//! no load:
//!
//! * launched at v₀ = 1 on a floor at rest, it slides forward under −g:
//!   x(t) = (v₀/ω) sin ωt − (g/k)(1 − cos ωt) until it stops;
//! * at rest on a belt at V = 5, dragged by +g: x(t) = (g/k)(1 − cos ωt);
//!
//! r̈₀ = ∓g, Newmark ¼, ½'s ledger closes to round-off from the first step
//! (its trapezoid books ½(J₁ + J₀)·Δr, which the dynamics now match), and
//! both schemes are second order from the start: no gΔt/2 velocity lost.

use stickslip_testkit::read_mesh;
use stickslip_testkit::scene::{Slab, END_LOAD, NU, PRESSURE};
use stickslip_testkit::sdof::{self, G, K, OMEGA};
use stickslip_testkit::solvers::every_solver;
use stickslip_time::{History, Integrator, MassKind, Scheme, Settings};

const DT: f64 = 1e-3;

/// The mass on `speed`'s belt (`None`: a floor at rest), launched at
/// `v0`, its pressure scaled by `pressure` from t = 0.
fn mass(
    speed: Option<f64>,
    v0: f64,
    pressure: Option<History>,
    mut settings: Settings,
) -> Integrator {
    let mut surface = sdof::surface(1e-2).unwrap();
    if let Some(v) = speed {
        surface.set_foundation(|_| v);
    }
    if v0 != 0.0 {
        settings.initial_velocity = Some(vec![v0]);
    }
    let mut i = sdof::with_surface(0.0, surface, settings).unwrap();
    if let Some(h) = pressure {
        i.set_pressure_histories(&[h]).unwrap();
    }
    i
}

/// Runs `i` to its end against `exact`, returning the largest error and,
/// for Newmark ¼, ½, asserting |balance| ≤ 1e-12 after every step.
fn run(name: &str, mut i: Integrator, exact: impl Fn(f64) -> f64, newmark: bool) -> f64 {
    let mut worst: f64 = 0.0;
    while !i.done() {
        i.step().unwrap();
        worst = worst.max((i.displacement()[0] - exact(i.time())).abs());
        if newmark {
            let b = i.energy().balance;
            assert!(b.abs() <= 1e-12, "{name}: t = {}: balance {b:e}", i.time());
        }
    }
    worst
}

#[test]
fn a_launched_mass_decelerates_from_the_start() {
    let v0 = 1.0;
    // ẋ = v₀ cos ωt − (g/(kω)) ω sin ωt... = 0 where tan ωt = v₀kω/(gω²)
    // = 10: the stop at ωt ≈ 1.47. One radian, t = 0.1, stays before it.
    let t_end = 0.1;
    let exact = |t: f64| v0 / OMEGA * (OMEGA * t).sin() - G / K * (1.0 - (OMEGA * t).cos());
    for (name, settings) in every_solver(DT, t_end) {
        let newmark = !matches!(settings.scheme, Scheme::CentralDifference);
        let i = mass(None, v0, None, settings);
        assert_eq!(i.acceleration()[0], -G, "{name}: r̈₀");
        let worst = run(name, i, exact, newmark);
        // Second order: the schemes' phase error, (ωΔt)²/12 ≈ 8e-6 of a
        // radian per radian, times the amplitude v₀/ω = 0.1, about 1e-6
        // by t = 0.1. A start without the friction leaves the velocity
        // gΔt/2 = 5e-4 short, 5e-5 in x by t = 0.1.
        assert!(worst < 2e-6, "{name}: {worst:e}");
    }
}

#[test]
fn a_belt_drags_the_mass_from_the_start() {
    let amplitude = G / K;
    let exact = |t: f64| amplitude * (1.0 - (OMEGA * t).cos());
    for (name, settings) in every_solver(DT, 1.0) {
        let newmark = !matches!(settings.scheme, Scheme::CentralDifference);
        let i = mass(Some(5.0), 0.0, None, settings);
        assert_eq!(i.acceleration()[0], G, "{name}: r̈₀");
        let worst = run(name, i, exact, newmark);
        // Second order, 1e-3 of the amplitude over ten radians; a
        // frictionless start oscillates by gΔt/(2ω) = 5e-5 = 5e-3 of it.
        assert!(worst < 2e-3 * amplitude, "{name}: {worst:e}");
    }
}

/// The pressure at t = 0 set after the start (a history whose value at 0
/// is 0.5) changes the friction there, and r̈₀ with it: −g/2 for the
/// launched mass, by the lumped mass and by a consistent one's solve.
#[test]
fn a_pressure_history_sets_the_initial_friction_and_acceleration() {
    let half = History::Table(vec![(0.0, 0.5), (1.0, 0.5)]);
    for (name, settings) in every_solver(DT, 0.1) {
        let newmark = !matches!(settings.scheme, Scheme::CentralDifference);
        let i = mass(None, 1.0, Some(half.clone()), settings);
        assert_eq!(i.acceleration()[0], -0.5 * G, "{name}: r̈₀");
        let exact =
            |t: f64| 1.0 / OMEGA * (OMEGA * t).sin() - 0.5 * G / K * (1.0 - (OMEGA * t).cos());
        let worst = run(name, i, exact, newmark);
        assert!(worst < 2e-6, "{name}: {worst:e}");
    }
}

/// On the paper's slab launched at ṙ₀ = (1, 0), a pressure history of 0.5
/// at t = 0 set after the start corrects r̈₀ (by M's solve of the change
/// of J₀) to what a start with half the friction bound built in computes
/// directly (μ = 0.15 against 0.3: g = μp either way, the pressure load
/// unchanged), for every solver and with Newmark's consistent and lumped
/// mass: the same r̈₀ to round-off, by two ways of forming it.
#[test]
fn the_corrected_acceleration_is_the_direct_one_on_the_slab() {
    let slab = |mu: f64| {
        let mesh = read_mesh("slab-q2-8x2.msh").expect("committed mesh reads");
        Slab::new(mesh, NU, PRESSURE, Some(mu), 1e-4, END_LOAD, History::Step)
            .expect("the slab builds")
    };
    let (full, half) = (slab(0.3), slab(0.15));
    let mut v0 = vec![0.0; full.n_free()];
    for node in 0..full.mesh.nodes.len() {
        if let Some(d) = full.dof(node, 0) {
            v0[d] = 1.0;
        }
    }
    let mut cases = every_solver(DT, 0.01);
    let mut lumped = cases[2].1.clone();
    lumped.mass = Some(MassKind::Lumped);
    cases.push(("Schur, lumped", lumped));
    let largest = |x: &[f64]| x.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let apart =
        |x: &[f64], y: &[f64]| largest(&x.iter().zip(y).map(|(a, b)| a - b).collect::<Vec<_>>());
    for (name, mut settings) in cases {
        settings.initial_velocity = Some(v0.clone());
        let uncorrected = full.integrator(settings.clone()).unwrap();
        let mut corrected = full.integrator(settings.clone()).unwrap();
        corrected
            .set_pressure_histories(&[History::Table(vec![(0.0, 0.5), (1.0, 0.5)])])
            .unwrap();
        let direct = half.integrator(settings).unwrap();
        let scale = largest(direct.acceleration());
        let worst = apart(corrected.acceleration(), direct.acceleration());
        assert!(worst <= 1e-11 * scale, "{name}: {worst:e} of {scale:e}");
        // The correction is the friction's change, far above round-off.
        let change = apart(uncorrected.acceleration(), direct.acceleration());
        assert!(change > 1e-3 * scale, "{name}: {change:e} of {scale:e}");
    }
}
