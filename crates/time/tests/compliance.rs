//! The normal-compliance law in the explicit scheme (METHOD.md §10) on the
//! bar impact of Hughes et al. (the test kit's `impact`): the rigid wall's
//! closed form is a contact of 2L/c at the stress ρcv₀ = v₀, the bar
//! leaving at −v₀.

use stickslip_testkit::impact::{run, C, L, V0};

#[test]
fn print_table() {
    for nx in [20, 40] {
        for cn in [1.0, 10.0, 100.0] { for courant in [0.9, 0.5, 0.2] {
            let r = run(nx, cn, courant).unwrap();
            println!(
                "nx {nx} cn {cn} courant {courant}: time {:.4} (2L/c {}), stress {:.5} ({V0}), exit {:.5}, balance {:.2e}, dt_crit {:.3e}",
                r.contact_time,
                2.0 * L / C,
                r.stress,
                r.exit_velocity,
                r.balance,
                r.dt_crit
            );
        } }
    }
}
