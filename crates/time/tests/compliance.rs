//! The normal-compliance law in the explicit scheme (METHOD.md §10) on the
//! bar impact of Hughes et al. (the test kit's `impact`): the rigid wall's
//! closed form is a contact of 2L/c at the stress ρcv₀ = v₀, the bar
//! leaving at −v₀.

use stickslip_contact::Compliance;
use stickslip_testkit::impact::{run, wall, C, L, V0};
use stickslip_testkit::scene::SceneError;
use stickslip_time::TimeError;

/// As the wall stiffens, the contact time approaches 2L/c: the error falls
/// at each step of c_n (40 cells, Courant 0.5); at c_n = E/h the run is
/// within the mesh's resolution of the rigid wall's closed form.
#[test]
fn bar_impact_approaches_the_rigid_wall() {
    let rigid_time = 2.0 * L / C;
    let mut last = f64::INFINITY;
    for cn in [0.1, 0.3, 1.0, 3.0] {
        let r = run(40, wall(40, cn), 0.5).unwrap();
        let error = (r.contact_time - rigid_time).abs();
        assert!(
            error < last,
            "c_n = {cn}: contact time {} (2L/c = {rigid_time}) not closer than at the softer wall ({last})",
            r.contact_time
        );
        last = error;
    }
    let r = run(40, wall(40, 1.0), 0.5).unwrap();
    // Release is resolved to a few cells' crossing times, 4h/c = 0.1; the
    // plateau stress ρcv₀ and the exit speed v₀ to 2% (the dispersion of
    // the mesh and the step); the ledger to 1% of the kinetic energy.
    assert!((r.contact_time - rigid_time).abs() < 0.1, "{r:?}");
    assert!((r.stress - V0).abs() < 0.02 * V0, "{r:?}");
    assert!((r.exit_velocity + V0).abs() < 0.02 * V0, "{r:?}");
    assert!(r.balance < 1e-2, "{r:?}");
}

/// The critical step includes the wall's springs: a Δt just above the
/// estimate with them is refused at the start.
#[test]
fn a_step_above_the_walls_critical_step_is_refused() {
    let r = run(20, wall(20, 10.0), 1.0).unwrap();
    match run(20, wall(20, 10.0), 1.02) {
        Err(SceneError::Time(TimeError::Unstable { dt_crit, .. })) => {
            assert_eq!(dt_crit.to_bits(), r.dt_crit.to_bits());
        }
        other => panic!("expected the refusal, got {other:?}"),
    }
    // Without the springs, 1-D Q1 with the lumped mass: Δt_crit = h/c =
    // 0.05; the wall (ten times a cell's stiffness) lowers it.
    let soft = run(20, wall(20, 1e-9), 0.5).unwrap();
    assert!((soft.dt_crit - 0.05).abs() < 1e-3, "{soft:?}");
    assert!(r.dt_crit < 0.6 * soft.dt_crit, "{r:?}");
}

/// m_n > 1: the stiffness grows with the approach, and a step whose Δt the
/// deepening contact makes unstable stops with the reason.
#[test]
fn a_wall_stiffening_past_the_step_stops_the_run() {
    let law = Compliance {
        cn: 1e6,
        mn: 2.0,
        ct: 0.0,
        mt: 2.0,
    };
    match run(20, law, 0.95) {
        Err(SceneError::Time(TimeError::Settings(m))) => {
            assert!(
                m.contains("contact stiffness") && m.contains("reduce time.dt"),
                "{m}"
            );
        }
        other => panic!("expected the stop, got {other:?}"),
    }
    // A gentle wall of the same power runs through and lets the bar go.
    let gentle = Compliance { cn: 100.0, ..law };
    let r = run(20, gentle, 0.5).unwrap();
    assert!((r.exit_velocity + V0).abs() < 0.05 * V0, "{r:?}");
}

/// A block pressed by p onto a compliant floor settles at the approach
/// (p/c_n)^{1/m_n} = 0.01 (p = 10), linear and quadratic.
#[test]
fn a_pressed_block_settles_at_the_static_approach() {
    for (cn, mn) in [(1e3, 1.0), (1e5, 2.0)] {
        let (most, least) = stickslip_testkit::settle::settle(8, cn, mn).unwrap();
        let expected = (stickslip_testkit::settle::P / cn).powf(1.0 / mn);
        for d in [most, least] {
            assert!((d - expected).abs() < 1e-9, "m_n = {mn}: {d} vs {expected}");
        }
    }
}

/// A run restored from a checkpoint taken in contact continues bit for
/// bit: the bounds and forces follow the restored displacement.
#[test]
fn a_restored_run_continues_bit_identically() {
    let bar = stickslip_testkit::impact::Bar::new(20, wall(20, 10.0)).unwrap();
    let dt = 0.5 * bar.dt_crit().unwrap();
    let mut a = bar.integrator(dt, false).unwrap();
    // Into the contact (it lasts 2L/c = 2).
    while a.time() < 1.0 {
        a.step().unwrap();
    }
    let checkpoint = a.checkpoint();
    let mut b = bar.integrator(dt, false).unwrap();
    b.restore(&checkpoint).unwrap();
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    while !a.done() {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(
            bits(a.displacement()),
            bits(b.displacement()),
            "t = {}",
            a.time()
        );
        assert_eq!(a.energy(), b.energy());
    }
}
