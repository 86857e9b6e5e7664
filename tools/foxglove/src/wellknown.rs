//! Foxglove's well-known messages from the walking and navigating systems' traffic.
//!
//! [`WellKnownState`] is fed every message a module sends, in order, and returns the
//! well-known messages that follow from it. It keeps what later messages need: the single
//! leg's carriage pose, a legged robot's description, body pose and joint positions, the
//! leg moves still under way (a leg's links are placed where a move leaves them when the move
//! succeeds), and the navigation's danger map (whole from a `nav.dangerMap` reply, then
//! changed by each `nav.insertDepth` reply).
//!
//! | traffic | becomes |
//! | --- | --- |
//! | `mapRegion`, `legReachability` replies (terrain maps) | `foxglove.Grid` on `/map/<kind>` |
//! | `nav.dangerMap` replies, then every `nav.insertDepth` reply applied to the last of them | `foxglove.Grid` on `/map/danger` (fields `danger`, NaN where the cell cannot be crossed, and `certainty`) |
//! | `bodyPosition`, `globalLegPosition` replies; `legged.bodyPose` replies, `legged.supportState`, `legged.legState` replies, `legged.legMove` successes; `acquireImage` replies (the scanner) | `foxglove.FrameTransforms` on `/tf` |
//! | `nav.frame` (the odometry's estimate), `nav.truePose` replies (the simulation's truth) | `foxglove.FrameTransforms` on `/tf`: `world → base`, `world → base_true` |
//! | `legged.robotModel` reply (URDF) | `{"data": URDF}` on `/robot_description` |
//! | `jointLegPosition` replies, `legMove`, `recoverLeg`, `stepPlanned`; `legged.legMove`, `legged.supportState`, `legged.stepPlanned`; `nav.frame` (planned path and goal) | `foxglove.SceneUpdate` on `/plan` |
//! | `acquireImage` replies (range images) | `foxglove.RawImage` on `/scanner/range` and `/scanner/reflectance` |
//! | `nav.acquireDepth` replies (depth images) | `foxglove.RawImage` (`32FC1`, metres, 0 where there is no depth) on `/camera/depth` |
//! | walks, navigations, steps, planned steps, failed moves, faults, tip-overs, failures, central's errors | `foxglove.Log` on `/log` |
//!
//! The navigation is planar: the base's frames, the path, the goal and the danger map all
//! lie on `z = 0` of the world frame (the path and goal a little above the map, so they
//! are not hidden in it).

use std::collections::HashMap;

use foxglove::messages::{
    ArrowPrimitive, FrameTransform, FrameTransforms, Grid, LinePrimitive, Log, PackedElementField,
    RawImage, SceneEntity, SceneUpdate, SpherePrimitive, TextPrimitive, Vector2, line_primitive,
    log::Level, packed_element_field::NumericType,
};
use nalgebra::{Isometry3, Point3 as P3};
use serde::Deserialize;
use tca_legged_model::RobotModel;
use tca_messages::{Class, Envelope, MessageId, decode_data};
use tca_nav_messages as nav;
use tca_robot::{CarriagePose, JointPosition, LegKinematics, LegParams};
use tca_single_leg_messages as leg;

use crate::geometry::{
    at, color, convex_hull, isometry_from_row_major, point, pose, rpy_pose, timestamp, vector,
};

/// Topic of the frame transforms.
pub const TF_TOPIC: &str = "/tf";
/// Topic of the scene (planned paths, footholds, support polygon, the single leg's links).
pub const PLAN_TOPIC: &str = "/plan";
/// Topic of walk progress and problems.
pub const LOG_TOPIC: &str = "/log";
/// Topic of the robot's URDF (`{"data": "<robot ...>"}`), for the 3D panel's URDF layer.
pub const ROBOT_DESCRIPTION_TOPIC: &str = "/robot_description";
/// Topic of the range images.
pub const RANGE_TOPIC: &str = "/scanner/range";
/// Topic of the reflectance images.
pub const REFLECTANCE_TOPIC: &str = "/scanner/reflectance";
/// Topic of the navigation camera's depth images.
pub const DEPTH_TOPIC: &str = "/camera/depth";
/// Topic of the navigation's danger map.
pub const DANGER_TOPIC: &str = "/map/danger";
/// The world frame.
pub const WORLD_FRAME: &str = "world";
/// The single leg's carriage frame.
pub const CARRIAGE_FRAME: &str = "carriage";
/// The single leg's foot frame (translation only).
pub const FOOT_FRAME: &str = "foot";
/// The range scanner's frame.
pub const SCANNER_FRAME: &str = "scanner";
/// The navigation camera's frame (of its depth images; no transform places it).
pub const CAMERA_FRAME: &str = "camera";
/// The navigating base as its odometry estimates it.
pub const BASE_FRAME: &str = "base";
/// The navigating base where the simulation truly has it.
pub const BASE_TRUE_FRAME: &str = "base_true";
/// Height of the navigation's path and goal above the danger map, m.
const NAV_SCENE_Z_M: f64 = 0.01;

