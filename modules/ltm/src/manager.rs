//! The LTM Manager's state: the builder, the merged map in its scrolling store, and the query
//! cache, behind one type ([`LocalTerrainMap`]) the module wraps.

use std::path::PathBuf;

use nalgebra::Point2;
use tca_ism::ImageFrames;
use tca_module::ComputeTime;
use tca_single_leg_messages::{MapGrid, MapKind, MapRegion, RangeImage, SensorKind};

use crate::builder::{BuilderConfig, build_map};
use crate::cell::{Cell, fuse};
use crate::error::{LtmError, Result};
use crate::footfall::FootParams;
use crate::patch::{Patch, lattice_index};
use crate::query::{CacheStats, QueryCache, answer};
use crate::region::Region;
use crate::scroller::{ScrollReport, TileStore};

/// Configuration of the LTM Manager.
#[derive(Debug, Clone, PartialEq)]
pub struct LtmConfig {
    /// The builder (its `resolution_m` is the map's).
    pub builder: BuilderConfig,
    /// Side of the square window kept in memory around the vehicle, metres (§5.2.2: 20 m).
    pub window_m: f64,
    /// Cells per side of a map tile (the unit of paging).
    pub tile_cells: usize,
    /// Where tiles are paged to; `None`: a fresh temporary directory, removed on drop.
    pub store_dir: Option<PathBuf>,
    /// The foot used by footfall and slope maps.
    pub foot: FootParams,
    /// Two elevations of a cell further apart than this many combined standard deviations are
    /// not averaged: the newer replaces the older (the terrain changed). `None`: always fuse.
    pub merge_gate_sigmas: Option<f32>,
    /// Largest number of cells a query may ask for.
    pub max_query_cells: usize,
    /// Cells the query cache may hold before it is emptied.
    pub cache_cells: usize,
    /// The sensor the module asks the ISM for when it needs an image.
    pub sensor: SensorKind,
    /// Stamp the module's messages with simulated time, charging each query what
    /// `compute_time` says for its map building and answering.
    pub simulated_time: bool,
    /// What a `mapRegion` charges to simulated time: what it measured, or a model per map cell
    /// computed, an image cell merged counting a quarter (`ComputeTime::PerUnit`).
    pub compute_time: ComputeTime,
}

impl Default for LtmConfig {
    fn default() -> Self {
        Self {
            builder: BuilderConfig::default(),
            window_m: 20.0,
            tile_cells: 64,
            store_dir: None,
            foot: FootParams::default(),
            merge_gate_sigmas: Some(5.0),
            max_query_cells: 4 << 20,
            cache_cells: 8 << 20,
            sensor: SensorKind::Erim,
            simulated_time: false,
            compute_time: ComputeTime::Measured,
        }
    }
}

impl LtmConfig {
    /// A map sized for a walking robot of any scale, for images from a legged ISM
    /// (`tca_ism::IsmConfig::legged_simulated`, the Perceptron on the body's mast):
    ///
    /// - cells of `cell_m` (0.1 m suits the Ambler, 0.02 m the small hexapod);
    /// - a square window of `2 * half_side_m` around the body kept in memory; it scrolls to
    ///   the body origin of every image merged (whatever the heading: the window stays
    ///   aligned with the world axes), paging the rest to disk;
    /// - tiles of about an eighth of the window's side (between 8 and 256 cells);
    /// - points mapped up to `2 * half_side_m` horizontally from the scanner, over an
    ///   elevation band of -10..10 m (well inside the Perceptron's 40 m ambiguity interval);
    /// - footfall and slope maps for a foot of radius `foot_radius_m` (the evaluation uses
    ///   at least 1.5 cells, see [`FootParams`]);
    /// - the Perceptron asked for when the module needs an image.
    ///
    /// Everything else is [`LtmConfig::default`]'s. Bad values (not positive, not finite) are
    /// refused by [`LocalTerrainMap::new`] with the reason.
    pub fn for_robot(cell_m: f64, half_side_m: f64, foot_radius_m: f64) -> Self {
        let base = Self::default();
        let tile_cells = if cell_m > 0.0 && half_side_m > 0.0 {
            (half_side_m / (4.0 * cell_m)).round().clamp(8.0, 256.0) as usize
        } else {
            base.tile_cells
        };
        Self {
            builder: BuilderConfig {
                resolution_m: cell_m,
                min_elevation_m: -10.0,
                max_elevation_m: 10.0,
                max_horizontal_range_m: 2.0 * half_side_m,
                ..base.builder.clone()
            },
            window_m: 2.0 * half_side_m,
            tile_cells,
            foot: FootParams {
                radius_m: foot_radius_m,
                ..base.foot
            },
            sensor: SensorKind::Perceptron,
            ..base
        }
    }
}

/// What merging a map did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MergeReport {
    /// Cells whose contents changed.
    pub cells_changed: usize,
    /// The patch's known, occluded and unknown cell counts.
    pub known: usize,
    /// Occluded cells in the patch.
    pub occluded: usize,
    /// Tiles paged out or in by the scroll that followed.
    pub scroll: ScrollReport,
}

/// The local terrain map: build, merge, scroll, query.
#[derive(Debug)]
pub struct LocalTerrainMap {
    config: LtmConfig,
    store: TileStore,
    cache: QueryCache,
    images: u64,
    _temp: Option<tempfile::TempDir>,
}

