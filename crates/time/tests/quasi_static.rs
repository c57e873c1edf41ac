//! Quasi-static increments on the strip of `stickslip_testkit::strip`:
//! the shear-lag closed form, the energy ledger, and one factor of Δt K
//! for the whole run.

use stickslip_mesh::CellKind;
use stickslip_testkit::read_mesh;
use stickslip_testkit::scene::{Slab, END_LOAD, MU, NU, PRESSURE};
use stickslip_testkit::strip::Strip;
use stickslip_time::{History, InitialState, Integrator, Scheme, Settings};

/// The pull ramped from 0 at t = 0 to P at t = 1.
fn ramp() -> History {
    History::Table(vec![(0.0, 0.0), (1.0, 1.0)])
}

/// Runs the strip of thickness 0.05 on 40 × 2 Q1 cells to t = 1 by
/// `steps` increments with ε = 1e-6; returns the integrator at the end.
fn run(strip: &Strip, steps: u32) -> (stickslip_testkit::Slab, Integrator) {
    let slab = strip
        .scene(CellKind::Quad4, (40, 2), 1e-6, ramp())
        .expect("the strip builds");
    let settings = Settings::new(Scheme::QuasiStatic, 1.0 / f64::from(steps), 1.0);
    let mut integrator = slab.integrator(settings).expect("the run starts");
    while !integrator.done() {
        integrator.step().expect("an increment converges");
    }
    (slab, integrator)
}

/// The slip zone and the end displacement against the 1-D closed form
/// (a = P/g = 0.5, u(L) = P²/(2 g E* H) = 0.06825): the slip front within
/// one cell (h = 0.025) of a, and u(L) within 5% (H/L = 0.05: the 2-D
/// strip's shear lag through its thickness, which verify's table shows
/// shrinking with H/L).
#[test]
fn strip_matches_the_shear_lag_closed_form() {
    let strip = Strip::new(0.05);
    let (slab, integrator) = run(&strip, 20);
    let a = strip.measured_slip(&slab, &integrator);
    assert!(
        (a - strip.slip_length()).abs() <= 0.025,
        "slip length {a} vs {}",
        strip.slip_length()
    );
    let u = strip.measured_end(&slab, integrator.displacement());
    let want = strip.end_displacement();
    assert!(
        (u - want).abs() <= 0.05 * want,
        "end displacement {u} vs {want}"
    );
}

/// The ledger of a run without inertia: nothing kinetic, friction
/// dissipates, and strain energy = external work − dissipation to
/// round-off (the trapezoid rule on both works closes exactly when each
/// increment ends in equilibrium: `quasi_static.rs`); ṙ is the last
/// increment over Δt, r̈ zero; Δt K is factorized once for all 20
/// increments.
#[test]
fn ledger_closes_and_the_factor_is_reused() {
    let strip = Strip::new(0.05);
    let (_, integrator) = run(&strip, 20);
    let e = integrator.energy();
    assert_eq!(e.kinetic, 0.0);
    assert!(e.dissipated > 0.0, "{e:?}");
    assert!(e.strain > 0.0, "{e:?}");
    assert!(
        e.balance.abs() <= 1e-12 * e.external_work,
        "balance {} of work {}",
        e.balance,
        e.external_work
    );
    assert!(integrator.acceleration().iter().all(|&a| a == 0.0));
    assert_eq!(integrator.steps(), 20);
    assert_eq!(integrator.factorizations(), 1);
}

/// A start at rest (r₀ = 0, every load from t = 0 on, the contact
/// pressure included, which the static start applies before t = 0): the
/// first increment's work is done from R = 0, and the ledger still closes.
#[test]
fn a_start_at_rest_closes_the_ledger() {
    let mesh = read_mesh("slab-q2-8x2.msh").expect("committed mesh reads");
    let slab = Slab::new(mesh, NU, PRESSURE, Some(MU), 1e-4, END_LOAD, History::Step)
        .expect("scene builds");
    let mut settings = Settings::new(Scheme::QuasiStatic, 0.05, 1.0);
    settings.initial_state = InitialState::Rest;
    let mut integrator = slab.integrator(settings).expect("the run starts");
    assert!(integrator.displacement().iter().all(|&x| x == 0.0));
    while !integrator.done() {
        integrator.step().expect("an increment converges");
        let e = integrator.energy();
        assert!(
            e.balance.abs() <= 1e-10 * e.external_work.abs(),
            "t = {}: balance {} of work {}",
            integrator.time(),
            e.balance,
            e.external_work
        );
    }
}
