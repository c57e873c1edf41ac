//! The static preload with a compliant foundation (METHOD.md §8, §10): the
//! test kit's block (1 × ½, E = 1000, ν = 0.3, floating) pressed by p = 10
//! onto a frictionless floor. Uniform compression passes p unchanged to
//! every bottom node, whose traction c_n δ^{m_n} = p gives the approach
//! (p/c_n)^{1/m_n} = 0.01 for both laws below; Q1 cells hold the linear
//! field exactly, so the closed form holds to the solver's tolerance.

use stickslip_contact::{Compliance, ContactSurface};
use stickslip_fem::{
    body_force_load, traction_load, Hypothesis, Material, Model, RigidMotion, Traction,
};
use stickslip_mesh::{CellKind, Mesh};
use stickslip_testkit::settle::{preload, Block, P};
use stickslip_testkit::{map_nodes, rectangle};
use stickslip_time::{Dynamics, History, Integrator, Load, Scheme, Settings, TimeError};

const LAWS: [(f64, f64); 2] = [(1e3, 1.0), (1e5, 2.0)];

/// r₀ settles every bottom node at (p/c_n)^{1/m_n} to 1e-9, the
/// foundation's stored energy at t = 0 is Σ w_J c_n δ^{m_n+1}/(m_n+1) =
/// 1 · c_n δ^{m_n+1}/(m_n+1) (Σ w_J the block's width 1) to 1e-9
/// relative, and 400 undamped steps from it leave the approach there to
/// 1e-9: the preload is an equilibrium of the explicit scheme with the
/// foundation's force in r̈₀.
#[test]
fn a_preloaded_block_starts_and_stays_at_the_static_approach() {
    for (cn, mn) in LAWS {
        let p = preload(8, cn, mn, 400).unwrap();
        let expected = (P / cn).powf(1.0 / mn);
        for d in [p.initial.0, p.initial.1, p.after.0, p.after.1] {
            assert!(
                (d - expected).abs() < 1e-9,
                "m_n = {mn}: {p:?} vs {expected}"
            );
        }
        let stored = cn * expected.powf(mn + 1.0) / (mn + 1.0);
        let e = p.run.energy();
        assert!(e.balance.abs() < 1e-9 * stored, "{e:?}");
        let p0 = preload(8, cn, mn, 0).unwrap();
        let e0 = p0.run.energy();
        assert!(
            (e0.foundation_stored - stored).abs() < 1e-9 * stored,
            "{} vs {stored}",
            e0.foundation_stored
        );
    }
}

/// A preload that pulls the block off the floor has no static state: it is
/// refused naming the motion the foundation cannot hold against it.
#[test]
fn a_preload_pulling_off_the_foundation_is_refused() {
    let block = Block::loaded(8, 1e3, 1.0, Traction::Pressure(-P), 0.0).unwrap();
    let e = block
        .integrator(Settings::new(Scheme::CentralDifference, 1e-4, 1.0))
        .unwrap_err();
    match &e {
        TimeError::Unbalanced(motions) => {
            assert!(
                motions.iter().any(|m| m.label.contains("translation in y")),
                "{e}"
            );
            assert!(e.to_string().contains("it only pushes"), "{e}");
        }
        _ => panic!("{e}"),
    }
}

/// A preload along the floor (a shear on the top) has nothing to balance
/// it on a frictionless foundation: refused naming the slide.
#[test]
fn a_preload_along_the_foundation_is_refused() {
    let block = Block::loaded(8, 1e3, 1.0, Traction::Vector([1.0, -P]), 0.0).unwrap();
    let e = block
        .integrator(Settings::new(Scheme::CentralDifference, 1e-4, 1.0))
        .unwrap_err();
    match &e {
        TimeError::Unbalanced(motions) => {
            assert_eq!(motions.len(), 1, "{e}");
            assert_eq!(motions[0].label, "translation in x", "{e}");
        }
        _ => panic!("{e}"),
    }
}

/// A block 0.05, 5 or 500 above the floor (`[initial] state = "static"`
/// from off the foundation) is carried onto it by the preload and settles
/// at the same approach (p/c_n)^{1/m_n} = 0.01 to 1e-9, both laws.
#[test]
fn a_preload_carries_a_block_from_off_the_foundation_onto_it() {
    // 5 and 500 are 500 and 50,000 times the approach (the preload's own
    // deformation is of that order): the Newton steps do not run out
    // however far it starts.
    for (cn, mn) in LAWS {
        for gap in [0.05, 5.0, 500.0] {
            let block = Block::loaded(8, cn, mn, Traction::Pressure(P), gap).unwrap();
            let run = block
                .integrator(Settings::new(Scheme::CentralDifference, 1e-4, 1.0))
                .unwrap();
            let (most, least) = block.approaches(run.displacement());
            let expected = (P / cn).powf(1.0 / mn);
            for d in [most, least] {
                assert!(
                    (d - expected).abs() < 1e-9,
                    "m_n = {mn}, gap {gap}: {d} vs {expected}"
                );
            }
        }
    }
}

