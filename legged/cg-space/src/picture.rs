//! Pictures of CG-space in the manner of Eldershaw and Yim's footmap and CGmap figures: the
//! ground's elevation in grey, the foot cells without traction as small circles, the
//! invalid CG cells as black squares, and a plan's route and footfalls over them.
//!
//! The CG cells shown are asked of the [`CgSpace`] itself ([`CgSpace::is_valid`]), so a
//! picture evaluates only cells not yet evaluated, and the cells it evaluates are then known
//! to the planner too. Cells marked invalid by the foot-level search's feedback show as
//! invalid.

use std::path::Path;

use nalgebra::Point2;
use tca_canvas::{Canvas, CanvasError, Rgb};
use thiserror::Error;

use crate::footplan::{FootStep, Stance, apply};
use crate::grid::{CgCell, CgGrid};
use crate::planner::Plan;
use crate::space::CgSpace;

/// An invalid CG cell (at the heading drawn, or at every heading).
pub const INVALID_CG: Rgb = [0, 0, 0];
/// A CG cell invalid at some headings and valid at others (when every heading is drawn).
pub const INVALID_SOME: Rgb = [55, 55, 55];
/// The outline of a foot cell without traction.
pub const INVALID_FOOT: Rgb = [225, 45, 45];
/// The route joining the CG cells' centres.
pub const ROUTE: Rgb = [30, 140, 255];
/// A footfall.
pub const FOOTFALL: Rgb = [255, 205, 0];
/// The start and goal marks.
pub const ENDS: Rgb = [40, 210, 70];
/// Darkest and lightest grey of the elevation: lower ground darker, never as dark as an
/// invalid cell.
const ELEVATION_GREY: (f64, f64) = (125.0, 245.0);
/// Pixels a cell needs before invalid foot cells are drawn as circles (below, tinted).
const CIRCLE_MIN_PX: f64 = 4.0;
/// The most pixels a cell is given when the scale is chosen automatically.
const AUTO_MAX_CELL_PX: f64 = 24.0;

/// Why a picture cannot be drawn or written.
#[derive(Debug, Error)]
pub enum PictureError {
    /// The region to draw is not a rectangle of positive size.
    #[error(
        "the region x {x_min}..{x_max} m, y {y_min}..{y_max} m is empty or inverted; give the lower-left corner first and a positive width and height"
    )]
    EmptyRegion {
        /// Smallest X asked for.
        x_min: f64,
        /// Largest X asked for.
        x_max: f64,
        /// Smallest Y asked for.
        y_min: f64,
        /// Largest Y asked for.
        y_max: f64,
    },
    /// The region lies wholly outside the map.
    #[error(
        "the region x {x_min}..{x_max} m, y {y_min}..{y_max} m lies outside the map, which covers x {map_x_min:.2}..{map_x_max:.2} m and y {map_y_min:.2}..{map_y_max:.2} m"
    )]
    RegionOutsideMap {
        /// Smallest X asked for.
        x_min: f64,
        /// Largest X asked for.
        x_max: f64,
        /// Smallest Y asked for.
        y_min: f64,
        /// Largest Y asked for.
        y_max: f64,
        /// The map's smallest X.
        map_x_min: f64,
        /// The map's largest X.
        map_x_max: f64,
        /// The map's smallest Y.
        map_y_min: f64,
        /// The map's largest Y.
        map_y_max: f64,
    },
    /// The heading bin asked for is not one of the space's.
    #[error(
        "heading bin {bin} does not exist: this CG-space has {bins} heading bin(s), 0..={last}; give one of those, or every heading"
    )]
    NoSuchHeading {
        /// The bin asked for.
        bin: u16,
        /// How many bins the space has.
        bins: u16,
        /// The last bin.
        last: u16,
    },
    /// The scale is not a positive number, or makes the picture too large.
    #[error("{pixels_per_m} pixels per metre cannot be drawn: {reason}")]
    Scale {
        /// The scale asked for.
        pixels_per_m: f64,
        /// Why not.
        reason: String,
    },
    /// The PNG could not be encoded or written.
    #[error(transparent)]
    Canvas(#[from] CanvasError),
}

