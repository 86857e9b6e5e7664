//! Errors: why a robot description was refused, and why a kinematic query failed.
//!
//! Every refusal names the joint or link at fault, says what is wrong with it and what to
//! change, so that a user's own URDF file can be fixed from the message alone.

use std::path::PathBuf;

use thiserror::Error;

/// A robot description that could not be read or does not follow the conventions of this
/// crate (see the crate documentation and `ROBOTS.md`).
#[derive(Debug, Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("cannot read the robot file {}: {source}", .path.display())]
    Read {
        /// The file that was asked for.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The text is not well-formed XML, or not a URDF `<robot>` document.
    #[error(
        "not a readable URDF document ({message}); the file must be well-formed XML with one \
         <robot> element whose <link> and <joint> elements carry the attributes URDF requires"
    )]
    Parse {
        /// What the URDF reader reported.
        message: String,
    },
    /// Neither a shipped robot nor an existing file has this name.
    #[error(
        "no built-in robot and no file is named `{name}`: the built-in robots are {known}; \
         otherwise give the path of a URDF file"
    )]
    UnknownRobot {
        /// The name or path that was asked for.
        name: String,
        /// The names of the shipped robots, comma-separated.
        known: String,
    },
    /// A joint is refused.
    #[error("joint `{joint}` {problem}")]
    Joint {
        /// The joint's name in the file.
        joint: String,
        /// What is wrong with it and what to do.
        problem: JointProblem,
    },
    /// A link is refused.
    #[error("link `{link}` {problem}")]
    Link {
        /// The link's name in the file.
        link: String,
        /// What is wrong with it and what to do.
        problem: LinkProblem,
    },
    /// The file has no link at all.
    #[error("the robot has no link: a URDF robot needs at least its body link")]
    NoLinks,
    /// Every link is the child of some joint: the joints form a loop.
    #[error(
        "the robot has no root link: every link is the child of a joint, so the joints form a \
         loop; the body must be the one link that is no joint's child"
    )]
    NoRoot,
    /// More than one link is the child of no joint.
    #[error(
        "the robot has several root links ({}): a URDF robot is one tree whose root is the \
         body; connect the others to it with joints (fixed ones for rigid parts) or remove them",
        .roots.join(", ")
    )]
    SeveralRoots {
        /// The links that are no joint's child, in file order.
        roots: Vec<String>,
    },
    /// No link's name ends in `_foot`.
    #[error(
        "the robot has no leg: no link's name ends in `_foot`; name the last link of each leg \
         `<leg>_foot` (for example `left_front_foot` for the leg `left_front`)"
    )]
    NoLegs,
    /// No link has a mass.
    #[error(
        "the robot has no mass: no link has an <inertial> with a positive <mass>; give the body \
         and the legs their masses so that the centre of mass can be computed"
    )]
    NoMass,
}

