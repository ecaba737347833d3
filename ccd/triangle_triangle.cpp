// Exact triangle-triangle intersection (docs/ccd.md, "Triangle-triangle DCD").
//
// Two closed triangles meet iff an edge of one meets the other triangle: if A and B share a point,
// A n B is a convex set whose extreme points lie on the boundary of A or of B (and a zero-area
// triangle is the union of its edges). Every decision is the exact sign of a polynomial in the
// input coordinates (detail/filtered.hpp: filtered double, GMP fallback).
//
// Shared corners: with one shared vertex s and both triangles non-degenerate, A n B is more than
// {s} iff the edge of A opposite s meets B or the edge of B opposite s meets A; with a shared edge,
// iff the triangles are coplanar and lie on the same side of it. A degenerate triangle sharing
// corners with a solid one is decided in the solid's plane (flat_meets_beyond_shared), two
// degenerate ones on their common line (flats_meet_beyond_shared). The shared part is the hull of
// the distinct corners of b named: a map naming one twice ({1, 1, -1}, a degenerate a repeating a
// mesh vertex) shares a vertex, and is read as such (degenerate_shared_intersect).
//
// The common cases first, with the same exact answers (issue 14): each triangle's plane normal is
// computed once in doubles, with the permanents of its components, and serves as a static filter
// for both the triangle's degeneracy and the orientation of each corner of the other triangle
// against its plane (a dot product per corner, no call). Pairs without shared corners that both
// planes fail to separate, with no corner on the other's plane, are decided by Guigue and
// Devillers' two orientations (2003, section 3); every other case takes the general path below
// with the plane orientations already known.

#include "ccd/triangle_triangle.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include "ccd/detail/filtered.hpp"
#include "ccd/orientation.hpp"

