//! The envelope of the Envelope Trajectory Finding Algorithm (§6.2.2, Figure 10b): the
//! lowest and highest foot heights the leg can be at, at the same moment, when the vertical
//! axis moves at full speed while the horizontal joints move. The leg stops to lift only
//! when the terrain ahead rises above the top of the envelope.

/// Foot heights (world Z of the sole, metres) reachable at one moment: `[lo_m, hi_m]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachEnvelope {
    /// Lowest reachable height.
    pub lo_m: f64,
    /// Highest reachable height.
    pub hi_m: f64,
}

impl ReachEnvelope {
    /// The leg at one height.
    pub fn at(z_m: f64) -> Self {
        Self {
            lo_m: z_m,
            hi_m: z_m,
        }
    }

    /// After `dt_s` of horizontal motion with the vertical axis free at `v` m/s, never
    /// below `floor_m` (the terrain under the way) nor above `ceiling_m` (the leg's reach).
    pub fn widen(self, dt_s: f64, v_m_per_s: f64, floor_m: f64, ceiling_m: f64) -> Self {
        let reach = v_m_per_s * dt_s.max(0.0);
        Self {
            lo_m: (self.lo_m - reach).max(floor_m).min(ceiling_m),
            hi_m: (self.hi_m + reach).min(ceiling_m).max(floor_m),
        }
    }

    /// Demands the foot be at least `required_m` now: when that is above the envelope the
    /// horizontal joints stop while the leg lifts. Returns the new envelope and the wait.
    pub fn require(self, required_m: f64, v_m_per_s: f64) -> (Self, f64) {
        if self.hi_m < required_m {
            (Self::at(required_m), (required_m - self.hi_m) / v_m_per_s)
        } else {
            (
                Self {
                    lo_m: self.lo_m.max(required_m),
                    hi_m: self.hi_m,
                },
                0.0,
            )
        }
    }

    /// One step from a cell to its neighbour taking `dt_s`: half the way in the first cell
    /// (requirement `from_m`), the border (requirement `border_m`, the highest of the cells
    /// met there), then half the way in the next cell (`to_m`). `None` when the border is
    /// above the leg's reach. Returns the envelope on arrival and the time spent waiting
    /// for lifts.
    pub fn step(
        self,
        dt_s: f64,
        v_m_per_s: f64,
        from_m: f64,
        border_m: f64,
        to_m: f64,
        ceiling_m: f64,
    ) -> Option<(Self, f64)> {
        if border_m > ceiling_m {
            return None;
        }
        let half = 0.5 * dt_s;
        let (at_border, wait) = self
            .widen(half, v_m_per_s, from_m, ceiling_m)
            .require(border_m, v_m_per_s);
        Some((at_border.widen(half, v_m_per_s, to_m, ceiling_m), wait))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const V: f64 = 0.036;

    #[test]
    fn the_envelope_opens_at_full_vertical_speed() {
        let e = ReachEnvelope::at(0.2).widen(10.0, V, -0.5, 1.0);
        assert!((e.lo_m + 0.16).abs() < 1e-12 && (e.hi_m - 0.56).abs() < 1e-12);
        // The terrain underneath and the reach clip it.
        let e = ReachEnvelope::at(0.2).widen(100.0, V, 0.1, 1.0);
        assert_eq!(
            e,
            ReachEnvelope {
                lo_m: 0.1,
                hi_m: 1.0
            }
        );
    }

    #[test]
    fn terrain_within_the_envelope_costs_no_wait() {
        // Figure 10: lifting while moving reaches a 0.3 m step in time.
        let (e, wait) = ReachEnvelope::at(0.0)
            .step(10.0, V, 0.0, 0.15, 0.15, 1.0)
            .unwrap();
        assert_eq!(wait, 0.0);
        assert!((e.lo_m - 0.15).abs() < 1e-12);
        assert!((e.hi_m - 0.36).abs() < 1e-12);
    }

    #[test]
    fn terrain_above_the_envelope_stops_the_leg_to_lift() {
        let (e, wait) = ReachEnvelope::at(0.0)
            .step(2.0, V, 0.0, 0.5, 0.5, 1.0)
            .unwrap();
        // Half a step (1 s) lifts 3.6 cm; the remaining 46.4 cm take 12.9 s.
        assert!((wait - (0.5 - 0.036) / V).abs() < 1e-9, "{wait}");
        assert!((e.lo_m - 0.5).abs() < 1e-12);
        assert!((e.hi_m - 0.536).abs() < 1e-12);
        assert!(
            ReachEnvelope::at(0.0)
                .step(2.0, V, 0.0, 1.1, 1.1, 1.0)
                .is_none()
        );
    }
}
