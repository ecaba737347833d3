// See test_generators_exact.hpp. Written for the tests, from the definitions: orientation signs
// decide every question, each computed exactly.

#include "tests/skinning/test_generators_exact.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Geometry>
#include <gmp.h>

namespace skelcd::test::exact {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;

constexpr double kEps = std::numeric_limits<double>::epsilon() / 2;  // 2^-53

// Exact evaluation: the doubles' values as integers on a common scale 2^-shift (shift from the
// smallest exponent among the non-zero inputs); differences and products of these are exact in
// GMP integers. Scratch integers are per thread and pre-sized, so the exact path rarely allocates.
struct Scratch {
  static constexpr int kCount = 24;
  mpz_t z[kCount];
  Scratch() {
    for (auto& v : z) mpz_init2(v, 512);
  }
  ~Scratch() {
    for (auto& v : z) mpz_clear(v);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

void to_integers(const double* x, int n, mpz_t* out) {
  int min_exp = std::numeric_limits<int>::max();
  for (int i = 0; i < n; ++i) {
    if (x[i] != 0.0) {
      int e = 0;
      (void)std::frexp(x[i], &e);
      min_exp = std::min(min_exp, e - 53);
    }
  }
  for (int i = 0; i < n; ++i) {
    if (x[i] == 0.0) {
      mpz_set_ui(out[i], 0);
      continue;
    }
    int e = 0;
    const double f = std::frexp(x[i], &e);  // x = f · 2^e, |f| in [0.5, 1)
    mpz_set_si(out[i], static_cast<long>(std::ldexp(f, 53)));
    mpz_mul_2exp(out[i], out[i], static_cast<mp_bitcnt_t>(e - 53 - min_exp));
  }
}

bool same_on_an_axis(std::initializer_list<const double*> points) {
  for (int k = 0; k < 3; ++k) {
    bool same = true;
    for (const double* p : points) same = same && p[k] == (*points.begin())[k];
    if (same) return true;
  }
  return false;
}

int orient2d_raw(const Vec2& a, const Vec2& b, const Vec2& c) {
  // Filter: Shewchuk's ccwerrboundA.
  const double detleft = (a.x() - c.x()) * (b.y() - c.y());
  const double detright = (a.y() - c.y()) * (b.x() - c.x());
  const double det = detleft - detright;
  const double bound = (3.0 + 16.0 * kEps) * kEps * (std::abs(detleft) + std::abs(detright));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (a == b || b == c || c == a) return 0;  // repeated point: exactly zero
  if ((a.x() == b.x() && b.x() == c.x()) || (a.y() == b.y() && b.y() == c.y())) return 0;  // on an axis line
  Scratch& s = scratch();
  const double x[6] = {a.x(), a.y(), b.x(), b.y(), c.x(), c.y()};
  mpz_t* z = s.z;
  to_integers(x, 6, z);
  mpz_sub(z[6], z[0], z[4]);   // ax - cx
  mpz_sub(z[7], z[3], z[5]);   // by - cy
  mpz_sub(z[8], z[1], z[5]);   // ay - cy
  mpz_sub(z[9], z[2], z[4]);   // bx - cx
  mpz_mul(z[10], z[6], z[7]);
  mpz_mul(z[11], z[8], z[9]);
  return mpz_cmp(z[10], z[11]) > 0 ? 1 : (mpz_cmp(z[10], z[11]) < 0 ? -1 : 0);
}

// D = (a − d) · ((b − d) × (c − d)), exact sign.
int orient3d_raw(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double adx = a.x() - d.x(), ady = a.y() - d.y(), adz = a.z() - d.z();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y(), bdz = b.z() - d.z();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y(), cdz = c.z() - d.z();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  const double bound = (7.0 + 56.0 * kEps) * kEps * permanent;  // Shewchuk's o3derrboundA
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (a == b || a == c || a == d || b == c || b == d || c == d) return 0;  // repeated point
  if (same_on_an_axis({a.data(), b.data(), c.data(), d.data()})) return 0;  // in an axis plane
  Scratch& s = scratch();
  const double x[12] = {a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z(), d.x(), d.y(), d.z()};
  mpz_t* z = s.z;
  to_integers(x, 12, z);
  // Differences to d, in place: z[0..8] = (a - d, b - d, c - d).
  for (int i = 0; i < 9; ++i) mpz_sub(z[i], z[i], z[9 + i % 3]);
  // D = ax (by cz - bz cy) + ay (bz cx - bx cz) + az (bx cy - by cx).
  mpz_t* t = s.z + 12;
  mpz_mul(t[0], z[4], z[8]);
  mpz_submul(t[0], z[5], z[7]);
  mpz_mul(t[1], z[0], t[0]);
  mpz_mul(t[0], z[5], z[6]);
  mpz_submul(t[0], z[3], z[8]);
  mpz_addmul(t[1], z[1], t[0]);
  mpz_mul(t[0], z[3], z[7]);
  mpz_submul(t[0], z[4], z[6]);
  mpz_addmul(t[1], z[2], t[0]);
  return mpz_sgn(t[1]);
}

// The coordinate axis to drop when projecting the plane of a, b, c: one where the normal's
// component is non-zero (exactly).
int drop_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  int best = -1;
  double best_value = 0;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3;
    const int j = (k + 2) % 3;
    const int s = orient2d_raw({a[i], a[j]}, {b[i], b[j]}, {c[i], c[j]});
    if (s == 0) continue;
    const double v = std::abs((b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]));
    if (best < 0 || v > best_value) {
      best = k;
      best_value = v;
    }
  }
  assert(best >= 0 && "degenerate triangle");
  return best;
}

