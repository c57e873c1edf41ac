//! Measured orders of convergence against the theory's: in h (static
//! manufactured solution, Q1 and Q2, L2 and H1), in Δt (smooth frictionless
//! dynamics against a fine-Δt run) and in ε (the regularization error).

use std::path::Path;

use stickslip_case::Scene;
use stickslip_mesh::CellKind;
use stickslip_testkit::manufactured;
use stickslip_testkit::sdof;
use stickslip_time::Scheme;

use crate::report::{max_or_nan, num, Report};
use crate::scene::{self, PaperCase};
use crate::suites::analytic::SCHEMES;
use crate::{Options, NEWMARK};

/// Least-squares slope of log(e) against log(x).
pub fn fitted_order(x: &[f64], e: &[f64]) -> f64 {
    let n = x.len() as f64;
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let le: Vec<f64> = e.iter().map(|v| v.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let me = le.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&le).map(|(a, b)| (a - mx) * (b - me)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

fn list(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
}

/// Runs the suite.
pub fn run(root: &Path, opts: &Options, r: &mut Report) {
    r.suite("rates");
    h_rates(opts, r);
    dt_rates(root, opts, r);
    eps_rates(root, opts, r);
}

// ---- h: the manufactured solution of crates/fem/tests/convergence.rs ----
// (stickslip_testkit::manufactured: a smooth u on the unit square with
// curved interior, clamped on x = 0 and y = 0, traction on x = 1 and y = 1.)

/// (L2 error, H1-seminorm error) on an n × n mesh.
fn h_errors(kind: CellKind, n: usize) -> Result<(f64, f64), String> {
    manufactured::errors(kind, n).map_err(|e| e.to_string())
}

fn h_rates(opts: &Options, r: &mut Report) {
    let ladders: [(CellKind, &str, &[usize], f64); 2] = if opts.quick {
        [
            (CellKind::Quad4, "Q1", &[8, 16, 32], 1.0),
            (CellKind::Quad9, "Q2", &[4, 8, 16], 2.0),
        ]
    } else {
        [
            (CellKind::Quad4, "Q1", &[8, 16, 32, 64], 1.0),
            (CellKind::Quad9, "Q2", &[4, 8, 16, 32], 2.0),
        ]
    };
    for (kind, name, ns, k) in ladders {
        let case = format!("manufactured static {name}");
        let errs: Result<Vec<(f64, f64)>, String> = ns.iter().map(|&n| h_errors(kind, n)).collect();
        let errs = match errs {
            Ok(e) => e,
            Err(e) => {
                r.holds(&case, "solve", e, "solves", false);
                continue;
            }
        };
        let h: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
        let l2: Vec<f64> = errs.iter().map(|e| e.0).collect();
        let h1: Vec<f64> = errs.iter().map(|e| e.1).collect();
        let span = format!("h = 1/{}..1/{}", ns[0], ns[ns.len() - 1]);
        r.close(
            &case,
            &format!("L2 order, {span}"),
            fitted_order(&h, &l2),
            k + 1.0,
            "Ciarlet: O(h^(k+1))",
            0.15,
        );
        r.close(
            &case,
            &format!("H1 order, {span}"),
            fitted_order(&h, &h1),
            k,
            "Ciarlet: O(h^k)",
            0.15,
        );
    }
}

// ---- Δt: the frictionless slab under the smooth end load −150·sin(8πt) ----

/// The displacement at t_end of the scene without its friction surface,
/// run with `scheme` at `dt`.
fn final_state(scene: &mut Scene, scheme: Scheme, dt: f64, t_end: f64) -> Result<Vec<f64>, String> {
    scene.contact = None;
    scene.settings = stickslip_time::Settings::new(scheme, dt, t_end);
    let mut i = scene.integrator().map_err(|e| e.to_string())?;
    while !i.done() {
        i.step().map_err(|e| e.to_string())?;
    }
    Ok(i.displacement().to_vec())
}

fn dt_rates(root: &Path, opts: &Options, r: &mut Report) {
    let case_file = root.join("cases/martins-oden/cd-sin-eps1e-4.toml");
    let mut scene = match PaperCase::read(&case_file).and_then(|c| c.scene()) {
        Ok(s) => s,
        Err(e) => {
            r.holds("Δt rates", "scene", e, "builds", false);
            return;
        }
    };
    // A smooth solution: sin(8πt) starts at 0, so r̈₀ = 0 and nothing jumps;
    // the low modes it drives dominate the error.
    let t_end = 0.25;
    let runs: [(&str, Scheme, f64, &[f64], f64); 3] = [
        (
            "CD",
            Scheme::CentralDifference,
            2.0,
            &[4e-4, 2e-4, 1e-4, 5e-5],
            6.25e-6,
        ),
        ("NM ¼,½", NEWMARK, 2.0, &[4e-3, 2e-3, 1e-3, 5e-4], 3.125e-5),
        (
            "NM 0.3025,0.6",
            Scheme::Newmark {
                beta: 0.3025,
                gamma: 0.6,
            },
            1.0,
            &[4e-3, 2e-3, 1e-3, 5e-4],
            3.125e-5,
        ),
    ];
    for (name, scheme, order, dts, dt_ref) in runs {
        // Quick: the three finest steps (the coarsest is not yet asymptotic).
        let dts = if opts.quick { &dts[1..] } else { dts };
        let case = format!("frictionless slab sin {name}");
        let result = (|| -> Result<Vec<f64>, String> {
            let reference = final_state(&mut scene, scheme, dt_ref, t_end)?;
            dts.iter()
                .map(|&dt| {
                    let u = final_state(&mut scene, scheme, dt, t_end)?;
                    Ok(max_or_nan(
                        u.iter()
                            .zip(&reference)
                            .map(|(a, b)| (a - b).abs())
                            .chain([0.0]),
                    ))
                })
                .collect()
        })();
        match result {
            Ok(errs) => r.close(
                &case,
                &format!("Δt order (errors {})", list(&errs)),
                fitted_order(dts, &errs),
                order,
                if order == 2.0 {
                    "Newmark γ=½: 2nd order"
                } else {
                    "Newmark γ≠½: 1st order"
                },
                0.2,
            ),
            Err(e) => r.holds(&case, "run completes", e, "completes", false),
        }
    }
}

// ---- ε: the regularization error ----

fn eps_rates(root: &Path, opts: &Options, r: &mut Report) {
    // Paper Thm 2.3: the error is O(√ε) in the energy norm, so the fitted
    // order must be at least ½. Δt = 2e-6 keeps the time error (O(Δt) at the
    // stick/slip kinks) well below the smallest ε error measured.
    let epsilons = [1e-2, 1e-3, 1e-4];
    let loads: &[f64] = if opts.quick { &[2.5] } else { &[2.5, 5.0, 0.8] };
    for (name, scheme) in SCHEMES {
        for &p in loads {
            let case = format!("1-DOF Coulomb P={p} {name}");
            let errs: Result<Vec<f64>, String> = epsilons
                .iter()
                .map(|&e| {
                    sdof::max_error(p, e, scheme, 2e-6)
                        .map(|x| x.0)
                        .map_err(|e| e.to_string())
                })
                .collect();
            match errs {
                Ok(errs) => {
                    r.at_least(
                        &case,
                        &format!("ε order, ε=1e-2..1e-4 (errors {})", list(&errs)),
                        fitted_order(&epsilons, &errs),
                        0.5,
                        "Thm 2.3: O(√ε)",
                    );
                    r.at_most(
                        &case,
                        "max |x − x_Coulomb| at ε=1e-4",
                        errs[2],
                        1e-4,
                        "closed form; amplitude 0.08",
                    );
                }
                Err(e) => r.holds(&case, "run completes", e, "completes", false),
            }
        }
    }
    if opts.quick {
        return;
    }
    // The slab (central difference, Δt = 1e-3, H(t)): u_x(81) history against
    // the run at ε = 1e-6.
    let case_file = root.join("cases/martins-oden/cd-step-eps1e-4.toml");
    let case = "slab CD H(t)";
    let result = (|| -> Result<(Vec<f64>, Vec<f64>), String> {
        let c = PaperCase::read(&case_file)?;
        let history = |eps: f64| -> Result<Vec<f64>, String> {
            let mut scene = c.scene()?;
            if let Some(s) = &mut scene.contact {
                s.law.eps = eps;
            }
            let t = scene::run(&scene);
            t.error.map_or(Ok(t.ux81), Err)
        };
        let reference = history(1e-6)?;
        let eps = vec![1e-1, 1e-2, 1e-3];
        let errs = eps
            .iter()
            .map(|&e| {
                let u = history(e)?;
                Ok(max_or_nan(
                    u.iter()
                        .zip(&reference)
                        .map(|(a, b)| (a - b).abs())
                        .chain([0.0]),
                ))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        Ok((eps, errs))
    })();
    match result {
        Ok((eps, errs)) => r.at_least(
            case,
            &format!("ε order of u_x(81) vs ε=1e-6 (errors {})", list(&errs)),
            fitted_order(&eps, &errs),
            0.5,
            "Thm 2.3: O(√ε)",
        ),
        Err(e) => r.holds(case, "run completes", e, "completes", false),
    }
}
