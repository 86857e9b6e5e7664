//! Scanner-to-body calibration (§5.2.1): a reflective target on the leg is moved to several
//! poses; at each the Controller gives the target's position in the body frame B and the
//! scanner sees it in the scanner frame S; the rigid transform `S_T_B` is then the least-squares
//! fit of the point pairs.
//!
//! - [`fit_scanner_from_body`]: the least-squares rigid fit (Kabsch/Horn: centroids, SVD of the
//!   cross-covariance, a reflection guard), with residuals.
//! - [`locate_target`]: finds a retro-reflective sphere in an image (the saturated pixels) and
//!   fits a sphere of the known radius to their points (Gauss–Newton from the centroid pushed
//!   back by 2/3 of the radius), giving its centre in S.
//! - [`calibrate`]: the whole procedure with a virtual scanner.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use tca_robot::CarriagePose;
use tca_single_leg_messages::RangeImage;

use crate::error::{IsmError, Result};
use crate::frames::ImageFrames;
use crate::scanner::{SphereTarget, VirtualScanner};
use crate::sensor::RangeSensor;
use crate::spec::{PixelDirections, SensorSpec};

/// One observation: the same point in the body and in the scanner frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correspondence {
    /// The target in the body (carriage) frame, from the Controller.
    pub in_body: Point3<f64>,
    /// The target in the scanner frame, from the image.
    pub in_scanner: Point3<f64>,
}

/// The result of a calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationFit {
    /// The estimated `S_T_B`.
    pub scanner_from_body: Isometry3<f64>,
    /// Root mean square distance between the observed and the fitted scanner-frame points,
    /// metres.
    pub rms_residual_m: f64,
    /// Largest such distance, metres.
    pub max_residual_m: f64,
    /// Observations used.
    pub observations: usize,
}

/// The rigid transform `S_T_B` minimising `sum |in_scanner - S_T_B in_body|^2`. Needs at
/// least three observations not all on one line.
pub fn fit_scanner_from_body(pairs: &[Correspondence]) -> Result<CalibrationFit> {
    if pairs.len() < 3 {
        return Err(IsmError::Calibration(format!(
            "{} observation(s) given; at least three target poses not on one line are needed",
            pairs.len()
        )));
    }
    if let Some(p) = pairs.iter().find(|p| {
        !(p.in_body.coords.iter().all(|v| v.is_finite())
            && p.in_scanner.coords.iter().all(|v| v.is_finite()))
    }) {
        return Err(IsmError::Calibration(format!(
            "observation {p:?} is not finite"
        )));
    }
    let n = pairs.len() as f64;
    let cb = pairs.iter().map(|p| p.in_body.coords).sum::<Vector3<f64>>() / n;
    let cs = pairs
        .iter()
        .map(|p| p.in_scanner.coords)
        .sum::<Vector3<f64>>()
        / n;
    let mut h = Matrix3::zeros();
    let mut spread = Matrix3::zeros();
    for p in pairs {
        let b = p.in_body.coords - cb;
        let s = p.in_scanner.coords - cs;
        h += b * s.transpose();
        spread += b * b.transpose();
    }
    let mut eig: Vec<f64> = spread.symmetric_eigenvalues().iter().copied().collect();
    eig.sort_by(|a, b| b.total_cmp(a));
    if !(eig[0] > 1e-12 && eig[1] > 1e-8 * eig[0]) {
        return Err(IsmError::Calibration(
            "the target positions lie on one line (or one point); move the target to poses \
             spread over a plane or a volume"
                .into(),
        ));
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(IsmError::Calibration(
            "the singular value decomposition did not converge".into(),
        ));
    };
    let v = v_t.transpose();
    let sign = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, sign)) * u.transpose();
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = cs - rotation * cb;
    let scanner_from_body = Isometry3::from_parts(Translation3::from(t), rotation);
    let residuals: Vec<f64> = pairs
        .iter()
        .map(|p| (scanner_from_body * p.in_body - p.in_scanner).norm())
        .collect();
    Ok(CalibrationFit {
        scanner_from_body,
        rms_residual_m: (residuals.iter().map(|r| r * r).sum::<f64>() / n).sqrt(),
        max_residual_m: residuals.iter().copied().fold(0.0, f64::max),
        observations: pairs.len(),
    })
}

