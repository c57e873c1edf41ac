//! The contact's normal traction a results file records at each contact
//! node and row (`/contact/normal_stress`, docs/results.md): on a
//! prescribed-pressure surface the pressure p(s, t) = p·profile(s)·θ(t)
//! the case gives (METHOD.md §9), on a compliant one the foundation's
//! c_n δ^{m_n} at the current displacement (METHOD.md §10).

use stickslip_case::{Case, History};
use stickslip_time::Integrator;

/// What the normal traction of a row is formed from.
#[derive(Debug)]
pub(crate) struct NormalStress {
    /// Per contact node, p·profile(s) of its prescribed-pressure surface
    /// (0 on a compliant one).
    base: Vec<f64>,
    /// Per contact node, its surface's index into `histories`.
    surface: Vec<usize>,
    /// Each surface's pressure history θ(t).
    histories: Vec<History>,
    /// Some surface is compliant.
    compliant: bool,
}

impl NormalStress {
    /// For the run of `case` by `integrator` (its contact surfaces are the
    /// case's `[contact]` tables in order).
    pub(crate) fn new(case: &Case, integrator: &Integrator) -> NormalStress {
        let Some(c) = integrator.contact() else {
            return NormalStress {
                base: Vec::new(),
                surface: Vec::new(),
                histories: Vec::new(),
                compliant: false,
            };
        };
        let surface = c.part_of_nodes();
        let sections = &case.contact;
        let base = c
            .nodes
            .iter()
            .zip(&surface)
            .map(|(n, &k)| {
                let Some(section) = sections.get(k) else {
                    return 0.0;
                };
                let profile = section
                    .pressure_profile
                    .as_ref()
                    .map_or(1.0, |p| History::Table(p.table.clone()).value(n.s));
                section.pressure.unwrap_or(0.0) * profile
            })
            .collect();
        NormalStress {
            base,
            surface,
            histories: sections
                .iter()
                .map(|s| s.pressure_history.clone())
                .collect(),
            compliant: c.is_compliant(),
        }
    }

    /// The normal traction at each contact node now, into `out`.
    pub(crate) fn fill(&self, integrator: &Integrator, out: &mut [f64]) {
        if self.compliant {
            integrator.normal_traction(out);
        } else {
            out.fill(0.0);
        }
        let t = integrator.time();
        for ((o, &p), &k) in out.iter_mut().zip(&self.base).zip(&self.surface) {
            if p != 0.0 {
                *o += p * self.histories.get(k).map_or(1.0, |h| h.value(t));
            }
        }
    }
}
