//! Scenes shared by the Gait Planner's tests.

#![allow(dead_code, unreachable_pub)]

use nalgebra::{Point2, Point3};
use tca_gait_planner::{GaitMaps, GaitParams, GaitPlanner, Result, StepPlan, synthetic};
use tca_lrp::{LegRecoveryPlanner, LrpParams, TerrainGrid};
use tca_robot::{CarriagePose, ElbowBranch, HeightField, JointPosition, LegKinematics, LegParams};

pub fn planner() -> GaitPlanner {
    GaitPlanner::new(LegParams::default(), GaitParams::default()).unwrap()
}

/// Footfall and elevation maps (10 cm) over the polygon the planner asks for.
pub fn maps_for(terrain: &HeightField, body_y: f64, goal_y: f64) -> (TerrainGrid, TerrainGrid) {
    let p = planner();
    let region = p.region(body_y, goal_y).unwrap();
    let poly = p.map_polygon(&region);
    let lo = Point2::new(poly[0].x_m, poly[0].y_m);
    let hi = Point2::new(poly[2].x_m, poly[2].y_m);
    (
        synthetic::footfall_map(terrain, lo, hi, 0.1, 0.15).unwrap(),
        synthetic::elevation_map(terrain, lo, hi, 0.1).unwrap(),
    )
}

/// Plans a step with every cell reachable.
pub fn plan_open(terrain: &HeightField, body_y: f64, goal_y: f64) -> Result<StepPlan> {
    let (footfall, elevation) = maps_for(terrain, body_y, goal_y);
    planner().plan(
        body_y,
        goal_y,
        &GaitMaps {
            footfall: &footfall,
            elevation: &elevation,
            reachable: &|_| true,
        },
    )
}

/// Plans a step with the Leg Recovery Planner's reachability from a foot at `start`.
pub fn plan_with_lrp(
    terrain: &HeightField,
    body_y: f64,
    goal_y: f64,
    start: &JointPosition,
) -> Result<StepPlan> {
    let (footfall, elevation) = maps_for(terrain, body_y, goal_y);
    let lrp = LegRecoveryPlanner::new(LegParams::default(), LrpParams::default()).unwrap();
    let lrp_map = TerrainGrid::elevation_from_height_field(
        terrain,
        Point2::new(0.0, body_y - 2.9),
        Point2::new(6.0, body_y + 2.9),
        0.05,
    )
    .unwrap();
    let cs = lrp.cspace(&lrp_map, body_y).unwrap();
    let reach = lrp.reachability(&cs, start).unwrap();
    planner().plan(
        body_y,
        goal_y,
        &GaitMaps {
            footfall: &footfall,
            elevation: &elevation,
            reachable: &|p| reach.reaches(p),
        },
    )
}

/// Joints of a foot resting on the ground at `xy`.
pub fn planted(terrain: &HeightField, body_y: f64, xy: Point2<f64>) -> JointPosition {
    let z = terrain.max_height_in_disc(xy, 0.15);
    LegKinematics::new(&LegParams::default())
        .inverse_world(
            &CarriagePose::level(body_y),
            &Point3::new(xy.x, xy.y, z),
            ElbowBranch::Positive,
        )
        .unwrap()
}

/// Height range of the true terrain over a disc, metres.
pub fn relief(terrain: &HeightField, c: Point2<f64>, radius: f64) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let n = 24;
    for i in 0..=n {
        for j in 0..=n {
            let p = Point2::new(
                c.x - radius + 2.0 * radius * f64::from(i) / f64::from(n),
                c.y - radius + 2.0 * radius * f64::from(j) / f64::from(n),
            );
            if (p - c).norm() <= radius {
                let h = terrain.height_at(p.x, p.y);
                lo = lo.min(h);
                hi = hi.max(h);
            }
        }
    }
    hi - lo
}
