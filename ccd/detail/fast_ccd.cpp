// `fast` CCD: the textbook method in plain double (no guarantee; see fast_ccd.hpp).

#include "ccd/detail/fast_ccd.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Geometry>

namespace skelcd::ccd::detail {
namespace {

using Eigen::Vector3d;

Vector3d lerp(const Vector3d& x0, const Vector3d& x1, double t) { return x0 + t * (x1 - x0); }

// Power coefficients of det(X(t), Y(t), Z(t)) for linearly moving X, Y, Z (via the Bernstein form).
std::array<double, 4> det_cubic(const Vector3d& x0, const Vector3d& y0, const Vector3d& z0,
                                const Vector3d& x1, const Vector3d& y1, const Vector3d& z1) {
  const auto det = [](const Vector3d& x, const Vector3d& y, const Vector3d& z) { return x.dot(y.cross(z)); };
  const double b0 = det(x0, y0, z0);
  const double b1 = (det(x1, y0, z0) + det(x0, y1, z0) + det(x0, y0, z1)) / 3.0;
  const double b2 = (det(x0, y1, z1) + det(x1, y0, z1) + det(x1, y1, z0)) / 3.0;
  const double b3 = det(x1, y1, z1);
  return {b0, 3.0 * (b1 - b0), 3.0 * (b0 - 2.0 * b1 + b2), b3 - b0 + 3.0 * (b1 - b2)};
}

double eval(const std::array<double, 4>& c, double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }

// Roots of the cubic in [0,1], ascending: split at the derivative's roots, bisect sign changes.
int roots_in_unit_interval(const std::array<double, 4>& c, std::array<double, 3>& roots) {
  std::array<double, 4> breaks{0.0, 1.0, 1.0, 1.0};
  int nb = 1;
  const double qa = 3.0 * c[3];
  const double qb = 2.0 * c[2];
  const double qc = c[1];
  if (qa != 0.0) {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double r = std::sqrt(disc);
      double x1 = (-qb - r) / (2.0 * qa);
      double x2 = (-qb + r) / (2.0 * qa);
      if (x1 > x2) std::swap(x1, x2);
      if (x1 > 0.0 && x1 < 1.0) breaks[static_cast<std::size_t>(nb++)] = x1;
      if (x2 > 0.0 && x2 < 1.0 && x2 != x1) breaks[static_cast<std::size_t>(nb++)] = x2;
    }
  } else if (qb != 0.0) {
    const double x = -qc / qb;
    if (x > 0.0 && x < 1.0) breaks[static_cast<std::size_t>(nb++)] = x;
  }
  breaks[static_cast<std::size_t>(nb++)] = 1.0;
  int n = 0;
  for (int i = 0; i + 1 < nb; ++i) {
    double lo = breaks[static_cast<std::size_t>(i)];
    double hi = breaks[static_cast<std::size_t>(i) + 1];
    double flo = eval(c, lo);
    const double fhi = eval(c, hi);
    if (flo == 0.0) {
      if (n == 0 || roots[static_cast<std::size_t>(n) - 1] != lo) roots[static_cast<std::size_t>(n++)] = lo;
      continue;
    }
    if ((flo < 0.0) == (fhi < 0.0) || fhi == 0.0) continue;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      const double fm = eval(c, mid);
      if ((fm < 0.0) == (flo < 0.0)) {
        lo = mid;
        flo = fm;
      } else {
        hi = mid;
      }
    }
    if (n < 3) roots[static_cast<std::size_t>(n++)] = 0.5 * (lo + hi);
  }
  if (eval(c, 1.0) == 0.0 && n < 3 && (n == 0 || roots[static_cast<std::size_t>(n) - 1] != 1.0)) {
    roots[static_cast<std::size_t>(n++)] = 1.0;
  }
  return n;
}

