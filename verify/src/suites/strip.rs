//! Quasi-static friction against closed forms, on the strip of
//! `stickslip_testkit::strip` (a thin strip on a rough base pulled at its
//! end by P = g L/2): the slip zone and the end displacement against the
//! 1-D shear-lag closed form as the strip thins and the mesh refines, the
//! independence of the monotonic result from the load increment, and a
//! slow ramp in dynamics ending near the quasi-static state.

use stickslip_mesh::CellKind;
use stickslip_testkit::strip::Strip;
use stickslip_testkit::Slab;
use stickslip_time::{History, Integrator, Scheme, Settings};

use crate::report::{num, Report};
use crate::Options;

/// ε of the runs: a stuck node creeps at most ε per unit time, against
/// end displacements of order 0.1 over the unit ramp.
const EPS: f64 = 1e-6;

/// The pull ramped from 0 to P over [0, t_ramp], then held.
fn ramp(t_ramp: f64) -> History {
    History::Table(vec![(0.0, 0.0), (t_ramp, 1.0)])
}

/// The strip of thickness `h_l` (L = 1) on Q1 cells `ny` through the
/// thickness (square cells), run by `scheme` with step `dt` to `t_end`
/// under the pull ramped over `t_ramp`.
fn run(
    strip: &Strip,
    ny: usize,
    scheme: Scheme,
    (dt, t_end, t_ramp): (f64, f64, f64),
) -> Result<(Slab, Integrator), String> {
    let nx = (ny as f64 * strip.length / strip.height).round() as usize;
    let slab = strip
        .scene(CellKind::Quad4, (nx, ny), EPS, ramp(t_ramp))
        .map_err(|e| e.to_string())?;
    let mut integrator = slab
        .integrator(Settings::new(scheme, dt, t_end))
        .map_err(|e| e.to_string())?;
    while !integrator.done() {
        integrator.step().map_err(|e| e.to_string())?;
    }
    Ok((slab, integrator))
}

/// Runs the checks.
pub fn run_all(opts: &Options, r: &mut Report) {
    closed_form(opts, r);
    increments(r);
    slow_ramp(opts, r);
}

/// The table against H/L and h. In the 2-D strip the stuck base beyond
/// the slip front still takes load, through the strip's shear over a
/// length of the order of its thickness H, so the slip zone is shorter
/// than the 1-D P/g by O(H): within H of it on every mesh. The end
/// displacement differs from the 1-D bar's by that shear lag too; the
/// table shows the difference falling fourfold as H/L halves, and the
/// checks hold it there: on the finest meshes a measured order in H/L of
/// at least 1.5, and the end within 1% of the 1-D form at H/L = 0.025.
fn closed_form(opts: &Options, r: &mut Report) {
    let thicknesses = [0.1, 0.05, 0.025];
    let layers: &[usize] = if opts.quick { &[1, 2] } else { &[1, 2, 4] };
    let mut finest = Vec::new();
    for h_l in thicknesses {
        let strip = Strip::new(h_l);
        for &ny in layers {
            let case = format!("QS strip H/L={h_l} ny={ny}");
            let h = h_l / ny as f64;
            match run(&strip, ny, Scheme::QuasiStatic, (0.05, 1.0, 1.0)) {
                Ok((slab, integrator)) => {
                    let a = strip.measured_slip(&slab, &integrator);
                    r.close(
                        &case,
                        &format!("slip length, h = {}", num(h)),
                        a,
                        strip.slip_length(),
                        "1-D closed form P/g, ± H",
                        h_l * strip.length,
                    );
                    let u = strip.measured_end(&slab, integrator.displacement());
                    let rel = u / strip.end_displacement() - 1.0;
                    r.reported(
                        &case,
                        "end displacement / P²/(2gE*H) − 1",
                        rel,
                        "table: → 0 as H/L → 0",
                    );
                    if ny == *layers.last().unwrap_or(&1) {
                        finest.push((h_l, rel));
                    }
                }
                Err(e) => r.holds(&case, "run completes", e, "completes", false),
            }
        }
    }
    if finest.len() == thicknesses.len() && finest.len() >= 2 {
        let (h_l, rel) = finest[finest.len() - 1];
        let (h_coarse, rel_coarse) = finest[finest.len() - 2];
        let case = format!("QS strip H/L={h_l} finest");
        let order = (rel_coarse.abs() / rel.abs()).ln() / (h_coarse / h_l).ln();
        r.at_least(
            &case,
            &format!("order in H/L of the end's error (from {h_coarse})"),
            order,
            1.5,
            "second order in H/L",
        );
        r.at_most(
            &case,
            "|end displacement / closed form − 1|",
            rel.abs(),
            0.01,
            "1-D shear lag, thin strip",
        );
    }
}

