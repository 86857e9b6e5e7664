//! The navigator on the bus (`navigator`): the `nav.navigate` goal. Each frame it asks the
//! ISM for a depth image and the odometry's estimate, the LTM Manager to map it, plans with
//! D* Lite and commands the base through `nav.drive`, informing `nav.frame` as it goes. It
//! never learns which base it drives, nor where the base really is.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Point2;
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};
use tca_nav_dstar_lite::PlanError;
use tca_nav_messages::{
    AcquireDepth, DangerMapQuery, DepthFrame, Drive, FrameOutcome, InsertDepth, NavFrame, Navigate,
};
use tca_nav_navigator::{Command, NavError, NavParams, Navigator};

use crate::convert::{change_of, pose_msg, pose_of};

/// Why a goal ends without reaching the goal when the map has no way there.
pub const NO_PATH_REASON: &str = "no traversable path to the goal on the map as perceived";

/// How the navigator runs.
#[derive(Debug, Clone)]
pub struct NavigatorConfig {
    /// The module's name.
    pub module_name: String,
    /// The navigation parameters.
    pub params: NavParams,
}

/// Connects the navigator.
pub async fn connect(
    connector: &Connector,
    config: NavigatorConfig,
) -> Result<Module, ModuleError> {
    let config = Arc::new(config);
    Module::builder(config.module_name.clone())
        .simulated_time(true)
        .handle(move |ctx, goal: Navigate| {
            let c = config.clone();
            async move { navigate(&ctx, &c.params, goal).await }
        })
        .connect(connector)
        .await
}

fn failed(what: &str, e: impl std::fmt::Display) -> HandlerError {
    HandlerError::new(format!("nav.navigate: {what}: {e}"))
}

async fn navigate(ctx: &Context, params: &NavParams, goal: Navigate) -> Result<(), HandlerError> {
    if !(goal.dx_m.is_finite() && goal.dy_m.is_finite()) {
        return Err(HandlerError::new(format!(
            "nav.navigate: the goal ({}, {}) m is not a pair of finite numbers",
            goal.dx_m, goal.dy_m
        )));
    }
    if goal.max_frames == 0 {
        return Err(HandlerError::new(
            "nav.navigate: max_frames must be at least 1",
        ));
    }
    let map = ctx
        .query(&DangerMapQuery)
        .await
        .map_err(|e| failed("the LTM Manager did not describe its map", e))?;
    let t0 = Instant::now();
    let frame: DepthFrame = ctx
        .query(&AcquireDepth)
        .await
        .map_err(|e| failed("the ISM gave no depth image", e))?;
    let start = pose_of(&frame.estimate);
    let target = Point2::new(start.x + goal.dx_m, start.y + goal.dy_m);
    let mut nav = Navigator::new(
        params.clone(),
        Point2::new(map.origin_x_m, map.origin_y_m),
        map.resolution_m,
        map.nx as usize,
        map.ny as usize,
        start,
        target,
    )
    .map_err(|e| HandlerError::new(format!("nav.navigate: {e}")))?;
    // The first frame, taken to learn the start, is the first the loop maps.
    let mut first = Some((t0, frame));
    let mut registrations = 0;
    for n in 0..goal.max_frames {
        let (t0, frame) = match first.take() {
            Some(taken) => taken,
            None => {
                let t0 = Instant::now();
                let frame = ctx
                    .query(&AcquireDepth)
                    .await
                    .map_err(|e| failed("the ISM gave no depth image", e))?;
                (t0, frame)
            }
        };
        let changes = ctx
            .query(&InsertDepth { frame })
            .await
            .map_err(|e| failed("the LTM Manager did not map the frame", e))?;
        let estimate = pose_of(&changes.estimate);
        registrations += u64::from(changes.registered);
        let cells: Vec<_> = changes.cells.iter().map(change_of).collect();
        let step = nav.step(estimate, &cells);
        let (outcome, forward, turn) = match &step {
            Ok(Command::Reached) => (FrameOutcome::Reached, 0.0, 0.0),
            Ok(Command::Drive {
                forward_mps,
                turn_rps,
            }) => (FrameOutcome::Drive, *forward_mps, *turn_rps),
            Err(NavError::Plan(PlanError::NoPath { .. })) => (FrameOutcome::NoPath, 0.0, 0.0),
            Err(NavError::NoProgress { .. }) => (FrameOutcome::NoProgress, 0.0, 0.0),
            Err(e) => return Err(HandlerError::new(format!("nav.navigate: {e}"))),
        };
        let loop_s = t0.elapsed().as_secs_f64();
        ctx.inform(&NavFrame {
            frame: n,
            estimate: pose_msg(&estimate),
            goal: [target.x, target.y],
            path: nav.path().iter().map(|p| [p.x, p.y]).collect(),
            outcome,
            forward_mps: forward,
            turn_rps: turn,
            replans: nav.replans(),
            exploration_turns: nav.exploration_turns(),
            registrations,
            changed_cells: cells.len() as u64,
            loop_s,
        })?;
        match outcome {
            FrameOutcome::Reached => return Ok(()),
            FrameOutcome::NoPath => return Err(HandlerError::new(NO_PATH_REASON)),
            FrameOutcome::NoProgress => {
                let reason = step.err().map(|e| e.to_string()).unwrap_or_default();
                return Err(HandlerError::new(reason));
            }
            FrameOutcome::Drive => {}
        }
        let driven = ctx
            .query(&Drive {
                forward_mps: forward,
                turn_rps: turn,
                duration_s: params.frame_period_s,
            })
            .await
            .map_err(|e| failed("the base did not drive", e))?;
        if driven.fell {
            tracing::warn!(frame = n, "the base tipped over");
        }
    }
    Err(HandlerError::new(format!(
        "no goal within {} frames",
        goal.max_frames
    )))
}
