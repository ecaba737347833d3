// Rigid rows (culling/rigid_rows.hpp, docs/culling.md "Rigid rows") on real rigs: which triangles
// skinning moves by one matrix, when an interval certifies them, and `kdop` skipping their pairs
// with every contact kept.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/elementary.hpp"
#include "culling/method.hpp"
#include "culling/rigid_rows.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

struct Rig {
  skinning::LoadedModel model;
  skinning::Topology topology;
  std::unique_ptr<skinning::Motion> motion;
  std::shared_ptr<const RigidRows> rows;
};

Rig load(const std::filesystem::path& path, const skinning::LoadOptions& options = {}) {
  Rig r{skinning::load_model(path, options), {}, nullptr, nullptr};
  r.topology = skinning::build_topology(*r.model.mesh);
  r.motion = r.model.motion();
  const skinning::SkinWeights* w = r.motion->skin_weights();
  if (w != nullptr) {
    r.rows = std::make_shared<const RigidRows>(
        build_rigid_rows(*r.model.mesh, r.topology, *w, static_cast<std::int32_t>(w->cols())));
  }
  return r;
}

std::vector<std::pair<std::int32_t, double>> weight_row(const skinning::SkinWeights& w, int v) {
  std::vector<std::pair<std::int32_t, double>> row;
  for (skinning::SkinWeights::InnerIterator it(w, v); it; ++it) {
    row.emplace_back(static_cast<std::int32_t>(it.col()), it.value());
  }
  return row;
}

TEST(RigidRows, EachRowIsOneWeightRowAndItsRestPairsLieWithinTheTolerance) {
  const Rig r = load(test::asset("characters/ninja/ninja.mesh"));
  ASSERT_NE(r.rows, nullptr);
  const RigidRows& rows = *r.rows;
  const skinning::SkinWeights& w = *r.motion->skin_weights();
  ASSERT_EQ(
      static_cast<std::int64_t>(rows.triangle_row.size()), r.topology.welded_triangles.rows());
  EXPECT_GT(rows.num_rows(), 1);
  EXPECT_DOUBLE_EQ(rows.rest_tolerance, 1e-6 * rows.rest_extent);
  // Each triangle's weight row when its three (welded) corners share one, and how many share it.
  using Row = std::vector<std::pair<std::int32_t, double>>;
  const auto nf = r.topology.welded_triangles.rows();
  std::vector<std::optional<Row>> one_row(static_cast<std::size_t>(nf));
  std::map<Row, std::int64_t> triangles_of;
  for (Eigen::Index f = 0; f < nf; ++f) {
    std::set<Row> corner_rows;
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v =
          r.topology
              .representative_vertex[static_cast<std::size_t>(r.topology.welded_triangles(f, k))];
      corner_rows.insert(weight_row(w, v));
    }
    const bool repeated = r.topology.welded_triangles(f, 0) == r.topology.welded_triangles(f, 1) ||
                          r.topology.welded_triangles(f, 1) == r.topology.welded_triangles(f, 2) ||
                          r.topology.welded_triangles(f, 0) == r.topology.welded_triangles(f, 2);
    if (corner_rows.size() == 1 && !repeated) {
      one_row[static_cast<std::size_t>(f)] = *corner_rows.begin();
      ++triangles_of[*corner_rows.begin()];
    }
  }
  std::int64_t in_rows = 0;
  for (Eigen::Index f = 0; f < nf; ++f) {
    const std::int32_t row = rows.triangle_row[static_cast<std::size_t>(f)];
    const auto& expected = one_row[static_cast<std::size_t>(f)];
    const bool kept = expected.has_value() && triangles_of[*expected] >= 2;
    EXPECT_EQ(row >= 0, kept) << "triangle " << f;
    if (row >= 0 && kept) {
      EXPECT_EQ(rows.rows[static_cast<std::size_t>(row)], *expected) << "triangle " << f;
      ++in_rows;
    }
  }
  // A row is kept for two triangles or more; every one-row triangle of a kept row has it.
  std::vector<std::int64_t> per_row(static_cast<std::size_t>(rows.num_rows()), 0);
  for (const std::int32_t row : rows.triangle_row) {
    if (row >= 0) ++per_row[static_cast<std::size_t>(row)];
  }
  for (const std::int64_t n : per_row) EXPECT_GE(n, 2);
  EXPECT_EQ(rows.triangles_in_rows, in_rows);
  // Most of the ninja hangs from single bones (docs/benchmarks.md, "Pairs that skinning moves as
  // one"); a few of its shells touch at rest, within one row.
  EXPECT_GT(2 * in_rows, r.topology.welded_triangles.rows());
  ASSERT_FALSE(rows.rest_pairs.empty());
  for (const TrianglePair& p : rows.rest_pairs) {
    EXPECT_LT(p.a, p.b);
    EXPECT_GE(rows.triangle_row[static_cast<std::size_t>(p.a)], 0);
    EXPECT_EQ(
        rows.triangle_row[static_cast<std::size_t>(p.a)],
        rows.triangle_row[static_cast<std::size_t>(p.b)]);
  }
}