namespace skelcd::ccd {
namespace {

using detail::cross;
using detail::dot;
using detail::exact_sign;
using detail::lift;
using Eigen::Vector3d;

// Sign of ((b - a) x (c - a))[k].
int cross_sign(const Vector3d& a, const Vector3d& b, const Vector3d& c, int k) {
  return exact_sign([&]<typename T>() -> T {
    const auto pa = lift<T>(a);
    return detail::component(cross(lift<T>(b) - pa, lift<T>(c) - pa), k);
  });
}

// (b - a) x (c - a) == 0: the three points are collinear (or coincide). One component that the
// static filter finds nonzero settles it (almost every triangle); the exact signs otherwise.
bool collinear(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  constexpr int kAxes[3][2] = {{1, 2}, {2, 0}, {0, 1}};  // components x, y, z of the cross product
  for (const auto& axes : kAxes) {
    // The static filter returns ±1 (certain) or kUndecided, never 0.
    if (detail::cross_component_static(a, b, c, axes[0], axes[1]) != detail::kUndecided) {
      return false;
    }
  }
  return cross_sign(a, b, c, 0) == 0 && cross_sign(a, b, c, 1) == 0 && cross_sign(a, b, c, 2) == 0;
}

// p on the closed segment [a, b] (a point when a == b).
bool on_segment(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  if (!collinear(a, b, p)) return false;
  return exact_sign([&]<typename T>() -> T {
           const auto pp = lift<T>(p);
           return dot(pp - lift<T>(a), pp - lift<T>(b));
         }) <= 0;
}

// Closed segments [p, q] and [r, s], known to be coplanar, share a point.
bool coplanar_segments_intersect(const Vector3d& p, const Vector3d& q, const Vector3d& r, const Vector3d& s) {
  bool parallel = true;
  for (int k = 0; k < 3 && parallel; ++k) {
    parallel = exact_sign([&]<typename T>() -> T {
                 return detail::component(cross(lift<T>(q) - lift<T>(p), lift<T>(s) - lift<T>(r)), k);
               }) == 0;
  }
  if (parallel) {
    // Parallel (or a zero-length segment): they meet iff an endpoint of one is on the other.
    return on_segment(p, r, s) || on_segment(q, r, s) || on_segment(r, p, q) || on_segment(s, p, q);
  }
  // The lines meet at p + (u / nn)(q - p) = r + (v / nn)(s - r), n = d1 x d2, nn = n.n > 0.
  const auto u_sign = [&](bool complement) {
    return exact_sign([&]<typename T>() -> T {
      const auto d1 = lift<T>(q) - lift<T>(p);
      const auto d2 = lift<T>(s) - lift<T>(r);
      const auto w = lift<T>(r) - lift<T>(p);
      const auto n = cross(d1, d2);
      const T u = dot(cross(w, d2), n);
      return complement ? T(dot(n, n) - u) : u;
    });
  };
  const auto v_sign = [&](bool complement) {
    return exact_sign([&]<typename T>() -> T {
      const auto d1 = lift<T>(q) - lift<T>(p);
      const auto d2 = lift<T>(s) - lift<T>(r);
      const auto w = lift<T>(r) - lift<T>(p);
      const auto n = cross(d1, d2);
      const T v = dot(cross(w, d1), n);
      return complement ? T(dot(n, n) - v) : v;
    });
  };
  return u_sign(false) >= 0 && u_sign(true) >= 0 && v_sign(false) >= 0 && v_sign(true) >= 0;
}

// Closed segments [p, q] and [r, s] in space share a point.
bool segments_intersect(const Vector3d& p, const Vector3d& q, const Vector3d& r, const Vector3d& s) {
  if (orient3d(p, q, r, s) != 0) return false;
  return coplanar_segments_intersect(p, q, r, s);
}

struct Triangle {
  const Vector3d& a;
  const Vector3d& b;
  const Vector3d& c;
  bool degenerate;
};

// --- the coplanar case in the plane of one coordinate projection ---------------------------------
// Points known to lie in the plane of a non-degenerate triangle are compared in the projection
// that drops a coordinate k along which the triangle's normal has a nonzero component: it is
// injective on that plane, so every answer there is the answer in space, and 2D orientations do
// not run into the exact zeros that a plane parallel to a coordinate plane gives 3D cross
// products (which sent such pairs to rational arithmetic).

/// orient2d where the static filter could not decide, out of line (inlined, its arrays would cost
/// its callers' frames on every call). As orient3d_exact (ccd/orientation.cpp): two coincident
/// points answer 0; otherwise the expansion on fixed arrays, exact_sign (which may end in GMP) only
/// where a leaf or a product leaves the range where its steps are exact. No dynamic filter: the
/// static one failed with a bound on the differences, no looser than the dynamic one's on the
/// coordinates.
[[gnu::noinline]] int orient2d_exact(
    const Vector3d& a, const Vector3d& b, const Vector3d& c, int i, int j) {
  if ((a[i] == b[i] && a[j] == b[j]) || (a[i] == c[i] && a[j] == c[j]) ||
      (b[i] == c[i] && b[j] == c[j])) {
    return 0;
  }
  using detail::expansion_steps::unsafe_leaf;
  bool unsafe = unsafe_leaf(a[i]) || unsafe_leaf(a[j]) || unsafe_leaf(b[i]) || unsafe_leaf(b[j]) ||
                unsafe_leaf(c[i]) || unsafe_leaf(c[j]);
  if (!unsafe) {
    const int e = detail::cross2_sign(
        detail::difference(b[i], a[i]),
        detail::difference(b[j], a[j]),
        detail::difference(c[i], a[i]),
        detail::difference(c[j], a[j]),
        unsafe);
    if (!unsafe) return e;
  }
  return exact_sign([&]<typename T>() -> T {
    const T ai = lift<T>(a[i]), aj = lift<T>(a[j]);
    return T(
        (lift<T>(b[i]) - ai) * (lift<T>(c[j]) - aj) - (lift<T>(b[j]) - aj) * (lift<T>(c[i]) - ai));
  });
}

// Sign of the 2D orientation of (a, b, c) in coordinates (i, j): static filter, then exact.
int orient2d(const Vector3d& a, const Vector3d& b, const Vector3d& c, int i, int j) {
  const int s = detail::cross_component_static(a, b, c, i, j);
  if (s != detail::kUndecided) return s;
  return orient2d_exact(a, b, c, i, j);
}

struct Projection {
  int i = 0;
  int j = 1;
  int sign = 0;  ///< the triangle's orientation in (i, j), never 0
};

// A coordinate projection in which the non-degenerate triangle t keeps a nonzero area.
Projection projection_of(const Triangle& t) {
  constexpr int kAxes[3][2] = {{1, 2}, {2, 0}, {0, 1}};
  for (const auto& axes : kAxes) {  // the filter decides almost every triangle on one of them
    const int s = detail::cross_component_static(t.a, t.b, t.c, axes[0], axes[1]);
    if (s != detail::kUndecided) return {axes[0], axes[1], s};
  }
  for (const auto& axes : kAxes) {
    const int s = orient2d(t.a, t.b, t.c, axes[0], axes[1]);
    if (s != 0) return {axes[0], axes[1], s};
  }
  assert(false && "projection_of needs a non-degenerate triangle");
  return {};
}

// p, collinear with a and b in the projection, lies on the closed segment [a, b] there.
bool between_2d(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Projection& pr) {
  const auto within = [&](int k) {
    return std::min(a[k], b[k]) <= p[k] && p[k] <= std::max(a[k], b[k]);
  };
  return within(pr.i) && within(pr.j);
}

// Closed segments [p, q] and [a, b] meet in the projection.
bool segments_meet_2d(
    const Vector3d& p,
    const Vector3d& q,
    const Vector3d& a,
    const Vector3d& b,
    const Projection& pr) {
  const int o1 = orient2d(p, q, a, pr.i, pr.j);
  const int o2 = orient2d(p, q, b, pr.i, pr.j);
  const int o3 = orient2d(a, b, p, pr.i, pr.j);
  const int o4 = orient2d(a, b, q, pr.i, pr.j);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && between_2d(a, p, q, pr)) || (o2 == 0 && between_2d(b, p, q, pr)) ||
         (o3 == 0 && between_2d(p, a, b, pr)) || (o4 == 0 && between_2d(q, a, b, pr));
}

// p in the closed triangle t in the projection.
bool in_triangle_2d(const Vector3d& p, const Triangle& t, const Projection& pr) {
  return orient2d(t.a, t.b, p, pr.i, pr.j) * pr.sign >= 0 &&
         orient2d(t.b, t.c, p, pr.i, pr.j) * pr.sign >= 0 &&
         orient2d(t.c, t.a, p, pr.i, pr.j) * pr.sign >= 0;
}

// Closed segment [p, q], lying in the plane of the non-degenerate triangle t, meets t.
bool coplanar_segment_triangle(const Vector3d& p, const Vector3d& q, const Triangle& t) {
  const Projection pr = projection_of(t);
  return in_triangle_2d(p, t, pr) || in_triangle_2d(q, t, pr) ||
         segments_meet_2d(p, q, t.a, t.b, pr) || segments_meet_2d(p, q, t.b, t.c, pr) ||
         segments_meet_2d(p, q, t.c, t.a, pr);
}

// --- static filters on the triangles' planes (the common cases) ---------------------------------
// n = (p1 - p0) x (p2 - p0) in doubles: each component a 2x2 minor of the rounded edge vectors,
// with its permanent m_k = |u_i v_j| + |u_j v_i|. Computed once per triangle, it decides both the
// triangle's degeneracy and, by a dot product, the side of every corner of the other triangle.
// The bounds assume IEEE double arithmetic without contraction into fused multiply-adds (as the
// rest of ccd/; see detail/float_bounds.hpp).

/// Below this a minor's permanent may hide an underflowed product (whose absolute error, 2^-1075,
/// is then not within the slack of the relative bounds).
constexpr double kMinorFloor = 0x1p-960;
/// Minors whose permanents are all at least this make the side filter's underflow guard a single
/// comparison (see sides).
constexpr double kLargeMinor = 0x1p-900;

/// Every permanent m_k >= kLargeMinor (three compares, no branches: the flag is asked per pair).
inline bool large_minors(double m0, double m1, double m2) {
  return static_cast<bool>((m0 >= kLargeMinor) & (m1 >= kLargeMinor) & (m2 >= kLargeMinor));
}

struct Plane {
  const Vector3d* p0;
  const Vector3d* p1;
  const Vector3d* p2;
  double n[3];
  double m[3];
  bool large_minors;  ///< every m_k >= kLargeMinor
};

/// The minors of (p1 - p0) x (p2 - p0) and their permanents.
inline Plane plane_of(const Vector3d& p0, const Vector3d& p1, const Vector3d& p2) {
  const double ux = p1.x() - p0.x(), uy = p1.y() - p0.y(), uz = p1.z() - p0.z();
  const double vx = p2.x() - p0.x(), vy = p2.y() - p0.y(), vz = p2.z() - p0.z();
  const double yz = uy * vz, zy = uz * vy;
  const double zx = uz * vx, xz = ux * vz;
  const double xy = ux * vy, yx = uy * vx;
  const double m0 = std::abs(yz) + std::abs(zy);
  const double m1 = std::abs(zx) + std::abs(xz);
  const double m2 = std::abs(xy) + std::abs(yx);
  return {&p0, &p1, &p2, {yz - zy, zx - xz, xy - yx}, {m0, m1, m2}, large_minors(m0, m1, m2)};
}

/// The same Plane from its cached minors and permanents (triangle_plane of the same corners).
inline Plane plane_from(
    const TrianglePlane& t, const Vector3d& p0, const Vector3d& p1, const Vector3d& p2) {
  return {
      &p0,
      &p1,
      &p2,
      {t.n[0], t.n[1], t.n[2]},
      {t.m[0], t.m[1], t.m[2]},
      large_minors(t.m[0], t.m[1], t.m[2])};
}

/// Some n_k is certainly nonzero: the triangle is not degenerate. Shewchuk's orient2d bound on
/// each component, (3 + 16 eps) eps m_k, taken as 4 eps m_k: the slack (about eps m_k) covers the
/// two products' underflow (2^-1074) once m_k >= kMinorFloor. These are the components collinear()
/// screens with the same filter. Branch-free (& and |).
inline bool certified_solid(const Plane& pl) {
  bool solid = false;
  for (int k = 0; k < 3; ++k) {
    const double m = pl.m[k];
    solid |= (m >= kMinorFloor) & (m < std::numeric_limits<double>::infinity()) &
             (std::abs(pl.n[k]) > 0x1p-51 * m);
  }
  return solid;
}

/// The triangle of pl is degenerate, exactly (the filter first).
inline bool degenerate(const Plane& pl) {
  return !certified_solid(pl) && collinear(*pl.p0, *pl.p1, *pl.p2);
}

/// orient3d(p0, p1, p2, p) = sign of n . (p - p0), certain, or kUndecided. The determinant of the
/// rounded differences expanded along the row of w = p - p0 has the shape of Shewchuk's static
/// orient3d filter (a leaf times a 2x2 minor, three terms summed), whose bound is
/// (7 + 56 eps) eps P, P = sum |w_k| m_k; we take 8 eps P. Underflowed products add at most
/// 2^-1073 (|w|_1 + 1) (each minor's 2^-1074 times |w_k|, and the three outer products), which
/// the guard keeps under 2^-104 P, well inside the slack; a non-finite P leaves it undecided.
inline int side_static(const Plane& pl, const Vector3d& p) {
  const double wx = p.x() - pl.p0->x(), wy = p.y() - pl.p0->y(), wz = p.z() - pl.p0->z();
  const double det = pl.n[0] * wx + pl.n[1] * wy + pl.n[2] * wz;
  const double ax = std::abs(wx), ay = std::abs(wy), az = std::abs(wz);
  const double permanent = pl.m[0] * ax + pl.m[1] * ay + pl.m[2] * az;
  if (!(permanent < std::numeric_limits<double>::infinity()) ||
      !(ax + ay + az + 1.0 <= permanent * 0x1p969)) {
    return detail::kUndecided;
  }
  const double bound = 0x1p-50 * permanent;  // >= 2^-1019: exact, never subnormal
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return detail::kUndecided;
}

/// orient3d(p0, p1, p2, p), exact: the filter above, then the exact predicate.
inline int side(const Plane& pl, const Vector3d& p) {
  const int s = side_static(pl, p);
  return s != detail::kUndecided ? s : orient3d_exact(*pl.p0, *pl.p1, *pl.p2, p);
}

/// The filter of side_static on three points without branches; bit i of the result is set where
/// o[i] is not certain. With every m_k >= 2^-900 a minor's underflow (2^-1074) is under 2^-174
/// m_k, so the guard reduces to P >= 2^-969 (for the three outer products, and a normal bound).
/// On raw coordinates (p0: the plane's first corner), so that a caller without a Plane can ask.
template <bool kLargeMinors>
inline unsigned sides_static(
    const double n[3], const double m[3], const double* p0, const double* const p[3], int o[3]) {
  unsigned undecided = 0;
  for (int i = 0; i < 3; ++i) {
    const double* x = p[i];
    const double wx = x[0] - p0[0], wy = x[1] - p0[1], wz = x[2] - p0[2];
    const double det = n[0] * wx + n[1] * wy + n[2] * wz;
    const double ax = std::abs(wx), ay = std::abs(wy), az = std::abs(wz);
    const double permanent = m[0] * ax + m[1] * ay + m[2] * az;
    bool guarded;
    if constexpr (kLargeMinors) {
      guarded = (permanent >= 0x1p-969) & (permanent < std::numeric_limits<double>::infinity());
    } else {
      guarded = (permanent < std::numeric_limits<double>::infinity()) &
                (ax + ay + az + 1.0 <= permanent * 0x1p969);
    }
    const double bound = 0x1p-50 * permanent;
    const int sign = static_cast<int>(det > bound) - static_cast<int>(-det > bound);
    o[i] = sign;
    undecided |= static_cast<unsigned>(!guarded | (sign == 0)) << i;
  }
  return undecided;
}

/// sides_static of a Plane: bit i set where o[i] is not certain.
inline unsigned sides_static(const Plane& pl, const Vector3d* const p[3], int o[3]) {
  const double* const q[3] = {p[0]->data(), p[1]->data(), p[2]->data()};
  return pl.large_minors ? sides_static<true>(pl.n, pl.m, pl.p0->data(), q, o)
                         : sides_static<false>(pl.n, pl.m, pl.p0->data(), q, o);
}

/// o[i] = the exact orient3d where sides_static left it undecided (rare: out of line).
[[gnu::noinline]] void settle_sides(
    const Plane& pl, const Vector3d* const p[3], unsigned undecided, int o[3]) {
  for (int i = 0; i < 3; ++i) {
    if (undecided & (1u << i)) o[i] = orient3d_exact(*pl.p0, *pl.p1, *pl.p2, *p[i]);
  }
}

/// The three sides(pl, *p[i]), exact.
inline void sides(const Plane& pl, const Vector3d* const p[3], int o[3]) {
  const unsigned undecided = sides_static(pl, p, o);
  if (undecided != 0) settle_sides(pl, p, undecided, o);
}

/// orient3d(a, b, c, d), exact, through the same filter.
inline int orient3d_filtered(
    const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return side(plane_of(a, b, c), d);
}

/// orient3d(p, q, c[e], c[e + 1]) for the three edges e of the triangle (c[0], c[1], c[2]), exact:
/// the same filter, with d = q - p the expanded row and the minors of (c[e] - p) x (c[e + 1] - p);
/// the exact predicate for any it leaves undecided.
inline void edge_sides(const Vector3d& p, const Vector3d& q, const Vector3d* const c[3], int o[3]) {
  const double dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
  const double ax = std::abs(dx), ay = std::abs(dy), az = std::abs(dz);
  const double guard = ax + ay + az + 1.0;
  double w[3][3];
  for (int i = 0; i < 3; ++i) {
    w[i][0] = c[i]->x() - p.x();
    w[i][1] = c[i]->y() - p.y();
    w[i][2] = c[i]->z() - p.z();
  }
  bool undecided[3];
  bool any = false;
  for (int e = 0; e < 3; ++e) {
    const double* u = w[e];
    const double* v = w[(e + 1) % 3];
    const double yz = u[1] * v[2], zy = u[2] * v[1];
    const double zx = u[2] * v[0], xz = u[0] * v[2];
    const double xy = u[0] * v[1], yx = u[1] * v[0];
    const double det = (yz - zy) * dx + (zx - xz) * dy + (xy - yx) * dz;
    const double permanent = (std::abs(yz) + std::abs(zy)) * ax +
                             (std::abs(zx) + std::abs(xz)) * ay +
                             (std::abs(xy) + std::abs(yx)) * az;
    const bool guarded =
        (permanent < std::numeric_limits<double>::infinity()) & (guard <= permanent * 0x1p969);
    const double bound = 0x1p-50 * permanent;
    const int sign = static_cast<int>(det > bound) - static_cast<int>(-det > bound);
    undecided[e] = !guarded | (sign == 0);
    o[e] = sign;
    any |= undecided[e];
  }
  if (any) {
    for (int e = 0; e < 3; ++e) {
      if (undecided[e]) o[e] = orient3d_exact(p, q, *c[e], *c[(e + 1) % 3]);
    }
  }
}

// Closed segment [p, q] meets the closed triangle t; o_p, o_q = orient3d(t.a, t.b, t.c, p / q).
bool segment_triangle(const Vector3d& p, const Vector3d& q, const Triangle& t, int o_p, int o_q) {
  if (t.degenerate) {
    // A zero-area triangle is the union of its edges.
    return segments_intersect(p, q, t.a, t.b) || segments_intersect(p, q, t.b, t.c) ||
           segments_intersect(p, q, t.c, t.a);
  }
  if (o_p * o_q > 0) return false;  // both endpoints strictly on one side of the plane
  if (o_p == 0 && o_q == 0) return coplanar_segment_triangle(p, q, t);  // in the triangle's plane
  // The segment crosses (or touches) the plane at one point X; X is in the triangle iff it is not
  // strictly outside any edge: orient3d(p, q, e0, e1) has the sign of X's side of edge (e0, e1).
  const Vector3d* c[3] = {&t.a, &t.b, &t.c};
  int o[3];
  edge_sides(p, q, c, o);
  const bool some_positive = (o[0] > 0) | (o[1] > 0) | (o[2] > 0);
  const bool some_negative = (o[0] < 0) | (o[1] < 0) | (o[2] < 0);
  return !(some_positive && some_negative);
}

// Signs in {-1, 0, 1}: all +1 or all -1 (branch-free: the signs of real pairs are unpredictable).
inline bool strictly_one_side(const int o[3]) {
  const int sum = o[0] + o[1] + o[2];
  return sum == 3 || sum == -3;
}

// The index of the one sign that differs from the other two (signs +-1, not all equal).
int lone_corner(const int o[3]) {
  if (o[0] == o[1]) return 2;
  return o[0] == o[2] ? 1 : 0;
}

// Non-degenerate triangles a and b, every corner strictly off the other's plane, neither
// separated by the other's plane (oa, ob: the sides of a's corners against b's plane, of b's
// against a's). Each plane then cuts the other triangle along a segment of the line where the
// planes meet, and the closed triangles meet iff the two segments overlap (Guigue and Devillers,
// "Fast and robust triangle-triangle overlap test using orientation predicates", 2003, section 3):
// with a's corner alone on its side of b's plane first (p1) and b's likewise (q1), each triangle's
// orientation chosen so that the other's lone corner is on its positive side, the segments
// overlap iff orient3d(p1, p2, q1, q2) <= 0 and orient3d(p1, p3, q3, q1) <= 0.
bool crossing_triangles_meet(
    const Vector3d* const a[3], const Vector3d* const b[3], const int oa[3], const int ob[3]) {
  const int ia = lone_corner(oa);
  const int ib = lone_corner(ob);
  // Rotations keep a triangle's orientation; swapping its last two corners reverses it.
  const Vector3d& p1 = *a[ia];
  const Vector3d* p2 = a[(ia + 1) % 3];
  const Vector3d* p3 = a[(ia + 2) % 3];
  if (ob[ib] < 0) std::swap(p2, p3);
  const Vector3d& q1 = *b[ib];
  const Vector3d* q2 = b[(ib + 1) % 3];
  const Vector3d* q3 = b[(ib + 2) % 3];
  if (oa[ia] < 0) std::swap(q2, q3);
  return orient3d_filtered(p1, *p2, q1, *q2) <= 0 && orient3d_filtered(p1, *p3, *q3, q1) <= 0;
}

// The closed triangles meet; oa / ob = orient3d of the corners of a against the plane of b / of b
// against a (all 0 for a degenerate plane), the pair not separated by either plane.
bool triangles_meet(const Triangle& ta, const Triangle& tb, const int oa[3], const int ob[3]) {
  const Vector3d* a[3] = {&ta.a, &ta.b, &ta.c};
  const Vector3d* b[3] = {&tb.a, &tb.b, &tb.c};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segment_triangle(*a[i], *a[j], tb, oa[i], oa[j])) return true;
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segment_triangle(*b[i], *b[j], ta, ob[i], ob[j])) return true;
  }
  return false;
}

