//! Errors of the robot views.

/// A robot that cannot be summarised or drawn.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The robot's standing posture could not be worked out.
    #[error(
        "robot {robot}: cannot work out its standing posture: {source}; check that every leg \
         reaches the ground with its joints at 0 (or their nearest limits)"
    )]
    Posture {
        /// The robot.
        robot: String,
        /// Why.
        #[source]
        source: tca_legged_model::KinematicsError,
    },
    /// The picture could not be encoded or written.
    #[error("cannot write the robot picture: {0}")]
    Picture(#[from] tca_canvas::CanvasError),
}
