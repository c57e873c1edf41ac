//! The four suites of `verify` (`surfaces`, `belt`, `compliance` and
//! `consistency` run within `analytic`).

pub mod analytic;
pub mod belt;
pub mod compliance;
pub mod consistency;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
pub mod surfaces;
