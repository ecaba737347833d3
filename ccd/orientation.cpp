#include "ccd/orientation.hpp"

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
    return detail::exact_sign([&]<typename T>() -> T {
      const detail::Point3<T> pu{lift<T>(u[0]), lift<T>(u[1]), lift<T>(u[2])};
      const detail::Point3<T> pv{lift<T>(v[0]), lift<T>(v[1]), lift<T>(v[2])};
      const detail::Point3<T> pw{lift<T>(w[0]), lift<T>(w[1]), lift<T>(w[2])};
      return detail::dot(detail::cross(pu, pv), pw);
    });
  }
  return detail::exact_sign([&]<typename T>() -> T {
    const auto pa = lift<T>(a);
    return detail::dot(detail::cross(lift<T>(b) - pa, lift<T>(c) - pa), lift<T>(d) - pa);
  });
}

}  // namespace skelcd::ccd
