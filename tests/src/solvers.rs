//! Every way the integrator solves a step with friction, for tests that
//! hold them all to one expected motion.

use stickslip_time::{ExplicitFriction, ImplicitSolver, Integrator, Scheme, Settings};

/// The explicit closed form, the explicit iteration, Newmark ¼, ½ by the
/// Schur complement and by refactorization (direct), at Δt to `t_end`.
pub fn every_solver(dt: f64, t_end: f64) -> Vec<(&'static str, Settings)> {
    let cd = Settings::new(Scheme::CentralDifference, dt, t_end);
    let mut iterated = cd.clone();
    iterated.explicit_friction = ExplicitFriction::Iterate;
    let nm = Settings::new(
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
        dt,
        t_end,
    );
    let mut direct = nm.clone();
    direct.implicit_solver = ImplicitSolver::Direct;
    vec![
        ("closed form", cd),
        ("explicit iteration", iterated),
        ("Schur", nm),
        ("direct", direct),
    ]
}

/// Steps two runs together to the end, asserting their classes equal at
/// every step, with `each(a, b)` after each step; returns the slipping
/// nodes counted over the run (a comparison where nothing slips tests no
/// friction).
///
/// # Panics
/// A failed step or classes that differ, as a test should.
pub fn in_step(
    mut a: Integrator,
    mut b: Integrator,
    mut each: impl FnMut(&Integrator, &Integrator),
) -> usize {
    let mut slipping = 0;
    while !a.done() {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(a.classes(), b.classes(), "t = {}", a.time());
        slipping += a.classes().iter().filter(|c| !c.is_stuck()).count();
        each(&a, &b);
    }
    slipping
}
