//! How a planted foot drives the carriage: the compliant leg as a horizontal spring between
//! the joints' (deflected, unloaded) foot point and the real foot, the carriage held by the
//! rails' friction, and the foot held by the ground's.
//!
//! Quasi-static, one control cycle at a time, in the carriage's horizontal axes (X across
//! the rails, world Y along them):
//!
//! - the *strain* `s` is where the real foot is less where the joints would put an unloaded
//!   foot; the leg pulls the carriage with `s / compliance` and the ground holds the foot
//!   with the same force;
//! - the carriage stands until the pull along the rails passes the breakaway (static)
//!   friction, then rolls, the pull staying at the rolling (kinetic) friction while it keeps
//!   going; when the pull drops below that it stops again and must break away anew;
//! - the foot holds while the whole horizontal pull is within the traction limit (friction
//!   coefficient times the pressing force) and otherwise slides along the pull, the pull
//!   staying at the limit. When the joints drag the foot across the rails, most of the
//!   traction is spent across them, and the foot slips back along the rails as far as the
//!   carriage's friction needs: the carriage falls short of where the joints put it.
//!
//! The leg is taken to be relaxed when the propulsion starts (the foot settles as it is
//! pressed in), so the strain is counted from that moment.

use nalgebra::{Point3, Vector2};

/// A leg with no compliance is modelled as this stiff (metres per newton): rigid to well
/// under a millimetre at the loads of a body move.
const MIN_COMPLIANCE_M_PER_N: f64 = 1e-9;

/// The carriage-and-foot state of one body move's propulsion.
#[derive(Debug, Clone)]
pub(super) struct Drive {
    /// Horizontal compliance of the leg at its extension, metres per newton.
    compliance_m_per_n: f64,
    /// Rolling friction of the carriage, newtons.
    kinetic_n: f64,
    /// Breakaway friction of the carriage, newtons.
    static_n: f64,
    /// Largest horizontal force the ground holds the foot with, newtons.
    traction_n: f64,
    /// Strain when the propulsion began (counted as relaxed).
    rest: Vector2<f64>,
    /// Whether the carriage rolled in the last cycle.
    rolling: bool,
    /// Path length the foot has slid on the ground, metres.
    slid_m: f64,
    /// Ground force on the foot in the last cycle (carriage axes), newtons.
    force_n: Vector2<f64>,
}

/// Carriage Y and foot after a cycle.
#[derive(Debug, Clone, Copy)]
pub(super) struct DriveState {
    /// Carriage position along the rails, world Y, metres.
    pub(super) carriage_y_m: f64,
    /// The real foot, world frame.
    pub(super) foot: Point3<f64>,
}

