//! Closed-form problems: the Coulomb oscillator, d'Alembert's wave, the
//! static slab, the patch test, quasi-static friction on a strip
//! (`strip.rs`), the bodies held only by friction with Rayleigh damping
//! (`friction_held.rs`), and the checks of several surfaces and a
//! pressure that changes (`surfaces.rs`).

use std::path::Path;

use stickslip_fem::{static_solve, Dirichlet, Hypothesis, Material, Model};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::{add_point_group, map_nodes, rectangle};
use stickslip_testkit::{sdof, wave, Slab};
use stickslip_time::{History, Scheme};

use crate::report::{max_or_nan, Report};
use crate::{Options, NEWMARK};

/// The two schemes of the paper.
pub const SCHEMES: [(&str, Scheme); 2] = [("CD", Scheme::CentralDifference), ("NM ¼,½", NEWMARK)];

/// Runs the suite.
pub fn run(root: &Path, opts: &Options, r: &mut Report) {
    r.suite("analytic");
    coulomb_oscillator(opts, r);
    wave(root, opts, r);
    static_slab(root, r);
    patch(r);
    super::strip::run_all(opts, r);
    super::friction_held::run(opts, r);
    super::surfaces::run(root, opts, r);
    super::belt::run(root, r);
    super::compliance::run(r);
    super::consistency::run(root, r);
}

fn coulomb_oscillator(opts: &Options, r: &mut Report) {
    // Final rest positions of the closed form (see sdof::closed_form):
    // P = 2.5 stops at 0.03, P = 5 at 0.04, P = 0.8 never moves.
    let loads: &[(f64, f64)] = if opts.quick {
        &[(2.5, 0.03), (5.0, 0.04)]
    } else {
        &[(2.5, 0.03), (5.0, 0.04), (0.8, 0.0)]
    };
    for (name, scheme) in SCHEMES {
        for &(p, rest) in loads {
            let case = format!("1-DOF Coulomb P={p} {name}");
            match sdof::max_error(p, 1e-5, scheme, 1e-5) {
                Ok((_, x)) => r.close(
                    &case,
                    "x(1), ε=1e-5, Δt=1e-5",
                    x,
                    rest,
                    "Coulomb closed form, rest position",
                    // ε·(t since last stick)/... : a stuck mass creeps at
                    // |P − kx| ε / g ≤ ε, so 2e-5 over the run's unit time.
                    2e-5,
                ),
                Err(e) => r.holds(&case, "run completes", e.to_string(), "completes", false),
            }
        }
    }
}

/// Largest relative L2-in-time error of u_x(L, 0) over one period against
/// d'Alembert's triangle wave (`stickslip_testkit::wave`: ν = 0 makes
/// plane strain uniaxial, a bar with c = √(E/ρ); the end moves as
/// −(p c/E)·t up to 2L/c, then back).
fn wave_error(root: &Path, mesh_file: &str, scheme: Scheme, dt: f64) -> Result<f64, String> {
    let mesh =
        Mesh::from_file(root.join("cases/meshes").join(mesh_file)).map_err(|e| e.to_string())?;
    wave::end_error(mesh, scheme, dt).map_err(|e| e.to_string())
}

