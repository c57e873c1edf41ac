//! The pilot plan and what it measures: every candidate configuration of
//! the ladder with its estimated error and predicted time.

use std::time::Instant;

use stickslip_case::{Case, Method};

use super::candidates::Candidate;
use super::errors::{
    continue_errors, continue_errors_above, dt_error, ladder_errors, with_reference,
};
use super::input;
use super::ladder::{eps_of, read_ladder, LadderMesh};
use super::pilots::{Pilot, Pilots};
use super::quantity::{distance, grid, Quantity};

/// Central-difference Δt as fractions of Δt_crit (as in the chart).
pub const CD_FRACTIONS: [f64; 3] = [0.9, 0.45, 0.225];
/// Newmark Δt = t_end / these.
pub const NEWMARK_DIVISIONS: [f64; 4] = [50.0, 100.0, 200.0, 400.0];
/// ε candidates: the case's ε times these.
pub const EPS_FACTORS: [f64; 3] = [1.0, 10.0, 100.0];

/// Everything the pilots measured: the candidates with their estimates.
#[derive(Clone, Debug)]
pub struct Estimates {
    /// The quantity.
    pub quantity: Quantity,
    /// The ladder.
    pub ladder: Vec<LadderMesh>,
    /// Every candidate.
    pub candidates: Vec<Candidate>,
    /// The pilot runs.
    pub pilots: Vec<Pilot>,
    /// Total wall time of the pilots and the ladder's set-up, seconds.
    pub seconds: f64,
    /// Per ladder: what, the order used (NaN where none is), and its
    /// numbers: the reference's measured differences, the estimated errors
    /// per mesh (h ladders), the changes per Δt or ε.
    pub orders: Vec<(String, f64, Vec<f64>)>,
    /// Remarks for the report (probe positions that differ, skipped meshes).
    pub notes: Vec<String>,
}

