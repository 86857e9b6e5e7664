//! The two ways the Controller can propel the carriage (§4.2, §4.3).

use std::fmt;
use std::str::FromStr;

/// How `bodyMove` drives the shoulder and elbow while the foot is planted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum BodyMoveLaw {
    /// Servo on the carriage position: each control cycle the carriage speed is a clipped
    /// linear function of the error the position transducer reads, turned into joint rates
    /// through the inverse Jacobian, with the foot's position across the rails held. What the
    /// report settled on; within a few centimetres of the target.
    #[default]
    Servo,
    /// The report's first procedure: compute from the rigid kinematics the joint angles that
    /// put the carriage at the target and drive the joints there along a straight line in
    /// joint space, not looking at the carriage. Compliance and friction leave the carriage
    /// short, by tens of centimetres over a metre.
    OpenLoop,
}

impl BodyMoveLaw {
    /// The name used on the command line and in reports: `servo` or `open-loop`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Servo => "servo",
            Self::OpenLoop => "open-loop",
        }
    }
}

impl fmt::Display for BodyMoveLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A body-move law name that is neither `servo` nor `open-loop`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown body-move law {0:?}: use servo (the default) or open-loop")]
pub struct UnknownBodyMoveLaw(pub String);

impl FromStr for BodyMoveLaw {
    type Err = UnknownBodyMoveLaw;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "servo" => Ok(Self::Servo),
            "open-loop" | "open_loop" => Ok(Self::OpenLoop),
            other => Err(UnknownBodyMoveLaw(other.to_string())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_a_bad_name_says_what_to_use() {
        for law in [BodyMoveLaw::Servo, BodyMoveLaw::OpenLoop] {
            assert_eq!(law.name().parse::<BodyMoveLaw>(), Ok(law));
        }
        let err = "closed".parse::<BodyMoveLaw>().unwrap_err().to_string();
        assert!(err.contains("closed") && err.contains("open-loop"), "{err}");
    }
}
