//! Drawing a map grid (§5.2.3): cells coloured by value through a colour ramp, unknown cells
//! as a grey checkerboard and occluded cells as magenta hatching (so neither can be mistaken
//! for a value), a title, a colour scale with its values and units, a distance scale bar, the
//! map's world extent, and overlays of 3D positions (planned footfalls) and paths (leg paths)
//! drawn at their X, Y.
//!
//! North (world +Y) is up and east (world +X) is right.

use std::path::Path;

use tca_single_leg_messages::{MapCell, MapGrid, MapKind, Overlay, WorldPoint};

use crate::error::{PdmError, Result};
use tca_canvas::{Canvas, Rgb, font};

/// Largest number of cells drawn along a side.
pub const MAX_CELLS_PER_SIDE: u32 = 4096;

/// How to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Target size in pixels of the map's longer side (cells are drawn as squares of a whole
    /// number of pixels, between 1 and `max_cell_px`).
    pub map_px: u32,
    /// Largest square drawn per cell, pixels.
    pub max_cell_px: u32,
    /// Values mapped to the ends of the colour ramp; `None`: the known cells' range.
    pub value_range: Option<(f32, f32)>,
    /// A title; `None`: the map kind, size and resolution.
    pub title: Option<String>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            map_px: 640,
            max_cell_px: 24,
            value_range: None,
            title: None,
        }
    }
}

/// Background colour.
pub const BACKGROUND: Rgb = [255, 255, 255];
/// Text and frame colour.
pub const INK: Rgb = [20, 20, 20];
/// The two colours of the unknown cells' checkerboard.
pub const UNKNOWN_COLOURS: [Rgb; 2] = [[176, 176, 176], [222, 222, 222]];
/// The two colours of the occluded cells' hatching.
pub const OCCLUDED_COLOURS: [Rgb; 2] = [[225, 0, 225], [255, 255, 255]];
/// Colour of overlays.
pub const OVERLAY: Rgb = [230, 20, 20];

/// The colour ramp, from low (dark violet) through blue, teal and green to high (yellow).
const RAMP: [(f32, Rgb); 5] = [
    (0.0, [48, 18, 59]),
    (0.25, [40, 100, 190]),
    (0.5, [30, 170, 150]),
    (0.75, [140, 210, 60]),
    (1.0, [250, 240, 80]),
];

/// The ramp's colour at `t` in [0, 1] (clamped; NaN reads as 0).
pub fn ramp(t: f32) -> Rgb {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    for w in RAMP.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let f = (t - t0) / (t1 - t0);
            let mix =
                |a: u8, b: u8| (f32::from(a) + f * (f32::from(b) - f32::from(a))).round() as u8;
            return [mix(c0[0], c1[0]), mix(c0[1], c1[1]), mix(c0[2], c1[2])];
        }
    }
    RAMP[RAMP.len() - 1].1
}

/// The pattern colour of an unknown cell at picture pixel `(x, y)`.
pub fn unknown_colour(x: i64, y: i64) -> Rgb {
    UNKNOWN_COLOURS[((x.div_euclid(4) + y.div_euclid(4)) & 1) as usize]
}

/// The pattern colour of an occluded cell at picture pixel `(x, y)`.
pub fn occluded_colour(x: i64, y: i64) -> Rgb {
    OCCLUDED_COLOURS[((x + y).div_euclid(3) & 1) as usize]
}

/// The value a known cell is coloured by: its standard deviation for
/// [`MapKind::ElevationUncertainty`], its value otherwise.
pub fn shown_value(kind: MapKind, cell: &MapCell) -> Option<f32> {
    match *cell {
        MapCell::Known { value, sigma_m } => {
            let v = if kind == MapKind::ElevationUncertainty {
                sigma_m
            } else {
                value
            };
            v.is_finite().then_some(v)
        }
        _ => None,
    }
}

fn units(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Elevation => "ELEVATION M",
        MapKind::ElevationUncertainty => "SIGMA M",
        MapKind::Footfall => "FOOTFALL COST M",
        MapKind::Slope => "SLOPE RAD",
        MapKind::Reachability => "REACHABLE 1 0",
    }
}

