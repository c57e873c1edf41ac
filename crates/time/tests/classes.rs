//! The explicit step with K·x matrix-free by element classes
//! (`Dynamics::element_classes`) or by stencil types (`Dynamics::stencils`)
//! follows the run on the assembled K: the products differ in the last
//! bits (class matrices from cells alike to the coordinates' rounding,
//! another summation order; stencils alike to 1e-12 of max |K_ij| sharing
//! one copy), so the states agree to 1e-10 relative, not bit for bit; and
//! the run is bit-identical on one thread and on two.

mod common;
use common::*;
use stickslip_fem::testing::on_threads;
use stickslip_fem::{ElementClasses, Hypothesis, Material};
use stickslip_time::scenes::{E, NU};
use stickslip_time::{Dynamics, History, Integrator, Scheme, Settings, CHUNK, PARALLEL_MIN};

/// K·x by: the assembled K, element classes, stencil types.
#[derive(Clone, Copy, PartialEq)]
enum By {
    Assembled,
    Classes,
    Stencils,
}

fn run(s: &Slab, by: By, threads: usize, steps: usize) -> Integrator {
    let material = Material::new(E, NU, 1.0, Hypothesis::PlaneStrain).unwrap();
    on_threads(threads, || {
        let probe = s
            .integrator(Settings::new(Scheme::CentralDifference, 1e-9, 0.5))
            .unwrap();
        let dt = 0.9 * probe.dt_crit().unwrap();
        let ec = (by == By::Classes).then(|| {
            ElementClasses::with_limit(&s.mesh, &material, &s.model.dofs, 64)
                .expect("structured Q2 slab")
        });
        let dynamics = Dynamics::from_model(&s.model)
            .with_element_classes(ec)
            .with_stencils(by == By::Stencils);
        let settings = Settings::new(Scheme::CentralDifference, dt, 0.5);
        let mut i =
            Integrator::new(dynamics, s.contact.clone(), s.loads.clone(), settings).unwrap();
        assert_eq!(i.explicit_classes().is_some(), by == By::Classes);
        assert_eq!(i.explicit_stencils().is_some(), by == By::Stencils);
        for _ in 0..steps {
            i.step().unwrap();
        }
        i
    })
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The run by `by` within 1e-10 of the assembled one, and the same bits
/// on one thread and two.
fn follows_the_assembled_run(s: &Slab, by: By) {
    // Several chunks: the friction's rows formed alone.
    assert!(s.model.dofs.n_free() > CHUNK);
    let steps = 400;
    let plain = run(s, By::Assembled, 2, steps);
    let with = run(s, by, 2, steps);
    for (name, a, b) in [
        ("r", plain.displacement(), with.displacement()),
        ("ṙ", plain.velocity(), with.velocity()),
    ] {
        let d = max_diff(a, b);
        assert!(d <= 1e-10 * max_abs(a), "{name}: {d:e} of {:e}", max_abs(a));
    }
    let (e0, e1) = (plain.energy(), with.energy());
    for (x, y) in [
        (e0.kinetic, e1.kinetic),
        (e0.strain, e1.strain),
        (e0.dissipated, e1.dissipated),
    ] {
        assert!(
            (x - y).abs() <= 1e-10 * x.abs().max(e0.strain.abs()),
            "{x} vs {y}"
        );
    }
    assert!(with.classes().iter().any(|c| !c.is_stuck()) || e1.dissipated > 0.0);
    // Bit-identical on one thread and two.
    let one = run(s, by, 1, steps);
    assert_eq!(one.displacement(), with.displacement());
    assert_eq!(one.velocity(), with.velocity());
    assert_eq!(one.acceleration(), with.acceleration());
    assert_eq!(one.energy(), with.energy());
}

#[test]
fn classes_follow_the_assembled_run() {
    // Gmsh's numbering (boundary nodes first), where stencil types would
    // not apply, in its own test: the committed 8,352-DOF slab is one whole
    // chunk, so it runs on one thread.
    follows_the_assembled_run(
        &paper_slab("slab-q2-64x16.msh", 1e-4, History::Step),
        By::Classes,
    );
    follows_the_assembled_run(&threaded_slab(96, 24, true), By::Classes);
}

/// The paper's slab on a generated structured mesh of nx × ny cells, of at
/// least PARALLEL_MIN whole chunks, so that two threads share the passes.
fn threaded_slab(nx: usize, ny: usize, q2: bool) -> Slab {
    let s = slab(nx, ny, q2);
    assert!(s.model.dofs.n_free() / CHUNK >= PARALLEL_MIN, "{nx}x{ny}");
    s
}

/// The paper's slab on a generated structured mesh of nx × ny cells.
fn slab(nx: usize, ny: usize, q2: bool) -> Slab {
    let mesh = stickslip_time::scenes::structured_slab(nx, ny, q2);
    Slab::paper(mesh, 1e-4, History::Step, true).unwrap()
}

#[test]
fn stencils_follow_the_assembled_run() {
    follows_the_assembled_run(&threaded_slab(192, 48, false), By::Stencils);
}

/// Newmark on structured slabs too large for the block copy of K and M
/// (`linalg::PAIR_BLOCKS_MAX_BYTES`): the step's products by stencil types
/// follow the CSR run to 1e-10, and give the same bits on 1 and 2 threads.
#[test]
fn newmark_stencils_follow_the_csr_run() {
    use stickslip_time::scenes::{structured_slab, Slab};
    for (nx, ny, q2) in [(240, 60, false), (90, 22, true)] {
        let mesh = structured_slab(nx, ny, q2);
        let s = Slab::paper(mesh, 1e-4, History::Step, true).unwrap();
        assert!(17 * s.model.stiffness.nnz() > 8 << 20, "{nx}x{ny}: small");
        let newmark = |stencils: bool, threads: usize| {
            on_threads(threads, || {
                let dynamics = Dynamics::from_model(&s.model).with_stencils(stencils);
                let settings = Settings::new(
                    Scheme::Newmark {
                        beta: 0.25,
                        gamma: 0.5,
                    },
                    5e-3,
                    0.5,
                );
                let mut i = Integrator::new(dynamics, s.contact.clone(), s.loads.clone(), settings)
                    .unwrap();
                let mut slipped = 0;
                for _ in 0..60 {
                    i.step().unwrap();
                    slipped = slipped.max(i.classes().iter().filter(|c| !c.is_stuck()).count());
                }
                (i, slipped)
            })
        };
        let (plain, _) = newmark(false, 2);
        let (with, slipped) = newmark(true, 2);
        let name = format!("{nx}x{ny}");
        for (what, a, b) in [
            ("r", plain.displacement(), with.displacement()),
            ("ṙ", plain.velocity(), with.velocity()),
        ] {
            let d = max_diff(a, b);
            assert!(
                d <= 1e-10 * max_abs(a),
                "{name} {what}: {d:e} of {:e}",
                max_abs(a)
            );
        }
        let (e0, e1) = (plain.energy(), with.energy());
        for (x, y) in [(e0.kinetic, e1.kinetic), (e0.strain, e1.strain)] {
            assert!(
                (x - y).abs() <= 1e-10 * x.abs().max(e0.strain.abs()),
                "{name}: {x} vs {y}"
            );
        }
        assert!(slipped > 0, "{name}: nothing slipped");
        let (one, _) = newmark(true, 1);
        assert_eq!(one.displacement(), with.displacement(), "{name}");
        assert_eq!(one.velocity(), with.velocity(), "{name}");
        assert_eq!(one.energy(), with.energy(), "{name}");
    }
}
