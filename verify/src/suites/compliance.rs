//! The normal-compliance law (METHOD.md §10) against closed forms: the bar
//! impact of Hughes et al. approaching the rigid wall's contact time 2L/c,
//! stress ρcv₀ and exit velocity −v₀ as the wall stiffens (a table against
//! c_n and h, central difference and Newmark ¼, ½), and a block pressed
//! onto a compliant floor settling at the approach (p/c_n)^{1/m_n}, by
//! damped runs of both schemes and by the static preload. All cheap:
//! milliseconds a run.

use stickslip_testkit::impact::{self, wall, Impact, C, L, V0};
use stickslip_testkit::scene::SceneError;
use stickslip_testkit::settle;

use crate::report::Report;

/// Runs the checks.
pub fn run(r: &mut Report) {
    // Central difference conserves energy to O(Δt²) only.
    let ledger = (1e-2, "ledger with foundation_stored");
    bar_impact(r, "", ledger, |nx, law| impact::run(nx, law, 0.5));
    // Newmark at Δt = h/(2c), about the explicit run's step; its
    // energy-consistent normal force closes the ledger to round-off, the
    // touches and the release included.
    let ledger = (1e-12, "round-off: energy-consistent normal force");
    bar_impact(r, " by Newmark", ledger, |nx, law| {
        impact::run_newmark(nx, law, (0.25, 0.5), 0.5 * L / nx as f64 / C)
    });
    settling(r, "", None);
    // Newmark's numerical damping (γ = 0.6) for the high modes, which the
    // mass-proportional damping leaves ringing at ωΔt ≫ 1.
    settling(r, " by Newmark 0.3025, 0.6", Some(((0.3025, 0.6), 0.01)));
}

/// The wall's stiffness relative to a cell's, E/h.
const WALLS: [f64; 4] = [0.1, 0.3, 1.0, 3.0];

/// The table against c_n and h for one scheme (`by`, appended to the
/// case's name, "" for central difference), run by `run`, its ledger's
/// largest |balance|/E₀ held to `ledger` (the bound and why).
fn bar_impact(
    r: &mut Report,
    by: &str,
    ledger: (f64, &str),
    run: impl Fn(usize, stickslip_contact::Compliance) -> Result<Impact, SceneError>,
) {
    let rigid = 2.0 * L / C;
    for nx in [20, 40] {
        let mut softer = f64::INFINITY;
        for cn in WALLS {
            let case = format!("bar impact {nx} cells, c_n = {cn} E/h{by}");
            let run = match run(nx, wall(nx, cn)) {
                Ok(run) => run,
                Err(e) => {
                    r.holds(&case, "runs", e.to_string(), "runs", false);
                    continue;
                }
            };
            let error = (run.contact_time - rigid).abs();
            let quantity = format!(
                "|T − 2L/c| (|σ − ρcv₀| = {:.2e}, |v + v₀| = {:.2e})",
                (run.stress - V0).abs(),
                (run.exit_velocity + V0).abs()
            );
            if softer.is_finite() {
                r.at_most(&case, &quantity, error, softer, "below the softer wall's");
            } else {
                let start = "table: falls as c_n grows";
                r.reported(&case, &quantity, error, start);
            }
            softer = error;
            if nx == 40 && cn == 1.0 {
                // Release resolved to a few cells' crossings, 4h/c; the
                // plateau and the exit speed to 2% (the mesh's and the
                // step's dispersion).
                let h = L / nx as f64;
                r.close(
                    &case,
                    "contact time T",
                    run.contact_time,
                    rigid,
                    "2L/c",
                    4.0 * h / C,
                );
                r.close(&case, "wall stress", run.stress, V0, "ρcv₀", 0.02 * V0);
                r.close(
                    &case,
                    "exit velocity",
                    run.exit_velocity,
                    -V0,
                    "−v₀",
                    0.02 * V0,
                );
                r.at_most(&case, "|balance| / E₀", run.balance, ledger.0, ledger.1);
            }
        }
    }
}

fn settling(r: &mut Report, by: &str, newmark: Option<((f64, f64), f64)>) {
    for (cn, mn) in [(1e3, 1.0), (1e5, 2.0)] {
        let case = format!("block settling on c_n = {cn:e}, m_n = {mn}{by}");
        let expected = (settle::P / cn).powf(1.0 / mn);
        match settle::settle_by(8, cn, mn, newmark) {
            Ok((most, least)) => {
                for (what, d) in [("largest approach", most), ("smallest approach", least)] {
                    r.close(&case, what, d, expected, "(p/c_n)^(1/m_n)", 1e-9);
                }
            }
            Err(e) => r.holds(&case, "runs", e.to_string(), "runs", false),
        }
        // The same state by the static preload (Newton on the nonlinear
        // static problem: no run to wait out), kept through 100 steps.
        let case = format!("block preloaded on c_n = {cn:e}, m_n = {mn}");
        match settle::preload(8, cn, mn, 100) {
            Ok(p) => {
                for (what, d) in [
                    ("largest approach at t = 0", p.initial.0),
                    ("smallest approach at t = 0", p.initial.1),
                    ("largest approach after 100 steps", p.after.0),
                    ("smallest approach after 100 steps", p.after.1),
                ] {
                    r.close(&case, what, d, expected, "(p/c_n)^(1/m_n)", 1e-9);
                }
            }
            Err(e) => r.holds(&case, "runs", e.to_string(), "runs", false),
        }
    }
}
