//! The navigation loop on a large map: a 100 x 100 m terrain at the paper's 2 cm grid
//! (25 million cells), gently rolling ground with hills too steep to climb strewn over it,
//! and a goal 50 m east of the start. Prints the run and the loop's rate over measured
//! computing (the true-terrain judge is left out of it):
//! `cargo run --release -p tca-nav-navigator --example long_course [-- SEED]`.

use std::time::Instant;

use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tca_nav_navigator::{Pose2, RunOptions, WheeledBase, WheeledParams, run, wheeled_params};
use tca_robot::HeightField;

const RES: f64 = 0.02;
const SIDE_M: f64 = 100.0;

fn terrain(seed: u64) -> Result<HeightField, Box<dyn std::error::Error>> {
    let n = (SIDE_M / RES) as usize;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Hills 0.3-0.6 m high and 0.4-1.2 m in radius, a few of them on the straight way.
    let mut hills: Vec<(f64, f64, f64, f64)> = (0..400)
        .map(|_| {
            (
                rng.random_range(0.0..SIDE_M),
                rng.random_range(0.0..SIDE_M),
                rng.random_range(0.4..1.2),
                rng.random_range(0.3..0.6),
            )
        })
        .collect();
    for k in 0..8 {
        hills.push((
            30.0 + 5.5 * k as f64,
            50.0 + rng.random_range(-0.4..0.4),
            rng.random_range(0.5..1.0),
            0.4,
        ));
    }
    // Bucket hills by 4 m tiles so each cell looks only at nearby ones.
    let tile = 4.0;
    let tiles = (SIDE_M / tile) as usize + 1;
    let mut bucket: Vec<Vec<usize>> = vec![Vec::new(); tiles * tiles];
    for (i, &(hx, hy, r, _)) in hills.iter().enumerate() {
        let (x0, x1) = (
            ((hx - r) / tile).floor().max(0.0) as usize,
            ((hx + r) / tile) as usize,
        );
        let (y0, y1) = (
            ((hy - r) / tile).floor().max(0.0) as usize,
            ((hy + r) / tile) as usize,
        );
        for ty in y0..=y1.min(tiles - 1) {
            for tx in x0..=x1.min(tiles - 1) {
                bucket[ty * tiles + tx].push(i);
            }
        }
    }
    let mut h = Vec::with_capacity(n * n);
    for iy in 0..n {
        let y = iy as f64 * RES;
        for ix in 0..n {
            let x = ix as f64 * RES;
            let mut z = 0.05 * (x * 0.21).sin() * (y * 0.17).cos();
            let t = (y / tile) as usize * tiles + (x / tile) as usize;
            for &i in &bucket[t] {
                let (hx, hy, r, top) = hills[i];
                let d = ((x - hx).powi(2) + (y - hy).powi(2)).sqrt();
                if d < r {
                    z += top * (0.5 + 0.5 * (std::f64::consts::PI * d / r).cos());
                }
            }
            h.push(z);
        }
    }
    Ok(HeightField::new(Point2::new(0.0, 0.0), RES, n, n, h)?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed = std::env::args()
        .nth(1)
        .map(|s| s.parse::<u64>())
        .transpose()?
        .unwrap_or(1);
    let t = Instant::now();
    let terrain = terrain(seed)?;
    println!(
        "terrain: 5000 x 5000 cells in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let start = Pose2::new(25.0, 50.0, 0.0);
    let opts = RunOptions {
        start,
        goal_offset: [50.0, 0.0],
        drift: 0.0125,
        seed,
        max_frames: 8000,
    };
    let mut base = WheeledBase::new(WheeledParams::PIONEER, &terrain, start);
    let t = Instant::now();
    let (r, _) = run(&terrain, &mut base, wheeled_params(), &opts)?;
    println!(
        "seed {seed}: reached {} ({}), {} frames, {:.2} m driven (true-map path {:?} m), final error {:.3} m ({:.2} %), {} replans, {} turns, collisions {}, falls {}, untraversable frames {}, loop {:.1} Hz over measured computing; whole run with the judge {:.1} s",
        r.reached,
        r.reason,
        r.frames,
        r.distance_m,
        r.true_map_path_m,
        r.final_error_m,
        100.0 * r.final_error_m / r.distance_m.max(1e-9),
        r.replans,
        r.exploration_turns,
        r.collisions,
        r.falls,
        r.untraversable_frames,
        r.loop_hz,
        t.elapsed().as_secs_f64()
    );
    Ok(())
}
