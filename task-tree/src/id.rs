//! Node identifiers and the time base.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::point::{Endpoint, Point};

/// A time, in nanoseconds since an arbitrary epoch chosen by the caller.
///
/// The tree never reads a clock: every mutating call carries the caller's `now`, and the
/// times must not decrease from one call to the next.
pub type Nanos = u64;

/// The identity of a task-tree node.
///
/// A tree assigns ids sequentially from `n1` and never reuses one, so an id below
/// [`TaskTree::next_id`](crate::TaskTree::next_id) that is no longer in the tree belongs to
/// a node that finished and was retired.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct NodeId(pub u64);

impl NodeId {
    /// The raw number of this id.
    pub fn get(self) -> u64 {
        self.0
    }

    /// One of this node's four time points.
    pub fn at(self, point: Point) -> Endpoint {
        Endpoint::new(self, point)
    }

    /// The moment this node's handler starts.
    pub fn handling_start(self) -> Endpoint {
        self.at(Point::HandlingStart)
    }

    /// The moment this node's handler is recorded as finished.
    pub fn handling_end(self) -> Endpoint {
        self.at(Point::HandlingEnd)
    }

    /// The moment this node's achievement starts.
    pub fn achievement_start(self) -> Endpoint {
        self.at(Point::AchievementStart)
    }

    /// The moment this node is achieved.
    pub fn achievement_end(self) -> Endpoint {
        self.at(Point::AchievementEnd)
    }
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "n{}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn displays_as_n_and_number() {
        assert_eq!(NodeId(42).to_string(), "n42");
    }

    #[test]
    fn serializes_as_a_bare_number() {
        assert_eq!(serde_json::to_string(&NodeId(7)).ok().as_deref(), Some("7"));
    }
}