/// Which heading bins a picture's CG cells are judged at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Headings {
    /// Every bin: a cell is black if invalid at every heading, dark grey if invalid at some.
    #[default]
    All,
    /// One bin: a cell is black if invalid at that heading.
    Bin(u16),
}

impl Headings {
    /// `None` for every heading, `Some(bin)` for one.
    pub fn from_option(theta: Option<u16>) -> Self {
        theta.map_or(Headings::All, Headings::Bin)
    }
}

/// What a picture shows and at what scale.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureOptions {
    /// The heading bin(s) at which CG cells are judged (`None`: every bin).
    pub theta: Option<u16>,
    /// The world rectangle to draw, lower-left and upper-right corners in metres (clipped
    /// to the map, widened to whole cells); `None` for the whole map.
    pub region: Option<(Point2<f64>, Point2<f64>)>,
    /// Pixels per metre; `None` chooses a whole number of pixels per cell that keeps each
    /// side within `max_side_px`.
    pub pixels_per_m: Option<f64>,
    /// The longest side allowed, pixels (an explicit scale beyond it is refused).
    pub max_side_px: u32,
    /// Where the start mark goes (world metres); `None`: the route's first cell, if any.
    pub start: Option<Point2<f64>>,
    /// Where the goal mark goes (world metres); `None`: the route's last cell, if any.
    pub goal: Option<Point2<f64>>,
    /// A line of text drawn in the top-left corner.
    pub label: Option<String>,
}

impl Default for PictureOptions {
    fn default() -> Self {
        PictureOptions {
            theta: None,
            region: None,
            pixels_per_m: None,
            max_side_px: 2000,
            start: None,
            goal: None,
            label: None,
        }
    }
}

/// Where a picture's cells and pixels lie: the cells drawn and the scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    /// The first column drawn.
    pub ix0: i32,
    /// The first row drawn.
    pub iy0: i32,
    /// Columns drawn.
    pub cols: i32,
    /// Rows drawn.
    pub rows: i32,
    /// The world position of the picture's lower-left corner, metres.
    pub min: Point2<f64>,
    /// The world position of the picture's upper-right corner, metres.
    pub max: Point2<f64>,
    /// Pixels per metre.
    pub pixels_per_m: f64,
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
    /// Pixels a cell spans.
    pub cell_px: f64,
}