/// The same preload started by Newmark (¼, ½): r₀ at (p/c_n)^{1/m_n}, the
/// foundation's force in r̈₀ and the bounds set at r₀, so 200 undamped
/// steps leave every bottom node at that approach to 1e-9 and the ledger's
/// balance within 1e-9 of the stored energy c_n δ^{m_n+1}/(m_n+1).
#[test]
fn a_preloaded_block_stays_at_the_static_approach_under_newmark() {
    for (cn, mn) in LAWS {
        let block = Block::new(8, cn, mn).unwrap();
        let scheme = Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        };
        let mut run = block.integrator(Settings::new(scheme, 1e-3, 1.0)).unwrap();
        let expected = (P / cn).powf(1.0 / mn);
        let stored = cn * expected.powf(mn + 1.0) / (mn + 1.0);
        let e0 = run.energy();
        assert!(
            (e0.foundation_stored - stored).abs() < 1e-9 * stored,
            "m_n = {mn}: {} vs {stored}",
            e0.foundation_stored
        );
        for _ in 0..200 {
            run.step().unwrap();
        }
        let (most, least) = block.approaches(run.displacement());
        for d in [most, least] {
            assert!((d - expected).abs() < 1e-9, "m_n = {mn}: {d} vs {expected}");
        }
        let e = run.energy();
        assert!(e.balance.abs() < 1e-9 * stored, "m_n = {mn}: {e:?}");
    }
}

/// The slope's angle θ (20°).
const THETA: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// The block's width and height (ρ = 1: its mass is m = W·H).
const W: f64 = 1.0;
const H: f64 = 0.5;
/// Its gap above the slope.
const D: f64 = 0.5;
/// Gravity.
const G: f64 = 9.81;

/// The block W × H (8 × 4 Q1 cells, E = 10⁴) turned by −θ and lifted D
/// along ν = (sin θ, cos θ) above the frictionless compliant slope through
/// the origin with normal ν (c_n = 10⁴, m_n = 1), under gravity `g` (per
/// unit volume) and a uniform traction `top` on its top, both present
/// before t = 0; its integrator (Newmark, the preload solved at setup) or
/// the setup's error.
fn slope_block(
    g: [f64; 2],
    top: [f64; 2],
) -> (Mesh, ContactSurface, Result<Integrator, TimeError>) {
    slope_block_with(g, top, |_, _| {})
}

/// [`slope_block`] with forces `extra` adds to the full load vector (two
/// per node) besides.
fn slope_block_with(
    g: [f64; 2],
    top: [f64; 2],
    extra: impl Fn(&Mesh, &mut [f64]),
) -> (Mesh, ContactSurface, Result<Integrator, TimeError>) {
    let mut mesh = rectangle(CellKind::Quad4, 8, 4, [0.0, 0.0], [W, H]);
    let (s, c) = THETA.sin_cos();
    map_nodes(&mut mesh, |[x, y]| {
        [x * c + y * s + D * s, -x * s + y * c + D * c]
    });
    let material = Material::new(1e4, 0.3, 1.0, Hypothesis::PlaneStrain).unwrap();
    let model = Model::new(&mesh, &material, &[]).unwrap();
    let law = Compliance {
        cn: 1e4,
        mn: 1.0,
        ct: 0.0,
        mt: 1.0,
    };
    let slope = ([0.0, 0.0], [s, c]);
    let contact =
        ContactSurface::on_foundation(&mesh, &model.dofs, "bottom", slope, law, 1e-3).unwrap();
    let mut full = vec![0.0; 2 * mesh.nodes.len()];
    body_force_load(&mesh, g, &mut full);
    traction_load(&mesh, "top", Traction::Vector(top), &mut full).unwrap();
    extra(&mesh, &mut full);
    let mut vector = vec![0.0; model.dofs.n_free()];
    model.dofs.restrict(&full, &mut vector);
    let loads = vec![Load {
        vector,
        history: History::Constant,
    }];
    let scheme = Scheme::Newmark {
        beta: 0.25,
        gamma: 0.5,
    };
    let run = Integrator::new(
        Dynamics::from_model(&model),
        Some(contact.clone()),
        loads,
        Settings::new(scheme, 1e-3, 1.0),
    );
    (mesh, contact, run)
}

