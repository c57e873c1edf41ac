//! The explicit sweep forms the next step's predictor (kernels.rs,
//! `fused_step`'s `r_next`), used when the next step has the same Δt. A run
//! whose every step forms the predictor anew — each step taken by a fresh
//! integrator restored from the previous step's checkpoint — reaches the
//! bits of the uninterrupted run, also across the Δt changes of Remark 4.3
//! and the last step's landing on t_end. Expected values come from the
//! uninterrupted run, not from constants. On the slab of several chunks
//! the uninterrupted run also sweeps in place (ṙ_K and r̈_K written over
//! ṙ_{K−1} and r̈_{K−1}: `Integrator::in_place_steps`), which a restored
//! integrator's first step never does: the same bits either way.

mod common;
use common::*;
use stickslip_time::{History, Scheme, Settings, StickReduction};

/// The paper's mesh (one chunk: K r_K formed first) and a Q1 slab of
/// several chunks (the sweep forms K r_K, by stencil types).
#[test]
fn predictor_from_the_sweep_has_the_bits_of_pass_a() {
    for (mesh, dt, t_end, several_chunks) in [
        ("slab-q2-8x2.msh", 1e-3, 0.3, false),
        ("slab-q1-128x32.msh", 2e-4, 0.006, true),
    ] {
        check(mesh, dt, t_end, several_chunks);
    }
}

fn check(mesh: &str, dt: f64, t_end: f64, several_chunks: bool) {
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
    eprintln!(
        "{mesh}: {} DOFs, {} of {} steps in place",
        whole.displacement().len(),
        whole.in_place_steps(),
        whole.steps()
    );
    assert_eq!(
        whole.in_place_steps() > 0,
        several_chunks,
        "{mesh}: sweeps in place on systems of several chunks only"
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

/// A run past the critical step grows until a step forms a non-finite
/// entry and fails. The steps before it swept in place while their
/// bounds allowed; the failed one did not, so it left the state of the
/// last completed step (the architecture's invariant), bit for bit.
#[test]
fn a_blow_up_fails_with_the_last_state_kept() {
    let s = paper_slab("slab-q1-128x32.msh", 1e-4, History::Step);
    let probe = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-6, 1.0))
        .unwrap();
    let crit = probe.dt_crit().expect("explicit");
    let mut settings = Settings::new(Scheme::CentralDifference, 1.5 * crit, 1.0);
    settings.allow_unstable = true;
    let mut run = s.integrator(settings).unwrap();
    let before = loop {
        let state = (
            run.steps(),
            run.displacement().to_vec(),
            run.velocity().to_vec(),
            run.acceleration().to_vec(),
        );
        if run.step().is_err() {
            break state;
        }
        assert!(run.steps() < 5000, "no failure in 5000 steps");
    };
    eprintln!(
        "failed at step {}, {} steps in place",
        before.0 + 1,
        run.in_place_steps()
    );
    assert!(run.in_place_steps() > 0, "no step swept in place");
    assert_eq!(run.steps(), before.0);
    for (what, got, kept) in [
        ("r", run.displacement(), &before.1),
        ("ṙ", run.velocity(), &before.2),
        ("r̈", run.acceleration(), &before.3),
    ] {
        let changed = (0..kept.len()).filter(|&i| got[i].to_bits() != kept[i].to_bits());
        let changed: Vec<usize> = changed.collect();
        assert!(
            changed.is_empty(),
            "{what}: {} entries changed by the failed step, the first at {}",
            changed.len(),
            changed[0]
        );
    }
}
