//! Quasi-static increments on a compliant foundation (METHOD.md §10): each
//! increment K r_K + f_n(r_K) + J(ṙ_K) = R(t_K) with the foundation's
//! force at the end point.
//!
//! The scene: the block [0, 1] × [0, H], H = ½ (E = 1000, ν = 0, plane
//! strain, Q1 cells), its top held (u_x = u_y = 0), its bottom on the
//! foundation y = 0 (touching it, c_n, m_n, friction c_T = μ c_n, m_T =
//! m_n) and loaded by a traction of its own: a normal pull p θ(t) into the
//! foundation and a shear s θ_s(t) along +x. With ν = 0 the block carries
//! the uniform uniaxial stress σ_yy = E d/H (d the bottom's downward
//! displacement) and the simple shear σ_xy = G u/H (u the bottom's x
//! displacement, G = E/2; the sides loaded by its complementary shear),
//! fields the Q1 cells hold exactly, so every
//! bottom node (the foundation's nodal weights are the traction's) is in
//! the equilibrium of one unit of width:
//!
//! ```text
//! normal:      c_n d₊^{m_n} + (E/H) d = p θ        (d₊ = max(d, 0), δ = d₊)
//! tangential:  f_T + (G/H) u = s θ_s,  |f_T| ≤ μ c_n δ^{m_n}
//! ```
//!
//! the foundation and the block's stiffness E/H in parallel (the block's
//! top is held, so the foundation does not carry p alone: the approach is
//! (p/c_n)^{1/m_n} only as E/H → 0). Where f_T is at its bound (slipping)
//! u = (s θ_s − μ c_n δ^{m_n}) H/G exactly; stuck, the regularized law lets
//! the bottom creep at most ε per unit of time.

use stickslip_contact::{Compliance, ContactSurface};
use stickslip_fem::{traction_load, Dirichlet, Hypothesis, Material, Model, Traction};
use stickslip_mesh::CellKind;
use stickslip_testkit::grid::rectangle;
use stickslip_time::{
    Dynamics, History, InitialState, Integrator, Load, Scheme, Settings, TimeError,
};

const E: f64 = 1000.0;
const H: f64 = 0.5;
const G: f64 = 0.5 * E;
const CN: f64 = 4000.0;
const MU: f64 = 0.3;
const P: f64 = 10.0;
const EPS: f64 = 1e-6;

/// A shear (s, θ_s) on the bottom and (τ, θ_τ) on the sides: the
/// complementary shear σ_xy = −τ θ_τ of the left (traction (0, τ)) and
/// right (0, −τ) faces.
type Shear = ((f64, History), (f64, History));

/// The block of 8 × 4 cells on a foundation of (`CN`, `mn`), with the
/// normal pull P·`normal` and the shear `shear` = (s, θ_s) on its bottom;
/// `supported`: its top held (else it floats, held by nothing but the
/// foundation).
struct Block {
    model: Model,
    contact: ContactSurface,
    loads: Vec<Load>,
}

impl Block {
    fn new(mn: f64, normal: History, shear: Option<Shear>, supported: bool) -> Block {
        let mesh = rectangle(CellKind::Quad4, 8, 4, [0.0, 0.0], [1.0, H]);
        let material = Material::new(E, 0.0, 1.0, Hypothesis::PlaneStrain).unwrap();
        let top = |component| Dirichlet {
            group: "top".into(),
            component,
            value: 0.0,
        };
        let held = if supported {
            vec![top(0), top(1)]
        } else {
            Vec::new()
        };
        let model = Model::new(&mesh, &material, &held).unwrap();
        let law = Compliance {
            cn: CN,
            mn,
            ct: MU * CN,
            mt: mn,
        };
        let floor = ([0.0, 0.0], [0.0, 1.0]);
        let contact =
            ContactSurface::on_foundation(&mesh, &model.dofs, "bottom", floor, law, EPS).unwrap();
        let load = |group: &str, t: [f64; 2], history| {
            let mut full = vec![0.0; 2 * mesh.nodes.len()];
            traction_load(&mesh, group, Traction::Vector(t), &mut full).unwrap();
            let mut vector = vec![0.0; model.dofs.n_free()];
            model.dofs.restrict(&full, &mut vector);
            Load { vector, history }
        };
        let mut loads = vec![load("bottom", [0.0, -P], normal)];
        if let Some(((s, history), (tau, sides))) = shear {
            loads.push(load("bottom", [s, 0.0], history));
            loads.push(load("left", [0.0, tau], sides.clone()));
            loads.push(load("right", [0.0, -tau], sides));
        }
        Block {
            model,
            contact,
            loads,
        }
    }

    fn run(&self, dt: f64, t_end: f64) -> Result<Integrator, TimeError> {
        let mut settings = Settings::new(Scheme::QuasiStatic, dt, t_end);
        settings.initial_state = InitialState::Static;
        Integrator::new(
            Dynamics::from_model(&self.model),
            Some(self.contact.clone()),
            self.loads.clone(),
            settings,
        )
    }

