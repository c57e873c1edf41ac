//! The output the tolerance is on, and the error measure of one traced run
//! against another on it.

use stickslip_case::pilot::{self, relative_l2, sample, Trace};

/// The output the tolerance is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// u_x at a node.
    Ux,
    /// u_y at a node.
    Uy,
    /// σ_T at a contact node.
    FrictionStress,
    /// Total energy at t_end.
    Energy,
}

impl Quantity {
    /// Parses `--on`.
    ///
    /// # Errors
    /// An unknown name, with the accepted ones.
    pub fn parse(s: &str) -> Result<Quantity, String> {
        match s {
            "ux" => Ok(Quantity::Ux),
            "uy" => Ok(Quantity::Uy),
            "friction_stress" => Ok(Quantity::FrictionStress),
            "energy" => Ok(Quantity::Energy),
            _ => Err(format!(
                "--on {s:?}: expected ux, uy, friction_stress or energy"
            )),
        }
    }

    /// Name as given to `--on`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Ux => "ux",
            Quantity::Uy => "uy",
            Quantity::FrictionStress => "friction_stress",
            Quantity::Energy => "energy",
        }
    }
}

/// Uniform sample times for the L2-in-time norms.
pub const SAMPLES: usize = 5001;

/// The uniform grid of [`SAMPLES`] times on [0, t_end].
pub fn grid(t_end: f64) -> Vec<f64> {
    pilot::grid(t_end, SAMPLES)
}

/// The error measure of `a` against `b` (docs/work-precision.csv's):
/// ‖a − b‖ / ‖b − b(0)‖ in the discrete L2-in-time norm for u_x, u_y
/// (relative to the motion; the initial state is the static solution),
/// ‖a − b‖ / ‖b‖ for σ_T, and |E_a(t_end) − E_b(t_end)| / |E_b(t_end) −
/// E_b(0)| for the energy.
pub fn distance(q: Quantity, a: &Trace, b: &Trace, grid: &[f64]) -> f64 {
    if q == Quantity::Energy {
        return (a.energy_end - b.energy_end).abs() / (b.energy_end - b.energy0).abs();
    }
    let sa = sample(&a.t, &a.values[0], grid);
    let sb = sample(&b.t, &b.values[0], grid);
    let offset = if q == Quantity::FrictionStress {
        0.0
    } else {
        sb[0]
    };
    relative_l2(&sa, &sb, offset)
}

/// The size [`distance`] divides by, of the trace `b`: its motion
/// ‖b − b(0)‖ for u_x, u_y, ‖b‖ for σ_T, |E(t_end) − E(0)| for the
/// energy. Where it is 0 every relative error is undefined.
pub fn motion(q: Quantity, b: &Trace, grid: &[f64]) -> f64 {
    if q == Quantity::Energy {
        return (b.energy_end - b.energy0).abs();
    }
    let sb = sample(&b.t, &b.values[0], grid);
    let offset = if q == Quantity::FrictionStress {
        0.0
    } else {
        sb[0]
    };
    sb.iter().map(|y| (y - offset).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_quantities() {
        assert_eq!(
            Quantity::parse("friction_stress"),
            Ok(Quantity::FrictionStress)
        );
        assert!(Quantity::parse("sigma").is_err());
    }
}
