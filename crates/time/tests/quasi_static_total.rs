//! The total energy at t = 0 of a quasi-static run is strain −
//! rᵀR(0) with the load at t = 0 itself, a load that switches on at t = 0
//! included (docs/results.md), as the dynamic schemes report it: on the
//! paper's slab, whose end traction is a step at t = 0, from the same
//! static preload r₀.

use stickslip_testkit::scene::paper_slab;
use stickslip_time::{History, Scheme, Settings};

#[test]
fn the_initial_total_counts_a_load_that_starts_at_zero() {
    let slab = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let totals: Vec<(f64, f64)> = [Scheme::CentralDifference, Scheme::QuasiStatic]
        .into_iter()
        .map(|scheme| {
            let i = slab
                .integrator(Settings::new(scheme, 1e-3, 0.01))
                .expect("the run starts");
            let e = i.energy();
            (e.total, e.strain)
        })
        .collect();
    let [(dynamic, strain_d), (quasi, strain_q)] = totals[..] else {
        unreachable!("two schemes")
    };
    // One r₀ (the frictionless static preload), so one strain energy.
    assert_eq!(strain_d.to_bits(), strain_q.to_bits());
    // The step load's −rᵀR_step is the difference a total with the loads
    // before t = 0 would miss.
    assert!(
        (dynamic - quasi).abs() <= 1e-12 * dynamic.abs(),
        "quasi-static {quasi} against central difference {dynamic}"
    );
}
