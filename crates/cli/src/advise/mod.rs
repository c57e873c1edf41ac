//! `stickslip advise`: the cheapest configuration (element order, mesh of
//! the case's `mesh.ladder`, scheme, Δt, ε) whose estimated error on one
//! output is below a tolerance, from error estimates measured on the
//! user's own case.
//!
//! Error estimates. The pilots (below) include a reference run R, the
//! most accurate one they afford: central difference at 0.9 Δt_crit on the
//! mesh after the pilots of the highest element order. Every pilot run X
//! then has the error √(‖X − R‖² + e_R²) ([`with_reference`]), e_R from
//! the differences of R's own ladder (Richardson with the observed order
//! and correlation, [`ladder_errors`]); e_R enters only in quadrature, so
//! its uncertainty matters little. Measured this way, against the
//! finest run rather than from differences of neighbouring levels, the
//! estimate needs no model of how the errors of successive levels line up:
//! on the slab they are only partly aligned (stick/slip events move between
//! refinements; measured cosines 0.4-0.8), which made the Richardson
//! estimates from neighbour differences off by up to 1.5×.
//!
//! A candidate that was not run is estimated from three measured parts
//! combined in quadrature ([`Candidate::estimate`]): the error of its mesh
//! with its family's base Δt (central difference at 0.9 Δt_crit: the
//! combined h and Δt error of that path, since its Δt is tied to h;
//! Newmark at t_end/200), the change its method and Δt make from that base
//! on the pilot mesh, and the change its ε makes there. Meshes finer than
//! the measured ones continue the last measured decrease (observed order,
//! capped at the theoretical one; none when the errors stopped decreasing).
//! Newmark's errors per mesh, all at t_end/200, carry that Δt's error,
//! which no mesh reduces: the decrease is continued on the errors less
//! that part (estimated from the Δt pilots) and the part added back, so
//! that a finer mesh's estimate does not fall below it.
//!
//! * h: the first three meshes of each element order in the ladder, run
//!   with central difference at 0.9 Δt_crit of each mesh (its own family:
//!   lumped mass, Δt tied to h) and with Newmark ¼/½ at Δt = t_end/200
//!   (consistent mass; shared by the three Newmark variants); the
//!   reference R on the fourth mesh of the highest order.
//! * Δt: on one pilot mesh (the second of the highest order), central
//!   difference at 0.9, 0.45, 0.225 Δt_crit and each Newmark variant at
//!   Δt = t_end/50, /100, /200, /400.
//! * ε: the case's ε is the model the user asked for (its error part is 0);
//!   10ε and 100ε are candidates whose part is the measured difference to
//!   the case's ε on the pilot mesh (central difference, 0.9 Δt_crit). ε
//!   enters as O(√ε) (METHOD.md §2, Theorem 2.3), so no extrapolation to
//!   smaller ε is offered.
//!
//! Pilots run over the whole [0, t_end]: the error measures are integrals
//! (or the end value) over that interval, so a shorter run would not
//! measure them. The predicted time is steps × nnz(K) times one seconds-
//! per-step-per-entry constant per scheme measured on the pilots.
//!
//! The files: `quantity.rs` (the output and its error measure),
//! `ladder.rs` (the case's meshes, read once), `pilots.rs` (one traced run,
//! and the pilot runs of one estimate), `errors.rs` (Richardson, observed
//! orders, errors per level of a ladder), `estimate.rs` (the pilot plan and
//! every candidate's estimate), `candidates.rs` (a configuration and the
//! pick), `adjusted.rs` (the case rewritten for `--write`), `report.rs`
//! (the text and JSON reports) and `command.rs` (the options and the
//! command).

use stickslip_case::InputError;

mod adjusted;
mod candidates;
mod command;
mod errors;
mod estimate;
mod ladder;
mod pilots;
mod quantity;
mod report;

pub use adjusted::adjusted_case;
pub use candidates::{pick, Candidate, TIE};
pub use command::{command, parse_point, Options, Verdict};
pub use errors::{
    continue_errors, continue_errors_above, correlation, dt_error, extrapolate, ladder_errors,
    observed_order, richardson, with_reference, MIN_ORDER, TWO_LEVEL_ORDER,
};
pub use estimate::{estimate, Estimates, CD_FRACTIONS, EPS_FACTORS, NEWMARK_DIVISIONS};
pub use ladder::{read_ladder, LadderMesh};
pub use pilots::{run_traced, Pilot};
pub use quantity::{distance, grid, Quantity, SAMPLES};

/// Bad input (exit 2) with this message, for the parts to return.
fn input(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(InputError(msg.into()))
}
