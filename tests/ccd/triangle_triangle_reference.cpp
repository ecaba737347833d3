// triangles_intersect as it was at 5b0653f (ccd/triangle_triangle.cpp), kept verbatim but for the
// namespace, the function's name and clang-format's line breaks: the reference the faster test
// must agree with bit for bit (tests/ccd/test_triangle_triangle_equivalence.cpp,
// tests/culling/test_triangle_triangle_real.cpp, bench/ccd/bm_triangle_triangle.cpp). Do not edit
// it to follow changes of ccd/. (It calls ccd::orient3d, which is not copied.)
//
// Exact triangle-triangle intersection (docs/ccd.md, "Triangle-triangle DCD").
//
// Two closed triangles meet iff an edge of one meets the other triangle: if A and B share a point,
// A n B is a convex set whose extreme points lie on the boundary of A or of B (and a zero-area
// triangle is the union of its edges). Every decision is the exact sign of a polynomial in the
// input coordinates (detail/filtered.hpp: filtered double, GMP fallback).
//
// Shared corners: with one shared vertex s and both triangles non-degenerate, A n B is more than
// {s} iff the edge of A opposite s meets B or the edge of B opposite s meets A; with a shared edge,
// iff the triangles are coplanar and lie on the same side of it. Degenerate triangles that share
// corners go to an exact rational enumeration of the extreme points of A n B.

#include "tests/ccd/triangle_triangle_reference.hpp"

#include <algorithm>
#include <cassert>
#include <vector>

#include "ccd/detail/filtered.hpp"
#include "ccd/orientation.hpp"

