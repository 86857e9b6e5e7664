//! The CG-cell tests: the quadrant test and the vertical-reach test.

use serde::{Deserialize, Serialize};

use crate::footmap::FootMap;
use crate::grid::{CgCell, CgGrid};
use crate::robot::{CgRobot, HeadingTable};

/// Why a CG cell is valid or not.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Verdict {
    /// Valid: the body can stand at heights `lo..hi` (world Z of the body origin, metres).
    Valid {
        /// Lowest body height (the under-carriage's clearance).
        lo: f64,
        /// A body height at which every quadrant holds a reachable foot cell.
        at: f64,
    },
    /// The body's footprint leaves the map.
    OffMap,
    /// Quadrant `0..4` (front-left, rear-left, rear-right, front-right) holds no valid foot
    /// cell in any leg's range.
    EmptyQuadrant(u8),
    /// Every quadrant holds a valid foot cell, but no body height lets one foot per
    /// quadrant reach the ground with the under-carriage clear of it.
    NoHeight,
    /// Marked invalid from outside (the foot-level search found it impassable).
    Marked,
}

impl Verdict {
    /// Whether the cell is valid.
    pub fn is_valid(&self) -> bool {
        matches!(self, Verdict::Valid { .. })
    }

    /// The verdict in words, for messages.
    pub fn describe(&self) -> String {
        match *self {
            Verdict::Valid { lo, at } => {
                format!(
                    "valid: the body origin from {lo:.3} m up, every quadrant held at {at:.3} m"
                )
            }
            Verdict::OffMap => "the robot's underside there reaches past the map's edge (a point \
                 further inside the map, or a larger map)"
                .to_owned(),
            Verdict::EmptyQuadrant(q) => format!(
                "no leg can reach a foot cell with traction in the {} quadrant",
                ["front-left", "rear-left", "rear-right", "front-right"]
                    .get(usize::from(q))
                    .copied()
                    .unwrap_or("unknown")
            ),
            Verdict::NoHeight => "no body height lets a foot in every quadrant reach the ground \
                 with the underside clear of it"
                .to_owned(),
            Verdict::Marked => "the foot-level search found it impassable".to_owned(),
        }
    }
}

/// The lowest the body origin may stand over a CG cell so that its under-carriage clears
/// the ground by the clearance: `max(land + depth)`; `None` if part of it is off the map.
pub fn min_body_height(
    robot: &CgRobot,
    table: &HeadingTable,
    foot: &FootMap,
    ix: i32,
    iy: i32,
) -> Option<f64> {
    let mut h = f64::NEG_INFINITY;
    for u in &table.under {
        let land = foot.height(ix + u.di, iy + u.dj)?;
        h = h.max(land + u.depth);
    }
    Some(h + robot.params.clearance_m)
}

/// The body-height interval (world Z of the body origin) over which a foot of radius
/// `radius` on ground `ground` keeps its contact centre within `z_lo..z_hi` (body z).
pub fn foot_interval(ground: f64, radius: f64, z_lo: f64, z_hi: f64) -> (f64, f64) {
    (ground + radius - z_hi, ground + radius - z_lo)
}

/// Tests one CG cell: the quadrant test and the vertical-reach test.
pub fn assess(robot: &CgRobot, grid: &CgGrid, foot: &FootMap, cell: CgCell) -> Verdict {
    if !grid.contains(cell) {
        return Verdict::OffMap;
    }
    let table = &robot.headings[usize::from(cell.it)];
    let Some(min_h) = min_body_height(robot, table, foot, cell.ix, cell.iy) else {
        return Verdict::OffMap;
    };
    // Body-height intervals offered by each quadrant's reachable valid foot cells.
    let mut spans: Vec<(f64, f64, u8)> = Vec::new();
    let mut seen = [false; 4];
    for (leg, cells) in table.legs.iter().enumerate() {
        let r = robot.foot_radius[leg];
        for c in cells {
            if c.quadrant > 3 {
                continue;
            }
            let (fx, fy) = (cell.ix + c.di, cell.iy + c.dj);
            if !foot.valid(fx, fy) {
                continue;
            }
            let Some(g) = foot.height(fx, fy) else {
                continue;
            };
            seen[usize::from(c.quadrant)] = true;
            let (lo, hi) = foot_interval(g, r, c.z_lo, c.z_hi);
            let lo = lo.max(min_h);
            if lo <= hi {
                spans.push((lo, hi, c.quadrant));
            }
        }
    }
    if let Some(q) = (0..4u8).find(|&q| !seen[usize::from(q)]) {
        return Verdict::EmptyQuadrant(q);
    }
    match lowest_common_height(&spans) {
        Some(at) => Verdict::Valid { lo: min_h, at },
        None => Verdict::NoHeight,
    }
}

