//! The crossings furthest from their delay setting: where a tail in the delay figures came
//! from, by message, way and moment in the session.

use serde::Serialize;

use crate::recorded::RecordedCrossing;
use crate::side::Direction;

/// One crossing's delay against its way's setting.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LateCrossing {
    /// The crossing's number in the bridge's log.
    pub id: u32,
    /// `up` or `down`.
    pub direction: String,
    /// Its class as the log has it (`inform`, `goal`, `success`, ...).
    pub class: String,
    /// The message name.
    pub name: String,
    /// When the bridge took it, seconds after it took the session's first crossing.
    pub at_s: f64,
    /// The delay measured minus the setting, milliseconds.
    pub error_ms: f64,
}

/// The `n` crossings with the largest delay minus setting, largest first (ties by crossing
/// number). `settings` are the delays (up, down) in seconds; `delay` measures one crossing in
/// seconds, or `None` where it cannot.
pub fn worst<'a>(
    crossings: impl IntoIterator<Item = &'a RecordedCrossing>,
    settings: (f64, f64),
    n: usize,
    delay: impl Fn(&RecordedCrossing) -> Option<f64>,
) -> Vec<LateCrossing> {
    let crossings: Vec<&RecordedCrossing> = crossings.into_iter().collect();
    let first_ns = crossings.iter().filter_map(|c| c.in_ns).min().unwrap_or(0);
    let mut late: Vec<LateCrossing> = crossings
        .iter()
        .filter_map(|c| {
            let setting = match c.direction {
                Direction::Up => settings.0,
                Direction::Down => settings.1,
            };
            Some(LateCrossing {
                id: c.id,
                direction: c.direction.to_string(),
                class: format!("{:?}", c.class).to_lowercase(),
                name: c.name.to_string(),
                at_s: c
                    .in_ns
                    .map_or(0.0, |t| t.saturating_sub(first_ns) as f64 / 1e9),
                error_ms: (delay(c)? - setting) * 1e3,
            })
        })
        .collect();
    late.sort_by(|a, b| b.error_ms.total_cmp(&a.error_ms).then(a.id.cmp(&b.id)));
    late.truncate(n);
    late
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_messages::{Class, MessageName, ModuleName};

    fn crossing(id: u32, direction: Direction, in_ms: u64, out_ms: u64) -> RecordedCrossing {
        RecordedCrossing {
            id,
            direction,
            class: Class::Inform,
            name: MessageName::new("telemetry").unwrap(),
            data: Vec::new(),
            sender: ModuleName::new("controller").unwrap(),
            refers_to: None,
            in_ns: Some(in_ms * 1_000_000),
            out_ns: Some(out_ms * 1_000_000),
            in_cause: None,
            out_cause: None,
        }
    }

    #[test]
    fn the_latest_come_first_each_against_its_own_way() {
        let cs = [
            // Up is set to 1.0 s, down to 0.5 s.
            crossing(1, Direction::Up, 1_000, 2_003), // +3 ms
            crossing(2, Direction::Down, 1_500, 2_009), // +9 ms
            crossing(3, Direction::Up, 2_000, 3_009), // +9 ms, a later number
            crossing(4, Direction::Down, 2_500, 3_000), // on time
        ];
        let got = worst(&cs, (1.0, 0.5), 3, RecordedCrossing::delay_s);
        let ids: Vec<u32> = got.iter().map(|l| l.id).collect();
        assert_eq!(ids, [2, 3, 1]);
        assert!((got[0].error_ms - 9.0).abs() < 1e-6, "{got:?}");
        assert_eq!(got[0].direction, "down");
        assert_eq!(got[0].class, "inform");
        assert_eq!(got[0].name, "telemetry");
        assert!(
            (got[0].at_s - 0.5).abs() < 1e-9,
            "seconds after the first: {got:?}"
        );
        assert!((got[2].error_ms - 3.0).abs() < 1e-6, "{got:?}");
        // A crossing that cannot be measured is left out; n bounds the list.
        assert!(worst(&cs, (1.0, 0.5), 10, |_| None).is_empty());
        assert_eq!(
            worst(&cs, (1.0, 0.5), 10, RecordedCrossing::delay_s).len(),
            4
        );
    }
}
