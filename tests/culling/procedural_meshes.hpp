#pragma once
// Procedural meshes with known collisions for the culling tests and benchmark: sheets, tubes,
// spheres, their combination into multi-part meshes, and a small welded topology builder written
// independently of skinning::build_topology (so culling can be tested on its own).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "skinning/mesh.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/topology.hpp"

namespace skelcd::test {

using skinning::Mesh;
using skinning::Positions;
using skinning::Topology;
using skinning::Triangles;

/// Welds vertices with bit-identical positions and builds the parts of a Topology the culling
/// module reads: welded_of_vertex, representative_vertex, welded_triangles, edges (sorted, unique,
/// smaller id first), face_edges (-1 for a collapsed side), edge_face_offsets / edge_faces.
inline Topology simple_topology(const Mesh& mesh) {
  Topology t;
  const auto nv = static_cast<std::size_t>(mesh.rest_positions.rows());
  std::map<std::array<double, 3>, std::int32_t> ids;
  t.welded_of_vertex.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto r = static_cast<Eigen::Index>(v);
    const std::array<double, 3> key{
        mesh.rest_positions(r, 0), mesh.rest_positions(r, 1), mesh.rest_positions(r, 2)};
    const auto [it, inserted] =
        ids.emplace(key, static_cast<std::int32_t>(t.representative_vertex.size()));
    if (inserted) t.representative_vertex.push_back(static_cast<std::int32_t>(v));
    t.welded_of_vertex[v] = it->second;
  }
  const Eigen::Index nf = mesh.triangles.rows();
  t.welded_triangles.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (Eigen::Index k = 0; k < 3; ++k) {
      t.welded_triangles(f, k) = t.welded_of_vertex[static_cast<std::size_t>(mesh.triangles(f, k))];
    }
  }
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> edge_ids;
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t a = t.welded_triangles(f, k);
      const std::int32_t b = t.welded_triangles(f, (k + 1) % 3);
      if (a != b) edge_ids.emplace(std::minmax(a, b), 0);  // a collapsed side is no edge
    }
  }
  t.edges.resize(static_cast<Eigen::Index>(edge_ids.size()), 2);
  std::int32_t next = 0;
  for (auto& [key, id] : edge_ids) {
    id = next;
    t.edges(next, 0) = key.first;
    t.edges(next, 1) = key.second;
    ++next;
  }
  t.face_edges.resize(nf, 3);
  std::vector<std::vector<std::int32_t>> faces_of_edge(edge_ids.size());
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t a = t.welded_triangles(f, k);
      const std::int32_t b = t.welded_triangles(f, (k + 1) % 3);
      if (a == b) {
        t.face_edges(f, k) = -1;
        continue;
      }
      const std::int32_t e = edge_ids.at(std::minmax(a, b));
      t.face_edges(f, k) = e;
      auto& faces = faces_of_edge[static_cast<std::size_t>(e)];
      if (faces.empty() || faces.back() != static_cast<std::int32_t>(f)) {
        faces.push_back(static_cast<std::int32_t>(f));
      }
    }
  }
  t.edge_face_offsets.push_back(0);
  for (const auto& fs : faces_of_edge) {
    t.edge_faces.insert(t.edge_faces.end(), fs.begin(), fs.end());
    t.edge_face_offsets.push_back(static_cast<std::int32_t>(t.edge_faces.size()));
  }
  return t;
}

/// A mesh of one part from positions and triangles (part arrays filled).
inline Mesh single_part_mesh(Positions x, Triangles f, const char* name = "part0") {
  Mesh m;
  m.rest_positions = std::move(x);
  m.triangles = std::move(f);
  skinning::label_one_part_in_file_order(m, name);
  return m;
}

/// Appends `b` to `a` as new parts (vertices are not merged; welding may merge equal positions).
inline Mesh combine(const Mesh& a, const Mesh& b) {
  Mesh m;
  const Eigen::Index va = a.rest_positions.rows();
  m.rest_positions.resize(va + b.rest_positions.rows(), 3);
  m.rest_positions << a.rest_positions, b.rest_positions;
  m.triangles.resize(a.triangles.rows() + b.triangles.rows(), 3);
  m.triangles << a.triangles, (b.triangles.array() + static_cast<std::int32_t>(va)).matrix();
  const auto pa = a.num_parts();
  auto shifted = [pa](std::vector<std::int32_t> v) {
    for (auto& p : v) p += pa;
    return v;
  };
  auto cat = [](std::vector<std::int32_t> x, const std::vector<std::int32_t>& y) {
    x.insert(x.end(), y.begin(), y.end());
    return x;
  };
  m.face_part = cat(a.face_part, shifted(b.face_part));
  m.vertex_part = cat(a.vertex_part, shifted(b.vertex_part));
  m.face_index_in_part = cat(a.face_index_in_part, b.face_index_in_part);
  m.vertex_index_in_part = cat(a.vertex_index_in_part, b.vertex_index_in_part);
  m.part_names = a.part_names;
  m.part_names.insert(m.part_names.end(), b.part_names.begin(), b.part_names.end());
  m.excluded_part_pairs = a.excluded_part_pairs;
  for (auto [p, q] : b.excluded_part_pairs) m.excluded_part_pairs.emplace_back(p + pa, q + pa);
  return m;
}

