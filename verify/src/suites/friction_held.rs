//! The analytic suite's bodies held only by friction and Rayleigh damping
//! (METHOD.md §8): a block free in x sliding to rest and pushed then
//! released, against the rigid closed forms; damping's decays and
//! central difference's damped critical step (the runs are the test kit's
//! `block` and `damping` modules).

use stickslip_testkit::block::{slide, Block};
use stickslip_testkit::damping::{damped_threshold, mode_decay, translation_decay};
use stickslip_time::{History, Rayleigh, Scheme, Settings};

use crate::report::Report;
use crate::suites::analytic::SCHEMES;
use crate::Options;

/// The stiff block of both slides: 2 × 1, pressed by p = 10 with μ = 0.5,
/// so the friction force μpL = 10 on the mass ρLH = 2 decelerates it at
/// a = μp/(ρH) = 5.
fn block(e: f64, eps: f64) -> Block {
    Block {
        size: [2.0, 1.0],
        cells: [8, 4],
        e,
        pressure: 10.0,
        mu: 0.5,
        eps,
    }
}

/// Δt of a scheme on the block: central difference below its critical
/// step (about 4.8e-4 for E = 1e5 on 8 × 4 cells, ∝ 1/√E), Newmark 1e-3.
fn step(scheme: Scheme, e: f64) -> f64 {
    match scheme {
        Scheme::CentralDifference => 2e-4 * (1e5 / e).sqrt(),
        Scheme::Newmark { .. } | Scheme::QuasiStatic => 1e-3,
    }
}

/// Runs the rows.
pub fn run(opts: &Options, r: &mut Report) {
    slides_to_rest(opts, r);
    pushed_and_released(r);
    damping(r);
}

/// Launched at v₀ = 1: rigidly it stops after v₀/a = 0.2, having slid
/// v₀²/(2a) = 0.1 (the stop as `Slide::stop_time` measures it). The error
/// falls with 1/E (elastic ringing under the friction's shear) and ε.
fn slides_to_rest(opts: &Options, r: &mut Report) {
    let (v0, a) = (1.0, 5.0);
    let variants: &[(f64, f64)] = if opts.quick {
        &[(1e5, 1e-4)]
    } else {
        &[(1e4, 1e-3), (1e5, 1e-4)]
    };
    for (name, scheme) in SCHEMES {
        for &(e, eps) in variants {
            let case = format!("block slides to rest E={e:e} ε={eps:e} {name}");
            let b = block(e, eps);
            let dt = step(scheme, e);
            let result = b
                .scene(None)
                .and_then(|s| slide(&s, Settings::new(scheme, dt, 0.3), v0));
            match result {
                Ok(s) => {
                    let stop = v0 / a;
                    r.close(
                        &case,
                        "stop time",
                        s.stop_time,
                        stop,
                        "rigid v₀/a",
                        0.01 * stop,
                    );
                    let d = v0 * v0 / (2.0 * a);
                    r.close(
                        &case,
                        "distance slid",
                        s.distance,
                        d,
                        "rigid v₀²/(2a)",
                        0.01 * d,
                    );
                }
                Err(e) => r.holds(&case, "run completes", e.to_string(), "completes", false),
            }
        }
    }
}

