// Bone heat weights: invariants (non-negative, rows sum to 1), segments landing on their own
// bone, visibility, fall-backs, determinism, both distance modes, and bad input.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "segmentation/heat_weights.hpp"
#include "segmentation/voxel_occupancy.hpp"
#include "skinning/errors.hpp"
#include "tests/segmentation/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace {

using namespace skelcd::segmentation;
using skelcd::test::MeshData;

std::vector<BoneSegment> chain_bones(int n, double length = 1.0) {
  std::vector<BoneSegment> bones;
  for (int b = 0; b < n; ++b) {
    bones.push_back({Eigen::Vector3d(b * length, 0, 0), Eigen::Vector3d((b + 1) * length, 0, 0)});
  }
  return bones;
}

void expect_partition_of_unity(const Eigen::MatrixXd& W) {
  ASSERT_GT(W.rows(), 0);
  EXPECT_GE(W.minCoeff(), 0.0);
  const Eigen::VectorXd sums = W.rowwise().sum();
  EXPECT_LT((sums.array() - 1.0).abs().maxCoeff(), 1e-12);
}

// Bone of the largest summed corner weight of triangle f.
int triangle_bone(const Eigen::MatrixXd& W, const skelcd::skinning::Triangles& F, Eigen::Index f) {
  const Eigen::RowVectorXd s = W.row(F(f, 0)) + W.row(F(f, 1)) + W.row(F(f, 2));
  Eigen::Index best = 0;
  s.maxCoeff(&best);
  return static_cast<int>(best);
}

class HeatWeightsModes : public ::testing::TestWithParam<DistanceMode> {};

