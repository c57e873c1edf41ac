//! The work-precision study (issue 6, deliverable 1): every combination of
//! element order, mesh, method and Δt (and an ε ladder at a fixed
//! discretization) run on the paper's slab, timed (median of repeats) and
//! compared with a converged reference.
//!
//! Errors, all against the reference sampled on the same uniform grid of
//! [`SAMPLES`] times in [0, 0.5] (linear interpolation between steps):
//! relative L2-in-time error of u_x at (8, 0) and (8, 1), normalized by the
//! reference's motion ‖u_x − u_x(0)‖ (the initial state is exact on every
//! mesh: u_x = 0.117x, BENCHMARK.md); of σ_T at (7, 0), normalized by
//! ‖σ_T‖; and |E(0.5) − E_ref(0.5)| / |E_ref(0.5) − E_ref(0)|, the error of
//! the energy at t = 0.5 relative to the energy the run loses.

use std::fmt::Write as _;
use std::path::Path;

use stickslip_case::pilot::{self, relative_l2, sample, Trace};
use stickslip_case::{Case, Method};

use crate::plot::{self, Marker, Panel, Series, COLORS};
use crate::run::{configured, paper_case, timed_run, SIGMA_7_0, UX_8_0, UX_8_1};
use crate::slab::LoadKind;

/// End time of every run (the paper's plots end at 0.5).
pub const T_END: f64 = 0.5;
/// Sample times for the L2-in-time norms (spacing 1e-4).
pub const SAMPLES: usize = 5001;
/// The paper's ε.
pub const EPS: f64 = 1e-4;

/// A reference solution sampled on the grid.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Load history.
    pub load: LoadKind,
    /// The sample times.
    pub grid: Vec<f64>,
    /// u_x(8, 0), u_x(8, 1), σ_T(7, 0) at the sample times.
    pub ux81: Vec<f64>,
    /// See `ux81`.
    pub ux85: Vec<f64>,
    /// See `ux81`.
    pub sigma71: Vec<f64>,
    /// E(0) and E(0.5).
    pub energy0: f64,
    /// See `energy0`.
    pub energy_end: f64,
}

/// The four error measures of a run against a reference.
#[derive(Clone, Copy, Debug, Default)]
pub struct Errors {
    /// u_x at (8, 0).
    pub ux81: f64,
    /// u_x at (8, 1).
    pub ux85: f64,
    /// σ_T at (7, 0).
    pub sigma71: f64,
    /// E(0.5).
    pub energy: f64,
}

impl Errors {
    /// The measures as an array, in [`MEASURES`] order.
    pub fn as_array(self) -> [f64; 4] {
        [self.ux81, self.ux85, self.sigma71, self.energy]
    }
}

/// Names of the error measures (CSV columns and chart titles).
pub const MEASURES: [(&str, &str); 4] = [
    ("err_ux_8_0", "u_x at (8, 0), relative L2 in time"),
    ("err_ux_8_1", "u_x at (8, 1), relative L2 in time"),
    ("err_sigma_7_0", "σ_T at (7, 0), relative L2 in time"),
    (
        "err_energy_0_5",
        "E(0.5), relative to E_ref(0) − E_ref(0.5)",
    ),
];

impl Reference {
    /// Samples a trace.
    pub fn from_trace(load: LoadKind, tr: &Trace) -> Reference {
        let grid = pilot::grid(T_END, SAMPLES);
        Reference {
            load,
            ux81: sample(&tr.t, &tr.values[UX_8_0], &grid),
            ux85: sample(&tr.t, &tr.values[UX_8_1], &grid),
            sigma71: sample(&tr.t, &tr.values[SIGMA_7_0], &grid),
            grid,
            energy0: tr.energy0,
            energy_end: tr.energy_end,
        }
    }

