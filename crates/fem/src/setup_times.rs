//! Wall-clock times of a run's setup by part (mesh read, assembly,
//! ordering, the preload's factor, the critical step, ...), for the run
//! summary and the bench: the parts say where a setup's seconds go.

use std::time::Instant;

/// Named durations in seconds, in the order first taken; a part taken
/// twice (two factorizations) adds up under its name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SetupTimes {
    parts: Vec<(&'static str, f64)>,
}

impl SetupTimes {
    /// Runs `f`, adding its wall time to part `name`.
    pub fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let started = Instant::now();
        let out = f();
        self.add(name, started.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to part `name`.
    pub fn add(&mut self, name: &'static str, seconds: f64) {
        match self.parts.iter_mut().find(|(n, _)| *n == name) {
            Some((_, s)) => *s += seconds,
            None => self.parts.push((name, seconds)),
        }
    }

    /// Each of `other`'s parts added to this one's.
    pub fn extend(&mut self, other: &SetupTimes) {
        for &(name, seconds) in &other.parts {
            self.add(name, seconds);
        }
    }

    /// The parts taken so far, in order.
    pub fn parts(&self) -> &[(&'static str, f64)] {
        &self.parts
    }

    /// Their sum.
    pub fn total(&self) -> f64 {
        self.parts.iter().map(|(_, s)| s).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_taken_twice_adds_up_in_its_first_place() {
        let mut t = SetupTimes::default();
        t.add("assembly", 1.5);
        t.add("factor", 0.25);
        t.add("assembly", 0.5);
        assert_eq!(t.parts(), &[("assembly", 2.0), ("factor", 0.25)]);
        assert_eq!(t.total(), 2.25);
    }
}
