//! The LTM Scroller (§5.2.2, §5.3): the merged map lives in square tiles of the lattice; only
//! tiles meeting a window (20 x 20 m by default) centred on the vehicle stay in memory. Tiles
//! leaving the window are written to disk ([`crate::tile_file`]) and dropped; tiles on disk
//! that the window reaches again are read back, so walking backward uses the maps built
//! walking forward (§7.2). Reads of areas outside the window go to disk without making the
//! tiles resident.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use nalgebra::Point2;

use crate::cell::{Cell, CellState};
use crate::error::{LtmError, Result, check_resolution};
use crate::patch::Patch;
use crate::tile_file;

/// A tile's indices: it holds lattice cells `tx*T .. tx*T + T` by `ty*T .. ty*T + T`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TileKey {
    /// Tile column.
    pub tx: i64,
    /// Tile row.
    pub ty: i64,
}

#[derive(Debug, Clone)]
struct Tile {
    cells: Vec<Cell>,
    /// Changed since it was last written to disk (or never written).
    dirty: bool,
}

/// An inclusive rectangle of lattice cells: `((i_min, j_min), (i_max, j_max))`.
pub type CellBounds = ((i64, i64), (i64, i64));

/// What a scroll did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ScrollReport {
    /// Tiles written to disk and dropped from memory.
    pub paged_out: usize,
    /// Tiles read back from disk into memory.
    pub paged_in: usize,
}

/// The tiled, scrolling store of the merged map.
#[derive(Debug)]
pub struct TileStore {
    dir: PathBuf,
    resolution_m: f64,
    side: usize,
    window_m: f64,
    center: Option<Point2<f64>>,
    resident: HashMap<TileKey, Tile>,
    on_disk: HashSet<TileKey>,
}

impl TileStore {
    /// A store of `side x side`-cell tiles at `resolution_m`, keeping in memory the tiles that
    /// meet a `window_m` square around the vehicle, paging to `dir` (created if missing).
    /// Tiles already in `dir` (from an earlier run at the same resolution and side) are part of
    /// the map.
    pub fn open(
        dir: impl AsRef<Path>,
        resolution_m: f64,
        side: usize,
        window_m: f64,
    ) -> Result<Self> {
        check_resolution("map", resolution_m)?;
        if side == 0 || side > 4096 {
            return Err(LtmError::Config(format!(
                "tile side {side} cells is not in 1..=4096"
            )));
        }
        if !(window_m.is_finite() && window_m > 0.0) {
            return Err(LtmError::Config(format!(
                "the scrolling window must be a positive size, got {window_m} m"
            )));
        }
        let dir = dir.as_ref().to_owned();
        let io = |source| LtmError::Io {
            path: dir.clone(),
            source,
        };
        std::fs::create_dir_all(&dir).map_err(io)?;
        let mut on_disk = HashSet::new();
        for entry in std::fs::read_dir(&dir).map_err(io)? {
            let name = entry.map_err(io)?.file_name();
            if let Some((tx, ty)) = name.to_str().and_then(tile_file::parse_tile_name) {
                on_disk.insert(TileKey { tx, ty });
            }
        }
        Ok(Self {
            dir,
            resolution_m,
            side,
            window_m,
            center: None,
            resident: HashMap::new(),
            on_disk,
        })
    }

    /// Cell size, metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Cells per tile side.
    pub fn tile_side(&self) -> usize {
        self.side
    }

    /// The directory tiles are paged to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The window's centre (the vehicle), once set.
    pub fn center(&self) -> Option<Point2<f64>> {
        self.center
    }

    /// Tiles in memory.
    pub fn resident_tiles(&self) -> usize {
        self.resident.len()
    }

    /// Tiles that have a copy on disk.
    pub fn tiles_on_disk(&self) -> usize {
        self.on_disk.len()
    }

    /// Whether tile `key` is in memory.
    pub fn is_resident(&self, key: TileKey) -> bool {
        self.resident.contains_key(&key)
    }

    /// The tile holding lattice cell `(i, j)` and the cell's index in it.
    pub fn locate(&self, i: i64, j: i64) -> (TileKey, usize) {
        let s = self.side as i64;
        let key = TileKey {
            tx: i.div_euclid(s),
            ty: j.div_euclid(s),
        };
        let local = (j.rem_euclid(s) * s + i.rem_euclid(s)) as usize;
        (key, local)
    }

    fn tile_rect(&self, key: TileKey) -> (Point2<f64>, Point2<f64>) {
        let s = self.side as f64;
        let r = self.resolution_m;
        (
            Point2::new((key.tx as f64 * s - 0.5) * r, (key.ty as f64 * s - 0.5) * r),
            Point2::new(
                ((key.tx as f64 + 1.0) * s - 0.5) * r,
                ((key.ty as f64 + 1.0) * s - 0.5) * r,
            ),
        )
    }