/// Every pair of two triangles of one row of `r` with a vertex-face or edge-edge pair sharing no
/// vertex that the conservative kernel, asked on the held rest pose with no box or direction
/// before it, finds within the rows' rest tolerance.
std::vector<TrianglePair> kernel_rest_pairs(const Rig& r) {
  const RigidRows& rows = *r.rows;
  skinning::Positions rest;
  skinning::gather_welded(r.topology, r.model.mesh->rest_positions, rest);
  ccd::CcdOptions within;
  within.min_separation = rows.rest_tolerance;
  const auto corners = [&](std::int32_t f) {
    return std::array<std::int32_t, 3>{
        r.topology.welded_triangles(f, 0),
        r.topology.welded_triangles(f, 1),
        r.topology.welded_triangles(f, 2)};
  };
  const auto kernel_finds = [&](std::int32_t fa, std::int32_t fb) {
    const auto a = corners(fa);
    const auto b = corners(fb);
    const auto in = [](std::int32_t v, const std::array<std::int32_t, 3>& t) {
      return v == t[0] || v == t[1] || v == t[2];
    };
    for (int side = 0; side < 2; ++side) {
      const auto& p = side == 0 ? a : b;
      const auto& q = side == 0 ? b : a;
      for (const std::int32_t v : p) {
        if (in(v, q)) continue;
        const auto query = vertex_face_query(rest, rest, v, rest, rest, q);
        if (ccd::vertex_face_ccd(query, ccd::Accuracy::conservative, within).hit) return true;
      }
    }
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) {
        const std::array<std::int32_t, 2> ea{a[i], a[(i + 1) % 3]};
        const std::array<std::int32_t, 2> eb{b[j], b[(j + 1) % 3]};
        if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) continue;
        const auto query = edge_edge_query(rest, rest, ea, rest, rest, eb);
        if (ccd::edge_edge_ccd(query, ccd::Accuracy::conservative, within).hit) return true;
      }
    }
    return false;
  };
  std::vector<std::vector<std::int32_t>> of_row(static_cast<std::size_t>(rows.num_rows()));
  for (std::size_t f = 0; f < rows.triangle_row.size(); ++f) {
    if (rows.triangle_row[f] >= 0) {
      of_row[static_cast<std::size_t>(rows.triangle_row[f])].push_back(
          static_cast<std::int32_t>(f));
    }
  }
  std::vector<TrianglePair> expected;
  for (const auto& triangles : of_row) {
    for (std::size_t i = 0; i < triangles.size(); ++i) {
      for (std::size_t j = i + 1; j < triangles.size(); ++j) {
        if (kernel_finds(triangles[i], triangles[j]))
          expected.push_back({triangles[i], triangles[j]});
      }
    }
  }
  std::sort(expected.begin(), expected.end());
  return expected;
}

