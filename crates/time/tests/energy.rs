//! Energy conservation without friction: Newmark ¼, ½ (the trapezoidal
//! rule) conserves E = ½ṙᵀMṙ + ½rᵀKr − rᵀR exactly for a constant load;
//! central difference keeps it within a band that shrinks as Δt².

use stickslip_testkit::{read_mesh, Slab};
use stickslip_time::{History, Scheme, Settings};

/// Largest |E_K − E_0| of the frictionless slab (pressure and end load on,
/// no contact surface) and E_0.
fn energy_drift(mesh: &str, scheme: Scheme, dt: f64) -> (f64, f64) {
    let mesh = read_mesh(mesh).unwrap();
    let s = Slab::paper(mesh, 1.0, History::Step, false).unwrap();
    let mut i = s.integrator(Settings::new(scheme, dt, 0.5)).unwrap();
    let e0 = i.energy().total;
    let mut drift: f64 = 0.0;
    while !i.done() {
        i.step().unwrap();
        drift = drift.max((i.energy().total - e0).abs());
    }
    (drift, e0)
}

#[test]
fn newmark_trapezoidal_conserves_total_energy() {
    for mesh in ["slab-q2-8x2.msh", "slab-q1-16x4.msh"] {
        let (drift, e0) = energy_drift(
            mesh,
            Scheme::Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            5e-3,
        );
        assert!(
            drift <= 1e-9 * e0.abs(),
            "{mesh}: drift {drift} of |E0| = {}",
            e0.abs()
        );
    }
}

#[test]
fn central_difference_energy_band_shrinks_as_dt_squared() {
    let (coarse, _) = energy_drift("slab-q2-8x2.msh", Scheme::CentralDifference, 1e-3);
    let (fine, _) = energy_drift("slab-q2-8x2.msh", Scheme::CentralDifference, 5e-4);
    let ratio = coarse / fine;
    println!("central difference energy band: {coarse:.3e} at 1e-3, {fine:.3e} at 5e-4, ratio {ratio:.2}");
    // Second order: halving Δt divides the band by 4 (±25%).
    assert!((3.0..=5.0).contains(&ratio), "band ratio {ratio}");
    // paper.rs allows the friction runs a step-to-step rise of 0.05 at
    // Δt = 1e-3: the whole frictionless band must sit below that.
    assert!(coarse < 0.05, "band {coarse} at Δt = 1e-3");
}
