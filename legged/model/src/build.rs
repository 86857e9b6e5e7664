//! The conventions: from the URDF tree to a body with legs.
//!
//! The root link is the body. Every link whose name ends in `_foot` ends a leg, named by the
//! link without the suffix; the leg's joints are the chain from the root to that link. Fixed
//! joints are rigid connections (shared ones belong to the body); every moving joint must
//! belong to exactly one leg. Anything else is refused with the name of the joint or link.

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3};

use crate::convert::{self, JointSpec, LinkSpec};
use crate::error::{JointProblem, LinkProblem, ModelError};
use crate::joint::LegJoint;
use crate::leg::Leg;
use crate::link::{Link, Placement};
use crate::model::RobotModel;
use crate::shape::Shape;

/// The suffix that marks a foot link.
pub(crate) const FOOT_SUFFIX: &str = "_foot";

fn joint_error(joint: &str, problem: JointProblem) -> ModelError {
    ModelError::Joint {
        joint: joint.to_owned(),
        problem,
    }
}

fn link_error(link: &str, problem: LinkProblem) -> ModelError {
    ModelError::Link {
        link: link.to_owned(),
        problem,
    }
}

/// The file's links and joints, checked one by one and connected into a tree.
struct Tree {
    links: Vec<LinkSpec>,
    joints: Vec<JointSpec>,
    /// For each link, the joint whose child it is.
    parent_joint: Vec<Option<usize>>,
    /// For each link, the joints whose parent it is, in file order.
    child_joints: Vec<Vec<usize>>,
    /// For each joint, its parent and child link.
    ends: Vec<(usize, usize)>,
    root: usize,
}

impl Tree {
    fn new(robot: &urdf_rs::Robot) -> Result<Self, ModelError> {
        let mut joints = Vec::with_capacity(robot.joints.len());
        let mut joint_names = HashMap::new();
        for joint in &robot.joints {
            if joint_names
                .insert(joint.name.as_str(), joints.len())
                .is_some()
            {
                return Err(joint_error(&joint.name, JointProblem::DuplicateName));
            }
            joints.push(convert::joint(joint)?);
        }
        let mut links = Vec::with_capacity(robot.links.len());
        let mut link_index = HashMap::new();
        for link in &robot.links {
            if link_index.insert(link.name.clone(), links.len()).is_some() {
                return Err(link_error(&link.name, LinkProblem::DuplicateName));
            }
            links.push(convert::link(link)?);
        }
        if links.is_empty() {
            return Err(ModelError::NoLinks);
        }
        let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
        let mut child_joints = vec![Vec::new(); links.len()];
        let mut ends = Vec::with_capacity(joints.len());
        for (j, joint) in joints.iter().enumerate() {
            let find = |role: &'static str, name: &str| {
                link_index.get(name).copied().ok_or_else(|| {
                    joint_error(
                        &joint.name,
                        JointProblem::UnknownLink {
                            role,
                            link: name.to_owned(),
                        },
                    )
                })
            };
            let parent = find("parent", &joint.parent)?;
            let child = find("child", &joint.child)?;
            if parent == child {
                return Err(joint_error(
                    &joint.name,
                    JointProblem::SelfLoop {
                        link: joint.child.clone(),
                    },
                ));
            }
            if let Some(other) = parent_joint[child] {
                return Err(joint_error(
                    &joint.name,
                    JointProblem::SecondParent {
                        link: joint.child.clone(),
                        other: joints[other].name.clone(),
                    },
                ));
            }
            parent_joint[child] = Some(j);
            child_joints[parent].push(j);
            ends.push((parent, child));
        }
        let roots: Vec<usize> = (0..links.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        let root = match roots.as_slice() {
            [] => return Err(ModelError::NoRoot),
            [root] => *root,
            _ => {
                return Err(ModelError::SeveralRoots {
                    roots: roots.iter().map(|&l| links[l].name.clone()).collect(),
                });
            }
        };
        let tree = Tree {
            links,
            joints,
            parent_joint,
            child_joints,
            ends,
            root,
        };
        let order = tree.order_from_root();
        if order.len() < tree.links.len() {
            let mut reached = vec![false; tree.links.len()];
            for &l in &order {
                reached[l] = true;
            }
            if let Some(l) = reached.iter().position(|r| !r) {
                return Err(link_error(
                    &tree.links[l].name,
                    LinkProblem::Unreachable {
                        root: tree.links[root].name.clone(),
                    },
                ));
            }
        }
        Ok(tree)
    }

    /// Links reachable from the root, parents before children.
    fn order_from_root(&self) -> Vec<usize> {
        let mut order = vec![self.root];
        let mut next = 0;
        while next < order.len() {
            let link = order[next];
            next += 1;
            for &j in &self.child_joints[link] {
                order.push(self.ends[j].1);
            }
        }
        order
    }

    /// The joints from the root down to a link, root first.
    fn chain_to(&self, link: usize) -> Vec<usize> {
        let mut chain = Vec::new();
        let mut at = link;
        while let Some(j) = self.parent_joint[at] {
            chain.push(j);
            at = self.ends[j].0;
        }
        chain.reverse();
        chain
    }

    fn kind_name(&self, joint: usize) -> &'static str {
        self.joints[joint]
            .motion
            .map(|(kind, _)| kind.urdf_name())
            .unwrap_or("fixed")
    }
}

/// A foot link found by its name.
struct Foot {
    link: usize,
    leg_name: String,
}

