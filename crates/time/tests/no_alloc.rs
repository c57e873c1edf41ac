//! A step allocates nothing.
//! A counting global allocator sees every allocation of every thread of this
//! test binary, which holds this one test so that nothing else runs
//! meanwhile; steps are counted after a warm-up that builds the thread pool
//! and the factors of every Δt the counted steps use.

mod common;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use common::*;
use stickslip_linalg::chunks::{CHUNK, PARALLEL_MIN};
use stickslip_time::{History, ImplicitSolver, Integrator, Scheme, Settings, StickReduction};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations during `steps` steps.
fn count(i: &mut Integrator, steps: usize) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for _ in 0..steps {
        i.step().expect("step converges");
    }
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

#[test]
fn steps_allocate_nothing() {
    // One pool for the whole test, its workers started (a job run on each)
    // before anything is counted and alive until the end: a worker that
    // starts up or exits allocates or frees on its own thread while another
    // thread counts (measured under load, with a pool per mesh: 2
    // allocations in 200 steps, in the sequential paper-mesh run and in the
    // implicit runs that follow a dropped pool).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.broadcast(|_| ());
    // Explicit: the paper's mesh (sequential passes) and a mesh of at
    // least PARALLEL_MIN whole chunks of DOFs, whose passes run on the
    // thread pool (CHUNK).
    let threaded = stickslip_time::scenes::structured_slab(192, 48, false);
    for (mesh, s) in [
        (
            "slab-q2-8x2.msh",
            paper_slab("slab-q2-8x2.msh", 1e-4, History::Step),
        ),
        (
            "Q1 192x48",
            Slab::paper(threaded, 1e-4, History::Step, true).unwrap(),
        ),
    ] {
        if mesh != "slab-q2-8x2.msh" {
            assert!(
                s.model.dofs.n_free() / CHUNK >= PARALLEL_MIN,
                "{mesh} runs on one thread"
            );
        }
        let dt = 0.5
            * s.integrator(Settings::new(Scheme::CentralDifference, 1e-9, 1.0))
                .unwrap()
                .dt_crit()
                .unwrap();
        let mut i = s
            .integrator(Settings::new(Scheme::CentralDifference, dt, 1e3))
            .unwrap();
        // Inside the pool: a parallel loop started from outside it goes
        // through rayon's injector queue, which allocates a block per 63
        // jobs (measured: 13 allocations in 200 steps = 800 passes); a
        // worker thread uses its own reusable deque.
        // The warm-up is long enough for every worker to have stolen work:
        // a worker's first stolen job initializes rayon's per-thread state
        // (measured under a concurrent 2-thread load: 2 allocations in 200
        // steps after a 5-step warm-up).
        let n = pool.install(|| {
            count(&mut i, 100);
            count(&mut i, 200)
        });
        assert_eq!(n, 0, "{mesh}: {n} allocations in 200 explicit steps");
    }
    // Implicit, Schur path (each correction), with the step reduction:
    // warm up until the normal and the reduced Δt have their factors.
    for solver in [ImplicitSolver::SchurPaths, ImplicitSolver::SchurReach] {
        let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
        let mut settings = Settings::new(
            Scheme::Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
            5e-3,
            1e3,
        );
        settings.stick_reduction = Some(StickReduction {
            dt: 1e-7,
            steps: 10,
        });
        settings.implicit_solver = solver;
        let mut i = s.integrator(settings).unwrap();
        while i.factorizations() < 2 {
            i.step().unwrap();
        }
        count(&mut i, 3);
        let n = count(&mut i, 200);
        assert_eq!(i.factorizations(), 2, "{solver:?}: no other Δt");
        assert_eq!(n, 0, "{solver:?}: {n} allocations in 200 implicit steps");
    }
}
