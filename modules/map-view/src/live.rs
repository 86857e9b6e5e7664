//! Maps from a running walking system: a short-lived module joins central, asks the LTM
//! Manager for the region (`mapRegion`) and draws it, or has the system's PDM draw it
//! (`renderMap`).

use std::path::Path;
use std::time::Duration;

use anyhow::{Context as _, bail};
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};
use tca_robot::LegParams;
use tca_robot::course::{PIT_SIZE_X_M, PIT_SIZE_Y_M};
use tca_single_leg_messages::{BodyPosition, MapCell, MapGrid, MapKind, MapRegion, RenderMap};

use super::picture::{MapPicture, draw, png_size};
use super::request::{MapArea, MapRequest, check_region, rectangle};

/// Side of the square searched for mapped cells around the carriage, metres (twice the LTM
/// Manager's 20 m window, so maps paged out to disk are found too).
pub const SEARCH_SIDE_M: f64 = 40.0;

/// Cell size of that search, metres.
pub const SEARCH_RESOLUTION_M: f64 = 0.25;

/// How to ask a running system.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveMapOptions {
    /// Ask the LTM Manager to take a fresh image first.
    pub refresh: bool,
    /// Have the system's PDM draw the picture (it writes the file in its own process, so the
    /// path must be one it can write: same machine) instead of drawing it here.
    pub via_pdm: bool,
    /// Longest wait for each answer.
    pub timeout: Duration,
}

impl Default for LiveMapOptions {
    fn default() -> Self {
        Self {
            refresh: false,
            via_pdm: false,
            timeout: Duration::from_secs(30),
        }
    }
}

/// Draws the map of `request` from the walking system behind central (reached through
/// `connector`, whose description is used in errors) to `out`.
pub async fn map_from_system(
    connector: &Connector,
    request: &MapRequest,
    options: &LiveMapOptions,
    out: &Path,
) -> anyhow::Result<MapPicture> {
    let me = Module::builder(format!("map-{}", std::process::id()))
        // Stamped with simulated time (from zero), so asking never moves the system's clocks.
        .simulated_time(true)
        .query_timeout(options.timeout)
        .connect(connector)
        .await
        .with_context(|| {
            format!(
                "cannot reach {}; start the walking system (`tca up walk.toml`) or give its \
                 endpoint with --connect, or draw from a traffic log with --log FILE.mcap",
                connector.describe()
            )
        })?;
    let result = draw_from(&me, request, options, out).await;
    me.close().await;
    result
}

async fn draw_from(
    me: &Module,
    request: &MapRequest,
    options: &LiveMapOptions,
    out: &Path,
) -> anyhow::Result<MapPicture> {
    let ask = |kind, polygon, resolution_m, refresh| MapRegion {
        kind,
        polygon,
        resolution_m,
        refresh,
    };
    let mut refresh = options.refresh;
    let polygon = match &request.area {
        MapArea::Polygon(p) => p.clone(),
        MapArea::Mapped => {
            let (x, y) = search_centre(me).await;
            let h = 0.5 * SEARCH_SIDE_M;
            let search = ltm_query(
                me,
                &ask(
                    MapKind::Elevation,
                    rectangle(x - h, y - h, x + h, y + h),
                    SEARCH_RESOLUTION_M,
                    refresh,
                ),
            )
            .await?;
            refresh = false;
            let Some((lo, hi)) = mapped_bounds(&search) else {
                bail!(
                    "the LTM Manager's map is empty within {SEARCH_SIDE_M} m around ({x:.1}, \
                     {y:.1}) m; let the system take an image first (e.g. walk a step) or give \
                     --region"
                );
            };
            let pad = SEARCH_RESOLUTION_M;
            let corners = rectangle(lo.0 - pad, lo.1 - pad, hi.0 + pad, hi.1 + pad);
            check_region(&corners, request.resolution_m)
                .context("the whole mapped area cannot be drawn at this resolution")?;
            corners
        }
    };
    let region = ask(request.kind, polygon, request.resolution_m, refresh);
    let grid = ltm_query(me, &region).await?;
    if !options.via_pdm {
        return draw(&grid, &[], out);
    }
    let path = std::path::absolute(out)
        .with_context(|| format!("cannot make {} an absolute path", out.display()))?;
    let task = me
        .send_watched(
            &RenderMap {
                region: MapRegion {
                    refresh: false,
                    ..region
                },
                overlays: Vec::new(),
                path: path.to_string_lossy().into_owned(),
            },
            [],
        )
        .context("cannot send renderMap to the PDM")?;
    let outcome = tokio::time::timeout(options.timeout, task.outcome())
        .await
        .map_err(|_| {
            anyhow::anyhow!(
                "the PDM did not draw the map within {:?}; is the pdm module running?",
                options.timeout
            )
        })?
        .context("the PDM did not draw the map")?;
    match outcome {
        TaskOutcome::Achieved => {}
        TaskOutcome::Failed(reason) => bail!("the PDM did not draw the map: {reason}"),
        TaskOutcome::Killed => bail!("the PDM's renderMap was killed"),
    }
    let (w, h) = png_size(&path)?;
    let mut picture = MapPicture::describe(&grid, &path, w, h);
    picture.drawn_by = "running system's PDM";
    Ok(picture)
}

