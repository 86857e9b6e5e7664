//! The safety margin of each pair of parts: how close two parts of the robot, or a part and
//! the terrain, may come before it counts as a collision.
//!
//! Parts that sit close by construction (the chassis and a thigh) get a small margin; parts
//! that are normally far apart (a wheel and the chassis, parts of different legs) a larger
//! one, because compliance and encoder noise make their relative positions less certain.
//! Every part keeps the same margin from the terrain.
//!
//! Parts are named by *class*: a leg's link name without the leg's name (`left_front_thigh`
//! is a `thigh`), `foot` for the wheel, and a body link's own name (`body`). The table is
//! TOML:
//!
//! ```toml
//! environment_m = 0.04     # every part from the terrain
//! same_leg_m = 0.01        # two parts of the moving leg (not joined by one joint)
//! other_leg_m = 0.10       # a part of the moving leg from a part of another leg
//! body_m = 0.05            # a part of the moving leg from a body part
//!
//! [[pair]]                 # exceptions, either order
//! a = "body"
//! b = "thigh"
//! margin_m = 0.01
//! ```

use serde::{Deserialize, Serialize};

use crate::error::FootfallError;

/// One exception to the table's defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairMargin {
    /// One part class.
    pub a: String,
    /// The other part class.
    pub b: String,
    /// Their margin, metres.
    pub margin_m: f64,
}

/// The margins of every pair of parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarginTable {
    /// Every part from the terrain, metres.
    pub environment_m: f64,
    /// Two parts of the moving leg not joined by one joint, metres.
    pub same_leg_m: f64,
    /// A part of the moving leg from a part of another leg, metres.
    pub other_leg_m: f64,
    /// A part of the moving leg from a part of the body, metres.
    pub body_m: f64,
    /// Exceptions by part class, either order.
    #[serde(default, rename = "pair")]
    pub pairs: Vec<PairMargin>,
}

impl Default for MarginTable {
    /// The table for the shipped `athlete`: 4 cm from the terrain; 1 cm between parts of
    /// one leg; 10 cm from other legs; 5 cm from the body, except 1 cm for the thigh (which
    /// passes close under the chassis by design) and 10 cm for the wheel and the ankle.
    fn default() -> Self {
        let pair = |a: &str, b: &str, m: f64| PairMargin {
            a: a.to_owned(),
            b: b.to_owned(),
            margin_m: m,
        };
        Self {
            environment_m: 0.04,
            same_leg_m: 0.01,
            other_leg_m: 0.10,
            body_m: 0.05,
            pairs: vec![
                pair("body", "thigh", 0.01),
                pair("body", "foot", 0.10),
                pair("body", "ankle", 0.10),
            ],
        }
    }
}

impl MarginTable {
    /// Reads a table from TOML (see the [module documentation](self)); missing defaults are
    /// refused by name, as are negative or non-finite margins.
    pub fn from_toml(text: &str) -> Result<Self, FootfallError> {
        let table: MarginTable =
            toml::from_str(text).map_err(|e| FootfallError::Margins(e.to_string()))?;
        table.check()?;
        Ok(table)
    }

    /// Refuses a negative or non-finite margin, naming it.
    pub fn check(&self) -> Result<(), FootfallError> {
        let named = [
            ("environment_m", self.environment_m),
            ("same_leg_m", self.same_leg_m),
            ("other_leg_m", self.other_leg_m),
            ("body_m", self.body_m),
        ];
        for (name, v) in named {
            if !(v.is_finite() && v >= 0.0) {
                return Err(FootfallError::Margins(format!(
                    "{name} is {v}; give a margin of 0 or more metres"
                )));
            }
        }
        for p in &self.pairs {
            if !(p.margin_m.is_finite() && p.margin_m >= 0.0) {
                return Err(FootfallError::Margins(format!(
                    "the pair {} / {} has margin {}; give 0 or more metres",
                    p.a, p.b, p.margin_m
                )));
            }
        }
        Ok(())
    }

    /// The margin between a part of class `a` on the moving leg and a part of class `b`,
    /// which is on the body (`b_on_body`), on another leg (`other_leg`), or on the moving
    /// leg itself (neither).
    pub fn margin(&self, a: &str, b: &str, b_on_body: bool, other_leg: bool) -> f64 {
        if let Some(p) = self
            .pairs
            .iter()
            .find(|p| (p.a == a && p.b == b) || (p.a == b && p.b == a))
        {
            return p.margin_m;
        }
        if b_on_body {
            self.body_m
        } else if other_leg {
            self.other_leg_m
        } else {
            self.same_leg_m
        }
    }
}

/// The class of a link: its name without the leg's name and an underscore (`foot` for the
/// leg's foot link), or the whole name for a body link.
pub fn part_class(link: &str, leg: Option<&str>) -> String {
    match leg {
        Some(leg) => link
            .strip_prefix(leg)
            .and_then(|rest| rest.strip_prefix('_'))
            .unwrap_or(link)
            .to_owned(),
        None => link.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exceptions_win_in_either_order_and_defaults_follow_the_owner() {
        let t = MarginTable::default();
        assert_eq!(t.margin("thigh", "body", true, false), 0.01);
        assert_eq!(t.margin("body", "foot", true, false), 0.10);
        assert_eq!(t.margin("upper_shin", "body", true, false), 0.05);
        assert_eq!(t.margin("foot", "thigh", false, true), 0.10);
        assert_eq!(t.margin("foot", "thigh", false, false), 0.01);
    }

    #[test]
    fn tables_read_from_toml_and_bad_ones_say_what_is_wrong() {
        let t = MarginTable::from_toml(
            "environment_m = 0.05\nsame_leg_m = 0.02\nother_leg_m = 0.2\nbody_m = 0.1\n\
             [[pair]]\na = \"body\"\nb = \"thigh\"\nmargin_m = 0.0\n",
        )
        .unwrap();
        assert_eq!(t.environment_m, 0.05);
        assert_eq!(t.margin("thigh", "body", true, false), 0.0);
        let e = MarginTable::from_toml("environment_m = 0.05").unwrap_err();
        assert!(e.to_string().contains("same_leg_m"), "{e}");
        let e = MarginTable::from_toml(
            "environment_m = -1\nsame_leg_m = 0\nother_leg_m = 0\nbody_m = 0\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("environment_m is -1"), "{e}");
        let e = MarginTable::from_toml(
            "environment_m = 0\nsame_leg_m = 0\nother_leg_m = 0\nbody_m = 0\nbogus = 1\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("bogus"), "{e}");
    }

    #[test]
    fn classes_drop_the_leg_name() {
        assert_eq!(part_class("left_front_thigh", Some("left_front")), "thigh");
        assert_eq!(part_class("left_front_foot", Some("left_front")), "foot");
        assert_eq!(part_class("body", None), "body");
        assert_eq!(part_class("odd", Some("left_front")), "odd");
    }
}