/// One well-known message and where it goes.
#[derive(Clone, Debug, PartialEq)]
pub enum WellKnown {
    /// Frame transforms for [`TF_TOPIC`].
    Transforms(FrameTransforms),
    /// A terrain map on `/map/<kind>`, or the danger map on [`DANGER_TOPIC`].
    Grid {
        /// The topic.
        topic: String,
        /// The map.
        grid: Grid,
    },
    /// A scene update for [`PLAN_TOPIC`].
    Scene(SceneUpdate),
    /// An image on [`RANGE_TOPIC`], [`REFLECTANCE_TOPIC`] or [`DEPTH_TOPIC`].
    Image {
        /// The topic.
        topic: &'static str,
        /// The image.
        image: RawImage,
    },
    /// A log line for [`LOG_TOPIC`].
    Log(Log),
    /// The robot's URDF text for [`ROBOT_DESCRIPTION_TOPIC`].
    RobotDescription(String),
}

impl WellKnown {
    /// The topic this message goes to.
    pub fn topic(&self) -> &str {
        match self {
            WellKnown::Transforms(_) => TF_TOPIC,
            WellKnown::Grid { topic, .. } => topic,
            WellKnown::Scene(_) => PLAN_TOPIC,
            WellKnown::Image { topic, .. } => topic,
            WellKnown::Log(_) => LOG_TOPIC,
            WellKnown::RobotDescription(_) => ROBOT_DESCRIPTION_TOPIC,
        }
    }
}

/// The topic of a map kind's grids.
pub fn map_topic(kind: leg::MapKind) -> String {
    let name = match kind {
        leg::MapKind::Elevation => "elevation",
        leg::MapKind::ElevationUncertainty => "elevation_uncertainty",
        leg::MapKind::Footfall => "footfall",
        leg::MapKind::Slope => "slope",
        leg::MapKind::Reachability => "reachability",
    };
    format!("/map/{name}")
}

/// The legged walker's plan of one step (the shape of its `legged.stepPlanned` inform).
#[derive(Deserialize)]
struct LeggedStepPlanned {
    step: u32,
    footholds: Vec<(String, tca_legged_messages::WorldPoint)>,
    body_target: tca_legged_messages::Pose,
    min_margin_m: f64,
    #[allow(dead_code)] // read by serde: the field is part of the message's shape
    planning_ms: f64,
}

/// A legged robot as far as the traffic told.
struct Legged {
    model: RobotModel,
    posture: Vec<Vec<f64>>,
}

/// What the well-known conversion remembers between messages (see the module docs).
pub struct WellKnownState {
    kinematics: LegKinematics,
    params: LegParams,
    carriage: Option<CarriagePose>,
    robot: Option<Legged>,
    body: Option<Isometry3<f64>>,
    /// Legged leg moves under way: their leg index and final joint positions.
    leg_moves: HashMap<MessageId, (usize, Vec<f64>)>,
    /// The navigation's danger map as the traffic last left it.
    danger: Option<nav::DangerGrid>,
}

impl Default for WellKnownState {
    fn default() -> Self {
        let params = LegParams::default();
        Self {
            kinematics: LegKinematics::new(&params),
            params,
            carriage: None,
            robot: None,
            body: None,
            leg_moves: HashMap::new(),
            danger: None,
        }
    }
}

fn entity(at_ns: u64, frame: &str, id: &str) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(at_ns)),
        frame_id: frame.to_owned(),
        id: id.to_owned(),
        ..Default::default()
    }
}

fn sphere(x: f64, y: f64, z: f64, d: f64, c: foxglove::messages::Color) -> SpherePrimitive {
    SpherePrimitive {
        pose: Some(at(x, y, z)),
        size: Some(vector(d, d, d)),
        color: Some(c),
    }
}

fn text(x: f64, y: f64, z: f64, s: String) -> TextPrimitive {
    TextPrimitive {
        pose: Some(at(x, y, z)),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: Some(color(1.0, 1.0, 1.0, 1.0)),
        text: s,
    }
}

fn line(kind: line_primitive::Type, points: Vec<foxglove::messages::Point3>) -> LinePrimitive {
    LinePrimitive {
        r#type: kind as i32,
        pose: Some(at(0.0, 0.0, 0.0)),
        thickness: 3.0,
        scale_invariant: true,
        points,
        color: Some(color(0.2, 0.7, 1.0, 1.0)),
        ..Default::default()
    }
}