fn find_feet(tree: &Tree) -> Result<Vec<Foot>, ModelError> {
    let mut feet = Vec::new();
    for (l, link) in tree.links.iter().enumerate() {
        let Some(leg_name) = link.name.strip_suffix(FOOT_SUFFIX) else {
            continue;
        };
        if l == tree.root {
            return Err(link_error(&link.name, LinkProblem::BodyNamedFoot));
        }
        if leg_name.is_empty() {
            return Err(link_error(&link.name, LinkProblem::EmptyLegName));
        }
        feet.push(Foot {
            link: l,
            leg_name: leg_name.to_owned(),
        });
    }
    if feet.is_empty() {
        return Err(ModelError::NoLegs);
    }
    Ok(feet)
}

/// Which leg owns each moving joint; refuses a moving joint on two legs' chains or on none.
fn assign_joints(tree: &Tree, feet: &[Foot]) -> Result<Vec<Option<usize>>, ModelError> {
    let mut owner: Vec<Option<usize>> = vec![None; tree.joints.len()];
    for (leg, foot) in feet.iter().enumerate() {
        let chain = tree.chain_to(foot.link);
        let mut moving = 0;
        for j in chain {
            if tree.joints[j].motion.is_none() {
                continue;
            }
            moving += 1;
            if let Some(first) = owner[j] {
                return Err(joint_error(
                    &tree.joints[j].name,
                    JointProblem::SharedByLegs {
                        first: feet[first].leg_name.clone(),
                        second: foot.leg_name.clone(),
                    },
                ));
            }
            owner[j] = Some(leg);
        }
        if moving == 0 {
            return Err(link_error(
                &tree.links[foot.link].name,
                LinkProblem::RigidFoot,
            ));
        }
    }
    if let Some(j) =
        (0..tree.joints.len()).find(|&j| tree.joints[j].motion.is_some() && owner[j].is_none())
    {
        return Err(joint_error(
            &tree.joints[j].name,
            JointProblem::LeadsToNoFoot {
                kind: tree.kind_name(j),
            },
        ));
    }
    Ok(owner)
}

/// The contact sphere of a foot: its one collision sphere, or a point at its origin.
fn foot_contact(spec: &LinkSpec) -> Result<(Point3<f64>, f64), ModelError> {
    match spec.collisions.as_slice() {
        [] => Ok((Point3::origin(), 0.0)),
        [collision] => match collision.shape {
            Shape::Sphere { radius } => {
                Ok((Point3::from(collision.origin.translation.vector), radius))
            }
            other => Err(link_error(
                &spec.name,
                LinkProblem::FootShape {
                    found: format!("it has a {}", other.kind()),
                },
            )),
        },
        several => Err(link_error(
            &spec.name,
            LinkProblem::FootShape {
                found: format!("it has {} collision shapes", several.len()),
            },
        )),
    }
}

/// Builds the model from a parsed URDF robot, applying every convention.
pub(crate) fn build(robot: &urdf_rs::Robot) -> Result<RobotModel, ModelError> {
    let tree = Tree::new(robot)?;
    let feet = find_feet(&tree)?;
    let owner = assign_joints(&tree, &feet)?;

    let mut contacts = Vec::with_capacity(feet.len());
    for foot in &feet {
        contacts.push(foot_contact(&tree.links[foot.link])?);
    }

    let mut leg_joints: Vec<Vec<LegJoint>> = vec![Vec::new(); feet.len()];
    let mut placements: Vec<Option<Placement>> = vec![None; tree.links.len()];
    placements[tree.root] = Some(Placement {
        leg: None,
        stage: 0,
        offset: Isometry3::identity(),
    });
    for link in tree.order_from_root() {
        let Some(j) = tree.parent_joint[link] else {
            continue;
        };
        let joint = &tree.joints[j];
        let Some(parent) = placements[tree.ends[j].0] else {
            continue;
        };
        let placement = match (joint.motion, owner[j]) {
            (Some((kind, limits)), Some(leg)) => {
                leg_joints[leg].push(LegJoint {
                    name: joint.name.clone(),
                    kind,
                    origin: parent.offset * joint.origin,
                    limits,
                    child_link: joint.child.clone(),
                });
                Placement {
                    leg: Some(leg),
                    stage: parent.stage + 1,
                    offset: Isometry3::identity(),
                }
            }
            _ => Placement {
                offset: parent.offset * joint.origin,
                ..parent
            },
        };
        placements[link] = Some(placement);
    }

    let legs = feet
        .iter()
        .zip(leg_joints)
        .zip(&contacts)
        .map(|((foot, joints), &(contact_centre, foot_radius))| Leg {
            name: foot.leg_name.clone(),
            joints,
            foot_link: tree.links[foot.link].name.clone(),
            foot_offset: placements[foot.link]
                .map(|p| p.offset)
                .unwrap_or_else(Isometry3::identity),
            contact_centre,
            foot_radius,
        })
        .collect();

    let foot_links: Vec<usize> = feet.iter().map(|f| f.link).collect();
    let links: Vec<Link> = tree
        .links
        .iter()
        .zip(placements)
        .enumerate()
        .map(|(l, (spec, placement))| Link {
            name: spec.name.clone(),
            mass: spec.mass,
            centre_of_mass: spec.centre_of_mass,
            // A foot's one sphere is its contact, not an obstacle shape.
            collisions: if foot_links.contains(&l) {
                Vec::new()
            } else {
                spec.collisions.clone()
            },
            placement: placement.unwrap_or(Placement {
                leg: None,
                stage: 0,
                offset: Isometry3::identity(),
            }),
        })
        .collect();

    let total_mass: f64 = links.iter().map(|l| l.mass).sum();
    if total_mass <= 0.0 {
        return Err(ModelError::NoMass);
    }
    Ok(RobotModel {
        name: robot.name.clone(),
        body_link: tree.links[tree.root].name.clone(),
        legs,
        links,
        total_mass,
    })
}
