//! A friction bound that changes every step (`Integrator::
//! set_pressure_histories`) reaches every way of solving a step: on the
//! paper's slab with its pressure ramped from 1 to 0.2 over the run, the
//! explicit closed form equals the iteration, and the implicit Schur path
//! equals the direct path (A₀ + C refactorized), to the round-off the
//! constant-pressure tests hold them to (tests/paper.rs, tests/schur.rs);
//! a restart continues such a run bit for bit; and the bounds are those of
//! the history at each step's end.

use stickslip_testkit::paper_slab;
use stickslip_testkit::solvers::in_step;
use stickslip_time::{ExplicitFriction, History, ImplicitSolver, Integrator, Scheme, Settings};

/// θ(t): 1 at t = 0, 0.2 at t = 0.5, linear between.
fn ramp() -> History {
    History::Table(vec![(0.0, 1.0), (0.5, 0.2)])
}

fn run(settings: Settings) -> Integrator {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let mut i = s.integrator(settings).unwrap();
    i.set_pressure_histories(&[ramp()]).unwrap();
    i
}

/// Largest |ṙ_a − ṙ_b| over the run, the classes equal at every step.
fn worst_difference(a: Integrator, b: Integrator) -> f64 {
    let mut worst: f64 = 0.0;
    let slipping = in_step(a, b, |a, b| {
        for (x, y) in a.velocity().iter().zip(b.velocity()) {
            worst = worst.max((x - y).abs());
        }
    });
    assert!(slipping > 0, "the run must slip somewhere");
    worst
}

#[test]
fn a_changing_bound_reaches_every_solver() {
    let cd = Settings::new(Scheme::CentralDifference, 1e-3, 0.5);
    let mut iterated = cd.clone();
    iterated.explicit_friction = ExplicitFriction::Iterate;
    let worst = worst_difference(run(cd), run(iterated));
    // Velocities are O(1); 1e-12 is round-off over 500 steps.
    assert!(worst < 1e-12, "closed form against iteration: {worst:e}");

    let nm = Settings::new(
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
        5e-3,
        0.5,
    );
    let mut direct = nm.clone();
    direct.implicit_solver = ImplicitSolver::Direct;
    let worst = worst_difference(run(nm), run(direct));
    assert!(worst < 1e-10, "Schur against direct: {worst:e}");
}

#[test]
fn the_bounds_follow_the_history_and_a_restart_continues_bit_for_bit() {
    let settings = Settings::new(Scheme::CentralDifference, 1e-3, 0.5);
    let mut whole = run(settings.clone());
    let g0: Vec<f64> = whole
        .contact()
        .unwrap()
        .nodes
        .iter()
        .map(|n| n.bound)
        .collect();
    let mut checkpoint = None;
    while !whole.done() {
        whole.step().unwrap();
        // g = g₀ θ(t) at the step's end, θ(t) = 1 − 1.6 t.
        let theta = 1.0 - 1.6 * whole.time();
        for (n, g) in whole.contact().unwrap().nodes.iter().zip(&g0) {
            assert!(
                (n.bound - g * theta).abs() < 1e-12 * g,
                "t = {}",
                whole.time()
            );
        }
        if whole.steps() == 200 {
            checkpoint = Some(whole.checkpoint());
        }
    }
    let mut restarted = run(settings);
    restarted.restore(&checkpoint.unwrap()).unwrap();
    while !restarted.done() {
        restarted.step().unwrap();
    }
    let bits = |i: &Integrator| {
        i.displacement()
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&restarted), bits(&whole));
    assert_eq!(restarted.steps(), whole.steps());
}
