#include "segmentation/voxel_occupancy.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <deque>
#include <limits>
#include <utility>

namespace skelcd::segmentation {

namespace {

// Separating-axis test of a triangle (corners relative to the box centre) against an axis-aligned
// box of half size `half`: the box normals, the triangle normal and the nine edge cross products
// (Akenine-Möller 2001). Touching counts as overlap.
bool triangle_box_overlap(const std::array<Eigen::Vector3d, 3>& t, const Eigen::Vector3d& half) {
  const auto separated = [&](const Eigen::Vector3d& axis) {
    const double p0 = axis.dot(t[0]);
    const double p1 = axis.dot(t[1]);
    const double p2 = axis.dot(t[2]);
    const double r = half.dot(axis.cwiseAbs());
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
  };
  for (int a = 0; a < 3; ++a) {
    if (separated(Eigen::Vector3d::Unit(a))) return false;
  }
  const std::array<Eigen::Vector3d, 3> edges = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
  if (separated(edges[0].cross(edges[1]))) return false;
  for (int a = 0; a < 3; ++a) {
    for (const auto& e : edges) {
      if (separated(Eigen::Vector3d::Unit(a).cross(e))) return false;
    }
  }
  return true;
}

}  // namespace

VoxelOccupancy::VoxelOccupancy(const skinning::Positions& V, const skinning::Triangles& F,
                               int resolution) {
  assert(resolution >= 1 && F.rows() > 0);
  // Bounding box of the referenced vertices.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      lo = lo.cwiseMin(V.row(F(f, c)).transpose());
      hi = hi.cwiseMax(V.row(F(f, c)).transpose());
    }
  }
  const double longest = (hi - lo).maxCoeff();
  h_ = longest > 0.0 ? longest / resolution : 1.0;
  origin_ = lo - Eigen::Vector3d::Constant(h_);
  for (int a = 0; a < 3; ++a) {
    dims_[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / h_)) + 2;
  }
  cells_.assign(static_cast<std::size_t>(dims_.x()) * static_cast<std::size_t>(dims_.y()) *
                    static_cast<std::size_t>(dims_.z()),
                Cell::inside);

  // Surface: every cell a triangle touches.
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5 * h_);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    std::array<Eigen::Vector3d, 3> p;
    Eigen::Vector3d tlo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d thi = -tlo;
    for (int c = 0; c < 3; ++c) {
      p[static_cast<std::size_t>(c)] = V.row(F(f, c)).transpose();
      tlo = tlo.cwiseMin(p[static_cast<std::size_t>(c)]);
      thi = thi.cwiseMax(p[static_cast<std::size_t>(c)]);
    }
    Eigen::Vector3i clo, chi;
    for (int a = 0; a < 3; ++a) {
      // The cells holding the triangle's box (a triangle that only touches a neighbouring cell's
      // face need not mark it: the cells it lies in already seal the surface).
      clo[a] = std::clamp(static_cast<int>(std::floor((tlo[a] - origin_[a]) / h_)), 0,
                          dims_[a] - 1);
      chi[a] = std::clamp(static_cast<int>(std::floor((thi[a] - origin_[a]) / h_)), 0,
                          dims_[a] - 1);
    }
    for (int z = clo.z(); z <= chi.z(); ++z) {
      for (int y = clo.y(); y <= chi.y(); ++y) {
        for (int x = clo.x(); x <= chi.x(); ++x) {
          const Eigen::Vector3d centre =
              origin_ + h_ * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
          const std::array<Eigen::Vector3d, 3> rel = {p[0] - centre, p[1] - centre,
                                                      p[2] - centre};
          if (triangle_box_overlap(rel, half)) {
            cells_[static_cast<std::size_t>(index(x, y, z))] = Cell::surface;
          }
        }
      }
    }
  }

  // Outside: flood fill (6-connected) from every non-surface cell of the grid's border.
  std::deque<std::array<int, 3>> queue;
  const auto seed = [&](int x, int y, int z) {
    auto& cell = cells_[static_cast<std::size_t>(index(x, y, z))];
    if (cell == Cell::inside) {
      cell = Cell::outside;
      queue.push_back({x, y, z});
    }
  };
  for (int z = 0; z < dims_.z(); ++z) {
    for (int y = 0; y < dims_.y(); ++y) {
      for (int x = 0; x < dims_.x(); ++x) {
        if (x == 0 || y == 0 || z == 0 || x == dims_.x() - 1 || y == dims_.y() - 1 ||
            z == dims_.z() - 1) {
          seed(x, y, z);
        }
      }
    }
  }
  constexpr int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!queue.empty()) {
    const auto c = queue.front();
    queue.pop_front();
    for (const auto& s : kSteps) {
      const int x = c[0] + s[0], y = c[1] + s[1], z = c[2] + s[2];
      if (x < 0 || y < 0 || z < 0 || x >= dims_.x() || y >= dims_.y() || z >= dims_.z()) continue;
      seed(x, y, z);
    }
  }
}

Cell VoxelOccupancy::at(const Eigen::Vector3d& p) const {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) {
    const double u = std::floor((p[a] - origin_[a]) / h_);
    if (!(u >= 0.0 && u < dims_[a])) return Cell::outside;
    c[a] = static_cast<int>(u);
  }
  return cells_[static_cast<std::size_t>(index(c.x(), c.y(), c.z()))];
}

bool VoxelOccupancy::segment_inside(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  const double length = (b - a).norm();
  const auto steps = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(2.0 * length / h_)));
  for (std::int64_t k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / static_cast<double>(steps);
    if (at(a + t * (b - a)) == Cell::outside) return false;
  }
  return true;
}

std::int64_t VoxelOccupancy::count(Cell kind) const {
  return std::count(cells_.begin(), cells_.end(), kind);
}

skinning::Positions taubin_smooth(const skinning::Positions& V, const skinning::Triangles& F,
                                  int iterations) {
  // Unique undirected edges → CSR neighbour lists.
  const auto n = static_cast<std::size_t>(V.rows());
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  edges.reserve(static_cast<std::size_t>(F.rows()) * 6);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto a = F(f, k), b = F(f, (k + 1) % 3);
      if (a == b) continue;
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<std::size_t> offsets(n + 1, 0);
  for (const auto& e : edges) ++offsets[static_cast<std::size_t>(e.first) + 1];
  for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];

  skinning::Positions x = V;
  skinning::Positions next = V;
  const auto step = [&](double factor) {
    for (std::size_t i = 0; i < n; ++i) {
      const auto begin = offsets[i], end = offsets[i + 1];
      if (begin == end) continue;
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      for (auto k = begin; k < end; ++k) mean += x.row(edges[k].second);
      mean /= static_cast<double>(end - begin);
      next.row(static_cast<Eigen::Index>(i)) =
          x.row(static_cast<Eigen::Index>(i)) + factor * (mean - x.row(static_cast<Eigen::Index>(i)));
    }
    std::swap(x, next);
  };
  for (int it = 0; it < iterations; ++it) {
    step(0.5);
    step(-0.53);
  }
  return x;
}

}  // namespace skelcd::segmentation
