//! The compliance law against the paper's (METHOD.md §10): the paper's
//! slab (`cases/martins-oden/cd-step-eps1e-2.toml`: rollers on its top,
//! its left end held in x, pressed on its bottom by the prescribed
//! F_n = 300, μ = 0.3, the end load t_x = −150 H(t)) against the slab on a
//! compliant floor (c_T = μ c_n, m_n = 1), both measured by the difference
//! of the bottom's tangential displacement histories, in two limits.
//!
//! The soft limit reproduces the paper, and is the one checked. The
//! paper's slab is kept exactly (rollers on top, the same loads) and only
//! its prescribed bottom pressure is replaced by a floor pre-compressed so
//! that its traction is 300 at the start: the static preload (Remark 4.1,
//! frictionless) is then uniform uniaxial stress σ_yy = −300, whose
//! compression lifts the bottom by u₀ = 300 (1 − ν²) H / E (plane strain),
//! so the floor's line is placed an interference d = 300/c_n + u₀ above
//! the bottom (the closed form, [`interference`]). The floor's traction
//! is then 300 − c_n Δu_y (Δu_y the bottom's motion from the preload), so
//! as c_n → 0 with c_n (d − u₀) = 300 the run tends to the paper's, the
//! difference ∝ c_n: the criterion is that it falls at least fivefold a
//! decade of c_n and is below a stated bound at the softest floor.
//!
//! The slab pressed by the prescribed 300 onto a stiff compliant
//! foundation reproduces the paper as c_n grows, and is checked, where
//! the foundation replaces the paper's rollers: a frictionless ceiling
//! touching the top, with the bottom's prescribed pressure and friction
//! kept (two surfaces, one of each law). The ceiling gives way by t/c_n
//! under a traction t where the rollers hold, so the difference falls like
//! 1/c_n once the ceiling is stiffer than the slab (E/(c_n H) ≪ 1): from
//! there a decade divides it by 10 ± 5, and at the stiffest ceiling it is
//! below E/(c_n H) (a loose bound). Each ceiling's preload traction is
//! checked to be 300 at every node (c_n and the nodal weights), and its
//! traction to stay positive over the run (it holds the top throughout).
//! Frictionless, the ceiling checks the law's normal part; its friction
//! (c_T = μ c_n) is the floors' below.
//!
//! The floor's stiff limit does not reproduce it, and is reported: the slab pressed
//! by 300 on its top onto a floor of growing c_n from the static preload
//! (every bottom node at the approach 300/c_n, traction 300). The stiff
//! floor's limit is a rigid floor, which holds the bottom still in y where
//! the paper's model holds the top, so the end load's Poisson and inertial
//! motion across the thickness moves the floor's traction away from 300
//! (the table gives its range): the two models differ by that much, about
//! a tenth. Its criterion is on the compliance runs: their change from one
//! floor to the next ten times stiffer falls like 1/c_n (at least fivefold
//! a decade), and the last is below 0.2% of the history: the runs converge
//! to the rigid floor's.

use std::path::Path;

use stickslip_time::Integrator;

use crate::report::{max_or_nan, min_or_nan, Report};
use crate::scene::{integrator_of, paper_slab};

/// The floors' stiffness c_n.
const FLOORS: [f64; 4] = [1e3, 1e4, 1e5, 1e6];
/// One step for every run: half the stiffest floor's critical step.
const DT: f64 = 2.5e-4;
const T_END: f64 = 0.5;

/// Runs the check (2,000 steps of a 148-DOF slab a run: about a second
/// in all).
pub fn run(root: &Path, r: &mut Report) {
    let name = "paper's slab";
    let mut nodes = Vec::new();
    let reference = match history(root, &held(root, PRESSED), &mut nodes) {
        Ok(h) => h.u_t,
        Err(e) => return r.holds(name, "runs", e, "runs", false),
    };
    soft(root, r, (&reference, &mut nodes));
    ceiling(root, r, (&reference, &mut nodes));
    stiff(root, r, (&reference, &mut nodes));
}

/// The paper's slab with its left end held and its end load, `law` its
/// support and contact.
fn held(root: &Path, law: &str) -> String {
    slab(root, &format!("{LEFT}{LOAD}{law}"), T_END)
}

