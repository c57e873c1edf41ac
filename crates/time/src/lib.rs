//! stickslip-time (being written).
