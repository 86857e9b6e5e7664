//! The LTM Manager on the bus (`ltm`): the frame-aged terrain map and the danger map.
//! `nav.insertDepth` places a frame with its estimated pose and answers with the cells
//! whose danger changed; `nav.dangerMap` answers with the whole map.

use std::sync::{Arc, Mutex};

use nalgebra::Point2;
use tca_module::{Connector, HandlerError, Module, ModuleError};
use tca_nav_messages::{DangerChanges, DangerMapQuery, InsertDepth};
use tca_nav_navigator::{NavParams, PerceivedMap};

use crate::convert::{attitude_of, change_msg, depth_of, grid_msg, pose_msg, pose_of};

/// How the LTM Manager runs.
#[derive(Debug, Clone)]
pub struct LtmConfig {
    /// The module's name.
    pub module_name: String,
    /// The navigation parameters (danger, ageing, camera, mount, map range).
    pub params: NavParams,
    /// Centre of cell (0, 0), world frame.
    pub origin: Point2<f64>,
    /// Cell side, m.
    pub resolution_m: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
}

/// Connects the LTM Manager; refuses a map that cannot be made.
pub async fn connect(connector: &Connector, config: LtmConfig) -> Result<Module, ModuleError> {
    let map = PerceivedMap::new(
        config.params.clone(),
        config.origin,
        config.resolution_m,
        config.nx,
        config.ny,
    )
    .map_err(|e| ModuleError::Config(format!("the LTM Manager's map: {e}")))?;
    let (w, h) = (config.params.camera.width, config.params.camera.height);
    let map = Arc::new(Mutex::new(map));
    let m2 = map.clone();
    Module::builder(config.module_name.clone())
        .simulated_time(true)
        .handle(move |_ctx, q: InsertDepth| {
            let reply = insert(&map, &q, w, h);
            async move { reply }
        })
        .handle(move |_ctx, _q: DangerMapQuery| {
            let m = m2.lock().unwrap_or_else(|p| p.into_inner());
            let reply = grid_msg(m.danger().cells(), m.frames());
            async move { Ok(reply) }
        })
        .connect(connector)
        .await
}

fn insert(
    map: &Mutex<PerceivedMap>,
    q: &InsertDepth,
    width: usize,
    height: usize,
) -> Result<DangerChanges, HandlerError> {
    let image = depth_of(&q.frame, width, height)
        .map_err(|e| HandlerError::new(format!("nav.insertDepth: {e}")))?;
    let mut m = map.lock().unwrap_or_else(|p| p.into_inner());
    let inserted = m.insert(pose_of(&q.frame.estimate), &attitude_of(&q.frame), &image);
    Ok(DangerChanges {
        frames: m.frames(),
        estimate: pose_msg(&inserted.estimate),
        registered: inserted.registration.is_some(),
        cells: inserted.changes.iter().map(change_msg).collect(),
    })
}