/// The pre-compressed floors' stiffness c_n, stiffest first. The first
/// is reported only: there the floor's traction 300 − c_n Δu_y departs
/// from 300 by some 40% (the table's range), outside the regime where
/// the difference is linear in c_n; each floor after the second is
/// checked against the one before.
const SOFT: [f64; 5] = [1e4, 1e3, 1e2, 1e1, 1e0];

/// The bound on the difference at the softest floor, relative to the
/// history's size: the friction bound's relative change there, c_n
/// |Δu_y| / p, with |Δu_y| ≤ 2 ν (1 + ν) |t_x| H / E (the end load's
/// Poisson swell of the thickness, doubled by the step load's dynamics).
/// The friction force differs from the paper's by that fraction at most,
/// and the displacement history, which it drives, is held to the same
/// fraction of itself.
fn soft_limit(cn: f64) -> f64 {
    let (p, tx, e, nu, h) = (300.0, 150.0, 1000.0, 0.3, 1.0);
    cn * 2.0 * nu * (1.0 + nu) * tx * h / e / p
}

/// The soft limit: the paper's slab with its bottom pressure replaced by a
/// pre-compressed floor (see the module's comment).
fn soft(root: &Path, r: &mut Report, (reference, nodes): (&[f64], &mut Vec<usize>)) {
    let name = "paper's slab";
    let size = norm(reference, &vec![0.0; reference.len()]);
    let mut stiffer = f64::INFINITY;
    for (i, cn) in SOFT.into_iter().enumerate() {
        let case = format!("{name}, its pressure a floor of c_n = {cn:e} pre-compressed to 300");
        let text = held(root, &pre_compressed(cn));
        let (run, range) = match history(root, &text, nodes) {
            Ok(h) => (h.u_t, h.traction),
            Err(e) => return r.holds(&case, "runs", e, "runs", false),
        };
        let now = norm(&run, reference) / size;
        let quantity = format!(
            "‖u_T − u_T(p)‖ / ‖u_T(p)‖ (floor's traction {:.2} to {:.2}, p = 300)",
            range[0], range[1]
        );
        if i < 2 {
            let why = if i == 0 {
                "table: outside the linear regime"
            } else {
                "table: falls like c_n from here"
            };
            r.reported(&case, &quantity, now, why);
        } else {
            let why = "the stiffer floor's difference / 5 (∝ c_n: / 10)";
            r.at_most(&case, &quantity, now, RATE * stiffer, why);
        }
        stiffer = now;
    }
    let softest = SOFT[SOFT.len() - 1];
    r.at_most(
        &format!("{name}, its pressure a floor of c_n = {softest:e}"),
        "‖u_T − u_T(p)‖ / ‖u_T(p)‖",
        stiffer,
        soft_limit(softest),
        "c_n·2ν(1+ν)|t_x|H/E / p: the prescribed pressure's limit reached",
    );
}

