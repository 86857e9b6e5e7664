//! How a module charges its computing to simulated time: what it measured, or a model (of
//! another machine, say, so that a simulated run's timing compares with a real system's). A
//! model makes a module's simulated stamps independent of the machine it runs on, so that the
//! same run gives the same log twice.

use std::time::Duration;

/// The simulated duration a handler charges for its computing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ComputeTime {
    /// The wall-clock time the computation took on this machine.
    #[default]
    Measured,
    /// A fixed duration per handled message, whatever the computation took.
    Modeled(Duration),
    /// A duration that grows with the work done: `base` plus `per_unit` for each unit (a map
    /// cell computed, an image cell merged), whatever the computation took.
    PerUnit {
        /// Charged for any computation.
        base: Duration,
        /// Charged for each unit of work.
        per_unit: Duration,
    },
}

impl ComputeTime {
    /// The duration to charge for a computation that took `measured`.
    pub fn charged(&self, measured: Duration) -> Duration {
        self.charged_for(measured, 0)
    }

    /// The duration to charge for a computation of `units` units of work that took
    /// `measured`.
    pub fn charged_for(&self, measured: Duration, units: u64) -> Duration {
        match self {
            ComputeTime::Measured => measured,
            ComputeTime::Modeled(d) => *d,
            ComputeTime::PerUnit { base, per_unit } => {
                let n = u32::try_from(units).unwrap_or(u32::MAX);
                base.saturating_add(per_unit.saturating_mul(n))
            }
        }
    }

    /// Whether the charge depends on this machine's speed.
    pub fn is_measured(&self) -> bool {
        matches!(self, ComputeTime::Measured)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_passes_through_and_models_replace_it() {
        let ms = Duration::from_millis(3);
        assert_eq!(ComputeTime::Measured.charged(ms), ms);
        let s = Duration::from_secs(12);
        assert_eq!(ComputeTime::Modeled(s).charged(ms), s);
        let per = ComputeTime::PerUnit {
            base: Duration::from_millis(500),
            per_unit: Duration::from_micros(10),
        };
        assert_eq!(per.charged_for(ms, 1000), Duration::from_millis(510));
        assert_eq!(per.charged(ms), Duration::from_millis(500));
        assert!(!per.is_measured() && ComputeTime::Measured.is_measured());
    }
}