/// The block of [`slope_block`] held on the slope: gravity's pull along
/// the slope, m g sin θ, balanced by a traction of that total on its top,
/// pointing uphill. The loads' resultant is then m g cos θ against ν, so
/// the foundation's nodal forces N_J = w_J c_n δ_J sum to m g cos θ; the
/// traction, a height H above the bottom, and gravity, at H/2, make a
/// couple, so their moment about the block's uphill bottom corner gives
/// Σ_J s_J N_J = (W/2) m g cos θ − (H/2) m g sin θ (s_J the distance
/// along the slope from that corner). Both hold to 1e-9 of m g cos θ in
/// the discrete statics (the rigid motions are in the elements' space and
/// the consistent loads integrate their work exactly). The part starts D
/// = 0.5 off the slope, 250 times its deformation.
#[test]
fn a_preload_carries_a_block_onto_a_slope_and_balances_it() {
    let m = W * H;
    let (s, c) = THETA.sin_cos();
    let pull = m * G * s / W;
    let (mesh, contact, run) = slope_block([0.0, -G], [-pull * c, pull * s]);
    let run = run.unwrap();
    let r = run.displacement();
    let corner = [D * s, D * c];
    let (mut total, mut moment) = (0.0, 0.0);
    for k in &contact.compliance {
        let node = &contact.nodes[k.index];
        let delta = k.approach(node, r);
        let force = node.weight * k.law.traction(delta);
        let x = mesh.nodes[node.node];
        let along = (x[0] - corner[0]) * c - (x[1] - corner[1]) * s;
        total += force;
        moment += along * force;
    }
    let weight = m * G * c;
    assert!(
        (total - weight).abs() < 1e-9 * weight,
        "{total} vs {weight}"
    );
    let expected = 0.5 * W * weight - 0.5 * H * m * G * s;
    assert!(
        (moment - expected).abs() < 1e-9 * weight,
        "{moment} vs {expected}"
    );
}

/// Loads pulling the block of [`slope_block`] off the slope (gravity
/// reversed, its pull along the slope balanced by the top's traction):
/// refused naming the translation along ν by its direction, with the
/// net force along it, m g cos θ (ν·d) for the direction d named, and the
/// rotation about the block's centre with the couple's moment about it,
/// −(H/2) m g sin θ (the traction m g sin θ along the slope, H/2 above
/// the centre).
#[test]
fn a_preload_pulling_a_block_off_a_slope_names_the_direction() {
    let m = W * H;
    let (s, c) = THETA.sin_cos();
    let pull = m * G * s / W;
    let (_, _, run) = slope_block([0.0, G], [pull * c, -pull * s]);
    let e = run.unwrap_err();
    let TimeError::Unbalanced(motions) = &e else {
        panic!("{e}")
    };
    let message = e.to_string();
    let translation = motions
        .iter()
        .find(|m| m.label.starts_with("translation along ("))
        .unwrap_or_else(|| panic!("{message}"));
    let Some(RigidMotion::Translation(d)) = translation.motion else {
        panic!("{message}")
    };
    let named = format!("translation along ({:.6}, {:.6})", d[0], d[1]);
    assert!(translation.label.starts_with(&named), "{message}");
    let along_normal = d[0] * s + d[1] * c;
    assert!((along_normal.abs() - 1.0).abs() < 1e-6, "{message}");
    let expected = m * G * c * along_normal;
    assert!(
        (translation.work - expected).abs() < 1e-6 * m * G,
        "{message}: {} vs {expected}",
        translation.work
    );
    assert!(message.contains("net force along it F = "), "{message}");
    let rotation = motions
        .iter()
        .find(|m| m.label.starts_with("rotation about ("))
        .unwrap_or_else(|| panic!("{message}"));
    let expected = -0.5 * H * m * G * s;
    assert!(
        (rotation.work - expected).abs() < 1e-9 * m * G,
        "{message}: {} vs {expected}",
        rotation.work
    );
    assert!(!message.contains("combination"), "{message}");
}

/// A couple that tips the block over its downhill edge while its weight
/// presses it into the slope: the foundation holds the press, so the
/// refusal names the rotation alone, not also the translation along ν
/// (which it did, with the weight's force as if that were the cause).
#[test]
fn a_block_tipped_off_a_slope_is_refused_by_its_rotation_alone() {
    let m = W * H;
    let (s, c) = THETA.sin_cos();
    // Gravity along −ν: no share along the frictionless slope.
    let g = [-G * s, -G * c];
    // ±P ν at the top corners, P W twice the weight's moment m G W/2 about
    // either bottom edge: the left lifts.
    let p = 2.0 * m * G;
    let corner = |x: f64| [x * c + H * s + D * s, -x * s + H * c + D * c];
    let (_, _, run) = slope_block_with(g, [0.0, 0.0], |mesh, full| {
        for (x, sign) in [(0.0, 1.0), (W, -1.0)] {
            let at = corner(x);
            let node = mesh
                .nodes
                .iter()
                .position(|q| (q[0] - at[0]).hypot(q[1] - at[1]) < 1e-9)
                .expect("a corner node");
            full[2 * node] += sign * p * s;
            full[2 * node + 1] += sign * p * c;
        }
    });
    let e = run.unwrap_err();
    let TimeError::Unbalanced(motions) = &e else {
        panic!("{e}")
    };
    let message = e.to_string();
    assert_eq!(motions.len(), 1, "{message}");
    assert!(
        motions[0].label.starts_with("rotation about ("),
        "{message}"
    );
    assert!(
        matches!(motions[0].motion, Some(RigidMotion::Rotation(_))),
        "{message}"
    );
}
