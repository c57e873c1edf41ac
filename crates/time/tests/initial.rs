//! Where a run starts: Remark 4.1's static preload (the default) or rest,
//! with an initial velocity added.

use stickslip_fem::{Dirichlet, Hypothesis, Material, Traction};
use stickslip_linalg::csr::spmv;
use stickslip_mesh::CellKind;
use stickslip_testkit::{add_point_group, paper_slab, rectangle, Slab};
use stickslip_time::{History, InitialState, Scheme, Settings, TimeError};

/// Σ of the scene's load vectors (each history 1 at t = 0 and before,
/// for the scenes here) and its largest magnitude.
fn load_sum(s: &Slab) -> (Vec<f64>, f64) {
    let mut load = vec![0.0; s.n_free()];
    for l in &s.loads {
        for (r, f) in load.iter_mut().zip(&l.vector) {
            *r += f;
        }
    }
    let scale = load.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    (load, scale)
}

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// At rest r₀ = 0 and every load acts from t = 0: M r̈₀ = R(0), where R(0)
/// is the sum of the load vectors (the contact pressure, constant, and the
/// end load H(t), both 1 at t = 0). The static start of the same scene has
/// r₀ ≠ 0 (the pressure preloads it).
#[test]
fn rest_starts_undeformed_with_m_a_equal_to_the_loads() {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let n = s.n_free();
    let (load, scale) = load_sum(&s);
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let static_start = s.integrator(Settings::new(scheme, 1e-3, 0.1)).unwrap();
        assert!(static_start.displacement().iter().any(|&x| x != 0.0));
        let mut settings = Settings::new(scheme, 1e-3, 0.1);
        settings.initial_state = InitialState::Rest;
        let i = s.integrator(settings).unwrap();
        assert!(i.displacement().iter().all(|&x| x == 0.0), "{scheme:?}");
        let mut ma = vec![0.0; n];
        match scheme {
            Scheme::CentralDifference => {
                for ((m, a), out) in s
                    .model
                    .lumped_mass
                    .iter()
                    .zip(i.acceleration())
                    .zip(&mut ma)
                {
                    *out = m * a;
                }
            }
            Scheme::Newmark { .. } => {
                spmv(s.model.mass.as_ref().unwrap(), i.acceleration(), &mut ma)
            }
            Scheme::QuasiStatic => unreachable!("only the dynamic schemes are run here"),
        }
        for (k, (got, want)) in ma.iter().zip(&load).enumerate() {
            assert!(
                (got - want).abs() <= 1e-10 * scale,
                "{scheme:?} DOF {k}: M a = {got}, R(0) = {want}"
            );
        }
        // Nothing strained yet: the ledger starts at zero.
        assert_eq!(i.energy().strain, 0.0);
        assert_eq!(i.energy().kinetic, 0.0);
    }
}

/// ṙ₀ is added to either start: the velocity given is the velocity the
/// run starts with, and ½ṙ₀ᵀMṙ₀ the kinetic energy it books (lumped M:
/// Σ m v²/2 written out here).
#[test]
fn an_initial_velocity_is_added_to_the_chosen_state() {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let n = s.n_free();
    let v0: Vec<f64> = (0..n).map(|k| 0.01 * ((k % 7) as f64 - 3.0)).collect();
    let kinetic: f64 = 0.5
        * s.model
            .lumped_mass
            .iter()
            .zip(&v0)
            .map(|(m, v)| m * v * v)
            .sum::<f64>();
    for state in [InitialState::Static, InitialState::Rest] {
        let mut settings = Settings::new(Scheme::CentralDifference, 1e-3, 0.1);
        settings.initial_state = state;
        settings.initial_velocity = Some(v0.clone());
        let i = s.integrator(settings).unwrap();
        assert_eq!(i.velocity(), &v0[..]);
        let e = i.energy().kinetic;
        assert!(
            (e - kinetic).abs() <= 1e-12 * kinetic,
            "{state:?}: {e} vs {kinetic}"
        );
    }
}

/// A 4 × 1 block (Q1 8 × 2) held only by rollers on its top (u_y = 0),
/// so free in x, pressed on its bottom by `pressure` and pulled by `t_left`
/// and `t_right` (x tractions, "constant": part of the preload) on its ends.
fn floating_block(pressure: f64, t_left: f64, t_right: f64) -> Slab {
    let mesh = rectangle(CellKind::Quad4, 8, 2, [0.0, 0.0], [4.0, 1.0]);
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    let mut tractions = vec![("bottom", Traction::Pressure(pressure), History::Constant)];
    for (group, t) in [("left", t_left), ("right", t_right)] {
        if t != 0.0 {
            tractions.push((group, Traction::Vector([t, 0.0]), History::Constant));
        }
    }
    Slab::assemble(
        mesh,
        &material,
        &[Dirichlet::new("top", 1, 0.0)],
        &tractions,
        None,
    )
    .unwrap()
}

