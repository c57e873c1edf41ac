//! Frames: the steps at which a run writes the full fields (u, v, a at
//! every node), and how a reader finds them in a results file.
//!
//! The histories (`/time`, `/energy/*`, `/solver/*`, `/contact/*`) are
//! written at every step: they are small, and stick and slip live there.
//! The fields are what makes a file large (48 bytes per node a row), so
//! they are written at frames in simulated time (`output.frames`,
//! `output.interval`); the initial state and the last step are always
//! frames. `output.every = n` writes both, fields and histories, every
//! n-th step (and the last), as runs did before the frames. `/frames/time`
//! holds each frame's time and `/frames/row` its row of `/time`.

use hdf5::File;
use stickslip_case::{Fields, InputError};

/// When a run writes the fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    fields: Fields,
    t_end: f64,
}

impl Schedule {
    /// The schedule of `fields` over [0, `t_end`].
    pub fn new(fields: Fields, t_end: f64) -> Schedule {
        Schedule { fields, t_end }
    }

    /// The spacing in simulated time between frames, if the frames are
    /// by time.
    fn spacing(&self) -> Option<f64> {
        match self.fields {
            Fields::Frames(n) => Some(self.t_end / n.max(1) as f64),
            Fields::Interval(dt) => Some(dt),
            Fields::Every(_) => None,
        }
    }

    /// Whether the step that took the run from `t_prev` to `t`, its
    /// `steps`-th, writes the fields; `last`: it is the run's last step.
    ///
    /// By time, frame k is the first step at or after k·spacing: the step
    /// whose interval (t_prev, t] holds k·spacing. The step's times carry
    /// rounding (t = t₀ + kΔt), so a step within a millionth of its length
    /// short of k·spacing counts as reaching it; the rule needs nothing
    /// but the step's two ends, so a restart picks it up where it was.
    pub fn is_frame(&self, steps: u64, t_prev: f64, t: f64, last: bool) -> bool {
        if last {
            return true;
        }
        match (self.fields, self.spacing()) {
            (Fields::Every(n), _) => steps.is_multiple_of(n.max(1) as u64),
            (_, Some(h)) => {
                let tol = 1e-6 * (t - t_prev).abs();
                ((t + tol) / h).floor() > ((t_prev + tol) / h).floor()
            }
            (_, None) => true,
        }
    }

    /// Whether a step that is no frame writes its histories: yes, but
    /// with `output.every`, which writes every n-th step whole.
    pub fn histories_every_step(&self) -> bool {
        !matches!(self.fields, Fields::Every(_))
    }

    /// About how many frames (the initial state included) a run of `steps`
    /// steps of `dt` from t = 0 writes, its last landing on t_end: by
    /// [`Schedule::is_frame`]'s rule, exact where the steps are (Remark
    /// 4.3's reduced steps add some).
    pub fn frames(&self, steps: f64, dt: f64) -> f64 {
        let by_steps = match self.fields {
            Fields::Every(n) => {
                let n = n.max(1) as f64;
                (steps / n).floor() + if steps % n == 0.0 { 0.0 } else { 1.0 }
            }
            _ => steps,
        };
        let by_time = match self.spacing() {
            // Frames no closer than the steps: a step reaches at most one
            // frame time, so the run writes one a frame time up to t_end,
            // and its last step besides where that reaches none. Closer
            // frames fall on every step.
            Some(h) => {
                let t_prev = (steps - 1.0).max(0.0) * dt;
                let tol = 1e-6 * (self.t_end - t_prev).abs();
                let reached = ((self.t_end + tol) / h).floor();
                let last = if reached > ((t_prev + tol) / h).floor() {
                    0.0
                } else {
                    1.0
                };
                (reached + last).min(steps)
            }
            None => by_steps,
        };
        by_time.min(by_steps).max(1.0) + 1.0
    }

    /// How the fields are written, in words (`stickslip check`).
    pub fn describe(&self) -> String {
        match self.fields {
            Fields::Frames(n) => format!("{n} frames over [0, t_end] (output.frames)"),
            Fields::Interval(dt) => format!("a frame every {dt} of time (output.interval)"),
            Fields::Every(1) => "every step (output.every)".to_string(),
            Fields::Every(n) => format!("every {n} steps, the histories too (output.every)"),
        }
    }
}

/// The frames a results file holds: each one's time and its row of
/// `/time` (of the histories). A file written before the frames has the
/// fields at every row: its `/time` and the rows in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frames {
    /// `/frames/time`.
    pub time: Vec<f64>,
    /// `/frames/row`.
    pub row: Vec<usize>,
}

/// Rows of the dataset `ds` of `f` (named `name` in messages) as its
/// shape says, nothing read.
fn rows(f: &File, name: &str, ds: &str) -> Result<usize, InputError> {
    f.dataset(ds)
        .map(|d| d.shape().first().copied().unwrap_or(0))
        .map_err(|e| {
            InputError(format!(
                "{name}: cannot read /{ds}: {e}; give a results file written by `stickslip run`"
            ))
        })
}

/// Rows of the dataset `ds` of `f`, checked against those of `against`
/// before `ds` is read: a damaged file may claim more rows than it holds,
/// and reading them would allocate that much. The two grow together;
/// between two records `ds` may be one row ahead.
pub(crate) fn checked_rows(
    f: &File,
    name: &str,
    ds: &str,
    against: &str,
) -> Result<usize, InputError> {
    let (n, limit) = (rows(f, name, ds)?, rows(f, name, against)?);
    if n > limit + 1 {
        return Err(InputError(format!(
            "{name}: /{ds} has {n} rows but /{against} {limit}: the file is damaged; \
             run the case again"
        )));
    }
    Ok(n)
}