fn scene(entities: Vec<SceneEntity>) -> WellKnown {
    WellKnown::Scene(SceneUpdate {
        deletions: Vec::new(),
        entities,
    })
}

fn log(at_ns: u64, level: Level, sender: &str, message: String) -> WellKnown {
    WellKnown::Log(Log {
        timestamp: Some(timestamp(at_ns)),
        level: level as i32,
        message,
        name: sender.to_owned(),
        file: String::new(),
        line: 0,
    })
}

fn transform(at_ns: u64, parent: &str, child: &str, iso: &Isometry3<f64>) -> FrameTransform {
    let p = pose(iso);
    FrameTransform {
        timestamp: Some(timestamp(at_ns)),
        parent_frame_id: parent.to_owned(),
        child_frame_id: child.to_owned(),
        translation: p.position,
        rotation: p.orientation,
    }
}

/// A terrain map as a Foxglove grid in the world frame, with three float fields: `value`
/// (elevation, cost or slope where seen, NaN elsewhere), `sigma_m` (its uncertainty) and
/// `occluded_max_m` (where hidden: the greatest elevation possible there). `None` when the
/// cell count does not match the size.
pub fn grid(map: &leg::MapGrid, at_ns: u64) -> Option<Grid> {
    let nx = map.nx as usize;
    let n = nx.checked_mul(map.ny as usize)?;
    if map.cells.len() != n || !map.resolution_m.is_finite() || map.resolution_m <= 0.0 {
        return None;
    }
    let mut data = Vec::with_capacity(n * 12);
    for cell in &map.cells {
        let (value, sigma, occluded) = match *cell {
            leg::MapCell::Unknown => (f32::NAN, f32::NAN, f32::NAN),
            leg::MapCell::Occluded { max_elevation_m } => (f32::NAN, f32::NAN, max_elevation_m),
            leg::MapCell::Known { value, sigma_m } => (value, sigma_m, f32::NAN),
        };
        for v in [value, sigma, occluded] {
            data.extend_from_slice(&v.to_le_bytes());
        }
    }
    Some(float_grid(
        [map.origin_x_m, map.origin_y_m],
        map.resolution_m,
        map.nx,
        &["value", "sigma_m", "occluded_max_m"],
        data,
        at_ns,
    ))
}

/// A grid of float32 fields `names`, in that order in each cell, cell (0, 0) centred at
/// `origin` in the world frame (the grid's pose is that cell's south-west corner).
fn float_grid(
    origin: [f64; 2],
    resolution_m: f64,
    nx: u32,
    names: &[&str],
    data: Vec<u8>,
    at_ns: u64,
) -> Grid {
    let half = resolution_m / 2.0;
    let stride = 4 * names.len() as u32;
    Grid {
        timestamp: Some(timestamp(at_ns)),
        frame_id: WORLD_FRAME.to_owned(),
        pose: Some(at(origin[0] - half, origin[1] - half, 0.0)),
        column_count: nx,
        cell_size: Some(Vector2 {
            x: resolution_m,
            y: resolution_m,
        }),
        row_stride: nx * stride,
        cell_stride: stride,
        fields: names
            .iter()
            .zip(0u32..)
            .map(|(name, i)| PackedElementField {
                name: (*name).to_owned(),
                offset: 4 * i,
                r#type: NumericType::Float32 as i32,
            })
            .collect(),
        data: data.into(),
    }
}

/// A 16-bit image (`mono16`, little-endian) of `width` x `height` counts, row-major.
/// `None` when the count does not match the size.
pub fn mono16(counts: &[u16], width: u32, height: u32, at_ns: u64) -> Option<RawImage> {
    if counts.len() != (width as usize).checked_mul(height as usize)? {
        return None;
    }
    let mut data = Vec::with_capacity(counts.len() * 2);
    for c in counts {
        data.extend_from_slice(&c.to_le_bytes());
    }
    Some(RawImage {
        timestamp: Some(timestamp(at_ns)),
        frame_id: SCANNER_FRAME.to_owned(),
        width,
        height,
        encoding: "mono16".to_owned(),
        step: width * 2,
        data: data.into(),
    })
}

/// A navigation camera's depth image as a Foxglove image: `32FC1` (one little-endian
/// 32-bit float per pixel, metres along the optical axis, 0 where there is no depth),
/// row-major, in [`CAMERA_FRAME`]. `None` when the depth count does not match the size.
pub fn depth_image(frame: &nav::DepthFrame, at_ns: u64) -> Option<RawImage> {
    let n = (frame.width as usize).checked_mul(frame.height as usize)?;
    if frame.depth_m.len() != n {
        return None;
    }
    let mut data = Vec::with_capacity(n * 4);
    for d in &frame.depth_m {
        data.extend_from_slice(&d.to_le_bytes());
    }
    Some(RawImage {
        timestamp: Some(timestamp(at_ns)),
        frame_id: CAMERA_FRAME.to_owned(),
        width: frame.width,
        height: frame.height,
        encoding: "32FC1".to_owned(),
        step: frame.width.checked_mul(4)?,
        data: data.into(),
    })
}

