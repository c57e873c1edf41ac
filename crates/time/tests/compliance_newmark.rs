//! The normal-compliance law in the implicit Newmark step (METHOD.md §10,
//! §4-5) on the bar impact of Hughes et al. (the test kit's `impact`): the
//! rigid wall's closed form is a contact of 2L/c at the stress ρcv₀ = v₀,
//! the bar leaving at −v₀; and the energy ledger of Newmark ¼, ½.

use stickslip_testkit::impact::{run_newmark, wall, Bar, C, L, V0};
use stickslip_time::Scheme;

const AVERAGE: (f64, f64) = (0.25, 0.5);

/// As the wall stiffens, the contact time approaches 2L/c: the error
/// falls at each step of c_n (40 cells, Δt = h/(2c)); at c_n = E/h the run
/// is within the mesh's resolution of the rigid wall's closed form.
#[test]
fn bar_impact_by_newmark_approaches_the_rigid_wall() {
    let (nx, rigid_time) = (40, 2.0 * L / C);
    let dt = 0.5 * L / nx as f64 / C;
    let mut last = f64::INFINITY;
    for cn in [0.1, 0.3, 1.0, 3.0] {
        let r = run_newmark(nx, wall(nx, cn), AVERAGE, dt).unwrap();
        let error = (r.contact_time - rigid_time).abs();
        assert!(
            error < last,
            "c_n = {cn}: contact time {} (2L/c = {rigid_time}) not closer than at the softer wall ({last})",
            r.contact_time
        );
        last = error;
    }
    let r = run_newmark(nx, wall(nx, 1.0), AVERAGE, dt).unwrap();
    // Release resolved to a few cells' crossing times, 4h/c = 0.1; the
    // plateau stress ρcv₀ and the exit speed v₀ to 2% (the mesh's and the
    // step's dispersion).
    assert!((r.contact_time - rigid_time).abs() < 0.1, "{r:?}");
    assert!((r.stress - V0).abs() < 0.02 * V0, "{r:?}");
    assert!((r.exit_velocity + V0).abs() < 0.02 * V0, "{r:?}");
}

/// Frictionless Newmark ¼, ½ with m_n = 1 conserves the ledger's energy
/// to round-off while the wall's nodes stay in contact (a linear spring:
/// the trapezoidal rule's ½(f_K + f_{K−1})·(r_K − r_{K−1}) is the spring's
/// energy change exactly). A step where a node enters or leaves contact
/// adds, in closed form, ½ w c_n (δ_{K−1} g_K⁺ − δ_K g_{K−1}⁺) (g the
/// node's gap, δ its approach: the average force times the motion, less
/// the stored energy's change, on a one-sided spring); the balance's
/// change each step equals that sum to round-off.
#[test]
fn frictionless_average_acceleration_closes_the_ledger() {
    let nx = 40;
    let bar = Bar::new(nx, wall(nx, 1.0)).unwrap();
    let dt = 0.5 * L / nx as f64 / C;
    let mut run = bar
        .integrator_with(
            Scheme::Newmark {
                beta: AVERAGE.0,
                gamma: AVERAGE.1,
            },
            dt,
            false,
        )
        .unwrap();
    let e0 = run.energy().kinetic;
    let c = bar.contact.clone();
    let gaps = |r: &[f64]| -> Vec<(f64, f64)> {
        c.compliance
            .iter()
            .map(|k| {
                let node = &c.nodes[k.index];
                let mut g = k.gap;
                for comp in 0..2 {
                    if let Some(d) = node.dofs[comp] {
                        g += k.normal[comp] * r[d];
                    }
                }
                (g, node.weight * k.law.cn)
            })
            .collect()
    };
    let (mut before, mut balance) = (gaps(run.displacement()), run.energy().balance);
    let (mut switching, mut worst, mut steps_in_contact) = (0, 0.0_f64, 0);
    let mut ever_left = false;
    while !run.done() {
        run.step().unwrap();
        let after = gaps(run.displacement());
        let mut term = 0.0;
        for (&(g0, k), &(g1, _)) in before.iter().zip(&after) {
            let (d0, d1) = ((-g0).max(0.0), (-g1).max(0.0));
            term += 0.5 * k * (d0 * g1.max(0.0) - d1 * g0.max(0.0));
        }
        if term != 0.0 {
            switching += 1;
        }
        ever_left |= after.iter().any(|&(g, _)| g > 0.0);
        let b = run.energy().balance;
        worst = worst.max((b - balance - term).abs() / e0);
        if !ever_left {
            steps_in_contact += 1;
            assert!(
                b.abs() <= 1e-10 * e0,
                "t = {}: balance {b:e} in contact",
                run.time()
            );
        }
        (before, balance) = (after, b);
    }
    println!(
        "{switching} switching steps, {steps_in_contact} steps in contact, final |balance|/E0 = {:.3e}, worst residual {worst:.3e}",
        balance.abs() / e0
    );
    assert!(
        steps_in_contact > 40,
        "the run was in contact for {steps_in_contact} steps"
    );
    assert!(switching > 0, "no node left the wall");
    assert!(
        worst <= 1e-10,
        "a step's balance off its switching term by {worst:e} E0"
    );
}

