//! μ falling with the slip speed in the implicit steps (METHOD.md §9,
//! μ(w) = μk + (μs − μk) e^{−|w|/vs}), taken at each node's slip of the
//! previous step (`stickslip_contact`'s `lagged_mu.rs`):
//!
//! * μs = μk moves no bit against the constant law, on the Schur and the
//!   direct Newmark paths and the quasi-static increments, with a
//!   pressure ramp that changes the bounds every step;
//! * with μs > μk the Schur path equals the direct one to round-off;
//! * quasi-statically, a mass dragged through a spring breaks away at the
//!   static bound μs·p·w, within the regularization and one increment's
//!   load, and then slides at the kinetic one's μ(U)·p·w.

use stickslip_contact::Weakening;
use stickslip_testkit::solvers::in_step;
use stickslip_testkit::{paper_slab, sdof};
use stickslip_time::{History, ImplicitSolver, Integrator, Scheme, Settings};

fn newmark(dt: f64, t_end: f64) -> Settings {
    Settings::new(
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
        dt,
        t_end,
    )
}

/// The paper's slab, its pressure ramped from 1 to 0.2 over [0, 0.5], μ
/// falling by `ratio` over vs = 0.05 (`None`: the constant law).
fn slab(ratio: Option<f64>, settings: Settings) -> Integrator {
    let mut s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    if let Some(ratio) = ratio {
        let c = s.contact.as_mut().unwrap();
        c.set_weakening(|_| Some(Weakening { ratio, speed: 0.05 }));
    }
    let mut i = s.integrator(settings).unwrap();
    i.set_pressure_histories(&[History::Table(vec![(0.0, 1.0), (0.5, 0.2)])])
        .unwrap();
    i
}

#[test]
fn equal_static_and_kinetic_mu_is_the_constant_law_bit_for_bit() {
    let mut direct = newmark(5e-3, 0.3);
    direct.implicit_solver = ImplicitSolver::Direct;
    for (name, settings) in [
        ("Schur", newmark(5e-3, 0.3)),
        ("direct", direct),
        (
            "quasi-static",
            Settings::new(Scheme::QuasiStatic, 5e-3, 0.3),
        ),
    ] {
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let slipping = in_step(
            slab(None, settings.clone()),
            slab(Some(1.0), settings),
            |a, b| {
                assert_eq!(bits(a.displacement()), bits(b.displacement()), "{name}");
                assert_eq!(bits(a.velocity()), bits(b.velocity()), "{name}");
                assert_eq!(a.energy(), b.energy(), "{name}");
                assert_eq!(a.total_iterations(), b.total_iterations(), "{name}");
                assert_eq!(a.factorizations(), b.factorizations(), "{name}");
            },
        );
        assert!(slipping > 0, "{name}: the run must slip somewhere");
    }
}

/// μk = μs/2: the Schur path against A₀ + C refactorized, to the
/// round-off the constant law's tests hold them to (tests/pressure.rs:
/// 1e-10 on velocities of order 1).
#[test]
fn schur_equals_direct_with_a_falling_mu() {
    let mut direct = newmark(5e-3, 0.5);
    direct.implicit_solver = ImplicitSolver::Direct;
    let mut worst: f64 = 0.0;
    let slipping = in_step(
        slab(Some(0.5), newmark(5e-3, 0.5)),
        slab(Some(0.5), direct),
        |a, b| {
            for (x, y) in a.velocity().iter().zip(b.velocity()) {
                worst = worst.max((x - y).abs());
            }
        },
    );
    assert!(slipping > 0, "the run must slip somewhere");
    assert!(worst < 1e-10, "Schur against direct: {worst:e}");
}

