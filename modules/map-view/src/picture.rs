//! Drawing a map grid to a PNG file with the PDM's renderer, and what was drawn.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use serde::Serialize;
use tca_pdm::RenderOptions;
use tca_single_leg_messages::{MapCell, MapGrid, Overlay};

use super::request::kind_name;

/// What a `tca map` run drew (printed as one line, or as JSON with `--json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapPicture {
    /// The PNG file.
    pub path: PathBuf,
    /// The map kind, by its command-line name.
    pub kind: &'static str,
    /// Cells along X.
    pub nx: u32,
    /// Cells along Y.
    pub ny: u32,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// West edge of the grid, metres (world X).
    pub x_min_m: f64,
    /// East edge of the grid, metres.
    pub x_max_m: f64,
    /// South edge of the grid, metres (world Y).
    pub y_min_m: f64,
    /// North edge of the grid, metres.
    pub y_max_m: f64,
    /// Cells with a value.
    pub known_cells: usize,
    /// Cells hidden behind something.
    pub occluded_cells: usize,
    /// Cells never seen or outside the polygon.
    pub unknown_cells: usize,
    /// Picture width, pixels.
    pub width_px: u32,
    /// Picture height, pixels.
    pub height_px: u32,
    /// Range images the map was built from (from a log; `None` for a running system).
    pub images: Option<usize>,
    /// The map as it stood this many seconds into the log (`None`: at the end).
    pub at_s: Option<f64>,
    /// Footfalls drawn over the map.
    pub footfalls: usize,
    /// Who drew the picture: `tca map`, or the running system's PDM.
    pub drawn_by: &'static str,
}

impl MapPicture {
    /// Describes `grid` drawn as a `width_px x height_px` picture at `path`.
    pub fn describe(grid: &MapGrid, path: &Path, width_px: u32, height_px: u32) -> Self {
        let (mut known, mut occluded, mut unknown) = (0, 0, 0);
        for cell in &grid.cells {
            match cell {
                MapCell::Known { .. } => known += 1,
                MapCell::Occluded { .. } => occluded += 1,
                MapCell::Unknown => unknown += 1,
            }
        }
        let half = 0.5 * grid.resolution_m;
        Self {
            path: path.to_owned(),
            kind: kind_name(grid.kind),
            nx: grid.nx,
            ny: grid.ny,
            resolution_m: grid.resolution_m,
            x_min_m: grid.origin_x_m - half,
            x_max_m: grid.origin_x_m - half + f64::from(grid.nx) * grid.resolution_m,
            y_min_m: grid.origin_y_m - half,
            y_max_m: grid.origin_y_m - half + f64::from(grid.ny) * grid.resolution_m,
            known_cells: known,
            occluded_cells: occluded,
            unknown_cells: unknown,
            width_px,
            height_px,
            images: None,
            at_s: None,
            footfalls: 0,
            drawn_by: "tca map",
        }
    }

    /// One line for people.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "wrote {}: {} map, {} x {} cells at {} m (x {:.2} to {:.2} m, y {:.2} to {:.2} m), \
             {} known, {} occluded, {} unknown; {} x {} px",
            self.path.display(),
            self.kind,
            self.nx,
            self.ny,
            self.resolution_m,
            self.x_min_m,
            self.x_max_m,
            self.y_min_m,
            self.y_max_m,
            self.known_cells,
            self.occluded_cells,
            self.unknown_cells,
            self.width_px,
            self.height_px
        );
        if let Some(n) = self.images {
            s.push_str(&format!("; from {n} range images"));
        }
        if let Some(t) = self.at_s {
            s.push_str(&format!(" up to {t:.1} s"));
        }
        if self.footfalls > 0 {
            s.push_str(&format!("; {} footfalls", self.footfalls));
        }
        if self.drawn_by != "tca map" {
            s.push_str(&format!("; drawn by the {}", self.drawn_by));
        }
        s
    }
}

/// Draws `grid` with `overlays` to the PNG file `path` (PDM defaults: cells coloured by
/// value, unknown and occluded patterned, colour and distance scales).
pub fn draw(grid: &MapGrid, overlays: &[Overlay], path: &Path) -> anyhow::Result<MapPicture> {
    let picture = tca_pdm::render(grid, overlays, &RenderOptions::default())
        .context("the map cannot be drawn")?;
    picture.write_png(path).map_err(|e| {
        anyhow::anyhow!("{e}; check that the picture's directory exists and is writable")
    })?;
    let mut described = MapPicture::describe(grid, path, picture.width(), picture.height());
    described.footfalls = overlays
        .iter()
        .filter(|o| matches!(o, Overlay::Point { .. }))
        .count();
    Ok(described)
}

/// The width and height of a PNG file, pixels (for pictures drawn by another process).
pub fn png_size(path: &Path) -> anyhow::Result<(u32, u32)> {
    let file = std::fs::File::open(path)
        .with_context(|| format!("cannot read the picture {}", path.display()))?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .with_context(|| format!("{} is not a PNG picture", path.display()))?;
    let info = reader.info();
    Ok((info.width, info.height))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_single_leg_messages::MapKind;

    #[test]
    fn a_drawn_grid_is_described_by_its_cells_and_extent() {
        let grid = MapGrid {
            kind: MapKind::Slope,
            origin_x_m: 1.0,
            origin_y_m: 2.0,
            resolution_m: 0.5,
            nx: 3,
            ny: 2,
            cells: vec![
                MapCell::Known {
                    value: 0.1,
                    sigma_m: 0.01,
                },
                MapCell::Occluded {
                    max_elevation_m: 0.3,
                },
                MapCell::Unknown,
                MapCell::Unknown,
                MapCell::Known {
                    value: 0.2,
                    sigma_m: 0.01,
                },
                MapCell::Unknown,
            ],
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.png");
        let d = draw(&grid, &[], &path).unwrap();
        assert_eq!(
            (d.known_cells, d.occluded_cells, d.unknown_cells),
            (2, 1, 3)
        );
        assert_eq!(
            (d.x_min_m, d.x_max_m, d.y_min_m, d.y_max_m),
            (0.75, 2.25, 1.75, 2.75)
        );
        assert_eq!(png_size(&path).unwrap(), (d.width_px, d.height_px));
        assert!(
            d.summary().contains("slope map, 3 x 2 cells"),
            "{}",
            d.summary()
        );
        let e = draw(&grid, &[], &dir.path().join("no/such/dir/m.png")).unwrap_err();
        assert!(format!("{e:#}").contains("directory exists"), "{e:#}");
    }
}
