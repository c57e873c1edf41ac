//! The time of each step: t_k = k Δt over a run of equal steps, so a run
//! of t_end / Δt steps takes exactly that many, lands on t_end and keeps
//! one factorization. Summing Δt step by step drifted and, past 1e5 steps,
//! added a sliver of a last step (Δt ≈ 1e-10) and a second factorization.

use stickslip_testkit::paper_slab;
use stickslip_time::{History, Scheme, Settings, StickReduction};

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// Runs to t_end: (every step's Δt, every step's end time, factorizations).
fn run(settings: Settings) -> (Vec<f64>, Vec<f64>, u64) {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let mut i = s.integrator(settings).unwrap();
    let (mut dts, mut ts) = (Vec::new(), Vec::new());
    while !i.done() {
        dts.push(i.step().expect("step converges").dt);
        ts.push(i.time());
    }
    (dts, ts, i.factorizations())
}

#[test]
fn a_whole_number_of_steps_lands_on_t_end_without_drift() {
    // 1e-3 and 1e-4 have no exact binary form: their sums drift.
    for (scheme, dt, steps) in [
        (Scheme::CentralDifference, 1e-3, 30_000_u64),
        (NEWMARK, 1e-4, 20_000),
    ] {
        let t_end = steps as f64 * dt;
        let (dts, ts, factorizations) = run(Settings::new(scheme, dt, t_end));
        assert_eq!(dts.len() as u64, steps, "{scheme:?}: steps");
        assert!(dts.iter().all(|&d| d == dt), "{scheme:?}: every Δt");
        for (k, &t) in ts.iter().enumerate() {
            let expected = if k as u64 + 1 == steps {
                t_end
            } else {
                (k + 1) as f64 * dt
            };
            assert_eq!(t.to_bits(), expected.to_bits(), "{scheme:?}: t of step {k}");
        }
        if scheme == NEWMARK {
            assert_eq!(factorizations, 1, "one Δt, one factorization");
        }
    }
}

#[test]
fn a_t_end_between_steps_shortens_only_the_last() {
    let (dts, ts, _) = run(Settings::new(Scheme::CentralDifference, 1e-3, 0.1004));
    assert_eq!(dts.len(), 101);
    assert!(dts[..100].iter().all(|&d| d == 1e-3));
    assert!((dts[100] - 4e-4).abs() < 1e-15, "last Δt {}", dts[100]);
    assert_eq!(ts[100], 0.1004);
}

#[test]
fn reduced_steps_start_a_new_count() {
    // Newmark with Remark 4.3's reduction: runs of the reduced Δt between
    // runs of the normal one; each run's times are its start plus k Δt.
    let mut settings = Settings::new(NEWMARK, 5e-3, 0.5);
    settings.stick_reduction = Some(StickReduction {
        dt: 1e-4,
        steps: 10,
    });
    let (dts, ts, _) = run(settings);
    assert!(
        dts.contains(&1e-4),
        "the scene sticks, so the reduced step runs"
    );
    let (mut start, mut k, mut prev_dt, mut t_prev) = (0.0, 0u32, f64::NAN, 0.0);
    for (j, (&dt, &t)) in dts.iter().zip(&ts).enumerate() {
        if dt != prev_dt {
            (start, k, prev_dt) = (t_prev, 0, dt);
        }
        k += 1;
        if j + 1 < ts.len() {
            assert_eq!(t.to_bits(), (start + k as f64 * dt).to_bits(), "step {j}");
        }
        t_prev = t;
    }
    assert_eq!(*ts.last().unwrap(), 0.5);
}