/// The paper's rollers replaced by a frictionless ceiling of growing c_n
/// (see the module's comment): the slab pressed by its bottom's
/// prescribed 300 onto a stiff compliant foundation.
fn ceiling(root: &Path, r: &mut Report, (reference, nodes): (&[f64], &mut Vec<usize>)) {
    let name = "paper's slab";
    let size = norm(reference, &vec![0.0; reference.len()]);
    let mut softer = f64::INFINITY;
    for (i, cn) in FLOORS.into_iter().enumerate() {
        let case = format!("{name}, its rollers a frictionless ceiling of c_n = {cn:e}");
        let text = held(root, &format!("{}{}", ceiling_of(cn), PRESSURE));
        let h = match history(root, &text, nodes) {
            Ok(h) => h,
            Err(e) => return r.holds(&case, "runs", e, "runs", false),
        };
        // The preload is uniform σ_yy = −300, which the ceiling's nodes
        // hold by c_n δ w_J = 300 w_J: each one's traction is 300 (c_n
        // and the nodal weights as the law has them), and the ceiling is
        // to stay in contact for the rollers' limit to be the paper's.
        let [low, high] = h.others_at_start;
        let off = max_or_nan([(low - 300.0).abs(), (high - 300.0).abs()]);
        r.at_most(
            &case,
            "max |ceiling's traction − 300| at t = 0 (static preload)",
            off,
            1e-9 * 300.0,
            "uniform σ_yy = −300: c_n δ = 300 at every node",
        );
        r.at_least(
            &case,
            &format!(
                "ceiling's smallest traction over the run (largest {:.1})",
                h.others[1]
            ),
            h.others[0],
            f64::MIN_POSITIVE,
            "> 0: the ceiling holds the top all along",
        );
        let now = norm(&h.u_t, reference) / size;
        let quantity = "‖u_T − u_T(p)‖ / ‖u_T(p)‖";
        if i < 2 {
            // The first ceiling is as compliant as the slab, E/(c_n H) = 1:
            // the difference is not yet in its 1/c_n regime.
            let why = if i == 0 {
                "table: outside the 1/c_n regime"
            } else {
                "table: falls like 1/c_n from here"
            };
            r.reported(&case, quantity, now, why);
        } else {
            r.reported(&case, quantity, now, "table");
            r.close(
                &case,
                "difference / the softer ceiling's",
                now / softer,
                0.1,
                "∝ 1/c_n: a decade divides it by 10",
                0.05,
            );
        }
        softer = now;
    }
    let stiffest = FLOORS[FLOORS.len() - 1];
    r.at_most(
        &format!("{name}, its rollers a frictionless ceiling of c_n = {stiffest:e}"),
        "‖u_T − u_T(p)‖ / ‖u_T(p)‖",
        softer,
        ceiling_limit(stiffest),
        "E / (c_n H): the rollers' limit reached",
    );
}

/// The bound on the difference at the stiffest ceiling, relative to the
/// history's size: the ceiling's compliance against the slab's, E/(c_n H)
/// (a traction t moves the ceiling by t/c_n and strains the slab by
/// about t/E over its thickness H). The bottom's motion, which the
/// friction drives, departs from the rollers' by that fraction.
fn ceiling_limit(cn: f64) -> f64 {
    let (e, h) = (1000.0, 1.0);
    e / (cn * h)
}