bool point_in_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d v0 = b - a;
  const Vector3d v1 = c - a;
  const Vector3d v2 = p - a;
  const double d00 = v0.dot(v0);
  const double d01 = v0.dot(v1);
  const double d11 = v1.dot(v1);
  const double d20 = v2.dot(v0);
  const double d21 = v2.dot(v1);
  const double denom = d00 * d11 - d01 * d01;
  if (denom == 0.0) return false;
  const double v = (d11 * d20 - d01 * d21) / denom;
  const double w = (d00 * d21 - d01 * d20) / denom;
  return v >= 0.0 && w >= 0.0 && v + w <= 1.0;
}

bool segments_cross(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0, const Vector3d& q1) {
  const Vector3d d1 = p1 - p0;
  const Vector3d d2 = q1 - q0;
  const Vector3d r = p0 - q0;
  const double a = d1.dot(d1);
  const double e = d2.dot(d2);
  const double b = d1.dot(d2);
  const double c = d1.dot(r);
  const double f = d2.dot(r);
  const double denom = a * e - b * b;
  if (denom <= 0.0) return false;
  const double s = (b * f - c * e) / denom;
  const double t = (a * f - b * c) / denom;
  return s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0;
}

CcdResult hit_at(double t) { return {true, t, t, CcdStatus::contact}; }

}  // namespace

CcdResult vertex_face_ccd_fast(const VertexFaceQuery& q) {
  const auto c = det_cubic(q.v_t0 - q.f0_t0, q.f1_t0 - q.f0_t0, q.f2_t0 - q.f0_t0, q.v_t1 - q.f0_t1,
                           q.f1_t1 - q.f0_t1, q.f2_t1 - q.f0_t1);
  const auto inside_at = [&](double t) {
    return point_in_triangle(lerp(q.v_t0, q.v_t1, t), lerp(q.f0_t0, q.f0_t1, t), lerp(q.f1_t0, q.f1_t1, t),
                             lerp(q.f2_t0, q.f2_t1, t));
  };
  if (c[0] == 0.0 && c[1] == 0.0 && c[2] == 0.0 && c[3] == 0.0) {
    // Coplanar throughout: only the two ends are looked at.
    if (inside_at(0.0)) return hit_at(0.0);
    if (inside_at(1.0)) return hit_at(1.0);
    return {};
  }
  std::array<double, 3> roots{};
  const int n = roots_in_unit_interval(c, roots);
  for (int i = 0; i < n; ++i) {
    if (inside_at(roots[static_cast<std::size_t>(i)])) return hit_at(roots[static_cast<std::size_t>(i)]);
  }
  return {};
}

CcdResult edge_edge_ccd_fast(const EdgeEdgeQuery& q) {
  const auto c = det_cubic(q.eb0_t0 - q.ea0_t0, q.ea1_t0 - q.ea0_t0, q.eb1_t0 - q.eb0_t0, q.eb0_t1 - q.ea0_t1,
                           q.ea1_t1 - q.ea0_t1, q.eb1_t1 - q.eb0_t1);
  const auto cross_at = [&](double t) {
    return segments_cross(lerp(q.ea0_t0, q.ea0_t1, t), lerp(q.ea1_t0, q.ea1_t1, t), lerp(q.eb0_t0, q.eb0_t1, t),
                          lerp(q.eb1_t0, q.eb1_t1, t));
  };
  if (c[0] == 0.0 && c[1] == 0.0 && c[2] == 0.0 && c[3] == 0.0) {
    if (cross_at(0.0)) return hit_at(0.0);
    if (cross_at(1.0)) return hit_at(1.0);
    return {};
  }
  std::array<double, 3> roots{};
  const int n = roots_in_unit_interval(c, roots);
  for (int i = 0; i < n; ++i) {
    if (cross_at(roots[static_cast<std::size_t>(i)])) return hit_at(roots[static_cast<std::size_t>(i)]);
  }
  return {};
}

}  // namespace skelcd::ccd::detail