TEST(RigidRows, TheRestPairsAreThePairsOfARowThatTheKernelFindsWithinTheTolerance) {
  // By definition (rigid_rows.hpp): build_rigid_rows' sweep, its boxes and its separating
  // directions may drop only pairs the kernel would have dropped. The ninja's shells touch at
  // rest within a row; gen:cloth is one flat sheet, whose neighbours in a row pass the boxes and
  // are settled by the directions in the sheet's plane (the kernel's slowest, nearly coplanar,
  // queries).
  const Rig ninja = load(test::asset("characters/ninja/ninja.mesh"));
  ASSERT_NE(ninja.rows, nullptr);
  ASSERT_TRUE(ninja.model.mesh->excluded_part_pairs.empty());  // else those pairs are never kept
  const auto expected = kernel_rest_pairs(ninja);
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(ninja.rows->rest_pairs, expected);
  const Rig cloth = load("gen:cloth?triangles=1200&frames=4");
  ASSERT_NE(cloth.rows, nullptr);
  ASSERT_GT(cloth.rows->triangles_in_rows, 600);
  EXPECT_EQ(cloth.rows->rest_pairs, kernel_rest_pairs(cloth));
}

TEST(RigidRows, ARowsPairWithinTheToleranceInItsPlaneIsKept) {
  // Two coplanar triangles of one row (all corners on one bone): b's corner c lies at a distance
  // d from a's side along y = x, in their common plane, and their boxes overlap, so only the
  // directions in that plane could settle the pair. Kept at d = tolerance / 2 (the kernel finds
  // it within), dropped at 3 and 100 times the tolerance.
  for (const double factor : {0.5, 3.0, 100.0}) {
    SCOPED_TRACE(factor);
    const double tolerance = 1e-6 * 5.0;  // rest_tolerance: 1e-6 of the largest coordinate, 5
    const double h = factor * tolerance / std::numbers::sqrt2;
    skinning::Positions x(6, 3);
    x << 0, 0, 0, 4, 4, 0, -4, 4, 0,         // a, above y = x
        2 + h, 2 - h, 0, 5, 1, 0, 3, -1, 0;  // b, below it
    skinning::Triangles f(2, 3);
    f << 0, 1, 2, 3, 4, 5;
    const skinning::Mesh mesh = test::single_part_mesh(std::move(x), std::move(f));
    const skinning::Topology topology = skinning::build_topology(mesh);
    skinning::SkinWeights weights(6, 1);
    for (int v = 0; v < 6; ++v) weights.insert(v, 0) = 1.0;
    const RigidRows rows = build_rigid_rows(mesh, topology, weights, 1);
    ASSERT_EQ(rows.num_rows(), 1);
    EXPECT_DOUBLE_EQ(rows.rest_tolerance, tolerance);
    EXPECT_EQ(rows.rest_pairs.size(), factor < 1.0 ? 1u : 0u);
  }
}

