//! The explicit critical step with a compliant wall (METHOD.md §10): the
//! bar impact of Hughes et al. (the test kit's `impact`) against walls of
//! growing stiffness, its stability threshold in Δt/Δt_crit bisected by
//! energy growth against the time crate's estimate with the wall's springs
//! (w_J c_n at every wall node, as if all were in contact).

use std::fmt::Write as _;
use std::path::Path;

use stickslip_testkit::impact::{run_with, wall};

use crate::stability::GROWTH_LIMIT;

/// The walls' stiffness relative to a cell's, E/h.
const WALLS: [f64; 4] = [0.1, 1.0, 10.0, 100.0];

/// Largest energy growth of the bar (40 cells) against wall `cn` at
/// Δt = `ratio`·Δt_crit, to 3L/c.
fn growth(cn: f64, ratio: f64) -> Result<f64, String> {
    run_with(40, wall(40, cn), ratio, true)
        .map(|r| r.growth)
        .map_err(|e| e.to_string())
}

/// Bisects the threshold between `lo` (stable) and `hi` (unstable) to a
/// relative width `tol`.
fn threshold(cn: f64, mut lo: f64, mut hi: f64, tol: f64) -> Result<f64, String> {
    let stable = |r: f64| growth(cn, r).map(|g| g < GROWTH_LIMIT);
    if !stable(lo)? || stable(hi)? {
        return Err(format!(
            "wall c_n = {cn} E/h: the stability threshold is not between Δt/Δt_crit = {lo} and {hi}"
        ));
    }
    while hi - lo > tol * lo {
        let mid = 0.5 * (lo + hi);
        if stable(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// The thresholds into `stability-compliance.csv` in `out`, with the
/// growth at Δt/Δt_crit = 0.5 and 0.9 (a penalty wall gains energy at each
/// touch well below the linear threshold).
///
/// # Errors
/// A failed run or an unwritable output.
pub fn main(out: &Path) -> Result<(), String> {
    let mut csv = String::from(
        "cn_over_e_per_h,dt_crit,observed_over_estimate,growth_at_0.5,growth_at_0.9\n",
    );
    for cn in WALLS {
        let dt_crit = run_with(40, wall(40, cn), 0.5, false)
            .map_err(|e| e.to_string())?
            .dt_crit;
        let observed = threshold(cn, 0.5, 2.0, 1e-3)?;
        let (half, near) = (growth(cn, 0.5)?, growth(cn, 0.9)?);
        let _ = writeln!(
            csv,
            "{cn},{dt_crit:.6e},{observed:.4},{half:.4e},{near:.4e}"
        );
        eprintln!(
            "compliance wall c_n = {cn:>5} E/h: Δt_crit {dt_crit:.4e}, observed/estimate {observed:.4}, growth at 0.5 {half:.3e}, at 0.9 {near:.3e}"
        );
    }
    let p = out.join("stability-compliance.csv");
    std::fs::write(&p, csv).map_err(|e| format!("{}: {e}", p.display()))
}
