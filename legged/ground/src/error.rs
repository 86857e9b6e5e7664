//! What can go wrong on the ground side.

/// The ground side's errors; each says what was wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GroundError {
    /// A setting, the robot or its state does not allow what was asked.
    #[error("{0}")]
    Setup(String),
    /// A module could not connect, send or be answered.
    #[error(transparent)]
    Module(#[from] tca_module::ModuleError),
    /// The bridge could not start or play back.
    #[error(transparent)]
    Bridge(#[from] tca_bridge::BridgeError),
}
