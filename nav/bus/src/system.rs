//! The navigation modules of one run, connected with the settings they share.

use std::sync::Arc;

use nalgebra::Point2;
use tca_module::{Connector, Module, ModuleError};
use tca_nav_navigator::{NavParams, Pose2, WheeledParams};
use tca_robot::HeightField;

use crate::controller::ControllerConfig;
use crate::ism::IsmConfig;
use crate::ltm::LtmConfig;
use crate::navigator::NavigatorConfig;

/// Names of the navigation modules, in the order they are connected.
pub const NAV_MODULES: &[&str] = &["controller", "ism", "ltm", "navigator"];

/// What the modules of one run share.
#[derive(Debug, Clone)]
pub struct NavSetup {
    /// The true terrain (the simulator's and the camera's scene; its grid is the map's).
    pub terrain: Arc<HeightField>,
    /// The base.
    pub wheeled: WheeledParams,
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
    match name {
        "controller" => {
            crate::controller::connect(
                connector,
                ControllerConfig {
                    module_name: name.into(),
                    terrain: setup.terrain.clone(),
                    start: setup.start,
                    wheeled: setup.wheeled,
                    max_duration_s: 10.0,
                },
            )
            .await
        }
        "ism" => {
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
                },
            )
            .await
        }
        "ltm" => {
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
        "navigator" => {
            crate::navigator::connect(
                connector,
                NavigatorConfig {
                    module_name: name.into(),
                    params: setup.params.clone(),
                },
            )
            .await
        }
        other => Err(ModuleError::Usage(format!(
            "no navigation module named {other:?}; they are {}",
            NAV_MODULES.join(", ")
        ))),
    }
}

/// Connects all the navigation modules, in [`NAV_MODULES`]'s order.
pub async fn connect_all(
    connector: &Connector,
    setup: &NavSetup,
) -> Result<Vec<Module>, ModuleError> {
    let mut modules = Vec::new();
    for name in NAV_MODULES {
        modules.push(connect_module(name, connector, setup).await?);
    }
    Ok(modules)
}