/// Finds a retro-reflective sphere of radius `radius_m` in an image: pixels whose reflectance
/// is at least `min_reflectance` of full scale are its points. Returns its centre in the
/// scanner frame.
pub fn locate_target(
    image: &RangeImage,
    radius_m: f64,
    min_reflectance: f64,
) -> Result<Point3<f64>> {
    let spec = SensorSpec::of(image.sensor);
    spec.check_image(image)?;
    let not_found = |reason: String| IsmError::TargetNotFound {
        sequence: image.sequence,
        reason,
    };
    if !(radius_m.is_finite() && radius_m > 0.0) {
        return Err(IsmError::Calibration(format!(
            "the target radius must be a positive length, got {radius_m}"
        )));
    }
    let frames = ImageFrames::of(image)?;
    let dirs = PixelDirections::new(&spec);
    let threshold =
        (min_reflectance.clamp(0.0, 1.0) * f64::from(spec.max_reflectance_count())).max(1.0);
    let width = spec.width_px as usize;
    let points: Vec<Vector3<f64>> = image
        .reflectance
        .iter()
        .zip(&image.range_counts)
        .enumerate()
        .filter(|&(_, (&refl, _))| f64::from(refl) >= threshold)
        .filter_map(|(i, (_, &count))| {
            dirs.get(i / width, i % width)
                .map(|d| d * spec.count_range_m(count))
        })
        .collect();
    if points.len() < 6 {
        return Err(not_found(format!(
            "{} pixel(s) at or above {:.0} % reflectance; at least 6 are needed",
            points.len(),
            100.0 * min_reflectance
        )));
    }
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let Some(view) = centroid.try_normalize(1e-12) else {
        return Err(not_found("the target's points are at the scanner".into()));
    };
    // The visible cap's points average 2/3 of a radius in front of the centre.
    let mut c = centroid + view * (2.0 / 3.0 * radius_m);
    for _ in 0..30 {
        let mut jtj = Matrix3::zeros();
        let mut jte = Vector3::zeros();
        for p in &points {
            let diff = p - c;
            let dist = diff.norm();
            if dist < 1e-12 {
                continue;
            }
            let j = -diff / dist;
            let e = dist - radius_m;
            jtj += j * j.transpose();
            jte += j * e;
        }
        let Some(step) = jtj.lu().solve(&(-jte)) else {
            break;
        };
        c += step;
        if step.norm() < 1e-10 {
            break;
        }
    }
    if !c.iter().all(|v| v.is_finite()) {
        return Err(not_found("the sphere fit diverged".into()));
    }
    Ok(frames.locus_from_scanner.inverse() * Point3::from(c))
}

/// One pose of the calibration procedure: where the carriage is and where the Controller
/// says the target on the leg is, in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationPose {
    /// The carriage pose.
    pub carriage: CarriagePose,
    /// The target's centre in the body (carriage) frame.
    pub target_in_body: Point3<f64>,
}

/// The calibration procedure with a virtual scanner: at each pose a sphere target of
/// `radius_m` is placed where the leg holds it, an image is acquired and the target located;
/// the transform is then fitted. The scanner's calibration is not changed: apply the result
/// with [`VirtualScanner::set_calibration`].
pub fn calibrate(
    scanner: &mut VirtualScanner,
    poses: &[CalibrationPose],
    radius_m: f64,
) -> Result<CalibrationFit> {
    let mut pairs = Vec::with_capacity(poses.len());
    let result = (|| {
        for pose in poses {
            let center =
                pose.carriage.world_from_carriage(scanner.carriage_params()) * pose.target_in_body;
            scanner.set_targets(vec![SphereTarget { center, radius_m }]);
            let image = scanner.acquire(&pose.carriage)?;
            let in_scanner = locate_target(&image, radius_m, 0.999)?;
            tracing::debug!(
                sequence = image.sequence,
                ?in_scanner,
                "calibration target located"
            );
            pairs.push(Correspondence {
                in_body: pose.target_in_body,
                in_scanner,
            });
        }
        fit_scanner_from_body(&pairs)
    })();
    scanner.set_targets(Vec::new());
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn transform(a: f64, b: f64, c: f64, t: [f64; 3]) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(t[0], t[1], t[2]),
            UnitQuaternion::from_euler_angles(a, b, c),
        )
    }

    #[test]
    fn too_few_or_collinear_observations_are_refused() {
        let p = |x: f64| Correspondence {
            in_body: Point3::new(x, 0.0, 0.0),
            in_scanner: Point3::new(x, 1.0, 0.0),
        };
        let e = fit_scanner_from_body(&[p(0.0), p(1.0)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("at least three"), "{e}");
        let e = fit_scanner_from_body(&[p(0.0), p(1.0), p(2.0)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("one line"), "{e}");
    }

    proptest! {
        #[test]
        fn exact_observations_give_back_the_transform(
            a in -3.0..3.0f64, b in -1.5..1.5f64, c in -3.0..3.0f64,
            tx in -5.0..5.0f64, ty in -5.0..5.0f64, tz in -5.0..5.0f64,
            pts in proptest::collection::vec((-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64), 4..12),
        ) {
            let truth = transform(a, b, c, [tx, ty, tz]);
            let pairs: Vec<_> = pts.iter().map(|&(x, y, z)| {
                let in_body = Point3::new(x, y, z);
                Correspondence { in_body, in_scanner: truth * in_body }
            }).collect();
            match fit_scanner_from_body(&pairs) {
                Ok(fit) => {
                    let err = (fit.scanner_from_body.to_homogeneous() - truth.to_homogeneous()).abs().max();
                    prop_assert!(err < 1e-6, "error {}", err);
                    prop_assert!(fit.rms_residual_m < 1e-6);
                }
                // Random points can be (nearly) collinear; that must be the only failure.
                Err(e) => prop_assert!(e.to_string().contains("one line")),
            }
        }
    }
}