/// m_n = 2: the trapezoidal rule on a nonlinear spring is not exactly
/// conservative; its ledger error while the wall's nodes stay in contact
/// is of second order in Δt (the rule's own order), so halving Δt divides
/// it by about 4 (at least 3 here), from about 1e-3 E₀ at Δt = h/(2c).
#[test]
fn a_stiffening_wall_conserves_to_second_order() {
    let nx = 40;
    let law = stickslip_contact::Compliance {
        cn: 1.6e4,
        mn: 2.0,
        ct: 0.0,
        mt: 2.0,
    };
    let bar = Bar::new(nx, law).unwrap();
    let in_contact = |dt: f64| {
        let scheme = Scheme::Newmark {
            beta: AVERAGE.0,
            gamma: AVERAGE.1,
        };
        let mut run = bar.integrator_with(scheme, dt, false).unwrap();
        let e0 = run.energy().kinetic;
        let mut sigma = vec![0.0; bar.contact.len()];
        let mut worst = 0.0_f64;
        // Every wall node pushes through the middle of the contact.
        while run.time() < L / C {
            run.step().unwrap();
            run.normal_traction(&mut sigma);
            assert!(sigma.iter().all(|&s| s > 0.0), "t = {}", run.time());
            worst = worst.max(run.energy().balance.abs() / e0);
        }
        worst
    };
    let dt = 0.5 * L / nx as f64 / C;
    let errors: Vec<f64> = [dt, dt / 2.0, dt / 4.0].map(in_contact).to_vec();
    assert!(errors[0] < 2e-3 && errors[0] > 1e-12, "{errors:?}");
    for pair in errors.windows(2) {
        assert!(pair[0] > 3.0 * pair[1], "not second order: {errors:?}");
    }
}

/// Friction bounded by the iterate's approach: a block (1 × ½, ρ = 1,
/// lumped mass) sliding forward at every node on a rough compliant floor
/// (c_T = μ c_n, m_T = m_n = 1) under the top traction (q, −p) feels, node
/// by node, a friction force μ times its normal force. With K's rows
/// summing to zero along a translation, the trapezoidal rule of Newmark ¼,
/// ½ then keeps P_x + μ P_y = P_x(0) + (q − μ p) t at every step, P the
/// momentum Σ m_j ṙ_j; to round-off only if the bound follows the normal
/// approach of the converged step, not of the predictor or the last step.
#[test]
fn a_sliding_block_keeps_coulombs_momentum_balance() {
    use stickslip_contact::SlipState;
    use stickslip_time::{Dynamics, Integrator};

    let (q, p, mu) = (5.0, 10.0, 0.3);
    let block = SlidingBlock::new(q, p, mu);
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for node in 0..block.mesh.nodes.len() {
        xs.extend(block.model.dofs.free(node, 0));
        ys.extend(block.model.dofs.free(node, 1));
    }
    let (contact, load, s) = (block.floor.clone(), block.load.clone(), block.settings());
    let dynamics = Dynamics::from_model(&block.model);
    let mass = dynamics.lumped_mass.clone();
    let mut run = Integrator::new(dynamics, Some(contact), vec![load], s).unwrap();
    let momentum = |v: &[f64], dofs: &[usize]| dofs.iter().map(|&d| mass[d] * v[d]).sum::<f64>();
    let start = momentum(run.velocity(), &xs) + mu * momentum(run.velocity(), &ys);
    let mut sigma = vec![0.0; run.contact().unwrap().len()];
    let mut pressed = 0;
    while !run.done() {
        run.step().unwrap();
        assert!(
            run.classes().iter().all(|&c| c == SlipState::SlipPositive),
            "t = {}: a node stopped slipping forward",
            run.time()
        );
        run.normal_traction(&mut sigma);
        pressed += sigma.iter().filter(|&&s| s > 0.0).count();
        let v = run.velocity();
        let balance = momentum(v, &xs) + mu * momentum(v, &ys);
        let expected = start + (q - mu * p) * run.time();
        assert!(
            (balance - expected).abs() <= 1e-11 * expected.abs(),
            "t = {}: P_x + μP_y = {balance}, (q − μp)t + P(0) = {expected}",
            run.time()
        );
    }
    assert!(
        pressed > 1000,
        "the floor carried the block ({pressed} node-steps)"
    );
}

