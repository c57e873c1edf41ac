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
//!
//! The closed form and the oscillator are `stickslip_testkit::sdof`
//! (shared with `cargo xtask verify`); the first test checks the closed form
//! against the statement above.

use stickslip_testkit::sdof::closed_form;
use stickslip_time::Scheme;

/// Largest |x − x_exact| over the run, and x(1).
fn max_error(p: f64, eps: f64, scheme: Scheme, dt: f64) -> (f64, f64) {
    stickslip_testkit::sdof::max_error(p, eps, scheme, dt).unwrap()
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
