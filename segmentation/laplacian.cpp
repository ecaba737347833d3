#include "segmentation/laplacian.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::segmentation {

namespace {

// Twice the area below which a triangle's area is rounding noise of the cross product
// (each component of a × b carries an error of a few ε |a| |b|).
constexpr double kDegenerateFactor = 16.0 * std::numeric_limits<double>::epsilon() / 2.0;

}  // namespace

Eigen::SparseMatrix<double> CotangentLaplacian::area_normalised() const {
  Eigen::VectorXd inverse_mass(mass.size());
  for (Eigen::Index i = 0; i < mass.size(); ++i) {
    inverse_mass[i] = mass[i] > 0.0 ? 1.0 / mass[i] : 0.0;
  }
  Eigen::SparseMatrix<double> out = inverse_mass.asDiagonal() * stiffness;
  out.makeCompressed();
  return out;
}

CotangentLaplacian cotangent_laplacian(const skinning::Positions& V, const skinning::Triangles& F) {
  const auto num_vertices = V.rows();
  for (Eigen::Index i = 0; i < num_vertices; ++i) {
    if (!V.row(i).allFinite()) {
      throw InvalidInput("cotangent_laplacian: vertex " + std::to_string(i) +
                         " has a non-finite coordinate");
    }
  }

  CotangentLaplacian out;
  out.mass = Eigen::VectorXd::Zero(num_vertices);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(F.rows()) * 9);

  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const std::int32_t idx[3] = {F(f, 0), F(f, 1), F(f, 2)};
    for (const auto v : idx) {
      if (v < 0 || v >= num_vertices) {
        throw InvalidInput("cotangent_laplacian: triangle " + std::to_string(f) +
                           " has vertex index " + std::to_string(v) + " outside [0, " +
                           std::to_string(num_vertices) + ")");
      }
    }
    if (idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2]) {
      out.degenerate_triangles.push_back(static_cast<std::int32_t>(f));
      continue;
    }
    const Eigen::Vector3d p[3] = {V.row(idx[0]).transpose(), V.row(idx[1]).transpose(),
                                  V.row(idx[2]).transpose()};
    // Edge k is opposite corner k.
    const Eigen::Vector3d e[3] = {p[2] - p[1], p[0] - p[2], p[1] - p[0]};
    const double longest2 =
        std::max({e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()});
    const double double_area = e[1].cross(e[2]).norm();
    if (!(double_area > kDegenerateFactor * longest2)) {
      out.degenerate_triangles.push_back(static_cast<std::int32_t>(f));
      continue;
    }
    // Corner k: angle between the two edges leaving it; cot = cos/sin = (a·b)/|a×b|.
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3;
      const int j = (k + 2) % 3;
      const double cot = -e[i].dot(e[j]) / double_area;
      const double w = 0.5 * cot;  // this triangle's share of edge (i, j)
      triplets.emplace_back(idx[i], idx[j], w);
      triplets.emplace_back(idx[j], idx[i], w);
      triplets.emplace_back(idx[i], idx[i], -w);
      triplets.emplace_back(idx[j], idx[j], -w);
    }
    const double third_area = double_area / 6.0;
    for (const auto v : idx) out.mass[v] += third_area;
  }

  out.stiffness.resize(num_vertices, num_vertices);
  out.stiffness.setFromTriplets(triplets.begin(), triplets.end());
  out.stiffness.makeCompressed();
  return out;
}

}  // namespace skelcd::segmentation
