// Exact VF / EE CCD on rationals. Narrative of the algorithm (docs/ccd.md, "The exact reference"):
//  1. Contact needs coplanarity: the 4 points are coplanar at a contact time, so contact times are
//     roots of the cubic c(t) = det(...) unless c is identically zero.
//  2. c not identically 0: isolate the roots of c in [0,1] exactly (square-free part, Sturm
//     sequence, bisection on rationals) and, in increasing order, decide "in contact at t*" by exact
//     signs of polynomials at the algebraic number t*. The first that is in contact is the TOI.
//  3. c identically 0 (coplanar throughout): the first contact is at t = 0 or happens on the
//     boundary of a feature, so it is a point-segment contact (and the point-segment query, when
//     collinear throughout, reduces to point-point contacts the same way).

#include "ccd/exact_ccd.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "ccd/detail/rational_polynomial.hpp"

namespace skelcd::ccd {
namespace {

using detail::PolynomialVector;
using detail::RationalPolynomial;
using detail::RootPoint;

PolynomialVector moving(const RationalPoint& x_t0, const RationalPoint& x_t1) {
  return {RationalPolynomial::linear(x_t0[0], x_t1[0] - x_t0[0]),
          RationalPolynomial::linear(x_t0[1], x_t1[1] - x_t0[1]),
          RationalPolynomial::linear(x_t0[2], x_t1[2] - x_t0[2])};
}

RationalPoint rational(const Eigen::Vector3d& p) {
  return {mpq_class(p.x()), mpq_class(p.y()), mpq_class(p.z())};
}

// Earliest contact found so far, bracketed by rationals.
struct Earliest {
  bool hit = false;
  mpq_class lo, hi;

  // The minimum of two earliest times lies in [min lo, min hi].
  void merge(const Earliest& other) {
    if (!other.hit) return;
    if (!hit) {
      *this = other;
      return;
    }
    if (other.lo < lo) lo = other.lo;
    if (other.hi < hi) hi = other.hi;
  }
};

Earliest found_at(RootPoint& t, const mpq_class& width) {
  t.refine(width);
  return {true, t.lo(), t.hi()};
}

// Swept boxes: a linearly moving point stays in the box of its two positions, so disjoint boxes
// (compared exactly) mean no contact. Just a shortcut; the algorithm below does not need it.
bool swept_boxes_disjoint(std::initializer_list<const RationalPoint*> side_a,
                          std::initializer_list<const RationalPoint*> side_b) {
  for (int k = 0; k < 3; ++k) {
    const auto axis = static_cast<std::size_t>(k);
    const mpq_class* a_min = &(*side_a.begin())->at(axis);
    const mpq_class* a_max = a_min;
    for (const auto* p : side_a) {
      if ((*p)[axis] < *a_min) a_min = &(*p)[axis];
      if ((*p)[axis] > *a_max) a_max = &(*p)[axis];
    }
    const mpq_class* b_min = &(*side_b.begin())->at(axis);
    const mpq_class* b_max = b_min;
    for (const auto* p : side_b) {
      if ((*p)[axis] < *b_min) b_min = &(*p)[axis];
      if ((*p)[axis] > *b_max) b_max = &(*p)[axis];
    }
    if (*a_max < *b_min || *b_max < *a_min) return true;
  }
  return false;
}

// Polynomials deciding "point p on the closed segment [a, b]": p is on the segment iff
// (b - a) x (p - a) = 0 (collinear, or a = b) and (p - a).(p - b) <= 0 (between a and b, or p = a
// when a = b).
struct OnSegment {
  PolynomialVector collinear;
  RationalPolynomial between;

  OnSegment(const PolynomialVector& p, const PolynomialVector& a, const PolynomialVector& b)
      : collinear(detail::cross(b - a, p - a)), between(detail::dot(p - a, p - b)) {}

