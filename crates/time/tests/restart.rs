//! Checkpoint and restore: a run interrupted after step k and continued by a
//! fresh integrator from the checkpoint reaches bit-identically the state of
//! the uninterrupted run (the restart contract of the cli). Expected values
//! come from the uninterrupted run of the same case, not from constants.

use stickslip_testkit::paper_slab;
use stickslip_time::{Checkpoint, History, Integrator, Scheme, Settings, StickReduction};

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

fn settings(scheme: Scheme, t_end: f64) -> Settings {
    if scheme == NEWMARK {
        let mut s = Settings::new(scheme, 5e-3, t_end);
        s.stick_reduction = Some(StickReduction {
            dt: 1e-7,
            steps: 10,
        });
        s
    } else {
        Settings::new(scheme, 1e-3, t_end)
    }
}

fn finish(i: &mut Integrator) {
    while !i.done() {
        i.step().expect("step converges");
    }
}

fn assert_same_state(a: &Integrator, b: &Integrator, what: &str) {
    assert_eq!(a.steps(), b.steps(), "{what}: steps");
    assert_eq!(a.time().to_bits(), b.time().to_bits(), "{what}: t");
    assert_eq!(a.displacement(), b.displacement(), "{what}: r");
    assert_eq!(a.velocity(), b.velocity(), "{what}: ṙ");
    assert_eq!(a.acceleration(), b.acceleration(), "{what}: r̈");
    assert_eq!(a.classes(), b.classes(), "{what}: classes");
    assert_eq!(a.energy(), b.energy(), "{what}: energy ledger");
    assert_eq!(
        a.total_iterations(),
        b.total_iterations(),
        "{what}: iterations"
    );
}

#[test]
fn restored_runs_are_bit_identical_to_uninterrupted_ones() {
    for scheme in [Scheme::CentralDifference, NEWMARK, Scheme::QuasiStatic] {
        let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
        let mut whole = s.integrator(settings(scheme, 0.5)).unwrap();
        finish(&mut whole);
        assert!(whole.steps() > 100, "{scheme:?}: the run must be long");

        // Checkpoints early, in the middle (after node 81 slipped) and
        // during a reduced-step phase for Newmark.
        for k in [1_u64, 37, whole.steps() / 2, whole.steps() - 3] {
            let mut first = s.integrator(settings(scheme, 0.5)).unwrap();
            while first.steps() < k {
                first.step().unwrap();
            }
            let c: Checkpoint = first.checkpoint();
            assert_eq!(c.steps, k);

            // Same t_end.
            let mut second = s.integrator(settings(scheme, 0.5)).unwrap();
            second.restore(&c).unwrap();
            assert_eq!(second.checkpoint(), c, "{scheme:?} k = {k}: round trip");
            finish(&mut second);
            assert_same_state(&whole, &second, &format!("{scheme:?} k = {k}"));

            // Built to be restored: no static solve (its factor of K),
            // the same continuation.
            let mut restoring = settings(scheme, 0.5);
            restoring.restoring = true;
            let mut fourth = s.integrator(restoring).unwrap();
            assert!(
                fourth.displacement().iter().all(|&x| x == 0.0),
                "no static state solved for"
            );
            fourth.restore(&c).unwrap();
            finish(&mut fourth);
            assert_same_state(&whole, &fourth, &format!("{scheme:?} k = {k}, restoring"));

            // A fresh integrator built for a shorter run, extended.
            let mut third = s.integrator(settings(scheme, c.t + 1e-2)).unwrap();
            third.restore(&c).unwrap();
            third.set_t_end(0.5);
            finish(&mut third);
            assert_same_state(&whole, &third, &format!("{scheme:?} k = {k}, set_t_end"));
        }
    }
}

#[test]
fn a_checkpoint_of_another_model_is_refused() {
    let q2 = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let q1 = paper_slab("slab-q1-32x8.msh", 1e-4, History::Step);
    let c = q2
        .integrator(settings(Scheme::CentralDifference, 0.5))
        .unwrap()
        .checkpoint();
    let mut other = q1
        .integrator(settings(Scheme::CentralDifference, 0.5))
        .unwrap();
    let e = other.restore(&c).unwrap_err().to_string();
    assert!(e.contains("free DOFs"), "{e}");
    let mut bad = c.clone();
    bad.classes[0] = 3;
    let mut same = q2
        .integrator(settings(Scheme::CentralDifference, 0.5))
        .unwrap();
    let e = same.restore(&bad).unwrap_err().to_string();
    assert!(e.contains("class code 3"), "{e}");
}

/// With Rayleigh damping central difference keeps K r of the current
/// state for the stiffness part's half-step velocity; a restored run forms
/// it again from the checkpoint's r, and still continues bit-identically
/// (both schemes, the ledger's damped energy included).
#[test]
fn damped_runs_restore_bit_identically() {
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
        let damped = || {
            let mut set = settings(scheme, 0.1);
            set.damping = stickslip_time::Rayleigh {
                alpha: 2.0,
                beta: 1e-4,
            };
            set
        };
        let mut whole = s.integrator(damped()).unwrap();
        finish(&mut whole);
        assert!(whole.energy().damped > 0.0);
        let k = whole.steps() / 2;
        let mut first = s.integrator(damped()).unwrap();
        while first.steps() < k {
            first.step().unwrap();
        }
        let mut second = s.integrator(damped()).unwrap();
        second.restore(&first.checkpoint()).unwrap();
        finish(&mut second);
        assert_same_state(&whole, &second, &format!("{scheme:?} damped, k = {k}"));
    }
}