    /// Whether tile `key` meets the window (always, before the window is set).
    pub fn in_window(&self, key: TileKey) -> bool {
        let Some(c) = self.center else {
            return true;
        };
        let h = 0.5 * self.window_m;
        let (lo, hi) = self.tile_rect(key);
        lo.x < c.x + h && hi.x > c.x - h && lo.y < c.y + h && hi.y > c.y - h
    }

    fn read_tile(&self, key: TileKey) -> Result<Vec<Cell>> {
        let path = tile_file::tile_path(&self.dir, key.tx, key.ty);
        let bytes = std::fs::read(&path).map_err(|source| LtmError::Io {
            path: path.clone(),
            source,
        })?;
        tile_file::decode(&bytes, &path, self.side, self.resolution_m, key.tx, key.ty)
    }

    fn write_tile(&self, key: TileKey, tile: &Tile) -> Result<()> {
        let path = tile_file::tile_path(&self.dir, key.tx, key.ty);
        let bytes = tile_file::encode(self.side, self.resolution_m, key.tx, key.ty, &tile.cells);
        // Write then rename, so a crash never leaves a half-written tile.
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, bytes)
            .and_then(|()| std::fs::rename(&tmp, &path))
            .map_err(|source| LtmError::Io { path, source })
    }

    /// The tile `key` in memory, read from disk or created unknown.
    fn tile_mut(&mut self, key: TileKey) -> Result<&mut Tile> {
        if !self.resident.contains_key(&key) {
            let tile = if self.on_disk.contains(&key) {
                Tile {
                    cells: self.read_tile(key)?,
                    dirty: false,
                }
            } else {
                Tile {
                    cells: vec![Cell::UNKNOWN; self.side * self.side],
                    dirty: true,
                }
            };
            self.resident.insert(key, tile);
        }
        self.resident
            .get_mut(&key)
            .ok_or_else(|| LtmError::Config("tile vanished from memory".into()))
    }

    /// Applies `f` to every cell of the lattice rectangle `i_range x j_range` with the patch
    /// cell there, tile by tile (the tiles are made resident). Returns the cells changed.
    pub fn update_with(
        &mut self,
        patch: &Patch,
        mut f: impl FnMut(Cell, Cell) -> Cell,
    ) -> Result<usize> {
        if patch.nx == 0 || patch.ny == 0 {
            return Ok(0);
        }
        let s = self.side as i64;
        let (i_end, j_end) = (patch.i0 + patch.nx as i64, patch.j0 + patch.ny as i64);
        let mut changed = 0;
        for ty in patch.j0.div_euclid(s)..=(j_end - 1).div_euclid(s) {
            for tx in patch.i0.div_euclid(s)..=(i_end - 1).div_euclid(s) {
                let key = TileKey { tx, ty };
                // Skip tiles the patch knows nothing about.
                let (ia, ib) = ((tx * s).max(patch.i0), ((tx + 1) * s).min(i_end));
                let (ja, jb) = ((ty * s).max(patch.j0), ((ty + 1) * s).min(j_end));
                let any =
                    (ja..jb).any(|j| (ia..ib).any(|i| patch.get(i, j).state != CellState::Unknown));
                if !any {
                    continue;
                }
                let tile = self.tile_mut(key)?;
                for j in ja..jb {
                    for i in ia..ib {
                        let new = patch.get(i, j);
                        if new.state == CellState::Unknown {
                            continue;
                        }
                        let local = ((j - ty * s) * s + (i - tx * s)) as usize;
                        if let Some(cell) = tile.cells.get_mut(local) {
                            let fused = f(*cell, new);
                            if fused != *cell {
                                *cell = fused;
                                tile.dirty = true;
                                changed += 1;
                            }
                        }
                    }
                }
            }
        }
        Ok(changed)
    }

    /// The cells of the lattice rectangle starting at `(i0, j0)`, `nx x ny`: from memory, or
    /// from disk for tiles paged out (not made resident).
    pub fn extract(&self, i0: i64, j0: i64, nx: usize, ny: usize) -> Result<Patch> {
        let mut patch = Patch::unknown(i0, j0, nx, ny, self.resolution_m);
        if nx == 0 || ny == 0 {
            return Ok(patch);
        }
        let s = self.side as i64;
        let (i_end, j_end) = (i0 + nx as i64, j0 + ny as i64);
        for ty in j0.div_euclid(s)..=(j_end - 1).div_euclid(s) {
            for tx in i0.div_euclid(s)..=(i_end - 1).div_euclid(s) {
                let key = TileKey { tx, ty };
                let loaded;
                let cells: &[Cell] = if let Some(t) = self.resident.get(&key) {
                    &t.cells
                } else if self.on_disk.contains(&key) {
                    loaded = self.read_tile(key)?;
                    &loaded
                } else {
                    continue;
                };
                let (ia, ib) = ((tx * s).max(i0), ((tx + 1) * s).min(i_end));
                let (ja, jb) = ((ty * s).max(j0), ((ty + 1) * s).min(j_end));
                for j in ja..jb {
                    for i in ia..ib {
                        let local = ((j - ty * s) * s + (i - tx * s)) as usize;
                        if let (Some(dst), Some(src)) = (patch.get_mut(i, j), cells.get(local)) {
                            *dst = *src;
                        }
                    }
                }
            }
        }
        Ok(patch)
    }

    /// The cell at lattice `(i, j)` (from memory or disk).
    pub fn cell(&self, i: i64, j: i64) -> Result<Cell> {
        Ok(self.extract(i, j, 1, 1)?.get(i, j))
    }

    /// The lattice cells the map knows anything about (known or occluded), in memory or on
    /// disk, as the smallest index rectangle `((i_min, j_min), (i_max, j_max))` holding them
    /// all; `None` while the map is empty. Reads every tile on disk that is not in memory.
    pub fn mapped_cells(&self) -> Result<Option<CellBounds>> {
        let s = self.side as i64;
        let mut bounds: Option<CellBounds> = None;
        let mut include = |key: TileKey, cells: &[Cell]| {
            for (k, cell) in cells.iter().enumerate() {
                if cell.state == CellState::Unknown {
                    continue;
                }
                let k = k as i64;
                let (i, j) = (key.tx * s + k % s, key.ty * s + k / s);
                bounds = Some(match bounds {
                    None => ((i, j), (i, j)),
                    Some(((i0, j0), (i1, j1))) => ((i0.min(i), j0.min(j)), (i1.max(i), j1.max(j))),
                });
            }
        };
        for (key, tile) in &self.resident {
            include(*key, &tile.cells);
        }
        let mut on_disk: Vec<TileKey> = self
            .on_disk
            .iter()
            .copied()
            .filter(|k| !self.resident.contains_key(k))
            .collect();
        on_disk.sort();
        for key in on_disk {
            include(key, &self.read_tile(key)?);
        }
        Ok(bounds)
    }

    /// Moves the window's centre to the vehicle at `(x, y)`: tiles leaving the window are
    /// written to disk (if changed) and dropped; tiles on disk inside it are read back.
    pub fn set_center(&mut self, x_m: f64, y_m: f64) -> Result<ScrollReport> {
        if !(x_m.is_finite() && y_m.is_finite()) {
            return Err(LtmError::Config(format!(
                "the vehicle position ({x_m}, {y_m}) is not finite"
            )));
        }
        self.center = Some(Point2::new(x_m, y_m));
        let mut report = ScrollReport::default();
        let leaving: Vec<TileKey> = self
            .resident
            .keys()
            .copied()
            .filter(|&k| !self.in_window(k))
            .collect();
        for key in leaving {
            self.page_out(key)?;
            report.paged_out += 1;
        }
        // Read back the tiles on disk that the window meets.
        let entering: Vec<TileKey> = self
            .on_disk
            .iter()
            .copied()
            .filter(|k| !self.resident.contains_key(k) && self.in_window(*k))
            .collect();
        for key in entering {
            self.tile_mut(key)?;
            report.paged_in += 1;
        }
        if report != ScrollReport::default() {
            tracing::debug!(
                x_m,
                y_m,
                ?report,
                resident = self.resident.len(),
                "map scrolled"
            );
        }
        Ok(report)
    }

    fn page_out(&mut self, key: TileKey) -> Result<()> {
        if let Some(tile) = self.resident.get(&key) {
            let empty = tile.cells.iter().all(|c| c.state == CellState::Unknown);
            if tile.dirty && !empty {
                self.write_tile(key, tile)?;
                self.on_disk.insert(key);
            }
        }
        self.resident.remove(&key);
        Ok(())
    }

    /// Writes every changed resident tile to disk (they stay in memory).
    pub fn flush(&mut self) -> Result<usize> {
        let dirty: Vec<TileKey> = self
            .resident
            .iter()
            .filter(|(_, t)| t.dirty && t.cells.iter().any(|c| c.state != CellState::Unknown))
            .map(|(k, _)| *k)
            .collect();
        for key in &dirty {
            if let Some(tile) = self.resident.get(key) {
                self.write_tile(*key, tile)?;
            }
            self.on_disk.insert(*key);
            if let Some(tile) = self.resident.get_mut(key) {
                tile.dirty = false;
            }
        }
        Ok(dirty.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch_with(i0: i64, j0: i64, n: usize, f: impl Fn(i64, i64) -> Cell) -> Patch {
        let mut p = Patch::unknown(i0, j0, n, n, 0.1);
        for j in j0..j0 + n as i64 {
            for i in i0..i0 + n as i64 {
                if let Some(c) = p.get_mut(i, j) {
                    *c = f(i, j);
                }
            }
        }
        p
    }

    #[test]
    fn cells_scrolled_out_and_back_are_unchanged() {
        let dir = tempfile::tempdir().unwrap();
        let mut store = TileStore::open(dir.path(), 0.1, 16, 20.0).unwrap();
        store.set_center(0.0, 0.0).unwrap();
        let patch = patch_with(-40, -40, 80, |i, j| {
            Cell::known(
                (i as f32).sin() + j as f32 * 0.01,
                0.01 + (j.abs() as f32) * 1e-4,
            )
        });
        store.update_with(&patch, |_, new| new).unwrap();
        let before = store.extract(-40, -40, 80, 80).unwrap();
        assert_eq!(before, patch);
        // Walk 50 m away: everything leaves the window and goes to disk.
        let out = store.set_center(0.0, 50.0).unwrap();
        assert!(out.paged_out >= 25, "{out:?}");
        assert!(!store.is_resident(store.locate(0, 0).0));
        assert!(store.tiles_on_disk() >= 25);
        // Reads outside the window come from disk.
        assert_eq!(store.extract(-40, -40, 80, 80).unwrap(), patch);
        // Walk back: the tiles are read back, unchanged.
        let back = store.set_center(0.0, 0.0).unwrap();
        assert!(back.paged_in >= 25, "{back:?}");
        assert!(store.is_resident(store.locate(0, 0).0));
        assert_eq!(store.extract(-40, -40, 80, 80).unwrap(), patch);
    }

    #[test]
    fn the_window_bounds_memory() {
        let dir = tempfile::tempdir().unwrap();
        let mut store = TileStore::open(dir.path(), 0.1, 20, 20.0).unwrap();
        // A 60 m strip mapped while walking along it.
        for step in 0..30 {
            let y = step as f64 * 2.0;
            store.set_center(3.0, y).unwrap();
            let p = patch_with(0, (y / 0.1) as i64, 60, |_, _| Cell::known(0.0, 0.01));
            store.update_with(&p, |_, n| n).unwrap();
            // Tiles meeting a 20 m window of 2 m tiles: at most 11 x 11.
            assert!(store.resident_tiles() <= 121, "{}", store.resident_tiles());
        }
        assert!(store.tiles_on_disk() > 0);
    }

    #[test]
    fn a_reopened_store_sees_flushed_tiles() {
        let dir = tempfile::tempdir().unwrap();
        {
            let mut store = TileStore::open(dir.path(), 0.1, 8, 20.0).unwrap();
            let p = patch_with(3, 3, 4, |i, _| Cell::occluded(i as f32));
            store.update_with(&p, |_, n| n).unwrap();
            assert_eq!(store.flush().unwrap(), 1);
        }
        let store = TileStore::open(dir.path(), 0.1, 8, 20.0).unwrap();
        assert_eq!(store.cell(5, 4).unwrap(), Cell::occluded(5.0));
        let wrong = TileStore::open(dir.path(), 0.2, 8, 20.0).unwrap();
        assert!(
            wrong
                .cell(5, 4)
                .unwrap_err()
                .to_string()
                .contains("not valid")
        );
    }

    #[test]
    fn mapped_cells_span_memory_and_disk() {
        let dir = tempfile::tempdir().unwrap();
        let mut store = TileStore::open(dir.path(), 0.1, 16, 20.0).unwrap();
        assert_eq!(store.mapped_cells().unwrap(), None);
        store.set_center(0.0, 0.0).unwrap();
        let near = patch_with(-3, 2, 5, |_, _| Cell::known(0.0, 0.01));
        store.update_with(&near, |_, n| n).unwrap();
        assert_eq!(store.mapped_cells().unwrap(), Some(((-3, 2), (1, 6))));
        // Far away, then scrolled out to disk: still counted.
        store.set_center(0.0, 100.0).unwrap();
        let far = patch_with(10, 990, 3, |_, _| Cell::occluded(1.0));
        store.update_with(&far, |_, n| n).unwrap();
        store.set_center(0.0, 200.0).unwrap();
        assert_eq!(store.resident_tiles(), 0);
        assert_eq!(store.mapped_cells().unwrap(), Some(((-3, 2), (12, 992))));
    }

    #[test]
    fn bad_parameters_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert!(TileStore::open(dir.path(), 0.0, 8, 20.0).is_err());
        assert!(TileStore::open(dir.path(), 0.1, 0, 20.0).is_err());
        assert!(TileStore::open(dir.path(), 0.1, 8, f64::NAN).is_err());
        let mut s = TileStore::open(dir.path(), 0.1, 8, 20.0).unwrap();
        assert!(s.set_center(f64::NAN, 0.0).is_err());
    }
}
