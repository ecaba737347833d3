#include "culling/relative_aabb.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "culling/dop.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace skelcd::culling {
namespace {

inline bool shares_vertex(const std::array<std::int32_t, 3>& a, const std::array<std::int32_t, 3>& b) {
  for (const std::int32_t v : a) {
    if (v == b[0] || v == b[1] || v == b[2]) return true;
  }
  return false;
}

/// A triangle's box at t = 0 and at t = 1: lo/hi[time][axis]. Exact (min and max of doubles).
void end_boxes(
    const std::array<std::int32_t, 3>& t,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double (&lo)[2][kEndDirections],
    double (&hi)[2][kEndDirections]) {
  const auto v0 = static_cast<Eigen::Index>(t[0]);
  const auto v1 = static_cast<Eigen::Index>(t[1]);
  const auto v2 = static_cast<Eigen::Index>(t[2]);
  constexpr double kMax = std::numeric_limits<double>::max();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::size_t time = 0; time < 2; ++time) {
    const skinning::Positions& x = time == 0 ? x_t0 : x_t1;
    for (std::size_t k = 0; k < kEndDirections; ++k) {
      const auto c = static_cast<Eigen::Index>(k);
      const double p0 = x(v0, c), p1 = x(v1, c), p2 = x(v2, c);
      // A coordinate that is not finite: the widest box, never apart from anything.
      const bool finite = std::abs(p0) <= kMax && std::abs(p1) <= kMax && std::abs(p2) <= kMax;
      lo[time][k] = finite ? std::min({p0, p1, p2}) : -kInf;
      hi[time][k] = finite ? std::max({p0, p1, p2}) : kInf;
    }
  }
}

/// How far apart two boxes must be on an axis for points 2·half_width apart or less to be
/// excluded, rounded up (0 for half_width 0).
double end_reach(double half_width) { return half_width == 0.0 ? 0.0 : next_up(2.0 * half_width); }

/// Whether one triangle's box on an axis, [·, hi0] at t = 0 and [·, hi1] at t = 1, lies more than
/// `reach` below another's, [lo0b, ·] and [lo1b, ·], at both ends (strictly; the sum rounded up
/// when reach > 0).
inline bool below_at_both_ends(double hi0, double hi1, double lo0b, double lo1b, double reach) {
  if (reach == 0.0) return hi0 < lo0b && hi1 < lo1b;
  return next_up(hi0 + reach) < lo0b && next_up(hi1 + reach) < lo1b;
}

}  // namespace

bool relative_boxes_overlap(
    const FeatureTopology& topology,
    const TrianglePair& pair,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width) {
  assert(half_width >= 0.0);
  double alo[2][kEndDirections], ahi[2][kEndDirections];
  double blo[2][kEndDirections], bhi[2][kEndDirections];
  end_boxes(topology.triangle(pair.a), x_t0, x_t1, alo, ahi);
  end_boxes(topology.triangle(pair.b), x_t0, x_t1, blo, bhi);
  const double reach = end_reach(half_width);
  for (std::size_t k = 0; k < kEndDirections; ++k) {
    if (below_at_both_ends(ahi[0][k], ahi[1][k], blo[0][k], blo[1][k], reach) ||
        below_at_both_ends(bhi[0][k], bhi[1][k], alo[0][k], alo[1][k], reach)) {
      return false;
    }
  }
  return true;
}

namespace {

/// Removes, in place (order kept), the pairs of [from, to) without a shared vertex whose relative
/// boxes are apart; returns the new end of the range (the caller erases the rest of it).
std::vector<TrianglePair>::iterator remove_apart(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<TrianglePair>::iterator from,
    std::vector<TrianglePair>::iterator to) {
  return std::remove_if(from, to, [&](const TrianglePair& p) {
    if (shares_vertex(topology.triangle(p.a), topology.triangle(p.b))) return false;
    return !relative_boxes_overlap(topology, p, x_t0, x_t1, half_width);
  });
}

}  // namespace

