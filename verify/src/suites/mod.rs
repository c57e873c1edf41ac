//! The four suites of `verify`.

pub mod analytic;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
