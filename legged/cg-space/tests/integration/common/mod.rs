//! Terrains for the tests.

#![allow(dead_code, unreachable_pub)]

use nalgebra::Point2;
use tca_robot::HeightField;

/// A terrain from a height function over `x0..x1`, `y0..y1` at `res`.
pub fn terrain(
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    res: f64,
    f: impl Fn(f64, f64) -> f64,
) -> HeightField {
    let nx = ((x1 - x0) / res).round() as usize + 1;
    let ny = ((y1 - y0) / res).round() as usize + 1;
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            h.push(f(x0 + ix as f64 * res, y0 + iy as f64 * res));
        }
    }
    HeightField::new(Point2::new(x0, y0), res, nx, ny, h).expect("a terrain")
}

/// The cliff course: a plateau `height` m tall from x = 14 m on, beside a
/// ramp up to it for y in 3..9 m (from x = 6 to 14 m), on a 30 x 20 m map.
pub fn cliff(height: f64) -> HeightField {
    terrain(0.0, 30.0, -10.0, 10.0, 0.1, |x, y| {
        // A ramp 6 m wide: the Ambler's middle feet stand 7.7 m apart and fold in to no
        // less than about 4 m apart.
        if y > 3.0 && y < 9.0 {
            (height * (x - 6.0) / 8.0).clamp(0.0, height)
        } else if x >= 14.0 {
            height
        } else {
            0.0
        }
    })
}

/// Flat ground 30 x 20 m with the goal's yard about (20, 0) walled in by a square ring 1 m
/// thick and 5 m tall: taller than the legs span and than the under-carriage clears.
pub fn walled_yard() -> HeightField {
    terrain(0.0, 30.0, -10.0, 10.0, 0.1, |x, y| {
        let d = (x - 20.0).abs().max(y.abs());
        if (5.0..6.0).contains(&d) { 5.0 } else { 0.0 }
    })
}
