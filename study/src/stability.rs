//! The stability map, each row a measured fact:
//!
//! * central difference at Δt/Δt_crit ∈ {0.5, 0.9, 0.99, 1.01, 1.1, 2}:
//!   stable or not by energy growth, and the observed threshold (bisected)
//!   against the time crate's Lanczos estimate of Δt_crit = 2/ω_max;
//! * the ringing after sticking: the step-to-step oscillation of σ_T at the
//!   node that sticks, against x = Δt·w_J·g/(ε·m_J), the damping-to-mass
//!   ratio of the stuck node's update (METHOD.md §5, Remark 4.3);
//! * the stick/slip iteration: steps that fail to converge with and without
//!   Remark 4.2 across an ε ladder.

use std::fmt::Write as _;
use std::path::Path;

use stickslip_case::Method;
use stickslip_contact::IterationOptions;
use stickslip_mesh::Mesh;
use stickslip_time::{ExplicitFriction, Integrator, Scheme, Settings, TimeError};

use crate::plot::{self, Marker, Panel, Series, COLORS};
use crate::run::TRAPEZOIDAL;
use crate::slab::{self, read_mesh, LoadKind, Slab, G};

/// The Δt/Δt_crit ratios of the map.
pub const RATIOS: [f64; 6] = [0.5, 0.9, 0.99, 1.01, 1.1, 2.0];
/// Steps of a stability run: at Δt = (1 + δ)Δt_crit the highest mode grows
/// by about 1 + √(8δ) per step (central difference, λ² + (2 + 8δ)λ + 1 = 0),
/// so 3000 steps lift round-off (1e-16) above any physical energy for
/// δ ≳ 2e-5, far below the 2% the estimate must meet.
pub const STABILITY_STEPS: usize = 3000;
/// A run is unstable when its mechanical energy (kinetic + strain) grows
/// above this multiple of its initial value. The physical motion under the
/// end load stays within a few percent of the initial strain energy (the
/// end load does about 10 units of work against 380 of initial strain).
pub const GROWTH_LIMIT: f64 = 10.0;

/// Result of one stability run.
#[derive(Clone, Copy, Debug)]
pub struct Growth {
    /// max_K (kinetic + strain)_K / (kinetic + strain)_0; infinite when the
    /// state left the floating-point range.
    pub growth: f64,
    /// Steps completed.
    pub steps: usize,
}

impl Growth {
    /// Stable by the energy criterion.
    pub fn stable(self) -> bool {
        self.growth < GROWTH_LIMIT
    }
}

/// Runs central difference at Δt = `ratio`·Δt_crit for `steps` steps.
///
/// # Errors
/// Settings the time crate refuses.
pub fn growth(slab: &Slab, ratio: f64, steps: usize) -> Result<Growth, String> {
    let crit = estimate(slab);
    let dt = ratio * crit;
    let mut s = Settings::new(Scheme::CentralDifference, dt, dt * (steps as f64 + 0.5));
    s.allow_unstable = true;
    let mut i = slab.integrator(s).map_err(|e| e.to_string())?;
    let e0 = i.energy().kinetic + i.energy().strain;
    let mut worst: f64 = 1.0;
    for k in 0..steps {
        match i.step() {
            Ok(_) => {}
            Err(TimeError::NonFinite { .. }) => {
                return Ok(Growth {
                    growth: f64::INFINITY,
                    steps: k,
                })
            }
            Err(e) => return Err(e.to_string()),
        }
        let e = i.energy();
        let g = (e.kinetic + e.strain) / e0;
        if !g.is_finite() {
            return Ok(Growth {
                growth: f64::INFINITY,
                steps: k + 1,
            });
        }
        worst = worst.max(g);
        if worst > 1e6 * GROWTH_LIMIT {
            // Clearly unstable; the rest of the run adds nothing.
            return Ok(Growth {
                growth: worst,
                steps: k + 1,
            });
        }
    }
    Ok(Growth {
        growth: worst,
        steps,
    })
}

/// The time crate's estimate of Δt_crit (Lanczos on M_L⁻¹K, capped by
/// Gershgorin's bound: `stickslip_time::stability::critical_step`).
pub fn estimate(slab: &Slab) -> f64 {
    stickslip_time::stability::critical_step(&slab.model.stiffness, &slab.model.lumped_mass)
}