// --- two degenerate triangles with shared corners ------------------------------------------------
// A zero-area triangle is the segment (or point) its corners span. Two of them sharing a vertex v
// both lie on lines through v: if either is the point v, or the lines differ, they meet at v
// alone. Otherwise they lie on one line, and the intersection is the overlap of two intervals of
// it; it goes beyond the shared corners iff it reaches past their hull at either end. Exact signs
// of polynomials of degree 2 (the old code enumerated extreme points in GMP rationals).

// Sign of (x - y) . (d - v): x before (-1), level with (0) or after (+1) y along v -> d.
int along(const Vector3d& x, const Vector3d& y, const Vector3d& v, const Vector3d& d) {
  return exact_sign(
      [&]<typename T>() -> T { return dot(lift<T>(x) - lift<T>(y), lift<T>(d) - lift<T>(v)); });
}

// The first and last of `points` along v -> d.
void extremes_along(
    const Vector3d* const* points,
    int n,
    const Vector3d& v,
    const Vector3d& d,
    const Vector3d*& first,
    const Vector3d*& last) {
  first = last = points[0];
  for (int i = 1; i < n; ++i) {
    if (along(*points[i], *first, v, d) < 0) first = points[i];
    if (along(*points[i], *last, v, d) > 0) last = points[i];
  }
}

