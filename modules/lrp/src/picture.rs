//! Debugging pictures (§7.1): a small RGB canvas written as PNG, and the picture of the
//! configuration space with the search and the trajectory over it.
//!
//! In the C-space picture the shoulder runs left to right and the elbow bottom to top. A
//! cell's grey level is its requirement (black = the foot's lowest reach, white = its
//! highest); red cells are obstacles; blue tints the cells the search expanded; the path's
//! cells are green with the trajectory drawn in yellow, the start cyan and the goal magenta.

use crate::cspace::{CCell, CSpace};
use crate::planner::LegPlan;

/// Why a picture could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// PNG encoding failed.
    #[error("PNG encoding failed: {0}")]
    Encode(#[from] png::EncodingError),
    /// Writing the file failed.
    #[error(
        "cannot write the picture to {path}: {source}; check the directory exists and is writable"
    )]
    Write {
        /// The path.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// An RGB colour.
pub type Rgb = [u8; 3];

/// An RGB image, row 0 at the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with one colour.
    pub fn new(width: u32, height: u32, fill: Rgb) -> Self {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&fill);
        }
        Self { width, height, rgb }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour of a pixel, if on the canvas.
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        Some([
            *self.rgb.get(i)?,
            *self.rgb.get(i + 1)?,
            *self.rgb.get(i + 2)?,
        ])
    }

    /// Sets a pixel; off-canvas pixels are ignored.
    pub fn set(&mut self, x: i64, y: i64, c: Rgb) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        if let Some(px) = self.rgb.get_mut(i..i + 3) {
            px.copy_from_slice(&c);
        }
    }

    /// Fills a rectangle (clipped).
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        for yy in y.max(0)..(y + h).min(i64::from(self.height)) {
            for xx in x.max(0)..(x + w).min(i64::from(self.width)) {
                self.set(xx, yy, c);
            }
        }
    }

    /// Draws a line (clipped).
    pub fn line(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, c: Rgb) {
        let n = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as i64).clamp(1, 100_000);
        for k in 0..=n {
            let t = k as f64 / n as f64;
            self.set(
                (x0 + (x1 - x0) * t).round() as i64,
                (y0 + (y1 - y0) * t).round() as i64,
                c,
            );
        }
    }

    /// Draws a filled square marker centred on a point.
    pub fn marker(&mut self, x: f64, y: f64, half: i64, c: Rgb) {
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        self.fill_rect(cx - half, cy - half, 2 * half + 1, 2 * half + 1, c);
    }

    /// Copies another canvas onto this one with its top-left corner at `(x, y)`.
    pub fn blit(&mut self, other: &Canvas, x: i64, y: i64) {
        for yy in 0..other.height {
            for xx in 0..other.width {
                if let Some(c) = other.pixel(xx, yy) {
                    self.set(x + i64::from(xx), y + i64::from(yy), c);
                }
            }
        }
    }

    /// The picture as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>, PictureError> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header()?;
            writer.write_image_data(&self.rgb)?;
            writer.finish()?;
        }
        Ok(out)
    }

    /// Writes the picture to a PNG file.
    pub fn write_png(&self, path: impl AsRef<std::path::Path>) -> Result<(), PictureError> {
        let bytes = self.to_png()?;
        std::fs::write(path.as_ref(), bytes).map_err(|source| PictureError::Write {
            path: path.as_ref().display().to_string(),
            source,
        })
    }
}

/// A grey level for `value` between `lo` (black) and `hi` (white).
pub fn grey(value: f64, lo: f64, hi: f64) -> Rgb {
    let t = if hi > lo {
        (value - lo) / (hi - lo)
    } else {
        0.0
    };
    let g = (t.clamp(0.0, 1.0) * 255.0).round() as u8;
    [g, g, g]
}

/// Pixels per C-space cell in [`cspace_picture`].
pub const CELL_PIXELS: u32 = 8;

/// The configuration space, with the search and the trajectory of a plan if given.
pub fn cspace_picture(cs: &CSpace, plan: Option<&LegPlan>) -> Canvas {
    let (ns, ne) = cs.dims();
    let px = CELL_PIXELS as i64;
    let (w, h) = (ns as u32 * CELL_PIXELS, ne as u32 * CELL_PIXELS);
    let mut canvas = Canvas::new(w, h, [0, 0, 0]);
    let (z_min, z_max) = cs.z_range_m();
    let on_path: std::collections::HashSet<CCell> = plan
        .map(|p| p.cells.iter().copied().collect())
        .unwrap_or_default();
    for ie in 0..ne {
        for is in 0..ns {
            let c = CCell { is, ie };
            let mut colour = if cs.is_free(c) {
                grey(cs.required_m(c), z_min, z_max)
            } else {
                [150, 20, 20]
            };
            if plan.is_some_and(|p| p.expanded.get(cs.index(c)).copied().unwrap_or(false)) {
                colour = [colour[0] / 2, colour[1] / 2, colour[2] / 2 + 110];
            }
            if on_path.contains(&c) {
                colour = [40, 170, 60];
            }
            let y = (ne - 1 - ie) as i64 * px;
            canvas.fill_rect(is as i64 * px, y, px - 1, px - 1, colour);
        }
    }
    if let Some(plan) = plan {
        let (ds, de) = cs.cell_size_rad();
        let origin = cs.centre(CCell { is: 0, ie: 0 });
        let to_px = |s: f64, e: f64| {
            let x = ((s - origin.0) / ds + 0.5) * px as f64;
            let y = h as f64 - ((e - origin.1) / de + 0.5) * px as f64;
            (x, y)
        };
        for wp in plan.points.windows(2) {
            let (a, b) = (to_px(wp[0][0], wp[0][1]), to_px(wp[1][0], wp[1][1]));
            canvas.line(a.0, a.1, b.0, b.1, [250, 220, 40]);
        }
        if let (Some(first), Some(last)) = (plan.points.first(), plan.points.last()) {
            let a = to_px(first[0], first[1]);
            let b = to_px(last[0], last[1]);
            canvas.marker(a.0, a.1, 3, [40, 220, 230]);
            canvas.marker(b.0, b.1, 3, [230, 40, 220]);
        }
    }
    canvas
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_through_the_decoder() {
        let mut c = Canvas::new(5, 4, [10, 20, 30]);
        c.set(1, 2, [200, 100, 50]);
        c.set(-1, 99, [1, 1, 1]); // ignored
        let bytes = c.to_png().unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (5, 4));
        let i = 3 * (2 * 5 + 1);
        assert_eq!(&buf[i..i + 3], &[200, 100, 50]);
        assert_eq!(&buf[0..3], &[10, 20, 30]);
    }
}
