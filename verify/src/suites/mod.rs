//! The four suites of `verify` (`surfaces` and `belt` run within
//! `analytic`).

pub mod analytic;
pub mod belt;
pub mod friction_held;
pub mod paper;
pub mod rates;
pub mod reference;
pub mod strip;
pub mod surfaces;