bool flats_meet_beyond_shared(
    const Vector3d* const a[3], const Vector3d* const b[3], const SharedCorners& shared_with_b) {
  const Vector3d* shared[3];
  int ns = 0;
  for (int i = 0; i < 3; ++i) {
    if (shared_with_b[static_cast<std::size_t>(i)] >= 0) shared[ns++] = a[i];
  }
  assert(ns > 0);
  const Vector3d& v = *shared[0];
  // A corner of each away from v: none means that triangle is the point v.
  const Vector3d* da = nullptr;
  const Vector3d* db = nullptr;
  for (int i = 0; i < 3; ++i) {
    if (da == nullptr && *a[i] != v) da = a[i];
    if (db == nullptr && *b[i] != v) db = b[i];
  }
  if (da == nullptr || db == nullptr) return false;
  if (!collinear(v, *da, *db)) return false;  // two lines through v meet at v alone
  // One line: compare along v -> da.
  const Vector3d *a_first, *a_last, *b_first, *b_last, *s_first, *s_last;
  extremes_along(a, 3, v, *da, a_first, a_last);
  extremes_along(b, 3, v, *da, b_first, b_last);
  extremes_along(shared, ns, v, *da, s_first, s_last);
  const Vector3d* first = along(*a_first, *b_first, v, *da) > 0 ? a_first : b_first;
  const Vector3d* last = along(*a_last, *b_last, v, *da) < 0 ? a_last : b_last;
  return along(*first, *s_first, v, *da) < 0 || along(*last, *s_last, v, *da) > 0;
}

