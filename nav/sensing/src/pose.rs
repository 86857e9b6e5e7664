//! A planar pose.

/// A pose in the world's XY plane: position (m) and heading (rad, from +X toward +Y).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose2 {
    /// East, m.
    pub x: f64,
    /// North, m.
    pub y: f64,
    /// Heading, rad.
    pub yaw: f64,
}

impl Pose2 {
    /// A pose.
    pub fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self { x, y, yaw }
    }

    /// The motion from `self` to `other` in `self`'s frame: forward, left, turn.
    pub fn delta_to(&self, other: &Pose2) -> (f64, f64, f64) {
        let (dx, dy) = (other.x - self.x, other.y - self.y);
        let (s, c) = self.yaw.sin_cos();
        (
            c * dx + s * dy,
            -s * dx + c * dy,
            wrap(other.yaw - self.yaw),
        )
    }

    /// This pose moved by `(forward, left, turn)` in its own frame.
    pub fn moved(&self, forward: f64, left: f64, turn: f64) -> Pose2 {
        let (s, c) = self.yaw.sin_cos();
        Pose2 {
            x: self.x + c * forward - s * left,
            y: self.y + s * forward + c * left,
            yaw: wrap(self.yaw + turn),
        }
    }

    /// Distance between the positions, m.
    pub fn distance(&self, other: &Pose2) -> f64 {
        (other.x - self.x).hypot(other.y - self.y)
    }
}

/// An angle wrapped to (-π, π].
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut a = a % t;
    if a > std::f64::consts::PI {
        a -= t;
    } else if a <= -std::f64::consts::PI {
        a += t;
    }
    a
}