/// From rest, pushed on its left end (height H = 1) by t_x = q = 20 (twice
/// μpL) for T = 0.4, the push ramped off over τ = 0.01, then released.
/// Rigid impulse balance, mass M = 2, sliding friction 10: a₁ = (q − 10)/M
/// = 5 while pushed; over the ramp v gains (qτ/2 − 10τ)/M = 0 and x gains
/// v(T)τ + (q/M)τ²/3 − (10/M)τ²/2; then it decelerates at 5 to rest,
/// sliding v²/10 more. (The push reaches the far end of the floor after
/// L/c, about 0.6 ms at E = 1e6; the friction not yet acting meanwhile adds
/// to the impulse about μpL·L/(2c), which E = 1e6 and a long push keep
/// well below 1% of the distance.)
fn pushed_and_released(r: &mut Report) {
    let (q, t_push, ramp, m, friction) = (20.0, 0.4, 0.01, 2.0, 10.0);
    let a1 = (q - friction) / m;
    let v_t = a1 * t_push;
    let x_t = 0.5 * a1 * t_push * t_push;
    let v_r = v_t + (0.5 * q * ramp - friction * ramp) / m;
    let x_r = x_t + v_t * ramp + q / m * ramp * ramp / 3.0 - friction / m * ramp * ramp / 2.0;
    let distance = x_r + v_r * v_r / (2.0 * friction / m);
    for (name, scheme) in SCHEMES {
        let case = format!("block pushed then released {name}");
        let b = block(1e6, 1e-4);
        let dt = step(scheme, 1e6);
        let history = History::Table(vec![(0.0, 1.0), (t_push, 1.0), (t_push + ramp, 0.0)]);
        let result = b
            .scene(Some((q, history)))
            .and_then(|s| slide(&s, Settings::new(scheme, dt, 0.9), 0.0));
        match result {
            Ok(s) => r.close(
                &case,
                "distance slid",
                s.distance,
                distance,
                "rigid impulse balance",
                0.01 * distance,
            ),
            Err(e) => r.holds(&case, "run completes", e.to_string(), "completes", false),
        }
    }
}

/// αM on a free block launched at v₀: the velocity's error against
/// v₀e^{−αt} over its prediction αt(αΔt)²/12 (the trapezoidal rule's) at
/// α = 4, t = 0.5, Δt = 1e-3; βK on a cantilever's lowest mode with ξ =
/// 0.02: the decay rate over ξω; and central difference's bisected damped
/// stability threshold over (2/ω_max)(√(1+ξ²) − ξ) at ξ_max = 0.5.
fn damping(r: &mut Report) {
    for (name, scheme) in SCHEMES {
        let case = format!("mass damping v₀e^(−αt) {name}");
        match translation_decay(scheme, 1e-3, 4.0, 0.5) {
            Ok([error, predicted, ..]) => r.close(
                &case,
                "error / (αt(αΔt)²/12)",
                error / predicted,
                1.0,
                "trapezoidal rule's error, O(Δt²)",
                0.02,
            ),
            Err(e) => r.holds(&case, "run completes", e.to_string(), "completes", false),
        }
        let case = format!("stiffness damping e^(−ξωt) {name}");
        match mode_decay(scheme, 0.02) {
            Ok([rate, exact, _]) => r.close(
                &case,
                "decay rate / ξω",
                rate / exact,
                1.0,
                "ξ = βω/2",
                0.01,
            ),
            Err(e) => r.holds(&case, "run completes", e.to_string(), "completes", false),
        }
    }
    // ξ_max = βω_max/2 = 0.5 with ω_max = 2/Δt_crit(undamped) of the
    // cantilever: β = Δt_crit(undamped)/2, read off the undamped run. With
    // α = 50 as well the bound is the same (the mass part is centred).
    let undamped = stickslip_testkit::damping::cantilever()
        .integrator(Settings::new(Scheme::CentralDifference, 1e-6, 1e-3))
        .ok()
        .and_then(|i| i.dt_crit());
    for alpha in [0.0, 50.0] {
        let case = format!("CD critical step, α = {alpha}, βK with ξ_max = 0.5");
        let damping = undamped.map(|u| Rayleigh {
            alpha,
            beta: 0.5 * u,
        });
        match damping.map(damped_threshold) {
            Some(Ok((threshold, predicted))) => r.close(
                &case,
                "bisected threshold / predicted",
                threshold / predicted,
                1.0,
                "(2/ω_max)(√(1+ξ²) − ξ)",
                0.01,
            ),
            Some(Err(e)) => r.holds(&case, "runs complete", e.to_string(), "complete", false),
            None => r.holds(
                &case,
                "undamped estimate",
                "none".into(),
                "an estimate",
                false,
            ),
        }
    }
}