/// What is wrong with a joint.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum JointProblem {
    /// Another joint has the same name.
    #[error("is defined more than once: joint names must be unique; rename one of them")]
    DuplicateName,
    /// A `continuous` joint: a rotary joint without position limits.
    #[error(
        "is `continuous`, a rotary joint without position limits, which a leg may not have: make \
         it `revolute` with <limit lower=\"…\" upper=\"…\" velocity=\"…\" effort=\"…\"/>"
    )]
    Continuous,
    /// A `floating`, `planar` or `spherical` joint.
    #[error(
        "is `{kind}`, which a leg may not have: legs are made of `revolute`, `prismatic` and \
         `fixed` joints; the body's own motion in the world is not part of the model, so a \
         joint from a `world` link to the body should be removed (the body is then the root)"
    )]
    Unsupported {
        /// The joint type as written in the file.
        kind: &'static str,
    },
    /// The joint follows another through `<mimic>`.
    #[error(
        "follows joint `{of}` through <mimic>, which this model does not support: every moving \
         joint is driven on its own; remove the <mimic> element"
    )]
    Mimic {
        /// The joint it would follow.
        of: String,
    },
    /// A moving joint without a `<limit>` element.
    #[error(
        "is `{kind}` but has no <limit> (or one whose values are all 0): give it \
         <limit lower=\"…\" upper=\"…\" velocity=\"…\" effort=\"…\"/> with its range of motion \
         and top speed"
    )]
    MissingLimits {
        /// `revolute` or `prismatic`.
        kind: &'static str,
    },
    /// A position limit is missing or not finite.
    #[error(
        "has no finite position limits (lower {lower}, upper {upper}): give both `lower` and \
         `upper` in its <limit>"
    )]
    UnboundedLimits {
        /// The lower limit as read.
        lower: f64,
        /// The upper limit as read.
        upper: f64,
    },
    /// The lower position limit is above the upper one.
    #[error(
        "has its lower limit {lower} above its upper limit {upper}: swap them, or correct the one \
         that is wrong"
    )]
    LowerAboveUpper {
        /// The lower limit as read.
        lower: f64,
        /// The upper limit as read.
        upper: f64,
    },
    /// The velocity limit is zero.
    #[error(
        "has a velocity limit of 0 (or none), so it could never move: give its top speed, \
         greater than 0, as `velocity` in its <limit>"
    )]
    ZeroVelocity,
    /// The velocity limit is negative, infinite or not a number.
    #[error(
        "has a velocity limit of {velocity}: `velocity` must be a finite number greater than 0"
    )]
    BadVelocity {
        /// The velocity limit as read.
        velocity: f64,
    },
    /// The effort limit is negative or not a number.
    #[error("has an effort limit of {effort}: `effort` must be 0 or more")]
    BadEffort {
        /// The effort limit as read.
        effort: f64,
    },
    /// The joint axis is zero (or not finite).
    #[error(
        "has the axis ({x}, {y}, {z}), which gives no direction: give <axis xyz=\"…\"/> the \
         direction it turns about or slides along"
    )]
    BadAxis {
        /// Axis x as read.
        x: f64,
        /// Axis y as read.
        y: f64,
        /// Axis z as read.
        z: f64,
    },
    /// A number of the joint is infinite or not a number.
    #[error("has a {what} that is not a finite number: correct it")]
    NotFinite {
        /// Which value (for example "origin xyz").
        what: &'static str,
    },
    /// The parent or child link is not defined.
    #[error(
        "names the {role} link `{link}`, which the file does not define: add that link or \
         correct the name"
    )]
    UnknownLink {
        /// "parent" or "child".
        role: &'static str,
        /// The name as written.
        link: String,
    },
    /// The joint connects a link to itself.
    #[error("connects link `{link}` to itself: its parent and child must be different links")]
    SelfLoop {
        /// The link.
        link: String,
    },
    /// The child link is already the child of another joint.
    #[error(
        "makes `{link}` its child, but joint `{other}` already does: in a URDF tree every link has \
         one parent joint; remove one of the two joints"
    )]
    SecondParent {
        /// The child link.
        link: String,
        /// The first joint with that child.
        other: String,
    },
    /// A moving joint on no leg's chain.
    #[error(
        "is `{kind}` but no foot is beyond it: only legs may have moving joints, and a leg is the \
         chain of joints from the body to a link whose name ends in `_foot`; make the joint \
         `fixed`, or name the last link of its chain `<leg>_foot`"
    )]
    LeadsToNoFoot {
        /// `revolute` or `prismatic`.
        kind: &'static str,
    },
    /// A moving joint on the chains of two legs: a branching limb.
    #[error(
        "moves the feet of both `{first}` and `{second}`: a moving joint belongs to one leg, and a \
         limb that branches into two feet is not a leg; attach each leg to the body with its own \
         joints (only fixed joints, which belong to the body, may be shared)"
    )]
    SharedByLegs {
        /// The first leg whose chain has the joint.
        first: String,
        /// The second leg whose chain has the joint.
        second: String,
    },
}