std::int64_t relative_aabb_filter(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<TrianglePair>& pairs,
    std::size_t first) {
  assert(first <= pairs.size());
  const auto from = pairs.begin() + static_cast<std::ptrdiff_t>(first);
  const auto kept = remove_apart(topology, x_t0, x_t1, half_width, from, pairs.end());
  const auto removed = static_cast<std::int64_t>(pairs.end() - kept);
  pairs.erase(kept, pairs.end());
  return removed;
}

void RelativeAabbFilter::prepare(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  const std::int32_t num_triangles = topology.num_triangles();
  triangles_.resize(static_cast<std::size_t>(num_triangles));
  for (std::int32_t f = 0; f < num_triangles; ++f) {
    Triangle& t = triangles_[static_cast<std::size_t>(f)];
    double lo[2][kEndDirections], hi[2][kEndDirections];
    end_boxes(topology.triangle(f), x_t0, x_t1, lo, hi);
    for (std::size_t k = 0; k < kEndDirections; ++k) {
      t.lo0[k] = lo[0][k];
      t.hi0[k] = hi[0][k];
      t.lo1[k] = lo[1][k];
      t.hi1[k] = hi[1][k];
    }
  }
}

bool RelativeAabbFilter::overlap(const TrianglePair& pair, double half_width) const {
  assert(half_width >= 0.0);
  const Triangle& a = triangles_[static_cast<std::size_t>(pair.a)];
  const Triangle& b = triangles_[static_cast<std::size_t>(pair.b)];
  const double reach = end_reach(half_width);
  for (std::size_t k = 0; k < kEndDirections; ++k) {
    if (below_at_both_ends(a.hi0[k], a.hi1[k], b.lo0[k], b.lo1[k], reach) ||
        below_at_both_ends(b.hi0[k], b.hi1[k], a.lo0[k], a.lo1[k], reach)) {
      return false;
    }
  }
  return true;
}

std::int64_t RelativeAabbFilter::filter(
    const FeatureTopology& topology,
    double half_width,
    std::vector<TrianglePair>& pairs,
    std::size_t first) const {
  assert(first <= pairs.size());
  const auto from = pairs.begin() + static_cast<std::ptrdiff_t>(first);
  const auto kept = std::remove_if(from, pairs.end(), [&](const TrianglePair& p) {
    if (shares_vertex(topology.triangle(p.a), topology.triangle(p.b))) return false;
    return !overlap(p, half_width);
  });
  const auto removed = static_cast<std::int64_t>(pairs.end() - kept);
  pairs.erase(kept, pairs.end());
  return removed;
}

