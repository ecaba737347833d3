#pragma once
// The conservative CCD root finder over (t, u, v) (docs/ccd.md, "The conservative solver").
//
// Both queries reduce to: is there (t, u, v) in [0,1]^3 (vertex-face: with u + v <= 1) with
//   F(t, u, v) = (1 - t) (D0 + u E0 + v G0) + t (D1 + u E1 + v G1)
// within min_separation of 0? Vertex-face: D = p - a, E = a - b, G = a - c (F = p - point of the
// triangle); edge-edge: D = a0 - b0, E = a1 - a0, G = b0 - b1 (F = point of a - point of b). Each
// component of F is multilinear in (t, u, v), so over a box its range is spanned by its values at
// the 8 corners; those are computed with a proven error bound, boxes that provably stay away are
// dropped, the rest are bisected.

#include <cstdint>

#include <Eigen/Core>

#include "ccd/ccd_types.hpp"

namespace skelcd::ccd::detail {

struct InclusionProblem {
  /// Difference vectors at t = 0 and t = 1, each coordinate one floating-point subtraction of two
  /// input coordinates (or its exact negation).
  Eigen::Vector3d d_t0, e_t0, g_t0, d_t1, e_t1, g_t1;
  /// Vertex-face: only boxes meeting u + v <= 1 count.
  bool triangle_domain = false;
  /// Search t in [t_begin, 1] only (a caller that has excluded [0, t_begin) already).
  double t_begin = 0.0;
};

struct InclusionResult {
  bool hit = false;
  double toi_lower = 1.0;
  double toi_upper = 1.0;
  CcdStatus status = CcdStatus::separated;
  std::int64_t boxes = 0;
};

/// Earliest (t, u, v) box that cannot be proven separated. hit == false implies
/// |F(t, u, v)| > min_separation everywhere on the domain (never wrong for finite input).
/// @note No allocation, no throw.
[[nodiscard]] InclusionResult solve_inclusion(const InclusionProblem& problem, const CcdOptions& options);

}  // namespace skelcd::ccd::detail
