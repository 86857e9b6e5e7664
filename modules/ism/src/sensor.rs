//! What the ISM asks of a sensor, real or virtual (§5.2.1).

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
}
