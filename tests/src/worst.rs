//! Worst-of folds that keep a NaN.

/// The largest of `values` (−∞ for none), or NaN when any of them is NaN.
///
/// `f64::max` returns its other operand when one is NaN, so a plain
/// `fold(0.0, f64::max)` drops a NaN and a run that produced one would
/// pass its bound; every "worst of" in verify's suites and in this kit's
/// helpers goes through here (NaN then fails verify's `close`, `at_most`
/// and `at_least` alike).
pub fn max_or_nan(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(f64::NEG_INFINITY, |m, v| {
        if m.is_nan() || v.is_nan() {
            f64::NAN
        } else {
            m.max(v)
        }
    })
}

/// The smallest of `values` (+∞ for none), or NaN when any of them is NaN
/// ([`max_or_nan`] of the negated values).
pub fn min_or_nan(values: impl IntoIterator<Item = f64>) -> f64 {
    -max_or_nan(values.into_iter().map(|v| -v))
}