// shared_with_b seen from b: corner j of b is corner inverse[j] of a.
SharedCorners inverse(const SharedCorners& shared_with_b) {
  SharedCorners out = kNoSharedCorners;
  for (int i = 0; i < 3; ++i) {
    const int j = shared_with_b[static_cast<std::size_t>(i)];
    if (j >= 0) out[static_cast<std::size_t>(j)] = static_cast<std::int8_t>(i);
  }
  return out;
}

// A zero-area triangle F (corners `flat`, collinear: F is the segment they span) and a
// non-degenerate triangle S (`solid`, corners `solid_corners` in the order of its Triangle) that
// share one or two corners (`flat_to_solid`, as triangles_intersect's argument): is some point of
// F n S outside the hull of the shared corners? Exact, and without rationals:
// - F lies on a line L through a shared corner v, which is a corner of S and so in S's plane. If a
//   corner of F is off that plane, L meets the plane in v alone, and F n S is in {v}: no.
// - Otherwise F lies in S's plane. Two shared corners s0 != s1 (equal positions would make S
//   degenerate) put L on the line of S's edge s0 s1, which meets S in that edge: no.
// - One shared corner v: F n S is a segment from v; it goes beyond v iff for some corner c != v of
//   F, c - v lies in the closed cone of S at v, spanned by e1 = s1 - v and e2 = s2 - v (the other
//   two corners). Writing c - v = alpha e1 + beta e2 in the plane: cross(e1, c - v) = beta
//   cross(e1, e2) and cross(c - v, e2) = alpha cross(e1, e2), so both signs are read from 2D
//   orientations in a projection that is injective on the plane.
bool flat_meets_beyond_shared(
    const Vector3d* const flat[3],
    const SharedCorners& flat_to_solid,
    const Triangle& solid,
    const Vector3d* const solid_corners[3]) {
  int shared_count = 0;
  int v_index = -1;  // a corner of the solid triangle that is shared
  for (int i = 0; i < 3; ++i) {
    const int j = flat_to_solid[static_cast<std::size_t>(i)];
    if (j < 0) {
      if (orient3d(solid.a, solid.b, solid.c, *flat[i]) != 0) return false;
    } else {
      ++shared_count;
      v_index = j;
    }
  }
  if (shared_count >= 2) return false;
  const Vector3d& v = *solid_corners[v_index];
  const Vector3d& s1 = *solid_corners[(v_index + 1) % 3];
  const Vector3d& s2 = *solid_corners[(v_index + 2) % 3];
  const Projection pr = projection_of(solid);
  const int turn = orient2d(v, s1, s2, pr.i, pr.j);  // nonzero: pr keeps the triangle's area
  for (int i = 0; i < 3; ++i) {
    const Vector3d& c = *flat[i];
    if (c == v) continue;
    if (orient2d(v, s1, c, pr.i, pr.j) * turn >= 0 && orient2d(v, c, s2, pr.i, pr.j) * turn >= 0) {
      return true;
    }
  }
  return false;
}

