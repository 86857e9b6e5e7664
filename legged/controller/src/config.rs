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
}

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
        }
    }
}
