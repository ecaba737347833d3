#pragma once
// Exact signs of polynomial expressions in double inputs: evaluate once in floating point while
// tracking a proven error bound (a dynamic filter); only when the sign is not certain, evaluate
// again exactly, as a floating-point expansion (or, near underflow or overflow, in GMP rationals).
// A predicate is written once as a template over the number type.
//
//   const int s = exact_sign([&]<typename T>() { return orient3d(lift<T>(a), ...); });
//
// The bound is the rounding lemma of float_bounds.hpp: with k the rounding count of the expression
// tree (leaf 0; + and -: max + 1; *: sum + 1) and P the permanent (the same tree on absolute values
// with - as +), |computed - exact| <= fl((k + 1) eps P_hat) when no product underflows; a possible
// underflow or overflow sends the predicate to the exact path.

#include <gmpxx.h>

#include <Eigen/Core>
#include <algorithm>
#include <cfloat>
#include <cmath>

#include "ccd/detail/expansion.hpp"
#include "ccd/detail/float_bounds.hpp"

namespace skelcd::ccd::detail {

/// A double carrying the data of its own error bound.
struct Filtered {
  double value = 0.0;
  double permanent = 0.0;
  int roundings = 0;
  bool unsafe = false;  ///< a product may have underflowed, or a value is not finite

  static Filtered leaf(double x) { return {x, std::abs(x), 0, !std::isfinite(x)}; }
};

inline Filtered operator+(const Filtered& a, const Filtered& b) {
  return {a.value + b.value, a.permanent + b.permanent, std::max(a.roundings, b.roundings) + 1,
          a.unsafe || b.unsafe};
}
inline Filtered operator-(const Filtered& a, const Filtered& b) {
  return {a.value - b.value, a.permanent + b.permanent, std::max(a.roundings, b.roundings) + 1,
          a.unsafe || b.unsafe};
}
inline Filtered operator*(const Filtered& a, const Filtered& b) {
  const double v = a.value * b.value;
  const double p = a.permanent * b.permanent;
  // Underflow: the exact product of two nonzero values is below the normal range (its rounded value
  // is then at most 2 DBL_MIN). Checked on both the value and the permanent.
  const bool underflow = (a.value != 0.0 && b.value != 0.0 && std::abs(v) <= 2 * DBL_MIN) ||
                         (a.permanent != 0.0 && b.permanent != 0.0 && p <= 2 * DBL_MIN);
  return {v, p, a.roundings + b.roundings + 1, a.unsafe || b.unsafe || underflow};
}

/// Sign of f in {-1, 0, 1} when certain, 2 when the filter cannot decide.
inline int filtered_sign(const Filtered& f) {
  if (f.unsafe || !std::isfinite(f.value) || !std::isfinite(f.permanent)) return 2;
  if (f.permanent == 0.0) return 0;  // every term is exactly zero
  const double err = rounding_bound(f.roundings, f.permanent);
  if (f.value > err) return 1;
  if (-f.value > err) return -1;
  return 2;
}

template <typename T>
T lift(double x);
template <>
inline Filtered lift<Filtered>(double x) {
  return Filtered::leaf(x);
}
template <>
inline Expansion lift<Expansion>(double x) {
  return Expansion(x);
}
template <>
inline mpq_class lift<mpq_class>(double x) {
  return mpq_class(x);
}

/// A point with coordinates of number type T.
template <typename T>
struct Point3 {
  T x, y, z;
};

template <typename T>
Point3<T> lift(const Eigen::Vector3d& p) {
  return {lift<T>(p.x()), lift<T>(p.y()), lift<T>(p.z())};
}

template <typename T>
Point3<T> operator-(const Point3<T>& a, const Point3<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

template <typename T>
Point3<T> cross(const Point3<T>& a, const Point3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

template <typename T>
T dot(const Point3<T>& a, const Point3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <typename T>
T component(const Point3<T>& a, int k) {
  return k == 0 ? a.x : (k == 1 ? a.y : a.z);
}

inline int rational_sign(const mpq_class& q) {
  const int s = mpq_sgn(q.get_mpq_t());
  return (s > 0) - (s < 0);
}

/// Exact sign of the expression `predicate` builds: filtered double first; when undecided, an
/// exact floating-point expansion (expansion.hpp); GMP rationals only when the expansion could have
/// underflowed or overflowed.
/// @param predicate a generic lambda `[&]<typename T>() -> T`, evaluated with T = Filtered and, if
/// needed, T = Expansion and T = mpq_class.
template <typename Predicate>
int exact_sign(const Predicate& predicate) {
  const int s = filtered_sign(predicate.template operator()<Filtered>());
  if (s != 2) return s;
  const Expansion e = predicate.template operator()<Expansion>();
  if (!e.unsafe()) return e.sign();
  return rational_sign(mpq_class(predicate.template operator()<mpq_class>()));
}

}  // namespace skelcd::ccd::detail
