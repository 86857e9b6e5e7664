//! How the simulated Controller is set up: terrain, leg, start pose, faults and simulation
//! speed.

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use nalgebra::Point2;
use tca_robot::{Course, CourseError, ElbowBranch, HeightField, LegParams, TerrainError};

use crate::sim::{FaultConfig, SimError, StartPose};

/// The module name the Controller connects under unless told otherwise.
pub const DEFAULT_MODULE_NAME: &str = "controller";

/// Slowest allowed speed factor (a thousandfold slow motion).
pub const MIN_SPEED_FACTOR: f64 = 1e-3;
/// Fastest allowed finite speed factor; use [`SpeedFactor::AsFastAsPossible`] beyond.
pub const MAX_SPEED_FACTOR: f64 = 1e6;

/// How fast simulated time runs against wall-clock time.
///
/// Every duration the Controller reports is simulated time whatever the factor; the factor
/// only sets how long a command's handler waits before it ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpeedFactor {
    /// Simulated time runs this many times faster than the wall clock (1 = real time,
    /// 10 = a 10 s move ends after 1 s). Between [`MIN_SPEED_FACTOR`] and
    /// [`MAX_SPEED_FACTOR`].
    Times(f64),
    /// Commands end as soon as the simulator has computed them; the simulated clock only
    /// counts the time the mechanism spent moving.
    AsFastAsPossible,
}

impl Default for SpeedFactor {
    /// Real time, as the 1990 testbed ran.
    fn default() -> Self {
        SpeedFactor::Times(1.0)
    }
}

impl SpeedFactor {
    /// Real time (factor 1).
    pub fn real_time() -> Self {
        SpeedFactor::Times(1.0)
    }

    /// Checks that a finite factor is within [`MIN_SPEED_FACTOR`]..=[`MAX_SPEED_FACTOR`].
    pub fn validate(&self) -> Result<()> {
        match *self {
            SpeedFactor::Times(k)
                if !(k.is_finite() && (MIN_SPEED_FACTOR..=MAX_SPEED_FACTOR).contains(&k)) =>
            {
                Err(ConfigError::Speed {
                    given: k.to_string(),
                })
            }
            _ => Ok(()),
        }
    }

    /// The wall-clock time a simulated duration takes at this speed (zero when as fast as
    /// possible). Saturates instead of overflowing.
    pub fn wall_time(&self, simulated: Duration) -> Duration {
        match *self {
            SpeedFactor::Times(k) => scale(simulated, 1.0 / k),
            SpeedFactor::AsFastAsPossible => Duration::ZERO,
        }
    }

    /// The simulated time that passes during `wall` of wall-clock time (zero when as fast
    /// as possible: waiting does not advance the simulation). Saturates instead of
    /// overflowing.
    pub fn simulated_time(&self, wall: Duration) -> Duration {
        match *self {
            SpeedFactor::Times(k) => scale(wall, k),
            SpeedFactor::AsFastAsPossible => Duration::ZERO,
        }
    }
}

/// `d * factor`, saturating at [`Duration::MAX`] and clamped at zero.
fn scale(d: Duration, factor: f64) -> Duration {
    let secs = d.as_secs_f64() * factor;
    if secs.is_nan() || secs <= 0.0 {
        Duration::ZERO
    } else {
        Duration::try_from_secs_f64(secs).unwrap_or(Duration::MAX)
    }
}

impl fmt::Display for SpeedFactor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpeedFactor::Times(k) => write!(f, "{k}x"),
            SpeedFactor::AsFastAsPossible => f.write_str("max"),
        }
    }
}

impl FromStr for SpeedFactor {
    type Err = ConfigError;

    /// Parses `max` (or `afap`, `fast`) for as fast as possible, `realtime` for 1, or a
    /// factor such as `10`, `10x` or `0.5x`.
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim().to_ascii_lowercase();
        let speed = match t.as_str() {
            "max" | "afap" | "fast" | "as-fast-as-possible" => SpeedFactor::AsFastAsPossible,
            "realtime" | "real-time" => SpeedFactor::real_time(),
            _ => {
                let number = t.strip_suffix('x').unwrap_or(&t);
                let k: f64 = number.parse().map_err(|_| ConfigError::Speed {
                    given: s.to_owned(),
                })?;
                SpeedFactor::Times(k)
            }
        };
        speed.validate().map_err(|_| ConfigError::Speed {
            given: s.to_owned(),
        })?;
        Ok(speed)
    }
}

/// Everything the simulated Controller needs.
#[derive(Debug, Clone)]
pub struct ControllerConfig {
    /// The true terrain (the simulator's ground truth; nobody else sees it).
    pub terrain: HeightField,
    /// The leg, carriage and simulation parameters.
    pub params: LegParams,
    /// Where the leg starts.
    pub start: StartPose,
    /// Faults to inject.
    pub faults: FaultConfig,
    /// Compensate the leg's deflection with the calibrated model (`compliance.model_*`), as
    /// the report's Controller did: the joints of `legMove` and of the joint readouts are
    /// those of an ideal rigid leg, converted to and from the real joints through the model.
    pub compensate_deflection: bool,
    /// How `bodyMove` propels the carriage (default the servo on the carriage position;
    /// [`BodyMoveLaw::OpenLoop`](crate::sim::BodyMoveLaw::OpenLoop) is the report's first,
    /// inaccurate procedure).
    pub body_move_law: crate::sim::BodyMoveLaw,
    /// Simulated time against wall-clock time.
    pub speed: SpeedFactor,
    /// Module name on the bus (default [`DEFAULT_MODULE_NAME`]).
    pub module_name: String,
    /// Take the Controller's messages over from whichever module registered them before
    /// (default true, so a restarted or swapped-in simulator takes over).
    pub replace: bool,
    /// Stamp the module's messages with the bus's simulated time
    /// ([`tca_module::ModuleBuilder::simulated_time`]): each command charges its move's
    /// simulated duration ([`tca_module::Module::spend`]), so the stamps of a whole system
    /// running as fast as possible add up like the real mechanism's. Default false (wall
    /// clock stamps).
    pub bus_simulated_time: bool,
    /// Keep the Controller's state in this file ([`crate::persist`]): a Controller started
    /// with it goes on from where the last one left the leg, and answers a redelivered command
    /// it already carried out without moving again. `None`: start from `start` every time.
    pub state_file: Option<std::path::PathBuf>,
}