/// A flat sheet in the z = 0 plane over [0, sx] × [0, sy]: (nx+1)(ny+1) vertices, 2·nx·ny
/// triangles (each quad split along the same diagonal).
inline Mesh sheet(int nx, int ny, double sx = 1.0, double sy = 1.0) {
  Positions x((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      x.row(j * (nx + 1) + i) << sx * i / nx, sy * j / ny, 0.0;
    }
  }
  Triangles f(2 * nx * ny, 3);
  int t = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      const int b = a + 1;
      const int c = a + nx + 1;
      const int d = c + 1;
      f.row(t++) << a, b, d;
      f.row(t++) << a, d, c;
    }
  }
  return single_part_mesh(std::move(x), std::move(f), "sheet");
}

/// An open tube along z from 0 to `length`, radius `radius`: `around` × (`along`+1) vertices,
/// 2·around·along triangles, outward-facing.
inline Mesh tube(int around, int along, double radius = 0.5, double length = 2.0) {
  Positions x(around * (along + 1), 3);
  for (int j = 0; j <= along; ++j) {
    for (int i = 0; i < around; ++i) {
      const double phi = 2.0 * std::numbers::pi * i / around;
      x.row(j * around + i) << radius * std::cos(phi), radius * std::sin(phi), length * j / along;
    }
  }
  Triangles f(2 * around * along, 3);
  int t = 0;
  for (int j = 0; j < along; ++j) {
    for (int i = 0; i < around; ++i) {
      const int a = j * around + i;
      const int b = j * around + (i + 1) % around;
      const int c = a + around;
      const int d = b + around;
      f.row(t++) << a, b, d;
      f.row(t++) << a, d, c;
    }
  }
  return single_part_mesh(std::move(x), std::move(f), "tube");
}

/// A closed UV sphere centred at the origin: 2 poles + lat−1 rings of `lon` vertices,
/// 2·lon·(lat−1) triangles, outward-facing.
inline Mesh uv_sphere(int lat, int lon, double radius = 1.0) {
  const int rings = lat - 1;
  Positions x(2 + rings * lon, 3);
  x.row(0) << 0, 0, radius;
  for (int r = 0; r < rings; ++r) {
    const double theta = std::numbers::pi * (r + 1) / lat;
    for (int i = 0; i < lon; ++i) {
      const double phi = 2.0 * std::numbers::pi * i / lon;
      x.row(1 + r * lon + i) << radius * std::sin(theta) * std::cos(phi),
          radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta);
    }
  }
  const int south = 1 + rings * lon;
  x.row(south) << 0, 0, -radius;
  Triangles f(2 * lon * rings, 3);
  int t = 0;
  for (int i = 0; i < lon; ++i) f.row(t++) << 0, 1 + i, 1 + (i + 1) % lon;
  for (int r = 0; r + 1 < rings; ++r) {
    for (int i = 0; i < lon; ++i) {
      const int a = 1 + r * lon + i;
      const int b = 1 + r * lon + (i + 1) % lon;
      const int c = a + lon;
      const int d = b + lon;
      f.row(t++) << a, c, d;
      f.row(t++) << a, d, b;
    }
  }
  for (int i = 0; i < lon; ++i) {
    f.row(t++) << south, 1 + (rings - 1) * lon + (i + 1) % lon, 1 + (rings - 1) * lon + i;
  }
  return single_part_mesh(std::move(x), std::move(f), "sphere");
}

/// Positions `x` moved by `d`.
inline Positions translated(const Positions& x, const Eigen::Vector3d& d) {
  Positions y = x;
  y.rowwise() += d.transpose();
  return y;
}

/// Bends a sheet lying in z = 0 (x in [0, sx]) about the line x = pivot: points with x > pivot
/// rotate by `angle` radians about that line (axis y). With angle slightly above π the far half
/// passes through the near half — a sheet folded through itself.
inline Positions folded(const Positions& x, double pivot, double angle) {
  Positions y = x;
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    const double u = x(v, 0) - pivot;
    if (u <= 0.0) continue;
    y(v, 0) = pivot + c * u - s * x(v, 2);
    y(v, 2) = s * u + c * x(v, 2);
  }
  return y;
}

/// Welded positions of `mesh` in the numbering of `topology` (row w = representative vertex).
inline Positions welded(const Topology& topology, const Positions& x) {
  Positions w(topology.num_welded_vertices(), 3);
  for (std::int32_t i = 0; i < topology.num_welded_vertices(); ++i) {
    w.row(i) = x.row(topology.representative_vertex[static_cast<std::size_t>(i)]);
  }
  return w;
}

/// A smooth, deterministic, non-rigid deformation of welded positions at time s (for moving
/// meshes in tests and the benchmark): a twist about z plus a travelling wave, amplitude `amp`.
inline Positions deformed(const Positions& x, double s, double amp) {
  Positions y = x;
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    const double z = x(v, 2);
    const double a = amp * s * z;
    const double c = std::cos(a);
    const double sn = std::sin(a);
    const double px = x(v, 0);
    const double py = x(v, 1);
    y(v, 0) = c * px - sn * py + amp * 0.2 * std::sin(3.0 * z + 4.0 * s);
    y(v, 1) = sn * px + c * py;
    y(v, 2) = z + amp * 0.1 * std::sin(2.0 * px + s);
  }
  return y;
}

/// A tube along z squashed flat and through itself: y scaled by (1 − 1.2·s) (the walls meet at
/// s = 1/1.2 and cross after), with a slight twist about z so they do not meet all at once.
inline Positions squashed(const Positions& x, double s) {
  Positions y = x;
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    const double a = 0.15 * s * x(v, 2);
    const double px = x(v, 0);
    const double py = x(v, 1) * (1.0 - 1.2 * s);
    y(v, 0) = std::cos(a) * px - std::sin(a) * py;
    y(v, 1) = std::sin(a) * px + std::cos(a) * py;
  }
  return y;
}

}  // namespace skelcd::test
