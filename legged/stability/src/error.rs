//! The one error type of the crate.
//!
//! Every checked entry point refuses input it cannot give a meaningful answer for (NaN or
//! infinite coordinates, negative masses, no mass at all) with a [`StabilityError`] rather
//! than a panic or a silently wrong number. Each message says what was wrong and what to
//! give instead.

/// Why a stability computation refused its input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StabilityError {
    /// A point (a foot contact, a polygon vertex or a candidate foothold) has a NaN or
    /// infinite coordinate.
    #[error(
        "point {index} is ({x}, {y}), which is not finite; give every point finite coordinates in metres"
    )]
    NonFinitePoint {
        /// Position of the point in the slice that was passed.
        index: usize,
        /// Its X (east) coordinate as given.
        x: f64,
        /// Its Y (north) coordinate as given.
        y: f64,
    },
    /// The centre of gravity given to the quadrant test is NaN or infinite.
    #[error("centre of gravity ({x}, {y}) is not finite; give finite coordinates in metres")]
    NonFiniteCentre {
        /// X (east) coordinate as given.
        x: f64,
        /// Y (north) coordinate as given.
        y: f64,
    },
    /// The heading given to the quadrant test is NaN or infinite.
    #[error(
        "heading {0} rad is not finite; give a finite heading in radians, counter-clockwise from world +X (east)"
    )]
    NonFiniteHeading(f64),
    /// A link's mass or position is NaN or infinite.
    #[error(
        "link {index} has mass {mass_kg} kg at ({x}, {y}, {z}); give a finite mass in kilograms and a finite position in metres"
    )]
    NonFiniteLink {
        /// Position of the link in the slice that was passed.
        index: usize,
        /// Its mass as given, kg.
        mass_kg: f64,
        /// Its X coordinate as given, m.
        x: f64,
        /// Its Y coordinate as given, m.
        y: f64,
        /// Its Z coordinate as given, m.
        z: f64,
    },
    /// A link has a negative mass.
    #[error("link {index} has negative mass {mass_kg} kg; give every link a mass of zero or more")]
    NegativeMass {
        /// Position of the link in the slice that was passed.
        index: usize,
        /// Its mass as given, kg.
        mass_kg: f64,
    },
    /// The links' masses add up to zero (or there are no links), so there is no centre of
    /// mass.
    #[error(
        "the {links} links have a total mass of {total_kg} kg; give at least one link a mass above zero"
    )]
    NonPositiveTotalMass {
        /// Number of links passed.
        links: usize,
        /// Their total mass, kg.
        total_kg: f64,
    },
    /// The masses or positions are so large that their sum or the weighted mean overflows
    /// `f64`.
    #[error(
        "the centre of mass overflows f64 (total mass {total_kg} kg); rescale the masses or move the origin nearer the links"
    )]
    Overflow {
        /// The total mass as summed, kg (may be infinite).
        total_kg: f64,
    },
}
