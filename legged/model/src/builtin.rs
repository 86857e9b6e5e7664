//! The robots shipped with the crate, embedded from `robots/*.urdf`.

/// A robot description shipped with the crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuiltinRobot {
    /// The name [`RobotModel::builtin`](crate::RobotModel::builtin) knows it by.
    pub name: &'static str,
    /// One line saying what it is.
    pub summary: &'static str,
    /// The URDF text.
    pub urdf: &'static str,
}

/// The shipped robots: `ambler`, `hexapod`, `athlete`, `spider`, `polybot6` and `polybot8`.
pub const BUILTIN_ROBOTS: &[BuiltinRobot] = &[
    BuiltinRobot {
        name: "ambler",
        summary: "six legs of the single-leg testbed's kind (two rotary joints about vertical \
                  axes and a vertical prismatic one) in two stacks on a 3.5 m wide body, 2,500 kg",
        urdf: include_str!("../robots/ambler.urdf"),
    },
    BuiltinRobot {
        name: "hexapod",
        summary: "a small insect-like walker: a 0.30 m body, six coxa-femur-tibia legs, 2.5 kg",
        urdf: include_str!("../robots/hexapod.urdf"),
    },
    BuiltinRobot {
        name: "athlete",
        summary: "after NASA's ATHLETE: a hexagonal body 3 m across, six limbs of six revolute \
                  joints with a wheel at each end, 850 kg",
        urdf: include_str!("../robots/athlete.urdf"),
    },
    BuiltinRobot {
        name: "spider",
        summary: "eight coxa-femur-tibia legs spread evenly round a disc 0.7 m across, \
                  much shorter reach than the Ambler's, 68 kg",
        urdf: include_str!("../robots/spider.urdf"),
    },
    BuiltinRobot {
        name: "polybot6",
        summary: "a six-legged configuration of 6 cm one-joint modules after PolyBot: a \
                  0.42 m spine, three-module legs, 7.7 kg",
        urdf: include_str!("../robots/polybot6.urdf"),
    },
    BuiltinRobot {
        name: "polybot8",
        summary: "an eight-legged configuration of 6 cm one-joint modules after PolyBot: a \
                  0.56 m spine, three-module legs, 10.2 kg",
        urdf: include_str!("../robots/polybot8.urdf"),
    },
];

/// The shipped robot with this name.
pub(crate) fn find(name: &str) -> Option<&'static BuiltinRobot> {
    BUILTIN_ROBOTS.iter().find(|r| r.name == name)
}

/// The shipped robots' names, comma-separated, for messages.
pub(crate) fn names() -> String {
    BUILTIN_ROBOTS
        .iter()
        .map(|r| r.name)
        .collect::<Vec<_>>()
        .join(", ")
}