impl Layout {
    /// The cells and scale of a picture of `grid` with `options`; refuses an empty,
    /// inverted or outside region, a heading bin the grid has not and a scale that is not
    /// positive or makes a side longer than `options.max_side_px`.
    pub fn new(grid: &CgGrid, options: &PictureOptions) -> Result<Self, PictureError> {
        if let Some(bin) = options.theta
            && bin >= grid.theta_bins
        {
            return Err(PictureError::NoSuchHeading {
                bin,
                bins: grid.theta_bins,
                last: grid.theta_bins - 1,
            });
        }
        let map_min = grid.origin;
        let map_max = Point2::new(
            grid.origin.x + f64::from(grid.nx) * grid.cell_m,
            grid.origin.y + f64::from(grid.ny) * grid.cell_m,
        );
        let (lo, hi) = options.region.unwrap_or((map_min, map_max));
        let finite = [lo.x, lo.y, hi.x, hi.y].iter().all(|v| v.is_finite());
        if !finite || lo.x >= hi.x || lo.y >= hi.y {
            return Err(PictureError::EmptyRegion {
                x_min: lo.x,
                x_max: hi.x,
                y_min: lo.y,
                y_max: hi.y,
            });
        }
        let (ax, ay) = grid.xy_of(lo);
        // The upper-right corner belongs to the cell below and left of it when it falls on
        // a cell boundary.
        let bx = ((hi.x - grid.origin.x) / grid.cell_m).ceil() as i64 - 1;
        let by = ((hi.y - grid.origin.y) / grid.cell_m).ceil() as i64 - 1;
        let ix0 = i64::from(ax).max(0);
        let iy0 = i64::from(ay).max(0);
        let ix1 = bx.min(i64::from(grid.nx) - 1);
        let iy1 = by.min(i64::from(grid.ny) - 1);
        if ix0 > ix1 || iy0 > iy1 {
            return Err(PictureError::RegionOutsideMap {
                x_min: lo.x,
                x_max: hi.x,
                y_min: lo.y,
                y_max: hi.y,
                map_x_min: map_min.x,
                map_x_max: map_max.x,
                map_y_min: map_min.y,
                map_y_max: map_max.y,
            });
        }
        // Bounded by the grid's columns and rows, which are i32.
        let (ix0, iy0) = (ix0 as i32, iy0 as i32);
        let (cols, rows) = ((ix1 + 1) as i32 - ix0, (iy1 + 1) as i32 - iy0);
        let longest = f64::from(cols.max(rows));
        let max_side = f64::from(options.max_side_px.max(1));
        let pixels_per_m = match options.pixels_per_m {
            Some(ppm) => {
                if !(ppm.is_finite() && ppm > 0.0) {
                    return Err(PictureError::Scale {
                        pixels_per_m: ppm,
                        reason: "give a positive number".into(),
                    });
                }
                let side = (longest * grid.cell_m * ppm).ceil();
                if side > max_side {
                    return Err(PictureError::Scale {
                        pixels_per_m: ppm,
                        reason: format!(
                            "the picture would be {side} pixels across, more than the {max_side} allowed; draw a smaller region or at a smaller scale"
                        ),
                    });
                }
                ppm
            }
            None => {
                let cell_px = (max_side / longest).floor().min(AUTO_MAX_CELL_PX);
                if cell_px >= 1.0 {
                    cell_px / grid.cell_m
                } else {
                    max_side / (longest * grid.cell_m)
                }
            }
        };
        let min = Point2::new(
            grid.origin.x + f64::from(ix0) * grid.cell_m,
            grid.origin.y + f64::from(iy0) * grid.cell_m,
        );
        let max = Point2::new(
            min.x + f64::from(cols) * grid.cell_m,
            min.y + f64::from(rows) * grid.cell_m,
        );
        let side = |cells: i32| {
            ((f64::from(cells) * grid.cell_m * pixels_per_m).round() as u32).clamp(1, u32::MAX)
        };
        Ok(Layout {
            ix0,
            iy0,
            cols,
            rows,
            min,
            max,
            pixels_per_m,
            width: side(cols),
            height: side(rows),
            cell_px: grid.cell_m * pixels_per_m,
        })
    }

    /// The picture position (x right, y down, fractional pixels) of a world point.
    pub fn to_px(&self, p: Point2<f64>) -> (f64, f64) {
        (
            (p.x - self.min.x) * self.pixels_per_m,
            (self.max.y - p.y) * self.pixels_per_m,
        )
    }

    /// The pixel holding a world point, if it is in the picture.
    pub fn pixel_of(&self, p: Point2<f64>) -> Option<(u32, u32)> {
        let (x, y) = self.to_px(p);
        let (x, y) = (x.floor(), y.floor());
        (x >= 0.0 && y >= 0.0 && x < f64::from(self.width) && y < f64::from(self.height))
            .then_some((x as u32, y as u32))
    }

    /// The world point at a pixel's centre.
    pub fn world_of(&self, px: u32, py: u32) -> Point2<f64> {
        Point2::new(
            self.min.x + (f64::from(px) + 0.5) / self.pixels_per_m,
            self.max.y - (f64::from(py) + 0.5) / self.pixels_per_m,
        )
    }
}

/// What a picture shows of one cell.
#[derive(Debug, Clone, Copy)]
struct CellLook {
    height: f64,
    foot_valid: bool,
    /// 0: valid (at the heading, or at every heading), 1: invalid at some headings,
    /// 2: invalid.
    cg: u8,
}

fn look(space: &mut CgSpace, headings: Headings, ix: i32, iy: i32) -> CellLook {
    let bins = space.grid().theta_bins;
    let cg = match headings {
        Headings::Bin(it) => {
            if space.is_valid(CgCell::new(ix, iy, it)) {
                0
            } else {
                2
            }
        }
        Headings::All => {
            let invalid = (0..bins)
                .filter(|&it| !space.is_valid(CgCell::new(ix, iy, it)))
                .count();
            if invalid == 0 {
                0
            } else if invalid == usize::from(bins) {
                2
            } else {
                1
            }
        }
    };
    let foot = space.foot();
    CellLook {
        height: foot.height(ix, iy).unwrap_or(f64::NAN),
        foot_valid: foot.valid(ix, iy),
        cg,
    }
}

