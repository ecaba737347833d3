#pragma once
// Families of hard CCD queries with answers known by construction (the "Hard cases"):
// coplanar motion, parallel / collinear / overlapping edges, zero-length edges, zero-area triangles,
// contact exactly at t = 0 and t = 1, a vertex sliding along an edge or passing a corner, near
// misses at relative separations 1e-8 ... 1e-15 on both sides, scaled by 2^-20, 2^20, 1e-6, 1e6,
// translated by 1e6, and points that do not move. Shared by tests/ccd and bench/ccd.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gmpxx.h>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd::test {

struct HardCase {
  std::string family;  ///< e.g. "vf/edge-touch"
  std::string variant; ///< what was done to it (offset, transform), for failure messages
  bool vertex_face = true;
  /// The 8 points in the file order (vf: vertex, corners 0..2; ee: a0, a1, b0, b1; t = 0 then t = 1).
  std::array<Eigen::Vector3d, 8> points;
  /// Known answer, when every coordinate of the construction is exact in double (transforms that
  /// round drop it; the exact reference is then the judge).
  std::optional<bool> analytic_hit;
  /// Earliest contact time when analytic_hit is true and the time is known.
  std::optional<mpq_class> analytic_toi;
  /// The offset d of a near-miss variant (relative to the unit-size canonical frame), if any.
  std::optional<double> separation;

  [[nodiscard]] VertexFaceQuery vf() const;
  [[nodiscard]] EdgeEdgeQuery ee() const;
};

/// Relative separations of the near-miss variants: 1e-8, 1e-9, ..., 1e-15.
[[nodiscard]] std::vector<double> near_miss_separations();

/// Every family, each with its variants (offsets on both sides of contact) under every transform
/// (identity, exact integer affine map, moving frame, scales 2^-20, 2^20, 1e-6, 1e6, translation by
/// 1e6). `random_per_family` extra randomly placed instances per family, from `seed`.
[[nodiscard]] std::vector<HardCase> hard_cases(std::uint64_t seed, int random_per_family);

}  // namespace skelcd::ccd::test