  bool at(RootPoint& t) const {
    for (const auto& c : collinear) {
      if (t.sign(c) != 0) return false;
    }
    return t.sign(between) <= 0;
  }
};

// Roots in [0,1] of the common zeros of the given polynomials, first one for which `accept` holds.
// All of them identically zero is the caller's business.
template <typename Accept>
Earliest first_common_root(std::initializer_list<const RationalPolynomial*> polys,
                           const mpq_class& width,
                           Accept&& accept) {
  RationalPolynomial g;
  for (const auto* p : polys) g = detail::gcd(g, *p);
  if (g.is_zero() || g.degree() < 1) return {};
  const RationalPolynomial f = detail::square_free(g);
  for (const auto& root : detail::isolate_roots_in_unit_interval(f)) {
    RootPoint t(f, root);
    if (accept(t)) return found_at(t, width);
  }
  return {};
}

// Earliest t in [0,1] with p(t) = a(t).
Earliest point_point_ccd(const PolynomialVector& p, const PolynomialVector& a, const mpq_class& width) {
  const PolynomialVector d = p - a;
  if (detail::is_zero(d)) return {true, 0, 0};
  return first_common_root({&d[0], &d[1], &d[2]}, width, [](RootPoint&) { return true; });
}

// Earliest t in [0,1] with p(t) on the closed segment [a(t), b(t)].
Earliest point_segment_ccd(const PolynomialVector& p,
                           const PolynomialVector& a,
                           const PolynomialVector& b,
                           const mpq_class& width) {
  const OnSegment on(p, a, b);
  if (detail::is_zero(on.collinear)) {
    // Collinear throughout: the first contact after t = 0 has p at an endpoint (docs/ccd.md).
    RootPoint t0(mpq_class(0));
    if (on.at(t0)) return {true, 0, 0};
    Earliest e = point_point_ccd(p, a, width);
    e.merge(point_point_ccd(p, b, width));
    return e;
  }
  return first_common_root({&on.collinear[0], &on.collinear[1], &on.collinear[2]}, width,
                           [&](RootPoint& t) { return t.sign(on.between) <= 0; });
}

// --- vertex-face -------------------------------------------------------------------------------

struct VertexFacePolynomials {
  PolynomialVector p, a, b, c;
  PolynomialVector normal;      // (b - a) x (c - a)
  RationalPolynomial coplanar;  // normal . (p - a)

  explicit VertexFacePolynomials(const RationalVertexFaceQuery& q)
      : p(moving(q.v_t0, q.v_t1)),
        a(moving(q.f0_t0, q.f0_t1)),
        b(moving(q.f1_t0, q.f1_t1)),
        c(moving(q.f2_t0, q.f2_t1)),
        normal(detail::cross(b - a, c - a)),
        coplanar(detail::dot(normal, p - a)) {}

  // p(t*) in the closed triangle (a, b, c)(t*). The inside polynomials are built when needed.
  bool contact(RootPoint& t) const {
    if (t.sign(coplanar) != 0) return false;
    const bool degenerate =
        t.sign(normal[0]) == 0 && t.sign(normal[1]) == 0 && t.sign(normal[2]) == 0;
    if (!degenerate) {
      // Non-degenerate triangle, p in its plane: inside iff on the inner side of all three edges,
      // n . ((b - a) x (p - a)) >= 0 and its two rotations.
      return t.sign(detail::dot(normal, detail::cross(b - a, p - a))) >= 0 &&
             t.sign(detail::dot(normal, detail::cross(c - b, p - b))) >= 0 &&
             t.sign(detail::dot(normal, detail::cross(a - c, p - c))) >= 0;
    }
    // Zero-area triangle: it is the union of its three edges.
    return OnSegment(p, a, b).at(t) || OnSegment(p, b, c).at(t) || OnSegment(p, c, a).at(t);
  }
};

// --- edge-edge ---------------------------------------------------------------------------------

struct EdgeEdgePolynomials {
  PolynomialVector a0, a1, b0, b1;
  PolynomialVector normal;      // d1 x d2, d1 = a1 - a0, d2 = b1 - b0
  RationalPolynomial coplanar;  // normal . (b0 - a0)

  explicit EdgeEdgePolynomials(const RationalEdgeEdgeQuery& q)
      : a0(moving(q.ea0_t0, q.ea0_t1)),
        a1(moving(q.ea1_t0, q.ea1_t1)),
        b0(moving(q.eb0_t0, q.eb0_t1)),
        b1(moving(q.eb1_t0, q.eb1_t1)),
        normal(detail::cross(a1 - a0, b1 - b0)),
        coplanar(detail::dot(normal, b0 - a0)) {}

