#include "segmentation/orientation_stats.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "ccd/polynomial_sign.hpp"
#include "skinning/errors.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {

namespace {

Eigen::Vector3d apply(const skinning::BoneTransform& T, const Eigen::Vector3d& p) {
  return T.leftCols<3>() * p + T.col(3);
}

void add(OrientationCounts& counts, int sign) {
  (sign > 0 ? counts.h_plus : (sign < 0 ? counts.h_minus : counts.h_uncertain))++;
}

}  // namespace

OrientationCounts count_orientations(const Segmentation& segmentation,
                                     const skinning::Positions& x, const skinning::Triangles& F,
                                     std::span<const skinning::BoneTransform> transforms) {
  OrientationCounts counts;
  for (const auto& cluster : segmentation.clusters) {
    const auto& T = transforms[static_cast<std::size_t>(cluster.bone)];
    Observer posed = cluster.observer;
    posed.segment.head = apply(T, cluster.observer.segment.head);
    posed.segment.tail = apply(T, cluster.observer.segment.tail);
    for (const auto f : cluster.triangles) {
      add(counts, static_cast<int>(orientation(posed, x, F, f)));
    }
  }
  return counts;
}

OrientationCounts count_orientations_interval(
    const Segmentation& segmentation, const skinning::Positions& x_t0,
    const skinning::Positions& x_t1, const skinning::Triangles& F,
    std::span<const skinning::BoneTransform> transforms_t0,
    std::span<const skinning::BoneTransform> transforms_t1) {
  OrientationCounts counts;
  for (const auto& cluster : segmentation.clusters) {
    const auto b = static_cast<std::size_t>(cluster.bone);
    const auto& rest = cluster.observer.segment;
    const Eigen::Vector3d head_t0 = apply(transforms_t0[b], rest.head);
    const Eigen::Vector3d tail_t0 = apply(transforms_t0[b], rest.tail);
    const Eigen::Vector3d head_t1 = apply(transforms_t1[b], rest.head);
    const Eigen::Vector3d tail_t1 = apply(transforms_t1[b], rest.tail);
    const Eigen::Vector3d axis_t0 = tail_t0 - head_t0;
    const double len2 = axis_t0.squaredNorm();
    for (const auto f : cluster.triangles) {
      ccd::MovingOrientationQuery q;
      q.a_t0 = x_t0.row(F(f, 0)).transpose();
      q.b_t0 = x_t0.row(F(f, 1)).transpose();
      q.c_t0 = x_t0.row(F(f, 2)).transpose();
      q.a_t1 = x_t1.row(F(f, 0)).transpose();
      q.b_t1 = x_t1.row(F(f, 1)).transpose();
      q.c_t1 = x_t1.row(F(f, 2)).transpose();
      // The viewing position: a fixed parameter s of the moving bone segment.
      double s = 0.5;
      if (cluster.observer.kind == ObserverKind::line) {
        s = len2 > 0.0 ? std::clamp((q.a_t0 - head_t0).dot(axis_t0) / len2, 0.0, 1.0) : 0.0;
      }
      q.q_t0 = head_t0 + s * axis_t0;
      q.q_t1 = head_t1 + s * (tail_t1 - head_t1);
      add(counts, static_cast<int>(ccd::moving_orientation_sign(q)));
    }
  }
  return counts;
}

ClipOrientationStats clip_orientation_stats(
    const Segmentation& segmentation, const skinning::Motion& motion) {
  const auto start = std::chrono::steady_clock::now();
  const skinning::Mesh& mesh = motion.mesh();
  const std::string where = "clip '" + motion.name() + "'";
  if (motion.num_bones() <= 0) {
    throw InvalidInput(where + ": clip statistics need a motion with a skeleton");
  }
  if (static_cast<std::int64_t>(segmentation.triangle_cluster.size()) != mesh.num_triangles()) {
    throw InvalidInput(
        where + ": the segmentation has " + std::to_string(segmentation.triangle_cluster.size()) +
        " triangles, the mesh " + std::to_string(mesh.num_triangles()));
  }
  for (const auto& c : segmentation.clusters) {
    if (c.bone < 0 || c.bone >= motion.num_bones()) {
      throw InvalidInput(
          where + ": the segmentation names bone " + std::to_string(c.bone) +
          ", the skeleton has " + std::to_string(motion.num_bones()));
    }
  }
  const auto topology = skinning::build_topology(mesh);
  ClipOrientationStats out;
  out.clip = motion.name();
  const int n = motion.num_samples();
  skinning::Positions file_x, x_t0, x_t1;
  std::vector<skinning::BoneTransform> pose_t0, pose_t1;
  // The pose's skinning transforms at sample i (Motion::bone_transforms: #B bones first).
  const auto sample =
      [&](int i, skinning::Positions& welded, std::vector<skinning::BoneTransform>& pose) {
        motion.positions(i, file_x);
        skinning::gather_welded(topology, file_x, welded);
        motion.bone_transforms(i, pose);
      };
  sample(0, x_t0, pose_t0);
  double sum_minus = 0.0, sum_uncertain = 0.0;
  for (int i = 0; i + 1 < n; ++i) {
    sample(i + 1, x_t1, pose_t1);
    const auto counts = count_orientations_interval(
        segmentation, x_t0, x_t1, topology.welded_triangles, pose_t0, pose_t1);
    sum_minus += static_cast<double>(counts.h_minus);
    sum_uncertain += static_cast<double>(counts.h_uncertain);
    out.max_h_minus = std::max(out.max_h_minus, counts.h_minus);
    out.max_h_uncertain = std::max(out.max_h_uncertain, counts.h_uncertain);
    ++out.intervals;
    std::swap(x_t0, x_t1);
    std::swap(pose_t0, pose_t1);
  }
  if (out.intervals > 0) {
    out.mean_h_minus = sum_minus / out.intervals;
    out.mean_h_uncertain = sum_uncertain / out.intervals;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace skelcd::segmentation
