//! Checking a walk's recorded states against the terrain, as an outside checker would: from
//! the report's numbers alone.

use nalgebra::{Point2, Point3};
use tca_robot::HeightField;
use tca_stability::{stability_margin, support_polygon};

use crate::report::StateRecord;

/// How far a standing foot's contact point may be from the terrain's surface, metres.
pub const GROUND_TOLERANCE_M: f64 = 0.02;
/// How far a foot standing in two states in a row may have moved between them, metres.
pub const SLIP_TOLERANCE_M: f64 = 0.005;
/// How far the recorded margin may differ from the one recomputed from the feet, metres.
pub const MARGIN_TOLERANCE_M: f64 = 0.01;

/// One inconsistency found in the recorded states.
#[derive(Clone, Debug, PartialEq)]
pub struct StateProblem {
    /// The state's index in the report.
    pub index: usize,
    /// Its simulated time.
    pub t_s: f64,
    /// What is wrong.
    pub what: String,
}

impl std::fmt::Display for StateProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "state {} (t = {:.2} s): {}",
            self.index, self.t_s, self.what
        )
    }
}

/// Checks every state: at least three feet stand; each standing foot is on the terrain (its
/// contact point within [`GROUND_TOLERANCE_M`] of the surface below it); the centre of mass
/// is inside the standing feet's polygon with a positive margin that agrees with the one
/// recorded; a foot standing in two states in a row has not moved; time never runs back.
pub fn check_states(states: &[StateRecord], terrain: &HeightField) -> Vec<StateProblem> {
    let mut problems = Vec::new();
    let mut push =
        |index: usize, t_s: f64, what: String| problems.push(StateProblem { index, t_s, what });
    let (lo, hi) = terrain.extent();
    for (i, s) in states.iter().enumerate() {
        let standing: Vec<(&String, [f64; 3])> = s
            .feet
            .iter()
            .filter(|(_, f)| f.stance)
            .map(|(leg, f)| (leg, f.at))
            .collect();
        if standing.len() < 3 {
            push(i, s.t_s, format!("only {} feet stand", standing.len()));
        }
        for (leg, at) in &standing {
            if at[0] < lo.x || at[0] > hi.x || at[1] < lo.y || at[1] > hi.y {
                push(
                    i,
                    s.t_s,
                    format!(
                        "{leg} stands off the terrain at ({:.3}, {:.3})",
                        at[0], at[1]
                    ),
                );
                continue;
            }
            let ground = terrain.height_at(at[0], at[1]);
            if (at[2] - ground).abs() > GROUND_TOLERANCE_M {
                push(
                    i,
                    s.t_s,
                    format!(
                        "{leg} stands at z = {:.3} m where the terrain is at {:.3} m",
                        at[2], ground
                    ),
                );
            }
        }
        let feet: Vec<Point2<f64>> = standing
            .iter()
            .map(|(_, a)| Point2::new(a[0], a[1]))
            .collect();
        let margin = stability_margin(
            &support_polygon(&feet),
            Point3::new(s.com[0], s.com[1], s.com[2]),
        );
        if margin.is_nan() || margin <= 0.0 {
            push(
                i,
                s.t_s,
                format!(
                    "the centre of mass is not inside the standing feet (margin {margin:.3} m)"
                ),
            );
        } else if (margin - s.margin_m).abs() > MARGIN_TOLERANCE_M {
            push(
                i,
                s.t_s,
                format!(
                    "the recorded margin {:.3} m differs from the feet's {margin:.3} m",
                    s.margin_m
                ),
            );
        }
        if i > 0 {
            let before = &states[i - 1];
            if s.t_s + 1e-9 < before.t_s {
                push(i, s.t_s, format!("time ran back from {:.3} s", before.t_s));
            }
            for (leg, at) in &standing {
                if let Some(prev) = before.feet.get(*leg).filter(|f| f.stance) {
                    let d = ((at[0] - prev.at[0]).powi(2)
                        + (at[1] - prev.at[1]).powi(2)
                        + (at[2] - prev.at[2]).powi(2))
                    .sqrt();
                    if d > SLIP_TOLERANCE_M {
                        push(i, s.t_s, format!("{leg} moved {d:.3} m while standing"));
                    }
                }
            }
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::FootRecord;

    fn state(t: f64, feet: &[(&str, [f64; 3], bool)], com: [f64; 2], margin: f64) -> StateRecord {
        StateRecord {
            t_s: t,
            body: [0.0; 6],
            com: [com[0], com[1], 1.0],
            feet: feet
                .iter()
                .map(|(l, at, stance)| {
                    (
                        l.to_string(),
                        FootRecord {
                            at: *at,
                            stance: *stance,
                        },
                    )
                })
                .collect(),
            margin_m: margin,
        }
    }

    fn flat() -> HeightField {
        HeightField::flat(
            nalgebra::Point2::new(-5.0, -5.0),
            nalgebra::Point2::new(5.0, 5.0),
            0.1,
            0.0,
        )
        .expect("a flat terrain")
    }

    #[test]
    fn a_consistent_walk_passes_and_each_kind_of_inconsistency_is_named() {
        let terrain = flat();
        let tri = [
            ("a", [1.0, 0.0, 0.0], true),
            ("b", [-1.0, 1.0, 0.0], true),
            ("c", [-1.0, -1.0, 0.0], true),
            ("d", [0.0, 0.0, 0.3], false),
        ];
        // The margin of (0, 0) in that triangle: distance to the edge x = -1 is 1, to the
        // slanted edges 1 / sqrt(5).
        let m = 1.0 / 5f64.sqrt();
        let good = vec![
            state(0.0, &tri, [0.0, 0.0], m),
            state(1.0, &tri, [0.0, 0.0], m),
        ];
        assert!(check_states(&good, &terrain).is_empty());

        let two = [tri[0], tri[1], ("c", [-1.0, -1.0, 0.0], false)];
        let p = check_states(&[state(0.0, &two, [0.0, 0.0], m)], &terrain);
        assert!(p.iter().any(|p| p.what.contains("only 2 feet")), "{p:?}");

        let floating = [tri[0], tri[1], ("c", [-1.0, -1.0, 0.1], true)];
        let p = check_states(&[state(0.0, &floating, [0.0, 0.0], m)], &terrain);
        assert!(p.iter().any(|p| p.what.contains("c stands at z")), "{p:?}");

        let p = check_states(&[state(0.0, &tri, [3.0, 0.0], -2.0)], &terrain);
        assert!(p.iter().any(|p| p.what.contains("not inside")), "{p:?}");

        let slid = [("a", [1.1, 0.0, 0.0], true), tri[1], tri[2]];
        let p = check_states(
            &[
                state(0.0, &tri, [0.0, 0.0], m),
                state(1.0, &slid, [0.0, 0.0], 0.0),
            ],
            &terrain,
        );
        assert!(p.iter().any(|p| p.what.contains("a moved")), "{p:?}");

        let p = check_states(
            &[
                state(2.0, &tri, [0.0, 0.0], m),
                state(1.0, &tri, [0.0, 0.0], m),
            ],
            &terrain,
        );
        assert!(p.iter().any(|p| p.what.contains("time ran back")), "{p:?}");
    }
}
