#pragma once
// Evaluating a rig's skeleton: the node transforms of a clip at a time (lerp/slerp between keys),
// the bind and rest poses, and the skinning transforms that linear blend skinning applies.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "skinning/rig.hpp"

namespace skelcd::skinning {

/// A 3 × 4 affine transform [A | t], applied as A p + t: object-space rest → object-space posed.
using BoneTransform = Eigen::Matrix<double, 3, 4>;

/// Value of a keyed vector track at time `t` (seconds): linear interpolation between the two keys
/// around t, the first/last value before/after the keys.
/// @param times strictly increasing key times, same length as `values`, not empty.
[[nodiscard]] Eigen::Vector3d interpolate_vector(
    std::span<const double> times,
    std::span<const Eigen::Vector3d> values,
    double t);

/// Value of a keyed rotation track at time `t`: spherical linear interpolation along the shorter
/// arc between the two keys around t; the first/last key outside them.
/// @param times strictly increasing key times, same length as `values`, not empty; unit quaternions.
[[nodiscard]] Eigen::Quaterniond interpolate_rotation(
    std::span<const double> times,
    std::span<const Eigen::Quaterniond> values,
    double t);

/// The skeleton in one pose.
struct Pose {
  /// #nodes global transforms in object space (Skeleton::root_transform applied).
  std::vector<Eigen::Affine3d> node_global;
  /// #B + #P skinning transforms: one per bone (node_global × inverse_bind), then one per part
  /// attachment (Rig::part_attachments, identity when there are none or a part has no node).
  std::vector<BoneTransform> transforms;
};

/// Evaluates poses of one rig, built once; evaluation allocates nothing once `pose` has been
/// sized by a first call. The rig must outlive the evaluator.
class PoseEvaluator {
 public:
  /// @throws InvalidInput when validate_rig(rig) does.
  explicit PoseEvaluator(const Rig& rig);

  [[nodiscard]] const Rig& rig() const { return *rig_; }
  /// #B + #P: the length of Pose::transforms.
  [[nodiscard]] std::int32_t num_transforms() const;

  /// The bind pose: every bone at the inverse of its inverse bind matrix, so that skinning
  /// reproduces Mesh::rest_positions (up to rounding); other nodes at rest.
  void bind_pose(Pose& pose) const;
  /// Every node at its static transform (SkeletonNode::rest_local). Equals the bind pose only
  /// when the file's node hierarchy is saved in its bind pose.
  void rest_pose(Pose& pose) const;
  /// Clip `clip` at time `time_s` seconds: nodes with a channel take its interpolated
  /// translation, rotation and scale (a missing track keeps the node's rest value), the others
  /// keep their static transform. Times outside the keys clamp to the first/last key.
  /// @pre 0 <= clip < rig().clips.size()
  void clip_pose(std::int32_t clip, double time_s, Pose& pose) const;

 private:
  void prepare(Pose& pose) const;
  void finish(Pose& pose) const;  // node locals in node_global → globals and transforms

  const Rig* rig_;
  // Rest translation, rotation and scale of every node, for channels that lack one of them.
  std::vector<Eigen::Vector3d> rest_translation_;
  std::vector<Eigen::Quaterniond> rest_rotation_;
  std::vector<Eigen::Vector3d> rest_scale_;
  // Per clip: the channel of each node, or -1.
  std::vector<std::vector<std::int32_t>> channel_of_node_;
  // Object-space rest globals, for the bind pose.
  std::vector<Eigen::Affine3d> rest_global_;
};

}  // namespace skelcd::skinning
