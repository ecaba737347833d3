// The cotangent Laplacian: hand-computed entries, rows summing to 0, linear precision on flat
// meshes, the Dirichlet energy, and robustness to degenerate and non-manifold input.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "segmentation/laplacian.hpp"
#include "skinning/errors.hpp"
#include "tests/segmentation/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace {

using skelcd::segmentation::cotangent_laplacian;
using skelcd::test::MeshData;

double max_abs_row_sum(const Eigen::SparseMatrix<double>& A) {
  const Eigen::VectorXd sums = A * Eigen::VectorXd::Ones(A.cols());
  return sums.cwiseAbs().maxCoeff();
}

TEST(Laplacian, RightIsoscelesTriangleByHand) {
  // Corner 0 has the right angle (cot 0); corners 1 and 2 have 45° (cot 1).
  const auto m = skelcd::test::from_lists({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const auto lap = cotangent_laplacian(m.V, m.F);
  const Eigen::MatrixXd L(lap.stiffness);
  Eigen::MatrixXd expected(3, 3);
  // Edge (1,2) is opposite the right angle: 0. Edges (0,1), (0,2) are opposite 45°: 1/2.
  expected << -1.0, 0.5, 0.5,  //
      0.5, -0.5, 0.0,          //
      0.5, 0.0, -0.5;
  EXPECT_TRUE(skelcd::test::expect_matrix_near(L, expected, 1e-15));
  EXPECT_TRUE(skelcd::test::expect_matrix_near(lap.mass, Eigen::Vector3d::Constant(0.5 / 3.0),
                                               1e-15));
  EXPECT_TRUE(lap.degenerate_triangles.empty());
}

TEST(Laplacian, RowsSumToZeroOnASphere) {
  const auto m = skelcd::test::icosphere(3);
  const auto lap = cotangent_laplacian(m.V, m.F);
  EXPECT_LT(max_abs_row_sum(lap.stiffness), 1e-12);
  EXPECT_LT(max_abs_row_sum(lap.area_normalised()), 1e-9);
  // Closed sphere of radius 1: lumped areas add up to the polyhedron's area (< 4π, close to it).
  EXPECT_NEAR(lap.mass.sum(), 4.0 * std::numbers::pi, 0.01 * 4.0 * std::numbers::pi);
  EXPECT_LT(lap.mass.sum(), 4.0 * std::numbers::pi);
}

TEST(Laplacian, LinearFunctionsAreHarmonicInsideAFlatMesh) {
  // Linear precision of the cotangent weights: (L f)_i = 0 at interior vertices for linear f,
  // even on an irregular (jittered) grid.
  const int n = 8;
  const auto m = skelcd::test::flat_grid(n, 0.3);
  const auto lap = cotangent_laplacian(m.V, m.F);
  const Eigen::VectorXd f = 2.0 * m.V.col(0) - 3.0 * m.V.col(1) + Eigen::VectorXd::Ones(m.V.rows());
  const Eigen::VectorXd Lf = lap.stiffness * f;
  for (int j = 1; j < n; ++j) {
    for (int i = 1; i < n; ++i) {
      EXPECT_NEAR(Lf[j * (n + 1) + i], 0.0, 1e-12) << i << "," << j;
    }
  }
}

TEST(Laplacian, DirichletEnergyOfXIsTheArea) {
  // −fᵀ L f = ∫ |∇f|² over the mesh; for f = x on a flat mesh, |∇f| = 1: the area, n².
  const int n = 6;
  const auto m = skelcd::test::flat_grid(n, 0.25);
  const auto lap = cotangent_laplacian(m.V, m.F);
  const Eigen::VectorXd f = m.V.col(0);
  EXPECT_NEAR(-f.dot(lap.stiffness * f), n * n, 1e-10);
  EXPECT_NEAR(lap.mass.sum(), n * n, 1e-10);
}

TEST(Laplacian, NegativeIsPositiveSemidefinite) {
  const auto m = skelcd::test::closed_tube(3.0, 0.2, 30, 7, 0.1);  // many obtuse angles
  const auto lap = cotangent_laplacian(m.V, m.F);
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd x(m.V.rows());
    for (auto& v : x) v = g(rng);
    EXPECT_GE(-x.dot(lap.stiffness * x), -1e-10);
  }
}

TEST(Laplacian, DegenerateTrianglesAreSkippedNotNaN) {
  // A sphere plus a zero-area sliver (collinear corners), a repeated-index triangle and an
  // unreferenced vertex.
  auto m = skelcd::test::icosphere(1);
  const auto n = static_cast<std::int32_t>(m.V.rows());
  skelcd::test::MeshData extra = skelcd::test::from_lists(
      {{3, 0, 0}, {4, 0, 0}, {5, 0, 0}, {9, 9, 9}}, {{0, 1, 2}, {0, 0, 1}});
  auto both = skelcd::test::concat(m, extra);
  const auto lap = cotangent_laplacian(both.V, both.F);
  ASSERT_EQ(lap.degenerate_triangles.size(), 2u);
  EXPECT_EQ(lap.degenerate_triangles[0], m.F.rows());
  EXPECT_EQ(lap.degenerate_triangles[1], m.F.rows() + 1);
  EXPECT_TRUE(Eigen::MatrixXd(lap.stiffness).allFinite());
  EXPECT_LT(max_abs_row_sum(lap.stiffness), 1e-12);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(lap.mass[n + k], 0.0);
  EXPECT_LT(max_abs_row_sum(lap.area_normalised()), 1e-9);
}

TEST(Laplacian, NonManifoldEdgeAndTwoComponents) {
  // Three triangles on edge (0,1) — a non-manifold fan — and a separate triangle.
  const auto m = skelcd::test::from_lists(
      {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}, {5, 0, 0}, {6, 0, 0},
       {5, 1, 0}},
      {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {5, 6, 7}});
  const auto lap = cotangent_laplacian(m.V, m.F);
  EXPECT_LT(max_abs_row_sum(lap.stiffness), 1e-12);
  // Edge (0,1) gathers the cotangents of the three opposite corners: each angle at the apex of
  // an isosceles triangle of base 1, height h: cot = (h² − 1/4) / h.
  const double expected = 0.5 * (2.0 * (1.0 - 0.25) / 1.0 + (1.0 - 0.25) / 1.0);
  EXPECT_NEAR(lap.stiffness.coeff(0, 1), expected, 1e-14);
  EXPECT_EQ(lap.stiffness.coeff(0, 5), 0.0);
}

TEST(Laplacian, BadIndexAndNaNAreRefused) {
  auto m = skelcd::test::icosphere(0);
  m.F(3, 1) = 99;
  EXPECT_THROW_MESSAGE(std::ignore = cotangent_laplacian(m.V, m.F), skelcd::InvalidInput,
                       "triangle 3");
  auto n = skelcd::test::icosphere(0);
  n.V(5, 2) = std::nan("");
  EXPECT_THROW_MESSAGE(std::ignore = cotangent_laplacian(n.V, n.F), skelcd::InvalidInput,
                       "vertex 5");
}

}  // namespace