    /// The errors of `tr` against this reference.
    pub fn errors(&self, tr: &Trace) -> Errors {
        let s = |y: &[f64]| sample(&tr.t, y, &self.grid);
        Errors {
            ux81: relative_l2(&s(&tr.values[UX_8_0]), &self.ux81, self.ux81[0]),
            ux85: relative_l2(&s(&tr.values[UX_8_1]), &self.ux85, self.ux85[0]),
            sigma71: relative_l2(&s(&tr.values[SIGMA_7_0]), &self.sigma71, 0.0),
            energy: (tr.energy_end - self.energy_end).abs()
                / (self.energy_end - self.energy0).abs(),
        }
    }
}

/// One row of the CSV.
#[derive(Clone, Debug)]
pub struct Row {
    /// `dt` (the order × mesh × method × Δt ladder), `eps` (the ε ladder),
    /// `reference` or `refcheck` (the convergence check of the reference).
    pub study: &'static str,
    /// Load history.
    pub load: LoadKind,
    /// Element order (1 or 2).
    pub order: u8,
    /// Mesh file.
    pub mesh: String,
    /// Method.
    pub method: Method,
    /// Normal step.
    pub dt: f64,
    /// Δt / Δt_crit (central difference only; NaN otherwise).
    pub dt_over_crit: f64,
    /// ε.
    pub eps: f64,
    /// The run's trace summary (DOFs, steps, iterations, factorizations).
    pub dofs: usize,
    /// Steps.
    pub steps: u64,
    /// Stick/slip iterations.
    pub iterations: u64,
    /// Factorizations.
    pub factorizations: u64,
    /// Wall times of the repeats, seconds, sorted.
    pub times: Vec<f64>,
    /// Errors.
    pub errors: Errors,
    /// E(0.5).
    pub energy_end: f64,
}

impl Row {
    /// Median wall time.
    pub fn time(&self) -> f64 {
        self.times[self.times.len() / 2]
    }
}