/// Bisects the stability threshold in Δt/Δt_crit between `lo` (stable) and
/// `hi` (unstable) to a relative width `tol`.
///
/// # Errors
/// A bracket that does not bracket, or a failed run.
pub fn threshold(
    slab: &Slab,
    mut lo: f64,
    mut hi: f64,
    tol: f64,
    steps: usize,
) -> Result<f64, String> {
    if !growth(slab, lo, steps)?.stable() || growth(slab, hi, steps)?.stable() {
        return Err(format!(
            "the stability threshold is not between Δt/Δt_crit = {lo} and {hi}"
        ));
    }
    while hi - lo > tol * lo {
        let mid = 0.5 * (lo + hi);
        if growth(slab, mid, steps)?.stable() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// One row of the critical-step table.
#[derive(Clone, Debug)]
pub struct CriticalRow {
    /// Mesh file.
    pub mesh: String,
    /// With the contact surface.
    pub friction: bool,
    /// Estimated Δt_crit.
    pub estimate: f64,
    /// Observed threshold / estimate.
    pub observed_ratio: f64,
    /// (Δt/Δt_crit, growth) at [`RATIOS`].
    pub runs: Vec<(f64, Growth)>,
}

/// The critical-step map on `meshes`, frictionless and with friction.
///
/// # Errors
/// A failed run.
pub fn critical_map(meshes: &[(&str, Mesh)], steps: usize) -> Result<Vec<CriticalRow>, String> {
    let mut rows = Vec::new();
    for (name, mesh) in meshes {
        for friction in [false, true] {
            let slab = slab::paper(mesh, 1e-4, LoadKind::Step, friction)?;
            let runs = RATIOS
                .iter()
                .map(|&r| growth(&slab, r, steps).map(|g| (r, g)))
                .collect::<Result<Vec<_>, _>>()?;
            let observed = threshold(&slab, 0.5, 2.0, 1e-4, steps)?;
            rows.push(CriticalRow {
                mesh: name.to_string(),
                friction,
                estimate: estimate(&slab),
                observed_ratio: observed,
                runs,
            });
        }
    }
    Ok(rows)
}

/// The ringing of σ_T at a node while it is stuck after having slipped.
#[derive(Clone, Debug)]
pub struct Ringing {
    /// Method.
    pub method: Method,
    /// ε.
    pub eps: f64,
    /// Normal Δt.
    pub dt: f64,
    /// x = Δt·w_J·g/(ε·m_J) at the node (m_J its HRZ lumped mass): the
    /// stuck node's damping c = w_J g/ε against its mass over one step. The
    /// trapezoidal update of m v̇ = −c v multiplies v by (1 − x/2)/(1 + x/2)
    /// per step: negative (ringing) for x > 2, → −1 (undamped) as x → ∞.
    pub ratio: f64,
    /// Alternating component of σ_T, / g: the median of |Δ⁴σ| / (16 g) over
    /// the normal steps of the stuck intervals (a pure (−1)^k a has fourth
    /// difference 16a; smooth motion contributes O(Δt⁴), the kinks where
    /// neighbours change class a few isolated values the median ignores).
    pub amplitude: f64,
    /// The largest |Δ⁴σ| / (16 g) (kinks included).
    pub max: f64,
    /// Normal steps examined.
    pub window: usize,
    /// Stuck intervals (after a slip) examined.
    pub intervals: usize,
}

/// Runs `method` on `slab` and measures the ringing of σ_T at mesh node
/// `node` over every interval in which it is stuck after having slipped,
/// from the first normal step after the sticking step (that step holds the
/// jump from slip to stick, which is physics, not ringing). None: the node
/// never stays stuck for 5 normal steps after a slip.
///
/// # Errors
/// A failed run.
pub fn ringing(
    slab: &Slab,
    node: usize,
    method: Method,
    dt: f64,
    eps: f64,
    t_end: f64,
) -> Result<Option<Ringing>, String> {
    let c = slab
        .contact_index(node)
        .ok_or_else(|| format!("node {node} is not a contact node"))?;
    let contact = slab.contact.as_ref().ok_or("no contact surface")?;
    let cn = &contact.nodes[c];
    let dof = cn.dofs[0].ok_or("the node has no free x DOF")?;
    let ratio = dt * cn.weight * G / (eps * slab.model.lumped_mass[dof]);
    let mut i = slab
        .integrator(method.settings(dt, t_end))
        .map_err(|e| e.to_string())?;
    let mut stress = vec![0.0; contact.len()];
    let mut slipped = false;
    let mut current: Option<Vec<f64>> = None;
    let mut intervals: Vec<Vec<f64>> = Vec::new();
    while !i.done() {
        let info = i.step().map_err(|e| e.to_string())?;
        let stuck = i.classes()[c].is_stuck();
        if !stuck {
            slipped = true;
            if let Some(w) = current.take() {
                intervals.push(w);
            }
            continue;
        }
        if !slipped {
            continue;
        }
        match current.as_mut() {
            // The sticking step itself: not sampled.
            None => current = Some(Vec::new()),
            Some(w) => {
                // Normal steps only: the reduced ones are the cure.
                if info.dt >= 0.5 * dt {
                    i.friction_stress(&mut stress);
                    w.push(stress[c]);
                }
            }
        }
    }
    intervals.extend(current);
    let used: Vec<&Vec<f64>> = intervals.iter().filter(|w| w.len() >= 5).collect();
    if used.is_empty() {
        return Ok(None);
    }
    let mut d4: Vec<f64> = used
        .iter()
        .flat_map(|w| {
            w.windows(5)
                .map(|s| (s[0] - 4.0 * s[1] + 6.0 * s[2] - 4.0 * s[3] + s[4]).abs() / (16.0 * G))
        })
        .collect();
    d4.sort_by(f64::total_cmp);
    let amplitude = d4[d4.len() / 2];
    let max = d4[d4.len() - 1];
    Ok(Some(Ringing {
        method,
        eps,
        dt,
        ratio,
        amplitude,
        max,
        window: used.iter().map(|w| w.len()).sum(),
        intervals: used.len(),
    }))
}

/// The paper's normal step of each method (§4.3).
pub fn paper_dt(method: Method) -> f64 {
    if method == Method::CentralDifference {
        1e-3
    } else {
        5e-3
    }
}

/// Stick/slip iteration statistics of one run.
#[derive(Clone, Debug)]
pub struct IterationRow {
    /// "cd" (ExplicitFriction::Iterate) or Newmark.
    pub scheme: &'static str,
    /// ε.
    pub eps: f64,
    /// Remark 4.2 on.
    pub remark: bool,
    /// Steps whose iteration hit the cap.
    pub failed: usize,
    /// Steps.
    pub steps: u64,
    /// Iterations summed over the steps that converged.
    pub iterations: u64,
    /// Largest iteration count of a converged step.
    pub max_iterations: usize,
}

/// Cap of the iteration in the iteration study.
pub const ITERATION_CAP: usize = 50;

/// Runs the slab with the iterated friction, Remark 4.2 on or off. A step
/// that hits the cap is counted and then taken with Remark 4.2 from the same
/// state (checkpoint/restore) so that the run goes on along the regularized
/// solution and every step is tried.
///
/// # Errors
/// A failure other than the iteration cap.
pub fn iteration_run(
    slab: &Slab,
    scheme: Scheme,
    dt: f64,
    remark: bool,
    t_end: f64,
) -> Result<IterationRow, String> {
    let build = |remark_4_2: bool| -> Result<Integrator, String> {
        let mut s = Settings::new(scheme, dt, t_end);
        s.explicit_friction = ExplicitFriction::Iterate;
        s.iteration = IterationOptions {
            remark_4_2,
            max_iterations: ITERATION_CAP,
        };
        slab.integrator(s).map_err(|e| e.to_string())
    };
    let mut i = build(remark)?;
    let mut rescue = if remark { None } else { Some(build(true)?) };
    let (mut failed, mut iterations, mut max_it) = (0, 0u64, 0);
    while !i.done() {
        match i.step() {
            Ok(info) => {
                iterations += info.iterations as u64;
                max_it = max_it.max(info.iterations);
            }
            Err(TimeError::IterationCap { .. }) => {
                failed += 1;
                let r = rescue.as_mut().ok_or("Remark 4.2 run hit the cap")?;
                r.restore(&i.checkpoint()).map_err(|e| e.to_string())?;
                r.step().map_err(|e| e.to_string())?;
                i.restore(&r.checkpoint()).map_err(|e| e.to_string())?;
            }
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(IterationRow {
        scheme: if scheme == Scheme::CentralDifference {
            "cd"
        } else {
            "nm-0.25-0.5"
        },
        eps: 0.0,
        remark,
        failed,
        steps: i.steps(),
        iterations,
        max_iterations: max_it,
    })
}

/// `stickslip-study stability`: the three studies, CSV + charts in `out`.
///
/// # Errors
/// A failed run or an unwritable output.
pub fn main(out: &Path, quick: bool) -> Result<(), String> {
    let start = std::time::Instant::now();
    let mesh_names: &[&str] = if quick {
        &["slab-q1-16x4.msh", "slab-q2-8x2.msh"]
    } else {
        &[
            "slab-q1-16x4.msh",
            "slab-q1-32x8.msh",
            "slab-q2-8x2.msh",
            "slab-q2-16x4.msh",
        ]
    };
    let meshes = mesh_names
        .iter()
        .map(|n| read_mesh(n).map(|m| (*n, m)))
        .collect::<Result<Vec<_>, _>>()?;
    let steps = if quick { 1000 } else { STABILITY_STEPS };

    // 1. Critical step.
    let crit = critical_map(&meshes, steps)?;
    let mut csv = String::from("mesh,friction,dt_crit_estimate,observed_over_estimate");
    for r in RATIOS {
        let _ = write!(csv, ",growth_at_{r},stable_at_{r}");
    }
    csv.push('\n');
    for r in &crit {
        let _ = write!(
            csv,
            "{},{},{:.6e},{:.5}",
            r.mesh, r.friction, r.estimate, r.observed_ratio
        );
        for (_, g) in &r.runs {
            let _ = write!(csv, ",{:.4e},{}", g.growth, g.stable());
        }
        csv.push('\n');
        eprintln!(
            "critical {:20} friction {:5} estimate {:.5e} observed/estimate {:.5} growth {:?}",
            r.mesh,
            r.friction,
            r.estimate,
            r.observed_ratio,
            r.runs.iter().map(|(_, g)| g.growth).collect::<Vec<_>>()
        );
    }
    write(out, "stability-critical.csv", &csv)?;
    let mut panel = Panel {
        title: "Central difference: energy growth max (K+U)/(K+U)₀ over the run".into(),
        x_label: "Δt / Δt_crit (Lanczos estimate)".into(),
        y_label: "energy growth".into(),
        x_log: true,
        y_log: true,
        series: Vec::new(),
        vlines: vec![1.0],
        legend: true,
    };
    for (k, r) in crit.iter().enumerate() {
        panel.series.push(Series {
            label: format!(
                "{} {}, threshold {:.4}",
                r.mesh.trim_end_matches(".msh"),
                if r.friction {
                    "friction"
                } else {
                    "no friction"
                },
                r.observed_ratio
            ),
            color: COLORS[(k / 2) % COLORS.len()],
            marker: if r.friction {
                Marker::Cross
            } else {
                Marker::Circle
            },
            filled: true,
            line: !r.friction,
            points: r
                .runs
                .iter()
                .map(|(x, g)| (*x, g.growth.min(1e30)))
                .collect(),
        });
    }
    plot::save(&out.join("stability-critical"), &[panel], &[], 1, 1000, 620)?;

    // 2. Ringing after sticking, node (7, 0) of the paper's mesh under H(t).
    let eps_ladder: &[f64] = if quick {
        &[1e-2, 1e-4]
    } else {
        &[1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6]
    };
    let mesh = &meshes
        .iter()
        .find(|m| m.0 == "slab-q2-8x2.msh")
        .ok_or("the paper's mesh")?
        .1;
    let mut rings = Vec::new();
    for method in Method::ALL {
        for &eps in eps_ladder {
            let slab = slab::paper(mesh, eps, LoadKind::Step, true)?;
            let node = slab.node_at(7.0, 0.0).map_err(|e| e.to_string())?;
            if let Some(r) = ringing(&slab, node, method, paper_dt(method), eps, 0.5)? {
                eprintln!(
                    "ringing {:20} eps {:.0e} x {:.3e} amplitude/g {:.3e} max {:.3e} steps {} intervals {}",
                    method.name(),
                    eps,
                    r.ratio,
                    r.amplitude,
                    r.max,
                    r.window,
                    r.intervals
                );
                rings.push(r);
            } else {
                eprintln!(
                    "ringing {:20} eps {eps:.0e}: node (7, 0) never stays stuck for 5 steps after slipping",
                    method.name()
                );
            }
        }
    }
    let mut csv = String::from(
        "method,eps,dt,ratio_dt_w_g_over_eps_m,amplitude_over_g,max_over_g,steps_examined,stuck_intervals\n",
    );
    for r in &rings {
        let _ = writeln!(
            csv,
            "{},{:e},{:e},{:.6e},{:.6e},{:.6e},{},{}",
            r.method.name(),
            r.eps,
            r.dt,
            r.ratio,
            r.amplitude,
            r.max,
            r.window,
            r.intervals
        );
    }
    write(out, "stability-ringing.csv", &csv)?;
    let panel = Panel {
        title: "Ringing of σ_T at (7, 0) after it sticks (paper's mesh, H(t))".into(),
        x_label: "x = Δt·w·g / (ε·m)".into(),
        y_label: "alternating part of σ_T / g (median)".into(),
        x_log: true,
        y_log: true,
        series: Method::ALL
            .iter()
            .enumerate()
            .map(|(k, m)| Series {
                label: format!("{} (Δt = {:.0e})", m.label(), paper_dt(*m)),
                color: COLORS[k],
                marker: [
                    Marker::Circle,
                    Marker::Square,
                    Marker::Triangle,
                    Marker::Cross,
                ][k],
                filled: true,
                line: true,
                points: rings
                    .iter()
                    .filter(|r| r.method == *m)
                    .map(|r| (r.ratio, r.amplitude.max(1e-16)))
                    .collect(),
            })
            .collect(),
        vlines: vec![2.0],
        legend: true,
    };
    plot::save(&out.join("stability-ringing"), &[panel], &[], 1, 1000, 620)?;

    // 3. The iteration with and without Remark 4.2.
    let mut iters = Vec::new();
    for &eps in eps_ladder {
        let slab = slab::paper(mesh, eps, LoadKind::Step, true)?;
        for (scheme, dt) in [(Scheme::CentralDifference, 1e-3), (TRAPEZOIDAL, 5e-3)] {
            for remark in [true, false] {
                let mut row = iteration_run(&slab, scheme, dt, remark, 0.5)?;
                row.eps = eps;
                eprintln!(
                    "iteration {:12} eps {:.0e} remark {:5} failed {:4} / {} steps, iterations {} (max {})",
                    row.scheme, eps, remark, row.failed, row.steps, row.iterations, row.max_iterations
                );
                iters.push(row);
            }
        }
    }
    let mut csv = String::from(
        "scheme,eps,remark_4_2,failed_steps,steps,iterations,max_iterations_per_step\n",
    );
    for r in &iters {
        let _ = writeln!(
            csv,
            "{},{:e},{},{},{},{},{}",
            r.scheme, r.eps, r.remark, r.failed, r.steps, r.iterations, r.max_iterations
        );
    }
    write(out, "stability-iteration.csv", &csv)?;
    let mut series = Vec::new();
    for (k, (scheme, remark)) in [
        ("cd", true),
        ("cd", false),
        ("nm-0.25-0.5", true),
        ("nm-0.25-0.5", false),
    ]
    .into_iter()
    .enumerate()
    {
        series.push(Series {
            label: format!(
                "{}, Remark 4.2 {}",
                if scheme == "cd" {
                    "central difference (iterated)"
                } else {
                    "Newmark ¼,½"
                },
                if remark { "on" } else { "off" }
            ),
            color: COLORS[k],
            marker: if remark {
                Marker::Circle
            } else {
                Marker::Cross
            },
            filled: true,
            line: true,
            points: iters
                .iter()
                .filter(|r| r.scheme == scheme && r.remark == remark)
                .map(|r| (r.eps, r.failed as f64))
                .collect(),
        });
    }
    let panel = Panel {
        title: format!("Stick/slip iteration: steps hitting the cap of {ITERATION_CAP} (paper's mesh, H(t), t ≤ 0.5)"),
        x_label: "ε".into(),
        y_label: "failed steps".into(),
        x_log: true,
        y_log: false,
        series,
        vlines: Vec::new(),
        legend: true,
    };
    plot::save(
        &out.join("stability-iteration"),
        &[panel],
        &[],
        1,
        1000,
        620,
    )?;
    // 4. The critical step with a compliant wall.
    crate::stability_compliance::main(out)?;
    eprintln!(
        "stability study done in {:.0} s; wrote {}/stability-*",
        start.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

fn write(out: &Path, name: &str, text: &str) -> Result<(), String> {
    let p = out.join(name);
    std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
}
