//! How a module charges its computing to simulated time: what it measured, or a modeled
//! duration (for instance the 1990 system's, so that a simulated walk's timing resembles
//! the report's Figure 18 and concurrent planning pays off as it did there).

use std::time::Duration;

/// The simulated duration a handler charges for its computing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ComputeTime {
    /// The wall-clock time the computation took on this machine.
    #[default]
    Measured,
    /// A fixed duration per handled message, whatever the computation took.
    Modeled(Duration),
}

impl ComputeTime {
    /// The duration to charge for a computation that took `measured`.
    pub fn charged(&self, measured: Duration) -> Duration {
        match self {
            ComputeTime::Measured => measured,
            ComputeTime::Modeled(d) => *d,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_passes_through_and_modeled_replaces() {
        let ms = Duration::from_millis(3);
        assert_eq!(ComputeTime::Measured.charged(ms), ms);
        let s = Duration::from_secs(12);
        assert_eq!(ComputeTime::Modeled(s).charged(ms), s);
    }
}
