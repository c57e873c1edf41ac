//! The four suites of `verify` (`surfaces` and `compliance` run within `analytic`).

pub mod analytic;
pub mod compliance;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
pub mod surfaces;
