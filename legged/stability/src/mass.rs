//! Centre of mass of a walker from the masses and positions of its links.
//!
//! The centre of mass is the mass-weighted mean of the links' own centres of mass, all given
//! in one frame (usually the world frame, so the result can be projected onto the ground for
//! a stability margin). Links of zero mass are allowed and count for nothing.

use nalgebra::{Point3, Vector3};

use crate::error::StabilityError;

/// The centre of mass of links given as `(mass_kg, centre of that link in metres)`.
///
/// # Errors
///
/// - [`StabilityError::NonFiniteLink`] if a mass or coordinate is NaN or infinite;
/// - [`StabilityError::NegativeMass`] if a mass is below zero;
/// - [`StabilityError::NonPositiveTotalMass`] if there are no links or all masses are zero;
/// - [`StabilityError::Overflow`] if the total mass or the weighted mean does not fit in
///   `f64`.
pub fn centre_of_mass(links: &[(f64, Point3<f64>)]) -> Result<Point3<f64>, StabilityError> {
    let mut total_kg = 0.0;
    for (index, &(mass_kg, p)) in links.iter().enumerate() {
        if !(mass_kg.is_finite() && p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(StabilityError::NonFiniteLink {
                index,
                mass_kg,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        if mass_kg < 0.0 {
            return Err(StabilityError::NegativeMass { index, mass_kg });
        }
        total_kg += mass_kg;
    }
    if total_kg.is_infinite() {
        return Err(StabilityError::Overflow { total_kg });
    }
    if total_kg <= 0.0 {
        return Err(StabilityError::NonPositiveTotalMass {
            links: links.len(),
            total_kg,
        });
    }
    // Weights of at most one keep the products within the range of the positions.
    let mean: Vector3<f64> = links
        .iter()
        .map(|&(mass_kg, p)| p.coords * (mass_kg / total_kg))
        .sum();
    if mean.iter().all(|c| c.is_finite()) {
        Ok(Point3::from(mean))
    } else {
        Err(StabilityError::Overflow { total_kg })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    #[test]
    fn weighted_mean() {
        let links = [(1.0, q(0.0, 0.0, 0.0)), (3.0, q(4.0, 0.0, 2.0))];
        let c = centre_of_mass(&links).unwrap();
        assert!((c - q(3.0, 0.0, 1.5)).norm() < 1e-15);
    }

    #[test]
    fn single_link_and_massless_links() {
        let links = [(0.0, q(9.0, 9.0, 9.0)), (2.5, q(1.0, 2.0, 3.0))];
        assert_eq!(centre_of_mass(&links).unwrap(), q(1.0, 2.0, 3.0));
    }

    #[test]
    fn refuses_no_mass() {
        assert_eq!(
            centre_of_mass(&[]),
            Err(StabilityError::NonPositiveTotalMass {
                links: 0,
                total_kg: 0.0
            })
        );
        let err = centre_of_mass(&[(0.0, q(0.0, 0.0, 0.0))]).unwrap_err();
        assert!(matches!(
            err,
            StabilityError::NonPositiveTotalMass { links: 1, .. }
        ));
        assert!(err.to_string().contains("above zero"));
    }

    #[test]
    fn refuses_negative_and_non_finite() {
        assert_eq!(
            centre_of_mass(&[(1.0, q(0.0, 0.0, 0.0)), (-0.5, q(1.0, 0.0, 0.0))]),
            Err(StabilityError::NegativeMass {
                index: 1,
                mass_kg: -0.5
            })
        );
        assert!(matches!(
            centre_of_mass(&[(f64::NAN, q(0.0, 0.0, 0.0))]),
            Err(StabilityError::NonFiniteLink { index: 0, .. })
        ));
        assert!(matches!(
            centre_of_mass(&[(1.0, q(0.0, f64::INFINITY, 0.0))]),
            Err(StabilityError::NonFiniteLink { index: 0, .. })
        ));
    }

    #[test]
    fn refuses_overflow() {
        assert!(matches!(
            centre_of_mass(&[(f64::MAX, q(0.0, 0.0, 0.0)), (f64::MAX, q(1.0, 0.0, 0.0))]),
            Err(StabilityError::Overflow { .. })
        ));
        // Weighting before summing keeps positions near the top of the range usable.
        assert_eq!(
            centre_of_mass(&[(1.0, q(f64::MAX, 0.0, 0.0)), (1.0, q(f64::MAX, 0.0, 0.0))]),
            Ok(q(f64::MAX, 0.0, 0.0))
        );
    }
}
