//! Every way the integrator solves a step with friction, for tests that
//! hold them all to one expected motion.

use stickslip_time::{ExplicitFriction, ImplicitSolver, Scheme, Settings};

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
