//! A 1-D wave: the slab with ν = 0, rollers on top and bottom, held at x = 0,
//! a step traction −p at x = L, no friction. Every section moves as a bar
//! with c = √(E/ρ) (ν = 0 makes plane strain uniaxial), so d'Alembert gives
//! the end displacement: a triangle wave between 0 and −2pL/E with period
//! 4L/c, u(L, t) = −(p c/E)·t for t ≤ 2L/c, then back to 0 at 4L/c.

mod common;
use common::*;
use stickslip_fem::{traction_load, Dirichlet, Hypothesis, Material, Model, Traction};
use stickslip_mesh::Mesh;
use stickslip_time::{Dynamics, History, Integrator, Load, Scheme, Settings};

const E: f64 = 1000.0;
const L: f64 = 8.0;
const P: f64 = 1.0;

fn exact_end_displacement(t: f64) -> f64 {
    let c = E.sqrt();
    let period = 4.0 * L / c;
    let tau = t.rem_euclid(period);
    let rise = if tau <= period / 2.0 {
        tau
    } else {
        period - tau
    };
    -P * c / E * rise
}

/// Relative L2-in-time error of u_x(L, 0) over one period.
fn wave_error(mesh_file: &str, scheme: Scheme, dt: f64) -> f64 {
    let mesh = Mesh::from_file(mesh_path(mesh_file)).unwrap();
    let material = Material::new(E, 0.0, 1.0, Hypothesis::PlaneStrain).unwrap();
    let conditions = vec![
        Dirichlet {
            group: "support".into(),
            component: 1,
            value: 0.0,
        },
        Dirichlet {
            group: "contact".into(),
            component: 1,
            value: 0.0,
        },
        Dirichlet {
            group: "left".into(),
            component: 0,
            value: 0.0,
        },
    ];
    let model = Model::new(&mesh, &material, &conditions).unwrap();
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    traction_load(&mesh, "load", Traction::Vector([-P, 0.0]), &mut full).unwrap();
    let mut free = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut free);
    let end = mesh
        .nodes
        .iter()
        .position(|p| (p[0] - L).abs() < 1e-12 && p[1].abs() < 1e-12)
        .unwrap();
    let end_dof = model.dofs.free(end, 0).unwrap();
    let period = 4.0 * L / E.sqrt();
    let loads = vec![Load {
        vector: free,
        history: History::Step,
    }];
    let mut i = Integrator::new(
        Dynamics::from_model(&model),
        None,
        loads,
        Settings::new(scheme, dt, period),
    )
    .unwrap();
    let (mut err2, mut ref2) = (0.0, 0.0);
    while !i.done() {
        i.step().unwrap();
        let exact = exact_end_displacement(i.time());
        err2 += (i.displacement()[end_dof] - exact).powi(2);
        ref2 += exact * exact;
    }
    (err2 / ref2).sqrt()
}

#[test]
fn end_displacement_converges_to_dalembert() {
    let ladders: [(&str, [&str; 3]); 2] = [
        (
            "Q2",
            ["slab-q2-8x2.msh", "slab-q2-16x4.msh", "slab-q2-32x8.msh"],
        ),
        (
            "Q1",
            ["slab-q1-16x4.msh", "slab-q1-32x8.msh", "slab-q1-64x16.msh"],
        ),
    ];
    for scheme in [
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
        Scheme::CentralDifference,
    ] {
        for (order, meshes) in ladders {
            // Δt proportional to h, below every mesh's critical step.
            let errors: Vec<f64> = meshes
                .iter()
                .enumerate()
                .map(|(k, m)| wave_error(m, scheme, 2e-3 / f64::from(1 << k)))
                .collect();
            println!("{scheme:?} {order}: relative L2 errors {errors:?}");
            // Halving h and Δt roughly halves the error of the kinked wave
            // (dispersion at the kinks limits the rate to about 1).
            assert!(
                errors.windows(2).all(|w| w[1] < 0.7 * w[0]),
                "{scheme:?} {order}: errors {errors:?} must shrink"
            );
            assert!(
                errors[2] < 0.01,
                "{scheme:?} {order}: finest error {}",
                errors[2]
            );
        }
    }
}
