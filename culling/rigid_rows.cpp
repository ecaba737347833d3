#include "culling/rigid_rows.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/elementary.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace {

using Influences = std::vector<std::pair<std::int32_t, double>>;

/// The largest ‖L₀⁻¹ L₁ − I‖₂ a certified row may have: a turn of up to 2 asin(0.45) ≈ 53° within
/// the interval (‖R − I‖₂ = 2 sin(θ/2)); the blend's σ_min then stays above a tenth of L₀'s.
constexpr double kMaxBeta = 0.9;

[[nodiscard]] std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

/// Whether the boxes of two point sets of the held pose `x` (rows of the row-major positions) lie
/// more than `s` apart on an axis: the kernels' first test (ccd::swept_aabbs_disjoint) of a
/// query whose two ends are both `x`, on the same coordinates and with the same comparisons, so
/// that a query it rejects is one the kernel would have answered "no hit" at once.
template <std::size_t NA, std::size_t NB>
bool held_boxes_apart(
    const skinning::Positions& x,
    const std::array<std::int32_t, NA>& a,
    const std::array<std::int32_t, NB>& b,
    double s) {
  const double* p = x.data();
  for (std::size_t k = 0; k < 3; ++k) {
    const auto coordinate = [&](std::int32_t v) { return p[3 * static_cast<std::size_t>(v) + k]; };
    double a_lo = coordinate(a[0]);
    double a_hi = a_lo;
    for (std::size_t i = 1; i < NA; ++i) {
      a_lo = std::min(a_lo, coordinate(a[i]));
      a_hi = std::max(a_hi, coordinate(a[i]));
    }
    double b_lo = coordinate(b[0]);
    double b_hi = b_lo;
    for (std::size_t i = 1; i < NB; ++i) {
      b_lo = std::min(b_lo, coordinate(b[i]));
      b_hi = std::max(b_hi, coordinate(b[i]));
    }
    if (b_lo - a_hi > s || a_lo - b_hi > s) return true;
  }
  return false;
}

/// Row v of the row-major positions `x`.
Eigen::Vector3d point(const skinning::Positions& x, std::int32_t v) {
  const double* p = x.data() + 3 * static_cast<std::size_t>(v);
  return {p[0], p[1], p[2]};
}

