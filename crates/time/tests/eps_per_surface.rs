//! Surfaces joined with different ε keep each its own: two uncoupled
//! oscillators of tests/sdof.rs (m = 1, k = 100, g = 1, step force P),
//! one friction node each, joined into one surface with ε = 1e-2 and
//! 1e-4, move as each does alone with its own ε, in every way of solving a
//! step. The expected motion is the single oscillator's own run.

use nalgebra_sparse::{CooMatrix, CsrMatrix};
use stickslip_contact::{ContactNode, ContactSurface};
use stickslip_testkit::sdof::{self, G, K};
use stickslip_testkit::solvers::every_solver;
use stickslip_time::{Dynamics, History, Integrator, Load, Settings};

const P: [f64; 2] = [2.5, 5.0];
const EPS: [f64; 2] = [1e-2, 1e-4];

fn pair(settings: Settings) -> Integrator {
    let diagonal = |v: f64| {
        let mut coo = CooMatrix::new(2, 2);
        coo.push(0, 0, v);
        coo.push(1, 1, v);
        CsrMatrix::from(&coo)
    };
    let dynamics = Dynamics {
        stiffness: diagonal(K),
        consistent_mass: Some(diagonal(1.0)),
        lumped_mass: vec![1.0; 2],
        constant_load: vec![0.0; 2],
        stencils: true,
        fill_order: Default::default(),
        rigid_modes: Vec::new(),
    };
    let surfaces = (0..2)
        .map(|j| {
            let node = ContactNode {
                node: j,
                dofs: [Some(j), None],
                weight: 1.0,
                tangent: [1.0, 0.0],
                s: 0.0,
                bound: G,
            };
            ContactSurface::from_nodes(&format!("mass {j}"), vec![node], EPS[j]).unwrap()
        })
        .collect();
    let joined = ContactSurface::join(surfaces).unwrap();
    let loads = vec![Load {
        vector: P.to_vec(),
        history: History::Step,
    }];
    Integrator::new(dynamics, Some(joined), loads, settings).unwrap()
}

#[test]
fn each_surface_keeps_its_own_eps() {
    for (name, settings) in every_solver(1e-4, 0.8) {
        let mut both = pair(settings.clone());
        let mut alone: Vec<Integrator> = (0..2)
            .map(|j| {
                sdof::with_surface(P[j], sdof::surface(EPS[j]).unwrap(), settings.clone()).unwrap()
            })
            .collect();
        let mut worst: f64 = 0.0;
        while !both.done() {
            both.step().unwrap();
            for (j, a) in alone.iter_mut().enumerate() {
                a.step().unwrap();
                worst = worst.max((both.displacement()[j] - a.displacement()[0]).abs());
                assert_eq!(
                    both.classes()[j],
                    a.classes()[0],
                    "{name}: t = {}",
                    a.time()
                );
            }
        }
        // The same arithmetic per DOF, up to the order of a solve's sums:
        // round-off on displacements of 0.05.
        assert!(worst < 1e-14, "{name}: {worst:e}");
        // Both at rest by t = 0.8 (tests/sdof.rs: P = 2.5 at 0.03 from
        // 0.31, P = 5 at 0.04 from 0.63), each creeping on its own viscous
        // branch at ε |P − k x|/g: 1e-2·0.5 and 1e-4·1, 50 times apart.
        let creep: Vec<f64> = (0..2).map(|j| both.velocity()[j].abs()).collect();
        assert!(creep[0] > 10.0 * creep[1], "{name}: {creep:?}");
    }
}