/// A Newmark run restored from a checkpoint taken in contact continues
/// bit for bit: each step's Newton solve starts from the restored
/// velocity, and the bounds follow the restored displacement. Its count
/// of Newton iterations continues the checkpoint's, as the uninterrupted
/// run's does.
#[test]
fn a_restored_newmark_run_continues_bit_identically() {
    let nx = 20;
    let bar = Bar::new(nx, wall(nx, 10.0)).unwrap();
    let scheme = Scheme::Newmark {
        beta: AVERAGE.0,
        gamma: AVERAGE.1,
    };
    let dt = 0.5 * L / nx as f64 / C;
    let mut a = bar.integrator_with(scheme, dt, false).unwrap();
    while a.time() < 1.0 {
        a.step().unwrap();
    }
    assert!(a.normal_iterations() > 0);
    let mut b = bar.integrator_with(scheme, dt, false).unwrap();
    b.restore(&a.checkpoint()).unwrap();
    assert_eq!(b.normal_iterations(), a.normal_iterations());
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    while !a.done() {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(bits(a.velocity()), bits(b.velocity()), "t = {}", a.time());
        assert_eq!(a.energy(), b.energy());
        assert_eq!(a.normal_iterations(), b.normal_iterations());
    }
}

/// The normal rows go through both ways of the Schur step, W = L⁻¹Pᵀ and
/// solves on the reach: the bar's runs agree to round-off (1e-12 of the
/// speed), the direct reference refuses the law with its reason.
#[test]
fn both_schur_paths_carry_the_normal_rows() {
    use stickslip_time::{Dynamics, ImplicitSolver, InitialState, Integrator, Settings};
    let nx = 20;
    let bar = Bar::new(nx, wall(nx, 3.0)).unwrap();
    let mut v0 = vec![0.0; bar.model.dofs.n_free()];
    for node in 0..bar.mesh.nodes.len() {
        if let Some(d) = bar.model.dofs.free(node, 0) {
            v0[d] = V0;
        }
    }
    let build = |solver: ImplicitSolver| {
        let scheme = Scheme::Newmark {
            beta: AVERAGE.0,
            gamma: AVERAGE.1,
        };
        let mut s = Settings::new(scheme, 0.5 * L / nx as f64 / C, 3.0 * L / C);
        s.initial_state = InitialState::Rest;
        s.initial_velocity = Some(v0.clone());
        s.implicit_solver = solver;
        Integrator::new(
            Dynamics::from_model(&bar.model),
            Some(bar.contact.clone()),
            Vec::new(),
            s,
        )
    };
    let mut paths = build(ImplicitSolver::SchurPaths).unwrap();
    let mut reach = build(ImplicitSolver::SchurReach).unwrap();
    let mut touched = false;
    while !paths.done() {
        paths.step().unwrap();
        reach.step().unwrap();
        touched |= paths.energy().foundation_stored > 0.0;
        for (a, b) in paths.velocity().iter().zip(reach.velocity()) {
            assert!(
                (a - b).abs() <= 1e-12 * V0,
                "t = {}: {a} vs {b}",
                paths.time()
            );
        }
    }
    assert!(touched);
    let e = build(ImplicitSolver::Direct).unwrap_err().to_string();
    assert!(e.contains("Schur complement only"), "{e}");
}

