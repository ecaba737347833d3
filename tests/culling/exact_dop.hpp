#pragma once
// Exact (GMP rational) checks of Dop volumes for the culling tests: a volume must contain the
// exact projection of every point it bounds, whatever the floating-point rounding did.

#include <gmpxx.h>

#include "culling/dop.hpp"

namespace skelcd::test {

/// Exact projection of (x, y, z) on axis k of Dop<N>.
template <int N>
mpq_class exact_projection(double x, double y, double z, std::size_t k) {
  const auto& a = culling::DopAxes<N>::kAxes[k];
  return mpq_class(x) * a[0] + mpq_class(y) * a[1] + mpq_class(z) * a[2];
}

/// True when every exact projection of the point lies in the volume's slabs.
template <int N>
bool contains_exactly(const culling::Dop<N>& d, double x, double y, double z) {
  for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
    const mpq_class p = exact_projection<N>(x, y, z, k);
    if (p < mpq_class(d.lo[k]) || p > mpq_class(d.hi[k])) return false;
  }
  return true;
}

template <int N>
bool contains_exactly(const culling::Dop<N>& d, const Eigen::Vector3d& p) {
  return contains_exactly<N>(d, p.x(), p.y(), p.z());
}

}  // namespace skelcd::test
