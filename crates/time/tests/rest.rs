//! At rest (v = 0, t = 0) the friction stress is +0, not −0: −g φ(0) is
//! −0 in floating point, which the results file kept and scripts printed
//! as "-0.000".

mod common;
use common::*;
use stickslip_time::{History, Scheme, Settings};

#[test]
fn friction_stress_at_rest_is_plus_zero() {
    let s = paper_slab("slab-q2-8x2.msh", 1e-4, History::Step);
    for scheme in [
        Scheme::CentralDifference,
        Scheme::Newmark {
            beta: 0.25,
            gamma: 0.5,
        },
    ] {
        let i = s.integrator(Settings::new(scheme, 1e-3, 0.5)).unwrap();
        let n = i.contact().map_or(0, |c| c.len());
        assert!(n > 0);
        let mut stress = vec![f64::NAN; n];
        i.friction_stress(&mut stress);
        assert!(
            stress.iter().all(|x| x.to_bits() == 0),
            "{scheme:?}: {stress:?}"
        );
    }
}
