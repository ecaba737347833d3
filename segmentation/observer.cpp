#include "segmentation/observer.hpp"

#include <Eigen/Geometry>

#include "segmentation/detail/orient3d.hpp"

namespace skelcd::segmentation {

std::string_view to_string(ObserverKind kind) {
  return kind == ObserverKind::point ? "point" : "line";
}

Orientation orientation(const Observer& observer, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const int s = detail::orient3d_sign(a, b, c, observer.viewing_position(a));
  return s > 0 ? Orientation::positive : (s < 0 ? Orientation::negative : Orientation::uncertain);
}

ObserverChoice choose_observer(const skinning::Positions& V, const skinning::Triangles& F,
                               std::span<const std::int32_t> triangles, const BoneSegment& bone,
                               const Eigen::VectorXd& follow, double theta_rad) {
  ObserverChoice out;
  if (triangles.empty()) return out;

  // The test poses: identity, then ±θ about x, y, z, all about the bone's head joint.
  std::vector<Eigen::Matrix3d> rotations = {Eigen::Matrix3d::Identity()};
  for (int axis = 0; axis < 3; ++axis) {
    for (const double sign : {1.0, -1.0}) {
      rotations.push_back(
          Eigen::AngleAxisd(sign * theta_rad, Eigen::Vector3d::Unit(axis)).toRotationMatrix());
    }
  }
  const Eigen::Vector3d q1 = bone.head;
  std::int64_t positive_point = 0;
  std::int64_t positive_line = 0;
  for (std::size_t r = 0; r < rotations.size(); ++r) {
    const Eigen::Matrix3d& R = rotations[r];
    // The bone turns rigidly about q1; a vertex turns by its blend of R and the identity
    // (linear blend skinning with the bone's subtree weight), exactly as LBS would pose it.
    BoneSegment posed = bone;
    posed.tail = q1 + R * (bone.tail - q1);
    const Observer point{ObserverKind::point, posed};
    const Observer line{ObserverKind::line, posed};
    const auto pose = [&](std::int32_t v) -> Eigen::Vector3d {
      const Eigen::Vector3d x = V.row(v).transpose();
      if (r == 0) return x;  // the rest pose, bit for bit
      const double s = follow[v];
      return q1 + s * (R * (x - q1)) + (1.0 - s) * (x - q1);
    };
    for (const auto f : triangles) {
      const Eigen::Vector3d a = pose(F(f, 0)), b = pose(F(f, 1)), c = pose(F(f, 2));
      positive_point += orientation(point, a, b, c) == Orientation::positive;
      positive_line += orientation(line, a, b, c) == Orientation::positive;
    }
  }
  out.poses = static_cast<int>(rotations.size());
  out.mean_positive_point = static_cast<double>(positive_point) / out.poses;
  out.mean_positive_line = static_cast<double>(positive_line) / out.poses;
  // §4.2: "we set the observer primitive to q if |H̄⁺(q)| > |H̄⁺(q1q2)|, and to q1q2 otherwise".
  out.kind = out.mean_positive_point > out.mean_positive_line ? ObserverKind::point
                                                               : ObserverKind::line;
  return out;
}

}  // namespace skelcd::segmentation
