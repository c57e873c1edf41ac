//! The normal-compliance law in the implicit Newmark step (METHOD.md §10,
//! §4-5) on the bar impact of Hughes et al. (the test kit's `impact`): the
//! rigid wall's closed form is a contact of 2L/c at the stress ρcv₀ = v₀,
//! the bar leaving at −v₀; and the energy ledger of Newmark ¼, ½.

use stickslip_contact::ContactSurface;
use stickslip_testkit::impact::{run_newmark, wall, Bar, C, L, V0};
use stickslip_time::{MassKind, Scheme};

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

/// The bar by Newmark ¼, ½ from rest's shape at v₀ against `law`, with
/// `mass` (the consistent one by default).
fn bar_run(bar: &Bar, dt: f64, mass: MassKind) -> stickslip_time::Integrator {
    use stickslip_time::{Dynamics, InitialState, Integrator, Settings};
    let mut v0 = vec![0.0; bar.model.dofs.n_free()];
    for node in 0..bar.mesh.nodes.len() {
        if let Some(d) = bar.model.dofs.free(node, 0) {
            v0[d] = V0;
        }
    }
    let scheme = Scheme::Newmark {
        beta: AVERAGE.0,
        gamma: AVERAGE.1,
    };
    let mut s = Settings::new(scheme, dt, 3.0 * L / C);
    s.initial_state = InitialState::Rest;
    s.initial_velocity = Some(v0);
    s.mass = Some(mass);
    let dynamics = Dynamics::from_model(&bar.model);
    Integrator::new(dynamics, Some(bar.contact.clone()), Vec::new(), s).unwrap()
}

/// Each compliant node's signed approach −(g₀ + ν·r_J) and w_J.
fn approaches(c: &ContactSurface, r: &[f64]) -> Vec<(f64, f64)> {
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
            (-g, node.weight)
        })
        .collect()
}

/// Frictionless Newmark ¼, ½ carries the energy-consistent normal force:
/// the bar's energy, written out here as ½ṙᵀMṙ + ½rᵀKr + Σ_J w_J c_n
/// δ_J^{m_n+1}/(m_n+1) (δ_J the node's approach from r, M the scheme's
/// mass), stays its initial ½ṙ₀ᵀMṙ₀ to 1e-12 at every step, the steps
/// where nodes touch and leave the wall included; and the ledger's balance
/// (no loads, no friction: that same sum less its initial value) is
/// within 1e-12 E₀ of 0. For m_n = 1 and 2, with the consistent mass and
/// the lumped one; the bar leaves the wall (every node off it at the end)
/// at −v₀ to 2%.
#[test]
fn frictionless_average_acceleration_closes_the_ledger_on_every_step() {
    use stickslip_linalg::csr::quadratic_form;
    let nx = 40;
    let dt = 0.5 * L / nx as f64 / C;
    let stiff = stickslip_contact::Compliance {
        cn: 1.6e4,
        mn: 2.0,
        ct: 0.0,
        mt: 2.0,
    };
    for (law, mass) in [
        (wall(nx, 1.0), MassKind::Consistent),
        (wall(nx, 1.0), MassKind::Lumped),
        (stiff, MassKind::Consistent),
        (stiff, MassKind::Lumped),
    ] {
        let bar = Bar::new(nx, law).unwrap();
        let m = match mass {
            MassKind::Consistent => bar.model.mass.clone().unwrap(),
            MassKind::Lumped => lumped(&bar.model),
        };
        let mut partials = stickslip_linalg::chunks::partials(bar.model.dofs.n_free());
        let mut energy = |r: &[f64], v: &[f64]| {
            let stored: f64 = approaches(&bar.contact, r)
                .iter()
                .map(|&(a, w)| w * law.cn * a.max(0.0).powf(law.mn + 1.0) / (law.mn + 1.0))
                .sum();
            0.5 * quadratic_form(&m, v, &mut partials)
                + 0.5 * quadratic_form(&bar.model.stiffness, r, &mut partials)
                + stored
        };
        let mut run = bar_run(&bar, dt, mass);
        let e0 = energy(run.displacement(), run.velocity());
        assert!((e0 - run.energy().kinetic).abs() <= 1e-14 * e0);
        let mut before = approaches(&bar.contact, run.displacement());
        let (mut touches, mut releases, mut worst) = (0, 0, 0.0_f64);
        while !run.done() {
            run.step().unwrap();
            let after = approaches(&bar.contact, run.displacement());
            for (&(a0, _), &(a1, _)) in before.iter().zip(&after) {
                touches += usize::from(a0 <= 0.0 && a1 > 0.0);
                releases += usize::from(a0 > 0.0 && a1 <= 0.0);
            }
            before = after;
            let e = energy(run.displacement(), run.velocity());
            let balance = run.energy().balance;
            worst = worst.max((e - e0).abs() / e0);
            assert!(
                (e - e0).abs() <= 1e-12 * e0 && balance.abs() <= 1e-12 * e0,
                "m_n = {}, {mass:?}, t = {}: energy {e:e} against {e0:e}, balance {balance:e}",
                law.mn,
                run.time()
            );
        }
        println!(
            "m_n = {}, {mass:?}: {touches} touches, {releases} releases, worst |E − E₀|/E₀ = {worst:.2e}",
            law.mn
        );
        assert!(
            touches > 0 && releases > 0,
            "{touches} touches, {releases} releases"
        );
        assert!(before.iter().all(|&(a, _)| a <= 0.0), "still on the wall");
        let (mut p, mut mass_sum) = (0.0, 0.0);
        let lumped = &bar.model.lumped_mass;
        for (v, m) in run.velocity().iter().zip(lumped) {
            p += m * v;
            mass_sum += m;
        }
        assert!(
            (p / mass_sum + V0).abs() <= 0.02 * V0,
            "exit speed {}",
            p / mass_sum
        );
    }
}