namespace skelcd::ccd::reference {
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
bool coplanar_segments_intersect(
    const Vector3d& p, const Vector3d& q, const Vector3d& r, const Vector3d& s) {
  bool parallel = true;
  for (int k = 0; k < 3 && parallel; ++k) {
    parallel =
        exact_sign([&]<typename T>() -> T {
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
bool segments_intersect(
    const Vector3d& p, const Vector3d& q, const Vector3d& r, const Vector3d& s) {
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

// Sign of the 2D orientation of (a, b, c) in coordinates (i, j): static filter, then exact.
int orient2d(const Vector3d& a, const Vector3d& b, const Vector3d& c, int i, int j) {
  const int s = detail::cross_component_static(a, b, c, i, j);
  if (s != detail::kUndecided) return s;
  return exact_sign([&]<typename T>() -> T {
    const T ai = lift<T>(a[i]), aj = lift<T>(a[j]);
    return T(
        (lift<T>(b[i]) - ai) * (lift<T>(c[j]) - aj) - (lift<T>(b[j]) - aj) * (lift<T>(c[i]) - ai));
  });
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
  const int s1 = orient3d(p, q, t.a, t.b);
  const int s2 = orient3d(p, q, t.b, t.c);
  const int s3 = orient3d(p, q, t.c, t.a);
  const bool some_positive = s1 > 0 || s2 > 0 || s3 > 0;
  const bool some_negative = s1 < 0 || s2 < 0 || s3 < 0;
  return !(some_positive && some_negative);
}

bool segment_triangle(const Vector3d& p, const Vector3d& q, const Triangle& t) {
  if (t.degenerate) return segment_triangle(p, q, t, 0, 0);
  return segment_triangle(p, q, t, orient3d(t.a, t.b, t.c, p), orient3d(t.a, t.b, t.c, q));
}

bool triangles_meet(const Triangle& ta, const Triangle& tb) {
  const Vector3d* a[3] = {&ta.a, &ta.b, &ta.c};
  const Vector3d* b[3] = {&tb.a, &tb.b, &tb.c};
  int oa[3] = {0, 0, 0};  // corners of a against the plane of b
  int ob[3] = {0, 0, 0};
  if (!tb.degenerate) {
    for (int i = 0; i < 3; ++i) oa[i] = orient3d(tb.a, tb.b, tb.c, *a[i]);
    if ((oa[0] > 0 && oa[1] > 0 && oa[2] > 0) || (oa[0] < 0 && oa[1] < 0 && oa[2] < 0))
      return false;
  }
  if (!ta.degenerate) {
    for (int i = 0; i < 3; ++i) ob[i] = orient3d(ta.a, ta.b, ta.c, *b[i]);
    if ((ob[0] > 0 && ob[1] > 0 && ob[2] > 0) || (ob[0] < 0 && ob[1] < 0 && ob[2] < 0))
      return false;
  }
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

// --- exact rational enumeration (degenerate triangles with shared corners) ----------------------

using Q3 = detail::Point3<mpq_class>;

bool is_zero(const Q3& v) { return v.x == 0 && v.y == 0 && v.z == 0; }
bool equal(const Q3& a, const Q3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

bool q_on_segment(const Q3& p, const Q3& a, const Q3& b) {
  return is_zero(cross(b - a, p - a)) && dot(p - a, p - b) <= 0;
}

bool q_in_triangle(const Q3& p, const Q3& a, const Q3& b, const Q3& c) {
  const Q3 n = cross(b - a, c - a);
  if (is_zero(n)) return q_on_segment(p, a, b) || q_on_segment(p, b, c) || q_on_segment(p, c, a);
  if (dot(n, p - a) != 0) return false;
  return dot(n, cross(b - a, p - a)) >= 0 && dot(n, cross(c - b, p - b)) >= 0 &&
         dot(n, cross(a - c, p - c)) >= 0;
}

// Is some point of A n B outside the shared set (one point, or the segment between two)?
bool meet_beyond_shared_rational(
    const std::array<Q3, 3>& a, const std::array<Q3, 3>& b, const std::vector<Q3>& shared) {
  // Candidates for the extreme points of A n B: corners in the other triangle, single-point
  // edge-edge intersections, and transversal edge-plane intersections inside the other triangle.
  std::vector<Q3> candidates;
  for (const auto& p : a) {
    if (q_in_triangle(p, b[0], b[1], b[2])) candidates.push_back(p);
  }
  for (const auto& p : b) {
    if (q_in_triangle(p, a[0], a[1], a[2])) candidates.push_back(p);
  }
  for (int i = 0; i < 3; ++i) {
    const Q3& p = a[static_cast<std::size_t>(i)];
    const Q3& q = a[static_cast<std::size_t>((i + 1) % 3)];
    for (int j = 0; j < 3; ++j) {
      const Q3& r = b[static_cast<std::size_t>(j)];
      const Q3& s = b[static_cast<std::size_t>((j + 1) % 3)];
      const Q3 d1 = q - p;
      const Q3 d2 = s - r;
      const Q3 w = r - p;
      const Q3 n = cross(d1, d2);
      if (is_zero(n) || dot(n, w) != 0) continue;  // parallel, or not coplanar
      const mpq_class nn = dot(n, n);
      const mpq_class u = dot(cross(w, d2), n) / nn;
      const mpq_class v = dot(cross(w, d1), n) / nn;
      if (u < 0 || u > 1 || v < 0 || v > 1) continue;
      candidates.push_back({p.x + u * d1.x, p.y + u * d1.y, p.z + u * d1.z});
    }
  }
  const auto edge_plane = [&](const std::array<Q3, 3>& edges, const std::array<Q3, 3>& tri) {
    const Q3 n = cross(tri[1] - tri[0], tri[2] - tri[0]);
    if (is_zero(n)) return;
    for (int i = 0; i < 3; ++i) {
      const Q3& p = edges[static_cast<std::size_t>(i)];
      const Q3& q = edges[static_cast<std::size_t>((i + 1) % 3)];
      const mpq_class op = dot(n, p - tri[0]);
      const mpq_class oq = dot(n, q - tri[0]);
      if (!((op > 0 && oq < 0) || (op < 0 && oq > 0))) continue;
      const mpq_class lambda = op / (op - oq);
      const Q3 x{
          p.x + lambda * (q.x - p.x), p.y + lambda * (q.y - p.y), p.z + lambda * (q.z - p.z)};
      if (q_in_triangle(x, tri[0], tri[1], tri[2])) candidates.push_back(x);
    }
  };
  edge_plane(a, b);
  edge_plane(b, a);
  for (const auto& x : candidates) {
    const bool in_shared =
        shared.size() == 1 ? equal(x, shared[0]) : q_on_segment(x, shared[0], shared[1]);
    if (!in_shared) return true;
  }
  return false;
}

Q3 rational(const Vector3d& p) { return lift<mpq_class>(p); }

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

}  // namespace

bool triangles_intersect_reference(
    const TriangleTriangleQuery& q, const SharedCorners& shared_with_b) {
  const Vector3d* a[3] = {&q.a0, &q.a1, &q.a2};
  const Vector3d* b[3] = {&q.b0, &q.b1, &q.b2};
  int shared_count = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = shared_with_b[static_cast<std::size_t>(i)];
    assert(j >= -1 && j <= 2);
    if (j < 0) continue;
    assert(*a[i] == *b[j] && "a shared corner must have the same position in both triangles");
    ++shared_count;
  }
  const Triangle ta{q.a0, q.a1, q.a2, collinear(q.a0, q.a1, q.a2)};
  const Triangle tb{q.b0, q.b1, q.b2, collinear(q.b0, q.b1, q.b2)};
  if (shared_count == 0) return triangles_meet(ta, tb);
  if (shared_count == 3) return false;  // the same triangle: nothing beyond the shared part

  // Corners of a and b that are not shared (a degenerate triangle may repeat a shared vertex, so
  // only non-degenerate pairs have as many free corners on each side).
  int a_free[2] = {-1, -1};
  int na = 0;
  bool b_is_shared[3] = {false, false, false};
  for (int i = 0; i < 3; ++i) {
    const int j = shared_with_b[static_cast<std::size_t>(i)];
    if (j < 0) {
      a_free[na++] = i;
    } else {
      b_is_shared[j] = true;
    }
  }
  int b_free[2] = {-1, -1};
  int nb = 0;
  for (int j = 0; j < 3; ++j) {
    if (!b_is_shared[j]) b_free[nb++] = j;
  }

  if (ta.degenerate != tb.degenerate) {
    return ta.degenerate ? flat_meets_beyond_shared(a, shared_with_b, tb, b)
                         : flat_meets_beyond_shared(b, inverse(shared_with_b), ta, a);
  }
  if (ta.degenerate) {  // both degenerate: rare enough for the rational enumeration
    std::vector<Q3> shared;
    for (int i = 0; i < 3; ++i) {
      if (shared_with_b[static_cast<std::size_t>(i)] >= 0) shared.push_back(rational(*a[i]));
    }
    return meet_beyond_shared_rational(
        {rational(q.a0), rational(q.a1), rational(q.a2)},
        {rational(q.b0), rational(q.b1), rational(q.b2)},
        shared);
  }

  assert(na == nb);

  if (shared_count == 1) {
    // Beyond the shared vertex iff an edge opposite it meets the other triangle.
    return segment_triangle(*a[a_free[0]], *a[a_free[1]], tb) ||
           segment_triangle(*b[b_free[0]], *b[b_free[1]], ta);
  }

  // Shared edge (s0, s1): beyond it iff coplanar with the free corners on the same side.
  int s[2] = {-1, -1};
  int ns = 0;
  for (int i = 0; i < 3; ++i) {
    if (shared_with_b[static_cast<std::size_t>(i)] >= 0) s[ns++] = i;
  }
  const Vector3d& s0 = *a[s[0]];
  const Vector3d& s1 = *a[s[1]];
  const Vector3d& fa = *a[a_free[0]];
  const Vector3d& fb = *b[b_free[0]];
  // Both conditions must hold; the side test comes first because it is the cheap one on a
  // surface: neighbours fold away from each other (free corners on opposite sides, a robust
  // negative sign), while their orientation is near zero wherever the surface is nearly flat.
  const bool same_side = exact_sign([&]<typename T>() -> T {
                           const auto p0 = lift<T>(s0);
                           const auto e = lift<T>(s1) - p0;
                           return dot(cross(e, lift<T>(fa) - p0), cross(e, lift<T>(fb) - p0));
                         }) > 0;
  return same_side && orient3d(s0, s1, fa, fb) == 0;
}

}  // namespace skelcd::ccd::reference