/// The monotonic result at t_end as the increment halves twice: its
/// changes and their measured order. Coulomb's law is rate-independent;
/// what the increment changes is the regularized law's creep of the stuck
/// part, below ε per unit time, so the change is at most ε·t_end; the
/// creep's backward-Euler increments make it first order in Δt.
fn increments(r: &mut Report) {
    let strip = Strip::new(0.05);
    let case = "QS strip Δt halved twice";
    let ends: Result<Vec<f64>, String> = [0.1, 0.05, 0.025]
        .iter()
        .map(|&dt| {
            run(&strip, 2, Scheme::QuasiStatic, (dt, 1.0, 1.0))
                .map(|(slab, i)| strip.measured_end(&slab, i.displacement()))
        })
        .collect();
    let ends = match ends {
        Ok(e) => e,
        Err(e) => return r.holds(case, "run completes", e, "completes", false),
    };
    let (d1, d2) = ((ends[1] - ends[0]).abs(), (ends[2] - ends[1]).abs());
    r.at_least(
        case,
        &format!(
            "order log2(|Δ₁|/|Δ₂|), |Δ₁| = {}, |Δ₂| = {}",
            num(d1),
            num(d2)
        ),
        (d1 / d2).log2(),
        0.8,
        "first order (backward Euler)",
    );
    r.at_most(
        case,
        "|u(Δt=0.025) − u(Δt=0.05)| at the end",
        d2,
        EPS * 1.0,
        "creep ≤ ε·t_end",
    );
}

/// A slow ramp in dynamics (central difference) against the quasi-static
/// run of the same ramp: the end displacement at the ramp's end. The
/// ramp's kinks leave a vibration of relative amplitude about
/// 1/(ω T_ramp), ω of the slipping part (period 4a/c ≈ 0.06): the
/// difference falls as the ramp lengthens, by half at least from the
/// fastest ramp (0.25) to the slowest, and is under 1e-3 for the slowest
/// (at least 16 of those periods); its phase at the ramp's end makes it
/// no smooth function of the ramp time, hence the table.
fn slow_ramp(opts: &Options, r: &mut Report) {
    let strip = Strip::new(0.05);
    let ramps: &[f64] = if opts.quick {
        &[0.25, 1.0]
    } else {
        &[0.25, 0.5, 1.0, 2.0]
    };
    let mut diffs = Vec::new();
    for &t_ramp in ramps {
        let case = format!("CD ramp {t_ramp} vs QS strip");
        let qs = run(
            &strip,
            2,
            Scheme::QuasiStatic,
            (t_ramp / 20.0, t_ramp, t_ramp),
        );
        let cd = run(&strip, 2, Scheme::CentralDifference, (2e-4, t_ramp, t_ramp));
        match (qs, cd) {
            (Ok((slab, qs)), Ok((_, cd))) => {
                let u_qs = strip.measured_end(&slab, qs.displacement());
                let u_cd = strip.measured_end(&slab, cd.displacement());
                let rel = (u_cd - u_qs).abs() / u_qs.abs();
                r.reported(
                    &case,
                    "|u_CD − u_QS| / u_QS at the ramp's end",
                    rel,
                    "falls with the ramp time",
                );
                diffs.push(rel);
            }
            (Err(e), _) | (_, Err(e)) => {
                r.holds(&case, "runs complete", e, "complete", false);
            }
        }
    }
    if diffs.len() == ramps.len() {
        let case = "CD slow ramps vs QS strip";
        let (fastest, slowest) = (diffs[0], diffs[diffs.len() - 1]);
        r.at_most(
            case,
            "slowest ramp's difference / fastest's",
            slowest / fastest,
            0.5,
            "falls with the ramp time",
        );
        r.at_most(
            case,
            &format!("|u_CD − u_QS| / u_QS, ramp {}", num(ramps[ramps.len() - 1])),
            slowest,
            1e-3,
            "quasi-static limit",
        );
    }
}
