//! A moving foundation (METHOD.md §9: the law acts on the slip v_T − V) on
//! the single mass of tests/sdof.rs (m = 1, k = 100, ω = 10, friction
//! force g = 1), no load, at rest at 0, on a belt at speed V:
//!
//! * V = 5, far above the mass's speed: it slips backward against the belt
//!   the whole run, the belt dragging it by +g, so ẍ + ω²x = g and
//!   x(t) = (g/k)(1 − cos ωt) (its speed peaks at g/(kω)·ω² /ω = 0.1 < V);
//! * V = 1e-4 below ε = 1e-2: the viscous branch, force −(g/ε)(ẋ − V),
//!   at rest at last where k x = (g/ε)V, x = gV/(εk) = 1e-4;
//!
//! by every way of solving a step, with the ledger closed by the
//! foundation's work; and a foundation at V = 0 moves no bit.

use stickslip_testkit::sdof::{self, G, K, OMEGA};
use stickslip_testkit::solvers::every_solver;
use stickslip_time::{History, Integrator, Scheme, Settings};

fn belt(speed: Option<f64>, eps: f64, settings: Settings) -> Integrator {
    let mut surface = sdof::surface(eps).unwrap();
    if let Some(v) = speed {
        surface.set_foundation(|_| v);
    }
    let mut i = sdof::with_surface(0.0, surface, settings).unwrap();
    i.set_foundation_histories(&[History::Constant]).unwrap();
    i
}

/// The ways of solving a step, at Δt = 1e-3 to `t_end`.
fn solvers(t_end: f64) -> Vec<(&'static str, Settings)> {
    every_solver(1e-3, t_end)
}

#[test]
fn a_fast_belt_drags_the_mass_by_g() {
    let amplitude = G / K;
    for (name, settings) in solvers(1.0) {
        let newmark = !matches!(settings.scheme, Scheme::CentralDifference);
        let mut i = belt(Some(5.0), 1e-2, settings);
        let mut worst: f64 = 0.0;
        i.step().unwrap();
        let (first, x1) = (i.energy().balance, i.displacement()[0]);
        while !i.done() {
            i.step().unwrap();
            let exact = amplitude * (1.0 - (OMEGA * i.time()).cos());
            worst = worst.max((i.displacement()[0] - exact).abs());
            assert!(!i.classes()[0].is_stuck(), "{name}: t = {}", i.time());
        }
        // Both schemes are second order, (ωΔt)² = 1e-4 of the amplitude
        // per radian over ten radians, 1e-3 of it; the bound also admits a
        // frictionless start (r̈₀ = 0, not g: the velocity gΔt/2 short
        // after the first step, an oscillation of gΔt/(2ω) = 5e-5), which
        // tests/initial_friction.rs rules out.
        let dt = 1e-3;
        let bound = G * dt / (2.0 * OMEGA) + 1e-3 * amplitude;
        assert!(worst < bound, "{name}: {worst:e} > {bound:e}");
        let e = i.energy();
        // The belt did work on the mass: W_f = ∫ g V dt = 5 over the run,
        // nearly all of it dissipated on the slip.
        assert!(
            (e.foundation - G * 5.0).abs() < 1e-2,
            "{name}: {}",
            e.foundation
        );
        assert!(e.dissipated > 0.0);
        if newmark {
            // The trapezoidal rule closes the ledger to round-off from the
            // first step: r̈₀ carries f₀ (tests/initial_friction.rs).
            assert!(
                first.abs() <= 1e-12 * G * x1,
                "{name}: first step {first:e}"
            );
            let drift = e.balance - first;
            assert!(drift.abs() < 1e-12, "{name}: balance moved {drift:e}");
        } else {
            // Central difference's ledger is O(Δt²) of the energies.
            assert!(
                e.balance.abs() < 1e-3 * e.foundation,
                "{name}: {:e}",
                e.balance
            );
        }
    }
}

#[test]
fn a_slow_belt_holds_the_mass_on_the_viscous_branch() {
    let (eps, speed) = (1e-2, 1e-4);
    let rest = G * speed / (eps * K);
    let mut settings = solvers(20.0);
    settings.push((
        "quasi-static",
        Settings::new(Scheme::QuasiStatic, 1e-3, 20.0),
    ));
    for (name, settings) in settings {
        let mut i = belt(Some(speed), eps, settings);
        while !i.done() {
            i.step().unwrap();
        }
        assert!(i.classes()[0].is_stuck(), "{name}");
        // The slow root of s² + (g/ε)s + k = 0 is ≈ −1.01: after 20 time
        // units e⁻²⁰ ≈ 2e-9 of the approach is left.
        let x = i.displacement()[0];
        assert!((x - rest).abs() < 1e-6 * rest, "{name}: {x:e} vs {rest:e}");
    }
}

