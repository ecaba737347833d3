// The brute-force rational triangle-triangle reference (moved here from test_triangle_triangle.cpp
// so that the equivalence test can judge with it too).

#include "tests/ccd/triangle_triangle_brute.hpp"

#include <gmpxx.h>

#include <array>
#include <vector>

namespace skelcd::ccd::test {
namespace {

using V = Eigen::Vector3d;
using Q3 = std::array<mpq_class, 3>;

Q3 rational(const V& p) { return {mpq_class(p.x()), mpq_class(p.y()), mpq_class(p.z())}; }

// Solves M_S x = r exactly for the columns S (5 equations). Returns false when the columns are
// dependent or the system is inconsistent.
bool solve(
    const std::array<std::array<mpq_class, 6>, 5>& m,
    const std::array<mpq_class, 5>& r,
    const std::vector<int>& cols,
    std::vector<mpq_class>& x) {
  const std::size_t n = cols.size();
  std::vector<std::vector<mpq_class>> a(5, std::vector<mpq_class>(n + 1));
  for (std::size_t i = 0; i < 5; ++i) {
    for (std::size_t j = 0; j < n; ++j) a[i][j] = m[i][static_cast<std::size_t>(cols[j])];
    a[i][n] = r[i];
  }
  std::size_t row = 0;
  for (std::size_t col = 0; col < n; ++col) {
    std::size_t pivot = row;
    while (pivot < 5 && a[pivot][col] == 0) ++pivot;
    if (pivot == 5) return false;  // dependent columns
    std::swap(a[row], a[pivot]);
    for (std::size_t i = 0; i < 5; ++i) {
      if (i == row || a[i][col] == 0) continue;
      const mpq_class f = a[i][col] / a[row][col];
      for (std::size_t j = col; j <= n; ++j) a[i][j] -= f * a[row][j];
    }
    ++row;
  }
  for (std::size_t i = row; i < 5; ++i) {
    if (a[i][n] != 0) return false;  // inconsistent
  }
  x.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) x[i] = a[i][n] / a[i][i];
  return true;
}

bool on_segment(const Q3& p, const Q3& a, const Q3& b) {
  // p = a + s (b - a), 0 <= s <= 1, or p = a when a = b.
  Q3 d, e;
  for (std::size_t k = 0; k < 3; ++k) {
    d[k] = b[k] - a[k];
    e[k] = p[k] - a[k];
  }
  const mpq_class cx = d[1] * e[2] - d[2] * e[1], cy = d[2] * e[0] - d[0] * e[2],
                  cz = d[0] * e[1] - d[1] * e[0];
  if (cx != 0 || cy != 0 || cz != 0) return false;
  mpq_class dot_pa_pb = 0;
  for (std::size_t k = 0; k < 3; ++k) dot_pa_pb += (p[k] - a[k]) * (p[k] - b[k]);
  return dot_pa_pb <= 0;
}

}  // namespace

bool brute_intersect(const TriangleTriangleQuery& q, const SharedCorners& shared) {
  const Q3 a[3] = {rational(q.a0), rational(q.a1), rational(q.a2)};
  const Q3 b[3] = {rational(q.b0), rational(q.b1), rational(q.b2)};
  std::array<std::array<mpq_class, 6>, 5> m;
  for (std::size_t j = 0; j < 3; ++j) {
    m[0][j] = 1;
    m[0][j + 3] = 0;
    m[1][j] = 0;
    m[1][j + 3] = 1;
    for (std::size_t k = 0; k < 3; ++k) {
      m[2 + k][j] = a[j][k];
      m[2 + k][j + 3] = -b[j][k];
    }
  }
  const std::array<mpq_class, 5> r{1, 1, 0, 0, 0};
  std::vector<Q3> shared_points;
  for (std::size_t i = 0; i < 3; ++i) {
    if (shared[i] >= 0) shared_points.push_back(a[i]);
  }
  std::vector<mpq_class> x;
  for (int mask = 1; mask < 64; ++mask) {
    std::vector<int> cols;
    for (int j = 0; j < 6; ++j) {
      if (mask & (1 << j)) cols.push_back(j);
    }
    if (cols.size() > 5 || !solve(m, r, cols, x)) continue;
    bool feasible = true;
    for (const auto& xi : x) feasible = feasible && xi >= 0;
    if (!feasible) continue;
    // A vertex of A n B.
    Q3 p{0, 0, 0};
    for (std::size_t j = 0; j < cols.size(); ++j) {
      if (cols[j] >= 3) continue;
      for (std::size_t k = 0; k < 3; ++k) p[k] += x[j] * a[static_cast<std::size_t>(cols[j])][k];
    }
    if (shared_points.empty()) return true;
    const bool in_shared = shared_points.size() == 1 ? p == shared_points[0]
                           : shared_points.size() == 2
                               ? on_segment(p, shared_points[0], shared_points[1])
                               : true;  // three shared corners: the same triangle
    if (!in_shared) return true;
  }
  return false;
}

}  // namespace skelcd::ccd::test
