//! The time-stepping methods `stickslip advise` chooses from and the
//! studies compare, and how each is written into a case or into the time
//! crate's settings.

use std::path::Path;

use stickslip_time::{Scheme as TimeScheme, Settings, StickReduction as TimeReduction};

use crate::schema::{Case, Scheme, StickReduction};

/// Remark 4.3 as the paper did it: Δt = 1e-7 for 10 steps after sticking.
pub const PAPER_REDUCTION: StickReduction = StickReduction {
    dt: 1e-7,
    steps: 10,
};

/// A time-stepping method: scheme, its parameters and the step reduction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Central difference, lumped mass, closed-form nodal friction.
    CentralDifference,
    /// Newmark ¼/½ (trapezoidal rule), consistent mass.
    Trapezoidal,
    /// Newmark ¼/½ with the step reduction of Remark 4.3.
    TrapezoidalReduced,
    /// Newmark 0.3025/0.6 (numerical damping).
    Damped,
}

impl Method {
    /// All of them, in table order.
    pub const ALL: [Method; 4] = [
        Method::CentralDifference,
        Method::Trapezoidal,
        Method::TrapezoidalReduced,
        Method::Damped,
    ];

    /// Short name (tables, docs/work-precision.csv, advise's pilot lines).
    pub fn name(self) -> &'static str {
        match self {
            Method::CentralDifference => "cd",
            Method::Trapezoidal => "nm-0.25-0.5",
            Method::TrapezoidalReduced => "nm-0.25-0.5-reduced",
            Method::Damped => "nm-0.3025-0.6",
        }
    }

    /// Longer name (chart legends, advise's report).
    pub fn label(self) -> &'static str {
        match self {
            Method::CentralDifference => "central difference",
            Method::Trapezoidal => "Newmark ¼,½",
            Method::TrapezoidalReduced => "Newmark ¼,½ + reduction",
            Method::Damped => "Newmark 0.3025,0.6",
        }
    }

    /// (β, γ) of the Newmark methods; `None` for central difference.
    pub fn newmark(self) -> Option<(f64, f64)> {
        match self {
            Method::CentralDifference => None,
            Method::Trapezoidal | Method::TrapezoidalReduced => Some((0.25, 0.5)),
            Method::Damped => Some((0.3025, 0.6)),
        }
    }

    /// The time crate's settings for this method, for scenes built in code
    /// (the reduced method with the paper's Remark 4.3).
    pub fn settings(self, dt: f64, t_end: f64) -> Settings {
        let scheme = match self.newmark() {
            None => TimeScheme::CentralDifference,
            Some((beta, gamma)) => TimeScheme::Newmark { beta, gamma },
        };
        let mut s = Settings::new(scheme, dt, t_end);
        if self == Method::TrapezoidalReduced {
            s.stick_reduction = Some(TimeReduction {
                dt: PAPER_REDUCTION.dt,
                steps: PAPER_REDUCTION.steps,
            });
        }
        s
    }

    /// `case` on `mesh` with this method, Δt and ε: the scheme's own mass,
    /// no run above Δt_crit, and for the reduced method the case's step
    /// reduction or else the paper's.
    pub fn configure(self, case: &Case, mesh: &Path, dt: f64, eps: f64) -> Case {
        let mut c = case.clone();
        c.mesh.file = mesh.to_path_buf();
        c.time.dt = dt;
        c.time.mass = None;
        c.time.allow_unstable = false;
        match self.newmark() {
            None => c.time.scheme = Scheme::CentralDifference,
            Some((beta, gamma)) => {
                c.time.scheme = Scheme::Newmark;
                c.time.beta = beta;
                c.time.gamma = gamma;
            }
        }
        c.time.stick_reduction = (self == Method::TrapezoidalReduced)
            .then(|| case.time.stick_reduction.unwrap_or(PAPER_REDUCTION));
        for contact in c.contact.iter_mut() {
            contact.eps = eps;
        }
        c
    }
}