fn wave(root: &Path, opts: &Options, r: &mut Report) {
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
    for (name, scheme) in SCHEMES {
        for (order, meshes) in ladders {
            if opts.quick && order == "Q1" {
                continue;
            }
            let case = format!("1-D wave {order} {name}");
            // Δt proportional to h, below every mesh's critical step.
            let errors: Result<Vec<f64>, String> = meshes
                .iter()
                .enumerate()
                .map(|(k, m)| wave_error(root, m, scheme, 2e-3 / f64::from(1 << k)))
                .collect();
            let errors = match errors {
                Ok(e) => e,
                Err(e) => {
                    r.holds(&case, "run completes", e, "completes", false);
                    continue;
                }
            };
            // Halving h and Δt halves the error of the kinked wave or
            // better: dispersion at the kinks limits the order to about 1.
            // Measured ratios 0.37-0.50 (orders 1.01-1.43, the lowest Q1
            // by Newmark); order ≥ 0.9 (ratio ≤ 2^−0.9 = 0.536) claims
            // first order, where the old ratio ≤ 0.7 let order 0.51 pass.
            let worst_ratio = max_or_nan(errors.windows(2).map(|w| w[1] / w[0]));
            r.at_least(
                &case,
                &format!(
                    "lowest order per halving of h and Δt (errors {})",
                    errors
                        .iter()
                        .map(|e| format!("{e:.3e}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                -worst_ratio.log2(),
                0.9,
                "first-order convergence at the wave's kinks",
            );
            r.at_most(
                &case,
                &format!(
                    "rel. L2 error u_x(8,0), {}",
                    meshes[2].trim_end_matches(".msh")
                ),
                errors[2],
                0.01,
                "d'Alembert triangle wave",
            );
        }
    }
}

fn static_slab(root: &Path, r: &mut Report) {
    // Plane strain under σ_yy = −300 alone (rollers on top, free right end):
    // ε_yy = −(1−ν²)·300/E = −0.273, ε_xx = ν(1+ν)·300/E = 0.117, so
    // u_x = 0.117x, u_y = 0.273(1 − y) exactly (BENCHMARK.md).
    for mesh_file in ["slab-q2-8x2.msh", "slab-q1-16x4.msh"] {
        let case = format!("static slab {}", mesh_file.trim_end_matches(".msh"));
        let result = (|| -> Result<f64, String> {
            let mesh = Mesh::from_file(root.join("cases/meshes").join(mesh_file))
                .map_err(|e| e.to_string())?;
            // The slab of BENCHMARK.md with its pressure alone: no end load,
            // no friction surface.
            let slab = Slab::new(mesh, 0.3, 300.0, None, 1.0, 0.0, History::Step)
                .map_err(|e| e.to_string())?;
            let u = static_solve(&slab.model, &slab.loads[0].vector).map_err(|e| e.to_string())?;
            Ok(max_or_nan(slab.mesh.nodes.iter().enumerate().flat_map(
                |(v, p)| {
                    [
                        (u[2 * v] - 0.117 * p[0]).abs(),
                        (u[2 * v + 1] - 0.273 * (1.0 - p[1])).abs(),
                    ]
                },
            )))
        })();
        match result {
            Ok(w) => r.at_most(
                &case,
                "max |u − (0.117x, 0.273(1−y))|",
                w,
                1e-10,
                "plane-strain closed form",
            ),
            Err(e) => r.holds(&case, "solve", e, "solves", false),
        }
    }
}

/// Deterministic pseudo-random numbers in [−1, 1].
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn patch(r: &mut Report) {
    // Any linear field lies in the Q1/Q2 isoparametric space, so imposing it
    // on the boundary must give it back at every interior node (round-off:
    // displacements here are O(0.1)).
    let linear = |p: [f64; 2]| {
        [
            0.01 + 0.02 * p[0] - 0.015 * p[1],
            -0.02 + 0.005 * p[0] + 0.03 * p[1],
        ]
    };
    let mut q1 = rectangle(CellKind::Quad4, 5, 4, [0.0, 0.0], [2.5, 2.0]);
    let mut s = 7u64;
    for p in &mut q1.nodes {
        if p[0] > 1e-12 && p[0] < 2.5 - 1e-12 && p[1] > 1e-12 && p[1] < 2.0 - 1e-12 {
            p[0] += 0.15 * lcg(&mut s);
            p[1] += 0.15 * lcg(&mut s);
        }
    }
    let mut q2 = rectangle(CellKind::Quad9, 4, 3, [0.0, 0.0], [2.0, 1.5]);
    map_nodes(&mut q2, |[x, y]| {
        [
            x + 0.08 * (1.7 * y).sin() + 0.05 * x * y,
            y + 0.1 * (1.3 * x).cos() - 0.04 * x * x,
        ]
    });
    for (name, mut mesh) in [("patch distorted Q1", q1), ("patch curved Q2", q2)] {
        let mut boundary: Vec<usize> = ["bottom", "right", "top", "left"]
            .iter()
            .filter_map(|g| mesh.group(g).ok().map(|g| g.nodes.clone()))
            .flatten()
            .collect();
        boundary.sort_unstable();
        boundary.dedup();
        let mut bcs = Vec::new();
        for &v in &boundary {
            let group = format!("p{v}");
            add_point_group(&mut mesh, &group, &[v]);
            let u = linear(mesh.nodes[v]);
            bcs.push(Dirichlet::new(group.clone(), 0, u[0]));
            bcs.push(Dirichlet::new(group, 1, u[1]));
        }
        let material =
            Material::new(200.0, 0.27, 1.0, Hypothesis::PlaneStress).expect("valid material");
        let result = Model::new(&mesh, &material, &bcs)
            .map_err(|e| e.to_string())
            .and_then(|m| static_solve(&m, &vec![0.0; m.dofs.n_free()]).map_err(|e| e.to_string()));
        match result {
            Ok(u) => {
                let worst = max_or_nan(mesh.nodes.iter().enumerate().flat_map(|(v, p)| {
                    let e = linear(*p);
                    [(u[2 * v] - e[0]).abs(), (u[2 * v + 1] - e[1]).abs()]
                }));
                r.at_most(
                    name,
                    "max nodal |u − u_linear|",
                    worst,
                    1e-12,
                    "linear field reproduced exactly",
                );
            }
            Err(e) => r.holds(name, "solve", e, "solves", false),
        }
    }
}
