#include "ccd/orientation.hpp"

#include <array>

#include "ccd/detail/filtered.hpp"

namespace skelcd::ccd {
namespace {

/// d = fl(x − y); true when that is x − y exactly: the tail of Knuth's two-difference is zero.
/// False for infinities and NaN (the tail is then NaN).
inline bool exact_difference(double x, double y, double& d) {
  d = x - y;
  const double b_virtual = x - d;
  const double a_virtual = d + b_virtual;
  return (x - a_virtual) + (b_virtual - y) == 0.0;
}

/// The sign of (b − a) × (c − a) · (d − a) by detail::triple_product_sign, each difference a
/// two-component expansion; `unsafe` raised (and the result meaningless) where a coordinate or a
/// product leaves the range where the expansion's steps are exact, as Expansion's checks would.
int fixed_triple_sign(
    const double* a, const double* b, const double* c, const double* d, bool& unsafe) {
  using detail::expansion_steps::unsafe_leaf;
  for (int k = 0; k < 3; ++k) {
    unsafe =
        unsafe || unsafe_leaf(a[k]) || unsafe_leaf(b[k]) || unsafe_leaf(c[k]) || unsafe_leaf(d[k]);
  }
  if (unsafe) return 0;
  std::array<detail::Difference, 3> u, v, w;
  for (std::size_t k = 0; k < 3; ++k) {
    u[k] = detail::difference(b[k], a[k]);
    v[k] = detail::difference(c[k], a[k]);
    w[k] = detail::difference(d[k], a[k]);
  }
  return detail::triple_product_sign(u.data(), v.data(), w.data(), unsafe);
}

}  // namespace

int orient3d_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  using detail::lift;
  // The coordinates of a real mesh mostly differ exactly in double (those read from 32-bit
  // files always do, unless their exponents are more than 28 apart): the determinant is then a
  // polynomial in three exact difference vectors, and what reaches this call — the filter could
  // not decide — is mostly an exact zero, often of corners in one axis plane (a flat cloth, a
  // mesh's flat parts).
  double u[3];
  double v[3];
  double w[3];
  bool exact = true;
  for (int k = 0; k < 3; ++k) {
    exact &= exact_difference(b[k], a[k], u[k]);
    exact &= exact_difference(c[k], a[k], v[k]);
    exact &= exact_difference(d[k], a[k], w[k]);
  }
  if (exact) {
    for (int k = 0; k < 3; ++k) {
      // A zero row of the determinant: the four points lie in the plane x_k = a_k.
      if (u[k] == 0.0 && v[k] == 0.0 && w[k] == 0.0) return 0;
    }
    const auto triple = [&]<typename T>() -> T {
      const detail::Point3<T> pu{lift<T>(u[0]), lift<T>(u[1]), lift<T>(u[2])};
      const detail::Point3<T> pv{lift<T>(v[0]), lift<T>(v[1]), lift<T>(v[2])};
      const detail::Point3<T> pw{lift<T>(w[0]), lift<T>(w[1]), lift<T>(w[2])};
      return detail::dot(detail::cross(pu, pv), pw);
    };
    // The expansion on fixed arrays first (detail::triple_product_sign: the same sign as
    // exact_sign's, both being exact, without its heap and copies); exact_sign where a product
    // may not be exact. No dynamic filter before it: orient3d's static filter, which failed before
    // any call here, bounds the same products no looser.
    constexpr double kOrigin[3] = {0.0, 0.0, 0.0};
    bool unsafe = false;
    const int s = fixed_triple_sign(kOrigin, u, v, w, unsafe);
    if (!unsafe) return s;
    return detail::exact_sign(triple);
  }
  const auto general = [&]<typename T>() -> T {
    const auto pa = lift<T>(a);
    return detail::dot(detail::cross(lift<T>(b) - pa, lift<T>(c) - pa), lift<T>(d) - pa);
  };
  // Two points that coincide, or the four in one axis plane (a zero row, its differences exact
  // zeros however the others round): 0 without an expansion.
  if (b == c || b == d || c == d) return 0;
  for (Eigen::Index k = 0; k < 3; ++k) {
    if (b[k] == a[k] && c[k] == a[k] && d[k] == a[k]) return 0;
  }
  // As above, on the differences as two-component expansions (the dynamic filter on the
  // coordinates would bound the error by their magnitudes, looser than the static filter's bound
  // on the differences).
  bool unsafe = false;
  const int s = fixed_triple_sign(a.data(), b.data(), c.data(), d.data(), unsafe);
  if (!unsafe) return s;
  return detail::exact_sign(general);
}

}  // namespace skelcd::ccd
