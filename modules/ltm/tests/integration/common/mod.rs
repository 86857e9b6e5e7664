//! Scenes shared by the LTM tests: terrains with known geometry and scanners looking at them.

#![allow(dead_code)]

use std::sync::Arc;

use nalgebra::Point2;
use tca_ism::{NoiseModel, SensorSpec, VirtualScanner};
use tca_robot::{CarriagePose, HeightField, LegParams};
use tca_single_leg_messages::{PlanePoint, RangeImage};

/// Sample spacing of the test terrains, metres.
pub(crate) const TERRAIN_RES_M: f64 = 0.02;

/// An axis-aligned box on level ground.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TestBox {
    pub(crate) min: Point2<f64>,
    pub(crate) max: Point2<f64>,
    pub(crate) height_m: f64,
}

/// The box used by the tests: 1 x 1 m, 0.5 m tall, 6.5 m ahead of a carriage at y = 1 m.
pub(crate) const BOX: TestBox = TestBox {
    min: Point2::new(2.5, 7.5),
    max: Point2::new(3.5, 8.5),
    height_m: 0.5,
};

/// Level ground at height 0 over x in [-4, 10], y in [-4, 24], with the given boxes.
pub(crate) fn terrain(boxes: &[TestBox]) -> Arc<HeightField> {
    let origin = Point2::new(-4.0, -4.0);
    let (nx, ny) = (
        (14.0 / TERRAIN_RES_M) as usize + 1,
        (28.0 / TERRAIN_RES_M) as usize + 1,
    );
    let mut heights = vec![0.0; nx * ny];
    for (k, h) in heights.iter_mut().enumerate() {
        let x = origin.x + (k % nx) as f64 * TERRAIN_RES_M;
        let y = origin.y + (k / nx) as f64 * TERRAIN_RES_M;
        for b in boxes {
            if x >= b.min.x && x <= b.max.x && y >= b.min.y && y <= b.max.y {
                *h = f64::max(*h, b.height_m);
            }
        }
    }
    Arc::new(HeightField::new(origin, TERRAIN_RES_M, nx, ny, heights).unwrap())
}

/// The robot parameters with the scanner pitched 35° down, the mount these scenes were laid
/// out for (the box is in the Erim's view from a carriage at y = 1 m), whatever the shipped
/// parameters say.
pub(crate) fn params() -> LegParams {
    let mut p = LegParams::default();
    p.scanner.pitch_down_rad = 35f64.to_radians();
    p
}

/// A scanner of `spec` on the default carriage looking at `terrain`.
pub(crate) fn scanner(
    spec: SensorSpec,
    terrain: Arc<HeightField>,
    noisy: bool,
    seed: u64,
) -> VirtualScanner {
    let s = VirtualScanner::new(spec, terrain, &params()).with_seed(seed);
    if noisy {
        s
    } else {
        s.with_noise(NoiseModel::none())
    }
}

/// One image from a level carriage at `y_m`.
pub(crate) fn image(scanner: &VirtualScanner, y_m: f64, sequence: u64) -> RangeImage {
    scanner.cast(&CarriagePose::level(y_m), sequence).unwrap()
}

/// A rectangle as a polygon.
pub(crate) fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<PlanePoint> {
    [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        .iter()
        .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
        .collect()
}