// --- the pair without shared corners ------------------------------------------------------------

// cached_a / cached_b: the planes of a and b when the caller has them (triangle_plane), or null.
// first: the filter's sides of a's corners against b's plane when the caller has them (then
// cached_b is given too), or null.
bool no_shared_corner_intersect(
    const TriangleTriangleQuery& q,
    const TrianglePlane* cached_a,
    const TrianglePlane* cached_b,
    const FirstSides* first = nullptr) {
  const Vector3d* a[3] = {&q.a0, &q.a1, &q.a2};
  const Vector3d* b[3] = {&q.b0, &q.b1, &q.b2};
  // Most candidate pairs are separated by one of the planes: a's corners against b's plane,
  // then b's against a's. A degenerate triangle has no plane (the edge tests below want zeros):
  // its exact sides are all 0, which the filter never contradicts, so degeneracy is settled only
  // for pairs that no plane separates.
  const Plane pb =
      cached_b != nullptr ? plane_from(*cached_b, q.b0, q.b1, q.b2) : plane_of(q.b0, q.b1, q.b2);
  int oa[3];
  if (first != nullptr) {
    oa[0] = first->o[0];
    oa[1] = first->o[1];
    oa[2] = first->o[2];
    if (first->undecided != 0) settle_sides(pb, a, first->undecided, oa);
  } else {
    sides(pb, a, oa);
  }
  if (strictly_one_side(oa)) return false;
  const Plane pa =
      cached_a != nullptr ? plane_from(*cached_a, q.a0, q.a1, q.a2) : plane_of(q.a0, q.a1, q.a2);
  int ob[3];
  sides(pa, b, ob);
  if (strictly_one_side(ob)) return false;
  const bool b_degenerate = degenerate(pb);
  const bool a_degenerate = degenerate(pa);
  assert(!b_degenerate || (oa[0] == 0 && oa[1] == 0 && oa[2] == 0));
  assert(!a_degenerate || (ob[0] == 0 && ob[1] == 0 && ob[2] == 0));
  if (!a_degenerate && !b_degenerate && oa[0] * oa[1] * oa[2] != 0 && ob[0] * ob[1] * ob[2] != 0) {
    return crossing_triangles_meet(a, b, oa, ob);
  }
  // A corner on the other's plane, or a degenerate triangle: every edge against the other.
  return triangles_meet({q.a0, q.a1, q.a2, a_degenerate}, {q.b0, q.b1, q.b2, b_degenerate}, oa, ob);
}

// --- pairs with shared corners -------------------------------------------------------------------

// shared_with_b names some corner of b twice (two shared corners of a are one mesh vertex).
inline bool repeats_a_corner(const SharedCorners& s) {
  return (s[0] >= 0 && (s[0] == s[1] || s[0] == s[2])) || (s[1] >= 0 && s[1] == s[2]);
}

// shared_with_b with each corner of b named once: a later corner of a that names a corner of b
// already named is no longer marked shared. It has that corner's position (intersect's
// precondition), so the geometry is unchanged, and the shared set — the hull of the distinct
// corners of b named — is too; only the count now says vertex where it said edge.
SharedCorners without_repeats(const SharedCorners& shared_with_b) {
  SharedCorners out = shared_with_b;
  if (out[1] >= 0 && out[1] == out[0]) out[1] = -1;
  if (out[2] >= 0 && (out[2] == out[0] || out[2] == shared_with_b[1])) out[2] = -1;
  return out;
}

