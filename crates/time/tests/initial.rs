//! Where a run starts: Remark 4.1's static preload (the default) or rest,
//! with an initial velocity added.

use stickslip_linalg::csr::spmv;
use stickslip_testkit::paper_slab;
use stickslip_time::{History, InitialState, Scheme, Settings};

const NEWMARK: Scheme = Scheme::Newmark {
    beta: 0.25,
    gamma: 0.5,
};

/// At rest r₀ = 0 and every load acts from t = 0: M r̈₀ = R(0), where R(0)
/// is the sum of the load vectors (the contact pressure, constant, and the
/// end load H(t), both 1 at t = 0). The static start of the same scene has
/// r₀ ≠ 0 (the pressure preloads it).
#[test]
fn rest_starts_undeformed_with_m_a_equal_to_the_loads() {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let n = s.n_free();
    let mut load = vec![0.0; n];
    for l in &s.loads {
        for (r, f) in load.iter_mut().zip(&l.vector) {
            *r += f;
        }
    }
    let scale = load.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for scheme in [Scheme::CentralDifference, NEWMARK] {
        let static_start = s.integrator(Settings::new(scheme, 1e-3, 0.1)).unwrap();
        assert!(static_start.displacement().iter().any(|&x| x != 0.0));
        let mut settings = Settings::new(scheme, 1e-3, 0.1);
        settings.initial_state = InitialState::Rest;
        let i = s.integrator(settings).unwrap();
        assert!(i.displacement().iter().all(|&x| x == 0.0), "{scheme:?}");
        let mut ma = vec![0.0; n];
        match scheme {
            Scheme::CentralDifference => {
                for ((m, a), out) in s
                    .model
                    .lumped_mass
                    .iter()
                    .zip(i.acceleration())
                    .zip(&mut ma)
                {
                    *out = m * a;
                }
            }
            Scheme::Newmark { .. } => spmv(&s.model.mass, i.acceleration(), &mut ma),
        }
        for (k, (got, want)) in ma.iter().zip(&load).enumerate() {
            assert!(
                (got - want).abs() <= 1e-10 * scale,
                "{scheme:?} DOF {k}: M a = {got}, R(0) = {want}"
            );
        }
        // Nothing strained yet: the ledger starts at zero.
        assert_eq!(i.energy().strain, 0.0);
        assert_eq!(i.energy().kinetic, 0.0);
    }
}

/// ṙ₀ is added to either start: the velocity given is the velocity the
/// run starts with, and ½ṙ₀ᵀMṙ₀ the kinetic energy it books (lumped M:
/// Σ m v²/2 written out here).
#[test]
fn an_initial_velocity_is_added_to_the_chosen_state() {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    let n = s.n_free();
    let v0: Vec<f64> = (0..n).map(|k| 0.01 * ((k % 7) as f64 - 3.0)).collect();
    let kinetic: f64 = 0.5
        * s.model
            .lumped_mass
            .iter()
            .zip(&v0)
            .map(|(m, v)| m * v * v)
            .sum::<f64>();
    for state in [InitialState::Static, InitialState::Rest] {
        let mut settings = Settings::new(Scheme::CentralDifference, 1e-3, 0.1);
        settings.initial_state = state;
        settings.initial_velocity = Some(v0.clone());
        let i = s.integrator(settings).unwrap();
        assert_eq!(i.velocity(), &v0[..]);
        let e = i.energy().kinetic;
        assert!(
            (e - kinetic).abs() <= 1e-12 * kinetic,
            "{state:?}: {e} vs {kinetic}"
        );
    }
}
