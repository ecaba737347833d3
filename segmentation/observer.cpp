#include "segmentation/observer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

#include "ccd/orientation.hpp"

namespace skelcd::segmentation {

std::string_view to_string(ObserverKind kind) {
  return kind == ObserverKind::point ? "point" : "line";
}

Orientation orientation(const Observer& observer, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d q = observer.viewing_position(a);
  // ccd::orient3d (Shewchuk's static filter, then the exact predicate) is the sign of (q − a) · n,
  // the opposite of ours.
  const int s = -ccd::orient3d(a, b, c, q);
  return s > 0 ? Orientation::positive : (s < 0 ? Orientation::negative : Orientation::uncertain);
}

namespace {

/// The test poses: identity, then ±θ about x, y, z, all about the bone's head joint.
constexpr int kPoses = 7;

}  // namespace

void positive_counts(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    std::span<const std::int32_t> triangles,
    const BoneSegment& bone,
    const Eigen::MatrixXd& W,
    std::span<const std::int32_t> subtree,
    double theta_rad,
    std::span<PositiveCounts> out) {
  assert(out.size() == triangles.size());
  std::fill(out.begin(), out.end(), PositiveCounts{});
  if (triangles.empty()) return;

  // The triangles' vertices, each once, and the triangles in that local numbering.
  std::vector<std::int32_t> vertices;
  vertices.reserve(triangles.size() * 3);
  for (const auto f : triangles) {
    for (int c = 0; c < 3; ++c) vertices.push_back(F(f, c));
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  const auto local = [&](std::int32_t v) {
    return static_cast<std::size_t>(
        std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin());
  };
  std::vector<std::array<std::size_t, 3>> local_triangles;
  local_triangles.reserve(triangles.size());
  for (const auto f : triangles) local_triangles.push_back({local(F(f, 0)), local(F(f, 1)), local(F(f, 2))});
  // How much of each vertex follows the bone: its summed weight on the bone's subtree.
  // Column by column (W is column-major; the vertices ascend): each vertex's sum in the same
  // order as row by row, without a cache miss per weight.
  std::vector<double> follow(vertices.size(), 0.0);
  for (const auto b : subtree) {
    const double* column = W.col(b).data();
    for (std::size_t k = 0; k < vertices.size(); ++k) follow[k] += column[vertices[k]];
  }
  for (auto& f : follow) f = std::min(1.0, f);

  std::vector<Eigen::Matrix3d> rotations = {Eigen::Matrix3d::Identity()};
  for (int axis = 0; axis < 3; ++axis) {
    for (const double sign : {1.0, -1.0}) {
      rotations.push_back(
          Eigen::AngleAxisd(sign * theta_rad, Eigen::Vector3d::Unit(axis)).toRotationMatrix());
    }
  }
  assert(static_cast<int>(rotations.size()) == kPoses);
  const Eigen::Vector3d q1 = bone.head;
  std::vector<Eigen::Vector3d> posed(vertices.size());
  for (std::size_t r = 0; r < rotations.size(); ++r) {
    const Eigen::Matrix3d& R = rotations[r];
    BoneSegment posed_bone = bone;
    posed_bone.tail = q1 + R * (bone.tail - q1);
    const Observer point{ObserverKind::point, posed_bone};
    const Observer line{ObserverKind::line, posed_bone};
    for (std::size_t k = 0; k < vertices.size(); ++k) {
      const Eigen::Vector3d x = V.row(vertices[k]).transpose();
      // The rest pose bit for bit; otherwise the LBS blend of R and the identity about q1.
      posed[k] = r == 0 ? x : Eigen::Vector3d(q1 + follow[k] * (R * (x - q1)) + (1.0 - follow[k]) * (x - q1));
    }
    const Eigen::Vector3d midpoint = posed_bone.midpoint();  // the point observer's q
    for (std::size_t i = 0; i < local_triangles.size(); ++i) {
      const auto& t = local_triangles[i];
      const auto& a = posed[t[0]];
      const auto& b = posed[t[1]];
      const auto& c = posed[t[2]];
      // orientation()'s sign, (a − q) · ((b − a) × (c − a)) = det[u; v; a − q], by the static
      // orient3d filter on the transposed rows, whose 2 × 2 minors are those of u and v alone
      // (the same for both observers); the exact orientation() when it cannot tell, on the same q.
      const Eigen::Vector3d u = b - a;
      const Eigen::Vector3d v = c - a;
      const auto positive = [&](const Observer& observer, const Eigen::Vector3d& q) {
        const Eigen::Vector3d w = a - q;
        const int s = ccd::detail::det3_sign_static(
            u.x(), v.x(), w.x(), u.y(), v.y(), w.y(), u.z(), v.z(), w.z());
        return s != ccd::detail::kUndecided
                   ? s > 0
                   : orientation(observer, a, b, c) == Orientation::positive;
      };
      out[i].point = static_cast<std::uint8_t>(out[i].point + positive(point, midpoint));
      out[i].line =
          static_cast<std::uint8_t>(out[i].line + positive(line, line.viewing_position(a)));
    }
  }
}

ObserverChoice observer_choice(std::int64_t positive_point, std::int64_t positive_line) {
  ObserverChoice out;
  out.poses = kPoses;
  out.mean_positive_point = static_cast<double>(positive_point) / out.poses;
  out.mean_positive_line = static_cast<double>(positive_line) / out.poses;
  // §4.2: the point when it keeps more triangles positive on average, else the line. On a tie
  // the point: "the observer points are preferred over the observer line segments" (no
  // projection per triangle at run time); the paper's formula, read literally, gives ties to the
  // line.
  out.kind = out.mean_positive_point >= out.mean_positive_line ? ObserverKind::point
                                                                : ObserverKind::line;
  return out;
}

ObserverChoice choose_observer(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    std::span<const std::int32_t> triangles,
    const BoneSegment& bone,
    const Eigen::MatrixXd& W,
    std::span<const std::int32_t> subtree,
    double theta_rad) {
  if (triangles.empty()) return ObserverChoice{};
  std::vector<PositiveCounts> counts(triangles.size());
  positive_counts(V, F, triangles, bone, W, subtree, theta_rad, counts);
  std::int64_t point = 0;
  std::int64_t line = 0;
  for (const auto& c : counts) {
    point += c.point;
    line += c.line;
  }
  return observer_choice(point, line);
}

}  // namespace skelcd::segmentation