TEST(RigidRows, AnIntervalCertifiesARowOnlyWhileItsBlendStaysFarFromSingular) {
  const Rig r = load(test::asset("characters/ninja/ninja.mesh"));
  ASSERT_NE(r.rows, nullptr);
  const RigidRows& rows = *r.rows;
  std::vector<skinning::BoneTransform> t0;
  r.motion->bone_transforms(0, t0);
  ASSERT_GE(static_cast<std::int32_t>(t0.size()), rows.num_transforms);
  std::vector<std::uint8_t> certified;
  const auto count = [&] {
    std::int32_t n = 0;
    for (const std::uint8_t c : certified) n += c;
    return n;
  };
  // Held still: every row.
  certify_rigid_rows(rows, t0, t0, 0.0, certified);
  ASSERT_EQ(static_cast<std::int32_t>(certified.size()), rows.num_rows());
  EXPECT_EQ(count(), rows.num_rows());
  // A turn of 50 degrees about any axis, with a translation: still every row; 60: none (the
  // bound asks ‖R − I‖₂ = 2 sin(θ/2) < 0.9).
  const auto turned = [&](double degrees) {
    std::vector<skinning::BoneTransform> t1 = t0;
    const Eigen::Matrix3d q =
        Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Eigen::Vector3d(1, 2, 3).normalized())
            .toRotationMatrix();
    for (auto& t : t1) {
      t.leftCols<3>() = q * t.leftCols<3>();
      t.col(3) = q * t.col(3) + Eigen::Vector3d(0.5, -2.0, 1.0);
    }
    return t1;
  };
  certify_rigid_rows(rows, t0, turned(50.0), 0.0, certified);
  EXPECT_EQ(count(), rows.num_rows());
  certify_rigid_rows(rows, t0, turned(60.0), 0.0, certified);
  EXPECT_EQ(count(), 0);
  // Half a turn passes a blend that flattens the mesh: no row.
  certify_rigid_rows(rows, t0, turned(180.0), 0.0, certified);
  EXPECT_EQ(count(), 0);
  // Collapsed to a point at the end, or not finite: no row.
  std::vector<skinning::BoneTransform> t1 = t0;
  for (auto& t : t1) t.leftCols<3>().setZero();
  certify_rigid_rows(rows, t0, t1, 0.0, certified);
  EXPECT_EQ(count(), 0);
  t1 = t0;
  for (auto& t : t1) t(0, 0) = std::nan("");
  certify_rigid_rows(rows, t0, t1, 0.0, certified);
  EXPECT_EQ(count(), 0);
  // A contact distance beyond the rest tolerance: no row (pairs farther apart at rest could come
  // within it); no transforms: no row.
  certify_rigid_rows(rows, t0, t0, 10.0 * rows.rest_tolerance, certified);
  EXPECT_EQ(count(), 0);
  certify_rigid_rows(rows, {}, {}, 0.0, certified);
  EXPECT_EQ(count(), 0);
}

struct ClipRun {
  std::vector<std::pair<int, CcdContact>> contacts;  ///< (interval's first sample, contact)
  std::int64_t candidate_pairs = 0;
};

/// `method` over intervals first → last of the rig's clip, bone transforms carried.
ClipRun run(const Rig& r, CullingMethod& method, int first, int last) {
  ClipRun out;
  skinning::Positions file_x, x0, x1;
  std::vector<skinning::BoneTransform> b0, b1;
  r.motion->positions(first, file_x);
  skinning::gather_welded(r.topology, file_x, x0);
  r.motion->bone_transforms(first, b0);
  for (int s = first; s < last; ++s) {
    r.motion->positions(s + 1, file_x);
    skinning::gather_welded(r.topology, file_x, x1);
    r.motion->bone_transforms(s + 1, b1);
    FrameResult result;
    method.detect_ccd(
        Interval{
            .x_t0 = x0,
            .x_t1 = x1,
            .bones_t0 = b0,
            .bones_t1 = b1,
            .sample_t0 = s,
            .sample_t1 = s + 1},
        result);
    for (const CcdContact& c : result.contacts) out.contacts.emplace_back(s, c);
    out.candidate_pairs += result.counters.candidate_pairs;
    std::swap(x0, x1);
    std::swap(b0, b1);
  }
  return out;
}

struct Case {
  std::filesystem::path path;
  int first;
  int last;
};

TEST(RigidRows, KdopSkipsThePairsOfACertifiedRowAndKeepsEveryContact) {
  // The ninja's clip (its shells touch at rest within one row: the rest pairs carry those
  // contacts), a stretch of the robot's dance and of Testwuson's walk.
  const std::vector<Case> cases = {
      {test::asset("characters/ninja/ninja.mesh"), 0, 30},
      {test::asset("characters/RobotExpressive.glb"), 20, 32},
      {test::assimp_model("X/Testwuson.X"), 0, 10},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.path.string());
    const Rig r = load(c.path);
    ASSERT_NE(r.rows, nullptr);
    ASSERT_GE(r.motion->num_samples(), c.last + 1);
    MethodOptions with;
    with.rigid_rows = r.rows;
    auto kdop = make_method("kdop", *r.model.mesh, r.topology, {});
    auto kdop_rows = make_method("kdop", *r.model.mesh, r.topology, with);
    auto bvh_rows = make_method("bvh", *r.model.mesh, r.topology, with);  // `bvh` takes none
    const ClipRun plain = run(r, *kdop, c.first, c.last);
    const ClipRun skipped = run(r, *kdop_rows, c.first, c.last);
    const ClipRun baseline = run(r, *bvh_rows, c.first, c.last);
    ASSERT_FALSE(plain.contacts.empty());
    EXPECT_EQ(skipped.contacts, plain.contacts);
    EXPECT_EQ(baseline.contacts, plain.contacts);
    // Fewer pairs reach the feature stage: a quarter fewer at least on these rigs (Testwuson 32 %,
    // the robot and the ninja more).
    EXPECT_LT(4 * skipped.candidate_pairs, 3 * plain.candidate_pairs);
  }
}

