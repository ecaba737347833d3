#include "ccd/filters.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "ccd/polynomial_sign.hpp"

namespace skelcd::ccd {
namespace {

// Levels of de Casteljau halving the coplanarity filter may spend before giving up.
constexpr int kCoplanaritySubdivisions = 2;

struct Bounds {
  Eigen::Vector3d lo, hi;
};

template <typename... Points>
Bounds bounds_of(const Eigen::Vector3d& first, const Points&... rest) {
  Bounds b{first, first};
  ((b.lo = b.lo.cwiseMin(rest), b.hi = b.hi.cwiseMax(rest)), ...);
  return b;
}

// fl(x - y) > s implies x - y > s for a double s (rounding is monotone and s is representable).
bool separated(const Bounds& a, const Bounds& b, double min_separation) {
  for (int k = 0; k < 3; ++k) {
    if (b.lo[k] - a.hi[k] > min_separation || a.lo[k] - b.hi[k] > min_separation) return true;
  }
  return false;
}

bool coplanarity_rejects(const detail::DifferenceTriple& t0,
                         const detail::DifferenceTriple& t1,
                         double min_separation) {
  BernsteinCubic c = detail::trilinear_determinant(t0, t1);
  if (min_separation > 0.0) {
    // Shift by s * N >= s |n(t)|: the shifted cubics c -+ sN have the same Bernstein coefficients
    // moved by a constant, so widening the error by sN proves |c| > sN (docs/ccd.md).
    const double margin = min_separation * detail::cross_norm_bound(t0, t1) * detail::kRoundUp;
    c.error = detail::add_up(c.error, margin);
  }
  return cubic_sign(c, kCoplanaritySubdivisions) != PolynomialSign::uncertain;
}

}  // namespace

bool swept_aabbs_disjoint(const VertexFaceQuery& q, double min_separation) {
  assert(min_separation >= 0.0);
  return separated(bounds_of(q.v_t0, q.v_t1),
                   bounds_of(q.f0_t0, q.f1_t0, q.f2_t0, q.f0_t1, q.f1_t1, q.f2_t1), min_separation);
}

bool swept_aabbs_disjoint(const EdgeEdgeQuery& q, double min_separation) {
  assert(min_separation >= 0.0);
  return separated(bounds_of(q.ea0_t0, q.ea1_t0, q.ea0_t1, q.ea1_t1),
                   bounds_of(q.eb0_t0, q.eb1_t0, q.eb0_t1, q.eb1_t1), min_separation);
}

bool coplanarity_filter_rejects(const VertexFaceQuery& q, double min_separation) {
  assert(min_separation >= 0.0);
  // c(t) = (p - a) . ((b - a) x (c - a)).
  const detail::DifferenceTriple t0{q.v_t0 - q.f0_t0, q.f1_t0 - q.f0_t0, q.f2_t0 - q.f0_t0};
  const detail::DifferenceTriple t1{q.v_t1 - q.f0_t1, q.f1_t1 - q.f0_t1, q.f2_t1 - q.f0_t1};
  return coplanarity_rejects(t0, t1, min_separation);
}

bool coplanarity_filter_rejects(const EdgeEdgeQuery& q, double min_separation) {
  assert(min_separation >= 0.0);
  // c(t) = (b0 - a0) . ((a1 - a0) x (b1 - b0)).
  const detail::DifferenceTriple t0{q.eb0_t0 - q.ea0_t0, q.ea1_t0 - q.ea0_t0, q.eb1_t0 - q.eb0_t0};
  const detail::DifferenceTriple t1{q.eb0_t1 - q.ea0_t1, q.ea1_t1 - q.ea0_t1, q.eb1_t1 - q.eb0_t1};
  return coplanarity_rejects(t0, t1, min_separation);
}

}  // namespace skelcd::ccd
