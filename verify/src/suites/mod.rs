//! The four suites of `verify` (`surfaces`, `belt` and `compliance` run
//! within `analytic`).

pub mod analytic;
pub mod belt;
pub mod compliance;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
pub mod surfaces;
