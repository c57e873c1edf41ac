//! stickslip-fem (being written).