/// The lumped mass on K's pattern.
fn lumped(model: &stickslip_fem::Model) -> nalgebra_sparse::CsrMatrix<f64> {
    let mut m = model.stiffness.clone();
    let (offsets, cols, values) = m.csr_data_mut();
    for i in 0..model.lumped_mass.len() {
        for p in offsets[i]..offsets[i + 1] {
            values[p] = if cols[p] == i {
                model.lumped_mass[i]
            } else {
                0.0
            };
        }
    }
    m
}

/// The acceleration the run reports is the physical one, not the
/// algorithmic force's: M r̈ + K r = Σ_J ν_J w_J c_n δ_J^{m_n} (the wall's
/// force at r, the reported normal traction's) at every step, to 1e-9 of
/// |K r| + that force, through the touches and after the release, where
/// the force the scheme carries alternates; for both masses and m_n = 1,
/// 2.
#[test]
fn the_reported_acceleration_is_the_end_points() {
    use stickslip_linalg::csr::spmv;
    let nx = 20;
    let dt = 0.5 * L / nx as f64 / C;
    for (mn, cn) in [(1.0, 3.0 * nx as f64), (2.0, 1.6e4)] {
        let law = stickslip_contact::Compliance {
            cn,
            mn,
            ct: 0.0,
            mt: mn,
        };
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let bar = Bar::new(nx, law).unwrap();
            let m = match mass {
                MassKind::Consistent => bar.model.mass.clone().unwrap(),
                MassKind::Lumped => lumped(&bar.model),
            };
            let mut run = bar_run(&bar, dt, mass);
            let n = bar.model.dofs.n_free();
            let (mut ma, mut kr) = (vec![0.0; n], vec![0.0; n]);
            let mut sigma = vec![0.0; bar.contact.len()];
            let mut left = 0;
            while !run.done() {
                run.step().unwrap();
                spmv(&m, run.acceleration(), &mut ma);
                spmv(&bar.model.stiffness, run.displacement(), &mut kr);
                let mut force = vec![0.0; n];
                for (k, &(a, w)) in bar
                    .contact
                    .compliance
                    .iter()
                    .zip(&approaches(&bar.contact, run.displacement()))
                {
                    let f = w * cn * a.max(0.0).powf(mn);
                    for (d, nu) in bar.contact.nodes[k.index].dofs.iter().zip(k.normal) {
                        if let Some(d) = d {
                            force[*d] += f * nu;
                        }
                    }
                }
                run.normal_traction(&mut sigma);
                let reported: f64 = sigma
                    .iter()
                    .zip(&bar.contact.nodes)
                    .map(|(s, n)| s * n.weight)
                    .sum();
                let written: f64 = force.iter().map(|f| f.abs()).sum();
                assert!((reported - written).abs() <= 1e-12 * written.max(1e-300));
                left += usize::from(written == 0.0);
                let scale = kr.iter().chain(&force).fold(0.0_f64, |s, x| s.max(x.abs()));
                for i in 0..n {
                    let r = ma[i] + kr[i] - force[i];
                    assert!(
                        r.abs() <= 1e-9 * scale,
                        "m_n = {mn}, {mass:?}, t = {}, row {i}: M r̈ + K r − f = {r:e} ({scale:e})",
                        run.time()
                    );
                }
            }
            assert!(left > 10, "the bar left the wall for {left} steps");
        }
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
/// The scheme's normal force is the energy-consistent one, whose mean
/// over a step exceeds the end-point forces' mean (the friction's) by ½ w
/// D on a step where a node touches or leaves (D = c_n a₀a₁/|a₁ − a₀| for
/// m_n = 1, a the node's signed approach at the step's ends, written
/// here): that step adds μ Δt ½ Σ w D to the right-hand side.
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
    let (mut pressed, mut defects, mut switches) = (0, 0.0, 0);
    let mut before = approaches(&block.floor, run.displacement());
    let cn = block.floor.compliance[0].law.cn;
    while !run.done() {
        let dt = -run.time();
        run.step().unwrap();
        let dt = dt + run.time();
        let after = approaches(&block.floor, run.displacement());
        for (&(a0, w), &(a1, _)) in before.iter().zip(&after) {
            if (a0 > 0.0) != (a1 > 0.0) {
                defects += mu * dt * 0.5 * w * cn * a0 * a1 / (a1 - a0).abs();
                switches += 1;
            }
        }
        before = after;
        assert!(
            run.classes().iter().all(|&c| c == SlipState::SlipPositive),
            "t = {}: a node stopped slipping forward",
            run.time()
        );
        run.normal_traction(&mut sigma);
        pressed += sigma.iter().filter(|&&s| s > 0.0).count();
        let v = run.velocity();
        let balance = momentum(v, &xs) + mu * momentum(v, &ys);
        let expected = start + (q - mu * p) * run.time() + defects;
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
    println!("{switches} touches and releases, their term {defects:e}");
}

/// A Newmark run restored from a checkpoint taken after the bar left the
/// wall continues bit for bit: each step's Newton solve starts from the
/// restored velocity, the bounds follow the restored displacement, and the
/// energy-consistent force's excess (not 0 after a release) comes from
/// the checkpoint. Its count
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
    // After the release (about 2L/c): the force the scheme carries then
    // differs from the end-point one, and comes from the checkpoint.
    while a.time() < 2.4 {
        a.step().unwrap();
    }
    assert!(a.normal_iterations() > 0);
    let excess = a.checkpoint().normal_excess;
    assert_eq!(excess.len(), bar.contact.compliance.len());
    assert!(excess.iter().any(|&e| e != 0.0), "{excess:?}");
    let mut b = bar.integrator_with(scheme, dt, false).unwrap();
    b.restore(&a.checkpoint()).unwrap();
    assert_eq!(b.normal_iterations(), a.normal_iterations());
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    while !a.done() {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(bits(a.velocity()), bits(b.velocity()), "t = {}", a.time());
        assert_eq!(bits(a.acceleration()), bits(b.acceleration()));
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

/// A μ falling with the slip speed on the compliant floor's own nodes is
/// not built (their bound is c_T δ^{m_T}): the scene is refused at the
/// start, as a case file's `mu = { static, kinetic, speed }` with `law =
/// "compliance"` is.
#[test]
fn a_speed_dependent_mu_on_compliant_nodes_is_refused() {
    use stickslip_contact::Weakening;
    use stickslip_time::{Dynamics, Integrator, TimeError};

    let block = SlidingBlock::new(5.0, 10.0, 0.3);
    let mut floor = block.floor.clone();
    floor.set_weakening(|_| {
        Some(Weakening {
            ratio: 0.5,
            speed: 0.5,
        })
    });
    let dynamics = Dynamics::from_model(&block.model);
    let load = vec![block.load.clone()];
    match Integrator::new(dynamics, Some(floor), load, block.settings()) {
        Err(TimeError::Settings(m)) => {
            assert!(m.contains("compliance") && m.contains("constant mu"), "{m}");
        }
        other => panic!("expected the refusal, got {:?}", other.map(|_| ())),
    }
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