TEST_P(HeatWeightsModes, CapsuleChainSegmentsLandOnTheirOwnBones) {
  const int n = 5;
  const auto tube = skelcd::test::closed_tube(n, 0.25, n * 6, 16, 0.125);
  HeatWeightsOptions options;
  options.distance = GetParam();
  HeatWeightsSolver solver(tube.V, tube.F, chain_bones(n), options);
  const auto result = solver.solve_all();
  expect_partition_of_unity(result.weights);
  EXPECT_EQ(result.stats.fallback_vertices, 0);
  for (Eigen::Index f = 0; f < tube.F.rows(); ++f) {
    const double cx = (tube.V(tube.F(f, 0), 0) + tube.V(tube.F(f, 1), 0) + tube.V(tube.F(f, 2), 0)) / 3.0;
    const int expected = std::clamp(static_cast<int>(std::floor(cx)), 0, n - 1);
    ASSERT_EQ(triangle_bone(result.weights, tube.F, f), expected) << "triangle " << f << " x " << cx;
  }
  // Mid-bone, the bone's own weight dominates; at a joint the two neighbours
  // share about equally (symmetry of the tube about the joint plane).
  for (Eigen::Index v = 0; v < tube.V.rows(); ++v) {
    const double x = tube.V(v, 0);
    if (std::abs(x - 2.5) < 1e-12) {
      EXPECT_GT(result.weights(v, 2), 0.75) << v;
    }
    if (std::abs(x - 2.0) < 1e-12) {
      EXPECT_NEAR(result.weights(v, 1), result.weights(v, 2), 0.05) << v;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BothModes, HeatWeightsModes,
                         ::testing::Values(DistanceMode::exact, DistanceMode::coarse));

TEST(HeatWeights, SingleBoneGivesWeightOneEverywhere) {
  const auto sphere = skelcd::test::icosphere(2);
  HeatWeightsSolver solver(sphere.V, sphere.F, {{Eigen::Vector3d(-0.3, 0, 0), Eigen::Vector3d(0.3, 0, 0)}});
  const auto result = solver.solve_all();
  EXPECT_TRUE(skelcd::test::expect_matrix_near(
      result.weights, Eigen::MatrixXd::Ones(sphere.V.rows(), 1), 1e-12));
}

TEST(HeatWeights, RawSolutionsSumToOneAcrossBones) {
  // Σ_j p_j = 1 and L 1 = 0, so Σ_j w_j = 1 exactly in exact arithmetic, before any clean-up.
  const auto tube = skelcd::test::closed_tube(4, 0.3, 24, 12, 0.15);
  HeatWeightsSolver solver(tube.V, tube.F, chain_bones(4));
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(tube.V.rows());
  for (int j = 0; j < solver.num_bones(); ++j) sum += solver.solve(j);
  EXPECT_LT((sum.array() - 1.0).abs().maxCoeff(), 1e-9);
}

TEST(HeatWeights, AHiddenNearerBoneIsNotASource) {
  // Tube A (radius 1) around bone A along x; tube B (radius 0.1, longer than A so that the
  // nearest points of bone B are inside its tube, not on its caps) holds bone B just outside A,
  // 0.3 from A's surface. A's vertices facing B are nearer to bone B than to bone A, but the
  // segment to bone B crosses tube B's wall: exact visibility keeps them on A.
  const auto a = skelcd::test::closed_tube(2.0, 1.0, 8, 24, 0.5);
  const auto b = skelcd::test::closed_tube(4.0, 0.1, 16, 8, 0.05, Eigen::Vector3d(-1, 1.4, 0));
  const auto both = skelcd::test::concat(a, b);
  const std::vector<BoneSegment> bones = {
      {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0)},
      {Eigen::Vector3d(-1, 1.4, 0), Eigen::Vector3d(3, 1.4, 0)}};
  const auto sources = nearest_visible_bones(both.V, both.F, bones);
  int hidden_checked = 0;
  for (Eigen::Index v = 0; v < a.V.rows(); ++v) {
    const Eigen::Vector3d x = both.V.row(v).transpose();
    const double da = (bones[0].closest_point(x) - x).norm();
    const double db = (bones[1].closest_point(x) - x).norm();
    const auto begin = sources.offsets[static_cast<std::size_t>(v)];
    ASSERT_EQ(sources.offsets[static_cast<std::size_t>(v) + 1] - begin, 1);
    EXPECT_EQ(sources.bones[static_cast<std::size_t>(begin)], 0) << v;
    if (db < da) {
      ++hidden_checked;
      EXPECT_NEAR(sources.distance[v], da, 1e-12);
    }
  }
  EXPECT_GT(hidden_checked, 0);  // the configuration does test what it claims
  EXPECT_EQ(sources.fallback_vertices, 0);
}

TEST(HeatWeights, TiesShareTheSource) {
  // A vertex exactly halfway between two parallel bones inside one sphere: both are sources.
  const auto sphere = skelcd::test::icosphere(2, 1.0);
  const std::vector<BoneSegment> bones = {
      {Eigen::Vector3d(0, 0, -0.5), Eigen::Vector3d(0, 0, 0.5)},   // not tied for most
      {Eigen::Vector3d(0.3, -0.2, 0), Eigen::Vector3d(0.3, 0.2, 0)}};
  const auto sources = nearest_visible_bones(sphere.V, sphere.F, bones);
  for (Eigen::Index v = 0; v < sphere.V.rows(); ++v) {
    const Eigen::Vector3d x = sphere.V.row(v).transpose();
    const double d0 = (bones[0].closest_point(x) - x).norm();
    const double d1 = (bones[1].closest_point(x) - x).norm();
    const auto count = sources.offsets[static_cast<std::size_t>(v) + 1] -
                       sources.offsets[static_cast<std::size_t>(v)];
    if (std::abs(d0 - d1) <= 1e-6 * std::min(d0, d1)) {
      EXPECT_EQ(count, 2) << v;
    } else if (std::abs(d0 - d1) > 1e-3 * std::min(d0, d1)) {
      EXPECT_EQ(count, 1) << v;
    }
  }
}

TEST(HeatWeights, VerticesThatSeeNoBoneFallBackAndAreCounted) {
  // One bone far outside a sphere: the far side cannot see it, the near side can.
  const auto sphere = skelcd::test::icosphere(2, 1.0);
  const std::vector<BoneSegment> bones = {{Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(6, 0, 0)}};
  HeatWeightsSolver solver(sphere.V, sphere.F, bones);
  const auto result = solver.solve_all();
  EXPECT_GT(result.stats.fallback_vertices, 0);
  EXPECT_LT(result.stats.fallback_vertices, sphere.V.rows());
  expect_partition_of_unity(result.weights);
  // Coarse mode: the segment leaves the body through outside cells for every vertex.
  HeatWeightsOptions coarse;
  coarse.distance = DistanceMode::coarse;
  HeatWeightsSolver coarse_solver(sphere.V, sphere.F, bones, coarse);
  EXPECT_EQ(coarse_solver.solve_all().stats.fallback_vertices, sphere.V.rows());
}

TEST(HeatWeights, ZeroLengthBoneAndVertexOnABone) {
  const auto tube = skelcd::test::closed_tube(2, 0.25, 12, 8, 0.125);
  std::vector<BoneSegment> bones = chain_bones(2);
  bones.push_back({Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0)});  // zero length
  // A bone through a vertex of the mesh (d = 0 there: clamped, finite).
  bones.push_back({tube.V.row(3).transpose(), tube.V.row(3).transpose() + Eigen::Vector3d(0.1, 0, 0)});
  HeatWeightsSolver solver(tube.V, tube.F, bones);
  const auto result = solver.solve_all();
  ASSERT_TRUE(result.weights.allFinite());
  expect_partition_of_unity(result.weights);
  EXPECT_GT(result.weights(3, 3), 0.99);
}