/// The oscillator's mass (k = 100, w = 1, g = μs p = 1) with no inertia,
/// its spring's far end dragged at U = 1 from t = 0: k x + f(ẋ) = k U t.
/// μk/μs = 0.5, vs = 0.05, ε = 1e-4, Δt = 1e-4 (one increment's load
/// k U Δt = 0.01 g).
///
/// * Stuck, a node creeps at most ε, so f ≤ g μ(|w|)/μs ≤ g; it slips once
///   the spring's force passes g μ(ε)/μs + k Δt ε: the last stuck
///   increment's force F = k(U t − x) is within g(1 − μ(ε)/μs) + kUΔt +
///   kΔtε of g = μs p w (the constant law at μk would break away at 0.5).
/// * Then it slides at the drag's speed, ẋ → U, the force g μ(U)/μs =
///   0.5 + 0.5 e^{−20}: at t = 0.05, to 1e-9 of g (the lagged μ's error
///   decays by g (1 − r) e^{−U/vs}/(vs k Δt) = 2e-6 an increment there).
#[test]
fn a_dragged_mass_breaks_away_at_static_and_slides_at_kinetic_friction() {
    let (k, u, g) = (sdof::K, 1.0, sdof::G);
    let (ratio, vs, eps, dt, t_end) = (0.5, 0.05, 1e-4, 1e-4, 0.05);
    let mu = |w: f64| ratio + (1.0 - ratio) * (-w / vs).exp();
    let mut surface = sdof::surface(eps).unwrap();
    surface.set_weakening(|_| Some(Weakening { ratio, speed: vs }));
    let drag = History::Table(vec![(0.0, 0.0), (1.0, 1.0)]);
    let settings = Settings::new(Scheme::QuasiStatic, dt, t_end);
    let mut i = sdof::with_load(k * u, drag, surface, settings).unwrap();
    let force = |i: &Integrator| k * (u * i.time() - i.displacement()[0]);
    let mut break_away = None;
    let mut last_stuck = force(&i);
    while !i.done() {
        i.step().unwrap();
        if i.classes()[0].is_stuck() {
            assert!(break_away.is_none(), "sticks again at t = {}", i.time());
            last_stuck = force(&i);
        } else if break_away.is_none() {
            break_away = Some(last_stuck);
        }
    }
    let f = break_away.expect("the mass breaks away");
    let within = g * (1.0 - mu(eps)) + k * u * dt + k * dt * eps;
    assert!(
        f <= g * (1.0 + 1e-12) && g - f <= within,
        "break-away at {f}, g = {g}"
    );
    let kinetic = g * mu(u);
    let late = force(&i);
    assert!(
        (late - kinetic).abs() <= 1e-9 * g,
        "sliding at {late}, μ(U) p w = {kinetic}"
    );
    assert!((i.velocity()[0] - u).abs() <= 1e-9 * u);
}

/// The lagged μ is a function of the state a step starts from: a restart
/// from a checkpoint taken half way continues bit for bit.
#[test]
fn a_restart_continues_a_falling_mu_bit_for_bit() {
    let mut whole = slab(Some(0.5), newmark(5e-3, 0.3));
    let mut checkpoint = None;
    while !whole.done() {
        whole.step().unwrap();
        if whole.steps() == 30 {
            checkpoint = Some(whole.checkpoint());
        }
    }
    let mut restarted = slab(Some(0.5), newmark(5e-3, 0.3));
    restarted.restore(&checkpoint.unwrap()).unwrap();
    while !restarted.done() {
        restarted.step().unwrap();
    }
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(whole.displacement()), bits(restarted.displacement()));
    assert_eq!(bits(whole.velocity()), bits(restarted.velocity()));
    assert_eq!(whole.energy(), restarted.energy());
}

/// The ledger books the forces the steps applied (μ of the last step's
/// slip), so Newmark ¼, ½ closes it to round-off with μ falling as with
/// the constant law (tests/foundation.rs): the oscillator on a belt at
/// V = 0.05 with μk/μs = 0.6, vs = 1e-3, whose stick-slip cycles (the
/// belt verify suite's) stick and slip many times in t = 2.
#[test]
fn newmark_closes_the_ledger_with_a_falling_mu() {
    let mut surface = sdof::surface(1e-4).unwrap();
    surface.set_foundation(|_| 0.05);
    surface.set_weakening(|_| {
        Some(Weakening {
            ratio: 0.6,
            speed: 1e-3,
        })
    });
    let mut i = sdof::with_surface(0.0, surface, newmark(1e-4, 2.0)).unwrap();
    i.step().unwrap();
    let first = i.energy().balance;
    let (mut sticks, mut stuck) = (0, i.classes()[0].is_stuck());
    while !i.done() {
        i.step().unwrap();
        let now = i.classes()[0].is_stuck();
        sticks += usize::from(now && !stuck);
        stuck = now;
    }
    assert!(sticks >= 3, "{sticks} sticks");
    let e = i.energy();
    let drift = e.balance - first;
    // Energies of order g²/k = 1e-2; 1e-12 is round-off over 2e4 steps.
    assert!(drift.abs() < 1e-12, "balance moved {drift:e}");
    assert!(e.dissipated > 0.0 && e.foundation > 0.0);
}