double motion_scale(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  const Eigen::Index num_vertices = std::min(x_t0.rows(), x_t1.rows());
  const std::int32_t num_triangles = topology.num_triangles();
  if (num_vertices == 0 || num_triangles == 0) return 0.0;
  double moved = 0.0;
  double size = 0.0;
#if defined(__SSE2__)
  // The same terms, summed in the same order: each is a max of exact differences (or of absolute
  // values of one rounded difference each), which the lanes compute alike. Positions are
  // finite (the methods check them), so max and min need no NaN rule.
  const double* p0 = x_t0.data();  // row-major #W × 3
  const double* p1 = x_t1.data();
  const __m128d sign = _mm_set1_pd(-0.0);
  for (Eigen::Index v = 0; v < num_vertices; ++v) {
    const __m128d d =
        _mm_andnot_pd(sign, _mm_sub_pd(_mm_loadu_pd(p1 + 3 * v), _mm_loadu_pd(p0 + 3 * v)));
    const double dz = std::abs(p1[3 * v + 2] - p0[3 * v + 2]);
    moved += std::max(_mm_cvtsd_f64(_mm_max_sd(d, _mm_unpackhi_pd(d, d))), dz);
  }
  for (std::int32_t f = 0; f < num_triangles; ++f) {
    const auto& t = topology.triangle(f);
    const double* a = p0 + 3 * static_cast<std::ptrdiff_t>(t[0]);
    const double* b = p0 + 3 * static_cast<std::ptrdiff_t>(t[1]);
    const double* c = p0 + 3 * static_cast<std::ptrdiff_t>(t[2]);
    const __m128d axy = _mm_loadu_pd(a), bxy = _mm_loadu_pd(b), cxy = _mm_loadu_pd(c);
    const __m128d dxy =
        _mm_sub_pd(_mm_max_pd(_mm_max_pd(axy, bxy), cxy), _mm_min_pd(_mm_min_pd(axy, bxy), cxy));
    const double dz = std::max({a[2], b[2], c[2]}) - std::min({a[2], b[2], c[2]});
    size += std::max(std::max(_mm_cvtsd_f64(dxy), _mm_cvtsd_f64(_mm_unpackhi_pd(dxy, dxy))), dz);
  }
#else
  for (Eigen::Index v = 0; v < num_vertices; ++v) {
    moved += std::max(
        {std::abs(x_t1(v, 0) - x_t0(v, 0)),
         std::abs(x_t1(v, 1) - x_t0(v, 1)),
         std::abs(x_t1(v, 2) - x_t0(v, 2))});
  }
  for (std::int32_t f = 0; f < num_triangles; ++f) {
    const auto& t = topology.triangle(f);
    const auto a = static_cast<Eigen::Index>(t[0]);
    const auto b = static_cast<Eigen::Index>(t[1]);
    const auto c = static_cast<Eigen::Index>(t[2]);
    double side = 0.0;
    for (Eigen::Index k = 0; k < 3; ++k) {
      side = std::max(
          side,
          std::max({x_t0(a, k), x_t0(b, k), x_t0(c, k)}) -
              std::min({x_t0(a, k), x_t0(b, k), x_t0(c, k)}));
    }
    size += side;
  }
#endif
  const double scale =
      (moved / static_cast<double>(num_vertices)) / (size / static_cast<double>(num_triangles));
  return std::isfinite(scale) ? scale : 0.0;
}

std::size_t RelativePairTrial::trial_pairs(std::int32_t num_triangles) {
  return std::clamp<std::size_t>(
      static_cast<std::size_t>(std::max(num_triangles, 0)), 1, kMaxTrial);
}

void RelativePairTrial::start(std::size_t trial) {
  trial_ = std::max<std::size_t>(trial, 1);
  seen_ = 0;
  removed_ = 0;
  state_ = State::trial;
}

std::int64_t RelativePairTrial::filter(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<TrianglePair>& pairs,
    std::size_t first) {
  assert(first <= pairs.size());
  std::int64_t removed = 0;
  if (state_ == State::trial) {
    // Exactly the query's first trial_ pairs, from the positions, whatever the installments:
    // the decision, and so every counter, is the same for any block size.
    const std::size_t k = std::min(pairs.size() - first, trial_ - static_cast<std::size_t>(seen_));
    const auto from = pairs.begin() + static_cast<std::ptrdiff_t>(first);
    const auto to = from + static_cast<std::ptrdiff_t>(k);
    const auto kept = remove_apart(topology, x_t0, x_t1, half_width, from, to);
    removed = static_cast<std::int64_t>(to - kept);
    pairs.erase(kept, to);
    seen_ += static_cast<std::int64_t>(k);
    removed_ += removed;
    first += k - static_cast<std::size_t>(removed);
    if (seen_ >= static_cast<std::int64_t>(trial_)) {
      if (static_cast<double>(removed_) >= kTrialShare * static_cast<double>(seen_)) {
        prepared_.prepare(topology, x_t0, x_t1);
        state_ = State::kept;
      } else {
        state_ = State::dropped;
      }
    }
  }
  if (state_ == State::kept) removed += prepared_.filter(topology, half_width, pairs, first);
  return removed;
}

}  // namespace skelcd::culling