// At least one triangle degenerate (shared_count 1 or 2).
[[gnu::noinline]] bool degenerate_shared_intersect(
    const TriangleTriangleQuery& q,
    const SharedCorners& shared_corners,
    const Triangle& ta,
    const Triangle& tb) {
  const Vector3d* a[3] = {&q.a0, &q.a1, &q.a2};
  const Vector3d* b[3] = {&q.b0, &q.b1, &q.b2};
  // A repeated entry names one vertex, not an edge: {1, 1, -1} shares b's corner 1 alone. Such a
  // map only arrives here — its two corners of a have one position, so a's normal is exactly zero
  // and a is degenerate — with two entries (intersect answers three itself: a is then within
  // the hull of the shared corners). Counted as an edge, a degenerate a reaching into a solid b
  // from the vertex would be answered "no" (flat_meets_beyond_shared's two-corner case).
  const SharedCorners shared_with_b =
      repeats_a_corner(shared_corners) ? without_repeats(shared_corners) : shared_corners;
  if (ta.degenerate != tb.degenerate) {
    return ta.degenerate ? flat_meets_beyond_shared(a, shared_with_b, tb, b)
                         : flat_meets_beyond_shared(b, inverse(shared_with_b), ta, a);
  }
  return flats_meet_beyond_shared(a, b, shared_with_b);
}

// The exact side test of the shared edge (s0, s1): fa and fb strictly on the same side of it.
[[gnu::noinline]] bool same_side_exact(
    const Vector3d& s0, const Vector3d& s1, const Vector3d& fa, const Vector3d& fb) {
  return exact_sign([&]<typename T>() -> T {
           const auto p0 = lift<T>(s0);
           const auto e = lift<T>(s1) - p0;
           return dot(cross(e, lift<T>(fa) - p0), cross(e, lift<T>(fb) - p0));
         }) > 0;
}

// Sign of na . nb for the normals of two planes, certain, or kUndecided. Each component carries
// the error of Shewchuk's orient2d evaluation, |n_k - N_k| <= 4 eps m_k + 2^-1073 (the absolute
// term for underflowed products); the dot product adds 3 eps sum |na_k nb_k| and 3 2^-1075. All
// told under 12 eps S + 2^-1072 (sum_k (m_ak + m_bk) + 1), S = sum_k m_ak m_bk, since |n_k| <=
// (1 + eps) m_k; the guard keeps the absolute part under 2^-103 S, and 16 eps S covers the rest
// with the rounding of S itself.
inline int normals_dot_static(const Plane& pa, const Plane& pb) {
  const double d = pa.n[0] * pb.n[0] + pa.n[1] * pb.n[1] + pa.n[2] * pb.n[2];
  const double big_s = pa.m[0] * pb.m[0] + pa.m[1] * pb.m[1] + pa.m[2] * pb.m[2];
  const double guard = pa.m[0] + pa.m[1] + pa.m[2] + pb.m[0] + pb.m[1] + pb.m[2] + 1.0;
  if (!(big_s < std::numeric_limits<double>::infinity()) || !(guard <= big_s * 0x1p969)) {
    return detail::kUndecided;
  }
  const double bound = 0x1p-49 * big_s;  // >= 2^-1018: exact
  if (d > bound) return 1;
  if (-d > bound) return -1;
  return detail::kUndecided;
}

// +1 when (c[i], c[j], c[3 - i - j]) is a rotation of (c[0], c[1], c[2]), -1 when it is reversed.
inline int order_sign(int i, int j) { return (j - i + 3) % 3 == 1 ? 1 : -1; }

