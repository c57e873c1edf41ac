//! `time.allow_unstable` runs an explicit step above the bound that a
//! stiffening foundation (m_n > 1) puts on Δt, as it does above Δt_crit:
//! that bound is Weyl's inequality's, a sufficient condition, so a user
//! who knows better may run past it (the stability study bisects there).

use stickslip_contact::Compliance;
use stickslip_testkit::impact::run_with;

#[test]
fn allow_unstable_runs_past_the_stiffening_walls_bound() {
    // The wall that stops the run of tests/compliance.rs without the flag.
    let law = Compliance {
        cn: 1e6,
        mn: 2.0,
        ct: 0.0,
        mt: 2.0,
    };
    assert!(run_with(20, law, 0.95, false).is_err());
    let r = run_with(20, law, 0.95, true);
    assert!(r.is_ok(), "{r:?}");
}
