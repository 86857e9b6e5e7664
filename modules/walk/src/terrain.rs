//! Which terrain a walk is on, and where the leg starts.

use std::path::PathBuf;

use anyhow::Context as _;
use nalgebra::Point2;
use tca_controller_sim::sim::StartPose;
use tca_robot::kinematics::ElbowBranch;
use tca_robot::terrain::asc::{NoData, read_height_field};
use tca_robot::{Course, HeightField, LegParams};

/// The terrain of a walk.
#[derive(Clone, Debug, PartialEq)]
pub enum TerrainChoice {
    /// A built-in obstacle course of §7 (1 to 4).
    Course(u32),
    /// A random course from a seed.
    Random(u64),
    /// An ESRI ASCII grid file.
    File(PathBuf),
}

impl TerrainChoice {
    /// The terrain the command-line options name: `--terrain FILE` if given, else `--course`
    /// (1 to 4, or "random" for a course from `seed`).
    pub fn from_args(
        course: &str,
        file: Option<&std::path::Path>,
        seed: u64,
    ) -> anyhow::Result<Self> {
        Ok(match (file, course) {
            (Some(path), _) => TerrainChoice::File(path.to_path_buf()),
            (None, "random") => TerrainChoice::Random(seed),
            (None, n) => match n.parse::<u32>() {
                Ok(n @ 1..=4) => TerrainChoice::Course(n),
                _ => anyhow::bail!("--course must be 1, 2, 3, 4 or random (got {n:?})"),
            },
        })
    }

    /// A short name for reports.
    pub fn describe(&self) -> String {
        match self {
            TerrainChoice::Course(n) => format!("course {n}"),
            TerrainChoice::Random(seed) => format!("random course (seed {seed})"),
            TerrainChoice::File(p) => format!("terrain {}", p.display()),
        }
    }

    /// Loads the height field.
    pub fn load(&self) -> anyhow::Result<HeightField> {
        match self {
            TerrainChoice::Course(n) => Ok(Course::builtin(*n)
                .with_context(|| format!("course {n}"))?
                .height_field()?),
            TerrainChoice::Random(seed) => Ok(Course::random(*seed).height_field()?),
            TerrainChoice::File(path) => read_height_field(path, NoData::Refuse)
                .with_context(|| format!("cannot load terrain {}", path.display())),
        }
    }
}

/// Where the carriage starts along the rails.
pub const START_Y_M: f64 = 1.0;

/// Finds a start: the carriage at `carriage_y_m`, the foot planted on the flattest spot near
/// (3.8, carriage_y + 0.2), within the leg's reach.
pub fn find_start(
    terrain: &HeightField,
    params: &LegParams,
    carriage_y_m: f64,
) -> anyhow::Result<StartPose> {
    let foot_r = params.leg.foot_radius_m;
    let mut best: Option<(f64, Point2<f64>)> = None;
    for i in -6..=6 {
        for j in -4..=6 {
            let p = Point2::new(
                3.8 + 0.1 * f64::from(i),
                carriage_y_m + 0.2 + 0.1 * f64::from(j),
            );
            let reach = (p - Point2::new(params.carriage.x_m, carriage_y_m)).norm();
            if !(0.8..=2.2).contains(&reach) {
                continue;
            }
            let top = terrain.max_height_in_disc(p, foot_r + 0.1);
            let bottom = [
                (0.0, 0.0),
                (foot_r, 0.0),
                (-foot_r, 0.0),
                (0.0, foot_r),
                (0.0, -foot_r),
            ]
            .iter()
            .map(|(dx, dy)| terrain.height_at(p.x + dx, p.y + dy))
            .fold(f64::INFINITY, f64::min);
            // Flat first, then close to the usual start spot.
            let score = (top - bottom) + 0.01 * (p - Point2::new(3.8, carriage_y_m + 0.2)).norm();
            if top.is_finite() && best.is_none_or(|(s, _)| score < s) {
                best = Some((score, p));
            }
        }
    }
    let (score, foot) =
        best.ok_or_else(|| anyhow::anyhow!("no place to plant the foot near the start"))?;
    if score > 0.1 {
        anyhow::bail!(
            "the terrain near the start (carriage at y = {carriage_y_m} m) has no flat place for \
             the foot (best unevenness {score:.2} m); level the first metre of the terrain"
        );
    }
    Ok(StartPose::PlantedAt {
        carriage_y_m,
        foot_xy: foot,
        branch: ElbowBranch::Positive,
        force_n: params.body_move.traction_force_n,
    })
}
