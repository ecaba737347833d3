// skinning/mesh_order.hpp: the spatial order a frame sequence is held in. It must be a
// permutation that keeps every element under its file index, refuse what it cannot order, and
// bring back the locality a shuffled file lacks.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "skinning/mesh_order.hpp"

namespace skelcd::skinning {
namespace {

/// A flat n × n grid of vertices, two triangles a cell, in row order.
Mesh grid_sheet(int n) {
  Mesh m;
  m.rest_positions.resize(static_cast<Eigen::Index>(n) * n, 3);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) m.rest_positions.row(j * n + i) << i, j, 0.25 * ((i + j) % 3);
  }
  m.triangles.resize(static_cast<Eigen::Index>(2 * (n - 1) * (n - 1)), 3);
  Eigen::Index f = 0;
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int v = j * n + i;
      m.triangles.row(f++) << v, v + 1, v + n + 1;
      m.triangles.row(f++) << v, v + n + 1, v + n;
    }
  }
  label_one_part_in_file_order(m, "sheet");
  return m;
}

/// The same mesh with its vertices and triangles in a random order (a simulator's file).
Mesh shuffled(const Mesh& m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  MeshPermutation p;
  p.faces.resize(static_cast<std::size_t>(m.num_triangles()));
  p.vertices.resize(static_cast<std::size_t>(m.num_vertices()));
  std::iota(p.faces.begin(), p.faces.end(), 0);
  std::iota(p.vertices.begin(), p.vertices.end(), 0);
  std::shuffle(p.faces.begin(), p.faces.end(), rng);
  std::shuffle(p.vertices.begin(), p.vertices.end(), rng);
  return reordered(m, p);
}

/// The median over the triangles of the distance between their least and greatest corner ids:
/// how far apart in memory one triangle's corners lie.
double median_corner_span(const Triangles& t) {
  std::vector<int> spans;
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    spans.push_back(t.row(f).maxCoeff() - t.row(f).minCoeff());
  std::nth_element(
      spans.begin(), spans.begin() + static_cast<std::ptrdiff_t>(spans.size() / 2), spans.end());
  return spans[spans.size() / 2];
}

/// `p` lists each of 0 … n−1 once.
bool is_permutation_of(const std::vector<std::int32_t>& p, std::size_t n) {
  std::vector<std::int32_t> sorted = p;
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::int32_t> all(n);
  std::iota(all.begin(), all.end(), 0);
  return sorted == all;
}

// Each triangle of the reordered mesh is a triangle of the original one with the same corners in
// the same turn, and each vertex has its coordinates, both found under their file indices.
void expect_same_elements_under_file_indices(const Mesh& original, const Mesh& laid_out) {
  ASSERT_EQ(laid_out.num_triangles(), original.num_triangles());
  ASSERT_EQ(laid_out.num_vertices(), original.num_vertices());
  for (Eigen::Index v = 0; v < laid_out.num_vertices(); ++v) {
    const auto file_v = laid_out.vertex_index_in_part[static_cast<std::size_t>(v)];
    ASSERT_EQ(laid_out.rest_positions.row(v), original.rest_positions.row(file_v)) << v;
    ASSERT_EQ(
        laid_out.vertex_part[static_cast<std::size_t>(v)],
        original.vertex_part[static_cast<std::size_t>(file_v)]);
  }
  for (Eigen::Index f = 0; f < laid_out.num_triangles(); ++f) {
    const auto file_f = laid_out.face_index_in_part[static_cast<std::size_t>(f)];
    ASSERT_EQ(
        laid_out.face_part[static_cast<std::size_t>(f)],
        original.face_part[static_cast<std::size_t>(file_f)]);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(
          laid_out.vertex_index_in_part[static_cast<std::size_t>(laid_out.triangles(f, k))],
          original.triangles(file_f, k))
          << f << " " << k;
    }
  }
}

TEST(MeshOrder, AShuffledSheetGetsItsLocalityBack) {
  const Mesh sheet = grid_sheet(64);
  const Mesh file = shuffled(sheet, 7);
  // The shuffled file: a triangle's corners lie thousands of vertices apart.
  EXPECT_GT(median_corner_span(file.triangles), 500.0);
  const MeshPermutation p = spatial_order(file.rest_positions, file.triangles);
  ASSERT_TRUE(is_permutation_of(p.faces, static_cast<std::size_t>(file.num_triangles())));
  ASSERT_TRUE(is_permutation_of(p.vertices, static_cast<std::size_t>(file.num_vertices())));
  const Mesh laid_out = reordered(file, p);
  // Vertices by first use along the curve: most triangles' corners within a few vertices of each
  // other (7 here), closer than in the row order the grid was made in (a row apart: 65).
  EXPECT_LT(median_corner_span(laid_out.triangles), 16.0);
  EXPECT_EQ(median_corner_span(sheet.triangles), 65.0);
  // Every element kept under the index the file gave it (here: the shuffled order's).
  Mesh file_numbered = file;
  std::iota(file_numbered.face_index_in_part.begin(), file_numbered.face_index_in_part.end(), 0);
  std::iota(
      file_numbered.vertex_index_in_part.begin(), file_numbered.vertex_index_in_part.end(), 0);
  expect_same_elements_under_file_indices(file_numbered, reordered(file_numbered, p));
  // Deterministic: the same input gives the same order.
  const MeshPermutation again = spatial_order(file.rest_positions, file.triangles);
  EXPECT_EQ(again.faces, p.faces);
  EXPECT_EQ(again.vertices, p.vertices);
}

