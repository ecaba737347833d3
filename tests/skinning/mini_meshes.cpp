#include "tests/skinning/mini_meshes.hpp"

#include <array>

namespace skelcd::skinning::test {

Mesh make_mesh(
    const std::vector<Eigen::Vector3d>& positions,
    const std::vector<std::array<std::int32_t, 3>>& triangles,
    const std::string& name) {
  Mesh m;
  const auto nv = static_cast<Eigen::Index>(positions.size());
  const auto nf = static_cast<Eigen::Index>(triangles.size());
  m.rest_positions.resize(nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) m.rest_positions.row(v) = positions[static_cast<std::size_t>(v)];
  m.triangles.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) m.triangles(f, k) = triangles[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
  }
  m.face_part.assign(static_cast<std::size_t>(nf), 0);
  m.face_index_in_part.resize(static_cast<std::size_t>(nf));
  for (std::size_t f = 0; f < m.face_index_in_part.size(); ++f) m.face_index_in_part[f] = static_cast<std::int32_t>(f);
  m.vertex_part.assign(static_cast<std::size_t>(nv), 0);
  m.vertex_index_in_part.resize(static_cast<std::size_t>(nv));
  for (std::size_t v = 0; v < m.vertex_index_in_part.size(); ++v) m.vertex_index_in_part[v] = static_cast<std::int32_t>(v);
  m.part_names = {name};
  return m;
}

void append_part(Mesh& a, const Mesh& b) {
  const auto v0 = a.num_vertices();
  const auto f0 = a.num_triangles();
  const auto part = a.num_parts();
  Positions p(v0 + b.num_vertices(), 3);
  p << a.rest_positions, b.rest_positions;
  a.rest_positions = p;
  Triangles t(f0 + b.num_triangles(), 3);
  t << a.triangles, (b.triangles.array() + static_cast<std::int32_t>(v0)).matrix();
  a.triangles = t;
  for (std::size_t f = 0; f < b.face_part.size(); ++f) {
    a.face_part.push_back(part + b.face_part[f]);
    a.face_index_in_part.push_back(b.face_index_in_part[f]);
  }
  for (std::size_t v = 0; v < b.vertex_part.size(); ++v) {
    a.vertex_part.push_back(part + b.vertex_part[v]);
    a.vertex_index_in_part.push_back(b.vertex_index_in_part[v]);
  }
  a.part_names.insert(a.part_names.end(), b.part_names.begin(), b.part_names.end());
}

namespace {
// Corner c of the unit cube: bit 0 → x, bit 1 → y, bit 2 → z.
Eigen::Vector3d corner(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }
// The six faces as corner quads, counter-clockwise seen from outside.
constexpr std::array<std::array<int, 4>, 6> kQuads{{
    {0, 2, 3, 1},  // z = 0
    {4, 5, 7, 6},  // z = 1
    {0, 1, 5, 4},  // y = 0
    {2, 6, 7, 3},  // y = 1
    {0, 4, 6, 2},  // x = 0
    {1, 3, 7, 5},  // x = 1
}};
}  // namespace

Mesh shared_cube() {
  std::vector<Eigen::Vector3d> p;
  for (int c = 0; c < 8; ++c) p.push_back(corner(c));
  std::vector<std::array<std::int32_t, 3>> t;
  for (const auto& q : kQuads) {
    t.push_back({q[0], q[1], q[2]});
    t.push_back({q[0], q[2], q[3]});
  }
  return make_mesh(p, t, "cube");
}

Mesh seamed_cube() {
  std::vector<Eigen::Vector3d> p;
  std::vector<std::array<std::int32_t, 3>> t;
  for (const auto& q : kQuads) {
    const auto base = static_cast<std::int32_t>(p.size());
    for (int k = 0; k < 4; ++k) p.push_back(corner(q[static_cast<std::size_t>(k)]));
    t.push_back({base, base + 1, base + 2});
    t.push_back({base, base + 2, base + 3});
  }
  return make_mesh(p, t, "seamed_cube");
}

Mesh sheet(int n, int m) {
  std::vector<Eigen::Vector3d> p;
  for (int j = 0; j <= m; ++j) {
    for (int i = 0; i <= n; ++i) p.emplace_back(i, j, 0.0);
  }
  std::vector<std::array<std::int32_t, 3>> t;
  const auto id = [n](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return make_mesh(p, t, "sheet");
}

}  // namespace skelcd::skinning::test