impl Drive {
    /// A drive with the leg relaxed at `start`, where `tip` is the joints' unloaded foot
    /// point (carriage X, carriage-relative Y).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        compliance_m_per_n: f64,
        kinetic_n: f64,
        static_n: f64,
        traction_n: f64,
        carriage_x_m: f64,
        start: &DriveState,
        tip: Vector2<f64>,
    ) -> Self {
        let mut drive = Self {
            compliance_m_per_n: compliance_m_per_n.max(MIN_COMPLIANCE_M_PER_N),
            kinetic_n,
            static_n: static_n.max(kinetic_n),
            traction_n,
            rest: Vector2::zeros(),
            rolling: false,
            slid_m: 0.0,
            force_n: Vector2::zeros(),
        };
        drive.rest = drive.raw_strain(carriage_x_m, start, tip);
        drive
    }

    fn raw_strain(&self, carriage_x_m: f64, state: &DriveState, tip: Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            state.foot.x - carriage_x_m - tip.x,
            state.foot.y - state.carriage_y_m - tip.y,
        )
    }

    /// Sets the compliance for the leg's current extension.
    pub(super) fn set_compliance(&mut self, compliance_m_per_n: f64) {
        self.compliance_m_per_n = compliance_m_per_n.max(MIN_COMPLIANCE_M_PER_N);
    }

    /// One control cycle: the joints have put the unloaded foot point at `tip`; where do
    /// the carriage and the foot go.
    ///
    /// Solved for the end of the cycle as Coulomb friction has it: the carriage stands, or
    /// rolls with the pull at the rolling friction; the foot holds, or slides along the pull
    /// with the pull at the traction limit. The first consistent case of: nothing moves; the
    /// carriage rolls and the foot holds; both move; the foot slides and the carriage stands.
    pub(super) fn step(
        &mut self,
        carriage_x_m: f64,
        state: DriveState,
        tip: Vector2<f64>,
    ) -> DriveState {
        let c = self.compliance_m_per_n;
        let s = self.raw_strain(carriage_x_m, &state, tip) - self.rest;
        let stand_limit = if self.rolling {
            self.kinetic_n
        } else {
            self.static_n
        };
        let holds = |s: &Vector2<f64>| s.norm() <= self.traction_n * c * (1.0 + 1e-12);
        let (carriage_dy, foot_d, end) = if s.y.abs() <= stand_limit * c && holds(&s) {
            (0.0, Vector2::zeros(), s)
        } else if s.y.abs() > stand_limit * c {
            // The pull breaks the carriage away (or keeps it rolling).
            let rolled = Vector2::new(s.x, s.y.signum() * self.kinetic_n * c);
            if holds(&rolled) {
                (s.y - rolled.y, Vector2::zeros(), rolled)
            } else if let Some(both) = self.roll_and_slide(&s) {
                both
            } else {
                self.slide_only(&s)
            }
        } else {
            self.slide_only(&s)
        };
        self.rolling = carriage_dy != 0.0;
        self.slid_m += foot_d.norm();
        self.force_n = end / c;
        let mut next = state;
        next.carriage_y_m += carriage_dy;
        next.foot.x += foot_d.x;
        next.foot.y += foot_d.y;
        next
    }

    /// The carriage rolls (the pull along the rails at the rolling friction) while the foot
    /// slides (the whole pull at the traction limit, the slide along it): carriage move,
    /// foot slide and strain at the end. `None` when the foot's traction cannot even pull
    /// the carriage, or the slide would have to go against the pull.
    fn roll_and_slide(&self, s: &Vector2<f64>) -> Option<(f64, Vector2<f64>, Vector2<f64>)> {
        let c = self.compliance_m_per_n;
        if self.traction_n <= self.kinetic_n || s.x == 0.0 {
            return None;
        }
        let across = (self.traction_n.powi(2) - self.kinetic_n.powi(2)).sqrt() * c;
        let end = Vector2::new(s.x.signum() * across, s.y.signum() * self.kinetic_n * c);
        // s = end + slide, the slide a non-negative multiple of `end`: across the rails
        // that fixes how far; along them the carriage takes up the rest.
        let lambda = s.x / end.x - 1.0;
        if lambda < 0.0 {
            return None;
        }
        let foot_d = -lambda * end;
        let carriage_dy = s.y - end.y + foot_d.y;
        Some((carriage_dy, foot_d, end))
    }

    /// The foot slides along the pull until it is at the traction limit; the carriage stands.
    fn slide_only(&self, s: &Vector2<f64>) -> (f64, Vector2<f64>, Vector2<f64>) {
        let limit = self.traction_n * self.compliance_m_per_n;
        let norm = s.norm();
        if norm <= limit {
            return (0.0, Vector2::zeros(), *s);
        }
        let end = s * (limit / norm);
        (0.0, end - s, end)
    }

    /// Path length the foot has slid so far, metres.
    pub(super) fn slid_m(&self) -> f64 {
        self.slid_m
    }

    /// The ground's horizontal force on the foot in the last cycle (carriage axes), newtons.
    pub(super) fn force_n(&self) -> Vector2<f64> {
        self.force_n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const C: f64 = 2e-5;

    fn drive(static_n: f64) -> (Drive, DriveState) {
        let start = DriveState {
            carriage_y_m: 1.0,
            foot: Point3::new(4.0, 2.0, 0.0),
        };
        let d = Drive::new(
            C,
            450.0,
            static_n,
            1300.0,
            3.0,
            &start,
            Vector2::new(1.0, 1.0),
        );
        (d, start)
    }

    #[test]
    fn the_carriage_stands_until_the_pull_breaks_it_away_then_rolls_with_a_lag() {
        let (mut d, mut s) = drive(900.0);
        // The joints pull the foot point back 1 cm: 500 N, under the breakaway force.
        s = d.step(3.0, s, Vector2::new(1.0, 0.99));
        assert_eq!(s.carriage_y_m, 1.0);
        // 2 cm: 1000 N breaks it away; it rolls until the pull is down to 450 N.
        s = d.step(3.0, s, Vector2::new(1.0, 0.98));
        assert!((s.carriage_y_m - (1.0 + 0.02 - 450.0 * C)).abs() < 1e-12);
        // Rolling, it follows the joints with the kinetic lag.
        s = d.step(3.0, s, Vector2::new(1.0, 0.90));
        assert!((s.carriage_y_m - (1.0 + 0.10 - 450.0 * C)).abs() < 1e-12);
        assert!((d.force_n().y - 450.0).abs() < 1e-6);
        assert_eq!(d.slid_m(), 0.0);
    }

    #[test]
    fn a_sideways_pull_past_traction_slides_the_foot_and_the_carriage_stands() {
        let (mut d, mut s) = drive(900.0);
        // The joints bow 5 cm across the rails and 1.5 cm back along them: about 2600 N in all.
        s = d.step(3.0, s, Vector2::new(0.95, 0.985));
        let f = d.force_n();
        assert!((f.norm() - 1300.0).abs() < 1e-6, "{f}");
        assert!(d.slid_m() > 0.02);
        // The pull along the rails is what is left of the traction: under the breakaway force.
        assert!(f.y.abs() < 900.0);
        assert_eq!(s.carriage_y_m, 1.0);
        // The foot slipped toward the joints' point, back along the rails too.
        assert!(s.foot.x < 4.0 && s.foot.y < 2.0);
    }

    #[test]
    fn a_rigid_leg_moves_the_carriage_with_the_joints() {
        let start = DriveState {
            carriage_y_m: 1.0,
            foot: Point3::new(4.0, 2.0, 0.0),
        };
        let mut d = Drive::new(
            0.0,
            450.0,
            900.0,
            1300.0,
            3.0,
            &start,
            Vector2::new(1.0, 1.0),
        );
        let s = d.step(3.0, start, Vector2::new(1.0, 0.5));
        assert!((s.carriage_y_m - 1.5).abs() < 1e-5);
        assert!(d.slid_m() < 1e-5);
    }
}
