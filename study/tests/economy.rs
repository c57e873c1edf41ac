//! Solver economy (issue 6, deliverable 4), measured with the time crate's
//! counters on the paper's slab: work done is what the scene needs.

use std::collections::BTreeSet;

use stickslip_case::{Method, PAPER_REDUCTION as REDUCTION};
use stickslip_study::slab::{self, read_mesh, LoadKind, Slab};
use stickslip_time::{ImplicitSolver, Integrator};

fn slab(mesh: &str, friction: bool) -> Slab {
    slab::paper(&read_mesh(mesh).unwrap(), 1e-4, LoadKind::Step, friction).unwrap()
}

/// Runs to the end; returns the distinct step sizes (bit patterns) and the
/// number of steps in which the stuck set or Δt changed from the step
/// before.
fn run(i: &mut Integrator) -> (BTreeSet<u64>, u64) {
    let mut dts = BTreeSet::new();
    let mut changes = 0;
    let mut last: Option<(u64, Vec<bool>)> = None;
    while !i.done() {
        let info = i.step().unwrap();
        dts.insert(info.dt.to_bits());
        let stuck: Vec<bool> = i.classes().iter().map(|c| c.is_stuck()).collect();
        let key = (info.dt.to_bits(), stuck);
        if last.as_ref() != Some(&key) {
            changes += 1;
        }
        last = Some(key);
    }
    (dts, changes)
}

#[test]
fn a_scene_without_a_contact_group_runs_no_friction_code() {
    for method in [Method::CentralDifference, Method::TrapezoidalReduced] {
        let s = slab("slab-q2-8x2.msh", false);
        let dt = if method == Method::CentralDifference {
            1e-3
        } else {
            5e-3
        };
        let mut i = s.integrator(method.settings(dt, 0.5)).unwrap();
        assert!(i.contact().is_none(), "{method:?}: no contact surface");
        run(&mut i);
        // One linear solve (implicit) or one pass (explicit) per step: no
        // stick/slip iteration ran (StepInfo: "1 without contact").
        assert_eq!(i.total_iterations(), i.steps(), "{method:?}");
        assert!(i.classes().is_empty(), "{method:?}: no friction nodes");
        // No friction: nothing dissipated (METHOD.md §6).
        assert_eq!(i.energy().dissipated, 0.0, "{method:?}");
    }
}

#[test]
fn an_implicit_run_factorizes_once_per_distinct_dt() {
    // The Schur-complement path (the default) factorizes A₀ once per
    // distinct Δt and never for a change of the stuck set; the
    // reduction of Remark 4.3 alternates the normal and the reduced step,
    // both kept (the last step may be a third, shortened Δt).
    for mesh in ["slab-q2-8x2.msh", "slab-q1-32x8.msh"] {
        let s = slab(mesh, true);
        for method in [
            Method::Trapezoidal,
            Method::TrapezoidalReduced,
            Method::Damped,
        ] {
            let mut i = s.integrator(method.settings(5e-3, 0.5)).unwrap();
            assert!(!i.is_explicit());
            assert_eq!(i.implicit_solver(), ImplicitSolver::Schur, "{mesh}");
            let (dts, changes) = run(&mut i);
            assert_eq!(
                i.factorizations(),
                dts.len() as u64,
                "{mesh} {method:?}: factorizations against distinct Δt"
            );
            if method == Method::TrapezoidalReduced {
                assert!(
                    dts.contains(&REDUCTION.dt.to_bits()),
                    "{mesh}: no reduced step ran"
                );
                // The stuck set changed many times: a per-stuck-set path
                // would have refactorized at each change.
                assert!(changes > dts.len() as u64 + 5, "{mesh}: {changes} changes");
            }
        }
    }
}

#[test]
fn the_direct_path_refactorizes_only_when_dt_or_the_stuck_set_changes() {
    // ImplicitSolver::Direct (the reference path) factorizes A₀ + C, which
    // depends on Δt and the stuck set only: at most one factorization per
    // change of (Δt, stuck set) and per stick/slip iteration that changes
    // the classes, never one per step while both stay put.
    let s = slab("slab-q2-8x2.msh", true);
    let mut settings = Method::Trapezoidal.settings(5e-3, 0.5);
    settings.implicit_solver = ImplicitSolver::Direct;
    let mut i = s.integrator(settings).unwrap();
    let (_, changes) = run(&mut i);
    assert!(i.factorizations() >= 1);
    // Each step's iteration solves once per class set it tries: the extra
    // solves beyond one per step are the iterations that changed a class.
    assert!(
        i.factorizations() <= changes + (i.total_iterations() - i.steps()),
        "{} factorizations, {changes} changes of (Δt, stuck set), {} extra iterations",
        i.factorizations(),
        i.total_iterations() - i.steps()
    );
    assert!(
        i.factorizations() < i.steps(),
        "{} factorizations in {} steps",
        i.factorizations(),
        i.steps()
    );
}

#[test]
fn the_explicit_run_does_no_linear_solve() {
    for mesh in ["slab-q2-8x2.msh", "slab-q1-32x8.msh"] {
        for friction in [true, false] {
            let s = slab(mesh, friction);
            let mut i = s
                .integrator(Method::CentralDifference.settings(1e-3, 0.5))
                .unwrap();
            assert!(i.is_explicit(), "{mesh}");
            run(&mut i);
            // The initial static state (Remark 4.1) is one Cholesky solve at
            // set-up; the steps themselves factorize nothing.
            assert_eq!(i.factorizations(), 0, "{mesh} friction {friction}");
            assert_eq!(i.factor_len(), 0, "{mesh}: no factor kept");
            assert!(i.steps() >= 500);
        }
    }
}
