//! The time left to a run, for its progress line (`eta 1m12s`).
//!
//! A run's pace changes: the explicit step is re-estimated as the part
//! deforms, contact and mass scaling change what a step costs, and the
//! implicit increment grows and shrinks with Newton's convergence. So the
//! estimate is the simulated time still to go over the *recent* rate of
//! simulated seconds per wall-clock second (steps per second times the
//! step), smoothed exponentially over about [`SMOOTHING_S`] of wall time,
//! not the run's average since its start, which lags behind every change.
//! Not for timing runs: it is a guide for the person waiting.

/// The time constant of the smoothing (wall-clock seconds): long enough to
/// steady the 100 ms progress updates, short enough to follow a run whose
/// pace changes over a minute.
pub const SMOOTHING_S: f64 = 10.0;

/// Wall time a rate is measured over before it counts (seconds): shorter
/// samples are mostly timer and scheduling noise.
const MIN_SAMPLE_S: f64 = 0.5;

/// The smoothed pace of a run.
#[derive(Debug, Clone, Default)]
pub struct Eta {
    /// Wall and simulated time at the start of the current sample.
    mark: Option<(f64, f64)>,
    /// Simulated seconds per wall second, smoothed.
    rate: Option<f64>,
}

impl Eta {
    /// No observation yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes note that simulated `time` was reached at `wall` seconds
    /// (from any fixed origin) and returns the wall seconds left to reach
    /// `end_time` at the recent rate; None until a rate is known (the
    /// first half second) or while the run does not advance.
    pub fn update(&mut self, wall: f64, time: f64, end_time: f64) -> Option<f64> {
        let Some((wall0, time0)) = self.mark else {
            self.mark = Some((wall, time));
            return None;
        };
        let elapsed = wall - wall0;
        if elapsed >= MIN_SAMPLE_S {
            let sample = (time - time0) / elapsed;
            if sample.is_finite() && sample >= 0.0 {
                let weight = 1.0 - (-elapsed / SMOOTHING_S).exp();
                self.rate = Some(match self.rate {
                    Some(r) => r + weight * (sample - r),
                    None => sample,
                });
            }
            self.mark = Some((wall, time));
        }
        let rate = self.rate.filter(|r| *r > 0.0)?;
        Some(((end_time - time).max(0.0) / rate).max(0.0))
    }
}

/// `seconds` as a progress line shows it: `45s`, `1m12s`, `2h05m`.
pub fn duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "?".to_owned();
    }
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_a_clock() {
        assert_eq!(duration(0.4), "0s");
        assert_eq!(duration(45.0), "45s");
        assert_eq!(duration(72.0), "1m12s");
        assert_eq!(duration(3599.4), "59m59s");
        assert_eq!(duration(7500.0), "2h05m");
        assert_eq!(duration(f64::INFINITY), "?");
    }

    /// A steady run: 0.01 simulated s per wall s, 1 s simulated. After
    /// 30 s of wall time 0.3 s are done, 70 s remain, exactly.
    #[test]
    fn a_steady_run_gets_the_exact_time_left() {
        let mut eta = Eta::new();
        let mut left = None;
        for k in 0..=300 {
            let wall = 0.1 * f64::from(k);
            left = eta.update(wall, 0.01 * wall, 1.0);
            if k < 5 {
                assert_eq!(left, None, "no rate before half a second");
            }
        }
        let left = left.unwrap();
        assert!((left - 70.0).abs() < 1e-9, "{left}");
    }

    /// A run that slows down four times (contact sets in) at wall 20 s:
    /// the estimate follows the new pace within a few smoothing times,
    /// where the average since the start would still be far off.
    #[test]
    fn the_estimate_follows_a_change_of_pace() {
        let mut eta = Eta::new();
        let (mut time, mut left) = (0.0, None);
        for k in 1..=1000 {
            let wall = 0.1 * f64::from(k);
            time += if wall <= 20.0 { 1e-3 } else { 0.25e-3 };
            left = eta.update(wall, time, 10.0);
        }
        // At wall 100 s: 0.2 + 0.2 = 0.4 s done at 2.5e-3 s/s now.
        let exact = (10.0 - time) / 2.5e-3;
        let left = left.unwrap();
        // 8 smoothing times after the change: e⁻⁸ of the old pace left.
        assert!((left / exact - 1.0).abs() < 2e-3, "{left} vs {exact}");
        let average = (10.0 - time) / (time / 100.0);
        // The average since the start (0.004 s/s) says 2400 s, 37 % short.
        assert!((average / exact - 1.0).abs() > 0.3, "{average} vs {exact}");
    }

    #[test]
    fn a_stalled_run_has_no_estimate() {
        let mut eta = Eta::new();
        for k in 0..20 {
            assert_eq!(eta.update(0.1 * f64::from(k), 0.0, 1.0), None);
        }
    }
}
