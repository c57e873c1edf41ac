//! A moving foundation (METHOD.md §9): the paper's slab held at its left
//! end and resting on a belt that runs along +x under its bottom face.
//! Once the start's waves have died out (Rayleigh damping C = αM, which a
//! state at rest does not feel) the bottom slips backward against the belt
//! at every node, so the belt drags it by the full bound g = μ·p: the late
//! state is the static state under the pressure and a uniform tangential
//! traction μ·p along +x on that face. The expected state is a separate
//! static solve of that case through the same case path: the belt's
//! `[contact]` replaced by two constant `[[traction]]` tables on its group
//! (the pressure, and t = [μp, 0]), whose initial state (Remark 4.1, the
//! static equilibrium under the loads present before t = 0) is K r = R.

use std::path::Path;

use stickslip_contact::Weakening;
use stickslip_testkit::sdof;
use stickslip_time::{Integrator, Rayleigh, Scheme, Settings};

use crate::report::{max_or_nan, min_or_nan, Report};
use crate::scene::{integrator_of, paper_slab};

/// Pressure, μ, the belt's speed.
const P: f64 = 300.0;
const MU: f64 = 0.3;
const V: f64 = 1.0;

/// Runs the checks: the held slab on both schemes, stick-slip on the
/// oscillator. e^{−αt/2} = e^{−10} of the slab's start is left at t = 10
/// with α = 2, in quick mode as in full (a 148-DOF slab: a fraction of a
/// second); the oscillator is one DOF.
pub fn run(root: &Path, r: &mut Report) {
    held_slab(root, r);
    stick_slip(r);
}

fn held_slab(root: &Path, r: &mut Report) {
    for (name, scheme, dt) in [
        ("central difference", "central_difference", 4e-3),
        ("Newmark", "newmark", 1e-2),
    ] {
        let case = format!("slab on a belt, {name}");
        match late_against_static(root, scheme, dt, 10.0) {
            Ok(e) => r.at_most(
                &case,
                "max |u(t_end) − u_static| / max |u_static − u₀|",
                e,
                0.01,
                "static state under the traction μ·p along +x, 1%",
            ),
            Err(e) => r.holds(&case, "runs", e, "runs", false),
        }
    }
}

/// The case text: the slab, left end held in x, top in y, pressed on its
/// bottom ("contact") by P, with `bottom` as the bottom's tables.
fn slab(root: &Path, bottom: &str, scheme: &str, dt: f64, t_end: f64) -> String {
    let rest = format!(
        "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n[[dirichlet]]\ngroup = \"support\"\nuy = 0.0\n\
         {bottom}\n"
    );
    let time = format!("scheme = \"{scheme}\"\ndt = {dt}\nt_end = {t_end}\n");
    paper_slab(
        root,
        "damping = { alpha = 2.0, beta = 0.0 }\n",
        &rest,
        &time,
    )
}

fn integrator(root: &Path, text: &str) -> Result<Integrator, String> {
    integrator_of(root, "belt.toml", text)
}

/// max |u(t_end) − u_static| over max |u_static − u₀|, u₀ the belt run's
/// initial state (the pressure alone): the error against what the belt
/// moved.
fn late_against_static(root: &Path, scheme: &str, dt: f64, t_end: f64) -> Result<f64, String> {
    let belt = format!(
        "[contact]\ngroup = \"contact\"\npressure = {P}\nmu = {MU}\neps = 1e-3\n\
         foundation_velocity = {V}\n"
    );
    let traction = format!(
        "[[traction]]\ngroup = \"contact\"\npressure = {P}\nhistory = \"constant\"\n\
         [[traction]]\ngroup = \"contact\"\nt = [{}, 0.0]\nhistory = \"constant\"\n",
        MU * P
    );
    let mut run = integrator(root, &slab(root, &belt, scheme, dt, t_end))?;
    let start = run.displacement().to_vec();
    while !run.done() {
        run.step().map_err(|e| e.to_string())?;
    }
    if run.classes().iter().any(|c| c.is_stuck()) {
        return Err("a node sticks to the belt at t_end".into());
    }
    let statics = integrator(root, &slab(root, &traction, scheme, dt, t_end))?;
    let expected = statics.displacement();
    if expected.len() != start.len() {
        return Err("the two cases number their DOFs differently".into());
    }
    let moved = max_or_nan(expected.iter().zip(&start).map(|(e, s)| (e - s).abs()));
    let error = max_or_nan(
        run.displacement()
            .iter()
            .zip(expected)
            .map(|(u, e)| (u - e).abs()),
    );
    Ok(error / moved)
}

