//! What `advise` prints: the measured errors and orders, the choice and its
//! estimate as text, or everything in one JSON object; the header of the
//! adjusted case.

use std::fmt::Write as _;

use stickslip_case::{Case, Method};

use crate::console::WriteError;

use super::candidates::Candidate;
use super::command::Options;
use super::estimate::Estimates;
use super::ladder::LadderMesh;
use super::quantity::Quantity;

/// A candidate in one line: element order, mesh, DOFs, method, Δt, ε.
pub(super) fn describe(c: &Candidate, ladder: &[LadderMesh]) -> String {
    let extra = if c.method == Method::CentralDifference {
        format!(" ({:.3} dt_crit)", c.dt / ladder[c.mesh_index].dt_crit)
    } else {
        String::new()
    };
    // A case without [contact] has no ε (NaN).
    let eps = if c.eps.is_nan() {
        String::new()
    } else {
        format!(", eps = {:e}", c.eps)
    };
    format!(
        "Q{} {} ({} DOFs), {}, dt = {:.4e}{extra}{eps}",
        c.order,
        c.mesh,
        c.dofs,
        c.method.label(),
        c.dt,
    )
}

/// What the error is measured on, in words.
pub(super) fn measure(q: Quantity, node_at: Option<[f64; 2]>) -> String {
    match (q, node_at) {
        (Quantity::Energy, _) => "total energy at t_end, relative to E(0) - E(t_end)".to_string(),
        (q, Some(p)) => format!(
            "{} at the node ({}, {}), relative L2 in time",
            match q {
                Quantity::Ux => "u_x",
                Quantity::Uy => "u_y",
                _ => "friction stress",
            },
            p[0],
            p[1]
        ),
        (q, None) => q.name().to_string(),
    }
}

/// The whole result as one JSON object on stdout (`--json`).
pub(super) fn json(
    case: &Case,
    o: &Options,
    est: &Estimates,
    what: &str,
    choice: Option<&Candidate>,
    best: Option<&Candidate>,
) -> Result<(), WriteError> {
    let cand = |c: &Candidate| {
        serde_json::json!({
            "order": c.order,
            "mesh": c.mesh,
            "dofs": c.dofs,
            "method": c.method.name(),
            "dt": c.dt,
            "eps": c.eps,
            "estimate": c.estimate(),
            "estimate_h": c.parts[0],
            "estimate_dt": c.parts[1],
            "estimate_eps": c.parts[2],
            "h_measured": c.measured_h,
            "pilot": c.run,
            "steps": c.steps,
            "predicted_time_s": c.predicted_time,
        })
    };
    let j = serde_json::json!({
        "case": case.path.display().to_string(),
        "on": o.quantity.name(),
        "measure": what,
        "tol": o.tol,
        "found": choice.is_some(),
        "choice": choice.map(cand),
        "most_accurate": best.map(cand),
        "pilot_runs": est.pilots.len(),
        "pilot_time_s": est.seconds,
        "orders": est.orders.iter().map(|(w, p, d)| serde_json::json!({"what": w, "order": p, "values": d})).collect::<Vec<_>>(),
        "notes": est.notes,
        "written": o.write.as_ref().filter(|_| choice.is_some()).map(|w| w.display().to_string()),
    });
    crate::console::out(&format!("{j}\n"))
}

/// The text report up to the choice: the case, the measure, the pilots and
/// what they measured, the notes.
pub(super) fn measured(
    case: &Case,
    o: &Options,
    est: &Estimates,
    what: &str,
) -> Result<(), WriteError> {
    let mut t = String::new();
    let _ = writeln!(t, "case        {}", case.path.display());
    let _ = writeln!(t, "on          {what}, tol {:e}", o.tol);
    let _ = writeln!(
        t,
        "pilots      {} runs in {:.2} s",
        est.pilots.len(),
        est.seconds
    );
    for (w, p, d) in &est.orders {
        let d: Vec<String> = d.iter().map(|x| format!("{x:.2e}")).collect();
        let p = if p.is_nan() {
            String::new()
        } else {
            format!("; order {p:.2}")
        };
        let _ = writeln!(t, "  {w}: {}{p}", d.join(", "));
    }
    for n in &est.notes {
        let _ = writeln!(t, "note        {n}");
    }
    crate::console::out(&t)
}

/// The error when no configuration meets the tolerance, with the smallest
/// estimate, on stderr.
pub(super) fn not_reachable(
    case: &Case,
    o: &Options,
    est: &Estimates,
    what: &str,
    best: Option<&Candidate>,
) -> Result<(), WriteError> {
    let b = best.map_or("none".to_string(), |b| {
        format!("{:.3e} with {}", b.estimate(), describe(b, &est.ladder))
    });
    crate::console::err(&format!(
        "error: {}: no configuration of the ladder reaches an estimated error of {:e} on {what}; \
         the smallest estimate is {b}; add finer meshes to mesh.ladder or loosen --tol\n",
        case.path.display(),
        o.tol
    ))
}

/// The choice, its estimate and its predicted time.
pub(super) fn choice(c: &Candidate, ladder: &[LadderMesh]) -> Result<(), WriteError> {
    let mut t = String::new();
    let _ = writeln!(t, "choice      {}", describe(c, ladder));
    if c.run {
        let _ = writeln!(
            t,
            "estimate    {:.3e} (this configuration was a pilot: its distance to the reference, with the reference's error)",
            c.estimate()
        );
    } else {
        let _ = writeln!(
            t,
            "estimate    {:.3e} = sqrt(mesh {:.3e}{}^2 + dt {:.3e}^2 + eps {:.3e}^2)",
            c.estimate(),
            c.parts[0],
            if c.measured_h { "" } else { " (extrapolated)" },
            c.parts[1],
            c.parts[2]
        );
    }
    let _ = writeln!(
        t,
        "predicted   {:.3} s ({:.0} steps x {} DOFs; the pilots' seconds per step per entry of K)",
        c.predicted_time, c.steps, c.dofs
    );
    crate::console::out(&t)
}

/// The comment that heads the adjusted case (`--write`): the command and
/// the choice.
pub(super) fn write_header(o: &Options, c: &Candidate, ladder: &[LadderMesh]) -> String {
    let at =
        o.at.map_or(String::new(), |[x, y]| format!(" --at {x},{y}"));
    format!(
        "Adjusted by `stickslip advise --tol {:e} --on {}{at}`: {}\nestimated error {:.3e}, predicted run time {:.3} s",
        o.tol,
        o.quantity.name(),
        describe(c, ladder),
        c.estimate(),
        c.predicted_time
    )
}
