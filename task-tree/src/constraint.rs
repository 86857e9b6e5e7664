//! Temporal constraints between time points, and the shorthands that expand to them.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::id::NodeId;
use crate::point::{Endpoint, Point};

/// `before <= after`: the `after` point may not occur until the `before` point has.
///
/// Start points (`HandlingStart`, `AchievementStart`) act as gates on dispatch; end points
/// are delayed (see the crate documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Constraint {
    /// The point that must come first.
    pub before: Endpoint,
    /// The point that waits.
    pub after: Endpoint,
}

impl Constraint {
    /// The general point constraint `before <= after`.
    pub fn new(before: Endpoint, after: Endpoint) -> Self {
        Constraint { before, after }
    }

    /// Sequential achievement: `b` starts being achieved only once `a` is achieved,
    /// `end(achieve a) <= start(achieve b)`. `b` may still be planned meanwhile.
    pub fn sequential_achievement(a: NodeId, b: NodeId) -> Self {
        Constraint::new(a.achievement_end(), b.achievement_start())
    }

    /// Delay planning: `b` is not handled until `a` is achieved,
    /// `end(achieve a) <= start(handle b)`.
    pub fn delay_planning(a: NodeId, b: NodeId) -> Self {
        Constraint::new(a.achievement_end(), b.handling_start())
    }

    /// Invocation order: `b`'s handler starts no earlier than `a`'s,
    /// `start(handle a) <= start(handle b)`.
    pub fn invocation_order(a: NodeId, b: NodeId) -> Self {
        Constraint::new(a.handling_start(), b.handling_start())
    }
}

impl fmt::Display for Constraint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} <= {}", self.before, self.after)
    }
}

/// A constraint given with a new node, relative to that node (whose id is not known yet
/// when the spec is written).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum NewConstraint {
    /// `before <= point` of the new node.
    After {
        /// A point of an existing node.
        before: Endpoint,
        /// The new node's point that waits for it.
        point: Point,
    },
    /// `point` of the new node `<= after`.
    Before {
        /// The new node's point that must come first.
        point: Point,
        /// A point of an existing node that waits for it.
        after: Endpoint,
    },
    /// Plan first: every goal of the new node's subtree (itself included) finishes
    /// planning before any achievement in the subtree starts. See
    /// [`TaskTree::plan_first`](crate::TaskTree::plan_first).
    PlanFirst,
}

impl NewConstraint {
    /// The new node starts being achieved only once `prev` is achieved.
    pub fn sequential_achievement_after(prev: NodeId) -> Self {
        NewConstraint::After {
            before: prev.achievement_end(),
            point: Point::AchievementStart,
        }
    }

    /// The new node is not handled until `prev` is achieved.
    pub fn delay_planning_until(prev: NodeId) -> Self {
        NewConstraint::After {
            before: prev.achievement_end(),
            point: Point::HandlingStart,
        }
    }

    /// The new node's handler starts no earlier than `prev`'s.
    pub fn invocation_after(prev: NodeId) -> Self {
        NewConstraint::After {
            before: prev.handling_start(),
            point: Point::HandlingStart,
        }
    }

    /// The point constraint this stands for once the new node has the id `new`, or `None`
    /// for [`NewConstraint::PlanFirst`], which is not a single point constraint.
    pub fn resolve(self, new: NodeId) -> Option<Constraint> {
        match self {
            NewConstraint::After { before, point } => Some(Constraint::new(before, new.at(point))),
            NewConstraint::Before { point, after } => Some(Constraint::new(new.at(point), after)),
            NewConstraint::PlanFirst => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shorthands_expand_to_the_documented_points() {
        let (a, b) = (NodeId(1), NodeId(2));
        assert_eq!(
            Constraint::sequential_achievement(a, b).to_string(),
            "end(achieve n1) <= start(achieve n2)"
        );
        assert_eq!(
            Constraint::delay_planning(a, b).to_string(),
            "end(achieve n1) <= start(handle n2)"
        );
        assert_eq!(
            Constraint::invocation_order(a, b).to_string(),
            "start(handle n1) <= start(handle n2)"
        );
        assert_eq!(
            NewConstraint::delay_planning_until(a).resolve(b),
            Some(Constraint::delay_planning(a, b))
        );
        assert_eq!(NewConstraint::PlanFirst.resolve(b), None);
    }
}
