//! One cell of the local terrain map, and how two observations of it are fused (the LTM
//! Merger's maximum-likelihood rule).

use tca_single_leg_messages::MapCell;

/// What is known about a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum CellState {
    /// Never seen (outside every field of view so far).
    Unknown = 0,
    /// Hidden behind something: the terrain is at most `elevation_m` high.
    Occluded = 1,
    /// Seen: elevation and its standard deviation.
    Known = 2,
}

impl CellState {
    /// The state of a stored byte.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            0 => Some(Self::Unknown),
            1 => Some(Self::Occluded),
            2 => Some(Self::Known),
            _ => None,
        }
    }
}

/// A map cell: 12 bytes. For [`CellState::Occluded`] `elevation_m` is the greatest elevation
/// possible and `sigma_m` is 0; for [`CellState::Unknown`] both are 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// What is known.
    pub state: CellState,
    /// Elevation (known) or its upper bound (occluded), metres, world Z.
    pub elevation_m: f32,
    /// Standard deviation of the elevation (known cells), metres.
    pub sigma_m: f32,
}

impl Cell {
    /// Nothing known.
    pub const UNKNOWN: Cell = Cell {
        state: CellState::Unknown,
        elevation_m: 0.0,
        sigma_m: 0.0,
    };

    /// A seen cell.
    pub fn known(elevation_m: f32, sigma_m: f32) -> Self {
        Self {
            state: CellState::Known,
            elevation_m,
            sigma_m,
        }
    }

    /// A hidden cell with its greatest possible elevation.
    pub fn occluded(max_elevation_m: f32) -> Self {
        Self {
            state: CellState::Occluded,
            elevation_m: max_elevation_m,
            sigma_m: 0.0,
        }
    }

    /// Whether the cell was seen.
    pub fn is_known(&self) -> bool {
        self.state == CellState::Known
    }

    /// The cell as an elevation map cell on the wire.
    pub fn to_wire(&self) -> MapCell {
        match self.state {
            CellState::Unknown => MapCell::Unknown,
            CellState::Occluded => MapCell::Occluded {
                max_elevation_m: self.elevation_m,
            },
            CellState::Known => MapCell::Known {
                value: self.elevation_m,
                sigma_m: self.sigma_m,
            },
        }
    }
}

/// Smallest standard deviation used in fusion, metres (a zero would mean infinite weight).
const MIN_SIGMA_M: f32 = 1e-4;

/// Fuses a new observation of a cell into what the map held (§5.2.2, the LTM Merger):
///
/// - unknown adds nothing; anything replaces unknown;
/// - two known elevations are replaced by their maximum-likelihood (inverse-variance weighted)
///   estimate, whose variance `1 / (1/s1^2 + 1/s2^2)` is below both;
/// - except that when they disagree by more than `gate_sigmas` combined standard deviations
///   the terrain is taken to have changed (the foot pressed the sand, an object moved) and the
///   new observation replaces the old;
/// - a known elevation beats an occlusion bound; two bounds give the lower (both hold).
pub fn fuse(old: Cell, new: Cell, gate_sigmas: Option<f32>) -> Cell {
    use CellState::*;
    match (old.state, new.state) {
        (_, Unknown) => old,
        (Unknown, _) => new,
        (Known, Occluded) => old,
        (Occluded, Known) => new,
        (Occluded, Occluded) => Cell::occluded(old.elevation_m.min(new.elevation_m)),
        (Known, Known) => {
            let s1 = old.sigma_m.max(MIN_SIGMA_M);
            let s2 = new.sigma_m.max(MIN_SIGMA_M);
            if let Some(gate) = gate_sigmas {
                let combined = (s1 * s1 + s2 * s2).sqrt();
                if (old.elevation_m - new.elevation_m).abs() > gate * combined {
                    return new;
                }
            }
            let w1 = 1.0 / (s1 * s1);
            let w2 = 1.0 / (s2 * s2);
            let w = w1 + w2;
            Cell::known(
                (w1 * old.elevation_m + w2 * new.elevation_m) / w,
                (1.0 / w).sqrt(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn ml_fusion_of_equal_sigmas_averages_and_shrinks_by_root_two() {
        let f = fuse(Cell::known(1.0, 0.1), Cell::known(1.2, 0.1), None);
        assert!((f.elevation_m - 1.1).abs() < 1e-6);
        assert!((f.sigma_m - 0.1 / 2f32.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn disagreeing_observations_replace_when_gated() {
        let f = fuse(Cell::known(0.0, 0.01), Cell::known(1.0, 0.01), Some(5.0));
        assert_eq!(f, Cell::known(1.0, 0.01));
        let g = fuse(Cell::known(0.0, 0.01), Cell::known(1.0, 0.01), None);
        assert!((g.elevation_m - 0.5).abs() < 1e-6);
    }

    #[test]
    fn occlusion_rules() {
        let k = Cell::known(0.3, 0.02);
        assert_eq!(fuse(k, Cell::occluded(1.0), None), k);
        assert_eq!(fuse(Cell::occluded(1.0), k, None), k);
        assert_eq!(
            fuse(Cell::occluded(1.0), Cell::occluded(0.5), None),
            Cell::occluded(0.5)
        );
        assert_eq!(fuse(Cell::UNKNOWN, k, None), k);
        assert_eq!(fuse(k, Cell::UNKNOWN, None), k);
    }

    proptest! {
        #[test]
        fn fused_sigma_is_below_both(
            z1 in -2.0..2.0f32, z2 in -2.0..2.0f32, s1 in 0.001..1.0f32, s2 in 0.001..1.0f32,
        ) {
            let f = fuse(Cell::known(z1, s1), Cell::known(z2, s2), None);
            prop_assert!(f.sigma_m < s1 && f.sigma_m < s2);
            prop_assert!(f.elevation_m >= z1.min(z2) - 1e-5 && f.elevation_m <= z1.max(z2) + 1e-5);
        }
    }
}