TEST(RigidRows, WithoutItsRestPairsTheNinjaWouldLoseContacts) {
  // The rest pairs are what keeps the contacts of shells that touch at rest within one row: the
  // same skip without them loses some (so the test above could fail).
  const Rig r = load(test::asset("characters/ninja/ninja.mesh"));
  ASSERT_NE(r.rows, nullptr);
  auto rows = std::make_shared<RigidRows>(*r.rows);
  rows->rest_pairs.clear();
  MethodOptions with;
  with.rigid_rows = rows;
  auto kdop = make_method("kdop", *r.model.mesh, r.topology, {});
  auto kdop_rows = make_method("kdop", *r.model.mesh, r.topology, with);
  EXPECT_LT(run(r, *kdop_rows, 0, 30).contacts.size(), run(r, *kdop, 0, 30).contacts.size());
}

TEST(RigidRows, TheExactContactsAreBruteForcesOnTheNinja) {
  const Rig r = load(test::asset("characters/ninja/ninja.mesh"));
  MethodOptions exact;
  exact.accuracy = ccd::Accuracy::exact;
  MethodOptions exact_rows = exact;
  exact_rows.rigid_rows = r.rows;
  auto brute = make_method("brute", *r.model.mesh, r.topology, exact);
  auto kdop_rows = make_method("kdop", *r.model.mesh, r.topology, exact_rows);
  const ClipRun reference = run(r, *brute, 10, 16);
  ASSERT_FALSE(reference.contacts.empty());
  EXPECT_EQ(run(r, *kdop_rows, 10, 16).contacts, reference.contacts);
}

TEST(RigidRows, ARobotsLinksAreRowsWithoutRestPairs) {
  // The Panda's weights are one-hot, a link each: every triangle of a link of two triangles or more
  // has a row, and a link is excluded against itself (docs/robots.md), so no rest pair is sought.
  skinning::LoadOptions options;
  options.trajectory = test::asset("trajectories/panda_reach.csv");
  const Rig r = load(
      test::asset("robots/example-robot-data/robots/panda_description/urdf/panda.urdf"), options);
  ASSERT_NE(r.rows, nullptr);
  EXPECT_GT(r.rows->num_rows(), 5);
  EXPECT_GT(10 * r.rows->triangles_in_rows, 9 * r.topology.welded_triangles.rows());
  EXPECT_TRUE(r.rows->rest_pairs.empty());
  MethodOptions with;
  with.rigid_rows = r.rows;
  auto kdop = make_method("kdop", *r.model.mesh, r.topology, {});
  auto kdop_rows = make_method("kdop", *r.model.mesh, r.topology, with);
  const int last = r.motion->num_samples() - 1;
  const ClipRun plain = run(r, *kdop, 0, last);
  ASSERT_FALSE(plain.contacts.empty());
  EXPECT_EQ(run(r, *kdop_rows, 0, last).contacts, plain.contacts);
}

TEST(RigidRows, AFrameSequenceHasNoWeights) {
  // A motion that is not linear blend skinning has no skin weights: nothing to build rows from.
  const auto model = skinning::load_model(test::asset("cloth-funnel/frames"));
  EXPECT_EQ(model.motion()->skin_weights(), nullptr);
}

}  // namespace
}  // namespace skelcd::culling
