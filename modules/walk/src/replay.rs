//! Replaying a recorded walk (`tca log replay`): the walking modules not played from the log
//! run live, set up as `tca walk` sets them up, and what they send is compared with the record
//! (see `tca_replay` for the engine).
//!
//! ```text
//! tca walk --course 4 --seed 1 --out out/c4          # records out/c4/traffic.mcap
//! tca log replay out/c4/traffic.mcap --as controller,ism
//! tca log replay out/c4/traffic.mcap --as controller,ism --gait-params my-gait.toml
//! ```
//!
//! The driver stands in for the walker and sends the recorded `walk` goals (and the walk back
//! with `--backward`). `--gait-params FILE.toml` runs the Gait Planner with other parameters
//! (the format of `modules/gait-planner/params/gait.toml`): the way to see a divergence on
//! purpose, e.g. `first divergence: gait -> recoverLeg #3, field footfall.x_m: recorded 1.55,
//! live 1.65`. Modules run live that need the terrain (the Controller, the ISM) need the
//! recorded terrain and seed.
//!
//! Replays are exact, concurrent walks included: the recorded walk ran on central's simulated
//! clock, which releases every message in simulated-time order one at a time, and the replay's
//! central keeps the same clock, so the live modules see the same inputs at the same times.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context as _, bail};
use futures::future::BoxFuture;
use tca_logs::compare::{FieldRule, Rules};
use tca_messages::Class;
use tca_module::{Connector, Module};
use tca_replay::{LiveSide, ReplayPlan, ReplayReport};

use crate::system::{ComputeModel, SystemSetup, WALKING_MODULES, connect_module};
use crate::terrain::TerrainChoice;

/// The root goal a walk replay sends again.
pub const WALK_GOAL: &str = "walk";

/// What to replay.
#[derive(Clone, Debug)]
pub struct WalkReplayOptions {
    /// The recorded traffic log (`tca walk --out DIR` writes `DIR/traffic.mcap`).
    pub log: PathBuf,
    /// Modules played from the log.
    pub stand_ins: Vec<String>,
    /// Run the Gait Planner with these parameters instead of the shipped ones.
    pub gait_params: Option<PathBuf>,
    /// The recorded terrain, for a live Controller or ISM.
    pub terrain: Option<TerrainChoice>,
    /// The recorded scanner-noise seed, for a live ISM.
    pub seed: u64,
    /// What the live planners' computing costs in simulated time (as recorded: only the
    /// stamps depend on it, never the data compared).
    pub compute: ComputeModel,
    /// Keep the replay's traffic log in this directory.
    pub out: Option<PathBuf>,
    /// Wall-clock limit of each replayed goal (see [`ReplayPlan::goal_timeout`]).
    pub goal_timeout: Option<Duration>,
}

/// The data fields of the walking vocabulary that a replay treats specially.
pub fn comparison_rules() -> Rules {
    Rules {
        ignored: vec![FieldRule {
            message: "controllerStatus",
            class: Class::Reply,
            path: "clock_s",
            why: "the controller's clock advances with the wall clock whenever the simulator \
                  runs at a finite speed factor",
        }],
        message_ids: vec![FieldRule {
            message: "planStep",
            class: Class::Goal,
            path: "after_body_move",
            why: "names the previous step's bodyMove message (concurrent walking)",
        }],
    }
}

/// Replays a recorded walk. An `Err` means the log cannot be replayed; divergences are in the
/// report.
pub async fn replay_walk(options: &WalkReplayOptions) -> anyhow::Result<ReplayReport> {
    let gait_params = match &options.gait_params {
        Some(p) => Some(
            tca_gait_planner::GaitParams::load(p)
                .with_context(|| format!("cannot load gait parameters {}", p.display()))?,
        ),
        None => None,
    };
    let plan = ReplayPlan {
        log: options.log.clone(),
        stand_ins: options.stand_ins.clone(),
        root_goal: WALK_GOAL.into(),
        rules: comparison_rules(),
        how_to_record: "record a walk with `tca walk --out DIR` and replay DIR/traffic.mcap".into(),
        out: options.out.clone(),
        goal_timeout: options.goal_timeout,
    };
    let mut live = WalkingLive {
        terrain: options.terrain.clone(),
        seed: options.seed,
        compute: options.compute,
        gait_params,
        setup: None,
    };
    tca_replay::replay(&plan, &mut live).await
}

/// The walking modules, run live in a replay.
struct WalkingLive {
    terrain: Option<TerrainChoice>,
    seed: u64,
    compute: ComputeModel,
    gait_params: Option<tca_gait_planner::GaitParams>,
    setup: Option<SystemSetup>,
}

impl LiveSide for WalkingLive {
    fn runs_live(&self, module: &str) -> bool {
        WALKING_MODULES.contains(&module)
    }

    fn prepare(&mut self, live: &[String], dir: &Path) -> anyhow::Result<()> {
        let needs_terrain = live.iter().find(|m| *m == "controller" || *m == "ism");
        let mut setup = match (&self.terrain, needs_terrain) {
            (Some(t), _) => SystemSetup::new(t.clone(), self.seed)?,
            (None, Some(m)) => bail!(
                "{m} runs live in this replay and needs the recorded terrain: give --course N \
                 (or --terrain FILE.asc) and --seed N as recorded, or play it from the log with \
                 --as {m}"
            ),
            // The planners never read the terrain: any will do.
            (None, None) => SystemSetup::new(TerrainChoice::Course(1), self.seed)?,
        };
        setup.out = Some(dir.to_owned());
        setup.compute = self.compute;
        setup.gait_params = self.gait_params;
        self.setup = Some(setup);
        Ok(())
    }

    fn connect<'a>(
        &'a self,
        name: &'a str,
        connector: &'a Connector,
    ) -> BoxFuture<'a, anyhow::Result<Module>> {
        Box::pin(async move {
            let setup = self
                .setup
                .as_ref()
                .context("the walking modules were not prepared")?;
            Ok(connect_module(name, connector, setup).await?)
        })
    }
}
