#include "clustering/orientation_class.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ccd/polynomial_sign.hpp"
#include "culling/dop.hpp"

namespace skelcd::clustering {
namespace {

using ccd::BernsteinCubic;
using ccd::PolynomialSign;
using culling::next_down;
using culling::next_up;

/// Unit roundoff of double (round to nearest).
constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;

OrientationClass to_class(PolynomialSign s) {
  switch (s) {
    case PolynomialSign::positive: return OrientationClass::positive;
    case PolynomialSign::negative: return OrientationClass::negative;
    default: return OrientationClass::uncertain;
  }
}

BernsteinCubic orientation_cubic(
    const MovingTriangle& t,
    const Eigen::Vector3d& q_t0,
    const Eigen::Vector3d& q_t1) {
  return ccd::moving_orientation_cubic(
      {t.a_t0, t.b_t0, t.c_t0, q_t0, t.a_t1, t.b_t1, t.c_t1, q_t1});
}

/// (1 − σ)·f₁ + σ·f₂ for σ in [0,1], with an error bound that covers the stored coefficients'
/// errors and the rounding of this combination: |fl(w0·a + σ·b) − ((1−σ)a + σb)| is at most
/// u·(|a|) for w0 = fl(1 − σ), plus 3u·(|w0·a| + |σ·b|) for the products and the sum; bounded
/// here by 4u·(|a| + |b|) (1 + u terms absorbed by rounding the bound up).
BernsteinCubic blend(const BernsteinCubic& f1, const BernsteinCubic& f2, double sigma) {
  BernsteinCubic out;
  const double w0 = 1.0 - sigma;
  double scale = 0.0;
  for (std::size_t k = 0; k < 4; ++k) {
    out.coefficients[k] = w0 * f1.coefficients[k] + sigma * f2.coefficients[k];
    scale = std::max(scale, std::abs(f1.coefficients[k]) + std::abs(f2.coefficients[k]));
  }
  // w0 and sigma are both in [0,1]: the blended input errors are at most max(e1, e2).
  out.error = next_up(next_up(std::max(f1.error, f2.error) * (1.0 + 4 * kUnit)) +
                      next_up(8 * kUnit * scale));
  return out;
}

/// Bernstein coefficients (degree 2, on [0,1]) of u(t)·v(t) for u, v linear in t, their rounding
/// error bound, and the range they enclose: [min − err, max + err] contains u(t)·v(t) exactly for
/// every t in [0,1] (convex hull property), where u_t0 … v_t1 are the *exact* differences whose
/// rounded values are passed.
struct QuadraticRange {
  double lo = 0.0;
  double hi = 0.0;
};

QuadraticRange product_range(
    const Eigen::Vector3d& u0,
    const Eigen::Vector3d& u1,
    const Eigen::Vector3d& v0,
    const Eigen::Vector3d& v1) {
  const double b0 = u0.dot(v0);
  const double b1 = 0.5 * (u0.dot(v1) + u1.dot(v0));
  const double b2 = u1.dot(v1);
  // Each input component is a rounded difference, within u·|value| of the exact one (so each
  // product within (2u + u²)·|product|); each dot product adds γ₃ and b1 one more addition. 16u
  // times the largest sum of |products| covers all of it.
  const double m = std::max(
      {u0.cwiseAbs().dot(v0.cwiseAbs()), u0.cwiseAbs().dot(v1.cwiseAbs()),
       u1.cwiseAbs().dot(v0.cwiseAbs()), u1.cwiseAbs().dot(v1.cwiseAbs())});
  const double err = next_up(16 * kUnit * m);
  return {next_down(std::min({b0, b1, b2}) - err), next_up(std::max({b0, b1, b2}) + err)};
}

/// Lower / upper bound of n / d for n in [n_lo, n_hi], d in [d_lo, d_hi], d_lo > 0.
double quotient_lo(double n_lo, double d_lo, double d_hi) {
  return next_down(n_lo >= 0.0 ? n_lo / d_hi : n_lo / d_lo);
}
double quotient_hi(double n_hi, double d_lo, double d_hi) {
  return next_up(n_hi >= 0.0 ? n_hi / d_lo : n_hi / d_hi);
}

}  // namespace

std::string_view to_string(OrientationClass c) {
  switch (c) {
    case OrientationClass::positive: return "positive";
    case OrientationClass::negative: return "negative";
    default: return "uncertain";
  }
}

namespace {

/// cubic_sign(orientation_cubic(t, q_t0, q_t1)), screened first (ccd::moving_orientation_sign).
PolynomialSign orientation_sign(
    const MovingTriangle& t, const Eigen::Vector3d& q_t0, const Eigen::Vector3d& q_t1) {
  return ccd::moving_orientation_sign({t.a_t0, t.b_t0, t.c_t0, q_t0, t.a_t1, t.b_t1, t.c_t1, q_t1});
}

}  // namespace

OrientationClass classify(const MovingTriangle& triangle, const MovingPoint& observer) {
  return to_class(orientation_sign(triangle, observer.t0, observer.t1));
}

namespace {

/// screen_classes_x4 for an observer point moving from q_t0 to q_t1 (three doubles each).
ScreenedClasses screened_from(
    const double* q_t0,
    const double* q_t1,
    const ccd::FaceCorners& corners_t0,
    const ccd::FaceCorners& corners_t1) {
  const ccd::CoplanarityScreens screens =
      ccd::point_faces_screen_x4(q_t0, q_t1, corners_t0, corners_t1);
  ScreenedClasses out;
  out.settled = screens.apart;
  for (std::size_t lane = 0; lane < 4; ++lane) {
    // Settled: all four coefficients of one sign; classify's cubic is this one negated.
    out.classes[lane] = screens.coefficients[lane][0] < 0.0 ? OrientationClass::positive
                                                            : OrientationClass::negative;
  }
  return out;
}

}  // namespace

ScreenedClasses screen_classes_x4(
    const ccd::FaceCorners& corners_t0,
    const ccd::FaceCorners& corners_t1,
    const MovingPoint& observer) {
  return screened_from(observer.t0.data(), observer.t1.data(), corners_t0, corners_t1);
}

ScreenedClasses screen_classes_x4(
    const ccd::FaceCorners& corners_t0,
    const ccd::FaceCorners& corners_t1,
    const MovingSegment& observer) {
  // classify's two endpoint cubics: one sign for both and it is the class (no blending needed).
  const ScreenedClasses one =
      screened_from(observer.q1_t0.data(), observer.q1_t1.data(), corners_t0, corners_t1);
  const ScreenedClasses two =
      screened_from(observer.q2_t0.data(), observer.q2_t1.data(), corners_t0, corners_t1);
  ScreenedClasses out;
  out.settled = one.settled & two.settled;
  for (std::size_t lane = 0; lane < 4; ++lane) {
    out.classes[lane] = one.classes[lane];
    if (one.classes[lane] != two.classes[lane]) out.settled &= ~(1u << lane);
  }
  return out;
}

ProjectionRange projection_range(const MovingTriangle& t, const MovingSegment& s) {
  // σ(x, t) = clamp(N(t) / D(t)) with N = (x(t) − q1(t)) · d(t), D = |d(t)|², d = q2 − q1: both
  // quadratics in t. Enclose D first; if it may vanish the segment may degenerate to a point in
  // the interval and every σ in [0,1] is possible.
  const Eigen::Vector3d d0 = s.q2_t0 - s.q1_t0;
  const Eigen::Vector3d d1 = s.q2_t1 - s.q1_t1;
  const QuadraticRange D = product_range(d0, d1, d0, d1);
  if (!(D.lo > 0.0) || !std::isfinite(D.hi)) return {0.0, 1.0};
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  const std::array<std::array<const Eigen::Vector3d*, 2>, 3> corners{
      {{&t.a_t0, &t.a_t1}, {&t.b_t0, &t.b_t1}, {&t.c_t0, &t.c_t1}}};
  for (const auto& c : corners) {
    const Eigen::Vector3d u0 = *c[0] - s.q1_t0;
    const Eigen::Vector3d u1 = *c[1] - s.q1_t1;
    const QuadraticRange N = product_range(u0, u1, d0, d1);
    lo = std::min(lo, quotient_lo(N.lo, D.lo, D.hi));
    hi = std::max(hi, quotient_hi(N.hi, D.lo, D.hi));
  }
  if (!(lo <= hi)) return {0.0, 1.0};  // NaN somewhere
  return {std::clamp(lo, 0.0, 1.0), std::clamp(hi, 0.0, 1.0)};
}

namespace {

/// classify's answer for a segment observer whose end cubics do not settle it alone: only σ in
/// the proven enclosure [lo, hi] matters; h is affine in σ, so the sign at both ends of the
/// enclosure decides it.
OrientationClass classify_blended(const MovingTriangle& triangle, const MovingSegment& observer) {
  const BernsteinCubic f1 = orientation_cubic(triangle, observer.q1_t0, observer.q1_t1);
  const BernsteinCubic f2 = orientation_cubic(triangle, observer.q2_t0, observer.q2_t1);
  const ProjectionRange r = projection_range(triangle, observer);
  const PolynomialSign lo = ccd::cubic_sign(blend(f1, f2, r.lo));
  if (lo == PolynomialSign::uncertain) return OrientationClass::uncertain;
  if (r.hi == r.lo) return to_class(lo);
  const PolynomialSign hi = ccd::cubic_sign(blend(f1, f2, r.hi));
  return lo == hi ? to_class(lo) : OrientationClass::uncertain;
}

}  // namespace

OrientationClass classify(const MovingTriangle& triangle, const MovingSegment& observer) {
  // f₁, f₂: the cubics of the two endpoints. At any instant and any point x of the triangle,
  // h(x) = (1 − σ(x))·f₁ + σ(x)·f₂ with σ(x) in [0,1] (docs/radial-view.md), so two cubics of one
  // proven sign settle the class for every σ at once.
  const PolynomialSign s1 = orientation_sign(triangle, observer.q1_t0, observer.q1_t1);
  if (s1 == PolynomialSign::uncertain) return classify_blended(triangle, observer);
  const PolynomialSign s2 = orientation_sign(triangle, observer.q2_t0, observer.q2_t1);
  if (s1 == s2) return to_class(s1);
  return classify_blended(triangle, observer);
}

}  // namespace skelcd::clustering