impl LocalTerrainMap {
    /// An empty map.
    pub fn new(config: LtmConfig) -> Result<Self> {
        config.builder.validate()?;
        if !(config.foot.radius_m.is_finite() && config.foot.radius_m > 0.0) {
            return Err(LtmError::Config(format!(
                "the foot radius must be a positive length, got {} m",
                config.foot.radius_m
            )));
        }
        let (dir, temp) = match &config.store_dir {
            Some(dir) => (dir.clone(), None),
            None => {
                let temp = tempfile::Builder::new()
                    .prefix("tca-ltm-")
                    .tempdir()
                    .map_err(|source| LtmError::Io {
                        path: std::env::temp_dir(),
                        source,
                    })?;
                (temp.path().to_owned(), Some(temp))
            }
        };
        let store = TileStore::open(
            &dir,
            config.builder.resolution_m,
            config.tile_cells,
            config.window_m,
        )?;
        Ok(Self {
            cache: QueryCache::new(config.cache_cells),
            config,
            store,
            images: 0,
            _temp: temp,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &LtmConfig {
        &self.config
    }

    /// Images merged so far.
    pub fn images_merged(&self) -> u64 {
        self.images
    }

    /// The scrolling store of the merged map.
    pub fn store(&self) -> &TileStore {
        &self.store
    }

    /// What the query cache saved so far.
    pub fn cache_stats(&self) -> CacheStats {
        self.cache.stats()
    }

    /// Empties the query cache (the map is unchanged).
    pub fn clear_cache(&mut self) {
        self.cache.clear();
    }

    /// Builds the map of one range image, merges it, and scrolls the window to where the
    /// carriage was when the image was taken.
    pub fn add_image(&mut self, image: &RangeImage) -> Result<MergeReport> {
        let patch = build_map(image, &self.config.builder)?;
        let frames = ImageFrames::of(image)?;
        let body = frames.body_origin_world();
        let mut report = self.merge(&patch)?;
        report.scroll = self.scroll_to(body.x, body.y)?;
        self.images += 1;
        tracing::debug!(
            sequence = image.sequence,
            sensor = ?image.sensor,
            known = report.known,
            occluded = report.occluded,
            changed = report.cells_changed,
            "image merged into the terrain map"
        );
        Ok(report)
    }

    /// Merges a map patch (at the map's resolution) into the map by the maximum-likelihood
    /// rule ([`fuse`]) and invalidates the cached query cells it may change.
    pub fn merge(&mut self, patch: &Patch) -> Result<MergeReport> {
        if patch.resolution_m != self.store.resolution_m() {
            return Err(LtmError::ResolutionMismatch {
                patch_m: patch.resolution_m,
                map_m: self.store.resolution_m(),
            });
        }
        let gate = self.config.merge_gate_sigmas;
        let changed = self
            .store
            .update_with(patch, |old, new| fuse(old, new, gate))?;
        if changed > 0 {
            let (lo, hi) = patch.bounds();
            self.cache
                .invalidate(lo, hi, self.config.foot.radius_m + patch.resolution_m);
        }
        let (_, occluded, known) = patch.counts();
        Ok(MergeReport {
            cells_changed: changed,
            known,
            occluded,
            scroll: ScrollReport::default(),
        })
    }

    /// Moves the scrolling window to the vehicle at `(x, y)`.
    pub fn scroll_to(&mut self, x_m: f64, y_m: f64) -> Result<ScrollReport> {
        self.store.set_center(x_m, y_m)
    }

    /// The map cell containing a world point.
    pub fn cell_at(&self, p: Point2<f64>) -> Result<Cell> {
        let r = self.store.resolution_m();
        self.store
            .cell(lattice_index(p.x, r), lattice_index(p.y, r))
    }

    /// The world rectangle `(min, max)` through the centres of the outermost cells the map
    /// knows anything about (known or occluded, in memory or paged out); `None` while nothing
    /// is mapped. A region query of this rectangle at the map's resolution returns exactly
    /// those cells.
    pub fn mapped_extent(&self) -> Result<Option<(Point2<f64>, Point2<f64>)>> {
        let r = self.store.resolution_m();
        Ok(self.store.mapped_cells()?.map(|((i0, j0), (i1, j1))| {
            (
                Point2::new(i0 as f64 * r, j0 as f64 * r),
                Point2::new(i1 as f64 * r, j1 as f64 * r),
            )
        }))
    }

    /// Checks a region request without answering it.
    pub fn check_region(&self, request: &MapRegion) -> Result<Region> {
        if !matches!(
            request.kind,
            MapKind::Elevation | MapKind::ElevationUncertainty | MapKind::Footfall | MapKind::Slope
        ) {
            return Err(LtmError::UnsupportedKind(request.kind));
        }
        Region::new(
            &request.polygon,
            request.resolution_m,
            self.config.max_query_cells,
        )
    }

    /// Answers a region query (the `refresh` flag is the module's business and ignored here).
    pub fn query(&mut self, request: &MapRegion) -> Result<MapGrid> {
        let region = self.check_region(request)?;
        answer(
            &region,
            request.kind,
            &self.store,
            &mut self.cache,
            &self.config.foot,
        )
    }

    /// Writes every changed tile in memory to the store directory.
    pub fn flush(&mut self) -> Result<usize> {
        self.store.flush()
    }
}
