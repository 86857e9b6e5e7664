//! The walking system's modules: one function per module to connect it with the settings a
//! walk uses, shared by `tca walk` (all in this process) and `tca module NAME` (one process
//! each, over zenoh).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tca_controller_sim::sim::{BodyMoveLaw, FaultConfig};
use tca_controller_sim::{ControllerConfig, SpeedFactor};
use tca_gait_planner::GaitConfig;
use tca_ism::IsmConfig;
use tca_lrp::LrpConfig;
use tca_ltm::LtmConfig;
use tca_module::{ComputeTime, Connector, Module, ModuleError};
use tca_pdm::PdmConfig;
use tca_robot::{HeightField, LegParams};

use crate::terrain::{START_Y_M, TerrainChoice, find_start};

/// What the modules of one walking system share.
#[derive(Clone, Debug)]
pub struct SystemSetup {
    /// The terrain (the simulator's truth and the virtual scanner's scene).
    pub terrain: Arc<HeightField>,
    /// Which terrain it is.
    pub choice: TerrainChoice,
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Where pictures go (the PDM's output directory; per-step planner pictures in
    /// `steps/` below it when `step_pictures`).
    pub out: Option<PathBuf>,
    /// Write the planners' per-step pictures.
    pub step_pictures: bool,
    /// The simulator's speed.
    pub speed: SpeedFactor,
    /// What the planners charge to simulated time for their computing.
    pub compute: ComputeModel,
    /// Where modules keep what must survive their restart (the Controller's state file, the
    /// LTM Manager's map tiles); `None`: nothing is kept, a restarted module starts afresh.
    pub state_dir: Option<PathBuf>,
    /// Run the Gait Planner with these parameters instead of the shipped ones.
    pub gait_params: Option<tca_gait_planner::GaitParams>,
    /// Faults the simulated Controller injects, and its leg's compliance.
    pub faults: FaultConfig,
    /// How the simulated Controller propels the carriage.
    pub body_move_law: BodyMoveLaw,
}

/// What the planners charge to simulated time for their computing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ComputeModel {
    /// The 1990 system's planning times (§7.2, Figure 18, exclusive of waiting): the Gait
    /// Planner about 2 s a step, the Leg Recovery Planner about 12 s. Simulated walks then
    /// take about as long as the report's, and planning the next step during the current
    /// one saves about as much.
    #[default]
    Paper,
    /// What the computing measures on this machine (milliseconds): the mechanism's motion
    /// is then nearly all the time there is, and concurrent planning has little to save.
    Measured,
}

impl ComputeModel {
    /// Simulated seconds the Gait Planner charges per step under [`ComputeModel::Paper`].
    pub const PAPER_GAIT_S: u64 = 2;
    /// Simulated seconds the Leg Recovery Planner charges per leg move under
    /// [`ComputeModel::Paper`].
    pub const PAPER_LRP_S: u64 = 12;
    /// Simulated seconds the Leg Recovery Planner charges per reachability map under
    /// [`ComputeModel::Paper`] (the report gives no figure of its own for it).
    pub const PAPER_REACHABILITY_S: u64 = 1;
    /// What the LTM Manager charges under [`ComputeModel::Paper`] for any `mapRegion`, ms.
    pub const PAPER_LTM_BASE_MS: u64 = 500;
    /// What the LTM Manager charges under [`ComputeModel::Paper`] per map cell computed (a
    /// cached cell costs nothing), µs; an image cell merged costs a quarter of that. Fitted to
    /// the report's Figure 18 (the 1990 LTM Manager's map computing was most of a step's
    /// planning time: the first map, from scratch, most of the first step's minute; later
    /// maps reuse the cache): on course 3 it charges about 45 s for the first step and 25 to
    /// 30 s for each later one (BENCHMARKS.md).
    pub const PAPER_LTM_PER_CELL_US: u64 = 2000;
    /// Simulated seconds the PDM charges per picture under [`ComputeModel::Paper`].
    pub const PAPER_PDM_S: u64 = 1;

    fn fixed(self, seconds: u64) -> ComputeTime {
        match self {
            ComputeModel::Paper => ComputeTime::Modeled(Duration::from_secs(seconds)),
            ComputeModel::Measured => ComputeTime::Measured,
        }
    }

    /// What the Gait Planner charges per step.
    pub fn gait(self) -> ComputeTime {
        self.fixed(Self::PAPER_GAIT_S)
    }

    /// What the Leg Recovery Planner charges per leg move.
    pub fn lrp(self) -> ComputeTime {
        self.fixed(Self::PAPER_LRP_S)
    }

    /// What the Leg Recovery Planner charges per reachability map.
    pub fn reachability(self) -> ComputeTime {
        self.fixed(Self::PAPER_REACHABILITY_S)
    }

    /// What the PDM charges per picture.
    pub fn pdm(self) -> ComputeTime {
        self.fixed(Self::PAPER_PDM_S)
    }