/// Whether the point sets a and b of the held pose `x` lie more than 2s apart along the direction
/// u, whatever u is: the gap between their projections on u, over |u|, is a lower bound of their
/// distance. Computed, the projections are off by a few units of roundoff of |u| times the
/// coordinates' size, and |u| by two: with 2s in place of s, a gap this accepts is more than s
/// exactly while s is above some 10⁻¹⁴ of the coordinates (the rest tolerance is 10⁻⁶ of them).
/// A degenerate u (zero, not finite) settles nothing.
template <std::size_t NA, std::size_t NB>
bool apart_along(
    const skinning::Positions& x,
    const Eigen::Vector3d& u,
    const std::array<std::int32_t, NA>& a,
    const std::array<std::int32_t, NB>& b,
    double s) {
  const double norm = u.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  const Eigen::Vector3d origin = point(x, b[0]);
  const auto range = [&](const auto& set) {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (const std::int32_t v : set) {
      const double d = u.dot(point(x, v) - origin);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    return std::pair{lo, hi};
  };
  const auto [a_lo, a_hi] = range(a);
  const auto [b_lo, b_hi] = range(b);
  const double need = 2.0 * s * norm;
  return a_lo - b_hi > need || b_lo - a_hi > need;
}

/// Whether triangles a and b (welded corners) have a vertex-face or edge-edge pair sharing no
/// vertex that the conservative CCD test of the held pose `x` finds within
/// options.min_separation. A pair whose boxes are apart (held_boxes_apart, the kernel's own first
/// test) is not handed to the kernel: nearly all of them are, and forming the query cost more
/// than the kernel's answer (the same answers; docs/benchmarks.md "Rest pairs without queries").
/// Nor is one that a direction shows more than twice the tolerance apart (apart_along): the face's
/// normal and its sides' normals in its plane for a vertex-face pair; the two edges' cross product,
/// the triangles' normals and each edge's normal in its triangle's plane for an edge-edge pair.
/// Neighbours in a flat or smooth stretch of a row pass the boxes but not these, and the kernel
/// on such a nearly coplanar held pose is at its slowest (docs/benchmarks.md "Rest pairs apart
/// along a direction").
bool features_within(
    const skinning::Positions& x,
    const std::array<std::int32_t, 3>& a,
    const std::array<std::int32_t, 3>& b,
    const ccd::CcdOptions& options) {
  const auto in = [](std::int32_t v, const std::array<std::int32_t, 3>& t) {
    return v == t[0] || v == t[1] || v == t[2];
  };
  const double s = options.min_separation;
  const auto normal = [&](const std::array<std::int32_t, 3>& t) -> Eigen::Vector3d {
    const Eigen::Vector3d p0 = point(x, t[0]);
    return (point(x, t[1]) - p0).cross(point(x, t[2]) - p0);
  };
  const Eigen::Vector3d n_a = normal(a);
  const Eigen::Vector3d n_b = normal(b);
  const auto vertex_face = [&](std::int32_t v, const std::array<std::int32_t, 3>& f) {
    const std::array<std::int32_t, 1> p{v};
    if (held_boxes_apart(x, p, f, s)) return false;
    const Eigen::Vector3d& n = &f == &a ? n_a : n_b;
    if (apart_along(x, n, p, f, s)) return false;
    for (std::size_t i = 0; i < 3; ++i) {
      const Eigen::Vector3d side = point(x, f[(i + 1) % 3]) - point(x, f[i]);
      if (apart_along(x, n.cross(side), p, f, s)) return false;
    }
    return ccd::vertex_face_ccd(
               vertex_face_query(x, x, v, x, x, f), ccd::Accuracy::conservative, options)
        .hit;
  };
  for (const std::int32_t v : a) {
    if (!in(v, b) && vertex_face(v, b)) return true;
  }
  for (const std::int32_t v : b) {
    if (!in(v, a) && vertex_face(v, a)) return true;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const std::int32_t a0 = a[i];
    const std::int32_t a1 = a[(i + 1) % 3];
    for (std::size_t j = 0; j < 3; ++j) {
      const std::int32_t b0 = b[j];
      const std::int32_t b1 = b[(j + 1) % 3];
      if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
      const std::array<std::int32_t, 2> ea{a0, a1};
      const std::array<std::int32_t, 2> eb{b0, b1};
      if (held_boxes_apart(x, ea, eb, s)) continue;
      const Eigen::Vector3d da = point(x, a1) - point(x, a0);
      const Eigen::Vector3d db = point(x, b1) - point(x, b0);
      if (apart_along(x, da.cross(db), ea, eb, s) || apart_along(x, n_a, ea, eb, s) ||
          apart_along(x, n_b, ea, eb, s) || apart_along(x, n_a.cross(da), ea, eb, s) ||
          apart_along(x, n_b.cross(db), ea, eb, s)) {
        continue;
      }
      const ccd::EdgeEdgeQuery q = edge_edge_query(x, x, {a0, a1}, x, x, {b0, b1});
      if (ccd::edge_edge_ccd(q, ccd::Accuracy::conservative, options).hit) return true;
    }
  }
  return false;
}

/// The row's blended matrix, as linear_blend_skinning forms it (the same products and sums in the
/// same order), and the size that bounds its rounding and the posed corners': per output row,
/// Σ over influences of |w| times that row of |T| (linear part and translation apart).
struct Blend {
  skinning::BoneTransform m;
  double linear_size = 0.0;       ///< max over rows i of Σ_k |w_k| Σ_j |T_k(i, j)|, j < 3
  double translation_size = 0.0;  ///< max over rows i of Σ_k |w_k| |T_k(i, 3)|
};

Blend blend(const Influences& row, std::span<const skinning::BoneTransform> t) {
  Blend b;
  b.m = row.front().second * t[at(row.front().first)];
  for (std::size_t k = 1; k < row.size(); ++k) b.m.noalias() += row[k].second * t[at(row[k].first)];
  for (int i = 0; i < 3; ++i) {
    double linear = 0.0;
    double translation = 0.0;
    for (const auto& [index, w] : row) {
      const auto& tk = t[at(index)];
      linear += std::abs(w) * (std::abs(tk(i, 0)) + std::abs(tk(i, 1)) + std::abs(tk(i, 2)));
      translation += std::abs(w) * std::abs(tk(i, 3));
    }
    b.linear_size = std::max(b.linear_size, linear);
    b.translation_size = std::max(b.translation_size, translation);
  }
  return b;
}

}  // namespace