/// Balanced loads on a part free in x: r₀ solves K r₀ = R(0⁻) (residual
/// against the loads) with no mean translation (Σ m u_x = 0), and equals the
/// solution of the same part held at one node in x (the ordinary Cholesky
/// path) less that solution's mean translation.
#[test]
fn the_static_preload_of_a_floating_part_is_solved_on_its_complement() {
    let s = floating_block(300.0, 50.0, -50.0);
    assert_eq!(s.model.dofs.rigid_modes().len(), 1);
    let n = s.n_free();
    let (load, scale) = load_sum(&s);
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let i = s.integrator(Settings::new(scheme, 1e-3, 0.1)).unwrap();
        let r = i.displacement();
        let mut kr = vec![0.0; n];
        spmv(&s.model.stiffness, r, &mut kr);
        for (k, (a, b)) in kr.iter().zip(&load).enumerate() {
            assert!(
                (a - b).abs() <= 1e-9 * scale,
                "{scheme:?} DOF {k}: K r = {a}, R = {b}"
            );
        }
        assert!(r.iter().any(|&x| x != 0.0));
    }
    // Held at the bottom-left corner in x instead: the same deformation.
    let i = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-3, 0.1))
        .unwrap();
    let r = i.displacement();
    let m = &s.model.lumped_mass;
    let xs: Vec<usize> = (0..s.mesh.nodes.len())
        .filter_map(|v| s.dof(v, 0))
        .collect();
    let mean = |r: &[f64], dofs: &[usize], m: &[f64]| {
        dofs.iter().map(|&d| m[d] * r[d]).sum::<f64>() / dofs.iter().map(|&d| m[d]).sum::<f64>()
    };
    assert!(
        mean(r, &xs, m).abs() <= 1e-12,
        "mean u_x {}",
        mean(r, &xs, m)
    );
    let mut mesh = rectangle(CellKind::Quad4, 8, 2, [0.0, 0.0], [4.0, 1.0]);
    add_point_group(&mut mesh, "pin", &[0]);
    let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    let held = Slab::assemble(
        mesh,
        &material,
        &[Dirichlet::new("top", 1, 0.0), Dirichlet::new("pin", 0, 0.0)],
        &[
            ("bottom", Traction::Pressure(300.0), History::Constant),
            ("left", Traction::Vector([50.0, 0.0]), History::Constant),
            ("right", Traction::Vector([-50.0, 0.0]), History::Constant),
        ],
        None,
    )
    .unwrap();
    assert!(held.model.dofs.rigid_modes().is_empty());
    let h = held
        .integrator(Settings::new(Scheme::CentralDifference, 1e-3, 0.1))
        .unwrap();
    let rh = h.displacement();
    // Per node and component (the two DOF maps number differently).
    let hx: Vec<usize> = (0..held.mesh.nodes.len())
        .filter_map(|v| held.dof(v, 0))
        .collect();
    let hm = &held.model.lumped_mass;
    // The pinned node's u_x = 0 enters the mean with its mass.
    let pinned_mass: f64 =
        xs.iter().map(|&d| m[d]).sum::<f64>() - hx.iter().map(|&d| hm[d]).sum::<f64>();
    let shift = hx.iter().map(|&d| hm[d] * rh[d]).sum::<f64>()
        / (hx.iter().map(|&d| hm[d]).sum::<f64>() + pinned_mass);
    let size = rh.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for v in 0..s.mesh.nodes.len() {
        for c in 0..2 {
            let float = s.dof(v, c).map_or(0.0, |d| r[d]);
            let pin = held.dof(v, c).map_or(0.0, |d| rh[d]) - if c == 0 { shift } else { 0.0 };
            if s.dof(v, c).is_some() {
                assert!(
                    (float - pin).abs() <= 1e-9 * size,
                    "node {v} comp {c}: {float} vs {pin}"
                );
            }
        }
    }
}

/// Unbalanced preloads on a floating part are refused with the net force:
/// t = 50 on the left end (height 1) and nothing on the right leave
/// F_x = 50 · 1.
#[test]
fn unbalanced_preloads_on_a_floating_part_are_refused_with_the_net_force() {
    let s = floating_block(300.0, 50.0, 0.0);
    let e = s
        .integrator(Settings::new(Scheme::CentralDifference, 1e-3, 0.1))
        .unwrap_err();
    match &e {
        TimeError::Unbalanced(list) => {
            assert_eq!(list.len(), 1);
            assert_eq!(list[0].label, "translation in x");
            assert!((list[0].work - 50.0).abs() < 1e-9, "{list:?}");
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("net force F_x = 5.000000e1"), "{e}");
    // At rest no static state is needed.
    let mut settings = Settings::new(Scheme::CentralDifference, 1e-3, 0.1);
    settings.initial_state = InitialState::Rest;
    assert!(s.integrator(settings).is_ok());
}

/// A floating part without loads or friction launched at v₀ translates
/// rigidly: u_x(t) = v₀ t at every node, both schemes (each integrates a
/// constant velocity exactly), u_y = 0.
#[test]
fn a_floating_part_launched_at_v0_translates_rigidly() {
    let s = floating_block(0.0, 0.0, 0.0);
    let v0 = 0.7;
    let n = s.n_free();
    let mut velocity = vec![0.0; n];
    for v in 0..s.mesh.nodes.len() {
        if let Some(d) = s.dof(v, 0) {
            velocity[d] = v0;
        }
    }
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let mut settings = Settings::new(scheme, 1e-3, 0.05);
        settings.initial_velocity = Some(velocity.clone());
        let mut i = s.integrator(settings).unwrap();
        while !i.done() {
            i.step().unwrap();
        }
        let t = i.time();
        for v in 0..s.mesh.nodes.len() {
            let ux = s.dof(v, 0).map(|d| i.displacement()[d]).unwrap();
            assert!(
                (ux - v0 * t).abs() <= 1e-12,
                "{scheme:?} node {v}: {ux} vs {}",
                v0 * t
            );
            if let Some(d) = s.dof(v, 1) {
                assert!(i.displacement()[d].abs() <= 1e-12);
            }
        }
    }
}
