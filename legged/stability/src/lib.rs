//! Static stability of multi-legged walkers: pure geometry, no robot model.
//!
//! A walker that moves slowly stays upright while its centre of mass is over its *support
//! polygon*, the convex hull of its standing feet seen from above. This crate computes that
//! polygon, a smaller *conservative* one that stays supported whichever one leg is lifted,
//! signed stability margins against either, the quadrant test on candidate footholds about
//! the centre of gravity, and the centre of mass from link masses.
//!
//! ```
//! use nalgebra::{Point2, Point3};
//! use tca_stability::{centre_of_mass, conservative_support_polygon, stability_margin, support_polygon};
//!
//! // Six feet of a hexapod standing on a regular hexagon of radius 0.5 m.
//! let feet: Vec<Point2<f64>> = (0..6)
//!     .map(|k| {
//!         let a = f64::from(k) * std::f64::consts::TAU / 6.0;
//!         Point2::new(0.5 * a.cos(), 0.5 * a.sin())
//!     })
//!     .collect();
//! let body = centre_of_mass(&[(10.0, Point3::new(0.05, 0.0, 0.4)), (2.0, Point3::new(-0.1, 0.0, 0.3))])?;
//! let margin = stability_margin(&support_polygon(&feet), body);
//! let conservative = stability_margin(&conservative_support_polygon(&feet), body);
//! assert!(margin > conservative && conservative > 0.0);
//! # Ok::<(), tca_stability::StabilityError>(())
//! ```
//!
//! # Layout
//!
//! - [`polygon`] has [`Polygon`], a convex polygon (counter-clockwise), with
//!   [`contains`](Polygon::contains), [`area`](Polygon::area), [`centroid`](Polygon::centroid)
//!   and [`signed_distance`](Polygon::signed_distance); degenerate polygons (empty, a point,
//!   a segment) have no interior.
//! - [`hull`] has [`support_polygon`], the convex hull of the standing feet.
//! - [`intersection`] has [`Polygon::intersection`] of convex polygons.
//! - [`conservative`] has [`conservative_support_polygon`], the intersection of the support
//!   polygons left by lifting each standing foot in turn.
//! - [`margin`] has [`stability_margin`] of a centre of mass, and its exact minimum along
//!   straight moves ([`margin_along`], [`margin_along_path`]).
//! - [`quadrants`] has [`quadrant_test`]: which quadrants about the centre of gravity (in a
//!   frame turned by the heading) hold a candidate foothold.
//! - [`mass`] has [`centre_of_mass`] of links.
//! - [`error`] has [`StabilityError`].
//!
//! # Frames and units
//!
//! SI units: metres, kilograms, radians. Positions are in the world frame of ROS REP 103:
//! +X east, +Y north, +Z up. Stability is judged in the horizontal XY plane: feet and centres
//! of mass are projected straight down along Z, so only their X and Y count. Headings are
//! counter-clockwise from +X.
//!
//! # Bad input and rounding
//!
//! Nothing here panics on bad input. Constructors and tests that need finite input
//! ([`Polygon::convex_hull`], [`try_conservative_support_polygon`], [`quadrant_test`],
//! [`centre_of_mass`]) return a [`StabilityError`]. [`support_polygon`] and
//! [`conservative_support_polygon`] never fail: a NaN or infinite foot gives the empty
//! polygon, which supports nothing. Distance queries with a non-finite point return NaN.
//!
//! Geometry is in `f64`. Vertices within about 1e-12 of the largest coordinate of another
//! vertex, or of the line through their neighbours, are merged away, and intersecting
//! polygons counts a corner that close to the other polygon as in it; a point within rounding
//! of a boundary may test either side of it.

pub mod conservative;
pub mod error;
pub mod hull;
pub mod intersection;
pub mod margin;
pub mod mass;
pub mod polygon;
pub mod quadrants;

pub use conservative::{conservative_support_polygon, try_conservative_support_polygon};
pub use error::StabilityError;
pub use hull::support_polygon;
pub use margin::{
    MinimumMargin, ground_projection, margin_along, margin_along_path, stability_margin,
};
pub use mass::centre_of_mass;
pub use polygon::Polygon;
pub use quadrants::{Quadrant, QuadrantReport, quadrant_test};

#[cfg(test)]
mod properties_tests;