/// The oscillator's belt speed, μk/μs, vs, its mass-proportional damping
/// (ξ = α/(2ω) = 0.025 on ω = 10: the start's motion dies out, a cycle the
/// belt feeds does not), the run's length and the cycles measured at its
/// end.
const BELT: f64 = 0.05;
const RATIO: f64 = 0.6;
const VS: f64 = 1e-3;
const ALPHA: f64 = 0.5;
const T_END: f64 = 12.0;
const CYCLES: usize = 6;

/// The mass on a spring (m = 1, k = 100, g = μs·p = 1) on a belt at 0.05,
/// with μ(w)/μs = r + (1 − r) e^{−|w|/vs}: (period, peak-to-peak amplitude
/// of x) over the last cycles, a cycle from one slip → stick event to the
/// next; `None` when it no longer sticks once the start's motion has died
/// out (after t = 6: e^{−αt/2} = 0.22 of it is left, below the cycles'
/// amplitude).
fn cycles(scheme: Scheme, ratio: f64, dt: f64, eps: f64) -> Result<Option<(f64, f64)>, String> {
    let mut surface = sdof::surface(eps).map_err(|e| e.to_string())?;
    surface.set_foundation(|_| BELT);
    surface.set_weakening(|_| Some(Weakening { ratio, speed: VS }));
    let mut settings = Settings::new(scheme, dt, T_END);
    settings.damping = Rayleigh {
        alpha: ALPHA,
        beta: 0.0,
    };
    let mut i = sdof::with_surface(0.0, surface, settings).map_err(|e| e.to_string())?;
    let (mut sticks, mut xs) = (Vec::new(), Vec::new());
    let mut stuck = i.classes()[0].is_stuck();
    while !i.done() {
        i.step().map_err(|e| e.to_string())?;
        let now = i.classes()[0].is_stuck();
        if now && !stuck && i.time() > 0.5 * T_END {
            sticks.push(i.time());
        }
        stuck = now;
        xs.push((i.time(), i.displacement()[0]));
    }
    if sticks.len() < CYCLES + 1 {
        return Ok(None);
    }
    let last = &sticks[sticks.len() - CYCLES - 1..];
    let period = (last[CYCLES] - last[0]) / CYCLES as f64;
    let span = || xs.iter().filter(|(t, _)| *t >= last[0]).map(|&(_, x)| x);
    let (lo, hi) = (min_or_nan(span()), max_or_nan(span()));
    Ok(Some((period, hi - lo)))
}

/// Newmark ¼, ½, the implicit scheme the stick-slip is compared on.
const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// μs > μk: stick-slip cycles, their period and amplitude at four levels
/// of (Δt, ε) halved together, by central difference (μ at the step's own
/// slip, the nodal closed form) and by Newmark (μ at the last step's slip,
/// `stickslip_contact`'s `lagged_mu.rs`). Central difference converged
/// when each change from a level to the next is at most the one before it
/// and the last is below 1% of the finest value; Newmark against it when
/// their difference shrinks as Δt halves, to below 0.5% at the finest
/// level (the lag is first order in Δt: the difference halves). μs = μk: no stick after the start, on
/// both.
fn stick_slip(r: &mut Report) {
    let levels = [(4e-4, 1e-4), (2e-4, 5e-5), (1e-4, 2.5e-5), (5e-5, 1.25e-5)];
    let explicit = table(r, "central difference", Scheme::CentralDifference, &levels);
    if let Some(found) = &explicit {
        converged(r, found);
    }
    let implicit = table(r, "Newmark", NEWMARK, &levels);
    if let (Some(cd), Some(nm)) = (&explicit, &implicit) {
        agree(r, cd, nm);
    }
    for (name, scheme) in [
        ("central difference", Scheme::CentralDifference),
        ("Newmark", NEWMARK),
    ] {
        let case = format!("μs = μk on a belt, {name}");
        match cycles(scheme, 1.0, levels[0].0, levels[0].1) {
            Ok(None) => r.holds(&case, "sticks after t = 6", "never".into(), "never", true),
            Ok(Some((period, _))) => r.holds(
                &case,
                "sticks after t = 6",
                format!("every {}", crate::report::num(period)),
                "never",
                false,
            ),
            Err(e) => r.holds(&case, "runs", e, "runs", false),
        }
    }
}

