#pragma once
// The triangle-triangle queries of real DCDs: every pair `bvh`'s DCD hands to its triangle test on
// posed frames of a model, with the corners the two triangles share, recorded through a stand-in
// triangle test. For the equivalence test of ccd::triangles_intersect (tests/culling/
// test_triangle_triangle_real.cpp) and its benchmark (bench/ccd/bm_triangle_triangle.cpp).

#include <cstdint>
#include <filesystem>
#include <vector>

#include "ccd/triangle_triangle.hpp"

namespace skelcd::culling::test {

struct RecordedTriangleQuery {
  ccd::TriangleTriangleQuery query;
  ccd::SharedCorners shared = ccd::kNoSharedCorners;
  /// The DCD with ccd::triangles_intersect settles this pair by a certified vertex fan and does
  /// not test it (culling/vertex_fans.hpp); a stand-in test sees every pair.
  bool fan_settled = false;
};

struct RealTriangleQueries {
  std::vector<RecordedTriangleQuery> queries;
  /// tt_tests of the same DCDs run with ccd::triangles_intersect: the queries not fan_settled.
  std::int64_t production_tests = 0;
  std::int64_t intersecting_pairs = 0;
};

/// The queries of `bvh`'s DCD at `samples` samples spread evenly over the model's first clip (or
/// frame sequence), welded positions as the check uses them.
/// @param model a file or frame folder skinning::load_model reads.  @pre samples >= 1.
[[nodiscard]] RealTriangleQueries record_dcd_queries(
    const std::filesystem::path& model, int samples);

}  // namespace skelcd::culling::test
