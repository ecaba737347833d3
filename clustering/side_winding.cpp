#include "clustering/side_winding.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

#include "ccd/orientation.hpp"

namespace skelcd::clustering {
namespace {

using V = Eigen::Vector3d;

enum class Meet : std::uint8_t { miss, cross, other };

/// Segment [p, q] against triangle (a, b, c), exactly: miss (no common point), cross (one common
/// point, interior to both, p and q strictly on opposite sides; `sign` is q's side: +1 when the
/// segment runs along the triangle's normal) or other (anything else: a touch at an edge, a vertex
/// or an endpoint, or a segment in the plane).
Meet segment_meets(const V& p, const V& q, const V& a, const V& b, const V& c, int& sign) {
  const int sp = ccd::orient3d(a, b, c, p);
  const int sq = ccd::orient3d(a, b, c, q);
  if (sp == sq && sp != 0) return Meet::miss;  // both strictly on one side
  // The line pq against the triangle's edges: strictly mixed signs put the line outside it (when
  // the segment lies in the plane all three are 0 and the answer is `other`).
  const int e0 = ccd::orient3d(p, q, a, b);
  const int e1 = ccd::orient3d(p, q, b, c);
  const int e2 = ccd::orient3d(p, q, c, a);
  if ((e0 > 0 || e1 > 0 || e2 > 0) && (e0 < 0 || e1 < 0 || e2 < 0)) return Meet::miss;
  if (sp != 0 && sq != 0 && e0 != 0 && e1 != 0 && e2 != 0) {
    sign = sq;
    return Meet::cross;
  }
  return Meet::other;
}

/// Ray tilts from the normal, one per attempt (fixed, far from axes and from one another).
constexpr std::array<std::array<double, 3>, 8> kTilts{{
    {0.1237, 0.2711, -0.0893},
    {-0.2913, 0.0571, 0.1861},
    {0.0419, -0.3127, 0.2203},
    {0.3301, -0.1049, -0.2417},
    {-0.1523, -0.2287, -0.3011},
    {0.2659, 0.3389, 0.0731},
    {-0.3473, 0.1997, -0.1301},
    {0.0877, -0.0619, 0.3529},
}};

}  // namespace

culling::Aabb surface_box(
    std::span<const std::int32_t> surface,
    const skinning::Triangles& triangles,
    const skinning::Positions& x) {
  culling::Aabb box = culling::Aabb::empty();
  for (const std::int32_t t : surface) {
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<Eigen::Index>(triangles(t, k));
      for (std::size_t c = 0; c < 3; ++c) {
        const double p = x(v, static_cast<Eigen::Index>(c));
        box.lo[c] = std::min(box.lo[c], p);
        box.hi[c] = std::max(box.hi[c], p);
      }
    }
  }
  return box;
}

std::optional<WindingRay> winding_ray(
    const culling::Aabb& box,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f,
    int attempt) {
  const auto corner = [&](int k) -> V {
    return x.row(static_cast<Eigen::Index>(triangles(f, k))).transpose();
  };
  const V a = corner(0);
  const V b = corner(1);
  const V c = corner(2);
  const V n = (b - a).cross(c - a);
  const double len = n.norm();
  if (!(len > 0.0) || !std::isfinite(len)) return std::nullopt;
  const V nh = n / len;
  // The short segment [back, front] through f near its centroid, along its normal.
  const V centroid = (a + b + c) / 3.0;
  const double delta = 1e-3 * std::sqrt(len);
  WindingRay ray;
  ray.front = centroid + delta * nh;
  ray.back = centroid - delta * nh;
  int side = 0;
  if (segment_meets(ray.back, ray.front, a, b, c, side) != Meet::cross || side != 1) {
    return std::nullopt;
  }
  // The ray ends beyond the surface's box, where w = 0.
  const V lo(box.lo[0], box.lo[1], box.lo[2]);
  const V hi(box.hi[0], box.hi[1], box.hi[2]);
  const auto& tilt = kTilts[static_cast<std::size_t>(attempt) % kTilts.size()];
  const double scale = 1.0 + static_cast<double>(attempt / static_cast<int>(kTilts.size()));
  V d = nh + scale * V(tilt[0], tilt[1], tilt[2]);
  if (!(d.norm() > 0.0)) return std::nullopt;
  d.normalize();
  const double reach = 2.0 * ((hi - lo).norm() + (ray.front - 0.5 * (lo + hi)).norm()) + 1.0;
  ray.far = ray.front + reach * d;
  ray.dir = d;
  if (!((ray.far.array() < lo.array()).any() || (ray.far.array() > hi.array()).any()) ||
      !ray.far.allFinite()) {
    return std::nullopt;
  }
  return ray;
}