/// The (period, amplitude) rows of `scheme` at each level, `None` unless
/// every level cycles.
fn table(
    r: &mut Report,
    name: &str,
    scheme: Scheme,
    levels: &[(f64, f64)],
) -> Option<Vec<(f64, f64)>> {
    let mut found = Vec::new();
    for &(dt, eps) in levels {
        let case = format!("stick-slip on a belt, {name}, Δt = {dt:e}, ε = {eps:e}");
        match cycles(scheme, RATIO, dt, eps) {
            Ok(Some((period, amplitude))) => {
                r.holds(
                    &case,
                    "period, peak-to-peak x",
                    format!(
                        "{}, {}",
                        crate::report::num(period),
                        crate::report::num(amplitude)
                    ),
                    "cycles of stick and slip",
                    true,
                );
                found.push((period, amplitude));
            }
            Ok(None) => r.holds(&case, "cycles", "steady sliding".into(), "cycles", false),
            Err(e) => r.holds(&case, "runs", e, "runs", false),
        }
    }
    (found.len() == levels.len()).then_some(found)
}

/// Period and amplitude, each as a list over the levels.
fn columns(found: &[(f64, f64)]) -> [(&'static str, Vec<f64>); 2] {
    [
        ("period", found.iter().map(|f| f.0).collect()),
        ("amplitude", found.iter().map(|f| f.1).collect()),
    ]
}

fn converged(r: &mut Report, found: &[(f64, f64)]) {
    for (what, x) in columns(found) {
        let changes: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        let (last, finest) = (changes[changes.len() - 1], x[x.len() - 1]);
        r.at_most(
            "stick-slip on a belt, convergence",
            &format!("{what}: last change / finest"),
            last / finest,
            0.01,
            "converged to 1%",
        );
        let listed: Vec<String> = changes.iter().map(|c| crate::report::num(*c)).collect();
        r.holds(
            "stick-slip on a belt, convergence",
            &format!("{what}: changes as Δt, ε halve"),
            listed.join(", "),
            "each ≤ the one before",
            changes.windows(2).all(|w| w[1] <= w[0]),
        );
    }
}

/// Newmark against central difference, level by level: |NM − CD| / CD.
fn agree(r: &mut Report, cd: &[(f64, f64)], nm: &[(f64, f64)]) {
    let case = "stick-slip on a belt, Newmark against central difference";
    for ((what, a), (_, b)) in columns(cd).into_iter().zip(columns(nm)) {
        let gaps: Vec<f64> = a.iter().zip(&b).map(|(a, b)| (b - a).abs() / a).collect();
        let listed: Vec<String> = gaps.iter().map(|g| crate::report::num(*g)).collect();
        r.holds(
            case,
            &format!("{what}: |NM − CD| / CD as Δt, ε halve"),
            listed.join(", "),
            "each < the one before",
            gaps.windows(2).all(|w| w[1] < w[0]),
        );
        r.at_most(
            case,
            &format!("{what}: |NM − CD| / CD at the finest level"),
            gaps[gaps.len() - 1],
            0.005,
            "within 0.5%",
        );
    }
}
