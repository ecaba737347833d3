#pragma once
// A bone as a segment in space (rest pose, object space), and the point of it nearest to a point.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "skinning/rig.hpp"

namespace skelcd::segmentation {

struct BoneSegment {
  Eigen::Vector3d head = Eigen::Vector3d::Zero();  ///< the bone's joint (shared with its parent)
  Eigen::Vector3d tail = Eigen::Vector3d::Zero();  ///< the child's joint or the extended end
  std::int32_t parent = -1;  ///< parent bone (index into the same list), −1 for a root

  [[nodiscard]] Eigen::Vector3d midpoint() const { return 0.5 * (head + tail); }
  /// The point of the segment nearest to `p` (the head when the bone has zero length).
  [[nodiscard]] Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d axis = tail - head;
    const double len2 = axis.squaredNorm();
    if (!(len2 > 0.0)) return head;
    const double s = std::clamp((p - head).dot(axis) / len2, 0.0, 1.0);
    return head + s * axis;
  }
};

/// The rest segments of a skeleton's bones, in bone order (Bone::rest_head, Bone::rest_tail,
/// Bone::parent).
[[nodiscard]] inline std::vector<BoneSegment> bone_segments(const skinning::Skeleton& skeleton) {
  std::vector<BoneSegment> out;
  out.reserve(skeleton.bones.size());
  for (const auto& bone : skeleton.bones) out.push_back({bone.rest_head, bone.rest_tail, bone.parent});
  return out;
}

}  // namespace skelcd::segmentation
