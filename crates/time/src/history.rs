//! Load histories θ(t): a load is t₀(x)·θ(t) (METHOD.md §1).

/// How a load varies in time.
#[derive(Clone, Debug, PartialEq)]
pub enum History {
    /// Always on, also before t = 0: part of the initial static state.
    Constant,
    /// Heaviside H(t): off before 0, on from t = 0 (H(0) = 1), so it is not
    /// in the initial static state but is in R(0) (BENCHMARK.md).
    Step,
    /// sin(ω t) (the paper's θ = sin 8πt has ω = 8π).
    Sin {
        /// Angular frequency ω (rad per unit time).
        omega: f64,
    },
    /// Piecewise linear through (t, θ) points sorted by t, constant beyond
    /// the ends; in the initial static state only if it starts before t = 0.
    Table(Vec<(f64, f64)>),
}

impl History {
    /// θ(t) for t ≥ 0.
    pub fn value(&self, t: f64) -> f64 {
        match self {
            History::Constant | History::Step => 1.0,
            History::Sin { omega } => (omega * t).sin(),
            History::Table(points) => interpolate(points, t),
        }
    }

    /// θ(0⁻): how much of the load acts in the initial static state.
    pub fn before_start(&self) -> f64 {
        match self {
            History::Constant => 1.0,
            History::Step | History::Sin { .. } => 0.0,
            History::Table(points) => match points.first() {
                Some(&(t0, _)) if t0 < 0.0 => interpolate(points, 0.0),
                _ => 0.0,
            },
        }
    }
}

fn interpolate(points: &[(f64, f64)], t: f64) -> f64 {
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return 0.0;
    };
    if t <= first.0 {
        return first.1;
    }
    if t >= last.0 {
        return last.1;
    }
    // Sorted by t: the segment holding t is the first whose end is ≥ t.
    let k = points.partition_point(|p| p.0 < t);
    let (t0, f0) = points[k - 1];
    let (t1, f1) = points[k];
    if t1 > t0 {
        f0 + (f1 - f0) * (t - t0) / (t1 - t0)
    } else {
        f1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histories_take_their_defining_values() {
        assert_eq!(History::Step.value(0.0), 1.0);
        assert_eq!(History::Step.before_start(), 0.0);
        assert_eq!(History::Constant.before_start(), 1.0);
        let s = History::Sin {
            omega: 8.0 * std::f64::consts::PI,
        };
        assert!((s.value(1.0 / 16.0) - 1.0).abs() < 1e-15); // sin(π/2)
        let table = History::Table(vec![(0.0, 0.0), (1.0, 2.0), (3.0, 2.0)]);
        assert_eq!(table.value(0.5), 1.0);
        assert_eq!(table.value(2.0), 2.0);
        assert_eq!(table.value(9.0), 2.0);
        assert_eq!(table.before_start(), 0.0);
        assert_eq!(
            History::Table(vec![(-1.0, 4.0), (1.0, 0.0)]).before_start(),
            2.0
        );
    }
}