/// Whether a danger map's cell counts match its size and its cells have a usable side.
fn danger_map_fits(map: &nav::DangerGrid) -> bool {
    let n = (map.nx as usize).checked_mul(map.ny as usize);
    n.is_some_and(|n| map.danger.len() == n && map.certainty.len() == n)
        && map.resolution_m.is_finite()
        && map.resolution_m > 0.0
        && map.nx.checked_mul(8).is_some()
}

/// The navigation's danger map as a Foxglove grid in the world frame, laid out as
/// [`grid`] lays out terrain maps (the pose at the south-west corner of cell (0, 0), rows
/// from the south), with two float fields: `danger` (`[0, 1]`, 1 where unknown; NaN where
/// the cell cannot be crossed) and `certainty` (`[0, 1]`). `None` when the cell counts do
/// not match the size.
pub fn danger_grid(map: &nav::DangerGrid, at_ns: u64) -> Option<Grid> {
    if !danger_map_fits(map) {
        return None;
    }
    let mut data = Vec::with_capacity(map.danger.len() * 8);
    for (&d, &c) in map.danger.iter().zip(&map.certainty) {
        let d = if d < 0.0 { f32::NAN } else { d };
        data.extend_from_slice(&d.to_le_bytes());
        data.extend_from_slice(&c.to_le_bytes());
    }
    Some(float_grid(
        [map.origin_x_m, map.origin_y_m],
        map.resolution_m,
        map.nx,
        &["danger", "certainty"],
        data,
        at_ns,
    ))
}

/// A planar pose as a transform from the world frame to `child`, on `z = 0`. `None` when
/// the pose is not finite.
fn planar_transform(at_ns: u64, child: &str, p: &nav::PlanarPose) -> Option<WellKnown> {
    if !(p.x_m.is_finite() && p.y_m.is_finite() && p.yaw_rad.is_finite()) {
        return None;
    }
    let iso = rpy_pose(p.x_m, p.y_m, 0.0, 0.0, 0.0, p.yaw_rad);
    Some(WellKnown::Transforms(FrameTransforms {
        transforms: vec![transform(at_ns, WORLD_FRAME, child, &iso)],
    }))
}

/// The navigator's plan of one frame: the path as a line strip (entity `nav_path`) and the
/// goal as a sphere (entity `nav_goal`), in the world frame.
fn nav_plan(f: &nav::NavFrame, at_ns: u64) -> WellKnown {
    let z = NAV_SCENE_Z_M;
    let mut path = entity(at_ns, WORLD_FRAME, "nav_path");
    path.lines.push(line(
        line_primitive::Type::LineStrip,
        f.path
            .iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .map(|p| point(p[0], p[1], z))
            .collect(),
    ));
    let mut goal = entity(at_ns, WORLD_FRAME, "nav_goal");
    if f.goal[0].is_finite() && f.goal[1].is_finite() {
        goal.spheres.push(sphere(
            f.goal[0],
            f.goal[1],
            z,
            0.08,
            color(1.0, 0.8, 0.1, 0.9),
        ));
        goal.texts.push(text(
            f.goal[0],
            f.goal[1],
            z + 0.08,
            format!("frame {}: {:?}", f.frame, f.outcome),
        ));
    }
    scene(vec![path, goal])
}

/// Applies a `nav.insertDepth` reply's changed cells to the danger map (cells outside it are
/// passed over).
fn apply_danger_changes(map: &mut nav::DangerGrid, changes: &nav::DangerChanges) {
    let (nx, ny) = (map.nx as usize, map.ny as usize);
    for c in &changes.cells {
        let (ix, iy) = (c.ix as usize, c.iy as usize);
        if ix >= nx || iy >= ny {
            continue;
        }
        let i = iy * nx + ix;
        if let (Some(d), Some(k)) = (map.danger.get_mut(i), map.certainty.get_mut(i)) {
            *d = c.danger.map_or(-1.0, |v| v as f32);
            *k = c.certainty as f32;
        }
    }
    map.frames = changes.frames;
}

impl WellKnownState {
    /// A fresh state.
    pub fn new() -> Self {
        Self::default()
    }

    /// The well-known messages that follow from `envelope`, which a module sent at `at_ns`
    /// (nanoseconds since the UNIX epoch). Data that does not decode as its message's type
    /// gives nothing (and a debug trace): the traffic channels still carry it.
    pub fn feed(&mut self, envelope: &Envelope, at_ns: u64) -> Vec<WellKnown> {
        let out = self.convert(envelope, at_ns);
        match out {
            Ok(v) => v,
            Err(why) => {
                tracing::debug!(name = %envelope.name, %why, "no well-known message");
                Vec::new()
            }
        }
    }

