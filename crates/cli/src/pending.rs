//! The rows a results file has not yet written: buffered along time and
//! written one block per dataset (`output.rs`).

use crate::output::{Record, ENERGY_NAMES};

/// Rows appended since the last write into the datasets, row after row.
///
/// Writing each row as it comes costs about 30 HDF5 calls a row (a resize
/// and a hyperslab write per dataset), which on small meshes was most of a
/// run (docs/performance.md). Rows are kept here and written one block
/// per dataset when they reach [`PENDING_BYTES`] (or [`HISTORY_BLOCK`]
/// rows), and before every flush, checkpoint and the end of the run, so a
/// flushed file holds every row appended before the flush. A block need
/// not end at a chunk's end: HDF5 keeps the partly written chunk in its
/// cache (1 MiB a dataset, more than a chunk) until the next block fills it.
#[derive(Debug, Default)]
pub(crate) struct Pending {
    /// One entry a row: its length is the number of rows.
    pub(crate) time: Vec<f64>,
    /// One entry a frame: its time and its row (counted from the file's
    /// first).
    pub(crate) frame_time: Vec<f64>,
    pub(crate) frame_row: Vec<u64>,
    pub(crate) displacement: Vec<f64>,
    pub(crate) velocity: Vec<f64>,
    pub(crate) acceleration: Vec<f64>,
    pub(crate) friction_stress: Vec<f64>,
    pub(crate) slip_velocity: Vec<f64>,
    pub(crate) state: Vec<i8>,
    pub(crate) normal_stress: Vec<f64>,
    pub(crate) energy: [Vec<f64>; ENERGY_NAMES.len()],
    pub(crate) dt: Vec<f64>,
    pub(crate) iterations: Vec<u32>,
}

impl Pending {
    pub(crate) fn rows(&self) -> usize {
        self.time.len()
    }

    pub(crate) fn frames(&self) -> usize {
        self.frame_time.len()
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        let f64s = self.time.len()
            + self.frame_time.len()
            + self.displacement.len()
            + self.velocity.len()
            + self.acceleration.len()
            + self.friction_stress.len()
            + self.slip_velocity.len()
            + self.normal_stress.len()
            + self.dt.len()
            + self.energy.iter().map(Vec::len).sum::<usize>();
        8 * (f64s + self.frame_row.len()) + self.state.len() + 4 * self.iterations.len()
    }

    /// Appends `rec` as the file's row `row`.
    pub(crate) fn push(&mut self, rec: &Record, row: usize) {
        self.time.push(rec.t);
        if !rec.displacement.is_empty() {
            self.frame_time.push(rec.t);
            self.frame_row.push(row as u64);
        }
        self.displacement.extend_from_slice(rec.displacement);
        self.velocity.extend_from_slice(rec.velocity);
        self.acceleration.extend_from_slice(rec.acceleration);
        self.friction_stress.extend_from_slice(rec.friction_stress);
        self.slip_velocity.extend_from_slice(rec.slip_velocity);
        self.state.extend_from_slice(rec.state);
        self.normal_stress.extend_from_slice(rec.normal_stress);
        let e: [f64; ENERGY_NAMES.len()] = [
            rec.kinetic,
            rec.strain,
            rec.external_work,
            rec.dissipated,
            rec.total,
            rec.balance,
            rec.damped,
            rec.foundation,
            rec.foundation_stored,
        ];
        for (series, v) in self.energy.iter_mut().zip(e) {
            series.push(v);
        }
        self.dt.push(rec.dt);
        self.iterations.push(rec.iterations);
    }

    /// Empties the buffers, keeping their capacity.
    pub(crate) fn clear(&mut self) {
        for v in [
            &mut self.time,
            &mut self.displacement,
            &mut self.velocity,
            &mut self.acceleration,
            &mut self.friction_stress,
            &mut self.slip_velocity,
            &mut self.normal_stress,
            &mut self.dt,
        ]
        .into_iter()
        .chain(&mut self.energy)
        {
            v.clear();
        }
        self.state.clear();
        self.iterations.clear();
        self.frame_time.clear();
        self.frame_row.clear();
    }
}