/// A compliant floor beside a surface whose μ falls with the slip speed
/// (`mu = { static, kinetic, speed }` on another `[[contact]]`): with μs =
/// μk that μ is the constant law's, so the run, its ledger included, is
/// bit for bit the run with a constant μ on that surface. The ledger books
/// the forces on the lagged surface, whose compliant nodes must carry the
/// bounds at the step's end as the run's do. The block of the test above
/// slides on the rough floor with a rough top (pressure p, μ = 0.2).
#[test]
fn a_compliant_floor_beside_a_lagged_mu_keeps_the_constant_law_bits() {
    use stickslip_contact::{ContactSurface, Weakening};
    use stickslip_time::{Dynamics, Integrator};

    let block = SlidingBlock::new(5.0, 10.0, 0.3);
    let build = |weakening: Option<Weakening>| {
        let (mesh, dofs) = (&block.mesh, &block.model.dofs);
        let mut top = ContactSurface::from_group(mesh, dofs, "top", 10.0, 0.2, 1e-3).unwrap();
        top.set_weakening(|_| weakening);
        let contact = ContactSurface::join(vec![block.floor.clone(), top]).unwrap();
        let dynamics = Dynamics::from_model(&block.model);
        let load = vec![block.load.clone()];
        Integrator::new(dynamics, Some(contact), load, block.settings()).unwrap()
    };
    let mut lagged = build(Some(Weakening {
        ratio: 1.0,
        speed: 0.5,
    }));
    let mut constant = build(None);
    assert!(lagged.contact().unwrap().weakens());
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    while !constant.done() {
        constant.step().unwrap();
        lagged.step().unwrap();
        let t = constant.time();
        assert_eq!(
            bits(constant.velocity()),
            bits(lagged.velocity()),
            "t = {t}"
        );
        assert_eq!(constant.energy(), lagged.energy(), "t = {t}");
    }
    assert!(constant.energy().dissipated > 0.0);
}

/// The block (1 × ½, Q1 4 × 2, E = 1000, ν = 0.3, ρ = 1) of the sliding
/// tests on a rough compliant floor (c_n = 1e4, c_T = μ c_n, m = 1) under
/// the top traction (q, −p), launched along x at 1 from rest's shape.
struct SlidingBlock {
    mesh: stickslip_mesh::Mesh,
    model: stickslip_fem::Model,
    floor: stickslip_contact::ContactSurface,
    load: stickslip_time::Load,
    velocity: Vec<f64>,
}

impl SlidingBlock {
    fn new(q: f64, p: f64, mu: f64) -> SlidingBlock {
        use stickslip_contact::{Compliance, ContactSurface};
        use stickslip_fem::{traction_load, Hypothesis, Material, Model, Traction};
        use stickslip_mesh::CellKind;
        use stickslip_testkit::grid::rectangle;
        use stickslip_time::{History, Load};

        let mesh = rectangle(CellKind::Quad4, 4, 2, [0.0, 0.0], [1.0, 0.5]);
        let material = Material::new(1000.0, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
        let model = Model::new(&mesh, &material, &[]).unwrap();
        let law = Compliance {
            cn: 1e4,
            mn: 1.0,
            ct: mu * 1e4,
            mt: 1.0,
        };
        let at = ([0.0, 0.0], [0.0, 1.0]);
        let floor =
            ContactSurface::on_foundation(&mesh, &model.dofs, "bottom", at, law, 1e-3).unwrap();
        let mut full = vec![0.0; 2 * mesh.nodes.len()];
        traction_load(&mesh, "top", Traction::Vector([q, -p]), &mut full).unwrap();
        let mut vector = vec![0.0; model.dofs.n_free()];
        model.dofs.restrict(&full, &mut vector);
        let mut velocity = vec![0.0; model.dofs.n_free()];
        for node in 0..mesh.nodes.len() {
            if let Some(d) = model.dofs.free(node, 0) {
                velocity[d] = 1.0;
            }
        }
        let load = Load {
            vector,
            history: History::Constant,
        };
        SlidingBlock {
            mesh,
            model,
            floor,
            load,
            velocity,
        }
    }

    /// Newmark ¼, ½, Δt = 1e-3 to t = 0.5, the lumped mass, from rest's
    /// shape at the launch velocity.
    fn settings(&self) -> stickslip_time::Settings {
        use stickslip_time::{InitialState, MassKind, Settings};
        let mut s = Settings::new(
            Scheme::Newmark {
                beta: AVERAGE.0,
                gamma: AVERAGE.1,
            },
            1e-3,
            0.5,
        );
        s.mass = Some(MassKind::Lumped);
        s.initial_state = InitialState::Rest;
        s.initial_velocity = Some(self.velocity.clone());
        s
    }
}
