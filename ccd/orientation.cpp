#include "ccd/orientation.hpp"

#include <array>

#include "ccd/detail/filtered.hpp"

namespace skelcd::ccd {

int orient3d_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  using detail::lift;
  using detail::expansion_steps::unsafe_leaf;
  // The differences b − a, c − a, d − a, each as an expansion of at most two components (Knuth's
  // two-difference; one when it is exact, none when it is zero; NaN and infinities leave two).
  // The coordinates of a real mesh mostly differ exactly in double (those read from 32-bit files
  // always do, unless their exponents are more than 28 apart): the determinant is then a
  // polynomial in three exact difference vectors, and what reaches this call — the filter could
  // not decide — is mostly an exact zero, often of corners in one axis plane (a flat cloth, a
  // mesh's flat parts).
  std::array<detail::Difference, 3> u, v, w;
  bool exact = true;
  for (std::size_t k = 0; k < 3; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    u[k] = detail::difference(b[i], a[i]);
    v[k] = detail::difference(c[i], a[i]);
    w[k] = detail::difference(d[i], a[i]);
    exact = exact && u[k].n <= 1 && v[k].n <= 1 && w[k].n <= 1;
  }
  // A zero row of the determinant (the four points in the plane x_k = a_k: those three
  // differences are exact zeros however the others round), or two points that coincide: 0
  // without an expansion.
  for (std::size_t k = 0; k < 3; ++k) {
    if (u[k].n == 0 && v[k].n == 0 && w[k].n == 0) return 0;
  }
  if (b == c || b == d || c == d) return 0;
  // The expansion on fixed arrays (detail::triple_product_sign: the same sign as exact_sign's,
  // both being exact, without its heap and copies), its leaves checked as exact_sign's Expansion
  // checks them — the exact differences where they are exact, else the coordinates; exact_sign
  // where a leaf or a product may not be exact. No dynamic filter before it: orient3d's static
  // filter, which failed before any call here, bounds the same products by the differences'
  // magnitudes, no looser (the dynamic filter on the coordinates would bound them by the
  // coordinates').
  const auto value = [](const detail::Difference& e) { return e.n == 0 ? 0.0 : e.c[0]; };
  bool unsafe = false;
  for (std::size_t k = 0; k < 3; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    unsafe =
        unsafe ||
        (exact ? unsafe_leaf(value(u[k])) || unsafe_leaf(value(v[k])) || unsafe_leaf(value(w[k]))
               : unsafe_leaf(a[i]) || unsafe_leaf(b[i]) || unsafe_leaf(c[i]) || unsafe_leaf(d[i]));
  }
  if (!unsafe) {
    const int s = detail::triple_product_sign(u.data(), v.data(), w.data(), unsafe);
    if (!unsafe) return s;
  }
  if (exact) {
    return detail::exact_sign([&]<typename T>() -> T {
      const detail::Point3<T> pu{lift<T>(value(u[0])), lift<T>(value(u[1])), lift<T>(value(u[2]))};
      const detail::Point3<T> pv{lift<T>(value(v[0])), lift<T>(value(v[1])), lift<T>(value(v[2]))};
      const detail::Point3<T> pw{lift<T>(value(w[0])), lift<T>(value(w[1])), lift<T>(value(w[2]))};
      return detail::dot(detail::cross(pu, pv), pw);
    });
  }
  return detail::exact_sign([&]<typename T>() -> T {
    const auto pa = lift<T>(a);
    return detail::dot(detail::cross(lift<T>(b) - pa, lift<T>(c) - pa), lift<T>(d) - pa);
  });
}

}  // namespace skelcd::ccd
