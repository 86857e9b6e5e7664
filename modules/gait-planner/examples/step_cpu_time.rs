//! CPU time per step of both planners on course 3 (the Gait Planner with the LRP's
//! reachability, and the leg trajectory), measured from the thread's own CPU clock
//! (`/proc/thread-self/schedstat`, Linux) so that it does not depend on the machine's load,
//! unlike the wall-clock criterion benchmarks in `benches/`.
//!
//! `CARGO_TARGET_DIR=/work/target-planning cargo run --release -p tca-gait-planner --example step_cpu_time`

use nalgebra::{Point2, Point3};
use tca_gait_planner::{GaitMaps, GaitParams, GaitPlanner, synthetic};
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{CarriagePose, Course, ElbowBranch, LegKinematics, LegParams};

type AnyResult<T> = Result<T, Box<dyn std::error::Error>>;

/// Nanoseconds this thread has run on a CPU.
fn cpu_ns() -> AnyResult<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat")?;
    let first = text.split_whitespace().next().ok_or("empty schedstat")?;
    Ok(first.parse()?)
}

fn main() -> AnyResult<()> {
    let terrain = Course::builtin(3)?.height_field()?;
    let gait = GaitPlanner::new(LegParams::default(), GaitParams::default())?;
    let lrp = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default())?;
    let kin = LegKinematics::new(&LegParams::default());
    // The first five steps of the course-3 walk in `tests/system/walk.rs`: carriage Y, planted foot.
    let steps = [
        (1.0, (3.8, 0.6)),
        (2.49, (1.55, 1.75)),
        (3.98, (3.65, 4.14)),
        (5.47, (5.05, 4.13)),
        (6.96, (4.45, 5.72)),
    ];
    let goal_y = 9.5;
    let repeats = 40;
    let (mut t_cspace, mut t_gait, mut t_leg, mut n) = (0u64, 0u64, 0u64, 0u64);
    for &(body_y, (fx, fy)) in &steps {
        let region = gait.region(body_y, goal_y)?;
        let poly = gait.map_polygon(&region);
        let (lo, hi) = (
            Point2::new(poly[0].x_m, poly[0].y_m),
            Point2::new(poly[2].x_m, poly[2].y_m),
        );
        let footfall = synthetic::footfall_map(&terrain, lo, hi, 0.1, 0.15)?;
        let elevation = synthetic::elevation_map(&terrain, lo, hi, 0.1)?;
        let lrp_map = TerrainGrid::elevation_from_height_field(
            &terrain,
            Point2::new(0.0, body_y - 2.9),
            Point2::new(6.0, body_y + 2.9),
            0.05,
        )?;
        let foot = Point3::new(
            fx,
            fy,
            terrain.max_height_in_disc(Point2::new(fx, fy), 0.15),
        );
        let pose = CarriagePose::level(body_y);
        let start = kin
            .inverse_world(&pose, &foot, ElbowBranch::Positive)
            .or_else(|_| kin.inverse_world(&pose, &foot, ElbowBranch::Negative))?;
        for _ in 0..repeats {
            let t0 = cpu_ns()?;
            let cs = lrp.cspace(&lrp_map, body_y)?;
            let t1 = cpu_ns()?;
            let reach = lrp.reachability(&cs, &start)?;
            let reachable = |p: Point2<f64>| reach.reaches(p);
            let maps = GaitMaps {
                footfall: &footfall,
                elevation: &elevation,
                reachable: &reachable,
            };
            let step = gait.plan(body_y, goal_y, &maps)?;
            let t2 = cpu_ns()?;
            let plan = lrp.plan_in(&cs, &start, &step.footfall)?;
            let t3 = cpu_ns()?;
            std::hint::black_box(plan);
            t_cspace += t1 - t0;
            t_gait += t2 - t1;
            t_leg += t3 - t2;
            n += 1;
        }
    }
    let ms = |t: u64| t as f64 / n as f64 / 1e6;
    println!(
        "CPU time per step, mean of {n} plans over {} course-3 steps:\n  \
         configuration space {:.2} ms\n  reachability + gait plan {:.2} ms\n  \
         ETFA + trajectory {:.2} ms\n  total {:.2} ms (target 20 ms; 1990: about 14 s)",
        steps.len(),
        ms(t_cspace),
        ms(t_gait),
        ms(t_leg),
        ms(t_cspace + t_gait + t_leg)
    );
    Ok(())
}
