#pragma once
// A URDF robot as a rigid-skinned Rig: one skeleton node per link, one bone and one mesh part per
// link that has geometry, and the joints that move the links (forward kinematics).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "skinning/rig.hpp"

namespace skelcd::skinning {

struct LoadedModel;
struct LoadOptions;

enum class JointType { kFixed, kRevolute, kContinuous, kPrismatic };

/// Name of a joint type as URDF spells it ("fixed", "revolute", "continuous", "prismatic").
[[nodiscard]] std::string_view joint_type_name(JointType type);

/// A URDF joint: moves its child link relative to its parent link.
struct RobotJoint {
  std::string name;
  JointType type = JointType::kFixed;
  std::int32_t parent_link = -1;  ///< index into Robot::links
  std::int32_t child_link = -1;   ///< index into Robot::links
  /// Parent link frame → joint frame (the URDF <origin>); the child link frame at position 0.
  Eigen::Affine3d origin = Eigen::Affine3d::Identity();
  /// Unit axis in the joint frame (rotation axis, or translation direction for prismatic).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  bool has_limits = false;  ///< revolute and prismatic joints have limits; continuous do not
  double lower = 0.0;       ///< radians or metres
  double upper = 0.0;
  /// Mimic: position = multiplier * position(mimic_joint) + offset; -1 when not a mimic joint.
  std::int32_t mimic_joint = -1;
  double mimic_multiplier = 1.0;
  double mimic_offset = 0.0;

  [[nodiscard]] bool movable() const { return type != JointType::kFixed; }
  /// Movable and not driven by another joint.
  [[nodiscard]] bool independent() const { return movable() && mimic_joint < 0; }
};

struct RobotLink {
  std::string name;
  std::int32_t parent_joint = -1;  ///< index into Robot::joints, -1 for the root link
  std::int32_t part = -1;          ///< mesh part of its geometry, -1 when it has none
  std::int32_t bone = -1;          ///< its bone, -1 when it has no geometry
};

/// A robot: links in skeleton order (parents before children; link i is skeleton node i) and the
/// rig that carries their collision geometry.
struct Robot {
  std::string name;
  std::filesystem::path urdf_file;
  std::vector<RobotLink> links;
  /// One joint per non-root link, in the order of their child links.
  std::vector<RobotJoint> joints;
  /// Mesh (rest = all joint positions 0, object space = root link frame), skeleton (node i =
  /// link i, rest_local = joint origin), one-hot weights, no clip.
  Rig rig;

  [[nodiscard]] std::int32_t num_links() const { return static_cast<std::int32_t>(links.size()); }
  [[nodiscard]] std::int32_t num_joints() const { return static_cast<std::int32_t>(joints.size()); }
  /// Joints that are not fixed (mimic joints included).
  [[nodiscard]] std::int32_t num_movable_joints() const;
  /// Index of the link / joint with this name, -1 when there is none.
  [[nodiscard]] std::int32_t find_link(std::string_view name) const;
  [[nodiscard]] std::int32_t find_joint(std::string_view name) const;
};

struct UrdfOptions {
  /// Extra folders searched for `package://NAME/...` and relative mesh paths, after the URDF's
  /// folder and its ancestors.
  std::vector<std::filesystem::path> package_path;
  /// An SRDF whose <disable_collisions link1 link2/> pairs are excluded too (empty: none).
  std::filesystem::path srdf;
  /// Cylinders and spheres: segments around the axis (>= 3).
  int round_segments = 32;
  /// Spheres: rings from pole to pole (>= 2).
  int sphere_rings = 16;
};

/// Loads a URDF robot and its collision geometry (visual geometry for links without collision
/// geometry): meshes (STL, DAE, OBJ, ... through assimp, `scale` applied), boxes (12 triangles),
/// cylinders (4 × round_segments triangles, capped), spheres (UV sphere, 2 × round_segments ×
/// (sphere_rings − 1) triangles).
/// Mesh::excluded_part_pairs holds (a, a) for every link part, every pair of link parts joined by a
/// joint (through links without geometry), every pair of parts joined rigidly by fixed joints,
/// and the SRDF's disabled pairs.
/// @throws IoError when the URDF, SRDF or a mesh file cannot be found, read or parsed.
/// @throws InvalidInput (naming the file and link or joint) for a link with two parents, a joint
///   cycle, an unknown link, an unsupported joint type (floating, planar), a mimic cycle, a zero
///   joint axis, a mesh with non-finite coordinates.
[[nodiscard]] Robot load_urdf(const std::filesystem::path& urdf_file, const UrdfOptions& options = {});

/// Local transform of a joint's child link at joint position `position` (radians or metres):
/// origin · rotation(axis, position) or origin · translation(position · axis).
[[nodiscard]] Eigen::Affine3d joint_transform(const RobotJoint& joint, double position);

/// Effective positions of every joint: `positions` (#joints, one per joint, entries of fixed
/// joints ignored) with mimic joints recomputed from their master.
[[nodiscard]] std::vector<double> resolve_mimic(const Robot& robot, std::span<const double> positions);

/// Forward kinematics: #links transforms link frame → root link frame for joint positions
/// `positions` (#joints; mimic entries are recomputed, fixed entries ignored).
/// @pre positions.size() == robot.joints.size()
[[nodiscard]] std::vector<Eigen::Affine3d> forward_kinematics(
    const Robot& robot,
    std::span<const double> positions);

/// The load_model() entry point for robots (ModelKind::robot): load_urdf with
/// LoadOptions::package_path and srdf, plus, when LoadOptions::trajectory is given, its clip
/// (read_joint_trajectory + trajectory_clip, named after the CSV file's stem). Motions sample the
/// clip at its rows' rate (every row when they are evenly spaced) unless asked otherwise.
/// Without a trajectory the robot has no clip and its one motion is the rest pose.
/// LoadedModel::problems lists links without geometry and the absence of a trajectory.
/// @throws as load_urdf and read_joint_trajectory.
[[nodiscard]] LoadedModel load_urdf_model(
    const std::filesystem::path& urdf_file,
    const LoadOptions& options);

}  // namespace skelcd::skinning