TEST(HeatWeights, DegenerateTrianglesAndIsolatedVertices) {
  auto tube = skelcd::test::closed_tube(2, 0.25, 12, 8, 0.125);
  const auto extra = skelcd::test::from_lists({{0.5, 0, 0}, {0.6, 0, 0}, {0.7, 0, 0}, {1.5, 0.1, 0}},
                                              {{0, 1, 2}});
  const auto mesh = skelcd::test::concat(tube, extra);
  HeatWeightsSolver solver(mesh.V, mesh.F, chain_bones(2));
  const auto result = solver.solve_all();
  EXPECT_EQ(result.stats.degenerate_triangles, 1);
  EXPECT_EQ(result.stats.isolated_vertices, 4);
  expect_partition_of_unity(result.weights);
  // An isolated vertex takes its heat source directly: (1.5, 0.1, 0) is on bone 1's side.
  EXPECT_EQ(result.weights(mesh.V.rows() - 1, 1), 1.0);
}

TEST(HeatWeights, ParallelAndSerialAreIdentical) {
  const auto tube = skelcd::test::closed_tube(6, 0.3, 60, 24, 0.15);
  HeatWeightsOptions serial;
  serial.parallel = false;
  HeatWeightsOptions parallel;
  const auto a = HeatWeightsSolver(tube.V, tube.F, chain_bones(6), serial).solve_all();
  const auto b = HeatWeightsSolver(tube.V, tube.F, chain_bones(6), parallel).solve_all();
  EXPECT_EQ((a.weights - b.weights).cwiseAbs().maxCoeff(), 0.0);
}

TEST(HeatWeights, BadInputIsRefused) {
  const auto tube = skelcd::test::closed_tube(2, 0.25, 12, 8, 0.125);
  EXPECT_THROW_MESSAGE(HeatWeightsSolver(tube.V, tube.F, {}), skelcd::InvalidInput, "no bones");
  EXPECT_THROW_MESSAGE(HeatWeightsSolver(tube.V, skelcd::skinning::Triangles(0, 3), chain_bones(2)),
                       skelcd::InvalidInput, "no triangles");
  std::vector<BoneSegment> nan_bone = chain_bones(2);
  nan_bone[1].tail.x() = std::nan("");
  EXPECT_THROW_MESSAGE(HeatWeightsSolver(tube.V, tube.F, nan_bone), skelcd::InvalidInput, "bone 1");
  HeatWeightsOptions bad;
  bad.grid_resolution = 0;
  EXPECT_THROW(HeatWeightsSolver(tube.V, tube.F, chain_bones(2), bad), skelcd::InvalidInput);
}

}  // namespace

