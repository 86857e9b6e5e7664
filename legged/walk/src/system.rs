//! The legged walking system's modules, connected with the settings one walk shares: the
//! simulated Controller, the body-mounted scanner (ISM), the scrolling terrain map (LTM
//! Manager) and the walking module with its free gait.

use std::sync::Arc;

use tca_ism::{IsmConfig, PoseSource, SensorSpec, VirtualScanner};
use tca_legged_controller::{InjectedFault, LeggedControllerConfig};
use tca_legged_model::RobotModel;
use tca_legged_sim::StartPose;
use tca_ltm::LtmConfig;
use tca_module::{ComputeTime, Connector, Module, ModuleError};
use tca_robot::HeightField;

use crate::gait_module::GaitModuleConfig;
use crate::terrain::max_reach;

/// Names of the legged walking modules, in the order they are connected.
pub const LEGGED_MODULES: &[&str] = &["controller", "ism", "ltm", "gait"];

/// What the modules of one legged walk share.
#[derive(Clone, Debug)]
pub struct LeggedSetup {
    /// The robot.
    pub model: Arc<RobotModel>,
    /// Its URDF text (the Controller hands it to planners that ask).
    pub urdf: String,
    /// The terrain (the simulator's truth and the scanner's scene).
    pub terrain: Arc<HeightField>,
    /// Where the body starts.
    pub start: StartPose,
    /// Seed of the scanner noise.
    pub seed: u64,
    /// The walking module plans on the true terrain instead of the LTM Manager's maps.
    pub ground_truth: bool,
    /// Hardware faults the simulated Controller injects.
    pub faults: Vec<InjectedFault>,
    /// What plans the steps.
    pub planner: LeggedPlanner,
    /// The simulated Controller's robot sags under load (`None`: rigid).
    pub sag: Option<tca_legged_sim::SagParams>,
    /// With the CG-space planner: workers for its route's joins (`None`: none).
    pub cg_workers: Option<crate::cg_workers::CgWorkers>,
    /// With the CG-space planner: its parameters (`None`: the defaults).
    pub cg_plan: Option<tca_cg_space::PlanParams>,
}

/// What plans a legged walk's steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LeggedPlanner {
    /// The free gait, step by step on the LTM Manager's map (or the true terrain with
    /// `ground_truth`).
    #[default]
    FreeGait,
    /// The integrated RRT-Connect planner over the whole terrain, in this gait.
    Rrt(tca_rrt::Gait),
    /// CG-space route and footfall planning over the whole terrain.
    CgSpace,
}

impl LeggedPlanner {
    /// `free` or `rrt` (with `tripod` or `wave`), as on the command line.
    pub fn parse(planner: &str, gait: Option<&str>) -> Result<Self, String> {
        match (planner, gait) {
            ("free", None) => Ok(LeggedPlanner::FreeGait),
            ("free", Some(g)) => Err(format!(
                "the free gait chooses its own leg order; a gait ({g}) is for --planner rrt"
            )),
            ("rrt", g) => tca_rrt::Gait::from_name(g.unwrap_or("tripod"))
                .map(LeggedPlanner::Rrt)
                .map_err(|e| e.to_string()),
            ("cgspace", None) => Ok(LeggedPlanner::CgSpace),
            ("cgspace", Some(g)) => Err(format!(
                "CG-space planning chooses its own foot order; a gait ({g}) is for --planner rrt"
            )),
            (other, _) => Err(format!(
                "no planner named {other:?}: the planners are free (the free gait), rrt (RRT-Connect) and cgspace (CG-space)"
            )),
        }
    }

    /// For people: `free gait` or `RRT-Connect (tripod gait)`.
    pub fn describe(&self) -> String {
        match self {
            LeggedPlanner::FreeGait => "free gait".to_owned(),
            LeggedPlanner::Rrt(g) => format!("RRT-Connect ({} gait)", g.name()),
            LeggedPlanner::CgSpace => "CG-space".to_owned(),
        }
    }
}