/// The stiff limit, reported: the slab pressed on its top onto floors of
/// growing c_n (see the module's comment).
fn stiff(root: &Path, r: &mut Report, (reference, nodes): (&[f64], &mut Vec<usize>)) {
    let name = "paper's slab";
    let size = norm(reference, &vec![0.0; reference.len()]);
    let mut softer: Option<Vec<f64>> = None;
    let mut change = f64::INFINITY;
    for cn in FLOORS {
        let case = format!("{name} on a floor of c_n = {cn:e}");
        let (run, range) = match history(root, &held(root, &floor(cn)), nodes) {
            Ok(h) => (h.u_t, h.traction),
            Err(e) => {
                r.holds(&case, "runs", e, "runs", false);
                return;
            }
        };
        r.reported(
            &case,
            &format!(
                "‖u_T − u_T(p)‖ / ‖u_T(p)‖ (floor's traction {:.1} to {:.1}, p = 300)",
                range[0], range[1]
            ),
            norm(&run, reference) / size,
            "table against c_n: the models' difference",
        );
        if let Some(softer) = &softer {
            let now = norm(&run, softer) / size;
            let quantity = "‖u_T − u_T(softer floor)‖ / ‖u_T(p)‖";
            if change.is_finite() {
                let why = "the softer floor's change / 5 (1/c_n: / 10)";
                r.at_most(&case, quantity, now, RATE * change, why);
            } else {
                let why = "table: falls like 1/c_n";
                r.reported(&case, quantity, now, why);
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
    let time = format!("scheme = \"central_difference\"\ndt = {DT}\nt_end = {t_end}\n");
    paper_slab(root, "", rest, &time)
}

/// The paper's left end held in x, and its end load.
const LEFT: &str = "[[dirichlet]]\ngroup = \"left\"\nux = 0.0\n";
const LOAD: &str = "[[traction]]\ngroup = \"load\"\nt = [-150.0, 0.0]\nhistory = \"step\"\n";

/// The paper's contact: rollers on the top, the prescribed pressure.
const PRESSED: &str = "[[dirichlet]]\ngroup = \"support\"\nuy = 0.0\n[contact]\n\
    group = \"contact\"\npressure = 300.0\nmu = 0.3\neps = 1e-2\n";

/// The paper's prescribed pressure on the bottom, as one of two surfaces.
const PRESSURE: &str = "[[contact]]\ngroup = \"contact\"\npressure = 300.0\nmu = 0.3\neps = 1e-2\n";

/// A frictionless ceiling of `cn` touching the top y = 1 in place of the
/// paper's rollers.
fn ceiling_of(cn: f64) -> String {
    format!(
        "[[contact]]\ngroup = \"support\"\nlaw = \"compliance\"\n\
         foundation = {{ point = [0.0, 1.0], normal = [0.0, -1.0] }}\ncn = {cn:e}\n\
         mu = 0.0\neps = 1e-2\n"
    )
}

/// The paper's rollers on the top, its bottom on a floor of `cn` whose
/// line lies [`interference`] above the bottom y = 0.
fn pre_compressed(cn: f64) -> String {
    format!(
        "[[dirichlet]]\ngroup = \"support\"\nuy = 0.0\n\
         [contact]\ngroup = \"contact\"\nlaw = \"compliance\"\n\
         foundation = {{ point = [0.0, {:e}], normal = [0.0, 1.0] }}\ncn = {cn:e}\n\
         mu = 0.3\neps = 1e-2\n",
        interference(cn)
    )
}

/// The interference d of a floor of `cn` whose preloaded traction is
/// p = 300: the preload is uniform uniaxial stress σ_yy = −p (rollers on
/// the top, σ_xx = 0 with the right end free), ε_yy = −p (1 − ν²)/E in
/// plane strain, so the bottom rises by u₀ = p (1 − ν²) H / E (E = 1000,
/// ν = 0.3, H = 1) and the approach d − u₀ must be p/c_n.
fn interference(cn: f64) -> f64 {
    let (p, e, nu, h) = (300.0, 1000.0, 0.3, 1.0);
    p / cn + p * (1.0 - nu * nu) * h / e
}

/// The top pressed by 300 onto a floor of `cn` under the bottom.
fn floor(cn: f64) -> String {
    format!(
        "[[traction]]\ngroup = \"support\"\npressure = 300.0\nhistory = \"constant\"\n\
         [contact]\ngroup = \"contact\"\nlaw = \"compliance\"\n\
         foundation = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\ncn = {cn:e}\n\
         mu = 0.3\neps = 1e-2\n"
    )
}

/// A run's record on its contact surface.
struct History {
    /// The tangential displacement τ·u after every step at each mesh node
    /// of `nodes` (see [`history`]), node by node within a step.
    u_t: Vec<f64>,
    /// The normal traction's range over the run at those nodes.
    traction: [f64; 2],
    /// The normal traction's range over the run at the surface's other
    /// nodes (a second surface's), and at t = 0.
    others: [f64; 2],
    others_at_start: [f64; 2],
}

/// The run of case `text`: [`History`] at each mesh node of `nodes`
/// (every contact node where empty, then listed there).
fn history(root: &Path, text: &str, nodes: &mut Vec<usize>) -> Result<History, String> {
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
    let rest: Vec<usize> = (0..c.len()).filter(|j| !at.contains(j)).collect();
    let (mut u_t, mut traction) = (Vec::new(), vec![0.0; c.len()]);
    let range = |t: &[f64], of: &[usize], into: &mut [f64; 2]| {
        for &j in of {
            *into = [min_or_nan([into[0], t[j]]), max_or_nan([into[1], t[j]])];
        }
    };
    let empty = [f64::INFINITY, f64::NEG_INFINITY];
    let (mut on, mut others, mut others_at_start) = (empty, empty, empty);
    run.normal_traction(&mut traction);
    range(&traction, &rest, &mut others_at_start);
    while !run.done() {
        run.step().map_err(|e| e.to_string())?;
        let c = run.contact().ok_or("no contact surface")?;
        u_t.extend(
            at.iter()
                .map(|&j| c.nodes[j].tangential(run.displacement())),
        );
        run.normal_traction(&mut traction);
        range(&traction, &at, &mut on);
        range(&traction, &rest, &mut others);
    }
    Ok(History {
        u_t,
        traction: on,
        others,
        others_at_start,
    })
}

fn integrator(root: &Path, text: &str) -> Result<Integrator, String> {
    integrator_of(root, "consistency.toml", text)
}
