//! Modules built into the `tca` command, runnable as their own process with
//! `tca module NAME [--connect ENDPOINT] [options]`: the echo used by `tca ping`, and the six
//! modules of the walking system.

pub mod echo;

use std::path::PathBuf;

use tca_module::{Connector, Module, ModuleError};

use crate::walk::{ComputeModel, SystemSetup, TerrainChoice, WALKING_MODULES, connect_module};

/// Names of the built-in modules.
pub const BUILTIN_MODULES: &[&str] = &["echo", "controller", "ism", "ltm", "pdm", "lrp", "gait"];

/// What the walking modules run on.
#[derive(Clone, Debug)]
pub struct ModuleOptions {
    /// The terrain (the controller's and the scanner's world).
    pub terrain: TerrainChoice,
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Where pictures go (PDM output, planner step pictures).
    pub out: Option<PathBuf>,
    /// Write the planners' per-step pictures.
    pub pictures: bool,
    /// What the planners charge to simulated time.
    pub compute: ComputeModel,
    /// How fast the simulated Controller runs.
    pub speed: tca_controller_sim::SpeedFactor,
    /// Where the Controller and the LTM Manager keep what must survive their restart.
    pub state_dir: Option<PathBuf>,
}

impl Default for ModuleOptions {
    fn default() -> Self {
        ModuleOptions {
            terrain: TerrainChoice::Course(3),
            seed: 1,
            out: None,
            pictures: false,
            compute: ComputeModel::default(),
            speed: tca_controller_sim::SpeedFactor::AsFastAsPossible,
            state_dir: None,
        }
    }
}

/// Connects the built-in module `name`.
pub async fn connect(
    name: &str,
    connector: &Connector,
    options: &ModuleOptions,
) -> Result<Module, ModuleError> {
    if name == "echo" {
        return echo::connect(connector, "echo").await;
    }
    if !WALKING_MODULES.contains(&name) {
        return Err(ModuleError::Usage(format!(
            "no built-in module named {name:?}; built-in modules: {}",
            BUILTIN_MODULES.join(", ")
        )));
    }
    let mut setup = SystemSetup::new(options.terrain.clone(), options.seed)
        .map_err(|e| ModuleError::Usage(format!("{e:#}")))?;
    setup.out = options.out.clone();
    setup.step_pictures = options.pictures;
    setup.compute = options.compute;
    setup.speed = options.speed;
    setup.state_dir = options.state_dir.clone();
    if let Some(dir) = &setup.out {
        std::fs::create_dir_all(dir)
            .map_err(|e| ModuleError::Usage(format!("cannot create {}: {e}", dir.display())))?;
    }
    connect_module(name, connector, &setup).await
}
