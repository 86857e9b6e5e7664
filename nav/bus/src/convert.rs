//! Between the algorithm crates' types and the messages.

use nalgebra::Point2;
use tca_nav_danger_map::CellDanger;
use tca_nav_messages::{CellDangerMsg, DangerGrid, DepthFrame, PlanarPose};
use tca_nav_navigator::{CellChange, Pose2};
use tca_nav_sensing::{Attitude, DepthImage};
use tca_robot::{CellIndex, Grid};

/// A pose as sent.
pub fn pose_msg(p: &Pose2) -> PlanarPose {
    PlanarPose {
        x_m: p.x,
        y_m: p.y,
        yaw_rad: p.yaw,
    }
}

/// A pose as received.
pub fn pose_of(p: &PlanarPose) -> Pose2 {
    Pose2::new(p.x_m, p.y_m, p.yaw_rad)
}

/// A legged body's pose as its planar pose and its height and tilt.
pub fn body_pose_of(p: &tca_legged_messages::Pose) -> (Pose2, Attitude) {
    (
        Pose2::new(p.x_m, p.y_m, p.yaw_rad),
        Attitude {
            z_m: p.z_m,
            roll_rad: p.roll_rad,
            pitch_rad: p.pitch_rad,
        },
    )
}

/// The measured height and tilt a depth frame was taken with.
pub fn attitude_of(f: &DepthFrame) -> Attitude {
    Attitude {
        z_m: f.base_z_m,
        roll_rad: f.base_roll_rad,
        pitch_rad: f.base_pitch_rad,
    }
}

/// A depth image as sent: each depth as a 32-bit float, 0 where there is none. The
/// simulated camera already delivers 32-bit depths, so nothing is lost.
pub fn depth_msg(image: &DepthImage) -> (u32, u32, Vec<f32>) {
    let depth = image
        .depth
        .iter()
        .map(|d| d.map_or(0.0, |z| z as f32))
        .collect();
    (image.width as u32, image.height as u32, depth)
}

/// Why a received depth frame cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// Its pixel count is not its width times its height.
    #[error("a depth frame of {width} x {height} pixels carries {len} depths; send width x height")]
    Size {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// Depths carried.
        len: usize,
    },
    /// Its size is not the camera's the LTM Manager maps for.
    #[error(
        "a depth frame of {width} x {height} pixels, but the camera is {expected_w} x {expected_h}; the ISM and the LTM Manager must share the camera's parameters"
    )]
    Camera {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The camera's width.
        expected_w: usize,
        /// The camera's height.
        expected_h: usize,
    },
    /// A depth or the pose is not a finite number, or a depth is negative.
    #[error("a depth frame holds a depth or pose that is not a finite, non-negative number")]
    NotFinite,
}

/// A received depth frame as the map side's image, checked against the camera's size.
pub fn depth_of(f: &DepthFrame, width: usize, height: usize) -> Result<DepthImage, FrameError> {
    if f.depth_m.len() != f.width as usize * f.height as usize {
        return Err(FrameError::Size {
            width: f.width,
            height: f.height,
            len: f.depth_m.len(),
        });
    }
    if f.width as usize != width || f.height as usize != height {
        return Err(FrameError::Camera {
            width: f.width,
            height: f.height,
            expected_w: width,
            expected_h: height,
        });
    }
    let e = &f.estimate;
    if !(e.x_m.is_finite()
        && e.y_m.is_finite()
        && e.yaw_rad.is_finite()
        && attitude_of(f).is_finite())
        || f.depth_m.iter().any(|d| !(d.is_finite() && *d >= 0.0))
    {
        return Err(FrameError::NotFinite);
    }
    Ok(DepthImage {
        width,
        height,
        depth: f
            .depth_m
            .iter()
            .map(|&d| (d > 0.0).then_some(f64::from(d)))
            .collect(),
    })
}

/// A changed cell as sent.
pub fn change_msg(c: &CellChange) -> CellDangerMsg {
    CellDangerMsg {
        ix: c.cell.ix as u32,
        iy: c.cell.iy as u32,
        danger: c.danger.danger.is_finite().then_some(c.danger.danger),
        certainty: c.danger.certainty,
    }
}

/// A changed cell as received (slope, roughness and step are not sent: the navigator plans
/// on the danger and certainty alone).
pub fn change_of(c: &CellDangerMsg) -> CellChange {
    CellChange {
        cell: CellIndex::new(c.ix as usize, c.iy as usize),
        danger: CellDanger {
            danger: c.danger.unwrap_or(f64::INFINITY),
            certainty: c.certainty,
            slope_rad: 0.0,
            roughness_m: 0.0,
            step_m: 0.0,
        },
    }
}

/// The danger map as sent.
pub fn grid_msg(cells: &Grid<CellDanger>, frames: u64) -> DangerGrid {
    let o = cells.origin();
    DangerGrid {
        origin_x_m: o.x,
        origin_y_m: o.y,
        resolution_m: cells.resolution_m(),
        nx: cells.nx() as u32,
        ny: cells.ny() as u32,
        danger: cells
            .cells()
            .iter()
            .map(|c| {
                if c.danger.is_finite() {
                    c.danger as f32
                } else {
                    -1.0
                }
            })
            .collect(),
        certainty: cells.cells().iter().map(|c| c.certainty as f32).collect(),
        frames,
    }
}

/// The danger map as received, for pictures (slope, roughness and step are 0).
pub fn grid_of(g: &DangerGrid) -> anyhow::Result<Grid<CellDanger>> {
    let n = g.nx as usize * g.ny as usize;
    anyhow::ensure!(
        g.danger.len() == n && g.certainty.len() == n,
        "a danger map of {} x {} cells carries {} dangers and {} certainties",
        g.nx,
        g.ny,
        g.danger.len(),
        g.certainty.len()
    );
    let cells = g
        .danger
        .iter()
        .zip(&g.certainty)
        .map(|(&d, &c)| CellDanger {
            danger: if d < 0.0 { f64::INFINITY } else { f64::from(d) },
            certainty: f64::from(c),
            slope_rad: 0.0,
            roughness_m: 0.0,
            step_m: 0.0,
        })
        .collect();
    Ok(Grid::from_vec(
        Point2::new(g.origin_x_m, g.origin_y_m),
        g.resolution_m,
        g.nx as usize,
        g.ny as usize,
        cells,
    )?)
}
