//! Shared pieces of the course generators: sampling a height function on a grid, random
//! smooth relief and the level patch around the start.

use nalgebra::Point2;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use tca_robot::{HeightField, TerrainError};

/// A rectangular sampling layout: sample (0, 0) at `origin`, `nx` x `ny` samples.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub(crate) origin: Point2<f64>,
    pub(crate) cell_m: f64,
    pub(crate) nx: usize,
    pub(crate) ny: usize,
}

impl Layout {
    /// World position of sample (ix, iy).
    pub(crate) fn node(&self, ix: usize, iy: usize) -> Point2<f64> {
        Point2::new(
            self.origin.x + ix as f64 * self.cell_m,
            self.origin.y + iy as f64 * self.cell_m,
        )
    }

    /// Nearest sample position to `p` (inside the layout).
    pub(crate) fn snap(&self, p: Point2<f64>) -> Point2<f64> {
        let ix = ((p.x - self.origin.x) / self.cell_m).round().max(0.0) as usize;
        let iy = ((p.y - self.origin.y) / self.cell_m).round().max(0.0) as usize;
        self.node(ix.min(self.nx - 1), iy.min(self.ny - 1))
    }

    /// The height field of `f` sampled at every node.
    pub(crate) fn render(
        &self,
        mut f: impl FnMut(Point2<f64>) -> f64,
    ) -> Result<HeightField, TerrainError> {
        let mut heights = Vec::with_capacity(self.nx * self.ny);
        for iy in 0..self.ny {
            for ix in 0..self.nx {
                heights.push(f(self.node(ix, iy)));
            }
        }
        HeightField::new(self.origin, self.cell_m, self.nx, self.ny, heights)
    }
}

/// Raised cosine: 1 at 0, 0 at 1 and beyond, with zero slope at both ends.
pub(crate) fn bump(d: f64) -> f64 {
    if d >= 1.0 {
        0.0
    } else {
        0.5 + 0.5 * (std::f64::consts::PI * d).cos()
    }
}

/// Weight of relief at distance `d` from the start: 0 inside the level patch of radius
/// `flat_m`, rising smoothly to 1 over the following `blend_m`.
pub(crate) fn start_blend(d: f64, flat_m: f64, blend_m: f64) -> f64 {
    1.0 - bump(((d - flat_m) / blend_m).max(0.0))
}

/// Smooth random relief: a sum of plane waves with random headings, wavelengths in
/// `[min_wavelength_m, max_wavelength_m]` and phases; values within about ±1.
pub(crate) struct Waves {
    waves: Vec<(f64, f64, f64, f64)>,
}

impl Waves {
    pub(crate) fn new(
        rng: &mut ChaCha8Rng,
        count: usize,
        min_wavelength_m: f64,
        max_wavelength_m: f64,
    ) -> Self {
        let waves = (0..count)
            .map(|_| {
                let heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let wavelength = rng.random_range(min_wavelength_m..max_wavelength_m);
                let k = std::f64::consts::TAU / wavelength;
                let phase = rng.random_range(0.0..std::f64::consts::TAU);
                let amplitude = rng.random_range(0.5..1.0) * (wavelength / max_wavelength_m);
                (k * heading.cos(), k * heading.sin(), phase, amplitude)
            })
            .collect::<Vec<_>>();
        Self { waves }
    }

    pub(crate) fn at(&self, p: Point2<f64>) -> f64 {
        self.waves
            .iter()
            .map(|(kx, ky, phase, a)| a * (kx * p.x + ky * p.y + phase).sin())
            .sum()
    }
}

/// Scales `field` (values over a layout, start patch already zero) so that its largest
/// magnitude is exactly `peak_m`.
pub(crate) fn normalise(values: &mut [f64], peak_m: f64) {
    let top = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if top > 0.0 {
        let s = peak_m / top;
        for v in values.iter_mut() {
            *v *= s;
        }
    }
}