    /// What the LTM Manager charges per `mapRegion`.
    pub fn ltm(self) -> ComputeTime {
        match self {
            ComputeModel::Paper => ComputeTime::PerUnit {
                base: Duration::from_millis(Self::PAPER_LTM_BASE_MS),
                per_unit: Duration::from_micros(Self::PAPER_LTM_PER_CELL_US),
            },
            ComputeModel::Measured => ComputeTime::Measured,
        }
    }
}

impl SystemSetup {
    /// Loads the terrain.
    pub fn new(choice: TerrainChoice, seed: u64) -> anyhow::Result<Self> {
        Ok(SystemSetup {
            terrain: Arc::new(choice.load()?),
            choice,
            seed,
            out: None,
            step_pictures: false,
            speed: SpeedFactor::AsFastAsPossible,
            compute: ComputeModel::default(),
            state_dir: None,
            gait_params: None,
            // The leg deflects as the report's did (§4.3); the planners compensate.
            faults: FaultConfig {
                compliance_scale: 1.0,
                ..FaultConfig::none()
            },
            body_move_law: BodyMoveLaw::Servo,
        })
    }

    /// A rigid leg (`true`): no deflection in the simulated Controller and nothing
    /// compensated; `false`: the compliant leg of the report, driven through the Controller's
    /// calibrated kinematics.
    pub fn set_rigid(&mut self, rigid: bool) {
        self.faults.compliance_scale = if rigid { 0.0 } else { 1.0 };
    }

    /// How the simulated Controller propels the carriage (the servo unless set).
    pub fn set_body_move_law(&mut self, law: BodyMoveLaw) {
        self.body_move_law = law;
    }

    fn steps_dir(&self) -> Option<PathBuf> {
        let dir = self.out.as_ref()?.join("steps");
        (self.step_pictures && std::fs::create_dir_all(&dir).is_ok()).then_some(dir)
    }
}

/// Names of the walking modules, in the order they are connected.
pub const WALKING_MODULES: &[&str] = &["controller", "ism", "ltm", "pdm", "lrp", "gait"];

fn config(e: impl std::fmt::Display) -> ModuleError {
    ModuleError::Config(e.to_string())
}

/// Connects one walking module. Every module keeps simulated time, so the durations reported
/// are those of the mechanism (§7.2) however fast the simulation runs.
pub async fn connect_module(
    name: &str,
    connector: &Connector,
    setup: &SystemSetup,
) -> Result<Module, ModuleError> {
    let params = LegParams::default();
    match name {
        "controller" => {
            let start = find_start(&setup.terrain, &params, START_Y_M).map_err(config)?;
            let mut config = ControllerConfig::new((*setup.terrain).clone(), start)
                .with_speed(setup.speed)
                .with_faults(setup.faults);
            // A compliant leg is driven through the calibrated kinematics (§7.1).
            config.compensate_deflection = setup.faults.compliance_scale > 0.0;
            config.body_move_law = setup.body_move_law;
            config.bus_simulated_time = true;
            config.state_file = setup.state_dir.as_ref().map(|d| d.join("controller.state"));
            tca_controller_sim::connect(connector, config).await
        }
        "ism" => {
            let config = IsmConfig::simulated(setup.terrain.clone(), &params, setup.seed)
                .with_simulated_time(true);
            tca_ism::connect(connector, config).await
        }
        "ltm" => {
            // The Perceptron: the Erim's 7.6 cm range steps make every patch look rough
            // (§1: the scanner "did not have sufficient resolution and accuracy").
            let config = LtmConfig {
                simulated_time: true,
                sensor: tca_single_leg_messages::SensorKind::Perceptron,
                store_dir: setup.state_dir.as_ref().map(|d| d.join("ltm-tiles")),
                compute_time: setup.compute.ltm(),
                ..LtmConfig::default()
            };
            tca_ltm::connect(connector, config).await
        }
        "pdm" => {
            let config = PdmConfig {
                output_dir: setup.out.clone(),
                simulated_time: true,
                compute_time: setup.compute.pdm(),
                ..PdmConfig::default()
            };
            tca_pdm::connect(connector, config).await
        }
        "lrp" => {
            let config = LrpConfig {
                picture_dir: setup.steps_dir(),
                simulated_time: true,
                compute_time: setup.compute.lrp(),
                reachability_compute_time: setup.compute.reachability(),
                ..LrpConfig::default()
            };
            tca_lrp::connect(connector, config).await
        }
        "gait" => {
            let mut config = GaitConfig {
                picture_dir: setup.steps_dir(),
                simulated_time: true,
                compute_time: setup.compute.gait(),
                ..GaitConfig::default()
            };
            if let Some(params) = setup.gait_params {
                config.params = params;
            }
            tca_gait_planner::connect(connector, config).await
        }
        other => Err(ModuleError::Usage(format!(
            "no walking module named {other:?}; they are {}",
            WALKING_MODULES.join(", ")
        ))),
    }
}

/// Connects all the walking modules.
pub async fn connect_all(
    connector: &Connector,
    setup: &SystemSetup,
) -> Result<Vec<Module>, ModuleError> {
    let mut modules = Vec::new();
    for name in WALKING_MODULES {
        modules.push(connect_module(name, connector, setup).await?);
    }
    Ok(modules)
}
