//! The LTM Manager as a TCA module: answers `mapRegion` ([`MapRegion`] -> [`MapGrid`]). When
//! the request asks for a refresh, or no image has been merged yet, it first asks the ISM for
//! an image (`acquireImage`) of the configured sensor and merges it. A bad region is refused
//! before any image is taken.
//!
//! With a store directory of its own ([`LtmConfig::store_dir`]) the map's tiles are written
//! there after every merge: an LTM Manager killed and started again on the same directory
//! answers from the map the dead one had built.

use std::sync::{Arc, Mutex};

use tca_module::{ComputeTime, Connector, Context, HandlerError, Module, ModuleError};
use tca_single_leg_messages::{AcquireImage, MapGrid, MapRegion};

use crate::error::LtmError;
use crate::manager::{LocalTerrainMap, LtmConfig};

/// Connects the LTM Manager module (`"ltm"`) with an empty map and serves `mapRegion`.
pub async fn connect(connector: &Connector, config: LtmConfig) -> Result<Module, ModuleError> {
    let map = LocalTerrainMap::new(config).map_err(|e| match e {
        LtmError::Io { path, source } => ModuleError::Io {
            what: format!("map tile store {}", path.display()),
            source,
        },
        other => ModuleError::Config(other.to_string()),
    })?;
    connect_with_map(connector, map).await
}

/// Connects the LTM Manager module serving an existing map (e.g. one loaded from a store
/// directory, or built from stored images).
pub async fn connect_with_map(
    connector: &Connector,
    map: LocalTerrainMap,
) -> Result<Module, ModuleError> {
    let simulated_time = map.config().simulated_time;
    let compute_time = map.config().compute_time;
    let map = Arc::new(Mutex::new(map));
    Module::builder("ltm")
        .simulated_time(simulated_time)
        // A module that dies while answering one of our queries is restarted; ask again.
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |ctx, request: MapRegion| {
            let map = map.clone();
            async move { map_region(&ctx, map, request, compute_time).await }
        })
        .connect(connector)
        .await
}

fn lock(
    map: &Mutex<LocalTerrainMap>,
) -> Result<std::sync::MutexGuard<'_, LocalTerrainMap>, HandlerError> {
    map.lock()
        .map_err(|_| HandlerError::new("the terrain map was poisoned by an earlier panic"))
}

async fn map_region(
    ctx: &Context,
    map: Arc<Mutex<LocalTerrainMap>>,
    request: MapRegion,
    compute_time: ComputeTime,
) -> Result<MapGrid, HandlerError> {
    let (needs_image, sensor) = {
        let map = lock(&map)?;
        map.check_region(&request)?;
        (
            request.refresh || map.images_merged() == 0,
            map.config().sensor,
        )
    };
    let mut computing = std::time::Duration::ZERO;
    // Work done, for a modelled charge: map cells computed, and image cells merged at a
    // quarter of a map cell each.
    let mut work = 0u64;
    if needs_image {
        let image = ctx.query(&AcquireImage { sensor }).await?;
        let map = map.clone();
        let began = std::time::Instant::now();
        let report = tokio::task::spawn_blocking(move || {
            let mut map = lock(&map)?;
            let report = map.add_image(&image).map_err(HandlerError::from)?;
            // With a store directory of its own, the map on disk is kept current, so a
            // restarted LTM Manager opens the map this one had built.
            if map.config().store_dir.is_some() {
                map.flush().map_err(HandlerError::from)?;
            }
            Ok::<_, HandlerError>(report)
        })
        .await
        .map_err(|e| HandlerError::new(format!("map building did not finish: {e}")))??;
        computing += began.elapsed();
        // Merging an image costs a quarter of computing a map cell, per cell (the modelled
        // charge of `ComputeTime::PerUnit` counts map cells computed).
        work += (report.known + report.occluded) as u64 / 4;
        tracing::debug!(
            changed = report.cells_changed,
            "new image merged for a query"
        );
    }
    let began = std::time::Instant::now();
    let (answer, computed) = tokio::task::spawn_blocking(move || {
        let mut map = lock(&map)?;
        let before = map.cache_stats().computed;
        let answer = map.query(&request).map_err(HandlerError::from);
        let computed = map.cache_stats().computed.saturating_sub(before);
        Ok::<_, HandlerError>((answer, computed))
    })
    .await
    .map_err(|e| HandlerError::new(format!("the query did not finish: {e}")))??;
    computing += began.elapsed();
    work += computed;
    let charged = compute_time.charged_for(computing, work);
    tracing::debug!(
        image = needs_image,
        cells = work,
        measured_ms = computing.as_secs_f64() * 1e3,
        charged_s = charged.as_secs_f64(),
        "mapRegion answered"
    );
    ctx.spend(charged);
    answer
}
