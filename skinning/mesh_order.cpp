#include "skinning/mesh_order.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace skelcd::skinning {
namespace {

/// The 21 low bits of x spread to every third bit of a 63-bit word.
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffffULL;
  x = (x | (x << 32)) & 0x1f00000000ffffULL;
  x = (x | (x << 16)) & 0x1f0000ff0000ffULL;
  x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

MeshPermutation spatial_order(const Positions& positions, const Triangles& triangles) {
  const Eigen::Index nv = positions.rows();
  const Eigen::Index nf = triangles.rows();
  std::vector<std::array<double, 3>> centroids(static_cast<std::size_t>(nf));
  std::array<double, 3> lo{};
  std::array<double, 3> hi{};
  lo.fill(std::numeric_limits<double>::infinity());
  hi.fill(-std::numeric_limits<double>::infinity());
  for (Eigen::Index f = 0; f < nf; ++f) {
    auto& c = centroids[static_cast<std::size_t>(f)];
    c = {0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = triangles(f, k);
      if (v < 0 || v >= nv) return {};
      // A third of each corner: no overflow where the corners themselves are finite.
      for (Eigen::Index a = 0; a < 3; ++a) c[static_cast<std::size_t>(a)] += positions(v, a) / 3.0;
    }
    for (std::size_t a = 0; a < 3; ++a) {
      if (!std::isfinite(c[a])) return {};
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  }
  // Cell of a centroid on each axis: 0 … 2^21 − 1 over [lo, hi] (one cell when the extent is 0).
  constexpr double kCells = 2097151.0;
  std::array<double, 3> scale{};
  for (std::size_t a = 0; a < 3; ++a) {
    const double extent = hi[a] - lo[a];
    scale[a] = extent > 0.0 && std::isfinite(extent) ? kCells / extent : 0.0;
  }
  std::vector<std::pair<std::uint64_t, std::int32_t>> keyed(static_cast<std::size_t>(nf));
  for (std::size_t f = 0; f < keyed.size(); ++f) {
    std::uint64_t code = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      // scale 0: one cell (an extent of 0, or one too large for a double, where c − lo may be
      // infinite and inf · 0 would be NaN).
      const double cell =
          scale[a] > 0.0 ? std::clamp((centroids[f][a] - lo[a]) * scale[a], 0.0, kCells) : 0.0;
      code |= spread_bits(static_cast<std::uint64_t>(cell)) << a;
    }
    keyed[f] = {code, static_cast<std::int32_t>(f)};
  }
  std::sort(keyed.begin(), keyed.end());  // (code, old index): ties keep the old order
  MeshPermutation p;
  p.faces.resize(keyed.size());
  p.vertices.reserve(static_cast<std::size_t>(nv));
  std::vector<bool> placed(static_cast<std::size_t>(nv), false);
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    const std::int32_t f = keyed[i].second;
    p.faces[i] = f;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(triangles(f, k));
      if (!placed[v]) {
        placed[v] = true;
        p.vertices.push_back(static_cast<std::int32_t>(v));
      }
    }
  }
  for (std::size_t v = 0; v < placed.size(); ++v) {
    if (!placed[v]) p.vertices.push_back(static_cast<std::int32_t>(v));
  }
  return p;
}

MeshPermutation file_order(const Mesh& mesh) {
  const auto sorted_by = [](const std::vector<std::int32_t>& part,
                            const std::vector<std::int32_t>& index,
                            std::vector<std::int32_t>& order) {
    order.resize(part.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::int32_t>(i);
    const auto key = [&](std::int32_t i) {
      return std::pair{part[static_cast<std::size_t>(i)], index[static_cast<std::size_t>(i)]};
    };
    if (std::is_sorted(
            order.begin(), order.end(), [&](auto a, auto b) { return key(a) < key(b); })) {
      return false;
    }
    std::sort(order.begin(), order.end(), [&](auto a, auto b) { return key(a) < key(b); });
    return true;
  };
  MeshPermutation p;
  const bool faces_moved = sorted_by(mesh.face_part, mesh.face_index_in_part, p.faces);
  const bool vertices_moved = sorted_by(mesh.vertex_part, mesh.vertex_index_in_part, p.vertices);
  if (!faces_moved && !vertices_moved) return {};
  return p;
}

void gather_rows(const Positions& from, const std::vector<std::int32_t>& rows, Positions& out) {
  out.resize(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    out.row(static_cast<Eigen::Index>(i)) = from.row(rows[i]);
  }
}

void label_one_part_in_file_order(Mesh& mesh, std::string name) {
  const auto nf = static_cast<std::size_t>(mesh.num_triangles());
  const auto nv = static_cast<std::size_t>(mesh.num_vertices());
  mesh.face_part.assign(nf, 0);
  mesh.vertex_part.assign(nv, 0);
  mesh.face_index_in_part.resize(nf);
  mesh.vertex_index_in_part.resize(nv);
  std::iota(mesh.face_index_in_part.begin(), mesh.face_index_in_part.end(), 0);
  std::iota(mesh.vertex_index_in_part.begin(), mesh.vertex_index_in_part.end(), 0);
  mesh.part_names = {std::move(name)};
}

Mesh reordered(const Mesh& mesh, const MeshPermutation& p) {
  assert(p.faces.size() == static_cast<std::size_t>(mesh.num_triangles()));
  assert(p.vertices.size() == static_cast<std::size_t>(mesh.num_vertices()));
  Mesh out;
  gather_rows(mesh.rest_positions, p.vertices, out.rest_positions);
  std::vector<std::int32_t> new_id(p.vertices.size());
  for (std::size_t i = 0; i < p.vertices.size(); ++i) {
    new_id[static_cast<std::size_t>(p.vertices[i])] = static_cast<std::int32_t>(i);
  }
  out.triangles.resize(mesh.triangles.rows(), 3);
  for (std::size_t i = 0; i < p.faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      out.triangles(static_cast<Eigen::Index>(i), k) =
          new_id[static_cast<std::size_t>(mesh.triangles(p.faces[i], k))];
    }
  }
  const auto moved = [](const std::vector<std::int32_t>& values,
                        const std::vector<std::int32_t>& order) {
    std::vector<std::int32_t> result;
    if (values.empty()) return result;
    result.reserve(order.size());
    for (const std::int32_t old : order) result.push_back(values[static_cast<std::size_t>(old)]);
    return result;
  };
  out.face_part = moved(mesh.face_part, p.faces);
  out.face_index_in_part = moved(mesh.face_index_in_part, p.faces);
  out.vertex_part = moved(mesh.vertex_part, p.vertices);
  out.vertex_index_in_part = moved(mesh.vertex_index_in_part, p.vertices);
  out.part_names = mesh.part_names;
  out.excluded_part_pairs = mesh.excluded_part_pairs;
  return out;
}

}  // namespace skelcd::skinning
