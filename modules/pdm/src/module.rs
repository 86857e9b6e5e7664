//! The PDM as a TCA module: handles the `renderMap` command ([`RenderMap`]) by asking the LTM
//! Manager for the map (`mapRegion`) and writing the picture to the requested path. The same
//! steps are available to command-line tools as [`render_map`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use tca_module::{ComputeTime, Connector, HandlerError, Module, ModuleError};
use tca_single_leg_messages::RenderMap;

use crate::error::{PdmError, Result};
use crate::render::{RenderOptions, write_png};

/// Configuration of the PDM module.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PdmConfig {
    /// How pictures are drawn.
    pub render: RenderOptions,
    /// Relative output paths are taken relative to this directory (`None`: the process's
    /// working directory).
    pub output_dir: Option<PathBuf>,
    /// Stamp messages with simulated time (run with a simulated Controller) and charge the
    /// drawing to it as `compute_time` says.
    pub simulated_time: bool,
    /// What drawing a picture charges to simulated time.
    pub compute_time: ComputeTime,
}

impl PdmConfig {
    /// Where a requested path is written.
    pub fn resolve(&self, path: &str) -> PathBuf {
        let p = Path::new(path);
        match &self.output_dir {
            Some(dir) if p.is_relative() => dir.join(p),
            _ => p.to_owned(),
        }
    }
}

/// Connects the PDM module (`"pdm"`) and handles `renderMap`.
pub async fn connect(connector: &Connector, config: PdmConfig) -> Result<Module, ModuleError> {
    let config = Arc::new(config);
    let simulated_time = config.simulated_time;
    let compute_time = config.compute_time;
    Module::builder("pdm")
        .simulated_time(simulated_time)
        // A module that dies while answering one of our queries is restarted; ask again.
        .requery_after_crash(tca_module::REQUERIES_AFTER_CRASH)
        .handle(move |ctx, request: RenderMap| {
            let config = config.clone();
            async move {
                let path = config.resolve(&request.path);
                let began = std::time::Instant::now();
                render_map(ctx.module(), &request, &config.render, &path)
                    .await
                    .map_err(HandlerError::from)?;
                if simulated_time {
                    ctx.spend(compute_time.charged(began.elapsed()));
                }
                tracing::info!(path = %path.display(), kind = ?request.region.kind, "map drawn");
                Ok(())
            }
        })
        .connect(connector)
        .await
}

/// Asks the LTM Manager (through `module`) for the region of `request` and writes its picture,
/// with the request's overlays, to `path`. For command-line tools (`tca map ...`).
pub async fn render_map(
    module: &Module,
    request: &RenderMap,
    options: &RenderOptions,
    path: &Path,
) -> Result<()> {
    let grid = module
        .query(&request.region)
        .await
        .map_err(|e| PdmError::Map(e.to_string()))?;
    let overlays = request.overlays.clone();
    let options = options.clone();
    let path = path.to_owned();
    tokio::task::spawn_blocking(move || write_png(&path, &grid, &overlays, &options))
        .await
        .map_err(|e| PdmError::Encode(format!("drawing did not finish: {e}")))?
}