fn check(grid: &MapGrid) -> Result<()> {
    if grid.nx == 0 || grid.ny == 0 {
        return Err(PdmError::BadGrid(format!(
            "it has {} x {} cells; a map needs at least one",
            grid.nx, grid.ny
        )));
    }
    if grid.nx > MAX_CELLS_PER_SIDE || grid.ny > MAX_CELLS_PER_SIDE {
        return Err(PdmError::TooLarge {
            nx: grid.nx,
            ny: grid.ny,
            limit: MAX_CELLS_PER_SIDE,
        });
    }
    let expected = grid.nx as usize * grid.ny as usize;
    if grid.cells.len() != expected {
        return Err(PdmError::BadGrid(format!(
            "{} x {} cells need {expected} values but {} were given",
            grid.nx,
            grid.ny,
            grid.cells.len()
        )));
    }
    if !(grid.resolution_m.is_finite() && grid.resolution_m > 0.0) {
        return Err(PdmError::BadGrid(format!(
            "its resolution {} m is not a positive length",
            grid.resolution_m
        )));
    }
    if !(grid.origin_x_m.is_finite() && grid.origin_y_m.is_finite()) {
        return Err(PdmError::BadGrid(format!(
            "its origin ({}, {}) is not finite",
            grid.origin_x_m, grid.origin_y_m
        )));
    }
    Ok(())
}

/// Formats a value with as many decimals as its range needs.
fn format_value(v: f32, span: f32) -> String {
    let decimals = if span >= 10.0 {
        1
    } else if span >= 0.5 {
        2
    } else {
        3
    };
    format!("{v:.decimals$}")
}

