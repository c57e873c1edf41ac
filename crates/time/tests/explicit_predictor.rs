//! The explicit sweep forms the next step's predictor (kernels.rs,
//! `fused_step`'s `r_next`), used when the next step has the same Δt. A run
//! whose every step forms the predictor anew — each step taken by a fresh
//! integrator restored from the previous step's checkpoint — reaches the
//! bits of the uninterrupted run, also across the Δt changes of Remark 4.3
//! and the last step's landing on t_end. Expected values come from the
//! uninterrupted run, not from constants.

mod common;
use common::*;
use stickslip_time::{History, Scheme, Settings, StickReduction};

/// The paper's mesh (one chunk: K r_K formed first) and a Q1 slab of
/// several chunks (the sweep forms K r_K, by stencil types).
#[test]
fn predictor_from_the_sweep_has_the_bits_of_pass_a() {
    for (mesh, dt, t_end) in [
        ("slab-q2-8x2.msh", 1e-3, 0.3),
        ("slab-q1-128x32.msh", 2e-4, 0.006),
    ] {
        check(mesh, dt, t_end);
    }
}

fn check(mesh: &str, dt: f64, t_end: f64) {
    let s = paper_slab(mesh, 1e-4, History::Step);
    let mut settings = Settings::new(Scheme::CentralDifference, dt, t_end);
    let reduced = dt / 4.0;
    settings.stick_reduction = Some(StickReduction {
        dt: reduced,
        steps: 5,
    });
    let mut whole = s.integrator(settings.clone()).unwrap();
    let mut reduced_steps = 0;
    while !whole.done() {
        let info = whole.step().unwrap();
        if info.dt == reduced {
            reduced_steps += 1;
        }
    }
    assert!(
        reduced_steps > 0,
        "{mesh}: no Remark 4.3 step: the test sees no Δt change"
    );

    let mut c = s.integrator(settings.clone()).unwrap().checkpoint();
    loop {
        let mut fresh = s.integrator(settings.clone()).unwrap();
        fresh.restore(&c).unwrap();
        if fresh.done() {
            assert_eq!(fresh.steps(), whole.steps());
            assert_eq!(fresh.time().to_bits(), whole.time().to_bits());
            assert_eq!(fresh.displacement(), whole.displacement(), "{mesh} r");
            assert_eq!(fresh.velocity(), whole.velocity(), "{mesh} ṙ");
            assert_eq!(fresh.acceleration(), whole.acceleration(), "{mesh} r̈");
            assert_eq!(fresh.classes(), whole.classes(), "{mesh} classes");
            assert_eq!(fresh.energy(), whole.energy(), "{mesh} energy ledger");
            break;
        }
        fresh.step().unwrap();
        c = fresh.checkpoint();
    }
}
