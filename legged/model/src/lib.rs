//! Multi-legged robots described in URDF: their legs, forward and inverse kinematics,
//! centre of mass and collision shapes, and three shipped robots (`ambler`, `hexapod`,
//! `athlete`).
//!
//! ```
//! use tca_legged_model::{IkOptions, RobotModel};
//!
//! let robot = RobotModel::builtin("ambler")?;
//! assert_eq!(robot.legs().len(), 6);
//! let leg = robot.leg("left_front").expect("the Ambler has a left front leg");
//! let foot = leg.foot_position(&leg.neutral())?;
//! let solution = leg.inverse_kinematics(&foot, &IkOptions::default())?;
//! assert!(solution.error_m < 1e-3);
//! let com = robot.centre_of_mass(&robot.neutral_posture())?;
//! println!("{:.0} kg, centre of mass at z = {:.2} m", com.mass, com.centre.z);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! A URDF file is read with `urdf-rs` and must follow these rules; anything else is refused
//! with a [`ModelError`] that names the joint or link, the reason and what to change.
//! `ROBOTS.md` beside this crate says the same for people writing their own files.
//!
//! - **Body.** The root link (the one link that is no joint's child) is the body. Its frame
//!   is the body frame of every result: x forward, y left, z up (ROS REP 103). Units are SI:
//!   metres, radians, kilograms, seconds. There must be exactly one root, and every link
//!   must be reachable from it.
//! - **Legs.** Every link whose name ends in `_foot` ends a leg, named by the link's name
//!   without the suffix (`left_front_foot` ends the leg `left_front`). The leg's joints are
//!   the chain from the body to that link. Legs keep the order of their foot links in the
//!   file.
//! - **Joints.** `revolute`, `prismatic` and `fixed` joints are allowed. A moving
//!   (revolute or prismatic) joint needs `<limit lower upper velocity>` with finite
//!   `lower <= upper` and `velocity > 0` (`effort`, which URDF requires, is kept but not
//!   used), a non-zero `<axis>`, no `<mimic>`, and must lie on exactly one leg's chain: a
//!   moving joint shared by two legs would be a limb branching into two feet, and one that
//!   leads to no foot is not part of a leg. Fixed joints are rigid connections; those off
//!   the legs, or shared by several legs, belong to the body. `continuous`, `floating`,
//!   `planar` and `spherical` joints are refused.
//! - **Feet.** A foot touches the ground with the sphere of its link's `<collision>`; a
//!   foot link without `<collision>` is a point (radius 0) at the link's origin. Any other
//!   foot collision is refused. The *foot position* used by [`Leg::foot_position`] and
//!   [`Leg::inverse_kinematics`] is the centre of that sphere.
//! - **Obstacle shapes.** The `<collision>` boxes, cylinders, spheres and capsules of the
//!   other links are what must not hit the terrain ([`RobotModel::collision_shapes`]).
//!   Collision meshes are refused (not ignored), so that no part of the robot silently
//!   escapes terrain checks; `<visual>` elements are not read.
//! - **Mass.** The `<inertial>` masses and origins of all links, legs included, give the
//!   centre of mass ([`RobotModel::centre_of_mass`]); a link without `<inertial>` weighs
//!   nothing, and a robot with no mass at all is refused.
//!
//! # Joint positions
//!
//! A leg's joint positions are a slice with one value per moving joint, from the body
//! outwards (radians or metres); a *posture* is one such slice per leg, in leg order.
//! Fixed joints have no position: their transforms are folded into the moving joints'
//! [`origin`](LegJoint::origin)s and the leg's [`foot_offset`](Leg::foot_offset). A leg's
//! [`neutral`](Leg::neutral) position is every joint at 0 (or its nearest limit); the
//! shipped robots stand in it.
//!
//! # Layout
//!
//! - [`model`]: [`RobotModel`], loading (`from_urdf_str`, `from_file`, `builtin`, `load`).
//! - [`leg`], [`joint`]: [`Leg`], [`LegJoint`], [`JointKind`], [`JointLimits`], forward
//!   kinematics and the Jacobian.
//! - [`link`], [`shape`]: [`Link`], [`Collision`], [`Shape`], [`PlacedShape`].
//! - [`posture`]: whole-robot link poses, collision shapes, feet, centre of mass.
//! - [`ik`]: [`Leg::inverse_kinematics`] with [`IkOptions`].
//! - [`stance`]: standing postures at a height.
//! - [`workspace`]: sampled reachable workspaces ([`WorkspaceSummary`]).
//! - [`builtin`]: the shipped robots ([`BUILTIN_ROBOTS`]).
//! - [`error`]: [`ModelError`] and [`KinematicsError`].

mod build;
pub mod builtin;
mod convert;
pub mod error;
pub mod ik;
pub mod joint;
pub mod leg;
pub mod leg_parts;
pub mod link;
pub mod model;
pub mod posture;
mod read;
mod sampler;
pub mod self_contact;
pub mod shape;
pub mod stance;
pub mod workspace;

pub use builtin::{BUILTIN_ROBOTS, BuiltinRobot};
pub use error::{JointProblem, KinematicsError, LinkProblem, ModelError};
pub use ik::{IkOptions, IkSolution};
pub use joint::{JointKind, JointLimits, LegJoint};
pub use leg::Leg;
pub use leg_parts::LegParts;
pub use link::Link;
pub use model::RobotModel;
pub use posture::{LinkPose, MassProperties};
pub use self_contact::{SelfContact, segment_distance};
pub use shape::{Collision, PlacedShape, Shape};
pub use workspace::WorkspaceSummary;