std::optional<int> count_winding(
    const WindingRay& ray,
    std::span<const std::int32_t> candidates,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f) {
  const auto corner = [&](std::int32_t t, int k) -> V {
    return x.row(static_cast<Eigen::Index>(triangles(t, k))).transpose();
  };
  const V& back = ray.back;
  const V& front = ray.front;
  const V& far = ray.far;
  const V& d = ray.dir;
  // Rejects triangles away from the ray by projections on d and on two directions across it,
  // with margins far above the rounding of the projections (a margin only lets more triangles
  // through to the exact test).
  int axis = 0;
  d.cwiseAbs().minCoeff(&axis);
  const V u = d.cross(V::Unit(axis)).normalized();
  const V v = d.cross(u);
  const V span = far - front;
  const double ray_u = span.dot(u);
  const double ray_v = span.dot(v);
  const double ray_d = span.dot(d);
  const double ray_margin = 1e-12 * span.cwiseAbs().sum();
  const V seg_lo = back.cwiseMin(front);
  const V seg_hi = back.cwiseMax(front);
  int w = 0;
  for (const std::int32_t t : candidates) {
    const std::array<V, 3> p{corner(t, 0), corner(t, 1), corner(t, 2)};
    // The short segment meets no other triangle (exact box test, then the exact one).
    if (t != f) {
      V tlo = p[0].cwiseMin(p[1]).cwiseMin(p[2]);
      V thi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
      if ((tlo.array() <= seg_hi.array()).all() && (seg_lo.array() <= thi.array()).all()) {
        int ignored = 0;
        if (segment_meets(back, front, p[0], p[1], p[2], ignored) != Meet::miss) {
          return std::nullopt;
        }
      }
    }
    // The ray [front, far].
    bool away = false;
    for (const auto& [axis_dir, extent] :
         {std::pair<const V*, double>{&u, ray_u}, {&v, ray_v}, {&d, ray_d}}) {
      const double top = std::max(0.0, extent);
      const double bottom = std::min(0.0, extent);
      int above = 0, below = 0;
      for (const V& q : p) {
        const V r = q - front;
        const double s = r.dot(*axis_dir);
        const double margin = 1e-12 * r.cwiseAbs().sum() + ray_margin;
        above += s > top + margin ? 1 : 0;
        below += s < bottom - margin ? 1 : 0;
      }
      if (above == 3 || below == 3) {
        away = true;
        break;
      }
    }
    if (away) continue;
    int sign = 0;
    const Meet m = segment_meets(front, far, p[0], p[1], p[2], sign);
    if (m == Meet::other) return std::nullopt;
    if (m == Meet::cross) w += sign;
  }
  return w;
}

std::optional<int> front_winding(
    std::span<const std::int32_t> surface,
    const culling::Aabb& box,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f,
    int attempt) {
  const std::optional<WindingRay> ray = winding_ray(box, triangles, x, f, attempt);
  if (!ray) return std::nullopt;
  return count_winding(*ray, surface, triangles, x, f);
}

bool segment_meets_box(const V& p, const V& q, const culling::Aabb& box) {
  // Slab test on the box grown by a margin far above the rounding of the arithmetic below (each
  // step is a few roundings of quantities bounded by `scale`); the parameter range [0, 1] is
  // grown too. Growing only lets more boxes through.
  double scale = 0.0;
  for (std::size_t c = 0; c < 3; ++c) {
    scale = std::max({scale, std::abs(box.lo[c]), std::abs(box.hi[c])});
    scale = std::max(
        {scale,
         std::abs(p[static_cast<Eigen::Index>(c)]),
         std::abs(q[static_cast<Eigen::Index>(c)])});
  }
  if (!std::isfinite(scale)) return true;
  const double margin = 1e-9 * scale;
  double t_lo = -1e-9;
  double t_hi = 1.0 + 1e-9;
  for (std::size_t c = 0; c < 3; ++c) {
    const auto i = static_cast<Eigen::Index>(c);
    const double lo = box.lo[c] - margin;
    const double hi = box.hi[c] + margin;
    if (!(lo <= hi)) return false;  // an empty box
    const double s = p[i];
    const double e = q[i] - p[i];
    if (std::abs(e) <= margin) {
      // Nearly parallel to the slab: the whole segment is within `margin` of s along this axis.
      if (s + margin < lo || s - margin > hi) return false;
      continue;
    }
    double t0 = (lo - s) / e;
    double t1 = (hi - s) / e;
    if (t0 > t1) std::swap(t0, t1);
    t_lo = std::max(t_lo, t0 - 1e-9);
    t_hi = std::min(t_hi, t1 + 1e-9);
    if (t_lo > t_hi) return false;
  }
  return true;
}

}  // namespace skelcd::clustering
