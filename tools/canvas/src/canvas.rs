//! An RGB canvas and its drawing primitives: rectangles, lines of any thickness, circles,
//! markers, text, copies of other canvases; and its PNG encoding. Everything is clipped to the
//! canvas: drawing off its edges does nothing.

use std::path::Path;

use crate::error::CanvasError;
use crate::font;

/// An RGB colour.
pub type Rgb = [u8; 3];

/// An RGB image, row-major from the top-left corner (row 0 at the top).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: Rgb) -> Self {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&background);
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

    /// The colour at `(x, y)`, if inside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let k = 3 * (y as usize * self.width as usize + x as usize);
        self.rgb.get(k..k + 3).map(|p| [p[0], p[1], p[2]])
    }

    /// Sets the pixel at `(x, y)`; outside the picture nothing happens.
    pub fn set(&mut self, x: i64, y: i64, c: Rgb) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let k = 3 * (y as usize * self.width as usize + x as usize);
        if let Some(p) = self.rgb.get_mut(k..k + 3) {
            p.copy_from_slice(&c);
        }
    }

    /// Fills the rectangle with corner `(x, y)` and size `w x h` (clipped).
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        for yy in y.max(0)..(y + h).min(i64::from(self.height)) {
            for xx in x.max(0)..(x + w).min(i64::from(self.width)) {
                self.set(xx, yy, c);
            }
        }
    }

    /// Draws a rectangle's outline.
    pub fn outline_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        self.fill_rect(x, y, w, 1, c);
        self.fill_rect(x, y + h - 1, w, 1, c);
        self.fill_rect(x, y, 1, h, c);
        self.fill_rect(x + w - 1, y, 1, h, c);
    }

    /// Draws a line `thickness` pixels wide (clipped).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), thickness: u32, c: Rgb) {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let steps = dx.abs().max(dy.abs()).ceil().clamp(1.0, 1e5) as usize;
        let t = i64::from(thickness.max(1));
        let off = (t - 1) / 2;
        for s in 0..=steps {
            let f = s as f64 / steps as f64;
            let (x, y) = (a.0 + f * dx, a.1 + f * dy);
            if !(x.is_finite() && y.is_finite()) {
                return;
            }
            self.fill_rect(x.round() as i64 - off, y.round() as i64 - off, t, t, c);
        }
    }

    /// Draws a filled square marker of side `2 * half + 1` centred on a point.
    pub fn marker(&mut self, center: (f64, f64), half: i64, c: Rgb) {
        let (cx, cy) = (center.0.round() as i64, center.1.round() as i64);
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

    /// Draws a circle's outline of radius `r` pixels.
    pub fn circle(&mut self, center: (f64, f64), r: f64, thickness: u32, c: Rgb) {
        let n = (r * 8.0).ceil().clamp(8.0, 720.0) as usize;
        let point = |k: usize| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            (center.0 + r * a.cos(), center.1 + r * a.sin())
        };
        for k in 0..n {
            self.line(point(k), point(k + 1), thickness, c);
        }
    }

    /// Draws text with its top-left corner at `(x, y)`, each font pixel `scale` pixels wide.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: u32, c: Rgb) {
        let s = i64::from(scale.max(1));
        for (n, ch) in text.chars().enumerate() {
            let g = font::glyph(ch);
            let gx = x + n as i64 * i64::from(font::ADVANCE) * s;
            for (row, bits) in g.iter().enumerate() {
                for col in 0..font::WIDTH {
                    if bits & (1 << (font::WIDTH - 1 - col)) != 0 {
                        self.fill_rect(gx + i64::from(col) * s, y + row as i64 * s, s, s, c);
                    }
                }
            }
        }
    }

    /// Draws text over a halo of `halo` so it reads on any background.
    pub fn text_with_halo(&mut self, x: i64, y: i64, text: &str, scale: u32, c: Rgb, halo: Rgb) {
        for (dx, dy) in [
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, 1),
            (-1, 1),
            (1, -1),
        ] {
            self.text(x + dx, y + dy, text, scale, halo);
        }
        self.text(x, y, text, scale, c);
    }

    /// Encodes the canvas as an 8-bit RGB PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, CanvasError> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // The fast encoder writes map pictures about five times faster than png's default,
        // for files about 1.8 times larger (tens of kilobytes; see BENCHMARKS.md).
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.rgb)?;
        writer.finish()?;
        Ok(out)
    }

    /// Writes the canvas to a PNG file.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), CanvasError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_png()?).map_err(|source| CanvasError::Write {
            path: path.to_owned(),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawing_is_clipped_and_png_decodes() {
        let mut p = Canvas::new(20, 10, [255, 255, 255]);
        p.fill_rect(-5, -5, 8, 8, [1, 2, 3]);
        p.line((0.0, 9.0), (100.0, 9.0), 1, [9, 9, 9]);
        p.set(-1, 100, [0, 0, 0]);
        p.text(0, 0, "A", 1, [0, 0, 0]);
        assert_eq!(p.pixel(2, 2), Some([1, 2, 3]));
        assert_eq!(p.pixel(19, 9), Some([9, 9, 9]));
        assert_eq!(p.pixel(20, 0), None);
        let png = p.to_png().unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (20, 10));
    }

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

    #[test]
    fn blits_markers_and_grey_levels() {
        let mut small = Canvas::new(2, 2, [7, 7, 7]);
        small.marker((0.0, 0.0), 0, [1, 1, 1]);
        let mut big = Canvas::new(4, 4, [0, 0, 0]);
        big.blit(&small, 3, 3);
        assert_eq!(big.pixel(3, 3), Some([1, 1, 1]));
        assert_eq!(big.pixel(2, 2), Some([0, 0, 0]));
        assert_eq!(grey(5.0, 0.0, 10.0), [128, 128, 128]);
        assert_eq!(grey(5.0, 1.0, 1.0), [0, 0, 0]);
    }

    #[test]
    fn an_unwritable_path_is_named() {
        let err = Canvas::new(1, 1, [0, 0, 0])
            .write_png("/nonexistent-dir/x.png")
            .unwrap_err();
        assert!(err.to_string().contains("/nonexistent-dir/x.png"), "{err}");
    }
}