  // The closed segments [a0, a1] and [b0, b1] share a point at t*.
  bool contact(RootPoint& t) const {
    if (t.sign(coplanar) != 0) return false;
    const bool parallel =
        t.sign(normal[0]) == 0 && t.sign(normal[1]) == 0 && t.sign(normal[2]) == 0;
    if (!parallel) {
      // Coplanar, non-parallel: the lines meet at a0 + (u/nn) d1 = b0 + (v/nn) d2 with
      // u = (w x d2) . n, v = (w x d1) . n, nn = n . n > 0, w = b0 - a0; on both segments iff
      // 0 <= u <= nn and 0 <= v <= nn.
      const PolynomialVector w = b0 - a0;
      const RationalPolynomial nn = detail::dot(normal, normal);
      const RationalPolynomial u = detail::dot(detail::cross(w, b1 - b0), normal);
      if (t.sign(u) < 0 || t.sign(nn - u) < 0) return false;
      const RationalPolynomial v = detail::dot(detail::cross(w, a1 - a0), normal);
      return t.sign(v) >= 0 && t.sign(nn - v) >= 0;
    }
    // Parallel or degenerate: two such segments meet iff an endpoint of one lies on the other.
    return OnSegment(a0, b0, b1).at(t) || OnSegment(a1, b0, b1).at(t) || OnSegment(b0, a0, a1).at(t) ||
           OnSegment(b1, a0, a1).at(t);
  }
};

// The contact times of a query whose coplanarity polynomial is not identically zero are roots of
// it in [0,1]: visit them in increasing order. A Bernstein hull of one strict sign proves there
// are none (a cheap exact shortcut).
template <typename Polynomials>
Earliest first_contact_at_coplanarity_roots(const Polynomials& P, const mpq_class& width) {
  if (detail::bernstein_sign(P.coplanar, 0, 1) != 0) return {};
  const RationalPolynomial f = detail::square_free(P.coplanar);
  for (const auto& root : detail::isolate_roots_in_unit_interval(f)) {
    RootPoint t(f, root);
    if (P.contact(t)) return found_at(t, width);
  }
  return {};
}

mpq_class positive_width(double toi_tolerance) {
  // Refining to width 0 would never end; 2^-64 is far below anything a double time can show.
  const double w = std::max(toi_tolerance, std::ldexp(1.0, -64));
  return mpq_class(w);
}

// Contact and contact times do not change under a translation and a uniform positive scaling of
// all points. Moving the first point to the origin and multiplying by the common denominator makes
// every coordinate an integer: the polynomial arithmetic then runs on integers (no gcds) and on
// smaller numbers (a query far from the origin loses its offset).
template <std::size_t N>
void normalize(const std::array<RationalPoint*, N>& points) {
  const RationalPoint origin = *points[0];
  mpz_class denominator = 1;
  for (RationalPoint* p : points) {
    for (std::size_t k = 0; k < 3; ++k) {
      (*p)[k] -= origin[k];
      mpz_lcm(denominator.get_mpz_t(), denominator.get_mpz_t(), (*p)[k].get_den_mpz_t());
    }
  }
  for (RationalPoint* p : points) {
    for (std::size_t k = 0; k < 3; ++k) (*p)[k] *= denominator;
  }
}

CcdResult to_ccd_result(const ExactCcdResult& r) {
  CcdResult out;
  out.hit = r.hit;
  if (r.hit) {
    out.toi_lower = std::clamp(round_down(r.toi_lo), 0.0, 1.0);
    out.toi_upper = std::clamp(round_up(r.toi_hi), 0.0, 1.0);
    out.status = CcdStatus::contact;
  }
  return out;
}

}  // namespace

RationalVertexFaceQuery to_rational(const VertexFaceQuery& q) {
  return {rational(q.v_t0), rational(q.f0_t0), rational(q.f1_t0), rational(q.f2_t0),
          rational(q.v_t1), rational(q.f0_t1), rational(q.f1_t1), rational(q.f2_t1)};
}

RationalEdgeEdgeQuery to_rational(const EdgeEdgeQuery& q) {
  return {rational(q.ea0_t0), rational(q.ea1_t0), rational(q.eb0_t0), rational(q.eb1_t0),
          rational(q.ea0_t1), rational(q.ea1_t1), rational(q.eb0_t1), rational(q.eb1_t1)};
}

ExactCcdResult vertex_face_ccd_rational(const RationalVertexFaceQuery& query, const mpq_class& width) {
  assert(width > 0);
  if (swept_boxes_disjoint({&query.v_t0, &query.v_t1},
                           {&query.f0_t0, &query.f1_t0, &query.f2_t0, &query.f0_t1, &query.f1_t1, &query.f2_t1})) {
    return {};
  }
  RationalVertexFaceQuery q = query;
  normalize(std::array{&q.v_t0, &q.f0_t0, &q.f1_t0, &q.f2_t0, &q.v_t1, &q.f0_t1, &q.f1_t1, &q.f2_t1});
  const VertexFacePolynomials P(q);
  Earliest e;
  if (!P.coplanar.is_zero()) {
    // Contact times are roots of the coplanarity cubic: test them in increasing order.
    e = first_contact_at_coplanarity_roots(P, width);
  } else {
    // Coplanar throughout: contact at t = 0, or the first contact is the vertex on an edge.
    RootPoint t0(mpq_class(0));
    if (P.contact(t0)) {
      e = {true, 0, 0};
    } else {
      e = point_segment_ccd(P.p, P.a, P.b, width);
      e.merge(point_segment_ccd(P.p, P.b, P.c, width));
      e.merge(point_segment_ccd(P.p, P.c, P.a, width));
    }
  }
  if (!e.hit) return {};
  return {true, e.lo, e.hi};
}

ExactCcdResult edge_edge_ccd_rational(const RationalEdgeEdgeQuery& query, const mpq_class& width) {
  assert(width > 0);
  if (swept_boxes_disjoint({&query.ea0_t0, &query.ea1_t0, &query.ea0_t1, &query.ea1_t1},
                           {&query.eb0_t0, &query.eb1_t0, &query.eb0_t1, &query.eb1_t1})) {
    return {};
  }
  RationalEdgeEdgeQuery q = query;
  normalize(std::array{&q.ea0_t0, &q.ea1_t0, &q.eb0_t0, &q.eb1_t0, &q.ea0_t1, &q.ea1_t1, &q.eb0_t1, &q.eb1_t1});
  const EdgeEdgePolynomials P(q);
  Earliest e;
  if (!P.coplanar.is_zero()) {
    e = first_contact_at_coplanarity_roots(P, width);
  } else {
    // Coplanar throughout: contact at t = 0, or the first contact has an endpoint of one segment
    // on the other.
    RootPoint t0(mpq_class(0));
    if (P.contact(t0)) {
      e = {true, 0, 0};
    } else {
      e = point_segment_ccd(P.a0, P.b0, P.b1, width);
      e.merge(point_segment_ccd(P.a1, P.b0, P.b1, width));
      e.merge(point_segment_ccd(P.b0, P.a0, P.a1, width));
      e.merge(point_segment_ccd(P.b1, P.a0, P.a1, width));
    }
  }
  if (!e.hit) return {};
  return {true, e.lo, e.hi};
}

CcdResult vertex_face_ccd_exact(const RationalVertexFaceQuery& query, const CcdOptions& options) {
  assert(options.min_separation == 0.0);
  return to_ccd_result(vertex_face_ccd_rational(query, positive_width(options.toi_tolerance)));
}

CcdResult edge_edge_ccd_exact(const RationalEdgeEdgeQuery& query, const CcdOptions& options) {
  assert(options.min_separation == 0.0);
  return to_ccd_result(edge_edge_ccd_rational(query, positive_width(options.toi_tolerance)));
}

double round_down(const mpq_class& q) {
  double d = q.get_d();  // truncates toward zero
  if (mpq_class(d) > q) d = std::nextafter(d, -std::numeric_limits<double>::infinity());
  return d;
}

double round_up(const mpq_class& q) {
  double d = q.get_d();
  if (mpq_class(d) < q) d = std::nextafter(d, std::numeric_limits<double>::infinity());
  return d;
}

double round_to_nearest(const mpq_class& q) {
  constexpr double kMax = std::numeric_limits<double>::max();
  // Beyond the largest double: round-to-nearest overflows once q >= max + ulp(max)/2.
  const mpq_class overflow_at = mpq_class(kMax) + mpq_class(std::ldexp(1.0, 970)) / 2;
  if (q >= overflow_at) return std::numeric_limits<double>::infinity();
  if (q <= -overflow_at) return -std::numeric_limits<double>::infinity();
  const double lo = round_down(q);
  const double hi = round_up(q);
  if (lo == hi) return lo;
  if (std::isinf(hi)) return lo;
  if (std::isinf(lo)) return hi;
  const mpq_class d_lo = q - mpq_class(lo);
  const mpq_class d_hi = mpq_class(hi) - q;
  if (d_lo < d_hi) return lo;
  if (d_hi < d_lo) return hi;
  // Tie: the one with an even last mantissa bit.
  int exponent = 0;
  const double mantissa_lo = std::frexp(lo, &exponent);
  const auto bits = static_cast<long long>(std::ldexp(mantissa_lo, 53));
  return (bits % 2 == 0) ? lo : hi;
}

}  // namespace skelcd::ccd