impl Frames {
    /// The frames of `f` (named `name` in messages), their times checked
    /// against the rows of `/displacement` ([`checked_rows`]). A frame
    /// whose row is past `/time` is dropped.
    pub fn read(f: &File, name: &str) -> Result<Frames, InputError> {
        let bad = |ds: &str, e: hdf5::Error| {
            InputError(format!(
                "{name}: cannot read /{ds}: {e}; give a results file written by `stickslip run`"
            ))
        };
        let by_frames = f.link_exists("frames");
        let time_ds = if by_frames { "frames/time" } else { "time" };
        checked_rows(f, name, time_ds, "displacement")?;
        let h_rows = rows(f, name, "time")?;
        let time = f
            .dataset(time_ds)
            .and_then(|d| d.read_1d::<f64>())
            .map_err(|e| bad(time_ds, e))?
            .to_vec();
        let row: Vec<usize> = if by_frames {
            f.dataset("frames/row")
                .and_then(|d| d.read_1d::<u64>())
                .map_err(|e| bad("frames/row", e))?
                .iter()
                .map(|&r| r as usize)
                .collect()
        } else {
            (0..time.len()).collect()
        };
        let n = row
            .iter()
            .take(time.len())
            .take_while(|&&r| r < h_rows)
            .count();
        Ok(Frames {
            time: time[..n].to_vec(),
            row: row[..n].to_vec(),
        })
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True without frames.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The steps of a run of `n` steps of `dt` that the schedule writes.
    fn frames_of(s: &Schedule, dt: f64, n: u64) -> Vec<u64> {
        (1..=n)
            .filter(|&k| s.is_frame(k, (k - 1) as f64 * dt, k as f64 * dt, k == n))
            .collect()
    }

    #[test]
    fn frames_are_the_first_steps_at_or_after_their_times() {
        // 500 steps of 1e-3 to 0.5, 200 frames: frame k at k·2.5e-3, the
        // first step at or after it is ceil(2.5 k).
        let s = Schedule::new(Fields::Frames(200), 0.5);
        let got = frames_of(&s, 1e-3, 500);
        let want: Vec<u64> = (1..=200).map(|k| (2.5 * k as f64).ceil() as u64).collect();
        assert_eq!(got, want);
        assert_eq!(s.frames(500.0, 1e-3), 201.0);
        // Frames closer than the steps: every step.
        let s = Schedule::new(Fields::Frames(200), 0.05);
        assert_eq!(frames_of(&s, 1e-3, 50), (1..=50).collect::<Vec<_>>());
        assert_eq!(s.frames(50.0, 1e-3), 51.0);
    }

    #[test]
    fn an_interval_and_every_n_steps_keep_the_last_step() {
        // 0.3 / 0.125: frames at 0.125 and 0.25 (steps 125 and 250), and
        // the last step 300.
        let s = Schedule::new(Fields::Interval(0.125), 0.3);
        assert_eq!(frames_of(&s, 1e-3, 300), vec![125, 250, 300]);
        assert_eq!(s.frames(300.0, 1e-3), 4.0);
        let s = Schedule::new(Fields::Every(7), 0.02);
        assert_eq!(frames_of(&s, 1e-3, 20), vec![7, 14, 20]);
        assert_eq!(s.frames(20.0, 1e-3), 4.0);
        let s = Schedule::new(Fields::Every(5), 0.02);
        assert_eq!(frames_of(&s, 1e-3, 20), vec![5, 10, 15, 20]);
        assert_eq!(s.frames(20.0, 1e-3), 5.0);
    }

    /// The count `stickslip check` says is the count a run writes: the
    /// steps as the integrator takes them (k·Δt, the last landing on
    /// t_end, shortened where t_end is off the grid), each put to
    /// [`Schedule::is_frame`].
    #[test]
    fn the_frames_said_are_the_frames_written() {
        for fields in [
            Fields::Interval(0.003),
            Fields::Interval(0.0025),
            Fields::Interval(0.007),
            Fields::Interval(1e-4),
            Fields::Frames(7),
            Fields::Frames(200),
            Fields::Every(3),
        ] {
            for dt in [1e-3, 2.5e-3, 3e-3] {
                for t_end in [0.1, 0.2, 0.1374, 0.099, 0.0021] {
                    let s = Schedule::new(fields, t_end);
                    let n = (t_end / dt - 1e-6).ceil() as u64;
                    let at = |k: u64| if k == n { t_end } else { k as f64 * dt };
                    let written = (1..=n)
                        .filter(|&k| s.is_frame(k, at(k - 1), at(k), k == n))
                        .count();
                    assert_eq!(
                        s.frames(n as f64, dt),
                        (written + 1) as f64,
                        "{fields:?}, dt = {dt}, t_end = {t_end}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_step_a_rounding_short_of_a_frame_time_reaches_it() {
        // 0.1 + 0.2 = 0.30000000000000004 and 3 · 0.1 = 0.30000000000000004,
        // but a clock may land at 0.29999999999999993: still frame 3 of 0.1.
        let s = Schedule::new(Fields::Interval(0.1), 1.0);
        assert!(s.is_frame(3, 0.19999999999999998, 0.29999999999999993, false));
        assert!(!s.is_frame(4, 0.29999999999999993, 0.39, false));
        assert!(s.is_frame(5, 0.39, 0.4000000000000001, false));
    }
}
