//! Nothing for what a scene lacks: a contact surface whose friction
//! cannot act (μ = 0, or no normal pressure: w g = 0 at every node) costs
//! no stick/slip iteration and no friction pass in any scheme, and its
//! run is the run without a contact surface, bit for bit.

use stickslip_testkit::read_mesh;
use stickslip_testkit::scene::{Slab, END_LOAD, MU, NU, PRESSURE};
use stickslip_time::{History, Integrator, Scheme, Settings};

const SCHEMES: [Scheme; 3] = [
    Scheme::CentralDifference,
    Scheme::Newmark {
        beta: 0.25,
        gamma: 0.5,
    },
    Scheme::QuasiStatic,
];

/// The paper's slab on its Q2 8×2 mesh with `pressure` on the bottom and
/// friction `mu` there (`None`: no contact surface).
fn slab(pressure: f64, mu: Option<f64>) -> Slab {
    let mesh = read_mesh("slab-q2-8x2.msh").expect("committed mesh reads");
    Slab::new(mesh, NU, pressure, mu, 1e-4, END_LOAD, History::Step).expect("scene builds")
}

/// Runs `i` to its end; asserts after every step that its state is the
/// bits of `reference`'s, stepped alongside.
fn same_bits(what: &str, mut i: Integrator, mut reference: Integrator) -> Integrator {
    while !i.done() {
        let a = i.step().unwrap();
        let b = reference.step().unwrap();
        assert_eq!(a.iterations, b.iterations, "{what}: step {}", i.steps());
        for (x, y) in [
            (i.displacement(), reference.displacement()),
            (i.velocity(), reference.velocity()),
            (i.acceleration(), reference.acceleration()),
        ] {
            assert!(
                x.iter().zip(y).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{what}: step {}: the state differs from the run without a contact surface",
                i.steps()
            );
        }
        assert_eq!(i.energy(), reference.energy(), "{what}: step {}", i.steps());
    }
    i
}

#[test]
fn a_surface_without_friction_runs_no_friction_code() {
    for scheme in SCHEMES {
        let settings = Settings::new(scheme, 1e-3, 0.1);
        let steps = 100;
        for (what, with, without) in [
            // μ = 0 under the paper's pressure.
            ("mu = 0", slab(PRESSURE, Some(0.0)), slab(PRESSURE, None)),
            // μ > 0 with no normal pressure: g = μ F_n = 0.
            ("pressure = 0", slab(0.0, Some(MU)), slab(0.0, None)),
        ] {
            let what = format!("{scheme:?}, {what}");
            assert!(with.contact.is_some() && without.contact.is_none());
            let i = with.integrator(settings.clone()).unwrap();
            assert!(!i.friction(), "{what}: friction should be off");
            // The surface stays for the observers.
            let n_c = i.contact().map_or(0, |c| c.len());
            assert!(n_c > 0, "{what}");
            let reference = without.integrator(settings.clone()).unwrap();
            let i = same_bits(&what, i, reference);
            assert_eq!(i.steps(), steps, "{what}");
            assert_eq!(i.friction_passes(), 0, "{what}: friction passes");
            // One linear solve (Newmark) or pass (explicit) a step and no
            // stick/slip iteration besides.
            assert_eq!(i.total_iterations(), steps, "{what}: iterations");
            // What the results show: no friction stress, the slip
            // velocity τ·v (τ = +x on the bottom).
            let (mut stress, mut slip) = (vec![f64::NAN; n_c], vec![f64::NAN; n_c]);
            i.friction_stress(&mut stress);
            i.slip_velocity(&mut slip);
            assert!(
                stress.iter().all(|s| s.to_bits() == 0),
                "{what}: {stress:?}"
            );
            let c = i.contact().unwrap();
            for (node, v) in c.nodes.iter().zip(&slip) {
                let vx = node.dofs[0].map_or(0.0, |d| i.velocity()[d]);
                assert_eq!(v.to_bits(), vx.to_bits(), "{what}: node {}", node.node);
            }
        }
    }
}

#[test]
fn a_surface_with_friction_counts_a_pass_a_step() {
    // The count the test above finds at 0 is the one friction moves.
    for scheme in SCHEMES {
        let s = slab(PRESSURE, Some(MU));
        let mut i = s.integrator(Settings::new(scheme, 1e-3, 0.02)).unwrap();
        assert!(i.friction());
        while !i.done() {
            i.step().unwrap();
        }
        assert_eq!(i.friction_passes(), 20, "{scheme:?}");
    }
}

#[test]
fn a_checkpoint_with_classes_restores_on_a_surface_without_friction() {
    // A version that ran friction code on a μ = 0 surface stored its
    // classes and (zero) forces; the run without friction continues from
    // it as from its own checkpoint.
    let settings = Settings::new(Scheme::CentralDifference, 1e-3, 0.02);
    let s = slab(PRESSURE, Some(0.0));
    let mut a = s.integrator(settings.clone()).unwrap();
    let n_c = a.contact().unwrap().len();
    for _ in 0..10 {
        a.step().unwrap();
    }
    let mut old = a.checkpoint();
    assert!(old.classes.is_empty() && old.forces.is_empty());
    old.classes = vec![1; n_c];
    old.forces = vec![0.0; n_c];
    let mut b = s.integrator(settings).unwrap();
    b.restore(&old).unwrap();
    let b = same_bits("restored", b, a);
    assert_eq!(b.friction_passes(), 0);
}