    /// Every bottom node's (x, y) displacement.
    fn bottom(&self, r: &[f64]) -> Vec<[f64; 2]> {
        self.contact
            .nodes
            .iter()
            .map(|n| {
                [
                    n.dofs[0].map_or(0.0, |d| r[d]),
                    n.dofs[1].map_or(0.0, |d| r[d]),
                ]
            })
            .collect()
    }
}

/// The closed form's bottom displacement d (downward) under the pull p:
/// the root of c_n d₊^{m_n} + (E/H) d = p, for m_n = 1 and 2 in closed
/// form (the quadratic's positive root).
fn pulled(p: f64, mn: f64) -> f64 {
    let k = E / H;
    if p <= 0.0 {
        return p / k;
    }
    if mn == 1.0 {
        p / (CN + k)
    } else {
        assert_eq!(mn, 2.0);
        (-k + (k * k + 4.0 * CN * p).sqrt()) / (2.0 * CN)
    }
}

/// (a), (c), (d): the pull ramped from 0 to P over [0, 1], then reversed to
/// −P/2 at t = 2 (a push off the foundation from t = 5/3): at every
/// increment each bottom node is at the closed form's d to 1e-9 of it
/// (exact equilibrium at the end point, not a lagged approach), its
/// normal traction c_n δ^{m_n} to 1e-9 of P; once the pull reverses the
/// contact opens, the traction is exactly 0 and the bottom has moved off
/// the foundation by the block's own compression P θ H/E. The Newton
/// iterations of the normal solve are counted, a few per increment.
#[test]
fn a_ramped_pull_presses_and_a_reversed_one_opens_the_contact() {
    let ramp = History::Table(vec![(0.0, 0.0), (1.0, 1.0), (2.0, -0.5)]);
    for mn in [1.0, 2.0] {
        let block = Block::new(mn, ramp.clone(), None, true);
        let dt = 0.05;
        let mut run = block.run(dt, 2.0).unwrap();
        let mut tractions = vec![0.0; block.contact.len()];
        let (mut opened, mut pressed) = (0, 0);
        while !run.done() {
            run.step().unwrap();
            let theta = ramp.value(run.time());
            let d = pulled(P * theta, mn);
            for [ux, uy] in block.bottom(run.displacement()) {
                assert!(
                    (-uy - d).abs() <= 1e-9 * d.abs(),
                    "m_n = {mn}, t = {}: d = {} vs {d}",
                    run.time(),
                    -uy
                );
                assert!(ux.abs() <= 1e-12, "m_n = {mn}: u_x = {ux}");
            }
            run.normal_traction(&mut tractions);
            let want = CN * d.max(0.0).powf(mn);
            for t in &tractions {
                assert!((t - want).abs() <= 1e-9 * P, "m_n = {mn}: {t} vs {want}");
            }
            if d < 0.0 {
                assert!(tractions.iter().all(|&t| t == 0.0));
                opened += 1;
            } else if d > 0.0 {
                pressed += 1;
            }
        }
        // Opened from t = 1.70 on (θ = 0 at 5/3).
        assert_eq!((pressed, opened), (33, 7), "m_n = {mn}");
        let steps = run.steps();
        let newton = run.normal_iterations();
        // A linear ramp on a linear spring repeats the last increment's
        // rate, where Newton starts: no iteration then.
        assert!(
            newton > 0 && newton <= 6 * steps,
            "m_n = {mn}: {newton} Newton iterations in {steps} increments"
        );
    }
}

