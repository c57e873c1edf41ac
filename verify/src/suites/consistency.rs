//! The compliance law against the paper's (METHOD.md §10): the paper's
//! slab (`cases/martins-oden/cd-step-eps1e-2.toml`: rollers on its top,
//! its left end held in x, pressed on its bottom by the prescribed
//! F_n = 300, μ = 0.3, the end load t_x = −150 H(t)) against the same slab
//! pressed by 300 on its top onto a compliant floor of c_n (c_T = μ c_n,
//! m_n = 1) from the static preload, which starts every bottom node at the
//! approach 300/c_n with the traction 300.
//!
//! A table against c_n of the difference of the bottom's tangential
//! displacement histories from the prescribed-pressure run, reported: it
//! does not vanish as c_n grows. The stiff floor's limit is a rigid floor,
//! which holds the bottom still in y where the paper's model holds the
//! top, so the end load's Poisson and inertial motion across the
//! thickness moves the floor's traction away from 300 (the table gives its
//! range): the two models differ by that much, about a tenth. The
//! criterion is on the compliance runs: their change from one floor to
//! the next ten times stiffer falls like 1/c_n (at least fivefold a
//! decade), and the last is below 0.2% of the history: the runs converge
//! to the rigid floor's.

use std::path::Path;

use stickslip_time::Integrator;

use crate::report::{num, Report};

/// The floors' stiffness c_n.
const FLOORS: [f64; 4] = [1e3, 1e4, 1e5, 1e6];
/// One step for every run: half the stiffest floor's critical step.
const DT: f64 = 2.5e-4;
const T_END: f64 = 0.5;

/// Runs the check (2,000 steps of a 148-DOF slab a run: well under a
/// second in all).
pub fn run(root: &Path, r: &mut Report) {
    let held = |law: &str| slab(root, &format!("{LEFT}{LOAD}{law}"), T_END);
    let name = "paper's slab";
    let mut nodes = Vec::new();
    let reference = match history(root, &held(PRESSED), &mut nodes) {
        Ok((h, _)) => h,
        Err(e) => return r.holds(name, "runs", e, "runs", false),
    };
    let size = norm(&reference, &vec![0.0; reference.len()]);
    let mut softer: Option<Vec<f64>> = None;
    let mut change = f64::INFINITY;
    for cn in FLOORS {
        let case = format!("{name} on a floor of c_n = {cn:e}");
        let (run, range) = match history(root, &held(&floor(cn)), &mut nodes) {
            Ok(h) => h,
            Err(e) => {
                r.holds(&case, "runs", e, "runs", false);
                return;
            }
        };
        r.row(
            &case,
            &format!(
                "‖u_T − u_T(p)‖ / ‖u_T(p)‖ (floor's traction {:.1} to {:.1}, p = 300)",
                range[0], range[1]
            ),
            num(norm(&run, &reference) / size),
            "table against c_n: the models' difference".into(),
            "reported".into(),
            true,
        );
        if let Some(softer) = &softer {
            let now = norm(&run, softer) / size;
            let quantity = "‖u_T − u_T(softer floor)‖ / ‖u_T(p)‖";
            if change.is_finite() {
                let why = "the softer floor's change / 5 (1/c_n: / 10)";
                r.at_most(&case, quantity, now, RATE * change, why);
            } else {
                let why = "table: falls like 1/c_n";
                r.row(
                    &case,
                    quantity,
                    num(now),
                    why.into(),
                    "reported".into(),
                    true,
                );
            }
            change = now;
        }
        softer = Some(run);
    }
    r.at_most(
        &format!("{name} on a floor of c_n = {:e}", FLOORS[FLOORS.len() - 1]),
        "‖u_T − u_T(softer floor)‖ / ‖u_T(p)‖",
        change,
        LIMIT,
        "the rigid floor's limit reached",
    );
}

/// ‖a − b‖₂.
fn norm(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
}

/// A decade of c_n divides the change between floors by at least 1/RATE
/// (10 where it falls like 1/c_n).
const RATE: f64 = 0.2;
/// The change from the second stiffest floor to the stiffest, relative to
/// the history's size, below which the runs have converged in c_n.
const LIMIT: f64 = 2e-3;

/// The slab's mesh and material, `rest` (its supports, loads and contact)
/// and the run to `t_end`.
fn slab(root: &Path, rest: &str, t_end: f64) -> String {
    format!(
        r#"[mesh]
file = "{}"
[material]
E = 1000.0
nu = 0.3
rho = 1.0
{rest}
[time]
scheme = "central_difference"
dt = {DT}
t_end = {t_end}
"#,
        root.join("cases/meshes/slab-q2-8x2.msh").display()
    )
}

/// The paper's left end held in x, and its end load.
const LEFT: &str = "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n";
const LOAD: &str = "[[traction]]\ngroup = \"load\"\nt = [-150.0, 0.0]\nhistory = \"step\"\n";

/// The paper's contact: rollers on the top, the prescribed pressure.
const PRESSED: &str = "[[dirichlet]]\ngroup = \"support\"\nuy = 0.0\n[contact]\n\
    group = \"contact\"\npressure = 300.0\nmu = 0.3\neps = 1e-2\n";

/// The top pressed by 300 onto a floor of `cn` under the bottom.
fn floor(cn: f64) -> String {
    format!(
        "[[traction]]\ngroup = \"support\"\npressure = 300.0\nhistory = \"constant\"\n\
         [contact]\ngroup = \"contact\"\nlaw = \"compliance\"\n\
         foundation = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\ncn = {cn:e}\n\
         mu = 0.3\neps = 1e-2\n"
    )
}

/// The tangential displacement τ·u after every step at each mesh node of
/// `nodes` (every contact node where empty, then listed there), node by
/// node within a step; and the floor's normal traction's range over the
/// run.
fn history(
    root: &Path,
    text: &str,
    nodes: &mut Vec<usize>,
) -> Result<(Vec<f64>, [f64; 2]), String> {
    let mut run = integrator(root, text)?;
    let c = run.contact().ok_or("no contact surface")?;
    if nodes.is_empty() {
        nodes.extend(c.nodes.iter().map(|n| n.node));
    }
    let at: Vec<usize> = nodes
        .iter()
        .map(|m| c.nodes.iter().position(|n| n.node == *m))
        .collect::<Option<_>>()
        .ok_or("the contact nodes differ")?;
    let (mut out, mut traction) = (Vec::new(), vec![0.0; c.len()]);
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    while !run.done() {
        run.step().map_err(|e| e.to_string())?;
        let c = run.contact().ok_or("no contact surface")?;
        out.extend(
            at.iter()
                .map(|&j| c.nodes[j].tangential(run.displacement())),
        );
        run.normal_traction(&mut traction);
        for &j in &at {
            range = [range[0].min(traction[j]), range[1].max(traction[j])];
        }
    }
    Ok((out, range))
}

fn integrator(root: &Path, text: &str) -> Result<Integrator, String> {
    let path = root.join("consistency.toml");
    let case = stickslip_case::load_str(&path, text, &[]).map_err(|e| e.to_string())?;
    let scene = stickslip_case::assemble(&case).map_err(|e| e.to_string())?;
    scene.integrator().map_err(|e| e.to_string())
}