RigidRows build_rigid_rows(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const skinning::SkinWeights& weights,
    std::int32_t num_transforms,
    double min_share) {
  const auto fail = [](const std::string& what) {
    throw InvalidInput("culling::rigid_rows: " + what);
  };
  if (weights.rows() != mesh.rest_positions.rows()) {
    fail(
        "the weights have " + std::to_string(weights.rows()) + " rows for " +
        std::to_string(mesh.rest_positions.rows()) + " vertices");
  }
  if (weights.cols() > num_transforms) {
    fail(
        "the weights have " + std::to_string(weights.cols()) + " columns for " +
        std::to_string(num_transforms) + " transforms");
  }
  const std::int32_t nw = topology.num_welded_vertices();
  const auto nf = static_cast<std::int32_t>(topology.welded_triangles.rows());
  RigidRows out;
  out.num_transforms = num_transforms;
  // Each welded vertex's row: its representative's influences, exactly as stored, copied into
  // one array (`columns`, `values`, vertex w's at [start[w], start[w + 1])). Equal rows are found
  // by sorting the vertices by their rows, not through a map of row vectors (on a subdivided
  // rig nearly every vertex has a row of its own: a vector and a map node each, most of this
  // function's instructions on CesiumMan-dense); rows are numbered in the order of their first
  // vertex, as such a map filled vertex by vertex numbers them.
  std::vector<std::int32_t> columns;
  std::vector<double> values;
  std::vector<std::size_t> start(at(nw) + 1, 0);
  skinning::Positions rest(nw, 3);
  double extent = 0.0;
  for (std::int32_t w = 0; w < nw; ++w) {
    const std::int32_t v = topology.representative_vertex[at(w)];
    if (v < 0 || v >= mesh.rest_positions.rows()) {
      fail("representative_vertex[" + std::to_string(w) + "] is not a mesh vertex");
    }
    rest.row(w) = mesh.rest_positions.row(v);
    if (!rest.row(w).allFinite()) fail("vertex " + std::to_string(v) + " is not finite at rest");
    extent = std::max(extent, rest.row(w).cwiseAbs().maxCoeff());
    for (skinning::SkinWeights::InnerIterator it(weights, v); it; ++it) {
      if (!std::isfinite(it.value()))
        fail("vertex " + std::to_string(v) + " has a non-finite weight");
      columns.push_back(static_cast<std::int32_t>(it.col()));
      values.push_back(it.value());
    }
    start[at(w) + 1] = columns.size();
  }
  // Lexicographic on (column, weight) pairs, a shorter row first where one is the other's
  // beginning: the order of std::vector<std::pair<int, double>>, so that equal means equal there.
  const auto row_less = [&](std::int32_t a, std::int32_t b) {
    const std::size_t na = start[at(a) + 1] - start[at(a)];
    const std::size_t nb = start[at(b) + 1] - start[at(b)];
    for (std::size_t k = 0; k < std::min(na, nb); ++k) {
      const std::size_t i = start[at(a)] + k;
      const std::size_t j = start[at(b)] + k;
      if (columns[i] != columns[j]) return columns[i] < columns[j];
      if (values[i] < values[j]) return true;
      if (values[j] < values[i]) return false;
    }
    return na < nb;
  };
  std::vector<std::int32_t> by_row;  // the vertices skinning blends (a row), sorted by row
  for (std::int32_t w = 0; w < nw; ++w) {
    if (start[at(w) + 1] > start[at(w)]) by_row.push_back(w);  // else left at rest: not a blend
  }
  std::stable_sort(by_row.begin(), by_row.end(), row_less);
  // Each blended vertex's first vertex with its row (stable: a run's first is its least), then
  // the rows numbered as those first vertices come, each later vertex taking its first's.
  std::vector<std::int32_t> first_of(at(nw), -1);
  for (std::size_t i = 0; i < by_row.size(); ++i) {
    const bool starts_run = i == 0 || row_less(by_row[i - 1], by_row[i]);
    first_of[at(by_row[i])] = starts_run ? by_row[i] : first_of[at(by_row[i - 1])];
  }
  std::vector<std::int32_t> vertex_row(at(nw), -1);
  std::vector<std::int32_t> row_vertex;  // each row's first vertex
  for (std::int32_t w = 0; w < nw; ++w) {
    const std::int32_t first = first_of[at(w)];
    if (first < 0) continue;
    if (first == w) {
      vertex_row[at(w)] = static_cast<std::int32_t>(row_vertex.size());
      row_vertex.push_back(w);
    } else {
      vertex_row[at(w)] = vertex_row[at(first)];  // first < w: numbered already
    }
  }
  // A row's influences, from its first vertex (the rows kept below only).
  const auto influences = [&](std::int32_t r) {
    const std::int32_t w = row_vertex[at(r)];
    Influences row;
    for (std::size_t i = start[at(w)]; i < start[at(w) + 1]; ++i) {
      row.emplace_back(columns[i], values[i]);
    }
    return row;
  };
  const auto num_rows = static_cast<std::int32_t>(row_vertex.size());
  out.rest_extent = std::max(extent, 1e-300);
  out.rest_tolerance = 1e-6 * out.rest_extent;
  out.triangle_row.assign(at(nf), -1);
  const auto& tris = topology.welded_triangles;
  const auto corners = [&](std::int32_t f) {
    return std::array<std::int32_t, 3>{tris(f, 0), tris(f, 1), tris(f, 2)};
  };
  std::vector<std::int32_t> triangles_in(at(num_rows), 0);
  for (std::int32_t f = 0; f < nf; ++f) {
    const auto c = corners(f);
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    const std::int32_t r = vertex_row[at(c[0])];
    if (r >= 0 && r == vertex_row[at(c[1])] && r == vertex_row[at(c[2])]) {
      out.triangle_row[at(f)] = r;
      ++triangles_in[at(r)];
    }
  }
  // Only rows of two triangles or more have a pair to skip: the others are dropped (each would
  // cost a certificate per interval), the rest renumbered in order.
  std::vector<std::int32_t> renumbered(at(num_rows), -1);
  for (std::int32_t r = 0; r < num_rows; ++r) {
    if (triangles_in[at(r)] < 2) continue;
    renumbered[at(r)] = static_cast<std::int32_t>(out.rows.size());
    out.rows.push_back(influences(r));
  }
  for (std::int32_t& r : out.triangle_row) {
    if (r >= 0) r = renumbered[at(r)];
    if (r >= 0) ++out.triangles_in_rows;
  }
  if (static_cast<double>(out.triangles_in_rows) < min_share * static_cast<double>(nf)) {
    out.rows.clear();
    out.triangle_row.assign(at(nf), -1);
    out.triangles_in_rows = 0;
    return out;
  }
  // Rest pairs: the triangles of each row by the low end of their rest boxes on x (grown by the
  // tolerance), swept; a pair whose grown boxes overlap is kept when a feature pair of it lies
  // within the tolerance.
  struct Item {
    std::int32_t row;
    std::int32_t f;
    std::array<double, 6> box;  // lo x, y, z, hi x, y, z
  };
  std::vector<Item> items;
  for (std::int32_t f = 0; f < nf; ++f) {
    const std::int32_t r = out.triangle_row[at(f)];
    if (r < 0) continue;
    Item item{r, f, {}};
    for (int d = 0; d < 3; ++d) {
      const double a = rest(tris(f, 0), d);
      const double b = rest(tris(f, 1), d);
      const double c = rest(tris(f, 2), d);
      item.box[at(d)] = std::min({a, b, c}) - out.rest_tolerance;
      item.box[at(3 + d)] = std::max({a, b, c}) + out.rest_tolerance;
    }
    items.push_back(item);
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return a.row != b.row ? a.row < b.row : a.box[0] < b.box[0];
  });
  // Pairs of parts never checked against each other (a robot's link against itself) have no
  // feature pair to test: no rest pair needed.
  const auto part = [&](std::int32_t f) {
    return mesh.face_part.empty() ? 0 : mesh.face_part[at(f)];
  };
  std::vector<std::pair<std::int32_t, std::int32_t>> excluded_parts;
  for (const auto& [a, b] : mesh.excluded_part_pairs) excluded_parts.push_back(std::minmax(a, b));
  std::sort(excluded_parts.begin(), excluded_parts.end());
  const auto excluded = [&](std::int32_t fa, std::int32_t fb) {
    const std::pair<std::int32_t, std::int32_t> parts = std::minmax(part(fa), part(fb));
    return std::binary_search(excluded_parts.begin(), excluded_parts.end(), parts);
  };
  ccd::CcdOptions within;
  within.min_separation = out.rest_tolerance;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& a = items[i];
    for (std::size_t j = i + 1; j < items.size() && items[j].row == a.row; ++j) {
      const Item& b = items[j];
      if (b.box[0] > a.box[3]) break;
      if (b.box[1] > a.box[4] || a.box[1] > b.box[4] || b.box[2] > a.box[5] ||
          a.box[2] > b.box[5]) {
        continue;
      }
      if (!excluded(a.f, b.f) && features_within(rest, corners(a.f), corners(b.f), within)) {
        out.rest_pairs.push_back({std::min(a.f, b.f), std::max(a.f, b.f)});
      }
    }
  }
  std::sort(out.rest_pairs.begin(), out.rest_pairs.end());
  return out;
}