/// (b): the pull P held from before t = 0 (the compliant static preload
/// starts the block at the closed form's approach), then the shear ramped
/// to 2.1 times the friction bound μ c_n δ^{m_n} at t = 1 (passing it at
/// t = 1/2.1, between increments). While below it
/// every node sticks and the bottom has crept less than ε t; beyond it
/// every node slips, the friction stress is the bound μ c_n δ^{m_n} (to
/// 1e-9 of it), and the bottom is at (sθ − μ c_n δ^{m_n}) H/G to 1e-9.
#[test]
fn a_ramped_shear_sticks_below_the_bound_and_slides_beyond() {
    for mn in [1.0, 2.0] {
        let d = pulled(P, mn);
        let bound = MU * CN * d.powf(mn);
        let s = 2.1 * bound;
        let shear = History::Table(vec![(0.0, 0.0), (1.0, 1.0)]);
        // The sides carry the block's shear stress s θ − μ c_n δ^{m_n}
        // once it slides (0 before: a stuck bottom leaves the block
        // unstrained, to the creep), so that its field is the uniform
        // simple shear of the closed form, not a finite block's.
        let onset = bound / s;
        let sides = History::Table(vec![(0.0, 0.0), (onset, 0.0), (1.0, 1.0)]);
        let block = Block::new(
            mn,
            History::Constant,
            Some(((s, shear.clone()), (s - bound, sides))),
            true,
        );
        let dt = 1.0 / 32.0;
        let mut run = block.run(dt, 1.0).unwrap();
        for [_, uy] in block.bottom(run.displacement()) {
            assert!((-uy - d).abs() <= 1e-9 * d, "preload: {} vs {d}", -uy);
        }
        let mut stress = vec![0.0; block.contact.len()];
        let (mut stuck, mut slid) = (0, 0);
        while !run.done() {
            run.step().unwrap();
            let t = run.time();
            let load = s * shear.value(t);
            let bottom = block.bottom(run.displacement());
            run.friction_stress(&mut stress);
            if load < bound * (1.0 - 1e-9) {
                stuck += 1;
                assert!(run.classes().iter().all(|c| c.is_stuck()), "t = {t}");
                for [ux, _] in &bottom {
                    assert!(ux.abs() <= EPS * t, "t = {t}: crept {ux}");
                }
            } else {
                slid += 1;
                let u = (load - bound) * H / G;
                assert!(run.classes().iter().all(|c| !c.is_stuck()), "t = {t}");
                for ([ux, uy], sigma) in bottom.iter().zip(&stress) {
                    assert!((ux - u).abs() <= 1e-9 * u, "t = {t}: u = {ux} vs {u}");
                    assert!((-uy - d).abs() <= 1e-9 * d);
                    // σ_T = −g φ: against the slip along +x.
                    assert!((sigma + bound).abs() <= 1e-9 * bound, "{sigma} vs {bound}");
                }
            }
        }
        assert_eq!((stuck, slid), (15, 17), "m_n = {mn}");
    }
}

/// (3): the energy ledger. Frictionless (no shear), each increment ends in
/// equilibrium, so the trapezoid rule's books move only by the
/// foundation's: per unit width ΔU_f + ½(F_K + F_{K−1})(d_{K−1} − d_K),
/// F = c_n d₊^{m_n} its force (upwards) and U_f = c_n d₊^{m_n+1}/(m_n+1)
/// its stored energy, written here from the closed form's d. For m_n = 1
/// that is 0 while the bottom stays in contact and ½ c_n δ_{K−1} g_K on
/// the increment that opens it (g_K = −d_K its gap): the switching step's
/// error, as in Newmark; for m_n = 2 in contact −c_n (δ_K − δ_{K−1})³/6,
/// the trapezoid's third-order error on the stiffening spring. The
/// ledger's balance moves by exactly that, to round-off.
#[test]
fn the_ledger_books_the_foundations_stored_energy() {
    let ramp = History::Table(vec![(0.0, 0.0), (1.0, 1.0), (2.0, -0.5)]);
    for mn in [1.0, 2.0] {
        let block = Block::new(mn, ramp.clone(), None, true);
        let mut run = block.run(0.05, 2.0).unwrap();
        let force = |d: f64| CN * d.max(0.0).powf(mn);
        let stored = |d: f64| CN * d.max(0.0).powf(mn + 1.0) / (mn + 1.0);
        let (mut balance, mut d0) = (run.energy().balance, 0.0_f64);
        let (mut switching, mut largest) = (0.0_f64, 0.0_f64);
        // Round-off of the energies, each of order P·d ≤ P²H/E.
        let tol = 1e-11 * P * P * H / E;
        while !run.done() {
            run.step().unwrap();
            let e = run.energy();
            let d = pulled(P * ramp.value(run.time()), mn);
            assert!((e.foundation_stored - stored(d)).abs() <= 1e-9 * P * P / CN);
            let want = stored(d) - stored(d0) + 0.5 * (force(d) + force(d0)) * (d0 - d);
            if mn == 1.0 && d0 > 0.0 && d > 0.0 {
                assert!(
                    want.abs() <= 1e-15 * P * d,
                    "a linear spring's trapezoid is exact"
                );
            }
            if d <= 0.0 && d0 > 0.0 {
                switching = want;
            }
            largest = largest.max(want.abs());
            let change = e.balance - balance;
            assert!(
                (change - want).abs() <= tol,
                "m_n = {mn}, t = {}: balance moved {change:e}, the closed form {want:e}",
                run.time()
            );
            assert_eq!(e.kinetic, 0.0);
            (balance, d0) = (e.balance, d);
        }
        // The errors are no round-off: the switching step's for m_n = 1,
        // the cubic one's for m_n = 2, far above the tolerance.
        assert!(largest > 1e3 * tol, "m_n = {mn}: {largest:e}");
        if mn == 1.0 {
            assert!(switching > 0.0);
        }
    }
}

/// A part held by nothing but the foundation: each increment factorizes
/// Δt K, singular along the motions no support holds; the run refuses it
/// and names them.
#[test]
fn a_floating_part_is_refused_with_its_motions() {
    let block = Block::new(1.0, History::Constant, None, false);
    let e = block.run(0.05, 1.0).unwrap_err().to_string();
    assert!(
        e.contains("singular along") && e.contains("translation"),
        "{e}"
    );
}
