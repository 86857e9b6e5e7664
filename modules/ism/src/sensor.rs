//! What the ISM asks of a sensor, real or virtual (§5.2.1).

use nalgebra::Isometry3;
use tca_robot::CarriagePose;
use tca_single_leg_messages::RangeImage;

use crate::error::Result;
use crate::spec::SensorSpec;

/// A source of range/reflectance images: the simulated scanner
/// ([`crate::VirtualScanner`]) or a stored sequence ([`crate::StoredSequence`]).
pub trait RangeSensor: Send {
    /// The sensor's characteristics.
    fn spec(&self) -> &SensorSpec;

    /// Acquires the next image with the carriage at `pose` (stored sequences ignore the pose:
    /// their images keep the transforms they were recorded with).
    fn acquire(&mut self, pose: &CarriagePose) -> Result<RangeImage>;

    /// Acquires the next image with the body the sensor is mounted on at `world_from_body`
    /// (a legged robot's body: any position, roll, pitch and yaw). Sensors that cannot image
    /// from a free body pose say so; stored sequences ignore the pose.
    fn acquire_from_body(&mut self, world_from_body: &Isometry3<f64>) -> Result<RangeImage> {
        let _ = world_from_body;
        Err(crate::IsmError::Config(format!(
            "the {:?} sensor cannot image from a legged robot's body pose; configure a \
             VirtualScanner::on_body or a stored sequence",
            self.spec().kind
        )))
    }
}
