//! The body advance map (§6.2.1): how far the carriage can travel from each footfall before
//! the leg reaches its full extension (or another joint limit), from the kinematics.
//!
//! With the foot planted, a body move of `a` shifts the foot by `-a` along the carriage's Y.
//! For every column of the grid (fixed carriage X of the foot) the foot's positions are
//! sampled every quarter cell along Y, each checked on both elbow branches for reach (the
//! elbow kept `min_abs_elbow_rad` from straight, as the Controller's body move does) and
//! joint limits; the advance from a cell is the length of the run of feasible samples it
//! starts, so it is conservative by at most a quarter cell.

use nalgebra::Point3;
use tca_robot::{ElbowBranch, Grid, JointPosition, LegKinematics, LegParams};

use crate::region::{StepRegion, WalkDirection};

/// Samples per grid cell along Y.
const SAMPLES_PER_CELL: usize = 4;

/// Per cell: the largest advance (metres, >= 0) and the elbow branch giving it; `None` where
/// the foot cannot be at the cell at all.
pub(crate) fn advance_map(
    region: &StepRegion,
    leg: &LegParams,
    kin: &LegKinematics,
) -> Grid<Option<(f64, ElbowBranch)>> {
    let res = region.layout.resolution_m();
    let h = res / SAMPLES_PER_CELL as f64;
    let reach = leg.leg.upper_link_m + leg.leg.lower_link_m;
    let k_max = (reach / h).ceil() as isize + SAMPLES_PER_CELL as isize;
    let vertical = 0.5 * (leg.leg.vertical.min_m + leg.leg.vertical.max_m);
    let min_elbow = leg.body_move.min_abs_elbow_rad;
    let feasible = |x: f64, y: f64, branch: ElbowBranch| -> Option<JointPosition> {
        kin.inverse(&Point3::new(x, y, -vertical), branch)
            .ok()
            .filter(|q| q.elbow_rad.abs() >= min_elbow)
    };
    let (nx, ny) = (region.layout.nx(), region.layout.ny());
    let mut out = region.grid_of(None);
    let o = region.layout.origin();
    let samples = (2 * k_max + 1) as usize;
    let mut run = vec![0isize; samples];
    for ix in 0..nx {
        let x = o.x + ix as f64 * res - region.column_x_m;
        for branch in [ElbowBranch::Positive, ElbowBranch::Negative] {
            // run[k]: the index of the far end of the feasible run containing sample k (the
            // lowest Y walking forward, the highest walking backward), or -1.
            let ok: Vec<bool> = (-k_max..=k_max)
                .map(|k| feasible(x, k as f64 * h, branch).is_some())
                .collect();
            match region.direction {
                WalkDirection::Forward => {
                    for k in 0..samples {
                        run[k] = match (ok[k], k.checked_sub(1)) {
                            (false, _) => -1,
                            (true, Some(prev)) if ok[prev] => run[prev],
                            (true, _) => k as isize,
                        };
                    }
                }
                WalkDirection::Backward => {
                    for k in (0..samples).rev() {
                        run[k] = match (ok[k], ok.get(k + 1)) {
                            (false, _) => -1,
                            (true, Some(true)) => run[k + 1],
                            (true, _) => k as isize,
                        };
                    }
                }
            }
            for iy in 0..ny {
                let y = o.y + iy as f64 * res - region.body_y_m;
                let k = (y / h).round() as isize + k_max;
                let Some(&end) = usize::try_from(k).ok().and_then(|k| run.get(k)) else {
                    continue;
                };
                if end < 0 {
                    continue;
                }
                let advance = ((k - end) as f64 * h).abs();
                if let Some(cell) = out.get_mut(tca_robot::CellIndex::new(ix, iy)) {
                    let better = cell.is_none_or(|(a, _)| advance > a);
                    if better {
                        *cell = Some((advance, branch));
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_advance_ends_at_full_extension_or_at_the_column() {
        let leg = LegParams::default();
        let kin = LegKinematics::new(&leg);
        let region = StepRegion::new(&leg, 0.1, 2.0, WalkDirection::Forward).unwrap();
        let map = advance_map(&region, &leg, &kin);
        // The cell 1.05 m ahead of the column and 1.05 m to its side: the foot can travel
        // back until it is 2.5 m (nearly straight links) from the column.
        let c = region
            .layout
            .cell_at(nalgebra::Point2::new(4.05, 3.05))
            .unwrap();
        let (a, _) = map.get(c).unwrap().unwrap();
        let expected = 1.05 + (2.499f64.powi(2) - 1.05f64.powi(2)).sqrt();
        assert!((a - expected).abs() < 0.06, "{a} vs {expected}");
        // 0.25 m to the side, the foot meets the column's inner limit (0.556 m) first.
        let c = region
            .layout
            .cell_at(nalgebra::Point2::new(3.25, 3.05))
            .unwrap();
        let (a, _) = map.get(c).unwrap().unwrap();
        let expected = 1.05 - (0.556f64.powi(2) - 0.25f64.powi(2)).sqrt();
        assert!((a - expected).abs() < 0.06, "{a} vs {expected}");
        // Out of reach cells have no advance.
        let corner = region
            .layout
            .cell_at(nalgebra::Point2::new(0.55, 4.45))
            .unwrap();
        assert!(map.get(corner).unwrap().is_none());
        // Far to the side, the advance is short.
        let side = region
            .layout
            .cell_at(nalgebra::Point2::new(5.45, 2.15))
            .unwrap();
        let (a, _) = map.get(side).unwrap().unwrap();
        assert!(a < 1.0, "{a}");
    }

    #[test]
    fn walking_backward_mirrors_walking_forward() {
        let leg = LegParams::default();
        let kin = LegKinematics::new(&leg);
        let fwd = StepRegion::new(&leg, 0.1, 5.0, WalkDirection::Forward).unwrap();
        let back = StepRegion::new(&leg, 0.1, 5.0, WalkDirection::Backward).unwrap();
        let f = advance_map(&fwd, &leg, &kin);
        let b = advance_map(&back, &leg, &kin);
        let a = |g: &Grid<Option<(f64, ElbowBranch)>>, r: &StepRegion, y: f64| {
            g.get(r.layout.cell_at(nalgebra::Point2::new(3.95, y)).unwrap())
                .unwrap()
                .unwrap()
                .0
        };
        let (af, ab) = (a(&f, &fwd, 6.05), a(&b, &back, 3.95));
        assert!((af - ab).abs() < 0.06, "{af} vs {ab}");
    }
}