impl LeggedSetup {
    /// The simulated Controller's configuration for this setup (module `controller`, the
    /// simulator's defaults for the robot, the faults to inject).
    pub fn controller_config(&self) -> LeggedControllerConfig {
        let mut config = LeggedControllerConfig {
            module_name: "controller".into(),
            faults: self.faults.clone(),
            ..LeggedControllerConfig::new(
                self.model.clone(),
                self.urdf.clone(),
                self.terrain.clone(),
                self.start,
            )
        };
        config.params.sag = self.sag;
        config
    }

    /// Half the side of the map the walking module asks for: the region the feet can reach
    /// from where the step leaves the body, with room for a body move.
    pub fn map_half_side_m(&self) -> f64 {
        2.0 * max_reach(&self.model)
    }

    /// The map's cell: a twentieth of the longest leg's reach, at most 0.1 m.
    pub fn map_cell_m(&self) -> f64 {
        (max_reach(&self.model) / 20.0).clamp(0.01, 0.1)
    }
}

/// Connects one legged walking module.
pub async fn connect_module(
    name: &str,
    connector: &Connector,
    setup: &LeggedSetup,
) -> Result<Module, ModuleError> {
    match name {
        "controller" => tca_legged_controller::connect(connector, setup.controller_config()).await,
        "ism" => {
            // The Perceptron on a mast sized for this robot's feet (see `mount`).
            let spec = SensorSpec::perceptron();
            let mount = crate::mount::mast_mount(&setup.model, spec.elevation_fov_rad);
            let config = IsmConfig::new()
                .with_pose_source(PoseSource::LeggedBody)
                .with_sensor(
                    VirtualScanner::on_body(spec, setup.terrain.clone(), mount)
                        .with_seed(setup.seed),
                )
                .with_simulated_time(true);
            tca_ism::connect(connector, config).await
        }
        "ltm" => {
            let config = LtmConfig {
                simulated_time: true,
                compute_time: ComputeTime::Measured,
                ..LtmConfig::for_robot(
                    setup.map_cell_m(),
                    setup.map_half_side_m(),
                    foot_radius(&setup.model),
                )
            };
            tca_ltm::connect(connector, config).await
        }
        "gait" => {
            let mut config = GaitModuleConfig::new(
                setup.model.clone(),
                setup.map_half_side_m(),
                setup.map_cell_m(),
            );
            if setup.ground_truth {
                config.ground_truth = Some(setup.terrain.clone());
            } else {
                config = config.with_map_allowance();
            }
            if let LeggedPlanner::Rrt(gait) = setup.planner {
                config.planner = crate::gait_module::StepPlanner::Rrt {
                    terrain: setup.terrain.clone(),
                    params: tca_rrt::RrtParams {
                        gait,
                        seed: setup.seed,
                        ..tca_rrt::RrtParams::default()
                    },
                };
            }
            if setup.planner == LeggedPlanner::CgSpace {
                let mut params = setup.cg_plan.clone().unwrap_or_default();
                params.route.seed = setup.seed;
                config.planner = crate::gait_module::StepPlanner::CgSpace {
                    terrain: setup.terrain.clone(),
                    cg: crate::cg_steps::walking_cg_params(),
                    params,
                    workers: setup.cg_workers.clone(),
                };
            }
            crate::gait_module::connect(connector, config).await
        }
        other => Err(ModuleError::Usage(format!(
            "no legged walking module named {other:?}; they are {}",
            LEGGED_MODULES.join(", ")
        ))),
    }
}

/// Connects all the legged walking modules, in [`LEGGED_MODULES`]'s order.
pub async fn connect_all(
    connector: &Connector,
    setup: &LeggedSetup,
) -> Result<Vec<Module>, ModuleError> {
    let mut modules = Vec::new();
    for name in LEGGED_MODULES {
        modules.push(connect_module(name, connector, setup).await?);
    }
    Ok(modules)
}

/// The largest foot's contact radius, metres (the footfall map is evaluated for it).
pub fn foot_radius(model: &RobotModel) -> f64 {
    model
        .legs()
        .iter()
        .map(|l| l.foot_radius())
        .fold(0.0, f64::max)
        .max(0.01)
}
