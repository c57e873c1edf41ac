//! The explicit scheme's threaded passes give bit-identical runs on one
//! thread and on several: the work is split into fixed chunks and
//! sums are added in chunk order, whatever the number of threads.

use stickslip_linalg::chunks::{CHUNK, PARALLEL_MIN};
use stickslip_testkit::{on_threads, structured_slab, Slab};
use stickslip_time::{History, Integrator, Scheme, Settings};

fn run(s: &Slab, threads: usize, steps: usize) -> Integrator {
    on_threads(threads, || {
        assert_eq!(rayon::current_num_threads(), threads);
        let probe = s
            .integrator(Settings::new(Scheme::CentralDifference, 1e-9, 0.5))
            .unwrap();
        let dt = 0.9 * probe.dt_crit().unwrap();
        let mut i = s
            .integrator(Settings::new(Scheme::CentralDifference, dt, 0.5))
            .unwrap();
        for _ in 0..steps {
            i.step().unwrap();
        }
        i
    })
}

#[test]
fn one_thread_and_several_give_the_same_bits() {
    // At least PARALLEL_MIN whole chunks of free DOFs (CHUNK), so
    // that the passes go parallel with more than one thread (the committed
    // 128×32 slabs, 8,352 DOFs, are below it).
    for (nx, ny, q2) in [(192, 48, false), (96, 24, true)] {
        let mesh = format!("{} {nx}x{ny}", if q2 { "Q2" } else { "Q1" });
        let s = Slab::paper(structured_slab(nx, ny, q2), 1e-4, History::Step, true).unwrap();
        let whole = s.model.dofs.n_free() / CHUNK;
        assert!(whole >= PARALLEL_MIN, "{mesh} too small to thread");
        let one = run(&s, 1, 400);
        for threads in [2, 3] {
            let many = run(&s, threads, 400);
            assert_eq!(
                one.displacement(),
                many.displacement(),
                "{mesh} {threads}: r"
            );
            assert_eq!(one.velocity(), many.velocity(), "{mesh} {threads}: ṙ");
            assert_eq!(
                one.acceleration(),
                many.acceleration(),
                "{mesh} {threads}: r̈"
            );
            assert_eq!(one.classes(), many.classes(), "{mesh} {threads}: classes");
            assert_eq!(one.energy(), many.energy(), "{mesh} {threads}: energy");
        }
        // The run did something: the end moved and friction slipped.
        assert!(one.classes().iter().any(|c| !c.is_stuck()) || one.energy().dissipated > 0.0);
    }
}