#[test]
fn a_foundation_at_rest_moves_no_bit() {
    for (name, settings) in solvers(0.5) {
        let mut a = belt(None, 1e-2, settings.clone());
        let mut b = belt(Some(0.0), 1e-2, settings);
        // A step force P = 2.5 makes the mass slip and stick (tests/sdof.rs).
        let mut c = a.checkpoint();
        c.velocity[0] = 1.0;
        a.restore(&c).unwrap();
        b.restore(&c).unwrap();
        while !a.done() {
            a.step().unwrap();
            b.step().unwrap();
            assert_eq!(
                a.displacement()[0].to_bits(),
                b.displacement()[0].to_bits(),
                "{name}"
            );
            assert_eq!(
                a.velocity()[0].to_bits(),
                b.velocity()[0].to_bits(),
                "{name}"
            );
            assert_eq!(a.energy(), b.energy(), "{name}");
        }
    }
}

/// μ falling with the slip speed runs with every solver but the explicit
/// iteration (the closed form's reference for the constant law), which
/// refuses it rather than run a law whose slip forces it would take as
/// constant.
#[test]
fn a_speed_dependent_mu_runs_with_every_solver_but_the_explicit_iteration() {
    for (name, settings) in solvers(0.01) {
        let iterated = name == "explicit iteration";
        let mut surface = sdof::surface(1e-3).unwrap();
        surface.set_weakening(|_| {
            Some(stickslip_contact::Weakening {
                ratio: 0.5,
                speed: 1e-2,
            })
        });
        let result = sdof::with_surface(2.5, surface, settings);
        assert_eq!(result.is_err(), iterated, "{name}");
        if let Err(e) = result {
            assert!(e.to_string().contains("closed form"), "{name}: {e}");
        }
    }
}

/// Quasi-static increments on a belt running from t = 0 (V = 5, Δt =
/// 0.1): the start is the frictionless static state x₀ = 0 (Remark 4.1,
/// METHOD.md §11), so no friction acts at t = 0 (its friction stress 0,
/// the node stuck) and the first increment's trapezoids take J₀ = 0. The
/// belt outruns the mass (k V Δt = 50 > g), which slips backward, dragged
/// by g: k x₁ = g, x₁ = 0.01; friction dissipates ½ g (V Δt − x₁) = 0.245
/// on the slip, the belt works ½ g V Δt = 0.25, and the balance ½ k x₁² +
/// 0.245 − 0.25 is 0 (to 1e-15: a friction J₀ = −g at t = 0 would book
/// ½J₀·x₁ = −0.005 more).
#[test]
fn quasi_static_increments_start_on_a_belt_without_friction() {
    let mut i = belt(
        Some(5.0),
        1e-2,
        Settings::new(Scheme::QuasiStatic, 0.1, 1.0),
    );
    let (mut stress, mut state) = ([f64::NAN], [9_i8]);
    i.friction_stress(&mut stress);
    i.slip_states(&mut state);
    assert_eq!((stress[0], state[0]), (0.0, 0));
    i.step().unwrap();
    let x1 = G / K;
    assert!(
        (i.displacement()[0] - x1).abs() < 1e-15,
        "{}",
        i.displacement()[0]
    );
    let e = i.energy();
    let (dt, v) = (0.1, 5.0);
    let dissipated = 0.5 * G * (v * dt - x1);
    let foundation = 0.5 * G * v * dt;
    assert!((e.dissipated - dissipated).abs() < 1e-15, "{e:?}");
    assert!((e.foundation - foundation).abs() < 1e-15, "{e:?}");
    assert!(e.balance.abs() < 1e-15, "{e:?}");
    // From the first increment on, the law at its rate: slipping, −g φ = g.
    i.friction_stress(&mut stress);
    i.slip_states(&mut state);
    assert_eq!((stress[0], state[0]), (G, -1));
}

/// A surface whose friction cannot act (g = 0) is kept for the observers,
/// and its slip w = v_T − V follows the foundation's speed history all the
/// same: V(t) = t on [0, 1] (a table on V = 1), the mass unloaded and at
/// rest, so w = −t at every step (0 at t = 0, stuck there), every scheme.
#[test]
fn a_surface_without_friction_slips_at_the_foundations_speed_of_the_time() {
    let mut settings = solvers(0.1);
    settings.push((
        "quasi-static",
        Settings::new(Scheme::QuasiStatic, 1e-3, 0.1),
    ));
    for (name, settings) in settings {
        let mut surface = sdof::surface(1e-2).unwrap();
        surface.nodes[0].bound = 0.0;
        surface.set_foundation(|_| 1.0);
        let mut i = sdof::with_surface(0.0, surface, settings).unwrap();
        assert!(!i.friction(), "{name}");
        i.set_foundation_histories(&[History::Table(vec![(0.0, 0.0), (1.0, 1.0)])])
            .unwrap();
        let (mut w, mut state) = ([f64::NAN], [9_i8]);
        i.slip_velocity(&mut w);
        i.slip_states(&mut state);
        assert_eq!((w[0], state[0]), (0.0, 0), "{name}");
        while !i.done() {
            i.step().unwrap();
            i.slip_velocity(&mut w);
            assert_eq!(i.displacement()[0], 0.0, "{name}");
            assert!(
                (w[0] + i.time()).abs() < 1e-15,
                "{name}: t = {}: w = {}",
                i.time(),
                w[0]
            );
        }
    }
}