impl ControllerConfig {
    /// A Controller over `terrain` with the leg at `start`: default parameters, no faults,
    /// real time, module `controller`, taking over the messages.
    pub fn new(terrain: HeightField, start: StartPose) -> Self {
        Self {
            terrain,
            params: LegParams::default(),
            start,
            faults: FaultConfig::none(),
            compensate_deflection: false,
            body_move_law: crate::sim::BodyMoveLaw::Servo,
            speed: SpeedFactor::default(),
            module_name: DEFAULT_MODULE_NAME.to_owned(),
            replace: true,
            bus_simulated_time: false,
            state_file: None,
        }
    }

    /// The built-in default: obstacle course 1, the carriage at y = 1 m with the foot
    /// planted at (3.8, 1.2) m under the traction force (500 lb), real time.
    pub fn builtin() -> Result<Self> {
        Self::course(1)
    }

    /// Built-in obstacle course `number` (1..=4) with the default start of
    /// [`builtin`](Self::builtin).
    pub fn course(number: u32) -> Result<Self> {
        let terrain = Course::builtin(number)?.height_field()?;
        let params = LegParams::default();
        let start = StartPose::PlantedAt {
            carriage_y_m: 1.0,
            foot_xy: Point2::new(3.8, 1.2),
            branch: ElbowBranch::Positive,
            force_n: params.body_move.traction_force_n,
        };
        Ok(Self {
            params,
            ..Self::new(terrain, start)
        })
    }

    /// The same configuration at another speed.
    pub fn with_speed(mut self, speed: SpeedFactor) -> Self {
        self.speed = speed;
        self
    }

    /// The same configuration with these faults.
    pub fn with_faults(mut self, faults: FaultConfig) -> Self {
        self.faults = faults;
        self
    }

    /// The same configuration under another module name.
    pub fn with_module_name(mut self, name: impl Into<String>) -> Self {
        self.module_name = name.into();
        self
    }
}

/// Why a Controller configuration is unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A speed factor that is not a number in range.
    #[error(
        "speed factor {given:?} is not usable; give a factor between {MIN_SPEED_FACTOR} and \
         {MAX_SPEED_FACTOR} (e.g. 1 for real time, 10x), or \"max\" for as fast as possible"
    )]
    Speed {
        /// What was given.
        given: String,
    },
    /// The built-in course does not exist.
    #[error(transparent)]
    Course(#[from] CourseError),
    /// The terrain could not be rendered.
    #[error(transparent)]
    Terrain(#[from] TerrainError),
    /// The simulator refused the start state or the faults.
    #[error(transparent)]
    Simulator(#[from] SimError),
}

/// Result of configuring the Controller.
pub type Result<T, E = ConfigError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_factors_parse() {
        assert_eq!(
            "max".parse::<SpeedFactor>().ok(),
            Some(SpeedFactor::AsFastAsPossible)
        );
        assert_eq!(
            "10x".parse::<SpeedFactor>().ok(),
            Some(SpeedFactor::Times(10.0))
        );
        assert_eq!(
            " 0.5 ".parse::<SpeedFactor>().ok(),
            Some(SpeedFactor::Times(0.5))
        );
        assert_eq!(
            "realtime".parse::<SpeedFactor>().ok(),
            Some(SpeedFactor::Times(1.0))
        );
        for bad in ["", "fastest", "0", "-2", "NaN", "inf", "1e9"] {
            let err = bad.parse::<SpeedFactor>().unwrap_err();
            assert!(err.to_string().contains("\"max\""), "{bad}: {err}");
        }
    }

    #[test]
    fn wall_and_simulated_time_are_inverse() {
        let ten = Duration::from_secs(10);
        let k = SpeedFactor::Times(4.0);
        assert_eq!(k.wall_time(ten), Duration::from_millis(2500));
        assert_eq!(k.simulated_time(Duration::from_millis(2500)), ten);
        let max = SpeedFactor::AsFastAsPossible;
        assert_eq!(max.wall_time(ten), Duration::ZERO);
        assert_eq!(max.simulated_time(ten), Duration::ZERO);
        // Saturates rather than panicking.
        let slow = SpeedFactor::Times(MIN_SPEED_FACTOR);
        assert_eq!(slow.wall_time(Duration::MAX), Duration::MAX);
    }

    #[test]
    fn builtin_configuration_starts() {
        let config = ControllerConfig::builtin().unwrap();
        assert_eq!(config.module_name, "controller");
        assert!(crate::sim::LegSimulator::new(config.params, config.terrain, config.start).is_ok());
        assert!(matches!(
            ControllerConfig::course(9),
            Err(ConfigError::Course(_))
        ));
    }
}
