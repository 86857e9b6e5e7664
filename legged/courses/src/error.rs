//! Why a course could not be built or written.

use tca_robot::TerrainError;
use tca_robot::terrain::asc::AscError;

/// Why a course could not be built or written.
#[derive(Debug, thiserror::Error)]
pub enum CourseError {
    /// No built-in course has this name.
    #[error("there is no built-in course `{name}`; the built-in courses are: {known}")]
    UnknownCourse {
        /// The name asked for.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// The terrain could not be rendered (a bug in a course's parameters).
    #[error("the course terrain could not be built: {0}")]
    Terrain(#[from] TerrainError),
    /// The `.asc` file could not be written.
    #[error("the course terrain could not be written: {0}")]
    Write(#[from] AscError),
}