bool shared_corners_intersect(
    const TriangleTriangleQuery& q,
    const SharedCorners& shared_with_b,
    int shared_count,
    const TrianglePlane* cached_a,
    const TrianglePlane* cached_b) {
  const Vector3d* a[3] = {&q.a0, &q.a1, &q.a2};
  const Vector3d* b[3] = {&q.b0, &q.b1, &q.b2};
  const Plane pa =
      cached_a != nullptr ? plane_from(*cached_a, q.a0, q.a1, q.a2) : plane_of(q.a0, q.a1, q.a2);
  const Plane pb =
      cached_b != nullptr ? plane_from(*cached_b, q.b0, q.b1, q.b2) : plane_of(q.b0, q.b1, q.b2);
  const Triangle ta{q.a0, q.a1, q.a2, degenerate(pa)};
  const Triangle tb{q.b0, q.b1, q.b2, degenerate(pb)};
  if (ta.degenerate || tb.degenerate) return degenerate_shared_intersect(q, shared_with_b, ta, tb);

  // Corners of a and b that are not shared (as many on each side: both are non-degenerate).
  int a_free[2] = {-1, -1};
  int na = 0;
  int s[2] = {-1, -1};  // a's shared corners
  int ns = 0;
  bool b_is_shared[3] = {false, false, false};
  for (int i = 0; i < 3; ++i) {
    const int j = shared_with_b[static_cast<std::size_t>(i)];
    if (j < 0) {
      a_free[na++] = i;
    } else {
      b_is_shared[j] = true;
      s[ns++] = i;
    }
  }
  int b_free[2] = {-1, -1};
  int nb = 0;
  for (int j = 0; j < 3; ++j) {
    if (!b_is_shared[j]) b_free[nb++] = j;
  }
  assert(na == nb && ns == shared_count);

  if (shared_count == 1) {
    // Beyond the shared vertex v iff an edge opposite v meets the other triangle. Each plane
    // passes through v: a triangle whose free corners are strictly on one side of the other's
    // plane meets that plane at v alone, and then the triangles meet at v alone.
    const Vector3d& pa0 = *a[a_free[0]];
    const Vector3d& pa1 = *a[a_free[1]];
    const int oa0 = side(pb, pa0);
    const int oa1 = side(pb, pa1);
    if (oa0 * oa1 > 0) return false;
    const Vector3d& pb0 = *b[b_free[0]];
    const Vector3d& pb1 = *b[b_free[1]];
    const int ob0 = side(pa, pb0);
    const int ob1 = side(pa, pb1);
    if (ob0 * ob1 > 0) return false;
    if (oa0 != 0 && oa1 != 0 && ob0 != 0 && ob1 != 0) {
      // Both free edges cross the other plane strictly, at X_a and X_b: a meets b's plane in the
      // segment [v, X_a], b meets a's in [v, X_b], both on the line where the planes meet, and
      // they overlap beyond v iff X_b lies in a's closed angle at v (whose trace on that line is
      // the ray from v through X_a). orient3d(pb0, pb1, e0, e1) is X_b's side of a's edge
      // (e0, e1) times the sign ob1 of the crossing (the segment is parallel to X_b - pb0, so
      // the triple product reduces to the 2D orientation of (e0, e1, X_b) in a's plane): inside
      // the angle iff both edges through v, in a's corner order, see X_b on their inner side.
      const int v = s[0];
      const int o1 = orient3d_filtered(pb0, pb1, *a[(v + 2) % 3], *a[v]);
      const int o2 = orient3d_filtered(pb0, pb1, *a[v], *a[(v + 1) % 3]);
      return ob1 * o1 >= 0 && ob1 * o2 >= 0;
    }
    // A free corner on the other's plane: the edges against the triangles.
    return segment_triangle(pa0, pa1, tb, oa0, oa1) || segment_triangle(pb0, pb1, ta, ob0, ob1);
  }

  // Shared edge (s0, s1): beyond it iff coplanar with the free corners on the same side.
  const Vector3d& s0 = *a[s[0]];
  const Vector3d& s1 = *a[s[1]];
  const Vector3d& fa = *a[a_free[0]];
  const Vector3d& fb = *b[b_free[0]];
  // b's free corner certainly off a's plane (the plane of s0, s1, fa): not coplanar.
  if (side_static(pa, fb) != detail::kUndecided) return false;
  // The side test: (s1 - s0) x (f - s0) is each triangle's normal up to the sign of its corner
  // order, so fa and fb are on the same side iff na . nb has the sign of the two orders' product.
  // Neighbours on a surface fold away from each other: a robust negative sign.
  const int dot_sign = normals_dot_static(pa, pb);
  if (dot_sign != detail::kUndecided) {
    const int orders = order_sign(s[0], s[1]) * order_sign(
                                                    shared_with_b[static_cast<std::size_t>(s[0])],
                                                    shared_with_b[static_cast<std::size_t>(s[1])]);
    if (dot_sign * orders < 0) return false;
  } else if (!same_side_exact(s0, s1, fa, fb)) {
    return false;
  }
  return orient3d(s0, s1, fa, fb) == 0;
}

// Both entries: the planes computed here (null) or given.
bool intersect(
    const TriangleTriangleQuery& q,
    const SharedCorners& shared_with_b,
    const TrianglePlane* cached_a,
    const TrianglePlane* cached_b) {
  int shared_count = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = shared_with_b[static_cast<std::size_t>(i)];
    assert(j >= -1 && j <= 2);
    if (j < 0) continue;
    assert(
        (i == 0   ? q.a0
         : i == 1 ? q.a1
                  : q.a2) == (j == 0   ? q.b0
                              : j == 1 ? q.b1
                                       : q.b2) &&
        "a shared corner must have the same position in both triangles");
    ++shared_count;
  }
  if (shared_count == 0) return no_shared_corner_intersect(q, cached_a, cached_b);
  // Three entries: a's corners are all shared corners of b, so a lies within their hull (the same
  // triangle, or with a repeated entry the shared edge or vertex): nothing beyond it.
  if (shared_count == 3) return false;
  return shared_corners_intersect(q, shared_with_b, shared_count, cached_a, cached_b);
}

}  // namespace

bool triangles_intersect(const TriangleTriangleQuery& q, const SharedCorners& shared_with_b) {
  return intersect(q, shared_with_b, nullptr, nullptr);
}

TrianglePlane triangle_plane(const Vector3d& p0, const Vector3d& p1, const Vector3d& p2) {
  const Plane pl = plane_of(p0, p1, p2);
  return {{pl.n[0], pl.n[1], pl.n[2]}, {pl.m[0], pl.m[1], pl.m[2]}};
}

bool triangles_intersect_with_planes(
    const TriangleTriangleQuery& q,
    const SharedCorners& shared_with_b,
    const TrianglePlane& plane_a,
    const TrianglePlane& plane_b) {
  return intersect(q, shared_with_b, &plane_a, &plane_b);
}

bool first_sides_separate(
    const double* a0,
    const double* a1,
    const double* a2,
    const double* b0,
    const TrianglePlane& plane_b,
    FirstSides& out) {
  const double* const a[3] = {a0, a1, a2};
  out.undecided = large_minors(plane_b.m[0], plane_b.m[1], plane_b.m[2])
                      ? sides_static<true>(plane_b.n, plane_b.m, b0, a, out.o)
                      : sides_static<false>(plane_b.n, plane_b.m, b0, a, out.o);
  // Decided signs are exact: all three strictly on one side separates the pair.
  return out.undecided == 0 && strictly_one_side(out.o);
}

bool triangles_intersect_after_first_sides(
    const TriangleTriangleQuery& q,
    const TrianglePlane& plane_a,
    const TrianglePlane& plane_b,
    const FirstSides& first) {
  return no_shared_corner_intersect(q, &plane_a, &plane_b, &first);
}

}  // namespace skelcd::ccd
