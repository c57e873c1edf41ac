//! Rayleigh damping C = αM + βK against closed forms (the runs and their
//! closed forms are the test kit's `damping` module): a floating part's
//! translation decays as v₀e^{−αt}, a mode as e^{−ξωt} with ξ = βω/2; the
//! ledger's damped energy closes the balance; bad coefficients and a step
//! above the damped critical step are refused.

use stickslip_testkit::damping::{cantilever, mode_decay, settings, translation_decay};
use stickslip_time::{Rayleigh, Scheme, Settings, TimeError};

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// v₀e^{−αt}: the error is the trapezoidal rule's αt(αΔt)²/12 to 2% at
/// two Δt (so its order is the schemes'), and the ledger balances to
/// round-off with the damped energy booked.
#[test]
fn mass_proportional_damping_decays_a_translation_as_exp_minus_alpha_t() {
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        for dt in [1e-3, 5e-4] {
            let [error, predicted, balance, damped] =
                translation_decay(scheme, dt, 4.0, 0.5).unwrap();
            assert!(
                (error / predicted - 1.0).abs() < 0.02,
                "{scheme:?} Δt = {dt}: error {error:e}, predicted {predicted:e}"
            );
            assert!(balance <= 1e-9, "{scheme:?}: balance {balance:e}");
            assert!(damped > 0.0);
        }
    }
}

/// e^{−ξωt}, ξ = βω/2 = 0.02: the decay rate within 1%, the balance within
/// 1e-3 of the initial energy (the schemes' usual level at this Δt).
#[test]
fn stiffness_proportional_damping_decays_a_mode_as_exp_minus_xi_omega_t() {
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let [rate, exact, balance] = mode_decay(scheme, 0.02).unwrap();
        assert!(
            (rate / exact - 1.0).abs() < 0.01,
            "{scheme:?}: decay rate {rate}, ξω = {exact}"
        );
        assert!(balance < 1e-3, "{scheme:?}: balance {balance:e}");
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
        let exact = 2.0 / omega * ((1.0f64 + xi * xi).sqrt() - xi);
        let damping = Rayleigh { alpha, beta };
        let i = s
            .integrator(settings(
                Scheme::CentralDifference,
                0.5 * exact,
                1e-3,
                damping,
            ))
            .unwrap();
        let got = i.dt_crit().unwrap();
        assert!((got / exact - 1.0).abs() < 1e-12, "{got} vs {exact}");
    }
    let beta = 0.1 / omega;
    let xi: f64 = 0.05;
    let between = 0.5 * (undamped + 2.0 / omega * ((1.0 + xi * xi).sqrt() - xi));
    let damping = Rayleigh { alpha: 0.0, beta };
    let e = s
        .integrator(settings(Scheme::CentralDifference, between, 1e-3, damping))
        .unwrap_err();
    assert!(matches!(e, TimeError::UnstableDamped { .. }), "{e}");
    assert!(e.to_string().contains("material.damping.beta"), "{e}");
    // Negative coefficients are refused.
    let damping = Rayleigh {
        alpha: -1.0,
        beta: 0.0,
    };
    let e = s
        .integrator(settings(NEWMARK, 1e-3, 1e-2, damping))
        .unwrap_err();
    assert!(e.to_string().contains("must be finite and >= 0"), "{e}");
}