/// A "round" length (1, 2 or 5 times a power of ten) near `target`.
fn nice_length(target: f64) -> f64 {
    if !(target.is_finite() && target > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(target.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .rfind(|&l| l <= target)
        .unwrap_or(p)
}

/// Where the map sits in the picture [`render`] draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapLayout {
    /// Picture column of the map's left edge.
    pub x: i64,
    /// Picture row of the map's top edge.
    pub y: i64,
    /// Pixels per cell side.
    pub cell_px: i64,
    grid_nx: i64,
    grid_ny: i64,
    origin: (f64, f64),
    res: f64,
}

/// Top margin, title height and gap: the map starts this far down.
const MAP_TOP: i64 = 12 + 2 * font::HEIGHT as i64 + 10;

impl MapLayout {
    /// The layout of `grid` drawn with `options`.
    pub fn of(grid: &MapGrid, options: &RenderOptions) -> Result<Self> {
        check(grid)?;
        let (nx, ny) = (i64::from(grid.nx), i64::from(grid.ny));
        let cell_px = (i64::from(options.map_px) / nx.max(ny))
            .clamp(1, i64::from(options.max_cell_px.max(1)));
        Ok(Self {
            x: 12,
            y: MAP_TOP,
            cell_px,
            grid_nx: nx,
            grid_ny: ny,
            origin: (grid.origin_x_m, grid.origin_y_m),
            res: grid.resolution_m,
        })
    }

    /// The picture pixel at the centre of cell `(ix, iy)`.
    pub fn cell_center(&self, ix: u32, iy: u32) -> (u32, u32) {
        let x = self.x + i64::from(ix) * self.cell_px + self.cell_px / 2;
        let y = self.y + (self.grid_ny - 1 - i64::from(iy)) * self.cell_px + self.cell_px / 2;
        (x.max(0) as u32, y.max(0) as u32)
    }

    /// Map width in pixels.
    pub fn width(&self) -> i64 {
        self.grid_nx * self.cell_px
    }

    /// Map height in pixels.
    pub fn height(&self) -> i64 {
        self.grid_ny * self.cell_px
    }

    /// Picture coordinates of a world point's X, Y.
    pub fn to_picture(&self, p: &WorldPoint) -> Option<(f64, f64)> {
        let gx = (p.x_m - self.origin.0) / self.res + 0.5;
        let gy = (p.y_m - self.origin.1) / self.res + 0.5;
        let x = self.x as f64 + gx * self.cell_px as f64;
        let y = self.y as f64 + (self.grid_ny as f64 - gy) * self.cell_px as f64;
        (x.is_finite() && y.is_finite()).then_some((x, y))
    }

    fn contains(&self, (x, y): (f64, f64)) -> bool {
        x >= self.x as f64
            && y >= self.y as f64
            && x <= (self.x + self.width()) as f64
            && y <= (self.y + self.height()) as f64
    }

    /// Clips a segment to the map (Liang–Barsky).
    fn clip(&self, a: (f64, f64), b: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let bounds = [
            (-dx, a.0 - self.x as f64),
            (dx, (self.x + self.width()) as f64 - a.0),
            (-dy, a.1 - self.y as f64),
            (dy, (self.y + self.height()) as f64 - a.1),
        ];
        for (p, q) in bounds {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        (t0 <= t1).then_some((
            (a.0 + t0 * dx, a.1 + t0 * dy),
            (a.0 + t1 * dx, a.1 + t1 * dy),
        ))
    }
}

/// Draws a map grid with overlays.
pub fn render(grid: &MapGrid, overlays: &[Overlay], options: &RenderOptions) -> Result<Canvas> {
    let area = MapLayout::of(grid, options)?;
    let (nx, ny) = (area.grid_nx, area.grid_ny);
    let cell_px = area.cell_px;
    let values: Vec<f32> = grid
        .cells
        .iter()
        .filter_map(|c| shown_value(grid.kind, c))
        .collect();
    let (lo, hi) = match options.value_range {
        Some((a, b)) if a.is_finite() && b.is_finite() && b > a => (a, b),
        _ if values.is_empty() => (0.0, 1.0),
        _ => {
            let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            if hi > lo {
                (lo, hi)
            } else {
                (lo - 0.5, hi + 0.5)
            }
        }
    };
    const M: i64 = 12;
    const LEGEND_BAR: i64 = 16;
    let title = options.title.clone().unwrap_or_else(|| {
        format!(
            "{} {}X{} AT {} M",
            units(grid.kind).split(' ').next().unwrap_or(""),
            grid.nx,
            grid.ny,
            grid.resolution_m
        )
    });
    let bar_h = area.height().max(160);
    let legend_x = area.x + area.width() + 20;
    let label_w = i64::from(font::text_width("-00000.000", 1))
        .max(i64::from(font::text_width(units(grid.kind), 1)));
    let width = (legend_x + LEGEND_BAR + 8 + label_w + M)
        .max(M + i64::from(font::text_width(&title, 2)) + M)
        .max(
            M + i64::from(font::text_width(
                "X -0000.00 TO -0000.00 M   Y -0000.00 TO -0000.00 M",
                1,
            )) + M,
        );
    let below_map = area.y + area.height() + 12 + 40;
    let below_legend = area.y + bar_h + 20 + 2 * 22;
    let height = below_map.max(below_legend) + M;
    let mut pic = Canvas::new(width as u32, height as u32, BACKGROUND);

    pic.text(M, M, &title, 2, INK);
    // Cells, north up.
    for (k, cell) in grid.cells.iter().enumerate() {
        let (ix, iy) = (k as i64 % nx, k as i64 / nx);
        let x0 = area.x + ix * cell_px;
        let y0 = area.y + (ny - 1 - iy) * cell_px;
        for y in y0..y0 + cell_px {
            for x in x0..x0 + cell_px {
                let c = match cell {
                    MapCell::Occluded { .. } => occluded_colour(x, y),
                    _ => match shown_value(grid.kind, cell) {
                        Some(v) => ramp((v - lo) / (hi - lo)),
                        None => unknown_colour(x, y),
                    },
                };
                pic.set(x, y, c);
            }
        }
    }
    pic.outline_rect(
        area.x - 1,
        area.y - 1,
        area.width() + 2,
        area.height() + 2,
        INK,
    );

    // Colour scale.
    for y in 0..bar_h {
        let t = 1.0 - y as f32 / (bar_h - 1).max(1) as f32;
        pic.fill_rect(legend_x, area.y + y, LEGEND_BAR, 1, ramp(t));
    }
    pic.outline_rect(legend_x - 1, area.y - 1, LEGEND_BAR + 2, bar_h + 2, INK);
    let span = hi - lo;
    let text_x = legend_x + LEGEND_BAR + 6;
    for (t, dy) in [(1.0f32, 0), (0.5, bar_h / 2 - 3), (0.0, bar_h - 7)] {
        pic.fill_rect(legend_x + LEGEND_BAR, area.y + dy + 3, 4, 1, INK);
        pic.text(
            text_x,
            area.y + dy,
            &format_value(lo + t * span, span),
            1,
            INK,
        );
    }
    pic.text(legend_x, area.y + bar_h + 8, units(grid.kind), 1, INK);
    // Swatches.
    let sw_y = area.y + bar_h + 24;
    for (n, (label, occluded)) in [("UNKNOWN", false), ("OCCLUDED", true)]
        .into_iter()
        .enumerate()
    {
        let y0 = sw_y + n as i64 * 22;
        for y in y0..y0 + LEGEND_BAR {
            for x in legend_x..legend_x + LEGEND_BAR {
                let c = if occluded {
                    occluded_colour(x, y)
                } else {
                    unknown_colour(x, y)
                };
                pic.set(x, y, c);
            }
        }
        pic.outline_rect(legend_x - 1, y0 - 1, LEGEND_BAR + 2, LEGEND_BAR + 2, INK);
        pic.text(text_x, y0 + 4, label, 1, INK);
    }

    // Distance scale bar: a round length near a quarter of the map's width.
    let map_w_m = grid.nx as f64 * grid.resolution_m;
    let len_m = nice_length(map_w_m / 4.0);
    let len_px = ((len_m / grid.resolution_m) * cell_px as f64)
        .round()
        .max(1.0) as i64;
    let sy = area.y + area.height() + 12;
    pic.fill_rect(area.x, sy, len_px, 4, INK);
    pic.fill_rect(area.x, sy - 3, 1, 10, INK);
    pic.fill_rect(area.x + len_px - 1, sy - 3, 1, 10, INK);
    pic.text(area.x + len_px + 6, sy - 1, &format!("{len_m} M"), 1, INK);
    let half = grid.resolution_m / 2.0;
    let (x0, y0) = (grid.origin_x_m - half, grid.origin_y_m - half);
    let extent = format!(
        "X {:.2} TO {:.2} M   Y {:.2} TO {:.2} M",
        x0,
        x0 + map_w_m,
        y0,
        y0 + grid.ny as f64 * grid.resolution_m
    );
    pic.text(area.x, sy + 16, &extent, 1, INK);

    draw_overlays(&mut pic, &area, overlays);
    Ok(pic)
}

fn draw_overlays(pic: &mut Canvas, area: &MapLayout, overlays: &[Overlay]) {
    let halo = [255, 255, 255];
    for overlay in overlays {
        match overlay {
            Overlay::Point { at, label } => {
                let Some(p) = area.to_picture(at).filter(|&p| area.contains(p)) else {
                    continue;
                };
                pic.circle(p, 6.0, 2, OVERLAY);
                pic.line((p.0 - 3.0, p.1), (p.0 + 3.0, p.1), 1, OVERLAY);
                pic.line((p.0, p.1 - 3.0), (p.0, p.1 + 3.0), 1, OVERLAY);
                if !label.is_empty() {
                    pic.text_with_halo(p.0 as i64 + 9, p.1 as i64 - 3, label, 1, OVERLAY, halo);
                }
            }
            Overlay::Path { points, label } => {
                let pts: Vec<(f64, f64)> =
                    points.iter().filter_map(|p| area.to_picture(p)).collect();
                for w in pts.windows(2) {
                    if let Some((a, b)) = area.clip(w[0], w[1]) {
                        pic.line(a, b, 2, OVERLAY);
                    }
                }
                for &p in pts.iter().filter(|&&p| area.contains(p)) {
                    pic.fill_rect(p.0 as i64 - 2, p.1 as i64 - 2, 5, 5, OVERLAY);
                }
                if let Some(&first) = pts.iter().find(|&&p| area.contains(p))
                    && !label.is_empty()
                {
                    pic.text_with_halo(
                        first.0 as i64 + 6,
                        first.1 as i64 + 6,
                        label,
                        1,
                        OVERLAY,
                        halo,
                    );
                }
            }
        }
    }
}

/// Draws a map grid with overlays as PNG bytes.
pub fn render_png(
    grid: &MapGrid,
    overlays: &[Overlay],
    options: &RenderOptions,
) -> Result<Vec<u8>> {
    Ok(render(grid, overlays, options)?.to_png()?)
}

/// Draws a map grid with overlays into a PNG file.
pub fn write_png(
    path: impl AsRef<Path>,
    grid: &MapGrid,
    overlays: &[Overlay],
    options: &RenderOptions,
) -> Result<()> {
    Ok(render(grid, overlays, options)?.write_png(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_lengths() {
        assert_eq!(nice_length(0.8), 0.5);
        assert_eq!(nice_length(1.0), 1.0);
        assert_eq!(nice_length(3.7), 2.0);
        assert_eq!(nice_length(7.0), 5.0);
        assert_eq!(nice_length(0.0), 1.0);
    }

    #[test]
    fn ramp_ends_and_patterns_are_distinct() {
        assert_eq!(ramp(0.0), RAMP[0].1);
        assert_eq!(ramp(1.0), RAMP[4].1);
        assert_eq!(ramp(2.0), RAMP[4].1);
        assert_eq!(ramp(f32::NAN), RAMP[0].1);
        // No ramp colour is one of the pattern colours.
        for k in 0..=100 {
            let c = ramp(k as f32 / 100.0);
            assert!(!UNKNOWN_COLOURS.contains(&c) && !OCCLUDED_COLOURS.contains(&c));
        }
    }

    #[test]
    fn clipping_keeps_segments_inside() {
        let area = MapLayout {
            x: 10,
            y: 10,
            cell_px: 1,
            grid_nx: 100,
            grid_ny: 100,
            origin: (0.0, 0.0),
            res: 1.0,
        };
        let (a, b) = area.clip((0.0, 50.0), (200.0, 50.0)).unwrap();
        assert!(
            (a.0 - 10.0).abs() < 1e-9 && (b.0 - 110.0).abs() < 1e-9,
            "{a:?} {b:?}"
        );
        assert!(area.clip((0.0, 0.0), (5.0, 200.0)).is_none());
    }
}
