#pragma once
// Seeded random CCD queries, mixed random and near-degenerate, for the property test (tests/ccd)
// and the long run (bench/ccd): uniform points; points on a coarse grid (exact coplanarity,
// collinearity, shared positions, zero-length edges); constructed contacts at a random time and
// place (often on an edge or a corner), then nudged by a few ulps or by a relative 1e-k; motion in a
// common plane; and all of it scaled by 10^-6 ... 10^6 and translated by up to 10^6.

#include <array>
#include <cstdint>
#include <random>
#include <string_view>

#include <Eigen/Core>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd::test {

struct RandomQuery {
  bool vertex_face = true;
  /// File order: vf — vertex, corners 0..2; ee — a0, a1, b0, b1; t = 0 then t = 1.
  std::array<Eigen::Vector3d, 8> points;
  std::string_view kind;  ///< which generator made it

  [[nodiscard]] VertexFaceQuery vf() const {
    const auto& p = points;
    return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  }
  [[nodiscard]] EdgeEdgeQuery ee() const {
    const auto& p = points;
    return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  }
};

class RandomQueryGenerator {
 public:
  explicit RandomQueryGenerator(std::uint64_t seed) : rng_(seed) {}
  /// The next query of the mix.
  [[nodiscard]] RandomQuery next();
  /// Uniform points in [-1, 1]^3 only (the "random" benchmark set).
  [[nodiscard]] RandomQuery next_uniform();

 private:
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  Eigen::Vector3d point(double r) { return {uniform(-r, r), uniform(-r, r), uniform(-r, r)}; }
  RandomQuery uniform_query();
  RandomQuery grid_query();
  RandomQuery contact_query(bool nudge_ulps);
  RandomQuery coplanar_query();
  void scale_and_translate(RandomQuery& q);

  std::mt19937_64 rng_;
};

}  // namespace skelcd::ccd::test
