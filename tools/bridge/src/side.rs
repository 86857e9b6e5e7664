//! The two sides a bridge joins and the two ways traffic crosses.

use std::fmt;

/// One of the two centrals a bridge joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Side {
    /// The robot's central: its Controller and sensors.
    Robot,
    /// The operators' central: their tools and planners.
    Ground,
}

impl Side {
    /// Both sides.
    pub const BOTH: [Side; 2] = [Side::Robot, Side::Ground];

    /// `robot` or `ground`: how the bridge's log names the side.
    pub fn label(self) -> &'static str {
        match self {
            Side::Robot => "robot",
            Side::Ground => "ground",
        }
    }

    /// The link number the bridge's log gives the side's central (1 robot, 2 ground).
    pub fn link(self) -> u32 {
        match self {
            Side::Robot => 1,
            Side::Ground => 2,
        }
    }

    /// The side of a link number of the bridge's log.
    pub fn from_link(link: u32) -> Option<Side> {
        match link {
            1 => Some(Side::Robot),
            2 => Some(Side::Ground),
            _ => None,
        }
    }

    /// The side of a label (`robot`, `ground`).
    pub fn from_label(label: &str) -> Option<Side> {
        match label {
            "robot" => Some(Side::Robot),
            "ground" => Some(Side::Ground),
            _ => None,
        }
    }

    /// The other side.
    pub fn other(self) -> Side {
        match self {
            Side::Robot => Side::Ground,
            Side::Ground => Side::Robot,
        }
    }

    /// Index 0 (robot) or 1 (ground), for per-side arrays.
    pub(crate) fn index(self) -> usize {
        match self {
            Side::Robot => 0,
            Side::Ground => 1,
        }
    }
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// Which way traffic crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    /// Ground to robot: commands, goals, queries the operators send.
    Up,
    /// Robot to ground: telemetry, and the answers and outcomes of what went up.
    Down,
}

impl Direction {
    /// Both directions.
    pub const BOTH: [Direction; 2] = [Direction::Up, Direction::Down];

    /// The side traffic this way leaves.
    pub fn from(self) -> Side {
        match self {
            Direction::Up => Side::Ground,
            Direction::Down => Side::Robot,
        }
    }

    /// The side traffic this way reaches.
    pub fn to(self) -> Side {
        self.from().other()
    }

    /// The direction of traffic leaving `side`.
    pub fn leaving(side: Side) -> Direction {
        match side {
            Side::Ground => Direction::Up,
            Side::Robot => Direction::Down,
        }
    }

    /// The other direction (the way answers go back).
    pub fn reverse(self) -> Direction {
        match self {
            Direction::Up => Direction::Down,
            Direction::Down => Direction::Up,
        }
    }

    /// `up` or `down`.
    pub fn label(self) -> &'static str {
        match self {
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }

    /// Index 0 (up) or 1 (down), for per-direction arrays.
    pub(crate) fn index(self) -> usize {
        match self {
            Direction::Up => 0,
            Direction::Down => 1,
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_join_the_sides_both_ways() {
        for d in Direction::BOTH {
            assert_eq!(d.to(), d.from().other());
            assert_eq!(Direction::leaving(d.from()), d);
            assert_eq!(d.reverse().from(), d.to());
        }
        assert_eq!(Direction::Up.from(), Side::Ground);
        assert_eq!(Direction::Down.from(), Side::Robot);
        for s in Side::BOTH {
            assert_eq!(Side::from_link(s.link()), Some(s));
            assert_eq!(Side::from_label(s.label()), Some(s));
        }
        assert_eq!(Side::from_link(0), None);
    }
}
