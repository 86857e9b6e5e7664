//! The navigation modules of one run, connected with the settings they share.

use std::sync::Arc;

use nalgebra::Point2;
use tca_legged_model::RobotModel;
use tca_module::{Connector, Module, ModuleError};
use tca_nav_hexapod::{Stepper, StepperParams, nav_sim_params};
use tca_nav_navigator::{NavParams, Pose2, WheeledParams};
use tca_robot::HeightField;

use crate::controller::ControllerConfig;
use crate::ism::{IsmConfig, PoseSource};
use crate::ltm::LtmConfig;
use crate::navigator::NavigatorConfig;
use crate::walking::WalkingConfig;

/// Names of the navigation modules of a wheeled base, in the order they are connected.
pub const NAV_MODULES: &[&str] = &["controller", "ism", "ltm", "navigator"];

/// Names of the navigation modules of a walking robot, in the order they are connected:
/// the legged Controller (the simulator) first, then the walking base's body-level
/// Controller and the rest.
pub const LEGGED_NAV_MODULES: &[&str] =
    &["legged-controller", "controller", "ism", "ltm", "navigator"];

/// The base a navigation drives.
#[derive(Debug, Clone)]
pub enum NavBase {
    /// The differential-drive wheeled base.
    Wheeled(WheeledParams),
    /// A walking robot: the legged simulator behind its Controller, and the walking
    /// base's Controller turning speeds into its moves.
    Legged(LeggedBase),
}

/// A walking robot as a navigation base.
#[derive(Debug, Clone)]
pub struct LeggedBase {
    /// The robot.
    pub model: Arc<RobotModel>,
    /// Its URDF text (the legged Controller answers `legged.robotModel` with it).
    pub urdf: String,
    /// How it walks.
    pub stepper: StepperParams,
}

impl NavBase {
    /// The modules of a run with this base, in the order they are connected.
    pub fn modules(&self) -> &'static [&'static str] {
        match self {
            NavBase::Wheeled(_) => NAV_MODULES,
            NavBase::Legged(_) => LEGGED_NAV_MODULES,
        }
    }

    /// The name reports give the base: `wheeled`, or the walking robot's name.
    pub fn name(&self) -> String {
        match self {
            NavBase::Wheeled(_) => "wheeled".into(),
            NavBase::Legged(l) => l.model.name().to_string(),
        }
    }
}

/// What the modules of one run share.
#[derive(Debug, Clone)]
pub struct NavSetup {
    /// The true terrain (the simulator's and the camera's scene; its grid is the map's).
    pub terrain: Arc<HeightField>,
    /// The base.
    pub base: NavBase,
    /// The navigation parameters.
    pub params: NavParams,
    /// Where the base starts.
    pub start: Pose2,
    /// Odometry drift, fraction of the distance travelled.
    pub drift: f64,
    /// Seed of the camera's and the odometry's noise.
    pub seed: u64,
}

/// Connects one navigation module.
pub async fn connect_module(
    name: &str,
    connector: &Connector,
    setup: &NavSetup,
) -> Result<Module, ModuleError> {
    let unknown = || {
        Err(ModuleError::Usage(format!(
            "no navigation module named {name:?} for this base; they are {}",
            setup.base.modules().join(", ")
        )))
    };
    match (name, &setup.base) {
        ("controller", NavBase::Wheeled(wheeled)) => {
            crate::controller::connect(
                connector,
                ControllerConfig {
                    module_name: name.into(),
                    terrain: setup.terrain.clone(),
                    start: setup.start,
                    wheeled: *wheeled,
                    max_duration_s: MAX_DRIVE_S,
                },
            )
            .await
        }
        ("controller", NavBase::Legged(legged)) => {
            crate::walking::connect(
                connector,
                WalkingConfig {
                    module_name: name.into(),
                    stepper: Arc::new(Stepper::new(
                        legged.model.clone(),
                        setup.terrain.clone(),
                        legged.stepper.clone(),
                    )),
                    max_duration_s: MAX_DRIVE_S,
                },
            )
            .await
        }
        ("legged-controller", NavBase::Legged(legged)) => {
            let mut config = tca_legged_controller::LeggedControllerConfig::new(
                legged.model.clone(),
                legged.urdf.clone(),
                setup.terrain.clone(),
                tca_legged_sim::StartPose {
                    x_m: setup.start.x,
                    y_m: setup.start.y,
                    yaw_rad: setup.start.yaw,
                },
            );
            config.params = nav_sim_params(&legged.model);
            config.module_name = name.into();
            tca_legged_controller::connect(connector, config).await
        }
        ("legged-controller", NavBase::Wheeled(_)) => unknown(),
        ("ism", _) => {
            crate::ism::connect(
                connector,
                IsmConfig {
                    module_name: name.into(),
                    terrain: setup.terrain.clone(),
                    camera: setup.params.camera.clone(),
                    mount: setup.params.mount,
                    start: setup.start,
                    drift: setup.drift,
                    seed: setup.seed,
                    pose_source: match setup.base {
                        NavBase::Wheeled(_) => PoseSource::Planar,
                        NavBase::Legged(_) => PoseSource::LeggedBody,
                    },
                },
            )
            .await
        }
        ("ltm", _) => {
            let g = setup.terrain.grid();
            crate::ltm::connect(
                connector,
                LtmConfig {
                    module_name: name.into(),
                    params: setup.params.clone(),
                    origin: Point2::new(g.origin().x, g.origin().y),
                    resolution_m: g.resolution_m(),
                    nx: g.nx(),
                    ny: g.ny(),
                },
            )
            .await
        }
        ("navigator", _) => {
            crate::navigator::connect(
                connector,
                NavigatorConfig {
                    module_name: name.into(),
                    params: setup.params.clone(),
                },
            )
            .await
        }
        _ => unknown(),
    }
}

/// Longest drive a base's Controller accepts, s.
const MAX_DRIVE_S: f64 = 10.0;

/// Connects all the navigation modules of the setup's base, in [`NavBase::modules`]'
/// order.
pub async fn connect_all(
    connector: &Connector,
    setup: &NavSetup,
) -> Result<Vec<Module>, ModuleError> {
    let mut modules = Vec::new();
    for name in setup.base.modules() {
        modules.push(connect_module(name, connector, setup).await?);
    }
    Ok(modules)
}
