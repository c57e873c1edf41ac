//! A single mass on a spring with Coulomb friction under a step force: the
//! regularized solution against the closed form as ε → 0, both schemes.
//!
//! m = 1, k = 100 (ω = 10), friction force g = 1, x(0) = ẋ(0) = 0, force P
//! from t = 0. Closed form (exact Coulomb): from rest at x_i the mass moves
//! if |P − k x_i| > g, along x_e + (x_i − x_e) cos ω(t − t_i) with
//! x_e = (P − s g)/k, s = sign(P − k x_i), for half a period π/ω; then it is
//! at rest again at 2x_e − x_i. P = 2.5 slips once on [0, π/10] and sticks
//! at 0.03; P = 5 slips forward to 0.08, back to 0.04 and sticks; P = 0.8
//! never moves.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_contact::{ContactNode, ContactSurface};
use stickslip_time::{Dynamics, History, Integrator, Load, Scheme, Settings};

const K: f64 = 100.0;
const G: f64 = 1.0;
const OMEGA: f64 = 10.0;

/// Exact Coulomb displacement at time t.
fn closed_form(p: f64, t: f64) -> f64 {
    let half = std::f64::consts::PI / OMEGA;
    let (mut x, mut t0) = (0.0, 0.0);
    loop {
        let f = p - K * x;
        if f.abs() <= G + 1e-12 {
            return x; // stuck for good: the load is constant
        }
        let xe = (p - f.signum() * G) / K;
        if t <= t0 + half {
            return xe + (x - xe) * (OMEGA * (t - t0)).cos();
        }
        x = 2.0 * xe - x;
        t0 += half;
    }
}

fn one_dof(p: f64, eps: f64, scheme: Scheme, dt: f64, t_end: f64) -> Integrator {
    let scalar = |v: f64| {
        let mut coo = CooMatrix::new(1, 1);
        coo.push(0, 0, v);
        CsrMatrix::from(&coo)
    };
    let dynamics = Dynamics {
        stiffness: scalar(K),
        consistent_mass: scalar(1.0),
        lumped_mass: vec![1.0],
        constant_load: vec![0.0],
    };
    let node = ContactNode {
        node: 0,
        dofs: [Some(0), None],
        weight: 1.0,
        tangent: [1.0, 0.0],
        s: 0.0,
        bound: G,
    };
    let surface = ContactSurface::from_nodes("mass", vec![node], eps).unwrap();
    let loads = vec![Load {
        vector: vec![p],
        history: History::Step,
    }];
    Integrator::new(
        dynamics,
        Some(surface),
        loads,
        Settings::new(scheme, dt, t_end),
    )
    .unwrap()
}

/// Largest |x − x_exact| over the run.
fn max_error(p: f64, eps: f64, scheme: Scheme, dt: f64) -> (f64, f64) {
    let mut i = one_dof(p, eps, scheme, dt, 1.0);
    let mut err: f64 = 0.0;
    while !i.done() {
        i.step().unwrap();
        err = err.max((i.displacement()[0] - closed_form(p, i.time())).abs());
    }
    (err, i.displacement()[0])
}

const SCHEMES: [Scheme; 2] = [
    Scheme::CentralDifference,
    Scheme::Newmark {
        beta: 0.25,
        gamma: 0.5,
    },
];

#[test]
fn closed_form_itself_stops_where_the_statement_says() {
    assert!((closed_form(2.5, 10.0) - 0.03).abs() < 1e-14);
    assert!((closed_form(5.0, 10.0) - 0.04).abs() < 1e-14);
    assert_eq!(closed_form(0.8, 10.0), 0.0);
}

#[test]
fn regularized_solution_converges_to_coulomb_as_eps_shrinks() {
    // Δt small enough that the time error (O(Δt) at the stick/slip kinks)
    // stays well below the smallest ε error measured.
    let dt = 2e-6;
    let epsilons = [1e-2, 1e-3, 1e-4];
    for scheme in SCHEMES {
        for p in [2.5, 5.0, 0.8] {
            let errors: Vec<f64> = epsilons
                .iter()
                .map(|&e| max_error(p, e, scheme, dt).0)
                .collect();
            // Fitted order over the ladder; the theory (paper Thm 2.3)
            // guarantees O(√ε) in the energy norm, i.e. at least 0.5.
            let order = (errors[0] / errors[2]).log10() / (epsilons[0] / epsilons[2]).log10();
            println!("{scheme:?} P = {p}: errors {errors:?}, fitted order {order:.3}");
            assert!(
                order >= 0.5,
                "{scheme:?} P = {p}: order {order} below the theory's 1/2"
            );
            assert!(
                errors.windows(2).all(|w| w[1] < w[0]),
                "{scheme:?} P = {p}: errors {errors:?} not decreasing"
            );
            // At ε = 1e-4 the position is within 1e-4 of the closed form (the
            // largest amplitude here is 0.08).
            assert!(
                errors[2] < 1e-4,
                "{scheme:?} P = {p}: error {} at ε = 1e-4",
                errors[2]
            );
        }
    }
}

#[test]
fn final_rest_positions_match_the_closed_form() {
    for scheme in SCHEMES {
        for (p, rest) in [(2.5, 0.03), (5.0, 0.04), (0.8, 0.0)] {
            let (_, x) = max_error(p, 1e-5, scheme, 1e-5);
            assert!(
                (x - rest).abs() < 2e-5,
                "{scheme:?} P = {p}: x(1) = {x}, closed form {rest}"
            );
        }
    }
}
