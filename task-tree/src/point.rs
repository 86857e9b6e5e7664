//! The four time points of a node and their names.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::id::NodeId;

/// One of the four time points of a node: the two ends of its handling interval and the
/// two ends of its achievement interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Point {
    /// The node's handler is started (the message is dispatched).
    HandlingStart,
    /// The node's handler is recorded as finished.
    HandlingEnd,
    /// The node's achievement starts (for a command: when its handler starts).
    AchievementStart,
    /// The node is achieved: handler finished, every descendant achieved or killed.
    AchievementEnd,
}

impl Point {
    /// The four points, in index order.
    pub const ALL: [Point; 4] = [
        Point::HandlingStart,
        Point::HandlingEnd,
        Point::AchievementStart,
        Point::AchievementEnd,
    ];

    /// Position of this point in per-node arrays.
    pub(crate) fn index(self) -> usize {
        match self {
            Point::HandlingStart => 0,
            Point::HandlingEnd => 1,
            Point::AchievementStart => 2,
            Point::AchievementEnd => 3,
        }
    }

    /// True for the two start points, which gate dispatch; end points are delayed instead.
    pub fn is_start(self) -> bool {
        matches!(self, Point::HandlingStart | Point::AchievementStart)
    }
}

/// A time point of a given node, e.g. `end(achieve n3)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Endpoint {
    /// The node.
    pub node: NodeId,
    /// Which of its points.
    pub point: Point,
}

impl Endpoint {
    /// The `point` of `node`.
    pub fn new(node: NodeId, point: Point) -> Self {
        Endpoint { node, point }
    }

    /// A compact key for hash maps: the id shifted left by two, or'ed with the point.
    pub(crate) fn key(self) -> u64 {
        (self.node.0 << 2) | self.point.index() as u64
    }

    /// The inverse of [`Endpoint::key`].
    pub(crate) fn from_key(key: u64) -> Self {
        let point = match key & 3 {
            0 => Point::HandlingStart,
            1 => Point::HandlingEnd,
            2 => Point::AchievementStart,
            _ => Point::AchievementEnd,
        };
        Endpoint::new(NodeId(key >> 2), point)
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (end, interval) = match self.point {
            Point::HandlingStart => ("start", "handle"),
            Point::HandlingEnd => ("end", "handle"),
            Point::AchievementStart => ("start", "achieve"),
            Point::AchievementEnd => ("end", "achieve"),
        };
        write!(f, "{end}({interval} {})", self.node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn displays_in_readable_form() {
        assert_eq!(NodeId(3).achievement_end().to_string(), "end(achieve n3)");
        assert_eq!(NodeId(2).handling_start().to_string(), "start(handle n2)");
    }

    #[test]
    fn key_round_trips() {
        for p in Point::ALL {
            let e = Endpoint::new(NodeId(123_456), p);
            assert_eq!(Endpoint::from_key(e.key()), e);
        }
    }
}