/// What is wrong with a link.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LinkProblem {
    /// Another link has the same name.
    #[error("is defined more than once: link names must be unique; rename one of them")]
    DuplicateName,
    /// The link is not connected to the body.
    #[error(
        "cannot be reached from the body `{root}`: the joints above it form a loop; a URDF robot \
         is a tree, so break the loop"
    )]
    Unreachable {
        /// The root link (the body).
        root: String,
    },
    /// A mesh collision shape.
    #[error(
        "has a mesh collision (`{filename}`), which is refused: terrain checks need boxes, \
         cylinders, spheres or capsules, so replace the mesh in <collision> with primitive \
         shapes that enclose it (meshes in <visual> are fine)"
    )]
    MeshCollision {
        /// The mesh file named in the URDF.
        filename: String,
    },
    /// A collision shape with a size that is zero, negative or not finite.
    #[error("has a collision {shape} whose {what} is {value}: sizes must be finite and above 0")]
    BadShape {
        /// "box", "cylinder", "sphere" or "capsule".
        shape: &'static str,
        /// Which size (for example "radius").
        what: &'static str,
        /// The value as read.
        value: f64,
    },
    /// A mass that is negative or not finite.
    #[error("has the mass {mass}: a mass must be a finite number of kilograms, 0 or more")]
    BadMass {
        /// The mass as read.
        mass: f64,
    },
    /// A number of the link is infinite or not a number.
    #[error("has a {what} that is not a finite number: correct it")]
    NotFinite {
        /// Which value (for example "collision origin").
        what: &'static str,
    },
    /// A foot link named only `_foot`.
    #[error(
        "would name a leg with nothing: a foot link is named `<leg>_foot`, for example `left_front_foot`"
    )]
    EmptyLegName,
    /// The root link's name ends in `_foot`.
    #[error(
        "is the root link, so the body, but its name ends in `_foot`, which marks a foot: rename it"
    )]
    BodyNamedFoot,
    /// A foot with no moving joint between it and the body.
    #[error(
        "is a foot, but no revolute or prismatic joint lies between it and the body: a leg needs \
         at least one moving joint"
    )]
    RigidFoot,
    /// A foot whose collision is not a single sphere.
    #[error(
        "is a foot, and a foot's <collision> must be one sphere, its contact with the ground \
         ({found}): give it a single <sphere>, or no <collision> for a point foot"
    )]
    FootShape {
        /// What was found instead.
        found: String,
    },
}

/// A kinematic query that could not be answered.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum KinematicsError {
    /// The robot has no leg with this index or name.
    #[error("the robot has no leg {leg} (it has {count} legs)")]
    UnknownLeg {
        /// The index or name asked for.
        leg: String,
        /// How many legs the robot has.
        count: usize,
    },
    /// Joint positions were given for the wrong number of legs.
    #[error("joint positions were given for {given} legs, but the robot has {expected}")]
    LegCount {
        /// Legs given.
        given: usize,
        /// Legs of the robot.
        expected: usize,
    },
    /// A leg was given the wrong number of joint positions.
    #[error("leg `{leg}` was given {given} joint positions, but it has {expected} moving joints")]
    JointCount {
        /// The leg.
        leg: String,
        /// Positions given.
        given: usize,
        /// Moving joints of the leg.
        expected: usize,
    },
    /// A joint position, or a target, is not a finite number.
    #[error("leg `{leg}`: {what} is not a finite number")]
    NotFinite {
        /// The leg.
        leg: String,
        /// Which value.
        what: String,
    },
    /// No joint positions within the limits put the foot at the target.
    #[error(
        "leg `{leg}` cannot put its foot at ({:.3}, {:.3}, {:.3}) m within its joint limits: it came no \
         closer than {closest_m:.4} m",
        .target[0], .target[1], .target[2]
    )]
    Unreachable {
        /// The leg.
        leg: String,
        /// The target foot position in the body frame.
        target: [f64; 3],
        /// How close the foot came (the least distance over all starts), or, for a target
        /// beyond the leg's reach bound, how far beyond it the target is.
        closest_m: f64,
    },
}