/// The lowest height that lies in some interval `lo..=hi` of every quadrant `0..4`, from
/// `(lo, hi, quadrant)` triples; `None` if there is none.
///
/// The answer is always some interval's `lo`. Starting from the highest of the quadrants'
/// lowest `lo`s (nothing below it can serve all four), a height that a quadrant does not
/// cover moves up to that quadrant's next `lo` above it (every interval of that quadrant
/// reaching the answer starts above the height), until all four cover it: a few passes over
/// the intervals instead of a sort.
pub fn lowest_common_height(spans: &[(f64, f64, u8)]) -> Option<f64> {
    let mut lowest = [f64::INFINITY; 4];
    for &(lo, _, q) in spans {
        let q = usize::from(q);
        if q < 4 {
            lowest[q] = lowest[q].min(lo);
        }
    }
    let mut h = lowest.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !h.is_finite() {
        return None;
    }
    loop {
        let mut moved = false;
        for q in 0..4u8 {
            let mut covered = false;
            let mut next = f64::INFINITY;
            for &(lo, hi, p) in spans {
                if p != q {
                    continue;
                }
                if lo <= h && h <= hi {
                    covered = true;
                    break;
                }
                if lo > h {
                    next = next.min(lo);
                }
            }
            if !covered {
                if !next.is_finite() {
                    return None;
                }
                h = next;
                moved = true;
            }
        }
        if !moved {
            return Some(h);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::lowest_common_height;
    use proptest::prelude::*;

    /// The same answer by sorting every interval's ends and sweeping them upwards.
    fn by_sweep(spans: &[(f64, f64, u8)]) -> Option<f64> {
        let mut events: Vec<(f64, i8, u8)> = spans
            .iter()
            .flat_map(|&(lo, hi, q)| [(lo, 1, q), (hi, -1, q)])
            .collect();
        events.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
        let mut open = [0i32; 4];
        for (h, kind, q) in events {
            open[usize::from(q)] += i32::from(kind);
            if kind > 0 && open.iter().all(|&n| n > 0) {
                return Some(h);
            }
        }
        None
    }

    proptest! {
        #[test]
        fn the_lowest_common_height_is_the_sweeps(
            raw in proptest::collection::vec((0u8..40, 0u8..12, 0u8..4), 0..40),
        ) {
            // Heights on a coarse grid, so that ends often coincide.
            let spans: Vec<(f64, f64, u8)> = raw
                .iter()
                .map(|&(lo, len, q)| (f64::from(lo) * 0.05, f64::from(lo + len) * 0.05, q))
                .collect();
            prop_assert_eq!(lowest_common_height(&spans), by_sweep(&spans));
        }
    }

    #[test]
    fn one_quadrant_without_intervals_has_no_common_height() {
        let spans = [(0.0, 1.0, 0), (0.0, 1.0, 1), (0.0, 1.0, 2)];
        assert_eq!(lowest_common_height(&spans), None);
        let all = [(0.0, 1.0, 0), (0.5, 1.0, 1), (0.2, 0.6, 2), (0.4, 2.0, 3)];
        assert_eq!(lowest_common_height(&all), Some(0.5));
    }
}
