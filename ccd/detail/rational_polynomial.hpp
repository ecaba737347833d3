#pragma once
// Univariate polynomials over the rationals (GMP mpq_class) and the real-root machinery the exact
// CCD reference needs: gcd, square-free part, Sturm sequences, root isolation on [0,1], and the
// sign of a polynomial at an algebraic root. Everything here is exact; nothing is rounded.
// Internal to ccd/ (used by exact_ccd.cpp and the triangle-triangle exact fallback).

#include <array>
#include <utility>
#include <vector>

#include <gmpxx.h>

namespace skelcd::ccd::detail {

/// Coefficients low to high (c[0] + c[1] t + ...); no trailing zeros, so the zero polynomial is
/// empty and degree() == size() - 1.
class RationalPolynomial {
 public:
  RationalPolynomial() = default;
  explicit RationalPolynomial(std::vector<mpq_class> coefficients);
  /// The constant c.
  static RationalPolynomial constant(const mpq_class& c);
  /// c0 + c1 t.
  static RationalPolynomial linear(const mpq_class& c0, const mpq_class& c1);

  [[nodiscard]] bool is_zero() const { return c_.empty(); }
  /// -1 for the zero polynomial.
  [[nodiscard]] int degree() const { return static_cast<int>(c_.size()) - 1; }
  [[nodiscard]] const std::vector<mpq_class>& coefficients() const { return c_; }
  [[nodiscard]] const mpq_class& leading() const { return c_.back(); }

  [[nodiscard]] mpq_class operator()(const mpq_class& t) const;
  /// Sign (-1, 0, 1) of the value at t (double-interval filter first, exact when undecided).
  [[nodiscard]] int sign_at(const mpq_class& t) const;
  /// Sign of the value at every point of [lo, hi] when a double-interval evaluation proves it is
  /// one strict sign; 0 when it cannot (the value may still be nonzero).
  [[nodiscard]] int certain_sign_on(double lo, double hi) const;

  [[nodiscard]] RationalPolynomial derivative() const;

  friend RationalPolynomial operator+(const RationalPolynomial& a, const RationalPolynomial& b);
  friend RationalPolynomial operator-(const RationalPolynomial& a, const RationalPolynomial& b);
  friend RationalPolynomial operator*(const RationalPolynomial& a, const RationalPolynomial& b);
  friend RationalPolynomial operator-(const RationalPolynomial& a);

 private:
  void trim();
  std::vector<mpq_class> c_;
  // Coefficients rounded outward to doubles, built on first use by certain_sign_on.
  mutable std::vector<std::pair<double, double>> bounds_;
};

/// Remainder of a / b. @pre !b.is_zero()
[[nodiscard]] RationalPolynomial remainder(const RationalPolynomial& a, const RationalPolynomial& b);
/// Quotient of a / b. @pre !b.is_zero()
[[nodiscard]] RationalPolynomial quotient(const RationalPolynomial& a, const RationalPolynomial& b);
/// Monic greatest common divisor; gcd(0, 0) = 0.
[[nodiscard]] RationalPolynomial gcd(const RationalPolynomial& a, const RationalPolynomial& b);
/// The square-free part p / gcd(p, p'), monic; same roots as p, each simple. 0 for 0.
[[nodiscard]] RationalPolynomial square_free(const RationalPolynomial& p);

/// A real number t* in [0,1] given exactly: either a rational (lo == hi == t*) or the unique root of
/// the square-free polynomial `f` inside the open interval (lo, hi), where f(lo) f(hi) < 0.
struct RealRoot {
  bool rational = true;
  mpq_class lo, hi;
};

/// The roots of `f` in the closed interval [0,1], in increasing order, each isolated.
/// @pre f is square-free and not zero.
[[nodiscard]] std::vector<RealRoot> isolate_roots_in_unit_interval(const RationalPolynomial& f);

/// +1 / -1 when the Bernstein coefficients of f on [lo, hi] all have that strict sign (so f has
/// that sign on all of [lo, hi]); 0 otherwise (f may or may not vanish there).
[[nodiscard]] int bernstein_sign(const RationalPolynomial& f, const mpq_class& lo, const mpq_class& hi);

/// Exact sign queries at one point t* of [0,1]: a rational, or an isolated root of a square-free
/// polynomial. Isolating intervals are refined in place as needed.
class RootPoint {
 public:
  /// The rational point t.
  explicit RootPoint(const mpq_class& t);
  /// The root `root` of `f` (as returned by isolate_roots_in_unit_interval(f)).
  RootPoint(const RationalPolynomial& f, const RealRoot& root);

  /// Sign (-1, 0, 1) of g(t*).
  [[nodiscard]] int sign(const RationalPolynomial& g);
  /// Narrows the isolating interval to width <= width (no-op for a rational point).
  void refine(const mpq_class& width);
  /// t* in [lo, hi] (lo == hi for a rational point).
  [[nodiscard]] const mpq_class& lo() const { return root_.lo; }
  [[nodiscard]] const mpq_class& hi() const { return root_.hi; }

 private:
  void bisect();
  RationalPolynomial f_;
  RealRoot root_;
  int sign_f_lo_ = 0;               // sign of f at root_.lo (algebraic roots)
  double lo_d_ = 0.0, hi_d_ = 0.0;  // doubles with lo_d_ <= lo, hi <= hi_d_
};

/// A 3-vector of polynomials in t: a point or vector moving with time.
using PolynomialVector = std::array<RationalPolynomial, 3>;

[[nodiscard]] PolynomialVector operator+(const PolynomialVector& a, const PolynomialVector& b);
[[nodiscard]] PolynomialVector operator-(const PolynomialVector& a, const PolynomialVector& b);
[[nodiscard]] PolynomialVector cross(const PolynomialVector& a, const PolynomialVector& b);
[[nodiscard]] RationalPolynomial dot(const PolynomialVector& a, const PolynomialVector& b);
[[nodiscard]] bool is_zero(const PolynomialVector& a);

}  // namespace skelcd::ccd::detail