// file_order undoes any order: a mesh in its files' order needs none, a reordered one comes back
// exactly (what the Python Model and `export` show).
TEST(MeshOrder, TheFilesOrderComesBack) {
  const Mesh sheet = grid_sheet(16);
  EXPECT_TRUE(file_order(sheet).faces.empty());
  EXPECT_TRUE(file_order(sheet).vertices.empty());
  const Mesh laid_out = reordered(sheet, spatial_order(sheet.rest_positions, sheet.triangles));
  const MeshPermutation back = file_order(laid_out);
  ASSERT_FALSE(back.faces.empty());
  const Mesh again = reordered(laid_out, back);
  EXPECT_EQ(again.triangles, sheet.triangles);
  EXPECT_EQ(again.rest_positions, sheet.rest_positions);
  EXPECT_EQ(again.face_index_in_part, sheet.face_index_in_part);
  EXPECT_EQ(again.vertex_index_in_part, sheet.vertex_index_in_part);
  EXPECT_EQ(again.face_part, sheet.face_part);
  EXPECT_EQ(again.vertex_part, sheet.vertex_part);
}

// Two parts with their own file indices: a reordered triangle keeps its part and its index in it.
TEST(MeshOrder, PartsAndTheirIndicesMoveWithTheirElements) {
  Mesh m = grid_sheet(8);
  const auto nf = static_cast<std::size_t>(m.num_triangles());
  const auto nv = static_cast<std::size_t>(m.num_vertices());
  m.part_names = {"left", "right"};
  m.excluded_part_pairs = {{0, 1}};
  for (std::size_t f = 0; f < nf; ++f) {
    m.face_part[f] = f < nf / 2 ? 0 : 1;
    m.face_index_in_part[f] = static_cast<std::int32_t>(f < nf / 2 ? f : f - nf / 2);
  }
  for (std::size_t v = 0; v < nv; ++v) {
    m.vertex_part[v] = v < nv / 2 ? 0 : 1;
    m.vertex_index_in_part[v] = static_cast<std::int32_t>(v < nv / 2 ? v : v - nv / 2);
  }
  const MeshPermutation p = spatial_order(m.rest_positions, m.triangles);
  ASSERT_EQ(p.faces.size(), nf);
  const Mesh r = reordered(m, p);
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.excluded_part_pairs, m.excluded_part_pairs);
  for (std::size_t i = 0; i < nf; ++i) {
    const auto old = static_cast<std::size_t>(p.faces[i]);
    EXPECT_EQ(r.face_part[i], m.face_part[old]);
    EXPECT_EQ(r.face_index_in_part[i], m.face_index_in_part[old]);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(
          p.vertices[static_cast<std::size_t>(r.triangles(static_cast<Eigen::Index>(i), k))],
          m.triangles(static_cast<Eigen::Index>(old), k));
    }
  }
  for (std::size_t i = 0; i < nv; ++i) {
    const auto old = static_cast<std::size_t>(p.vertices[i]);
    EXPECT_EQ(r.vertex_part[i], m.vertex_part[old]);
    EXPECT_EQ(r.vertex_index_in_part[i], m.vertex_index_in_part[old]);
  }
}

TEST(MeshOrder, WhatCannotBeOrderedIsLeftAsItIs) {
  Mesh m = grid_sheet(4);
  Positions bad = m.rest_positions;
  bad(5, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(spatial_order(bad, m.triangles).faces.empty());
  bad(5, 1) = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(spatial_order(bad, m.triangles).vertices.empty());
  Triangles out_of_range = m.triangles;
  out_of_range(3, 2) = static_cast<std::int32_t>(m.num_vertices());
  EXPECT_TRUE(spatial_order(m.rest_positions, out_of_range).faces.empty());
  out_of_range(3, 2) = -1;
  EXPECT_TRUE(spatial_order(m.rest_positions, out_of_range).faces.empty());
  // Finite coordinates whose extent a double cannot hold (their difference overflows): that axis
  // counts as one cell, the others still order the triangles.
  Positions huge = m.rest_positions;
  for (Eigen::Index v = 0; v < huge.rows(); ++v) huge(v, 2) = v < 8 ? 1.5e308 : -1.5e308;
  const MeshPermutation wide = spatial_order(huge, m.triangles);
  ASSERT_TRUE(is_permutation_of(wide.faces, static_cast<std::size_t>(m.num_triangles())));
  ASSERT_TRUE(is_permutation_of(wide.vertices, static_cast<std::size_t>(m.num_vertices())));
  // A vertex no triangle uses holds no position that matters: it goes last, in the old order.
  Positions extra(m.num_vertices() + 2, 3);
  extra.topRows(m.num_vertices()) = m.rest_positions;
  extra.row(m.num_vertices()) << std::numeric_limits<double>::quiet_NaN(), 0, 0;
  extra.row(m.num_vertices() + 1) << -100, -100, -100;
  const MeshPermutation p = spatial_order(extra, m.triangles);
  ASSERT_EQ(p.vertices.size(), static_cast<std::size_t>(extra.rows()));
  EXPECT_EQ(p.vertices[p.vertices.size() - 2], m.num_vertices());
  EXPECT_EQ(p.vertices.back(), m.num_vertices() + 1);
}

// All centroids at one point (no extent): one Morton code, so the old order, and the vertices by
// first use in it.
TEST(MeshOrder, NoExtentKeepsTheOldOrder) {
  Positions x = Positions::Zero(4, 3);
  Triangles t(3, 3);
  t << 2, 0, 1, 3, 2, 1, 0, 1, 3;
  const MeshPermutation p = spatial_order(x, t);
  EXPECT_EQ(p.faces, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(p.vertices, (std::vector<std::int32_t>{2, 0, 1, 3}));
}

}  // namespace
}  // namespace skelcd::skinning
