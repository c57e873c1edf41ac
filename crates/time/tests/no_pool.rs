//! A small model starts no threads: the paper's slab (148 free DOFs),
//! built, set up and stepped by both schemes, leaves the process with the
//! threads it had (rayon's pool, once started, keeps its workers; a start
//! costs more than the paper's whole explicit run). Alone in its test
//! binary, so that no other test starts the pool first.

use stickslip_testkit::paper_slab;
use stickslip_time::{History, Scheme, Settings};

/// The process's threads, from /proc (Linux).
fn threads() -> Option<usize> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|n| n.trim().parse().ok())
}

#[test]
fn the_paper_slab_starts_no_threads() {
    let Some(before) = threads() else {
        eprintln!("no /proc/self/status: not checked");
        return;
    };
    for (scheme, dt) in [
        (Scheme::CentralDifference, 1e-4),
        (
            Scheme::Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            1e-3,
        ),
    ] {
        let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
        let mut i = s.integrator(Settings::new(scheme, dt, 0.5)).unwrap();
        for _ in 0..20 {
            i.step().unwrap();
        }
    }
    assert_eq!(threads(), Some(before), "threads before the runs: {before}");
}
