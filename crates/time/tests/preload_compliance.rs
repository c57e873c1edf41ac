//! The static preload with a compliant foundation (METHOD.md §8, §10): the
//! test kit's block (1 × ½, E = 1000, ν = 0.3, floating) pressed by p = 10
//! onto a frictionless floor. Uniform compression passes p unchanged to
//! every bottom node, whose traction c_n δ^{m_n} = p gives the approach
//! (p/c_n)^{1/m_n} = 0.01 for both laws below; Q1 cells hold the linear
//! field exactly, so the closed form holds to the solver's tolerance.

use stickslip_fem::Traction;
use stickslip_testkit::settle::{preload, Block, P};
use stickslip_time::{Scheme, Settings, TimeError};

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
                motions.iter().any(|(m, _)| m.contains("translation in y")),
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
            assert_eq!(motions[0].0, "translation in x", "{e}");
        }
        _ => panic!("{e}"),
    }
}

/// A block 0.05 above the floor (`[initial] state = "static"` from off the
/// foundation) is carried onto it by the preload and settles at the same
/// approach (p/c_n)^{1/m_n} = 0.01 to 1e-9, both laws.
#[test]
fn a_preload_carries_a_block_from_off_the_foundation_onto_it() {
    for (cn, mn) in LAWS {
        let block = Block::loaded(8, cn, mn, Traction::Pressure(P), 0.05).unwrap();
        let run = block
            .integrator(Settings::new(Scheme::CentralDifference, 1e-4, 1.0))
            .unwrap();
        let (most, least) = block.approaches(run.displacement());
        let expected = (P / cn).powf(1.0 / mn);
        for d in [most, least] {
            assert!((d - expected).abs() < 1e-9, "m_n = {mn}: {d} vs {expected}");
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