Vec2 project(const Vec3& p, int drop) { return {p[(drop + 1) % 3], p[(drop + 2) % 3]}; }

bool on_segment_collinear(const Vec2& p, const Vec2& q, const Vec2& u) {
  return std::min(p.x(), q.x()) <= u.x() && u.x() <= std::max(p.x(), q.x()) && std::min(p.y(), q.y()) <= u.y() &&
         u.y() <= std::max(p.y(), q.y());
}

bool segments_intersect_2d(const Vec2& p, const Vec2& q, const Vec2& u, const Vec2& v) {
  const int d1 = orient2d_raw(p, q, u), d2 = orient2d_raw(p, q, v);
  const int d3 = orient2d_raw(u, v, p), d4 = orient2d_raw(u, v, q);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && on_segment_collinear(p, q, u)) || (d2 == 0 && on_segment_collinear(p, q, v)) ||
         (d3 == 0 && on_segment_collinear(u, v, p)) || (d4 == 0 && on_segment_collinear(u, v, q));
}

bool point_in_triangle_2d(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c) {
  const int o1 = orient2d_raw(a, b, p), o2 = orient2d_raw(b, c, p), o3 = orient2d_raw(c, a, p);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

// Closed segment pq against closed triangle abc.
bool segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int sp = orient3d(a, b, c, p);
  const int sq = orient3d(a, b, c, q);
  if (sp * sq > 0) return false;
  if (sp == 0 && sq == 0) {
    const int k = drop_axis(a, b, c);
    const Vec2 p2 = project(p, k), q2 = project(q, k), a2 = project(a, k), b2 = project(b, k), c2 = project(c, k);
    return point_in_triangle_2d(p2, a2, b2, c2) || point_in_triangle_2d(q2, a2, b2, c2) ||
           segments_intersect_2d(p2, q2, a2, b2) || segments_intersect_2d(p2, q2, b2, c2) ||
           segments_intersect_2d(p2, q2, c2, a2);
  }
  // The segment meets the plane in one point; it is in the triangle iff the line pq passes on
  // the same side of (or through) all three edges.
  const int s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

bool triangle_triangle_disjoint_corners(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  for (int i = 0; i < 3; ++i) {
    if (segment_triangle(a[static_cast<std::size_t>(i)], a[static_cast<std::size_t>((i + 1) % 3)], b[0], b[1], b[2])) return true;
    if (segment_triangle(b[static_cast<std::size_t>(i)], b[static_cast<std::size_t>((i + 1) % 3)], a[0], a[1], a[2])) return true;
  }
  return false;
}

// Segment s → x (s a corner of t = (s, t1, t2)) meets t beyond s: x lies in t's plane, inside the
// closed angle of t at s.
bool leaves_into(const Vec3& s, const Vec3& x, const Vec3& t1, const Vec3& t2) {
  if (orient3d(s, t1, t2, x) != 0) return false;
  const int k = drop_axis(s, t1, t2);
  const Vec2 s2 = project(s, k), x2 = project(x, k), a2 = project(t1, k), b2 = project(t2, k);
  const int o = orient2d_raw(s2, a2, b2);
  return o * orient2d_raw(s2, a2, x2) >= 0 && o * orient2d_raw(s2, x2, b2) >= 0;
}

}  // namespace

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return -orient3d_raw(a, b, c, d); }

