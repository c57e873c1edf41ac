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

use stickslip_time::Integrator;

use crate::report::Report;

/// Pressure, μ, the belt's speed.
const P: f64 = 300.0;
const MU: f64 = 0.3;
const V: f64 = 1.0;

/// Runs the check on both schemes.
/// e^{−αt/2} = e^{−10} of the start's motion is left at t = 10 with α = 2,
/// in quick mode as in full (a 148-DOF slab: a fraction of a second).
pub fn run(root: &Path, r: &mut Report) {
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
    format!(
        r#"[mesh]
file = "{}"
[material]
E = 1000.0
nu = 0.3
rho = 1.0
damping = {{ alpha = 2.0, beta = 0.0 }}
[[dirichlet]]
group = "left"
ux = 0.0
[[dirichlet]]
group = "support"
uy = 0.0
{bottom}
[time]
scheme = "{scheme}"
dt = {dt}
t_end = {t_end}
"#,
        root.join("cases/meshes/slab-q2-8x2.msh").display()
    )
}

fn integrator(root: &Path, text: &str) -> Result<Integrator, String> {
    let path = root.join("belt.toml");
    let case = stickslip_case::load_str(&path, text, &[]).map_err(|e| e.to_string())?;
    let scene = stickslip_case::assemble(&case).map_err(|e| e.to_string())?;
    scene.integrator().map_err(|e| e.to_string())
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
    let moved = expected
        .iter()
        .zip(&start)
        .map(|(e, s)| (e - s).abs())
        .fold(0.0, f64::max);
    let error = run
        .displacement()
        .iter()
        .zip(expected)
        .map(|(u, e)| (u - e).abs())
        .fold(0.0, f64::max);
    Ok(error / moved)
}