/// The pilot runs and every candidate's estimate (independent of the
/// tolerance: [`pick`](super::pick) then chooses). `log` receives one
/// line per pilot.
///
/// # Errors
/// As [`read_ladder`]; a pilot run that fails.
pub fn estimate(
    case: &Case,
    q: Quantity,
    at: Option<[f64; 2]>,
    log: &mut dyn FnMut(&str),
) -> anyhow::Result<Estimates> {
    let start = Instant::now();
    let ladder = read_ladder(case, q, at)?;
    let mut notes = Vec::new();
    if let Some(first) = ladder.iter().find_map(|m| m.node_at) {
        for m in &ladder {
            if let Some(p) = m.node_at {
                if (p[0] - first[0]).hypot(p[1] - first[1])
                    > 1e-9 * (1.0 + first[0].hypot(first[1]))
                {
                    notes.push(format!(
                        "the probed node of {} is at ({}, {}), not at ({}, {}) as on {}: its differences mix places",
                        m.text, p[0], p[1], first[0], first[1], ladder[0].text
                    ));
                }
            }
        }
    }
    let t_end = case.time.t_end;
    let eps0 = eps_of(case);
    let g_all = grid(t_end);
    let nm_dt: Vec<f64> = NEWMARK_DIVISIONS.iter().map(|d| t_end / d).collect();
    let dt_h = t_end / 200.0;
    let mut pilots = Pilots {
        case,
        q,
        at,
        ladder: &ladder,
        runs: Vec::new(),
        log,
    };
    let mut orders = Vec::new();

    // h: per element order, the first three meshes of the ladder.
    struct Group {
        order: u8,
        meshes: Vec<usize>,
        ratios: Vec<f64>,
        /// Pilot runs per measured mesh: central difference, Newmark ¼/½.
        cd_runs: Vec<usize>,
        nm_runs: Vec<usize>,
        /// Seconds per step per stored entry of K: central difference, Newmark ¼/½.
        cost_cd: f64,
        cost_nm: f64,
    }
    let mut groups = Vec::new();
    for order in [1u8, 2] {
        let meshes: Vec<usize> = (0..ladder.len())
            .filter(|&m| ladder[m].order == order)
            .collect();
        if meshes.len() < 2 {
            if let Some(&m) = meshes.first() {
                notes.push(format!(
                    "{} is the only Q{order} mesh of the ladder: no h estimate for Q{order}, left out",
                    ladder[m].text
                ));
            }
            continue;
        }
        let ratios: Vec<f64> = meshes
            .windows(2)
            .map(|w| (ladder[w[1]].cells as f64 / ladder[w[0]].cells as f64).sqrt())
            .collect();
        if let Some(k) = ratios.iter().position(|r| r.is_nan() || *r <= 1.0) {
            return Err(input(format!(
                "{}mesh.ladder: {} has no more cells than {} before it; list the Q{order} meshes coarse to fine",
                case.at("mesh.ladder"),
                ladder[meshes[k + 1]].text,
                ladder[meshes[k]].text
            )));
        }
        let pilot_levels = meshes.len().min(3);
        let mut cd_runs = Vec::new();
        let mut nm_runs = Vec::new();
        for &m in &meshes[..pilot_levels] {
            cd_runs.push(pilots.run(
                m,
                Method::CentralDifference,
                CD_FRACTIONS[0] * ladder[m].dt_crit,
                eps0,
            )?);
            nm_runs.push(pilots.run(m, Method::Trapezoidal, dt_h, eps0)?);
        }
        groups.push(Group {
            order,
            cost_cd: pilots.cost(*cd_runs.last().expect("two levels")),
            cost_nm: pilots.cost(*nm_runs.last().expect("two levels")),
            meshes,
            ratios,
            cd_runs,
            nm_runs,
        });
    }
    if groups.is_empty() {
        return Err(input(format!(
            "{}mesh.ladder: advise needs at least two meshes of one element order (Q1 or Q2); add a refinement",
            case.at("mesh.ladder")
        )));
    }
    // The reference R: central difference at 0.9 Δt_crit (explicit, the
    // cheapest step) on the mesh after the pilots of the highest order, or
    // on its finest pilot when the ladder has no more. Its own error e_R
    // comes from the differences of its ladder ([`ladder_errors`]).
    let top = groups.len() - 1;
    {
        let g = &mut groups[top];
        if g.meshes.len() > g.cd_runs.len() {
            let m = g.meshes[g.cd_runs.len()];
            let k = pilots.run(
                m,
                Method::CentralDifference,
                CD_FRACTIONS[0] * ladder[m].dt_crit,
                eps0,
            )?;
            g.cd_runs.push(k);
        }
    }
    let (r_run, e_ref) = {
        let g = &groups[top];
        let d = pilots.diffs(&g.cd_runs, &g_all);
        let (e, p, c) = ladder_errors(
            &d,
            pilots.skip(&g.cd_runs, &g_all),
            &g.ratios,
            f64::from(g.order) + 1.0,
        );
        let n = g.cd_runs.len();
        orders.push((
            format!(
                "reference R = Q{} {} (central difference, 0.9 dt_crit): error {:.2e} from the Q{} differences (correlation {c:.2})",
                g.order,
                ladder[g.meshes[n - 1]].text,
                e[n - 1],
                g.order
            ),
            p,
            d,
        ));
        (g.cd_runs[n - 1], e[n - 1])
    };
    // The error of a pilot run X: X − R plus R's own error, added in
    // quadrature, e_X = √(‖X − R‖² + e_R²): the measured difference and
    // the reference's uncertainty combined as independent parts (as a
    // measurement's uncertainty is combined with its reference standard's).
    // This uses the distance to the most accurate run, not the differences
    // of neighbours, whose errors are only partly aligned (stick/slip
    // events move between refinements) so that Richardson's model of them
    // misjudges the finer level's error.
    let err_of = |pilots: &Pilots, k: usize| -> f64 {
        if k == r_run {
            e_ref
        } else {
            with_reference(
                distance(q, pilots.trace(k), pilots.trace(r_run), &g_all),
                e_ref,
            )
        }
    };
    // Errors of the (mesh, base Δt) configurations per order and family:
    // measured pilots, then finer meshes by the order observed from the
    // last two measured errors.
    let mut e_cd_all = Vec::new();
    let mut e_nm_all = Vec::new();
    for g in &groups {
        let max_order = f64::from(g.order) + 1.0;
        let mc: Vec<f64> = g.cd_runs.iter().map(|&k| err_of(&pilots, k)).collect();
        let (ec, pc) = continue_errors(&mc, &g.ratios, max_order);
        orders.push((
            format!(
                "errors, Q{} meshes, central difference (0.9 dt_crit)",
                g.order
            ),
            pc,
            ec.clone(),
        ));
        e_cd_all.push(ec);
    }
    // Δt and ε on the second mesh of the highest order: each run's change
    // from its family's base configuration on that mesh (central
    // difference at 0.9 Δt_crit; Newmark ¼/½ at t_end/200).
    let pm = groups[top].meshes[1];
    let crit = ladder[pm].dt_crit;
    let cd_runs: Vec<usize> = CD_FRACTIONS
        .iter()
        .map(|f| pilots.run(pm, Method::CentralDifference, f * crit, eps0))
        .collect::<anyhow::Result<_>>()?;
    let nm_base = pilots.run(pm, Method::Trapezoidal, dt_h, eps0)?;
    let d_dt_cd: Vec<f64> = cd_runs
        .iter()
        .map(|&k| distance(q, pilots.trace(k), pilots.trace(cd_runs[0]), &g_all))
        .collect();
    orders.push((
        "changes, dt, central difference (from 0.9 dt_crit)".into(),
        f64::NAN,
        d_dt_cd.clone(),
    ));
    let mut d_dt_nm = Vec::new();
    let mut nm_runs_by_method = Vec::new();
    for method in [
        Method::Trapezoidal,
        Method::TrapezoidalReduced,
        Method::Damped,
    ] {
        let runs: Vec<usize> = nm_dt
            .iter()
            .map(|&dt| pilots.run(pm, method, dt, eps0))
            .collect::<anyhow::Result<_>>()?;
        let d: Vec<f64> = runs
            .iter()
            .map(|&k| distance(q, pilots.trace(k), pilots.trace(nm_base), &g_all))
            .collect();
        orders.push((
            format!(
                "changes, dt, {} (from nm-0.25-0.5 at t_end/200)",
                method.name()
            ),
            f64::NAN,
            d.clone(),
        ));
        d_dt_nm.push((method, d));
        nm_runs_by_method.push((method, runs));
    }
    // Newmark's errors per mesh at t_end/200 hold that Δt's error, which
    // no mesh reduces: it is estimated from the ¼/½ changes at t_end/100
    // and t_end/400 on the pilot mesh (the same Δt on every mesh, so taken
    // as every mesh's) and held as a floor under the finer meshes' errors
    // ([`continue_errors_above`]; continued as mesh error, the errors of
    // finer meshes went below it).
    let k_h = NEWMARK_DIVISIONS
        .iter()
        .position(|d| *d == 200.0)
        .expect("t_end/200 in the ladder");
    let dt_floor = {
        let d = &d_dt_nm[0].1;
        dt_error(d[k_h - 1], d[k_h + 1], 2.0)
    };
    for g in &groups {
        let mn: Vec<f64> = g.nm_runs.iter().map(|&k| err_of(&pilots, k)).collect();
        let (en, pn) = continue_errors_above(&mn, &g.ratios, f64::from(g.order) + 1.0, dt_floor);
        orders.push((
            format!(
                "errors, Q{} meshes, Newmark (t_end/200; its dt error {dt_floor:.2e} held under finer meshes)",
                g.order
            ),
            pn,
            en.clone(),
        ));
        e_nm_all.push(en);
    }
    let mut d_eps = vec![0.0];
    let eps_list: Vec<f64> = if !case.contact.is_empty() {
        let base = cd_runs[0];
        for f in &EPS_FACTORS[1..] {
            let k = pilots.run(
                pm,
                Method::CentralDifference,
                CD_FRACTIONS[0] * crit,
                eps0 * f,
            )?;
            d_eps.push(distance(q, pilots.trace(k), pilots.trace(base), &g_all));
        }
        orders.push(("changes, eps x 1, 10, 100".into(), f64::NAN, d_eps.clone()));
        EPS_FACTORS.iter().map(|f| eps0 * f).collect()
    } else {
        vec![eps0]
    };

    // Cost of the Newmark variants relative to Newmark ¼/½ at the same Δt on
    // the pilot mesh; extra steps of the reduction per contact node.
    let trap = &nm_runs_by_method[0].1;
    // One cost constant per scheme for all meshes (geometric mean over the
    // element orders): a step's work is proportional to nnz(K), so the
    // ranking of meshes within a scheme is by steps × nnz, which is exact,
    // rather than by timings of millisecond pilots on a shared machine.
    let shared = |f: fn(&Group) -> f64| {
        (groups.iter().map(|g| f(g).ln()).sum::<f64>() / groups.len() as f64).exp()
    };
    let (cost_cd, cost_nm) = (shared(|g| g.cost_cd), shared(|g| g.cost_nm));
    let mut candidates = Vec::new();
    for (gi, gr) in groups.iter().enumerate() {
        for (level, &m) in gr.meshes.iter().enumerate() {
            let lm = &ladder[m];
            for method in Method::ALL {
                let (dts, e_base, cost): (Vec<f64>, f64, f64) = match method {
                    Method::CentralDifference => (
                        CD_FRACTIONS.iter().map(|f| f * lm.dt_crit).collect(),
                        e_cd_all[gi][level],
                        cost_cd,
                    ),
                    _ => {
                        let runs = &nm_runs_by_method
                            .iter()
                            .find(|r| r.0 == method)
                            .expect("run")
                            .1;
                        let rel = pilots.cost(runs[k_h]) / pilots.cost(trap[k_h]);
                        (nm_dt.clone(), e_nm_all[gi][level], cost_nm * rel)
                    }
                };
                let measured_h = match method {
                    Method::CentralDifference => level < gr.cd_runs.len(),
                    _ => level < gr.nm_runs.len(),
                };
                for (kd, &dt) in dts.iter().enumerate() {
                    let d_dt = match method {
                        Method::CentralDifference => d_dt_cd[kd],
                        _ => d_dt_nm.iter().find(|e| e.0 == method).expect("estimated").1[kd],
                    };
                    let mut steps = (t_end / dt).ceil();
                    if method == Method::TrapezoidalReduced {
                        let runs = &nm_runs_by_method
                            .iter()
                            .find(|r| r.0 == method)
                            .expect("run")
                            .1;
                        let extra = (pilots.trace(runs[kd]).steps as f64 - steps).max(0.0);
                        let per_node = extra / ladder[pm].contact_nodes.max(1) as f64;
                        steps += per_node * lm.contact_nodes as f64;
                    }
                    for (ke, &eps) in eps_list.iter().enumerate() {
                        // A configuration that was itself run: its error
                        // against R directly.
                        let own = pilots.runs.iter().position(|r| {
                            r.0 == m && r.1 == method && r.2 == dt && r.3.to_bits() == eps.to_bits()
                        });
                        let parts = match own {
                            Some(k) => [err_of(&pilots, k), 0.0, 0.0],
                            None => [e_base, d_dt, d_eps[ke]],
                        };
                        candidates.push(Candidate {
                            order: gr.order,
                            mesh: lm.text.clone(),
                            mesh_index: m,
                            method,
                            dt,
                            eps,
                            parts,
                            predicted_time: cost * lm.nnz as f64 * steps,
                            dofs: lm.dofs,
                            steps,
                            measured_h,
                            run: own.is_some(),
                        });
                    }
                }
            }
        }
    }
    let pilots_out = pilots
        .runs
        .iter()
        .map(|r| Pilot {
            mesh_index: r.0,
            method: r.1,
            dt: r.2,
            eps: r.3,
            steps: r.4.steps,
            secs: r.4.secs,
        })
        .collect();
    Ok(Estimates {
        quantity: q,
        ladder,
        candidates,
        pilots: pilots_out,
        seconds: start.elapsed().as_secs_f64(),
        orders,
        notes,
    })
}
