//! One walking module on its own, as a process of its own runs it (`tca module NAME
//! [--connect ENDPOINT] [options]`): the settings it runs with, and connecting it.

use std::path::PathBuf;

use tca_module::{Connector, Module, ModuleError};

use crate::system::{ComputeModel, SystemSetup, WALKING_MODULES, connect_module};
use crate::terrain::TerrainChoice;

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
    /// A rigid leg (no deflection, nothing compensated) instead of the report's compliant
    /// one; give every module of a system the same.
    pub rigid: bool,
    /// How the simulated Controller propels the carriage.
    pub body_move_law: tca_controller_sim::sim::BodyMoveLaw,
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
            rigid: false,
            body_move_law: tca_controller_sim::sim::BodyMoveLaw::Servo,
        }
    }
}

/// Connects the walking module `name` (one of [`WALKING_MODULES`]).
pub async fn connect_standalone(
    name: &str,
    connector: &Connector,
    options: &ModuleOptions,
) -> Result<Module, ModuleError> {
    if !WALKING_MODULES.contains(&name) {
        return Err(ModuleError::Usage(format!(
            "no walking module named {name:?}; the walking modules are {}",
            WALKING_MODULES.join(", ")
        )));
    }
    let mut setup = SystemSetup::new(options.terrain.clone(), options.seed)
        .map_err(|e| ModuleError::Config(format!("{e:#}")))?;
    setup.out = options.out.clone();
    setup.step_pictures = options.pictures;
    setup.compute = options.compute;
    setup.speed = options.speed;
    setup.state_dir = options.state_dir.clone();
    setup.set_rigid(options.rigid);
    setup.set_body_move_law(options.body_move_law);
    if let Some(dir) = &setup.out {
        std::fs::create_dir_all(dir).map_err(|source| ModuleError::Io {
            what: format!("cannot create {}", dir.display()),
            source,
        })?;
    }
    connect_module(name, connector, &setup).await
}
