//! A 1-D wave: the slab with ν = 0, rollers on top and bottom, held at x = 0,
//! a step traction −p at x = L, no friction. Every section moves as a bar
//! with c = √(E/ρ) (ν = 0 makes plane strain uniaxial), so d'Alembert gives
//! the end displacement: a triangle wave between 0 and −2pL/E with period
//! 4L/c, u(L, t) = −(p c/E)·t for t ≤ 2L/c, then back to 0 at 4L/c.

use stickslip_testkit::{read_mesh, wave};
use stickslip_time::Scheme;

/// Relative L2-in-time error of u_x(L, 0) over one period against
/// d'Alembert (`wave::exact_end_displacement`, the closed form
/// above; the scene is `wave::scene`).
fn wave_error(mesh_file: &str, scheme: Scheme, dt: f64) -> f64 {
    wave::end_error(read_mesh(mesh_file).unwrap(), scheme, dt).unwrap()
}

#[test]
fn end_displacement_converges_to_dalembert() {
    let ladders: [(&str, [&str; 3]); 2] = [
        (
            "Q2",
            ["slab-q2-8x2.msh", "slab-q2-16x4.msh", "slab-q2-32x8.msh"],
        ),
        (
            "Q1",
            ["slab-q1-16x4.msh", "slab-q1-32x8.msh", "slab-q1-64x16.msh"],
        ),
    ];
    for scheme in [
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
        Scheme::CentralDifference,
    ] {
        for (order, meshes) in ladders {
            // Δt proportional to h, below every mesh's critical step.
            let errors: Vec<f64> = meshes
                .iter()
                .enumerate()
                .map(|(k, m)| wave_error(m, scheme, 2e-3 / f64::from(1 << k)))
                .collect();
            println!("{scheme:?} {order}: relative L2 errors {errors:?}");
            // Halving h and Δt halves the error of the kinked wave or
            // better: dispersion at the kinks limits the order to about 1.
            // Measured ratios 0.37-0.50 (orders 1.01-1.43, the lowest Q1 by
            // Newmark); order ≥ 0.9, ratio ≤ 2^−0.9 = 0.536, claims first
            // order (a ratio of 0.7 would let order 0.51 pass).
            let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
            assert!(
                orders.iter().all(|&p| p >= 0.9),
                "{scheme:?} {order}: errors {errors:?}, orders {orders:?}: not first order"
            );
            assert!(
                errors[2] < 0.01,
                "{scheme:?} {order}: finest error {}",
                errors[2]
            );
        }
    }
}
