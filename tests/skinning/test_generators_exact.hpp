#pragma once
// An exact, brute-force DCD reference written for the generator tests, independent of ccd/ and
// culling/: every pair of triangles whose closed bounding boxes overlap is tested with exact
// orientation predicates (a floating-point filter with Shewchuk's static bound, then integer
// arithmetic on the doubles' exact values with GMP). Pairs sharing vertices (welded by exact
// position) intersect only where they overlap beyond the shared vertex or edge.

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::test::exact {

/// Sign of det[b − a, c − a, d − a] (positive when d is above the plane of a, b, c seen with a, b, c
/// counter-clockwise), exact.
[[nodiscard]] int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d);

/// True iff the closed triangles share a point other than through their shared corners:
/// `shared` lists (corner of a, corner of b) pairs that are the same mesh vertex.
[[nodiscard]] bool triangles_intersect(
    const std::array<Eigen::Vector3d, 3>& a,
    const std::array<Eigen::Vector3d, 3>& b,
    const std::vector<std::pair<int, int>>& shared);

struct DcdResult {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;  ///< intersecting triangle pairs (a < b)
  std::int64_t candidates = 0;                               ///< pairs with overlapping boxes
};

/// All intersecting pairs of `triangles` at `positions` (stop after the first when `first_only`),
/// skipping pairs that `skip(fa, fb)` rejects (e.g. excluded parts).
[[nodiscard]] DcdResult self_intersections(
    const skinning::Positions& positions,
    const skinning::Triangles& triangles,
    bool first_only,
    const std::function<bool(std::int32_t, std::int32_t)>& skip = {});

}  // namespace skelcd::test::exact
