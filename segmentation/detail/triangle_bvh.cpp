#include "segmentation/detail/triangle_bvh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace skelcd::segmentation::detail {

namespace {
constexpr std::int32_t kLeafSize = 4;
}  // namespace

TriangleBvh::TriangleBvh(const skinning::Positions& V, const skinning::Triangles& F)
    : V_(V), F_(F) {
  const auto num_faces = static_cast<std::int32_t>(F.rows());
  if (num_faces == 0) return;
  order_.resize(static_cast<std::size_t>(num_faces));
  std::vector<Eigen::Vector3d> centroids(static_cast<std::size_t>(num_faces));
  for (std::int32_t f = 0; f < num_faces; ++f) {
    order_[static_cast<std::size_t>(f)] = f;
    centroids[static_cast<std::size_t>(f)] =
        (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))).transpose() / 3.0;
  }
  nodes_.reserve(static_cast<std::size_t>(2 * num_faces / kLeafSize + 2) * 2);
  nodes_.emplace_back();
  build(0, 0, num_faces, centroids);
}

void TriangleBvh::build(std::int32_t node, std::int32_t begin, std::int32_t end,
                        const std::vector<Eigen::Vector3d>& centroids) {
  // Bound the triangles of this node, and their centroids to choose the split axis.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  Eigen::Vector3d clo = lo, chi = hi;
  for (std::int32_t k = begin; k < end; ++k) {
    const auto f = order_[static_cast<std::size_t>(k)];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d p = V_.row(F_(f, c)).transpose();
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    clo = clo.cwiseMin(centroids[static_cast<std::size_t>(f)]);
    chi = chi.cwiseMax(centroids[static_cast<std::size_t>(f)]);
  }
  nodes_[static_cast<std::size_t>(node)].lo = lo;
  nodes_[static_cast<std::size_t>(node)].hi = hi;
  if (end - begin <= kLeafSize) {
    nodes_[static_cast<std::size_t>(node)].first = begin;
    nodes_[static_cast<std::size_t>(node)].count = end - begin;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const std::int32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::int32_t x, std::int32_t y) {
                     const double cx = centroids[static_cast<std::size_t>(x)][axis];
                     const double cy = centroids[static_cast<std::size_t>(y)][axis];
                     return cx < cy || (cx == cy && x < y);
                   });
  const auto left = static_cast<std::int32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[static_cast<std::size_t>(node)].first = left;
  nodes_[static_cast<std::size_t>(node)].count = 0;
  build(left, begin, mid, centroids);
  build(left + 1, mid, end, centroids);
}

bool TriangleBvh::slab_overlap(const Node& n, const Eigen::Vector3d& o,
                               const Eigen::Vector3d& inv_dir) {
  // Parameter range of the segment [0, 1] inside the box; a zero direction component gives
  // ±inf (or NaN when o sits on the slab plane, which the max/min below drop conservatively).
  double t0 = 0.0;
  double t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    double ta = (n.lo[a] - o[a]) * inv_dir[a];
    double tb = (n.hi[a] - o[a]) * inv_dir[a];
    if (std::isnan(ta) || std::isnan(tb)) continue;  // o on a slab plane with zero direction
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

double TriangleBvh::crossing(std::int32_t f, const Eigen::Vector3d& o,
                             const Eigen::Vector3d& dir) const {
  const Eigen::Vector3d a = V_.row(F_(f, 0)).transpose();
  const Eigen::Vector3d e1 = V_.row(F_(f, 1)).transpose() - a;
  const Eigen::Vector3d e2 = V_.row(F_(f, 2)).transpose() - a;
  const Eigen::Vector3d pv = dir.cross(e2);
  const double det = e1.dot(pv);
  if (det == 0.0 || !std::isfinite(det)) return -1.0;  // parallel or degenerate
  const double inv = 1.0 / det;
  const Eigen::Vector3d tv = o - a;
  const double u = tv.dot(pv) * inv;
  if (u < 0.0 || u > 1.0) return -1.0;
  const Eigen::Vector3d qv = tv.cross(e1);
  const double v = dir.dot(qv) * inv;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  const double t = e2.dot(qv) * inv;
  return (t > 0.0 && t < 1.0) ? t : -1.0;
}

bool TriangleBvh::segment_hits(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                               std::int32_t skip_vertex) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d dir = p1 - p0;
  const Eigen::Vector3d inv_dir = dir.cwiseInverse();
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--top])];
    if (!slab_overlap(n, p0, inv_dir)) continue;
    if (n.count > 0) {
      for (std::int32_t k = n.first; k < n.first + n.count; ++k) {
        const auto f = order_[static_cast<std::size_t>(k)];
        if (F_(f, 0) == skip_vertex || F_(f, 1) == skip_vertex || F_(f, 2) == skip_vertex) {
          continue;
        }
        if (crossing(f, p0, dir) > 0.0) return true;
      }
    } else {
      assert(top + 2 <= 128);
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
  }
  return false;
}

}  // namespace skelcd::segmentation::detail