bool triangles_intersect(
    const std::array<Vec3, 3>& a,
    const std::array<Vec3, 3>& b,
    const std::vector<std::pair<int, int>>& shared) {
  if (shared.empty()) return triangle_triangle_disjoint_corners(a, b);
  if (shared.size() >= 3) return true;  // the same triangle twice
  // Rotate both so that the shared corners come first.
  const auto rotate = [](const std::array<Vec3, 3>& t, int first) {
    return std::array<Vec3, 3>{t[static_cast<std::size_t>(first)], t[static_cast<std::size_t>((first + 1) % 3)],
                               t[static_cast<std::size_t>((first + 2) % 3)]};
  };
  if (shared.size() == 2) {
    // Shared edge u v: beyond it only when coplanar and folded onto the same side.
    const Vec3& u = a[static_cast<std::size_t>(shared[0].first)];
    const Vec3& v = a[static_cast<std::size_t>(shared[1].first)];
    const int ia = 3 - shared[0].first - shared[1].first;
    const int ib = 3 - shared[0].second - shared[1].second;
    const Vec3& pa = a[static_cast<std::size_t>(ia)];
    const Vec3& pb = b[static_cast<std::size_t>(ib)];
    if (orient3d(u, v, pa, pb) != 0) return false;
    const int k = drop_axis(u, v, pa);
    return orient2d_raw(project(u, k), project(v, k), project(pa, k)) * orient2d_raw(project(u, k), project(v, k), project(pb, k)) > 0;
  }
  const std::array<Vec3, 3> ra = rotate(a, shared[0].first);
  const std::array<Vec3, 3> rb = rotate(b, shared[0].second);
  const Vec3& s = ra[0];
  return segment_triangle(ra[1], ra[2], rb[0], rb[1], rb[2]) || segment_triangle(rb[1], rb[2], ra[0], ra[1], ra[2]) ||
         leaves_into(s, ra[1], rb[1], rb[2]) || leaves_into(s, ra[2], rb[1], rb[2]) ||
         leaves_into(s, rb[1], ra[1], ra[2]) || leaves_into(s, rb[2], ra[1], ra[2]);
}

DcdResult self_intersections(
    const skinning::Positions& positions,
    const skinning::Triangles& triangles,
    bool first_only,
    const std::function<bool(std::int32_t, std::int32_t)>& skip) {
  // Weld by exact position.
  std::map<std::array<double, 3>, std::int32_t> ids;
  std::vector<std::int32_t> welded(static_cast<std::size_t>(positions.rows()));
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    const std::array<double, 3> key{positions(v, 0), positions(v, 1), positions(v, 2)};
    welded[static_cast<std::size_t>(v)] = ids.emplace(key, static_cast<std::int32_t>(ids.size())).first->second;
  }
  const auto nf = static_cast<std::int32_t>(triangles.rows());
  std::vector<Eigen::AlignedBox3d> boxes(static_cast<std::size_t>(nf));
  for (std::int32_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) boxes[static_cast<std::size_t>(f)].extend(positions.row(triangles(f, k)).transpose());
  }
  std::vector<std::int32_t> order(static_cast<std::size_t>(nf));
  for (std::int32_t f = 0; f < nf; ++f) order[static_cast<std::size_t>(f)] = f;
  std::sort(order.begin(), order.end(), [&](std::int32_t x, std::int32_t y) {
    return boxes[static_cast<std::size_t>(x)].min().x() < boxes[static_cast<std::size_t>(y)].min().x();
  });
  DcdResult result;
  // Sweep along x: closed boxes overlap when every interval overlaps (touching counts).
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::int32_t fa = order[i];
    const Eigen::AlignedBox3d& ba = boxes[static_cast<std::size_t>(fa)];
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const std::int32_t fb = order[j];
      const Eigen::AlignedBox3d& bb = boxes[static_cast<std::size_t>(fb)];
      if (bb.min().x() > ba.max().x()) break;
      if (bb.min().y() > ba.max().y() || ba.min().y() > bb.max().y() || bb.min().z() > ba.max().z() ||
          ba.min().z() > bb.max().z()) {
        continue;
      }
      const std::int32_t lo = std::min(fa, fb);
      const std::int32_t hi = std::max(fa, fb);
      if (skip && skip(lo, hi)) continue;
      ++result.candidates;
      std::array<Vec3, 3> ta;
      std::array<Vec3, 3> tb;
      std::vector<std::pair<int, int>> shared;
      for (int p = 0; p < 3; ++p) {
        ta[static_cast<std::size_t>(p)] = positions.row(triangles(lo, p)).transpose();
        tb[static_cast<std::size_t>(p)] = positions.row(triangles(hi, p)).transpose();
      }
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) {
          if (welded[static_cast<std::size_t>(triangles(lo, p))] == welded[static_cast<std::size_t>(triangles(hi, q))]) {
            shared.emplace_back(p, q);
          }
        }
      }
      if (triangles_intersect(ta, tb, shared)) {
        result.pairs.emplace_back(lo, hi);
        if (first_only) return result;
      }
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end());
  return result;
}

}  // namespace skelcd::test::exact
