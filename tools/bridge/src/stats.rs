//! Measured delays: how far each crossing's time on the bridge was from the setting.

use serde::{Deserialize, Serialize};

use crate::side::Direction;

/// The delays measured one way, as errors against the setting.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayStats {
    /// `up` or `down`.
    pub direction: String,
    /// The delay set that way, seconds.
    pub setting_s: f64,
    /// Crossings measured.
    pub crossings: usize,
    /// The smallest measured delay minus the setting, milliseconds.
    pub min_error_ms: f64,
    /// The median of measured delay minus setting, milliseconds.
    pub median_error_ms: f64,
    /// The largest measured delay minus the setting, milliseconds.
    pub max_error_ms: f64,
    /// Crossings whose delay was off the setting by more than 10 ms.
    pub beyond_10ms: usize,
}

impl DelayStats {
    /// The statistics of `delays_s` (measured delays, seconds) against `setting_s`.
    pub fn of(direction: Direction, setting_s: f64, delays_s: &[f64]) -> Self {
        let mut errors: Vec<f64> = delays_s.iter().map(|d| (d - setting_s) * 1e3).collect();
        errors.sort_by(f64::total_cmp);
        let n = errors.len();
        let median = match n {
            0 => f64::NAN,
            _ if n % 2 == 1 => errors[n / 2],
            _ => (errors[n / 2 - 1] + errors[n / 2]) / 2.0,
        };
        DelayStats {
            direction: direction.label().to_owned(),
            setting_s,
            crossings: n,
            min_error_ms: errors.first().copied().unwrap_or(f64::NAN),
            median_error_ms: median,
            max_error_ms: errors.last().copied().unwrap_or(f64::NAN),
            beyond_10ms: errors.iter().filter(|e| e.abs() > 10.0).count(),
        }
    }

    /// Both ways (up, down) against `settings_s` (up, down): `delays_s` gives each way's
    /// measured delays, seconds.
    pub fn both_ways(
        settings_s: (f64, f64),
        mut delays_s: impl FnMut(Direction) -> Vec<f64>,
    ) -> Vec<Self> {
        Direction::BOTH
            .iter()
            .map(|&d| {
                let setting = match d {
                    Direction::Up => settings_s.0,
                    Direction::Down => settings_s.1,
                };
                DelayStats::of(d, setting, &delays_s(d))
            })
            .collect()
    }

    /// One line for people: `up (1.300 s): 20 crossings, error min +0.4 / median +1.1 / max +2.9 ms`.
    pub fn line(&self) -> String {
        if self.crossings == 0 {
            return format!(
                "{} ({:.3} s): nothing crossed",
                self.direction, self.setting_s
            );
        }
        format!(
            "{} ({:.3} s): {} crossings, delay minus setting min {:+.1} / median {:+.1} / max {:+.1} ms; {} beyond 10 ms",
            self.direction,
            self.setting_s,
            self.crossings,
            self.min_error_ms,
            self.median_error_ms,
            self.max_error_ms,
            self.beyond_10ms
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_measured_against_the_setting() {
        let s = DelayStats::of(Direction::Up, 1.3, &[1.3012, 1.3004, 1.315, 1.3020]);
        assert_eq!(s.crossings, 4);
        assert!((s.min_error_ms - 0.4).abs() < 1e-6, "{s:?}");
        assert!((s.median_error_ms - 1.6).abs() < 1e-6, "{s:?}");
        assert!((s.max_error_ms - 15.0).abs() < 1e-6, "{s:?}");
        assert_eq!(s.beyond_10ms, 1);
        assert!(s.line().contains("4 crossings"), "{}", s.line());
        let none = DelayStats::of(Direction::Down, 0.5, &[]);
        assert_eq!(none.crossings, 0);
        assert!(none.line().contains("nothing crossed"));
    }
}