fn elevation(height: f64, lo: f64, hi: f64) -> Rgb {
    let t = if hi > lo && height.is_finite() {
        ((height - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let g = (ELEVATION_GREY.0 + t * (ELEVATION_GREY.1 - ELEVATION_GREY.0)).round() as u8;
    [g, g, g]
}

fn tint(c: Rgb, with: Rgb) -> Rgb {
    let mix = |a: u8, b: u8| ((u16::from(a) + u16::from(b)) / 2) as u8;
    [mix(c[0], with[0]), mix(c[1], with[1]), mix(c[2], with[2])]
}

/// The stance a plan starts from, read from its moves: each leg where its first move takes
/// it from (in the air if that is a placing from the air), a leg that never moves where
/// [`FootPlan::start`](crate::FootPlan::start) has it.
pub fn start_stance(plan: &Plan) -> Stance {
    let mut feet = plan.feet.start.feet.clone();
    let mut seen = vec![false; feet.len()];
    for step in &plan.feet.steps {
        let (leg, from) = match *step {
            FootStep::Place { leg, from, .. } => (leg, from),
            FootStep::Lift { leg, from } => (leg, Some(from)),
            FootStep::Advance { .. } => continue,
        };
        if let (Some(slot), Some(done)) = (feet.get_mut(leg), seen.get_mut(leg))
            && !*done
        {
            *slot = from;
            *done = true;
        }
    }
    Stance::new(0, feet, plan.feet.start.z_mm)
}

/// The stances along a plan, from [`start_stance`], one after each move.
pub fn stances(plan: &Plan) -> Vec<Stance> {
    let mut s = start_stance(plan);
    let mut out = vec![s.clone()];
    for step in &plan.feet.steps {
        apply(&mut s, step);
        out.push(s.clone());
    }
    out
}

/// The foot cells a plan stands on: the starting stance's and every foot move's target.
pub fn footfalls(plan: &Plan) -> Vec<(i32, i32)> {
    let mut out: Vec<(i32, i32)> = start_stance(plan).feet.iter().flatten().copied().collect();
    out.extend(plan.feet.steps.iter().filter_map(|s| match s {
        FootStep::Place { to, .. } => Some(*to),
        _ => None,
    }));
    out
}

/// Draws CG-space as a picture, north up: the elevation in grey (darker lower), foot cells
/// without traction as small red circles (tinted red when a cell is too small for one),
/// invalid CG cells as black squares (at heading bin `options.theta`, or with every heading:
/// black where every heading is invalid, dark grey where some are), and, with a plan, its
/// route (the CG cells' centres joined, blue) and its footfalls (yellow crosses), and the
/// start (a green ring) and goal (a green square).
///
/// CG cells are asked of `space`, so they are evaluated there if they were not yet.
pub fn draw_cg_space(
    space: &mut CgSpace,
    options: &PictureOptions,
    plan: Option<&Plan>,
) -> Result<Canvas, PictureError> {
    let grid = *space.grid();
    let layout = Layout::new(&grid, options)?;
    let headings = Headings::from_option(options.theta);
    let (w, h) = (layout.width, layout.height);
    // The column and row under each pixel column and row, and the distinct ones in order.
    let col_of: Vec<i32> = (0..w)
        .map(|px| {
            grid.xy_of(layout.world_of(px, 0))
                .0
                .clamp(layout.ix0, layout.ix0 + layout.cols - 1)
        })
        .collect();
    let row_of: Vec<i32> = (0..h)
        .map(|py| {
            grid.xy_of(layout.world_of(0, py))
                .1
                .clamp(layout.iy0, layout.iy0 + layout.rows - 1)
        })
        .collect();
    let distinct = |v: &[i32]| {
        let mut d = v.to_vec();
        d.sort_unstable();
        d.dedup();
        d
    };
    let (cols, rows) = (distinct(&col_of), distinct(&row_of));
    let mut looks = Vec::with_capacity(cols.len() * rows.len());
    for &iy in &rows {
        for &ix in &cols {
            looks.push(look(space, headings, ix, iy));
        }
    }
    let (lo, hi) = looks
        .iter()
        .map(|l| l.height)
        .filter(|h| h.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(h), b.max(h))
        });
    let circles = layout.cell_px >= CIRCLE_MIN_PX;
    let col_index: Vec<usize> = col_of
        .iter()
        .map(|c| cols.binary_search(c).unwrap_or(0))
        .collect();
    let mut canvas = Canvas::new(w, h, [0, 0, 0]);
    for (py, row) in row_of.iter().enumerate() {
        let r = rows.binary_search(row).unwrap_or(0);
        for (px, &c) in col_index.iter().enumerate() {
            let l = looks[r * cols.len() + c];
            let mut colour = match l.cg {
                2 => INVALID_CG,
                1 => INVALID_SOME,
                _ => elevation(l.height, lo, hi),
            };
            if !circles && !l.foot_valid {
                colour = tint(colour, INVALID_FOOT);
            }
            canvas.set(px as i64, py as i64, colour);
        }
    }
    if circles {
        let r = (0.3 * layout.cell_px).max(1.5);
        for (j, &iy) in rows.iter().enumerate() {
            for (i, &ix) in cols.iter().enumerate() {
                if !looks[j * cols.len() + i].foot_valid {
                    canvas.circle(layout.to_px(grid.centre(ix, iy)), r, 1, INVALID_FOOT);
                }
            }
        }
    }
    let route: Vec<Point2<f64>> = plan
        .map(|p| {
            p.feet
                .route
                .iter()
                .map(|c| grid.centre(c.ix, c.iy))
                .collect()
        })
        .unwrap_or_default();
    let thick = (layout.cell_px / 5.0).round().clamp(2.0, 4.0) as u32;
    for seg in route.windows(2) {
        canvas.line(layout.to_px(seg[0]), layout.to_px(seg[1]), thick, ROUTE);
    }
    if let Some(p) = plan {
        let arm = (0.35 * layout.cell_px).clamp(2.0, 8.0);
        let cross = if layout.cell_px >= 12.0 { 2 } else { 1 };
        for (fx, fy) in footfalls(p) {
            let (x, y) = layout.to_px(grid.centre(fx, fy));
            canvas.line((x - arm, y - arm), (x + arm, y + arm), cross, FOOTFALL);
            canvas.line((x - arm, y + arm), (x + arm, y - arm), cross, FOOTFALL);
        }
    }
    let mark = (0.6 * layout.cell_px).clamp(4.0, 12.0);
    if let Some(s) = options.start.or_else(|| route.first().copied()) {
        canvas.circle(layout.to_px(s), mark, 2, ENDS);
    }
    if let Some(g) = options.goal.or_else(|| route.last().copied()) {
        canvas.marker(layout.to_px(g), (mark * 0.7).round() as i64, ENDS);
    }
    if let Some(label) = &options.label {
        let scale = if w >= 600 { 2 } else { 1 };
        canvas.text_with_halo(4, 4, label, scale, [255, 255, 255], [0, 0, 110]);
    }
    Ok(canvas)
}

/// Writes [`draw_cg_space`] to a PNG file.
pub fn write_cg_space_png(
    path: impl AsRef<Path>,
    space: &mut CgSpace,
    options: &PictureOptions,
    plan: Option<&Plan>,
) -> Result<(), PictureError> {
    draw_cg_space(space, options, plan)?.write_png(path)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::{PlanParams, plan};
    use crate::robot::CgParams;
    use tca_legged_model::RobotModel;
    use tca_robot::HeightField;

    /// 32 x 16 m, level but for a 10 x 10 m field of spikes about (22, 0) too steep to
    /// stand on, too large for the Ambler to straddle.
    fn steep_patch() -> HeightField {
        let res = 0.1;
        let (nx, ny) = (321, 161);
        let mut h = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                let (x, y) = (ix as f64 * res, -8.0 + iy as f64 * res);
                let inside = (x - 22.0).abs() < 5.0 && y.abs() < 5.0;
                h.push(if inside && (ix + iy) % 2 == 0 {
                    0.4
                } else {
                    0.0
                });
            }
        }
        HeightField::new(Point2::new(0.0, -8.0), res, nx, ny, h).expect("a terrain")
    }

    fn ambler_space(t: &HeightField) -> CgSpace {
        let model = RobotModel::builtin("ambler").expect("the Ambler");
        CgSpace::for_model(&model, t, CgParams::default()).expect("a CG-space")
    }

    #[test]
    fn black_where_the_space_says_invalid_and_the_route_drawn() {
        let t = steep_patch();
        let mut space = ambler_space(&t);
        let p = plan(
            &mut space,
            (Point2::new(6.0, 0.0), 0.0),
            (Point2::new(11.0, 0.0), 0.0),
            None,
            &PlanParams::default(),
        )
        .expect("a plan on level ground");
        let options = PictureOptions {
            theta: Some(0),
            label: Some("ambler, heading bin 0".into()),
            ..PictureOptions::default()
        };
        let evaluated = space.evaluations();
        let pic = draw_cg_space(&mut space, &options, Some(&p)).expect("a picture");
        assert!(
            space.evaluations() > evaluated,
            "the picture evaluates through the space"
        );
        let grid = *space.grid();
        let layout = Layout::new(&grid, &options).unwrap();
        assert_eq!((pic.width(), pic.height()), (layout.width, layout.height));
        assert!(pic.width() <= 2000 && pic.height() <= 2000);
        // A pixel inside a cell, clear of its centre (circles and crosses), of the route
        // (drawn along the centres) and of its edges.
        let probe = |ix: i32, iy: i32| {
            let c = grid.centre(ix, iy);
            let q = grid.cell_m * 0.42;
            layout
                .pixel_of(Point2::new(c.x - q, c.y - q))
                .and_then(|(x, y)| pic.pixel(x, y))
                .expect("inside the picture")
        };
        let (cx, cy) = grid.xy_of(Point2::new(22.0, 0.0));
        assert!(!space.is_valid(CgCell::new(cx, cy, 0)));
        assert_eq!(probe(cx, cy), INVALID_CG, "the middle of the field");
        // The label's corner aside.
        let under_label = |ix: i32, iy: i32| {
            let (_, y) = layout.to_px(grid.centre(ix, iy));
            y < 30.0
        };
        let mut black = 0;
        for iy in 0..grid.ny {
            for ix in 0..grid.nx {
                if under_label(ix, iy) {
                    continue;
                }
                let invalid = !space.is_valid(CgCell::new(ix, iy, 0));
                let at = probe(ix, iy);
                if invalid {
                    black += 1;
                    assert_eq!(at, INVALID_CG, "invalid cell ({ix}, {iy}) not black");
                }
                let far = grid.centre(ix, iy).x < 14.0 && !invalid;
                if far {
                    assert_ne!(at, INVALID_CG, "valid cell ({ix}, {iy}) drawn black");
                }
            }
        }
        assert!(black > 0);
        // No black pixel anywhere over a valid cell.
        for py in 0..pic.height() {
            for px in 0..pic.width() {
                let (ix, iy) = grid.xy_of(layout.world_of(px, py));
                if pic.pixel(px, py) == Some(INVALID_CG) {
                    assert!(
                        !space.is_valid(CgCell::new(ix, iy, 0)),
                        "pixel ({px}, {py}) black over valid cell ({ix}, {iy})"
                    );
                }
            }
        }
        // The route is drawn: the pixel between two consecutive route cells' centres.
        let route = &p.feet.route;
        let on_route = route
            .windows(2)
            .filter(|w| w[0].ix != w[1].ix || w[0].iy != w[1].iy)
            .filter(|w| {
                let m = nalgebra::center(
                    &grid.centre(w[0].ix, w[0].iy),
                    &grid.centre(w[1].ix, w[1].iy),
                );
                layout
                    .pixel_of(m)
                    .and_then(|(x, y)| pic.pixel(x, y))
                    .is_some_and(|c| c == ROUTE)
            })
            .count();
        assert!(on_route > 0, "no route pixels");
        let footfall_pixels = (0..pic.height())
            .flat_map(|y| (0..pic.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| pic.pixel(x, y) == Some(FOOTFALL))
            .count();
        assert!(footfall_pixels > 0, "no footfalls drawn");
        // The PNG decodes.
        let bytes = pic.to_png().unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }

    #[test]
    fn every_heading_black_only_where_all_are_invalid_and_regions_crop() {
        let t = steep_patch();
        let mut space = ambler_space(&t);
        let grid = *space.grid();
        let options = PictureOptions {
            region: Some((Point2::new(12.0, -7.0), Point2::new(30.0, 7.0))),
            ..PictureOptions::default()
        };
        let layout = Layout::new(&grid, &options).unwrap();
        assert!(layout.min.x <= 12.0 && layout.min.x > 12.0 - grid.cell_m);
        assert!(layout.max.x >= 30.0 - 1e-9 && layout.max.x < 30.0 + grid.cell_m);
        let pic = draw_cg_space(&mut space, &options, None).expect("a picture");
        assert_eq!((pic.width(), pic.height()), (layout.width, layout.height));
        let q = grid.cell_m * 0.42;
        let mut some = 0;
        for iy in layout.iy0..layout.iy0 + layout.rows {
            for ix in layout.ix0..layout.ix0 + layout.cols {
                let bad = (0..grid.theta_bins)
                    .filter(|&it| !space.is_valid(CgCell::new(ix, iy, it)))
                    .count();
                let c = grid.centre(ix, iy);
                let Some((x, y)) = layout.pixel_of(Point2::new(c.x - q, c.y - q)) else {
                    continue;
                };
                let at = pic.pixel(x, y).unwrap();
                if bad == usize::from(grid.theta_bins) {
                    assert_eq!(at, INVALID_CG);
                } else if bad > 0 {
                    some += 1;
                    assert_eq!(at, INVALID_SOME);
                } else {
                    assert_ne!(at, INVALID_CG);
                    assert_ne!(at, INVALID_SOME);
                }
            }
        }
        if grid.theta_bins > 1 {
            assert!(some > 0, "no cell invalid at some headings only");
        }
    }

    #[test]
    fn bad_regions_headings_and_scales_are_refused() {
        let t = steep_patch();
        let space = ambler_space(&t);
        let grid = *space.grid();
        let with = |o: PictureOptions| Layout::new(&grid, &o);
        let region = |a: (f64, f64), b: (f64, f64)| PictureOptions {
            region: Some((Point2::new(a.0, a.1), Point2::new(b.0, b.1))),
            ..PictureOptions::default()
        };
        let e = with(region((5.0, 0.0), (5.0, 3.0))).unwrap_err();
        assert!(matches!(e, PictureError::EmptyRegion { .. }), "{e}");
        assert!(e.to_string().contains("empty or inverted"), "{e}");
        let e = with(region((8.0, 0.0), (5.0, 3.0))).unwrap_err();
        assert!(matches!(e, PictureError::EmptyRegion { .. }), "{e}");
        let e = with(region((f64::NAN, 0.0), (5.0, 3.0))).unwrap_err();
        assert!(matches!(e, PictureError::EmptyRegion { .. }), "{e}");
        let e = with(region((100.0, 0.0), (120.0, 3.0))).unwrap_err();
        assert!(matches!(e, PictureError::RegionOutsideMap { .. }), "{e}");
        assert!(e.to_string().contains("outside the map"), "{e}");
        let e = with(PictureOptions {
            theta: Some(99),
            ..PictureOptions::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("heading bin 99"), "{e}");
        for ppm in [0.0, -3.0, f64::INFINITY, 1e6] {
            let e = with(PictureOptions {
                pixels_per_m: Some(ppm),
                ..PictureOptions::default()
            })
            .unwrap_err();
            assert!(matches!(e, PictureError::Scale { .. }), "{e}");
        }
        // A tiny side limit: fewer pixels than cells, still drawn.
        let mut space = space;
        let small = PictureOptions {
            max_side_px: 20,
            ..PictureOptions::default()
        };
        let pic = draw_cg_space(&mut space, &small, None).unwrap();
        assert!(pic.width() <= 20 && pic.height() <= 20 && pic.width() >= 1);
        let e = write_cg_space_png("/nonexistent-dir/x.png", &mut space, &small, None).unwrap_err();
        assert!(e.to_string().contains("/nonexistent-dir/x.png"), "{e}");
    }
}