namespace {

TEST(HeatWeights, OneShotOnARigGivesFileVertexRows) {
  auto rig = skelcd::test::capsule_chain(3);
  HeatWeightsSolver solver(rig.mesh.rest_positions, rig.mesh.triangles, bone_segments(rig.skeleton));
  const auto welded = solver.solve_all().weights;
  // A seam: the first ring's vertices duplicated, and the odd triangles using the copies.
  const auto nv = rig.mesh.num_vertices();
  const int sides = 16;
  rig.mesh.rest_positions.conservativeResize(nv + sides, 3);
  for (int k = 0; k < sides; ++k) {
    rig.mesh.rest_positions.row(nv + k) = rig.mesh.rest_positions.row(k);
    rig.mesh.vertex_part.push_back(0);
    rig.mesh.vertex_index_in_part.push_back(static_cast<std::int32_t>(nv + k));
  }
  for (Eigen::Index f = 1; f < rig.mesh.num_triangles(); f += 2) {
    for (int c = 0; c < 3; ++c) {
      if (rig.mesh.triangles(f, c) < sides) rig.mesh.triangles(f, c) += static_cast<std::int32_t>(nv);
    }
  }
  rig.weights.conservativeResize(nv + sides, 3);
  for (int k = 0; k < sides; ++k) rig.weights.insert(nv + k, 0) = 1.0;
  const auto result = heat_weights(rig);
  ASSERT_EQ(result.weights.rows(), nv + sides);
  ASSERT_EQ(result.weights.cols(), 3);
  expect_partition_of_unity(result.weights);
  EXPECT_EQ(result.stats.vertices, nv + sides);
  // Welding undoes the seam: the same numbers as on the seamless mesh, copies included.
  EXPECT_TRUE(skelcd::test::expect_matrix_near(result.weights.topRows(nv), welded, 0));
  EXPECT_TRUE(skelcd::test::expect_matrix_near(result.weights.bottomRows(sides), welded.topRows(sides), 0));
  skelcd::skinning::Rig no_bones = rig;
  no_bones.skeleton.bones.clear();
  EXPECT_THROW_MESSAGE(std::ignore = heat_weights(no_bones), skelcd::InvalidInput, "capsule_chain");
}

TEST(VoxelOccupancy, SphereInsideSurfaceOutside) {
  const auto sphere = skelcd::test::icosphere(3, 1.0);
  const VoxelOccupancy field(sphere.V, sphere.F, 20);
  EXPECT_EQ(field.at(Eigen::Vector3d::Zero()), Cell::inside);
  EXPECT_EQ(field.at(Eigen::Vector3d(0.5, 0.2, -0.1)), Cell::inside);
  EXPECT_EQ(field.at(Eigen::Vector3d(1.0, 0, 0)), Cell::surface);  // a vertex of the sphere
  EXPECT_EQ(field.at(Eigen::Vector3d(1.05, 1.05, 0)), Cell::outside);
  EXPECT_EQ(field.at(Eigen::Vector3d(9, 9, 9)), Cell::outside);   // beyond the grid
  EXPECT_NEAR(field.cell_size(), 2.0 / 20, 1e-12);
  EXPECT_GT(field.count(Cell::inside), 0);
  // Segments: centre to centre-ish stays inside; centre to far away leaves the body.
  EXPECT_TRUE(field.segment_inside(Eigen::Vector3d(-0.5, 0, 0), Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_FALSE(field.segment_inside(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 0, 0)));
  // Smoothing keeps a sphere a sphere (Taubin barely shrinks it) and moves nothing in no triangle.
  const auto smoothed = taubin_smooth(sphere.V, sphere.F, 10);
  const Eigen::VectorXd radii = smoothed.rowwise().norm();
  EXPECT_GT(radii.minCoeff(), 0.97);
  EXPECT_LT(radii.maxCoeff(), 1.03);
}

}  // namespace
