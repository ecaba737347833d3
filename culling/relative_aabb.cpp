#include "culling/relative_aabb.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include "culling/dop.hpp"

namespace skelcd::culling {
namespace {

inline bool shares_vertex(const std::array<std::int32_t, 3>& a, const std::array<std::int32_t, 3>& b) {
  for (const std::int32_t v : a) {
    if (v == b[0] || v == b[1] || v == b[2]) return true;
  }
  return false;
}

/// The swept box of one triangle in the relative motion: its corners at t = 0 (exact) and at
/// t = 1 minus the common displacement `w`. With `bracket`, each rounded difference is bracketed
/// by its neighbours (round-to-nearest is within one ulp of the exact difference); without, the
/// box holds the rounded differences themselves, which is enough for a test without width
/// (RelativeAabbFilter's class comment says why).
Aabb relative_box(
    const std::array<std::int32_t, 3>& t,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const Eigen::Vector3d& w,
    bool bracket) {
  Aabb box = Aabb::empty();
  for (const std::int32_t v : t) {
    const auto i = static_cast<Eigen::Index>(v);
    for (std::size_t k = 0; k < 3; ++k) {
      const auto c = static_cast<Eigen::Index>(k);
      const double p0 = x_t0(i, c);
      const double p1 = x_t1(i, c) - w[c];
      box.lo[k] = std::min({box.lo[k], p0, bracket ? next_down(p1) : p1});
      box.hi[k] = std::max({box.hi[k], p0, bracket ? next_up(p1) : p1});
    }
  }
  return box;
}

}  // namespace

bool relative_boxes_overlap(
    const FeatureTopology& topology,
    const TrianglePair& pair,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width) {
  assert(half_width >= 0.0);
  const auto& ta = topology.triangle(pair.a);
  const auto& tb = topology.triangle(pair.b);
  // The mean displacement of the six corners over the interval (velocity × Δt, Δt = 1).
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (const auto* t : {&ta, &tb}) {
    for (const std::int32_t v : *t) {
      const auto i = static_cast<Eigen::Index>(v);
      w += (x_t1.row(i) - x_t0.row(i)).transpose();
    }
  }
  w /= 6.0;
  const bool bracket = half_width > 0.0;
  Aabb a = relative_box(ta, x_t0, x_t1, w, bracket);
  Aabb b = relative_box(tb, x_t0, x_t1, w, bracket);
  a.inflate(half_width);
  b.inflate(half_width);
  return a.overlaps(b);
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
    const auto& corners = topology.triangle(f);
    for (std::size_t k = 0; k < 3; ++k) {
      const auto c = static_cast<Eigen::Index>(k);
      const auto v0 = static_cast<Eigen::Index>(corners[0]);
      const auto v1 = static_cast<Eigen::Index>(corners[1]);
      const auto v2 = static_cast<Eigen::Index>(corners[2]);
      t.lo0[k] = std::min({x_t0(v0, c), x_t0(v1, c), x_t0(v2, c)});
      t.hi0[k] = std::max({x_t0(v0, c), x_t0(v1, c), x_t0(v2, c)});
      t.lo1[k] = std::min({x_t1(v0, c), x_t1(v1, c), x_t1(v2, c)});
      t.hi1[k] = std::max({x_t1(v0, c), x_t1(v1, c), x_t1(v2, c)});
      t.sixth_displacement[k] = (((x_t1(v0, c) - x_t0(v0, c)) + (x_t1(v1, c) - x_t0(v1, c))) +
                                 (x_t1(v2, c) - x_t0(v2, c))) /
                                6.0;
    }
  }
}

bool RelativeAabbFilter::overlap(const TrianglePair& pair, double half_width) const {
  assert(half_width >= 0.0);
  const Triangle& a = triangles_[static_cast<std::size_t>(pair.a)];
  const Triangle& b = triangles_[static_cast<std::size_t>(pair.b)];
  if (half_width == 0.0) {
    // Apart on an axis when one box's lower end is above the other's upper end. Every end is a
    // double of the input (lo0, hi0) or a rounded fl(y - w) with the pair's one w, and rounding
    // is monotone: fl(y - w) > fl(z - w) implies y > z, fl(y - w) > c implies y - w > c for a
    // double c, and likewise the other way round. So a strict inequality between the rounded ends
    // holds between the exact ones: no bracketing, and no box to build.
    for (std::size_t k = 0; k < 3; ++k) {
      const double w = a.sixth_displacement[k] + b.sixth_displacement[k];
      const double a_lo = std::min(a.lo0[k], a.lo1[k] - w);
      const double a_hi = std::max(a.hi0[k], a.hi1[k] - w);
      const double b_lo = std::min(b.lo0[k], b.lo1[k] - w);
      const double b_hi = std::max(b.hi0[k], b.hi1[k] - w);
      if (a_lo > b_hi || b_lo > a_hi) return false;
    }
    return true;
  }
  Aabb ra, rb;
  for (std::size_t k = 0; k < 3; ++k) {
    const double w = a.sixth_displacement[k] + b.sixth_displacement[k];
    ra.lo[k] = std::min(a.lo0[k], next_down(a.lo1[k] - w));
    ra.hi[k] = std::max(a.hi0[k], next_up(a.hi1[k] - w));
    rb.lo[k] = std::min(b.lo0[k], next_down(b.lo1[k] - w));
    rb.hi[k] = std::max(b.hi0[k], next_up(b.hi1[k] - w));
  }
  ra.inflate(half_width);
  rb.inflate(half_width);
  return ra.overlaps(rb);
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
  for (Eigen::Index v = 0; v < num_vertices; ++v) {
    moved += std::max(
        {std::abs(x_t1(v, 0) - x_t0(v, 0)),
         std::abs(x_t1(v, 1) - x_t0(v, 1)),
         std::abs(x_t1(v, 2) - x_t0(v, 2))});
  }
  double size = 0.0;
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