void certify_rigid_rows(
    const RigidRows& rows,
    std::span<const skinning::BoneTransform> t0,
    std::span<const skinning::BoneTransform> t1,
    double min_separation,
    std::vector<std::uint8_t>& certified) {
  certified.assign(at(rows.num_rows()), 0);
  const auto needed = static_cast<std::size_t>(rows.num_transforms);
  if (t0.size() < needed || t1.size() < needed || !std::isfinite(min_separation)) return;
  // Unit roundoff, times a slack that covers the blend's sums (one per influence) and the
  // matrix-vector product (three products and three sums a coordinate) many times over.
  constexpr double kU = std::numeric_limits<double>::epsilon() / 2;
  for (std::int32_t r = 0; r < rows.num_rows(); ++r) {
    const Influences& row = rows.rows[at(r)];
    const Blend b0 = blend(row, t0);
    const Blend b1 = blend(row, t1);
    if (!b0.m.allFinite() || !b1.m.allFinite()) continue;
    const Eigen::Matrix3d l0 = b0.m.leftCols<3>();
    const Eigen::Matrix3d l1 = b1.m.leftCols<3>();
    Eigen::Matrix3d inverse;
    bool invertible = false;
    double determinant = 0.0;
    l0.computeInverseAndDetWithCheck(inverse, determinant, invertible, 0.0);
    if (!invertible || !inverse.allFinite()) continue;
    // β ≥ ‖B − I‖₂: the largest eigenvalue of (B − I)ᵀ(B − I), closed form, grown for its
    // rounding (relative 1e-15 of ‖B − I‖², absolute a few ulps of it).
    const Eigen::Matrix3d d = inverse * l1 - Eigen::Matrix3d::Identity();
    if (!d.allFinite()) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(d.transpose() * d, Eigen::EigenvaluesOnly);
    const double largest = std::max(eigen.eigenvalues().maxCoeff(), 0.0);
    const double beta = std::sqrt(largest * (1.0 + 1e-9) + 1e-12 * d.squaredNorm());
    if (!(beta < kMaxBeta)) continue;
    // σ_min of every blend between the two ends, shrunk by 1 % for the rounding of this bound.
    const double sigma = 0.99 * (1.0 - beta) / inverse.norm();
    const double slack = 64.0 * kU * (static_cast<double>(row.size()) + 3.0) * std::sqrt(3.0);
    const double e0 = slack * (b0.linear_size * rows.rest_extent + b0.translation_size);
    const double e1 = slack * (b1.linear_size * rows.rest_extent + b1.translation_size);
    const double reach = min_separation + 2.0 * std::max(e0, e1);
    if (std::isfinite(sigma) && sigma > 0.0 && reach < sigma * rows.rest_tolerance) {
      certified[at(r)] = 1;
    }
  }
}

}  // namespace skelcd::culling
