//! The four suites of `verify` (`surfaces` runs within `analytic`).

pub mod analytic;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
pub mod surfaces;
