//! The pilot runner and `Method` on the paper's case: what a pilot records
//! is the run the case describes, and a method written into a case is
//! that method.

use std::path::PathBuf;

use stickslip_case::pilot::{Pilot, Probe};
use stickslip_case::{Method, Scheme, PAPER_REDUCTION};
use stickslip_testkit::{meshes_dir, workspace_root};

fn paper_case() -> (stickslip_case::Case, PathBuf) {
    let path = workspace_root().join("cases/martins-oden/cd-step-eps1e-4.toml");
    let case = stickslip_case::load(&path, &[]).expect("the paper's case loads");
    (case, meshes_dir())
}

/// The paper's slab, central difference, Δt = 1e-3 to 0.5: 500 steps, 501
/// records. The initial state is the static solution, known in closed
/// form (BENCHMARK.md): u_x = 0.117 x, so u_x(8, 1) = 0.936, and
/// E(0) = −187.2 with the end load on at t = 0.
#[test]
fn a_pilot_records_the_case_it_runs() {
    let (case, _) = paper_case();
    let pilot = Pilot::new(&case).unwrap();
    let p = &pilot.prepared;
    let node = p
        .mesh
        .nodes
        .iter()
        .position(|q| q[0] == 8.0 && q[1] == 1.0)
        .expect("a node at (8, 1)");
    let dof = p.model.dofs.free(node, 0).expect("u_x(8, 1) free");
    let n_c = p.integrator.contact().expect("Γ_C").len();
    let tr = pilot
        .run(&[Probe::Dof(dof), Probe::Contact(n_c - 1)])
        .unwrap();
    assert_eq!(tr.steps, 500);
    assert_eq!(tr.t.len(), 501);
    assert_eq!(tr.values.len(), 2);
    assert!(tr.values.iter().all(|v| v.len() == 501));
    assert!(
        (tr.values[0][0] - 0.936).abs() < 1e-10,
        "u_x(8, 1) at t = 0: {}",
        tr.values[0][0]
    );
    // Closed form, exact but for round-off (measured 5.2e-15 relative).
    assert!(
        (tr.energy0 + 187.2).abs() <= 1e-9 * 187.2,
        "E(0) = {}",
        tr.energy0
    );
    // |σ_T| ≤ g = μ F_n = 90 (the Coulomb bound) at every step.
    assert!(tr.values[1].iter().all(|s| s.abs() <= 90.0 + 1e-9));
    assert!(tr.dt_crit.is_some() && tr.secs > 0.0 && tr.nnz > 0);
}

/// A method written into a case sets the scheme and its parameters, the
/// scheme's own mass, and the step reduction only for the reduced method.
#[test]
fn a_method_configures_the_case() {
    let (case, meshes) = paper_case();
    let mesh = meshes.join("slab-q1-16x4.msh");
    let c = Method::Damped.configure(&case, &mesh, 2e-3, 1e-2);
    assert_eq!(c.time.scheme, Scheme::Newmark);
    assert_eq!((c.time.beta, c.time.gamma), (0.3025, 0.6));
    assert_eq!(
        (c.time.dt, c.time.mass, c.time.stick_reduction),
        (2e-3, None, None)
    );
    assert_eq!(c.contact[0].eps, 1e-2);
    assert_eq!(c.mesh.file, mesh);
    let r = Method::TrapezoidalReduced.configure(&case, &mesh, 5e-3, 1e-4);
    assert_eq!((r.time.beta, r.time.gamma), (0.25, 0.5));
    assert_eq!(r.time.stick_reduction, Some(PAPER_REDUCTION));
    let cd = Method::CentralDifference.configure(&r, &mesh, 1e-3, 1e-4);
    assert_eq!(cd.time.scheme, Scheme::CentralDifference);
    assert_eq!(cd.time.stick_reduction, None);
    let s = Method::TrapezoidalReduced.settings(5e-3, 0.5);
    assert_eq!(s.stick_reduction.map(|r| (r.dt, r.steps)), Some((1e-7, 10)));
}