async fn ltm_query(me: &Module, region: &MapRegion) -> anyhow::Result<MapGrid> {
    me.query(region).await.context(
        "the LTM Manager did not give the map (mapRegion); is the walking system's ltm module \
         running behind central (`tca registry --connect ENDPOINT` lists the modules)?",
    )
}

/// Where to look for the map: around the carriage, or the middle of the course pit when no
/// Controller answers.
async fn search_centre(me: &Module) -> (f64, f64) {
    let x = LegParams::default().carriage.x_m;
    match me
        .query_with_timeout(&BodyPosition, Duration::from_secs(5))
        .await
    {
        Ok(pose) if pose.y_m.is_finite() => (x, pose.y_m),
        other => {
            if let Err(e) = other {
                tracing::info!(error = %e, "no carriage position; searching the course pit");
            }
            (0.5 * PIT_SIZE_X_M, 0.5 * PIT_SIZE_Y_M)
        }
    }
}

/// The centres of the outermost cells of `grid` that are known or occluded.
pub fn mapped_bounds(grid: &MapGrid) -> Option<((f64, f64), (f64, f64))> {
    let nx = grid.nx.max(1) as usize;
    let mut bounds: Option<((usize, usize), (usize, usize))> = None;
    for (k, cell) in grid.cells.iter().enumerate() {
        if matches!(cell, MapCell::Unknown) {
            continue;
        }
        let (i, j) = (k % nx, k / nx);
        bounds = Some(match bounds {
            None => ((i, j), (i, j)),
            Some(((i0, j0), (i1, j1))) => ((i0.min(i), j0.min(j)), (i1.max(i), j1.max(j))),
        });
    }
    let at = |i: usize, j: usize| {
        (
            grid.origin_x_m + i as f64 * grid.resolution_m,
            grid.origin_y_m + j as f64 * grid.resolution_m,
        )
    };
    bounds.map(|((i0, j0), (i1, j1))| (at(i0, j0), at(i1, j1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapped_bounds_are_the_outermost_seen_cells() {
        let known = MapCell::Known {
            value: 0.0,
            sigma_m: 0.01,
        };
        let mut grid = MapGrid {
            kind: MapKind::Elevation,
            origin_x_m: 10.0,
            origin_y_m: -1.0,
            resolution_m: 0.5,
            nx: 4,
            ny: 3,
            cells: vec![MapCell::Unknown; 12],
        };
        assert_eq!(mapped_bounds(&grid), None);
        grid.cells[5] = known; // (1, 1)
        grid.cells[11] = MapCell::Occluded {
            max_elevation_m: 1.0,
        }; // (3, 2)
        assert_eq!(mapped_bounds(&grid), Some(((10.5, -0.5), (11.5, 0.0))));
    }
}