    fn convert(&mut self, e: &Envelope, at_ns: u64) -> Result<Vec<WellKnown>, String> {
        fn de<T: serde::de::DeserializeOwned>(e: &Envelope) -> Result<T, String> {
            decode_data(&e.data).map_err(|x| x.to_string())
        }
        let sender = e.sender.as_str();
        let mut out = Vec::new();
        match (e.class, e.name.as_str()) {
            // ---- the single leg
            (Class::Reply, "mapRegion" | "legReachability") => {
                let map: leg::MapGrid = de(e)?;
                let grid = grid(&map, at_ns).ok_or("a map whose cells do not match its size")?;
                out.push(WellKnown::Grid {
                    topic: map_topic(map.kind),
                    grid,
                });
            }
            (Class::Reply, "bodyPosition") => {
                let p: leg::BodyPose = de(e)?;
                let pose = CarriagePose {
                    y_m: p.y_m,
                    roll_rad: p.roll_rad,
                    pitch_rad: p.pitch_rad,
                };
                self.carriage = Some(pose);
                let iso = pose.world_from_carriage(&self.params.carriage);
                out.push(WellKnown::Transforms(FrameTransforms {
                    transforms: vec![transform(at_ns, WORLD_FRAME, CARRIAGE_FRAME, &iso)],
                }));
            }
            (Class::Reply, "globalLegPosition") => {
                let p: leg::WorldPoint = de(e)?;
                let iso = Isometry3::translation(p.x_m, p.y_m, p.z_m);
                out.push(WellKnown::Transforms(FrameTransforms {
                    transforms: vec![transform(at_ns, WORLD_FRAME, FOOT_FRAME, &iso)],
                }));
            }
            (Class::Reply, "jointLegPosition") => {
                let q: leg::Joints = de(e)?;
                out.push(scene(vec![self.single_leg_links(&q, at_ns)]));
            }
            (Class::Command, "legMove") => {
                let m: leg::LegMove = de(e)?;
                let pose = self
                    .carriage
                    .unwrap_or_else(|| CarriagePose::level(self.params.rails.y_min_m));
                let points = m
                    .waypoints
                    .iter()
                    .map(|w| {
                        let q = JointPosition::new(w.shoulder_rad, w.elbow_rad, w.vertical_m);
                        let p = self.kinematics.forward_world(&pose, &q);
                        point(p.x, p.y, p.z)
                    })
                    .collect();
                let mut path = entity(at_ns, WORLD_FRAME, "leg_path");
                path.lines
                    .push(line(line_primitive::Type::LineStrip, points));
                out.push(scene(vec![path]));
            }
            (Class::Goal, "recoverLeg") => {
                let g: leg::RecoverLeg = de(e)?;
                let f = g.footfall;
                let mut ent = entity(at_ns, WORLD_FRAME, "footfall");
                ent.spheres
                    .push(sphere(f.x_m, f.y_m, f.z_m, 0.3, color(1.0, 0.8, 0.1, 0.9)));
                out.push(scene(vec![ent]));
            }
            (Class::Inform, "stepPlanned") => {
                let s: leg::StepPlanned = de(e)?;
                let f = s.footfall;
                let mut ent = entity(at_ns, WORLD_FRAME, "footfall");
                ent.spheres
                    .push(sphere(f.x_m, f.y_m, f.z_m, 0.3, color(1.0, 0.8, 0.1, 0.9)));
                ent.texts
                    .push(text(f.x_m, f.y_m, f.z_m + 0.3, format!("step {}", s.step)));
                out.push(scene(vec![ent]));
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!(
                        "step {} planned: footfall ({:.3}, {:.3}, {:.3}) m, carriage to y = {:.3} m, cost {:.3}",
                        s.step, f.x_m, f.y_m, f.z_m, s.body_target_y_m, s.cost
                    ),
                ));
            }
            (Class::Reply, "acquireImage") => {
                let img: leg::RangeImage = de(e)?;
                let range = mono16(&img.range_counts, img.width, img.height, at_ns)
                    .ok_or("a range image whose pixels do not match its size")?;
                out.push(WellKnown::Image {
                    topic: RANGE_TOPIC,
                    image: range,
                });
                if let Some(refl) = mono16(&img.reflectance, img.width, img.height, at_ns) {
                    out.push(WellKnown::Image {
                        topic: REFLECTANCE_TOPIC,
                        image: refl,
                    });
                }
                let body_from_global = isometry_from_row_major(&img.body_from_global.m);
                let scanner_from_body = isometry_from_row_major(&img.scanner_from_body.m);
                if let (Some(bg), Some(sb)) = (body_from_global, scanner_from_body) {
                    let world_from_scanner = (sb * bg).inverse();
                    out.push(WellKnown::Transforms(FrameTransforms {
                        transforms: vec![transform(
                            at_ns,
                            WORLD_FRAME,
                            SCANNER_FRAME,
                            &world_from_scanner,
                        )],
                    }));
                }
            }
            (Class::Goal, "walk") => {
                let w: leg::Walk = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!("walk to y = {:.3} m ({:?} stepping)", w.goal_y_m, w.mode),
                ));
            }
            (Class::Goal, "planStep") => {
                let s: leg::PlanStep = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Debug,
                    sender,
                    format!("planning step {}", s.step),
                ));
            }
            (Class::Exception, "moveFailed") => {
                let f: leg::MoveFailed = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Warning,
                    sender,
                    format!("{} failed ({:?}): {}", f.command, f.kind, f.detail),
                ));
            }
            (Class::Exception, "hardwareFault") => {
                let f: leg::HardwareFault = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Error,
                    sender,
                    format!("hardware fault: {}", f.detail),
                ));
            }
            // ---- legged robots
            (Class::Reply, "legged.robotModel") => {
                let d: tca_legged_messages::RobotDescription = de(e)?;
                match RobotModel::from_urdf_str(&d.urdf) {
                    Ok(model) => {
                        let posture = model.neutral_posture();
                        self.robot = Some(Legged { model, posture });
                        out.extend(self.link_transforms(at_ns));
                    }
                    Err(why) => tracing::debug!(%why, "the robot's URDF does not load"),
                }
                out.push(WellKnown::RobotDescription(d.urdf));
            }
            (Class::Reply, "legged.bodyPose") => {
                let p: tca_legged_messages::Pose = de(e)?;
                out.extend(self.body_pose(&p, at_ns));
            }
            (Class::Inform, "legged.supportState") => {
                let s: tca_legged_messages::SupportState = de(e)?;
                out.extend(self.body_pose(&s.body, at_ns));
                out.push(scene(self.support(&s, at_ns)));
            }
            (Class::Reply, "legged.legState") => {
                let s: tca_legged_messages::LegStateReply = de(e)?;
                if self.set_leg(&s.leg, s.joints) {
                    out.extend(self.link_transforms(at_ns));
                }
            }
            (Class::Command, "legged.legMove") => {
                let m: tca_legged_messages::LegMove = de(e)?;
                out.extend(self.legged_leg_path(e.id, &m, at_ns));
            }
            (Class::Success, "legged.legMove") => {
                if let Some(id) = e.correlation
                    && let Some((index, q)) = self.leg_moves.remove(&id)
                    && let Some(robot) = &mut self.robot
                    && robot.model.leg_at(index).is_ok_and(|l| l.check(&q).is_ok())
                {
                    robot.posture[index] = q;
                    out.extend(self.link_transforms(at_ns));
                }
            }
            (Class::Failure | Class::Error, "legged.legMove") => {
                if let Some(id) = e.correlation {
                    self.leg_moves.remove(&id);
                }
                out.extend(self.failure(e, at_ns));
            }
            (Class::Inform, "legged.stepPlanned") => {
                let s: LeggedStepPlanned = de(e)?;
                out.push(scene(vec![self.legged_plan(&s, at_ns)]));
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!(
                        "step {} planned: {} footholds, body to ({:.3}, {:.3}), least margin {:.3} m",
                        s.step,
                        s.footholds.len(),
                        s.body_target.x_m,
                        s.body_target.y_m,
                        s.min_margin_m
                    ),
                ));
            }
            (Class::Goal, "legged.walk") => {
                let w: tca_legged_messages::LeggedWalk = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!(
                        "walk to ({:.3}, {:.3}) within {:.3} m{}",
                        w.goal_x_m,
                        w.goal_y_m,
                        w.tolerance_m,
                        if w.concurrent { ", concurrent" } else { "" }
                    ),
                ));
            }
            (Class::Exception, "legged.moveFailed") => {
                let f: tca_legged_messages::MoveFailed = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Warning,
                    sender,
                    format!(
                        "{}{} failed ({:?}): {}",
                        f.command,
                        f.leg.map(|l| format!(" of {l}")).unwrap_or_default(),
                        f.kind,
                        f.detail
                    ),
                ));
            }
            (Class::Exception, "legged.hardwareFault") => {
                let f: tca_legged_messages::HardwareFault = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Error,
                    sender,
                    format!("hardware fault: {}", f.detail),
                ));
            }
            (Class::Exception, "legged.tipOver") => {
                let f: tca_legged_messages::TipOver = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Error,
                    sender,
                    format!("tipped over (margin {:.3} m): {}", f.margin_m, f.detail),
                ));
            }
            // ---- navigation
            (Class::Reply, "nav.acquireDepth") => {
                let f: nav::DepthFrame = de(e)?;
                let image = depth_image(&f, at_ns)
                    .ok_or("a depth image whose pixels do not match its size")?;
                out.push(WellKnown::Image {
                    topic: DEPTH_TOPIC,
                    image,
                });
            }
            (Class::Reply, "nav.dangerMap") => {
                let map: nav::DangerGrid = de(e)?;
                let grid = danger_grid(&map, at_ns)
                    .ok_or("a danger map whose cells do not match its size")?;
                self.danger = Some(map);
                out.push(WellKnown::Grid {
                    topic: DANGER_TOPIC.to_owned(),
                    grid,
                });
            }
            (Class::Reply, "nav.insertDepth") => {
                let changes: nav::DangerChanges = de(e)?;
                let map = self
                    .danger
                    .as_mut()
                    .ok_or("danger changes before any nav.dangerMap reply gave the map")?;
                apply_danger_changes(map, &changes);
                if let Some(grid) = danger_grid(map, at_ns) {
                    out.push(WellKnown::Grid {
                        topic: DANGER_TOPIC.to_owned(),
                        grid,
                    });
                }
            }
            (Class::Reply, "nav.truePose") => {
                let p: nav::PlanarPose = de(e)?;
                out.extend(planar_transform(at_ns, BASE_TRUE_FRAME, &p));
            }
            (Class::Inform, "nav.frame") => {
                let f: nav::NavFrame = de(e)?;
                out.extend(planar_transform(at_ns, BASE_FRAME, &f.estimate));
                out.push(nav_plan(&f, at_ns));
            }
            (Class::Goal, "nav.navigate") => {
                let g: nav::Navigate = de(e)?;
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!(
                        "navigate to ({:.3}, {:.3}) m from the start within {} frames",
                        g.dx_m, g.dy_m, g.max_frames
                    ),
                ));
            }
            // ---- any walk's or navigation's end, and every failure
            (Class::Success, "walk" | "legged.walk" | "nav.navigate") => {
                out.push(log(
                    at_ns,
                    Level::Info,
                    sender,
                    format!("{} succeeded", e.name),
                ));
            }
            (Class::Failure | Class::Error, _) => out.extend(self.failure(e, at_ns)),
            _ => {}
        }
        Ok(out)
    }

    fn failure(&self, e: &Envelope, at_ns: u64) -> Option<WellKnown> {
        let reason = match e.class {
            Class::Failure => decode_data::<tca_messages::Failure>(&e.data)
                .map(|f| f.reason)
                .unwrap_or_else(|_| "(undecoded)".into()),
            _ => decode_data::<tca_messages::RouteError>(&e.data)
                .map(|r| format!("central: {r}"))
                .unwrap_or_else(|_| "(undecoded)".into()),
        };
        Some(log(
            at_ns,
            Level::Error,
            e.sender.as_str(),
            format!("{} failed: {reason}", e.name),
        ))
    }

    /// The single leg's links, in the carriage frame: the shoulder column to the elbow, the
    /// foot's column, and down the vertical member to the sole.
    fn single_leg_links(&self, q: &leg::Joints, at_ns: u64) -> SceneEntity {
        let (upper, _) = self.kinematics.link_lengths_m();
        let h = self
            .kinematics
            .forward_horizontal(q.shoulder_rad, q.elbow_rad);
        let elbow = (upper * q.shoulder_rad.cos(), upper * q.shoulder_rad.sin());
        let mut ent = entity(at_ns, CARRIAGE_FRAME, "leg");
        ent.frame_locked = true;
        let mut l = line(
            line_primitive::Type::LineStrip,
            vec![
                point(0.0, 0.0, 0.0),
                point(elbow.0, elbow.1, 0.0),
                point(h.x, h.y, 0.0),
                point(h.x, h.y, -q.vertical_m),
            ],
        );
        l.thickness = 6.0;
        l.color = Some(color(0.9, 0.9, 0.9, 1.0));
        ent.lines.push(l);
        ent
    }

    fn body_frame(&self) -> String {
        self.robot
            .as_ref()
            .map(|r| r.model.body_link().to_owned())
            .unwrap_or_else(|| "body".to_owned())
    }

    fn body_pose(&mut self, p: &tca_legged_messages::Pose, at_ns: u64) -> Option<WellKnown> {
        if !p.is_finite() {
            return None;
        }
        let iso = rpy_pose(p.x_m, p.y_m, p.z_m, p.roll_rad, p.pitch_rad, p.yaw_rad);
        self.body = Some(iso);
        Some(WellKnown::Transforms(FrameTransforms {
            transforms: vec![transform(at_ns, WORLD_FRAME, &self.body_frame(), &iso)],
        }))
    }

    fn set_leg(&mut self, leg: &str, joints: Vec<f64>) -> bool {
        let Some(robot) = &mut self.robot else {
            return false;
        };
        let Some(index) = robot.model.leg_index(leg) else {
            return false;
        };
        if robot.model.legs()[index].check(&joints).is_err() {
            return false;
        }
        robot.posture[index] = joints;
        true
    }

    /// Every link's frame from the body link's, for the URDF layer of the 3D panel.
    fn link_transforms(&self, at_ns: u64) -> Option<WellKnown> {
        let robot = self.robot.as_ref()?;
        let body = robot.model.body_link();
        let poses = robot.model.link_poses(&robot.posture).ok()?;
        let transforms = poses
            .iter()
            .filter(|p| p.link != body)
            .map(|p| transform(at_ns, body, p.link, &p.pose))
            .collect();
        Some(WellKnown::Transforms(FrameTransforms { transforms }))
    }

    fn support(&self, s: &tca_legged_messages::SupportState, at_ns: u64) -> Vec<SceneEntity> {
        let mut feet = entity(at_ns, WORLD_FRAME, "feet");
        let mut standing = Vec::new();
        for f in &s.feet {
            let c = if f.stance {
                standing.push((f.at.x_m, f.at.y_m, f.at.z_m));
                color(0.2, 0.9, 0.3, 1.0)
            } else {
                color(0.6, 0.6, 0.6, 0.8)
            };
            feet.spheres
                .push(sphere(f.at.x_m, f.at.y_m, f.at.z_m, 0.08, c));
        }
        let mut polygon = entity(at_ns, WORLD_FRAME, "support_polygon");
        let hull = convex_hull(&standing);
        if hull.len() >= 3 {
            let mut l = line(
                line_primitive::Type::LineLoop,
                hull.iter().map(|p| point(p.0, p.1, p.2)).collect(),
            );
            l.color = Some(if s.margin_m >= 0.0 {
                color(0.2, 0.9, 0.3, 1.0)
            } else {
                color(1.0, 0.2, 0.2, 1.0)
            });
            polygon.lines.push(l);
        }
        let mut com = entity(at_ns, WORLD_FRAME, "centre_of_mass");
        com.spheres.push(sphere(
            s.com.x_m,
            s.com.y_m,
            s.com.z_m,
            0.1,
            color(1.0, 0.3, 0.3, 1.0),
        ));
        com.texts.push(text(
            s.com.x_m,
            s.com.y_m,
            s.com.z_m + 0.15,
            format!("margin {:.3} m", s.margin_m),
        ));
        vec![feet, polygon, com]
    }

    fn legged_leg_path(
        &mut self,
        id: MessageId,
        m: &tca_legged_messages::LegMove,
        at_ns: u64,
    ) -> Option<WellKnown> {
        let robot = self.robot.as_ref()?;
        let index = robot.model.leg_index(&m.leg)?;
        let leg = &robot.model.legs()[index];
        let last = m.waypoints.last()?.clone();
        self.leg_moves.insert(id, (index, last));
        let body = self.body?;
        let points: Vec<_> = m
            .waypoints
            .iter()
            .filter_map(|q| leg.foot_position(q).ok())
            .map(|p: P3<f64>| {
                let w = body * p;
                point(w.x, w.y, w.z)
            })
            .collect();
        let mut ent = entity(at_ns, WORLD_FRAME, &format!("leg_path/{}", m.leg));
        ent.lines
            .push(line(line_primitive::Type::LineStrip, points));
        Some(scene(vec![ent]))
    }

    fn legged_plan(&self, s: &LeggedStepPlanned, at_ns: u64) -> SceneEntity {
        let mut ent = entity(at_ns, WORLD_FRAME, "footholds");
        for (leg, p) in &s.footholds {
            ent.spheres
                .push(sphere(p.x_m, p.y_m, p.z_m, 0.1, color(1.0, 0.8, 0.1, 0.9)));
            ent.texts
                .push(text(p.x_m, p.y_m, p.z_m + 0.12, leg.clone()));
        }
        let b = &s.body_target;
        if b.is_finite() {
            ent.arrows.push(ArrowPrimitive {
                pose: Some(pose(&rpy_pose(
                    b.x_m,
                    b.y_m,
                    b.z_m,
                    b.roll_rad,
                    b.pitch_rad,
                    b.yaw_rad,
                ))),
                shaft_length: 0.3,
                shaft_diameter: 0.03,
                head_length: 0.1,
                head_diameter: 0.08,
                color: Some(color(0.3, 0.6, 1.0, 1.0)),
            });
        }
        ent
    }
}