const CSV_HEADER: &str = "study,load,order,mesh,dofs,method,dt,dt_over_crit,eps,steps,iterations,\
factorizations,time_s,time_min_s,time_max_s,repeats,err_ux_8_0,err_ux_8_1,err_sigma_7_0,\
err_energy_0_5,energy_0_5";

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for r in rows {
        let e = r.errors;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:e},{:.4},{:e},{},{},{},{:.6},{:.6},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.8}",
            r.study,
            r.load.name(),
            r.order,
            r.mesh,
            r.dofs,
            r.method.name(),
            r.dt,
            r.dt_over_crit,
            r.eps,
            r.steps,
            r.iterations,
            r.factorizations,
            r.time(),
            r.times[0],
            r.times[r.times.len() - 1],
            r.times.len(),
            e.ux81,
            e.ux85,
            e.sigma71,
            e.energy,
            r.energy_end
        );
    }
    s
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Load histories.
    pub loads: Vec<LoadKind>,
    /// (order, mesh file) ladder.
    pub meshes: Vec<(u8, &'static str)>,
    /// Newmark Δt ladder.
    pub newmark_dt: Vec<f64>,
    /// Central difference Δt as fractions of the mesh's Δt_crit.
    pub cd_fractions: Vec<f64>,
    /// ε ladder (at `eps_mesh`, Newmark ¼,½ + reduction at `eps_dt` and
    /// central difference at the first of `cd_fractions`).
    pub eps: Vec<f64>,
    /// Mesh of the ε ladder.
    pub eps_mesh: (u8, &'static str),
    /// Newmark Δt of the ε ladder.
    pub eps_dt: f64,
    /// Timing repeats.
    pub repeats: usize,
    /// Reference: mesh, Δt, and the next-coarser mesh for the check.
    pub reference: (&'static str, f64, &'static str),
}

impl Plan {
    /// The full study (about 10 minutes on a loaded 2-core machine).
    pub fn full() -> Plan {
        Plan {
            loads: vec![LoadKind::Step, LoadKind::Sin],
            meshes: vec![
                (1, "slab-q1-16x4.msh"),
                (1, "slab-q1-32x8.msh"),
                (1, "slab-q1-64x16.msh"),
                (1, "slab-q1-128x32.msh"),
                (2, "slab-q2-8x2.msh"),
                (2, "slab-q2-16x4.msh"),
                (2, "slab-q2-32x8.msh"),
                (2, "slab-q2-64x16.msh"),
            ],
            newmark_dt: vec![1e-2, 5e-3, 2.5e-3],
            cd_fractions: vec![0.9, 0.45, 0.225],
            eps: vec![1.0, 1e-1, 1e-2, 1e-3],
            eps_mesh: (2, "slab-q2-16x4.msh"),
            eps_dt: 2.5e-3,
            repeats: 3,
            reference: ("slab-q2-64x16.msh", 2e-4, "slab-q2-32x8.msh"),
        }
    }

    /// A smoke test: two meshes per order, one load, one repeat.
    pub fn quick() -> Plan {
        Plan {
            loads: vec![LoadKind::Step],
            meshes: vec![
                (1, "slab-q1-16x4.msh"),
                (1, "slab-q1-32x8.msh"),
                (2, "slab-q2-8x2.msh"),
                (2, "slab-q2-16x4.msh"),
            ],
            newmark_dt: vec![1e-2, 5e-3],
            cd_fractions: vec![0.9, 0.45],
            eps: vec![1.0, 1e-2],
            eps_mesh: (2, "slab-q2-8x2.msh"),
            eps_dt: 5e-3,
            repeats: 1,
            reference: ("slab-q2-32x8.msh", 1e-3, "slab-q2-16x4.msh"),
        }
    }
}

/// The reference method: the trapezoidal rule (no numerical damping,
/// second order) with the paper's step reduction, so that the friction
/// stress does not ring after sticking.
pub const REFERENCE_METHOD: Method = Method::TrapezoidalReduced;

/// The committed meshes' Δt_crit (central difference, lumped mass), each
/// computed once.
struct Meshes(Vec<(&'static str, f64)>);

impl Meshes {
    /// Δt_crit of the mesh `name` in `case`.
    fn crit(&mut self, case: &Case, name: &'static str) -> Result<f64, String> {
        if let Some(&(_, crit)) = self.0.iter().find(|m| m.0 == name) {
            return Ok(crit);
        }
        // A Newmark set-up refuses no Δt: the model is all that is needed.
        let c = configured(case, name, Method::Trapezoidal, T_END / 50.0, EPS, T_END);
        let p = stickslip_case::prepare(&c).map_err(|e| e.to_string())?;
        let crit =
            stickslip_time::stability::critical_step(&p.model.stiffness, &p.model.lumped_mass);
        self.0.push((name, crit));
        Ok(crit)
    }
}

#[allow(clippy::too_many_arguments)]
fn measure(
    meshes: &mut Meshes,
    case: &Case,
    reference: &Reference,
    study: &'static str,
    order: u8,
    mesh_name: &'static str,
    method: Method,
    dt: f64,
    eps: f64,
    repeats: usize,
) -> Result<Row, String> {
    let crit = meshes.crit(case, mesh_name)?;
    let c = configured(case, mesh_name, method, dt, eps, T_END);
    let mut times = Vec::with_capacity(repeats);
    let mut first = None;
    for _ in 0..repeats.max(1) {
        let tr = timed_run(&c)
            .map_err(|e| format!("{mesh_name} {} Δt = {dt:e} ε = {eps:e}: {e}", method.name()))?;
        times.push(tr.secs);
        first.get_or_insert(tr);
    }
    times.sort_by(f64::total_cmp);
    let tr = first.expect("at least one repeat");
    Ok(Row {
        study,
        load: reference.load,
        order,
        mesh: mesh_name.to_string(),
        method,
        dt,
        dt_over_crit: if method == Method::CentralDifference {
            dt / crit
        } else {
            f64::NAN
        },
        eps,
        dofs: tr.dofs,
        steps: tr.steps,
        iterations: tr.iterations,
        factorizations: tr.factorizations,
        times,
        errors: reference.errors(&tr),
        energy_end: tr.energy_end,
    })
}

/// Runs the plan; returns every row (reference checks first).
///
/// # Errors
/// A mesh that does not read or a run that fails.
pub fn study(plan: &Plan, mut progress: impl FnMut(&Row)) -> Result<Vec<Row>, String> {
    let mut meshes = Meshes(Vec::new());
    let mut rows = Vec::new();
    let (ref_mesh, ref_dt, coarser) = plan.reference;
    let order_of = |name: &str| if name.contains("-q1-") { 1 } else { 2 };
    for &load in &plan.loads {
        let case = paper_case(load)?;
        let tr = timed_run(&configured(
            &case,
            ref_mesh,
            REFERENCE_METHOD,
            ref_dt,
            EPS,
            T_END,
        ))?;
        let reference = Reference::from_trace(load, &tr);
        let row = Row {
            study: "reference",
            load,
            order: 2,
            mesh: ref_mesh.to_string(),
            method: REFERENCE_METHOD,
            dt: ref_dt,
            dt_over_crit: f64::NAN,
            eps: EPS,
            dofs: tr.dofs,
            steps: tr.steps,
            iterations: tr.iterations,
            factorizations: tr.factorizations,
            times: vec![tr.secs],
            errors: reference.errors(&tr),
            energy_end: tr.energy_end,
        };
        progress(&row);
        rows.push(row);
        // Convergence of the reference: the same method at 2Δt on the same
        // mesh, at Δt on the next-coarser mesh, and central difference at
        // Δt_crit/4 on the same mesh (another scheme, another mass).
        let crit = meshes.crit(&case, ref_mesh)?;
        for (m, method, dt) in [
            (ref_mesh, REFERENCE_METHOD, 2.0 * ref_dt),
            (coarser, REFERENCE_METHOD, ref_dt),
            (ref_mesh, Method::CentralDifference, 0.25 * crit),
        ] {
            let row = measure(
                &mut meshes,
                &case,
                &reference,
                "refcheck",
                order_of(m),
                m,
                method,
                dt,
                EPS,
                1,
            )?;
            progress(&row);
            rows.push(row);
        }
        for &(order, m) in &plan.meshes {
            let crit = meshes.crit(&case, m)?;
            for method in Method::ALL {
                let dts: Vec<f64> = if method == Method::CentralDifference {
                    plan.cd_fractions.iter().map(|f| f * crit).collect()
                } else {
                    plan.newmark_dt.clone()
                };
                for dt in dts {
                    let row = measure(
                        &mut meshes,
                        &case,
                        &reference,
                        "dt",
                        order,
                        m,
                        method,
                        dt,
                        EPS,
                        plan.repeats,
                    )?;
                    progress(&row);
                    rows.push(row);
                }
            }
        }
        let (order, m) = plan.eps_mesh;
        let crit = meshes.crit(&case, m)?;
        for &eps in &plan.eps {
            for (method, dt) in [
                (Method::CentralDifference, plan.cd_fractions[0] * crit),
                (Method::TrapezoidalReduced, plan.eps_dt),
            ] {
                let row = measure(
                    &mut meshes,
                    &case,
                    &reference,
                    "eps",
                    order,
                    m,
                    method,
                    dt,
                    eps,
                    plan.repeats,
                )?;
                progress(&row);
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// The Pareto front of (time, error) points: the points no other point
/// beats in both, sorted by time.
pub fn pareto(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(t, e)| t.is_finite() && e.is_finite() && *e > 0.0)
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if front.last().is_none_or(|l| q.1 < l.1) {
            front.push(q);
        }
    }
    front
}

fn marker(method: Method) -> Marker {
    match method {
        Method::CentralDifference => Marker::Circle,
        Method::Trapezoidal => Marker::Square,
        Method::TrapezoidalReduced => Marker::Triangle,
        Method::Damped => Marker::Cross,
    }
}

/// The chart panels: one per (error measure, load).
pub fn panels(rows: &[Row], loads: &[LoadKind]) -> Vec<Panel> {
    let mut panels = Vec::new();
    for (k, (_, title)) in MEASURES.iter().enumerate() {
        for &load in loads {
            let mut series = Vec::new();
            let mut all = Vec::new();
            for (mi, method) in Method::ALL.iter().enumerate() {
                for order in [1u8, 2] {
                    let pts: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(|r| {
                            r.study == "dt"
                                && r.load == load
                                && r.method == *method
                                && r.order == order
                        })
                        .map(|r| (r.time(), r.errors.as_array()[k]))
                        .collect();
                    all.extend(pts.iter().copied());
                    series.push(Series {
                        label: format!("{} Q{order}", method.label()),
                        color: COLORS[mi],
                        marker: marker(*method),
                        filled: order == 2,
                        line: false,
                        points: pts,
                    });
                }
            }
            for method in [Method::CentralDifference, Method::TrapezoidalReduced] {
                let pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.study == "eps" && r.load == load && r.method == method)
                    .map(|r| (r.time(), r.errors.as_array()[k]))
                    .collect();
                series.push(Series {
                    label: format!("ε ladder, {}", method.label()),
                    color: COLORS[5],
                    marker: marker(method),
                    filled: false,
                    line: false,
                    points: pts,
                });
            }
            series.push(Series {
                label: "Pareto front".into(),
                color: plotters::style::RGBColor(0, 0, 0),
                marker: Marker::None,
                filled: false,
                line: true,
                points: pareto(&all),
            });
            panels.push(Panel {
                title: format!("{title}, θ = {}", load_label(load)),
                x_label: "wall time per run, s (median)".into(),
                y_label: "error".into(),
                x_log: true,
                y_log: true,
                series,
                vlines: Vec::new(),
                legend: false,
            });
        }
    }
    panels
}

fn load_label(load: LoadKind) -> &'static str {
    match load {
        LoadKind::Step => "H(t)",
        LoadKind::Sin => "sin 8πt",
    }
}

/// `stickslip-study chart`: runs the study, writes
/// `out/work-precision.csv`, `.png` and `.svg`.
///
/// # Errors
/// A failed run or an unwritable output.
pub fn main(out: &Path, quick: bool) -> Result<(), String> {
    let plan = if quick { Plan::quick() } else { Plan::full() };
    let start = std::time::Instant::now();
    let rows = study(&plan, |r| {
        eprintln!(
            "{:9} {:7} Q{} {:20} {:20} dt {:.3e} eps {:.0e} steps {:5} t {:7.3}s  err {:.2e} {:.2e} {:.2e} {:.2e}",
            r.study,
            r.load.name(),
            r.order,
            r.mesh,
            r.method.name(),
            r.dt,
            r.eps,
            r.steps,
            r.time(),
            r.errors.ux81,
            r.errors.ux85,
            r.errors.sigma71,
            r.errors.energy
        )
    })?;
    let stem = out.join("work-precision");
    let path = stem.with_extension("csv");
    std::fs::write(&path, csv(&rows)).map_err(|e| format!("{}: {e}", path.display()))?;
    let panels = panels(&rows, &plan.loads);
    let legend: Vec<Series> = panels
        .first()
        .map(|p| {
            p.series
                .iter()
                .map(|s| Series {
                    points: Vec::new(),
                    ..s.clone()
                })
                .collect()
        })
        .unwrap_or_default();
    let written = plot::save(&stem, &panels, &legend, plan.loads.len(), 760, 480)?;
    eprintln!(
        "wrote {} and {} ({} runs in {:.0} s)",
        path.display(),
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        rows.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
