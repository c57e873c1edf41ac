//! stickslip-contact (being written).
