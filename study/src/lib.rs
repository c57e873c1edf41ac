//! Measured studies of the solver on the paper's slab: the work-precision
//! chart (error against wall time over element order, mesh, scheme, Δt and ε)
//! and the stability map (the explicit critical step, the ringing after
//! sticking, the stick/slip iteration with and without Remark 4.2, the
//! threshold with a compliant wall). Everything
//! runs the integrators in-process; results go to CSV files and PNG/SVG charts
//! in docs/.

pub mod chart;
pub mod plot;
pub mod run;
pub mod slab;
pub mod stability;
pub mod stability_compliance;
