//! What the Controller drives: the robot, its terrain, where it starts, and its name on the
//! bus.

use std::sync::Arc;

use tca_legged_model::RobotModel;
use tca_legged_sim::{SimParams, StartPose};
use tca_robot::HeightField;

/// The module name the Controller registers under unless told otherwise.
pub const DEFAULT_MODULE_NAME: &str = "controller";

/// The simulated Controller's configuration.
#[derive(Debug, Clone)]
pub struct LeggedControllerConfig {
    /// The robot.
    pub model: Arc<RobotModel>,
    /// Its URDF text, as `legged.robotModel` answers it.
    pub urdf: String,
    /// The true terrain.
    pub terrain: Arc<HeightField>,
    /// Where the robot stands at the start.
    pub start: StartPose,
    /// The simulator's parameters.
    pub params: SimParams,
    /// The module's name on the bus (default [`DEFAULT_MODULE_NAME`]).
    pub module_name: String,
    /// Hardware faults to inject (none by default).
    pub faults: Vec<InjectedFault>,
    /// Publish `legged.telemetry` this many times a second (wall clock), from the
    /// Controller's start; `None` (the default): no telemetry. Needs a central on wall-clock
    /// time.
    pub telemetry_hz: Option<f64>,
    /// Carry out moves in wall-clock time, this many times faster than the robot would (1:
    /// as fast as the robot): a move's handler takes its duration divided by this, its
    /// informs go out when their events happen, telemetry shows the move part-way, and the
    /// module stamps its messages with the wall clock, like a real robot's Controller.
    /// `None` (the default): moves end at once in wall-clock time and take their duration
    /// in simulated time. Needs a central on wall-clock time.
    pub speed: Option<f64>,
}

/// Most telemetry samples a second.
pub const MAX_TELEMETRY_HZ: f64 = 1000.0;

impl LeggedControllerConfig {
    /// A configuration with the simulator's defaults for the robot
    /// ([`SimParams::for_model`]) and the default module name.
    pub fn new(
        model: Arc<RobotModel>,
        urdf: impl Into<String>,
        terrain: Arc<HeightField>,
        start: StartPose,
    ) -> Self {
        let params = SimParams::for_model(&model);
        Self {
            model,
            urdf: urdf.into(),
            terrain,
            start,
            params,
            module_name: DEFAULT_MODULE_NAME.to_owned(),
            faults: Vec::new(),
            telemetry_hz: None,
            speed: None,
        }
    }

    /// Refuses a telemetry rate or a speed that is not a positive number (a rate above
    /// [`MAX_TELEMETRY_HZ`] too), saying what to give.
    pub fn check_wall_clock(&self) -> Result<(), String> {
        if let Some(hz) = self.telemetry_hz
            && !(hz.is_finite() && hz > 0.0 && hz <= MAX_TELEMETRY_HZ)
        {
            return Err(format!(
                "a telemetry rate of {hz} Hz is not valid: give a rate above 0 and at most \
                 {MAX_TELEMETRY_HZ} samples a second"
            ));
        }
        if let Some(speed) = self.speed
            && !(speed.is_finite() && speed > 0.0)
        {
            return Err(format!(
                "a speed of {speed} is not valid: give a positive factor (1: moves take as long \
                 as on the robot)"
            ));
        }
        Ok(())
    }
}

/// A hardware fault the simulated Controller injects: from `at_s` on the simulator's
/// motion clock (simulated seconds of moves carried out, the `t_s` of its
/// `legged.supportState`) the drives of leg `leg` stop responding. Every command that would move that leg's joints
/// (a `legged.legMove` of it, a `legged.bodyMove` while it stands) is then refused without
/// moving anything and raises `legged.hardwareFault` naming the leg.
#[derive(Debug, Clone, PartialEq)]
pub struct InjectedFault {
    /// The leg, by its name in the robot description.
    pub leg: String,
    /// When the fault starts, seconds on the simulator's motion clock.
    pub at_s: f64,
}

impl InjectedFault {
    /// Whether the fault is active at simulated time `clock_s`.
    pub fn active_at(&self, clock_s: f64) -> bool {
        clock_s >= self.at_s
    }

    /// Refuses a fault on a leg the robot does not have, naming the legs it has.
    pub fn check(&self, model: &RobotModel) -> Result<(), String> {
        if model.leg_index(&self.leg).is_some() {
            return Ok(());
        }
        let legs: Vec<&str> = model.legs().iter().map(|l| l.name()).collect();
        Err(format!(
            "cannot inject a fault on leg {:?}: the robot {} has no such leg; its legs are {}",
            self.leg,
            model.name(),
            legs.join(", ")
        ))
    }
}

impl std::str::FromStr for InjectedFault {
    type Err = String;

    /// `LEG@SECONDS`, e.g. `left_middle@30`: leg `left_middle` fails at 30 s of simulated time.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let usage = "write a fault as LEG@SECONDS, e.g. left_middle@30 (the leg's name, then the simulated time it fails at)";
        let Some((leg, at)) = text.rsplit_once('@') else {
            return Err(format!("the fault {text:?} has no '@': {usage}"));
        };
        let leg = leg.trim();
        if leg.is_empty() {
            return Err(format!("the fault {text:?} names no leg: {usage}"));
        }
        let at_s: f64 = at
            .trim()
            .parse()
            .map_err(|_| format!("the fault {text:?} has no time after '@': {usage}"))?;
        if !(at_s >= 0.0 && at_s.is_finite()) {
            return Err(format!(
                "the fault {text:?} starts at {at_s} s: give a time of zero or more seconds"
            ));
        }
        Ok(InjectedFault {
            leg: leg.to_owned(),
            at_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_are_read_as_leg_at_seconds() {
        let f: InjectedFault = "left_2@30.5".parse().unwrap();
        assert_eq!(f.leg, "left_2");
        assert_eq!(f.at_s, 30.5);
        assert!(!f.active_at(30.0));
        assert!(f.active_at(30.5));
        for bad in [
            "left_2",
            "@3",
            "left_2@",
            "left_2@soon",
            "left_2@-1",
            "left_2@inf",
        ] {
            let e = bad.parse::<InjectedFault>().unwrap_err();
            assert!(
                e.contains("LEG@SECONDS") || e.contains("zero or more"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn a_fault_on_an_unknown_leg_is_refused_with_the_legs() {
        let model = RobotModel::builtin("hexapod").unwrap();
        let f: InjectedFault = "wing@1".parse().unwrap();
        let e = f.check(&model).unwrap_err();
        assert!(
            e.contains("no such leg") && e.contains(model.legs()[0].name()),
            "{e}"
        );
        let ok = InjectedFault {
            leg: model.legs()[0].name().to_owned(),
            at_s: 1.0,
        };
        assert!(ok.check(&model).is_ok());
    }
}
