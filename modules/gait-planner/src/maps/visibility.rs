//! The scanner visibility map (§6.2.1): whether the horizontal links would be in the laser
//! scanner's field of view after the body move, the carriage moving its largest advance
//! from each footfall. Graded as the fraction of the links' length in view (the report's
//! binary map, extended as it proposed).

use nalgebra::{Isometry3, Point3};
use tca_robot::{ElbowBranch, Grid, LegKinematics, LegParams};

use crate::params::VisibilityParams;
use crate::region::StepRegion;

/// Fraction of the links' sample points inside the field of view, per cell, after moving
/// the carriage by `advance(cell)`; 0 where the cell has no advance entry.
pub(crate) fn visibility_map(
    region: &StepRegion,
    leg: &LegParams,
    kin: &LegKinematics,
    params: &VisibilityParams,
    advance: &Grid<Option<(f64, ElbowBranch)>>,
    move_of: impl Fn(f64) -> f64,
) -> Grid<f64> {
    let scanner_from_carriage: Isometry3<f64> = leg.scanner.carriage_from_scanner().inverse();
    let (l1, _) = kin.link_lengths_m();
    let vertical = 0.5 * (leg.leg.vertical.min_m + leg.leg.vertical.max_m);
    // Inside the field of view: in front of the scanner, within half the azimuth and half
    // the elevation field of the boresight (compared through tangents, no trigonometry).
    let tan_az = (0.5 * params.azimuth_fov_rad).min(1.5).tan();
    let tan_el = (0.5 * params.elevation_fov_rad).min(1.5).tan();
    let in_view = |p: Point3<f64>| {
        let s = scanner_from_carriage * p;
        s.x > 0.0 && s.y.abs() <= s.x * tan_az && s.z.abs() <= s.x.hypot(s.y) * tan_el
    };
    let sign = region.direction.sign();
    let mut out = region.grid_of(0.0);
    for ((c, v), (_, a)) in out.iter_mut().zip(advance.iter()) {
        let Some((a_max, branch)) = *a else { continue };
        let p = region.layout.cell_center(c);
        let moved = move_of(a_max);
        let foot = Point3::new(
            p.x - region.column_x_m,
            p.y - (region.body_y_m + sign * moved),
            -vertical,
        );
        let Ok(q) = kin.inverse(&foot, branch) else {
            continue;
        };
        let elbow = Point3::new(l1 * q.shoulder_rad.cos(), l1 * q.shoulder_rad.sin(), 0.0);
        let end = Point3::new(foot.x, foot.y, 0.0);
        let (mut seen, mut total) = (0usize, 0usize);
        for (a, b) in [(Point3::origin(), elbow), (elbow, end)] {
            let n = ((b - a).norm() / params.link_sample_m).ceil().max(1.0) as usize;
            for k in 1..=n {
                let t = k as f64 / n as f64;
                total += 1;
                if in_view(a + (b - a) * t) {
                    seen += 1;
                }
            }
        }
        *v = seen as f64 / total.max(1) as f64;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maps::advance::advance_map;
    use crate::region::WalkDirection;

    #[test]
    fn links_ahead_of_the_carriage_are_seen_and_links_behind_are_not() {
        // The scanner pitched 35° down, the mount this scene was laid out for (the shipped
        // mount looks more steeply down, at the first footfalls).
        let mut leg = LegParams::default();
        leg.scanner.pitch_down_rad = 35f64.to_radians();
        let kin = LegKinematics::new(&leg);
        let region = StepRegion::new(&leg, 0.1, 2.0, WalkDirection::Forward).unwrap();
        let advance = advance_map(&region, &leg, &kin);
        // No body move: a foot 2.2 m straight ahead puts the links under the scanner's gaze.
        let none = visibility_map(
            &region,
            &leg,
            &kin,
            &crate::params::GaitParams::default().scanner_visibility,
            &advance,
            |_| 0.0,
        );
        let ahead = region
            .layout
            .cell_at(nalgebra::Point2::new(3.05, 4.15))
            .unwrap();
        assert!(
            *none.get(ahead).unwrap() > 0.2,
            "{}",
            none.get(ahead).unwrap()
        );
        // After a 1.5 m body move a footfall 0.5 m ahead ends behind the carriage: unseen.
        let moved = visibility_map(
            &region,
            &leg,
            &kin,
            &crate::params::GaitParams::default().scanner_visibility,
            &advance,
            |a| a.min(1.5),
        );
        let near = region
            .layout
            .cell_at(nalgebra::Point2::new(3.95, 2.55))
            .unwrap();
        assert_eq!(*moved.get(near).unwrap(), 0.0);
    }
}
