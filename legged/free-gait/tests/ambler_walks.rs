//! The Ambler walks the courses with an ideal executor on the true terrain.

mod common;

use std::sync::Arc;

use common::{field, walk};
use nalgebra::Point2;
use tca_legged_model::RobotModel;

fn ambler() -> Arc<RobotModel> {
    Arc::new(RobotModel::builtin("ambler").expect("the Ambler loads"))
}

#[test]
fn ambler_walks_flat_ground_20_m() {
    let terrain = field((0.0, -7.0), (28.0, 7.0), 0.1, |_, _| 0.0);
    let w = walk("ambler flat", ambler(), terrain, (3.0, 0.0, 0.0), Point2::new(23.0, 0.0), 400);
    println!("ambler flat: {w:?}");
    assert!(w.reached, "{w:?}");
}
