#include "culling/bvh.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "culling/detail/swept_corners.hpp"
#include "skinning/errors.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#define SKELCD_BVH_AVX 1
#include <immintrin.h>

#include "ccd/detail/lanes.hpp"
#endif

namespace skelcd::culling {

namespace {

/// detail::force_bvh_baseline_binning's switch.
std::atomic<bool> baseline_binning{false};

/// The surface-area split's slabs per axis (Bvh::sah_split).
constexpr int kSahBins = 16;

/// A slab's box as x, y, z and a pad, so that two lanes of SSE2 (or four of AVX) update it (min /
/// max pick the same operand as std::min / std::max, so the boxes are those of a scalar loop, bit
/// for bit; the pad is never read).
struct alignas(32) SahBinBox {
  double lo[4];
  double hi[4];
};
using SahCounts = std::array<std::array<std::int32_t, kSahBins>, 3>;
using SahBoxes = std::array<std::array<SahBinBox, kSahBins>, 3>;

#if defined(SKELCD_BVH_AVX)
/// sah_split's binning of the items [first, last) on every axis, built for AVX where the CPU has
/// it: the same bins (the same SSE2 arithmetic, VEX-encoded) and the same boxes (each slab's lo
/// and hi updated by one four-lane min and max instead of two two-lane ones; lane 3 takes 0 and
/// is never read). `origin` and `scale` are the range's centroid box's low corner and kSahBins
/// over its extents (0 on an axis not used).
template <class Item>
[[gnu::target("avx")]] void sah_bins_avx(
    const Item* first,
    const Item* last,
    const double* origin,
    const double* scale,
    SahCounts& counts,
    SahBoxes& boxes) {
  const __m128d origin01 = _mm_loadu_pd(origin);
  const __m128d origin2 = _mm_load_sd(origin + 2);
  const __m128d scale01 = _mm_loadu_pd(scale);
  const __m128d scale2 = _mm_load_sd(scale + 2);
  const __m128d last_bin = _mm_set1_pd(kSahBins - 1.0);
  const __m128d zero = _mm_setzero_pd();
  for (const Item* item = first; item != last; ++item) {
    const __m256d lo = _mm256_insertf128_pd(
        _mm256_castpd128_pd256(_mm_loadu_pd(item->lo.data())), _mm_load_sd(item->lo.data() + 2), 1);
    const __m256d hi = _mm256_insertf128_pd(
        _mm256_castpd128_pd256(_mm_loadu_pd(item->hi.data())), _mm_load_sd(item->hi.data() + 2), 1);
    const __m128d t01 =
        _mm_mul_pd(_mm_sub_pd(_mm_loadu_pd(item->centroid.data()), origin01), scale01);
    const __m128d t2 =
        _mm_mul_sd(_mm_sub_sd(_mm_load_sd(item->centroid.data() + 2), origin2), scale2);
    const __m128i j01 = _mm_cvttpd_epi32(_mm_max_pd(_mm_min_pd(last_bin, t01), zero));
    const std::array<int, 3> bins{
        _mm_cvtsi128_si32(j01),
        _mm_cvtsi128_si32(_mm_srli_si128(j01, 4)),
        _mm_cvttsd_si32(_mm_max_sd(_mm_min_sd(last_bin, t2), zero))};
    for (std::size_t a = 0; a < 3; ++a) {
      const auto j = static_cast<std::size_t>(bins[a]);
      ++counts[a][j];
      SahBinBox& b = boxes[a][j];
      _mm256_store_pd(b.lo, _mm256_min_pd(lo, _mm256_load_pd(b.lo)));
      _mm256_store_pd(b.hi, _mm256_max_pd(hi, _mm256_load_pd(b.hi)));
    }
  }
}
#endif

}  // namespace

template <int N>
Bvh<N>::Bvh(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const BvhOptions& options)
    : leaf_size_(options.leaf_size),
      node_volumes_(options.node_volumes),
      float_node_volumes_(options.node_volumes && options.float_node_volumes),
      split_(options.split) {
  order_.resize(static_cast<std::size_t>(triangles.rows()));
  std::iota(order_.begin(), order_.end(), 0);
  build(triangles, positions);
}

template <int N>
Bvh<N>::Bvh(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    std::span<const std::int32_t> subset,
    const BvhOptions& options)
    : order_(subset.begin(), subset.end()),
      leaf_size_(options.leaf_size),
      node_volumes_(options.node_volumes),
      float_node_volumes_(options.node_volumes && options.float_node_volumes),
      split_(options.split) {
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (order_[i] < 0 || order_[i] >= triangles.rows()) {
      throw InvalidInput(
          "culling::Bvh: subset entry " + std::to_string(i) + " is triangle " +
          std::to_string(order_[i]) + ", outside [0, " + std::to_string(triangles.rows()) + ")");
    }
  }
  build(triangles, positions);
}

template <int N>
void Bvh<N>::build(const skinning::Triangles& triangles, const skinning::Positions& positions) {
  if (leaf_size_ < 1) {
    throw InvalidInput(
        "culling::Bvh: leaf_size must be at least 1, got " + std::to_string(leaf_size_));
  }
  // Centroids (times 3: the split only compares them) of the triangles, by slot.
  items_.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const auto f = static_cast<Eigen::Index>(order_[i]);
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t v = triangles(f, k);
      if (v < 0 || v >= positions.rows()) {
        throw InvalidInput(
            "culling::Bvh: triangle " + std::to_string(f) + " corner " + std::to_string(k) +
            " is vertex " + std::to_string(v) + ", outside [0, " +
            std::to_string(positions.rows()) + ")");
      }
      const Eigen::Vector3d p = positions.row(v).transpose();
      c += p;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    items_[i] = {c, lo, hi, order_[i]};
  }
  nodes_.clear();
  depth_ = 0;
  if (!order_.empty()) {
    // A binary tree with #F leaves at most has 2·#F − 1 nodes.
    nodes_.reserve(2 * order_.size() - 1);
    if (split_ == BvhSplit::surface_area) spill_.resize(order_.size() / 2);
    build_range(0, static_cast<std::int32_t>(order_.size()), 0);
  }
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = items_[i].id;
  if (float_node_volumes_) {
    FloatDop<N> empty;
    empty.lo.fill(std::numeric_limits<float>::infinity());
    empty.hi.fill(-std::numeric_limits<float>::infinity());
    float_node_bounds_.assign(nodes_.size(), empty);
  } else if (node_volumes_) {
    node_bounds_.assign(nodes_.size(), Volume::empty());
  }
  constexpr auto kAxes = static_cast<std::size_t>(kSlotAxes);
  slot_bounds_.assign(2 * kAxes * slot_stride(), 0.0f);
  for (std::size_t k = 0; k < kAxes; ++k) {
    float* lo = slot_bounds_.data() + k * slot_stride();
    float* hi = slot_bounds_.data() + (kAxes + k) * slot_stride();
    std::fill(lo, lo + slot_stride(), std::numeric_limits<float>::infinity());
    std::fill(hi, hi + slot_stride(), -std::numeric_limits<float>::infinity());
  }
  std::vector<Item>().swap(items_);  // free them: `items_ = {}` would keep the capacity
  std::vector<Item>().swap(spill_);
  build_wide();
}

template <int N>
void Bvh<N>::build_wide() {
  wide_.clear();
  wide_depth_ = 0;
  if (nodes_.empty()) return;
  // The virtual root (one lane: the root), then the inner nodes depth first, counted first so that
  // the vector is allocated once at its size (about #F / 12 nodes).
  wide_.reserve(nodes_[0].size() > bucket_size(leaf_size_) ? 1 + count_wide(0) : 1);
  wide_.emplace_back();
  WideBvhNode<N>& root = wide_[0];
  for (int k = 0; k < N; ++k) {
    for (int i = 0; i < WideBvhNode<N>::kWidth; ++i) {
      root.lo[k][i] = std::numeric_limits<float>::infinity();
      root.hi[k][i] = -std::numeric_limits<float>::infinity();
    }
  }
  root.num_children = 1;
  root.node[0] = 0;
  root.count[0] = nodes_[0].size();
  root.child[0] = ~nodes_[0].begin;
  wide_depth_ = 1;
  if (nodes_[0].size() > bucket_size(leaf_size_)) {
    const std::int32_t w = build_wide_node(0, 2);
    wide_[0].child[0] = w;
  }
}

template <int N>
int Bvh<N>::wide_lanes(
    std::int32_t node, std::array<std::int32_t, WideBvhNode<N>::kWidth>& lanes) const {
  // Collapse: start from the two children and, while fewer than four, replace the one with the
  // most triangles (the first on ties) that is larger than a bucket by its two children, in place
  // (left, right). A node larger than a bucket is larger than a leaf: it has children.
  const int bucket = bucket_size(leaf_size_);
  const BvhNode& n = nodes_[static_cast<std::size_t>(node)];
  lanes[0] = node + 1;
  lanes[1] = n.right;
  int used = 2;
  while (used < WideBvhNode<N>::kWidth) {
    int pick = -1;
    for (int i = 0; i < used; ++i) {
      const BvhNode& c = nodes_[static_cast<std::size_t>(lanes[static_cast<std::size_t>(i)])];
      if (c.size() <= bucket) continue;
      if (pick < 0 ||
          c.size() >
              nodes_[static_cast<std::size_t>(lanes[static_cast<std::size_t>(pick)])].size()) {
        pick = i;
      }
    }
    if (pick < 0) break;
    const std::int32_t split = lanes[static_cast<std::size_t>(pick)];
    for (int i = used; i > pick + 1; --i) {
      lanes[static_cast<std::size_t>(i)] = lanes[static_cast<std::size_t>(i - 1)];
    }
    lanes[static_cast<std::size_t>(pick)] = split + 1;
    lanes[static_cast<std::size_t>(pick + 1)] = nodes_[static_cast<std::size_t>(split)].right;
    ++used;
  }
  return used;
}

template <int N>
std::size_t Bvh<N>::count_wide(std::int32_t node) const {
  std::array<std::int32_t, WideBvhNode<N>::kWidth> lanes{};
  const int used = wide_lanes(node, lanes);
  std::size_t count = 1;
  for (int i = 0; i < used; ++i) {
    const std::int32_t c = lanes[static_cast<std::size_t>(i)];
    if (nodes_[static_cast<std::size_t>(c)].size() > bucket_size(leaf_size_))
      count += count_wide(c);
  }
  return count;
}

template <int N>
std::int32_t Bvh<N>::build_wide_node(std::int32_t node, int depth) {
  using Wide = WideBvhNode<N>;
  const auto index = static_cast<std::int32_t>(wide_.size());
  wide_.emplace_back();
  wide_depth_ = std::max(wide_depth_, depth);
  const int bucket = bucket_size(leaf_size_);
  std::array<std::int32_t, Wide::kWidth> lanes{};
  const int used = wide_lanes(node, lanes);
  // Lanes: unused ones empty; leaves point into triangle_order, inner children to their wide node.
  {
    Wide& w = wide_[static_cast<std::size_t>(index)];
    for (int k = 0; k < N; ++k) {
      for (int i = 0; i < Wide::kWidth; ++i) {
        w.lo[k][i] = std::numeric_limits<float>::infinity();
        w.hi[k][i] = -std::numeric_limits<float>::infinity();
      }
    }
    for (int i = 0; i < Wide::kWidth; ++i) {
      w.child[i] = 0;
      w.count[i] = 0;
      w.node[i] = 0;
    }
    w.num_children = used;
  }
  for (int i = 0; i < used; ++i) {
    const std::int32_t c = lanes[static_cast<std::size_t>(i)];
    const BvhNode& cn = nodes_[static_cast<std::size_t>(c)];
    // build_wide_node grows wide_: no reference into it is held across the call.
    const std::int32_t child = cn.size() <= bucket ? ~cn.begin : build_wide_node(c, depth + 1);
    Wide& w = wide_[static_cast<std::size_t>(index)];
    w.child[i] = child;
    w.count[i] = cn.size();
    w.node[i] = c;
  }
  return index;
}

template <int N>
std::int32_t Bvh<N>::build_range(
    std::int32_t begin, std::int32_t end, int depth, const CentroidBox* known) {
  const auto index = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({begin, end, 0});
  depth_ = std::max(depth_, depth);
  if (end - begin <= leaf_size_) return index;

  // Longest axis of the centroids' bounding box (the split that made this range met them all:
  // its box comes with it, else one pass here).
  CentroidBox box;
  if (known != nullptr) {
    box = *known;
  } else {
    box.lo = items_[static_cast<std::size_t>(begin)].centroid;
    box.hi = box.lo;
    for (std::int32_t i = begin + 1; i < end; ++i) {
      box.lo = box.lo.cwiseMin(items_[static_cast<std::size_t>(i)].centroid);
      box.hi = box.hi.cwiseMax(items_[static_cast<std::size_t>(i)].centroid);
    }
  }
  Eigen::Index axis = 0;
  (box.hi - box.lo).maxCoeff(&axis);

  // The surface-area heuristic's split where it finds one (down to kMaxSahDepth, which bounds
  // the recursion and the tree's depth on any input, and above the buckets: inside one the split
  // orders only its slots, which the traversals test as a whole, and most calls would be there),
  // else the median split by count along the longest axis: the lower half of centroids goes left.
  // Ties are broken by triangle id so the tree depends only on the input, not on the library's
  // nth_element.
  constexpr int kMaxSahDepth = 48;
  const bool surface_area = split_ == BvhSplit::surface_area && depth < kMaxSahDepth &&
                            end - begin > bucket_size(leaf_size_);
  std::array<CentroidBox, 2> sides;
  std::int32_t mid = surface_area ? sah_split(begin, end, box.lo, box.hi, sides) : -1;
  const bool sides_known = mid >= 0;
  if (mid < 0) {
    mid = begin + (end - begin) / 2;
    const auto before = [axis](const Item& s, const Item& t) {
      const double cs = s.centroid[axis];
      const double ct = t.centroid[axis];
      if (cs != ct) return cs < ct;
      return s.id < t.id;
    };
    std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end, before);
  }

  build_range(begin, mid, depth + 1, sides_known ? &sides[0] : nullptr);
  const std::int32_t right = build_range(mid, end, depth + 1, sides_known ? &sides[1] : nullptr);
  nodes_[static_cast<std::size_t>(index)].right = right;
  return index;
}

template <int N>
std::int32_t Bvh<N>::sah_split(
    std::int32_t begin,
    std::int32_t end,
    const Eigen::Vector3d& lo,
    const Eigen::Vector3d& hi,
    std::array<CentroidBox, 2>& sides) {
  // Binned (Wald 2007): the centroids in kBins equal slabs per axis, each bin's count and box;
  // the cost of the split after bin j is area(left) · #left + area(right) · #right, the expected
  // work of a query that meets the parent's box meeting each child's.
  constexpr int kBins = kSahBins;
  using BinBox = SahBinBox;
  const auto area = [](const double* l, const double* h) {
    const double dx = std::max(h[0] - l[0], 0.0);
    const double dy = std::max(h[1] - l[1], 0.0);
    const double dz = std::max(h[2] - l[2], 0.0);
    return dx * dy + dy * dz + dz * dx;
  };
  const auto bin_of = [&](const Item& item, Eigen::Index axis, double scale) {
    const double t = (item.centroid[axis] - lo[axis]) * scale;
    return static_cast<int>(std::max(0.0, std::min(t, kBins - 1.0)));  // NaN: bin 0; no branch
  };
  // One pass over the range bins it on every axis (the items are streamed once, not three times).
  std::array<double, 3> scale{};
  std::array<bool, 3> usable{};
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    const double extent = hi[axis] - lo[axis];
    const auto a = static_cast<std::size_t>(axis);
    usable[a] = extent > 0.0 && std::isfinite(extent);
    scale[a] = usable[a] ? kBins / extent : 0.0;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  SahCounts counts{};
  SahBoxes boxes;
  for (auto& axis_boxes : boxes) {
    for (BinBox& b : axis_boxes) {
      for (int k = 0; k < 4; ++k) {
        b.lo[k] = kInf;
        b.hi[k] = -kInf;
      }
    }
  }
#if defined(SKELCD_BVH_AVX)
  const bool avx = ccd::detail::cpu_has_avx2() && !baseline_binning.load(std::memory_order_relaxed);
  if (avx) {
    sah_bins_avx(
        items_.data() + begin, items_.data() + end, lo.data(), scale.data(), counts, boxes);
  }
#else
  constexpr bool avx = false;
#endif
  if (!avx) {
#if defined(__SSE2__)
    // bin_of on the three axes at once, x and y in two lanes: the same subtraction and product,
    // then _mm_min_pd(15, t) = 15 < t ? 15 : t = std::min(t, 15) and _mm_max_pd(m, 0) = m > 0 ? m :
    // 0 = std::max(0, m) (NaN: 0), truncated as static_cast<int> truncates: the same bins.
    const __m128d origin01 = _mm_loadu_pd(lo.data());
    const __m128d origin2 = _mm_load_sd(lo.data() + 2);
    const __m128d scale01 = _mm_loadu_pd(scale.data());
    const __m128d scale2 = _mm_load_sd(scale.data() + 2);
    const __m128d last_bin = _mm_set1_pd(kBins - 1.0);
    const __m128d zero = _mm_setzero_pd();
#endif
    for (std::int32_t i = begin; i < end; ++i) {
      const Item& item = items_[static_cast<std::size_t>(i)];
#if defined(__SSE2__)
      const __m128d lo01 = _mm_loadu_pd(item.lo.data());
      const __m128d lo2 = _mm_load_sd(item.lo.data() + 2);
      const __m128d hi01 = _mm_loadu_pd(item.hi.data());
      const __m128d hi2 = _mm_load_sd(item.hi.data() + 2);
      const __m128d t01 =
          _mm_mul_pd(_mm_sub_pd(_mm_loadu_pd(item.centroid.data()), origin01), scale01);
      const __m128d t2 =
          _mm_mul_sd(_mm_sub_sd(_mm_load_sd(item.centroid.data() + 2), origin2), scale2);
      const __m128i j01 = _mm_cvttpd_epi32(_mm_max_pd(_mm_min_pd(last_bin, t01), zero));
      const int j2 = _mm_cvttsd_si32(_mm_max_sd(_mm_min_sd(last_bin, t2), zero));
      const std::array<int, 3> bins{
          _mm_cvtsi128_si32(j01), _mm_cvtsi128_si32(_mm_srli_si128(j01, 4)), j2};
#endif
      for (Eigen::Index axis = 0; axis < 3; ++axis) {
        const auto a = static_cast<std::size_t>(axis);
#if defined(__SSE2__)
        const auto j = static_cast<std::size_t>(bins[a]);
#else
        const auto j = static_cast<std::size_t>(bin_of(item, axis, scale[a]));
#endif
        ++counts[a][j];
        BinBox& b = boxes[a][j];
#if defined(__SSE2__)
        // _mm_min_pd(x, y) is x < y ? x : y: std::min(y, x), as the scalar loop below.
        _mm_store_pd(b.lo, _mm_min_pd(lo01, _mm_load_pd(b.lo)));
        _mm_store_pd(b.lo + 2, _mm_min_pd(lo2, _mm_load_pd(b.lo + 2)));
        _mm_store_pd(b.hi, _mm_max_pd(hi01, _mm_load_pd(b.hi)));
        _mm_store_pd(b.hi + 2, _mm_max_pd(hi2, _mm_load_pd(b.hi + 2)));
#else
        for (Eigen::Index k = 0; k < 3; ++k) {
          b.lo[k] = std::min(b.lo[k], item.lo[k]);
          b.hi[k] = std::max(b.hi[k], item.hi[k]);
        }
#endif
      }
    }
  }
  double best_cost = kInf;
  std::int32_t best_imbalance = std::numeric_limits<std::int32_t>::max();
  std::int32_t best_left = 0;
  Eigen::Index best_axis = -1;
  int best_bin = -1;
  double best_scale = 0.0;
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    const auto a = static_cast<std::size_t>(axis);
    if (!usable[a]) continue;
    // The splits after the nonempty bins only: a split after an empty bin j cuts the items as
    // the split after the last nonempty bin before j does, with the same boxes (an empty bin's is
    // the identity of min / max), so the same cost and balance; of equal candidates the first in
    // bin order is kept, which is that nonempty bin's. (Small ranges leave most bins empty.)
    std::array<int, kBins> used;  // the first num_used are set
    int num_used = 0;
    for (int j = 0; j < kBins; ++j) {
      if (counts[a][static_cast<std::size_t>(j)] > 0)
        used[static_cast<std::size_t>(num_used++)] = j;
    }
    if (num_used < 2) continue;
    // Right sides (the used bins after the i-th) swept from the end, then the left sides.
    std::array<double, kBins> right_cost;  // the first num_used − 1 are set
    BinBox side{{kInf, kInf, kInf, kInf}, {-kInf, -kInf, -kInf, -kInf}};
    std::int32_t count = 0;
    for (int i = num_used - 1; i > 0; --i) {
      const auto b = static_cast<std::size_t>(used[static_cast<std::size_t>(i)]);
      count += counts[a][b];
      for (int k = 0; k < 3; ++k) {
        side.lo[k] = std::min(side.lo[k], boxes[a][b].lo[k]);
        side.hi[k] = std::max(side.hi[k], boxes[a][b].hi[k]);
      }
      right_cost[static_cast<std::size_t>(i - 1)] = area(side.lo, side.hi) * count;
    }
    side = BinBox{{kInf, kInf, kInf, kInf}, {-kInf, -kInf, -kInf, -kInf}};
    count = 0;
    for (int i = 0; i + 1 < num_used; ++i) {
      const int j = used[static_cast<std::size_t>(i)];
      const auto b = static_cast<std::size_t>(j);
      count += counts[a][b];
      for (int k = 0; k < 3; ++k) {
        side.lo[k] = std::min(side.lo[k], boxes[a][b].lo[k]);
        side.hi[k] = std::max(side.hi[k], boxes[a][b].hi[k]);
      }
      const double cost = area(side.lo, side.hi) * count + right_cost[static_cast<std::size_t>(i)];
      // Equal costs (boxes of no area: points, a flat strip): the more balanced split.
      const std::int32_t imbalance = std::abs(2 * count - (end - begin));
      if (cost < best_cost || (cost == best_cost && imbalance < best_imbalance)) {
        best_cost = cost;
        best_imbalance = imbalance;
        best_left = count;
        best_axis = axis;
        best_bin = j;
        best_scale = scale[a];
      }
    }
  }
  if (best_axis < 0) return -1;
  // Stable: the order within each side is the input's, so the tree depends only on the input.
  // The smaller side goes to spill_ (at most half the items: allocated once per build) while the
  // larger one slides together in place, then it comes back behind or before it.
  const auto goes_left = [&](const Item& item) {
    return bin_of(item, best_axis, best_scale) <= best_bin;
  };
  Item* const first = items_.data() + begin;
  Item* const last = items_.data() + end;
  Item* const spill = spill_.data();
  std::size_t spilled = 0;
  // Each side's centroid box on the way (its children's split axis and bins, which build_range
  // would otherwise find in a pass of its own): the least and greatest coordinates of the same
  // centroids, so the same values as that pass for finite centroids (a tie of −0 and +0 may keep
  // the other zero; the bins and extents computed from them are the same either way).
  constexpr double kBig = std::numeric_limits<double>::infinity();
#if defined(__SSE2__)
  struct SideBox {
    __m128d lo01 = _mm_set1_pd(kBig), lo2 = lo01;
    __m128d hi01 = _mm_set1_pd(-kBig), hi2 = hi01;
    // _mm_min_pd(c, l) is c < l ? c : l = std::min(l, c), Eigen's cwiseMin.
    void take(const Item& item) {
      const __m128d c01 = _mm_loadu_pd(item.centroid.data());
      const __m128d c2 = _mm_load_sd(item.centroid.data() + 2);
      lo01 = _mm_min_pd(c01, lo01);
      lo2 = _mm_min_sd(c2, lo2);
      hi01 = _mm_max_pd(c01, hi01);
      hi2 = _mm_max_sd(c2, hi2);
    }
    [[nodiscard]] CentroidBox box() const {
      CentroidBox b;
      _mm_storeu_pd(b.lo.data(), lo01);
      _mm_store_sd(b.lo.data() + 2, lo2);
      _mm_storeu_pd(b.hi.data(), hi01);
      _mm_store_sd(b.hi.data() + 2, hi2);
      return b;
    }
  };
#else
  struct SideBox {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kBig), hi = -lo;
    void take(const Item& item) {
      lo = lo.cwiseMin(item.centroid);
      hi = hi.cwiseMax(item.centroid);
    }
    [[nodiscard]] CentroidBox box() const { return CentroidBox{lo, hi}; }
  };
#endif
  SideBox left_box, right_box;
  if (best_left <= end - begin - best_left) {
    Item* write = last;  // the rights, from the back; never ahead of the read
    for (Item* read = last; read-- != first;) {
      if (goes_left(*read)) {
        left_box.take(*read);
        spill[spilled++] = *read;
      } else {
        right_box.take(*read);
        *--write = *read;
      }
    }
    for (std::size_t k = 0; k < spilled; ++k) first[k] = spill[spilled - 1 - k];
  } else {
    Item* write = first;  // the lefts, from the front; never ahead of the read
    for (Item* read = first; read != last; ++read) {
      if (goes_left(*read)) {
        left_box.take(*read);
        *write++ = *read;
      } else {
        right_box.take(*read);
        spill[spilled++] = *read;
      }
    }
    std::copy(spill, spill + spilled, write);
  }
  sides[0] = left_box.box();
  sides[1] = right_box.box();
  return begin + best_left;
}

template <int N>
void Bvh<N>::refit(std::span<const Volume> triangle_bounds) {
  constexpr auto kN = static_cast<std::size_t>(N);
  end_boxes_ready_ = false;  // they were of another interval
  slot_ends_ready_ = false;
  slot_whole_ = false;
  if (!node_volumes_) {
    refit_wide_only(triangle_bounds);
    return;
  }
  // Depth-first order puts every child after its parent, so one backward sweep is bottom-up. A
  // leaf also writes its triangles' float volumes by slot.
  const auto slot_floats = [&](std::size_t s, const Volume& t) {
    FloatBounds lo;
    FloatBounds hi;
    round_slot(s, t, lo, hi);
  };
  if (float_node_volumes_) {
    refit_float_nodes(triangle_bounds);
    return;
  }
  for (std::size_t n = nodes_.size(); n-- > 0;) {
    const BvhNode& node = nodes_[n];
    Volume v;
    if (node.is_leaf()) {
      const auto first = static_cast<std::size_t>(node.begin);
      v = triangle_bounds[static_cast<std::size_t>(order_[first])];
      slot_floats(first, v);
      for (auto s = first + 1; s < static_cast<std::size_t>(node.end); ++s) {
        const Volume& t = triangle_bounds[static_cast<std::size_t>(order_[s])];
        slot_floats(s, t);
        v.merge(t);
      }
    } else {
      v = node_bounds_[n + 1];
      v.merge(node_bounds_[static_cast<std::size_t>(node.right)]);
    }
    node_bounds_[n] = v;
  }
  // The wide copy: each lane's binary node volume, rounded outwards to floats.
  for (WideBvhNode<N>& w : wide_) {
    for (int i = 0; i < w.num_children; ++i) {
      std::array<float, kN> lo;
      std::array<float, kN> hi;
      round_outwards(node_bounds_[static_cast<std::size_t>(w.node[i])], lo, hi);
      for (std::size_t k = 0; k < kN; ++k) {
        w.lo[k][i] = lo[k];
        w.hi[k][i] = hi[k];
      }
    }
  }
}

template <int N>
void Bvh<N>::round_slot(std::size_t s, const Volume& t, FloatBounds& lo, FloatBounds& hi) {
  constexpr auto kAxes = static_cast<std::size_t>(kSlotAxes);
  const std::size_t stride = slot_stride();
  round_outwards(t, lo, hi);
  for (std::size_t k = 0; k < kAxes; ++k) {
    slot_bounds_[k * stride + s] = lo[k];
    slot_bounds_[(kAxes + k) * stride + s] = hi[k];
  }
}

template <int N>
void Bvh<N>::refit_float_nodes(std::span<const Volume> triangle_bounds) {
  constexpr auto kN = static_cast<std::size_t>(N);
  // As refit(), bottom-up in one backward sweep, on the rounded volumes: float_below and
  // float_above are monotone, so the union of rounded volumes is the rounded exact union, and the
  // wide copy below gets the bits refit() gives it.
  // The root's exact volume beside them (root_bounds).
  root_bounds_ = Volume::empty();
  for (std::size_t n = nodes_.size(); n-- > 0;) {
    const BvhNode& node = nodes_[n];
    FloatDop<N>& v = float_node_bounds_[n];
    if (node.is_leaf()) {
      v.lo.fill(std::numeric_limits<float>::infinity());
      v.hi.fill(-std::numeric_limits<float>::infinity());
      for (auto s = static_cast<std::size_t>(node.begin); s < static_cast<std::size_t>(node.end);
           ++s) {
        FloatBounds tl;
        FloatBounds th;
        const Volume& t = triangle_bounds[static_cast<std::size_t>(order_[s])];
        root_bounds_.merge(t);
        round_slot(s, t, tl, th);
        for (std::size_t k = 0; k < kN; ++k) {
          v.lo[k] = std::min(v.lo[k], tl[k]);
          v.hi[k] = std::max(v.hi[k], th[k]);
        }
      }
    } else {
      const FloatDop<N>& l = float_node_bounds_[n + 1];
      const FloatDop<N>& r = float_node_bounds_[static_cast<std::size_t>(node.right)];
      for (std::size_t k = 0; k < kN; ++k) {
        v.lo[k] = std::min(l.lo[k], r.lo[k]);
        v.hi[k] = std::max(l.hi[k], r.hi[k]);
      }
    }
  }
  for (WideBvhNode<N>& w : wide_) {
    for (int i = 0; i < w.num_children; ++i) {
      const FloatDop<N>& v = float_node_bounds_[static_cast<std::size_t>(w.node[i])];
      for (std::size_t k = 0; k < kN; ++k) {
        w.lo[k][i] = v.lo[k];
        w.hi[k][i] = v.hi[k];
      }
    }
  }
}

template <int N>
void Bvh<N>::refit_wide_only(std::span<const Volume> triangle_bounds) {
  // The triangles' volumes are by id, scattered over the slots.
  struct ById {
    std::span<const Volume> bounds;
    std::span<const std::int32_t> order;
    void prefetch(std::size_t s) const {
      __builtin_prefetch(&bounds[static_cast<std::size_t>(order[s])]);
    }
    [[nodiscard]] const Volume& volume(std::size_t s) const {
      return bounds[static_cast<std::size_t>(order[s])];
    }
  };
  refit_wide_from<false>(ById{triangle_bounds, order_});
}

template <int N>
template <bool kWhole, class Source>
void Bvh<N>::refit_wide_from(const Source& source) {
  constexpr auto kN = static_cast<std::size_t>(N);
  constexpr std::size_t kAhead = 16;
  [[maybe_unused]] constexpr auto kDiagonals = static_cast<std::size_t>(kSlotDiagonals);
  [[maybe_unused]] constexpr auto kFirstDiagonal = static_cast<std::size_t>(kSlotAxes);
  [[maybe_unused]] const std::size_t stride = slot_stride();
  // A wide node's inner children come after it (built depth first), so one backward sweep is
  // bottom-up. A bucket lane is its triangles' union, rounded outwards; an inner lane the union of
  // the lanes of its wide node, which partition its triangles. float_below and float_above are
  // monotone, so the min of rounded ends is the rounded min: the bits refit() gives. The root's
  // exact volume beside them (root_bounds).
  root_bounds_ = Volume::empty();
  for (std::size_t n = wide_.size(); n-- > 0;) {
    WideBvhNode<N>& w = wide_[n];
    for (int i = 0; i < w.num_children; ++i) {
      if (w.child[i] < 0) {
        // A bucket: its triangles' float volumes by slot, and their union.
        const auto begin = static_cast<std::size_t>(~w.child[i]);
        const auto end = begin + static_cast<std::size_t>(w.count[i]);
        // The sweep meets the buckets in nearly decreasing slot order: ask for the volumes (or
        // what they are computed from) kAhead slots below now.
        for (std::size_t s = begin; s < end && s >= kAhead; ++s) source.prefetch(s - kAhead);
        FloatBounds lo;
        FloatBounds hi;
        lo.fill(std::numeric_limits<float>::infinity());
        hi.fill(-std::numeric_limits<float>::infinity());
        for (std::size_t s = begin; s < end; ++s) {
          FloatBounds tl;
          FloatBounds th;
          const Volume& t = source.volume(s);
          root_bounds_.merge(t);
          round_slot(s, t, tl, th);
          if constexpr (kWhole && kDiagonals > 0) {
            for (std::size_t k = 0; k < kDiagonals; ++k) {
              slot_diagonals_[k * stride + s] = tl[kFirstDiagonal + k];
              slot_diagonals_[(kDiagonals + k) * stride + s] = th[kFirstDiagonal + k];
            }
          }
          for (std::size_t k = 0; k < kN; ++k) {
            lo[k] = std::min(lo[k], tl[k]);
            hi[k] = std::max(hi[k], th[k]);
          }
        }
        for (std::size_t k = 0; k < kN; ++k) {
          w.lo[k][i] = lo[k];
          w.hi[k][i] = hi[k];
        }
      } else {
        const WideBvhNode<N>& c = wide_[static_cast<std::size_t>(w.child[i])];
        for (std::size_t k = 0; k < kN; ++k) {
          float lo = c.lo[k][0];
          float hi = c.hi[k][0];
          for (int j = 1; j < c.num_children; ++j) {
            lo = std::min(lo, c.lo[k][j]);
            hi = std::max(hi, c.hi[k][j]);
          }
          w.lo[k][i] = lo;
          w.hi[k][i] = hi;
        }
      }
    }
  }
}

namespace {

/// a ∪= b, the end boxes of two sets (four slots at once).
inline void merge_ends(NodeEndBoxes& a, const NodeEndBoxes& b) {
#if defined(__SSE2__)
  _mm_store_ps(a.lo0, _mm_min_ps(_mm_load_ps(a.lo0), _mm_load_ps(b.lo0)));
  _mm_store_ps(a.hi0, _mm_max_ps(_mm_load_ps(a.hi0), _mm_load_ps(b.hi0)));
  _mm_store_ps(a.lo1, _mm_min_ps(_mm_load_ps(a.lo1), _mm_load_ps(b.lo1)));
  _mm_store_ps(a.hi1, _mm_max_ps(_mm_load_ps(a.hi1), _mm_load_ps(b.hi1)));
#else
  for (std::size_t k = 0; k < 4; ++k) {
    a.lo0[k] = std::min(a.lo0[k], b.lo0[k]);
    a.hi0[k] = std::max(a.hi0[k], b.hi0[k]);
    a.lo1[k] = std::min(a.lo1[k], b.lo1[k]);
    a.hi1[k] = std::max(a.hi1[k], b.hi1[k]);
  }
#endif
}

/// Slots ahead for which refit_end_boxes and refit_slot_ends ask for the corners' end boxes; and,
/// twice as far, for the triangle's row of corner ids, which that request reads: a row fetched
/// only then (the triangles by id are scattered over the slots) stalled the sweep there, on a
/// third of refit_slot_ends' cycles.
constexpr std::size_t kAheadEnds = 16;
constexpr std::size_t kAheadRows = 2 * kAheadEnds;

/// Asks for triangle f's row of corner ids.
inline void prefetch_triangle_row(const skinning::Triangles& triangles, std::int32_t f) {
  __builtin_prefetch(&triangles(static_cast<Eigen::Index>(f), 0));
}

/// Asks for the end boxes of triangle f's corners (scattered over the vertices).
inline void prefetch_corner_ends(
    const skinning::Triangles& triangles,
    std::span<const NodeEndBoxes> vertex_ends,
    std::int32_t f) {
  for (Eigen::Index j = 0; j < 3; ++j) {
    __builtin_prefetch(&vertex_ends[static_cast<std::size_t>(triangles(f, j))]);
  }
}

/// Triangle f's end boxes: the union of its corners'.
inline NodeEndBoxes triangle_ends(
    const skinning::Triangles& triangles,
    std::span<const NodeEndBoxes> vertex_ends,
    std::int32_t f) {
  const auto i = static_cast<Eigen::Index>(f);
  NodeEndBoxes box = vertex_ends[static_cast<std::size_t>(triangles(i, 0))];
  merge_ends(box, vertex_ends[static_cast<std::size_t>(triangles(i, 1))]);
  merge_ends(box, vertex_ends[static_cast<std::size_t>(triangles(i, 2))]);
  return box;
}

/// Where refit_end_boxes and refit_slot_ends read a triangle's end boxes: the corners' boxes of
/// vertex_end_boxes ...
struct CornerEndsSource {
  const skinning::Triangles& triangles;
  std::span<const NodeEndBoxes> vertex_ends;
  void prefetch_row(std::int32_t f) const { prefetch_triangle_row(triangles, f); }
  void prefetch(std::int32_t f) const { prefetch_corner_ends(triangles, vertex_ends, f); }
  [[nodiscard]] NodeEndBoxes triangle(std::int32_t f) const {
    return triangle_ends(triangles, vertex_ends, f);
  }
  /// No exact extremes: only the positions' source fills refit()'s volumes too.
  struct Exact {};
};

#if defined(__SSE2__)
/// The float box around [lo, hi] in lanes (x, y | z, 0): detail::float_below4 of the lower ends,
/// float_above of the upper ones as −float_below(−x), bit for bit the scalar float_below and
/// float_above; lane 3 zero.
inline void store_outward(
    __m128d lo_xy, __m128d lo_z, __m128d hi_xy, __m128d hi_z, float* lo, float* hi) {
  const __m128d sign = _mm_set1_pd(-0.0);
  // Lane 3 zeroed in the register, not by a store of its own after the vector's: a 16-byte read
  // of the box that follows two stores cannot be forwarded from them and waits until both have
  // left the store buffer (a refit reads each box back at once).
  const __m128 xyz = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
  _mm_store_ps(lo, _mm_and_ps(detail::float_below4(lo_xy, lo_z), xyz));
  _mm_store_ps(
      hi,
      _mm_and_ps(
          _mm_xor_ps(
              detail::float_below4(_mm_xor_pd(hi_xy, sign), _mm_xor_pd(hi_z, sign)),
              _mm_set1_ps(-0.0f)),
          xyz));
}
#endif

/// ... or the corners' positions, bounded per triangle first and rounded once: bit for bit the
/// same boxes (a coordinate's lower end float_below(next_down(x − w)) is monotone in x, so the
/// rounding of the least corner is the least of the corners' roundings), and no #W boxes held.
struct PositionEndsSource {
  const skinning::Triangles& triangles;
  const skinning::Positions& x_t0;
  const skinning::Positions& x_t1;
  double half_width;
  void prefetch_row(std::int32_t f) const { prefetch_triangle_row(triangles, f); }
  /// Where triangle f's corners start in the row-major positions.
  [[nodiscard]] std::array<std::size_t, 3> corner_offsets(std::int32_t f) const {
    const auto i = static_cast<Eigen::Index>(f);
    return {
        3 * static_cast<std::size_t>(triangles(i, 0)),
        3 * static_cast<std::size_t>(triangles(i, 1)),
        3 * static_cast<std::size_t>(triangles(i, 2))};
  }
  void prefetch(std::int32_t f) const {
    for (Eigen::Index j = 0; j < 3; ++j) {
      const auto v = static_cast<std::size_t>(triangles(f, j));
      __builtin_prefetch(x_t0.data() + 3 * v);
      __builtin_prefetch(x_t1.data() + 3 * v);
    }
  }
#if defined(__SSE2__)
  /// The corners' exact extremes so far, in (x, y) and (z) lanes (refit_swept_and_ends' root).
  struct Exact {
    __m128d lo_xy = _mm_set1_pd(std::numeric_limits<double>::infinity());
    __m128d lo_z = lo_xy;
    __m128d hi_xy = _mm_set1_pd(-std::numeric_limits<double>::infinity());
    __m128d hi_z = hi_xy;
  };
  /// Triangle f's end boxes without a width: as vertex_end_boxes, on the corners' least and
  /// greatest coordinates; those extremes also merged into `exact` when it is not null.
  [[nodiscard]] NodeEndBoxes without_width(std::int32_t f, Exact* exact) const {
    const std::array<std::size_t, 3> c = corner_offsets(f);
    NodeEndBoxes box;
    const auto end = [&](const double* p, float* lo, float* hi) {
      __m128d lo_xy = _mm_loadu_pd(p + c[0]);
      __m128d lo_z = _mm_set_sd(p[c[0] + 2]);
      __m128d hi_xy = lo_xy;
      __m128d hi_z = lo_z;
      for (std::size_t j = 1; j < 3; ++j) {
        const __m128d xy = _mm_loadu_pd(p + c[j]);
        const __m128d z = _mm_set_sd(p[c[j] + 2]);
        lo_xy = _mm_min_pd(lo_xy, xy);
        hi_xy = _mm_max_pd(hi_xy, xy);
        lo_z = _mm_min_sd(lo_z, z);
        hi_z = _mm_max_sd(hi_z, z);
      }
      store_outward(lo_xy, lo_z, hi_xy, hi_z, lo, hi);
      if (exact != nullptr) {
        exact->lo_xy = _mm_min_pd(exact->lo_xy, lo_xy);
        exact->hi_xy = _mm_max_pd(exact->hi_xy, hi_xy);
        exact->lo_z = _mm_min_sd(exact->lo_z, lo_z);
        exact->hi_z = _mm_max_sd(exact->hi_z, hi_z);
      }
    };
    end(x_t0.data(), box.lo0, box.hi0);
    end(x_t1.data(), box.lo1, box.hi1);
    return box;
  }
#else
  struct Exact {
    Dop<3> box = Dop<3>::empty();
  };
#endif
  /// Triangle f's end boxes, grown by half_width; without a width and with `exact` not null, the
  /// corners' extremes also merged into `exact` on the way (refit_swept_and_ends' root).
  [[nodiscard]] NodeEndBoxes triangle(std::int32_t f, Exact* exact = nullptr) const {
    assert(exact == nullptr || half_width == 0.0);
#if defined(__SSE2__)
    if (half_width == 0.0) return without_width(f, exact);
#endif
    const std::array<std::size_t, 3> c = corner_offsets(f);
    NodeEndBoxes box;
    const auto end = [&](const double* p, float* lo, float* hi) {
      for (std::size_t k = 0; k < 3; ++k) {
        const double a = p[c[0] + k];
        const double b = p[c[1] + k];
        const double d = p[c[2] + k];
        const double l = std::min(std::min(a, b), d);
        const double h = std::max(std::max(a, b), d);
#if !defined(__SSE2__)
        if (exact != nullptr) {
          exact->box.lo[k] = std::min(exact->box.lo[k], l);
          exact->box.hi[k] = std::max(exact->box.hi[k], h);
        }
#endif
        lo[k] = float_below(half_width > 0.0 ? next_down(l - half_width) : l);
        hi[k] = float_above(half_width > 0.0 ? next_up(h + half_width) : h);
      }
      lo[3] = hi[3] = 0.0f;
    };
    end(x_t0.data(), box.lo0, box.hi0);
    end(x_t1.data(), box.lo1, box.hi1);
    return box;
  }
};

/// Slot s of the 12 rows of slot end boxes (Bvh::refit_slot_ends), `stride` floats a row.
inline void write_slot_ends(
    float* rows, std::size_t stride, std::size_t s, const NodeEndBoxes& box) {
  for (std::size_t k = 0; k < 3; ++k) {
    rows[k * stride + s] = box.lo0[k];
    rows[(3 + k) * stride + s] = box.hi0[k];
    rows[(6 + k) * stride + s] = box.lo1[k];
    rows[(9 + k) * stride + s] = box.hi1[k];
  }
}

}  // namespace

void vertex_end_boxes(
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<NodeEndBoxes>& out) {
  // Lower and upper ends of a coordinate grown by half_width, rounded outwards.
  const auto below = [half_width](double x) {
    return float_below(half_width > 0.0 ? next_down(x - half_width) : x);
  };
  const auto above = [half_width](double x) {
    return float_above(half_width > 0.0 ? next_up(x + half_width) : x);
  };
  const auto rows = static_cast<std::size_t>(std::min(x_t0.rows(), x_t1.rows()));
  out.resize(rows);
#if defined(__SSE2__)
  if (half_width == 0.0) {
    // Without a width, float_below and float_above of the coordinates themselves (one
    // store_outward per end).
    const auto ends = [&](const double* p, float* lo, float* hi) {
      const __m128d xy = _mm_loadu_pd(p);
      const __m128d z0 = _mm_set_sd(p[2]);
      store_outward(xy, z0, xy, z0, lo, hi);
    };
    for (std::size_t v = 0; v < rows; ++v) {
      NodeEndBoxes& e = out[v];
      ends(x_t0.data() + 3 * v, e.lo0, e.hi0);
      ends(x_t1.data() + 3 * v, e.lo1, e.hi1);
    }
    return;
  }
#endif
  for (std::size_t v = 0; v < rows; ++v) {
    const double* p0 = x_t0.data() + 3 * v;  // row-major #W × 3
    const double* p1 = x_t1.data() + 3 * v;
    NodeEndBoxes& e = out[v];
    for (std::size_t k = 0; k < 3; ++k) {
      e.lo0[k] = below(p0[k]);
      e.hi0[k] = above(p0[k]);
      e.lo1[k] = below(p1[k]);
      e.hi1[k] = above(p1[k]);
    }
    e.lo0[3] = e.hi0[3] = e.lo1[3] = e.hi1[3] = 0.0f;
  }
}

template <int N>
void Bvh<N>::refit_end_boxes(
    const skinning::Triangles& triangles,
    std::span<const NodeEndBoxes> vertex_ends,
    bool with_slot_ends) {
  fill_end_boxes(CornerEndsSource{triangles, vertex_ends}, with_slot_ends);
}

template <int N>
void Bvh<N>::refit_end_boxes(
    const skinning::Triangles& triangles,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    bool with_slot_ends) {
  fill_end_boxes(PositionEndsSource{triangles, x_t0, x_t1, half_width}, with_slot_ends);
}

template <int N>
void Bvh<N>::refit_swept_and_ends(
    const skinning::Triangles& triangles,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    bool with_slot_ends) requires(N == 3) {
  if (node_volumes_) {
    // refit() would also have to fill the binary nodes' volumes, which this pass never reads.
    throw std::logic_error("Bvh::refit_swept_and_ends: the tree was built with node volumes");
  }
  end_boxes_ready_ = false;
  slot_ends_ready_ = false;
  slot_whole_ = false;
  root_bounds_ = Volume::empty();
  fill_end_boxes<true>(PositionEndsSource{triangles, x_t0, x_t1, 0.0}, with_slot_ends);
}

template <int N>
void Bvh<N>::refit_swept(
    const skinning::Triangles& triangles,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  if (node_volumes_) {
    // refit() would also have to fill the binary nodes' volumes, which this pass never reads.
    throw std::logic_error("Bvh::refit_swept: the tree was built with node volumes");
  }
  end_boxes_ready_ = false;
  slot_ends_ready_ = false;
  constexpr auto kDiagonals = static_cast<std::size_t>(kSlotDiagonals);
  if constexpr (kDiagonals > 0) {
    const std::size_t stride = slot_stride();
    if (slot_diagonals_.size() != 2 * kDiagonals * stride) {
      // Allocated at the first call; the padding slots stay empty, as slot_bounds_'.
      slot_diagonals_.assign(2 * kDiagonals * stride, std::numeric_limits<float>::infinity());
      std::fill(
          slot_diagonals_.begin() + static_cast<std::ptrdiff_t>(kDiagonals * stride),
          slot_diagonals_.end(),
          -std::numeric_limits<float>::infinity());
    }
  }
  // Each slot's volume from its triangle's corners, computed where it is rounded: the corners'
  // rows are scattered over the slots as the volumes by id were, and asked for as fill_end_boxes
  // asks for them (the triangle's row twice as far ahead as its corners).
  struct FromCorners {
    const skinning::Triangles& triangles;
    const double* p0;
    const double* p1;
    std::span<const std::int32_t> order;
    mutable Volume scratch;
    void prefetch(std::size_t s) const {
      if (s >= kAheadEnds) prefetch_triangle_row(triangles, order[s - kAheadEnds]);
      const auto f = static_cast<Eigen::Index>(order[s]);
      for (Eigen::Index j = 0; j < 3; ++j) {
        const auto v = static_cast<std::size_t>(triangles(f, j));
        __builtin_prefetch(p0 + 3 * v);
        __builtin_prefetch(p1 + 3 * v);
      }
    }
    [[nodiscard]] const Volume& volume(std::size_t s) const {
      const auto f = static_cast<Eigen::Index>(order[s]);
      std::array<const double*, 6> c{};
      for (Eigen::Index j = 0; j < 3; ++j) {
        const auto v = static_cast<std::size_t>(triangles(f, j));
        c[static_cast<std::size_t>(2 * j)] = p0 + 3 * v;
        c[static_cast<std::size_t>(2 * j + 1)] = p1 + 3 * v;
      }
      detail::swept_corners(c, scratch);
      return scratch;
    }
  };
  refit_wide_from<true>(FromCorners{triangles, x_t0.data(), x_t1.data(), order_, {}});
  slot_whole_ = true;
}

template <int N>
template <bool kSwept, class Source>
void Bvh<N>::fill_end_boxes(const Source& source, bool with_slot_ends) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const std::size_t stride = slot_stride();
  if (with_slot_ends && slot_ends_.size() != 12 * stride) slot_ends_.assign(12 * stride, 0.0f);
  float* const rows = slot_ends_.data();
  // The union of the triangles' corners' end boxes in slots [begin, end): float_below and
  // float_above are monotone, so it is the rounding of the exact union. With the slots' end
  // boxes, each triangle's box is written to its slot (refit_slot_ends' rows) on the way: the
  // corners are gathered once for both.
  const auto slot_boxes = [&](std::size_t begin, std::size_t end, NodeEndBoxes& out) {
    // The sweep meets the buckets in nearly decreasing slot order, the corners are scattered:
    // ask for the corners' boxes kAheadEnds slots below now (as refit_wide_only).
    for (std::size_t s = begin; s < end && s >= kAheadEnds; ++s) {
      if (s >= kAheadRows) source.prefetch_row(order_[s - kAheadRows]);
      source.prefetch(order_[s - kAheadEnds]);
    }
    [[maybe_unused]] typename Source::Exact exact;
    for (std::size_t s = begin; s < end; ++s) {
      NodeEndBoxes box;
      if constexpr (kSwept) {
        box = source.triangle(order_[s], &exact);
        // refit()'s slot volume: the union of the two ends' rounded boxes (refit_swept_and_ends).
        for (std::size_t k = 0; k < 3; ++k) {
          slot_bounds_[k * stride + s] = std::min(box.lo0[k], box.lo1[k]);
          slot_bounds_[(3 + k) * stride + s] = std::max(box.hi0[k], box.hi1[k]);
        }
      } else {
        box = source.triangle(order_[s]);
      }
      if (with_slot_ends) write_slot_ends(rows, stride, s, box);
      if (s == begin) {
        out = box;
      } else {
        merge_ends(out, box);
      }
    }
    if constexpr (kSwept) {
      // The root's exact volume: the bucket's corners' extremes (in registers until here).
#if defined(__SSE2__)
      alignas(16) std::array<double, 2> lo_xy;
      alignas(16) std::array<double, 2> hi_xy;
      _mm_store_pd(lo_xy.data(), exact.lo_xy);
      _mm_store_pd(hi_xy.data(), exact.hi_xy);
      const std::array<double, 3> lo{lo_xy[0], lo_xy[1], _mm_cvtsd_f64(exact.lo_z)};
      const std::array<double, 3> hi{hi_xy[0], hi_xy[1], _mm_cvtsd_f64(exact.hi_z)};
#else
      const auto& lo = exact.box.lo;
      const auto& hi = exact.box.hi;
#endif
      for (std::size_t k = 0; k < 3; ++k) {
        root_bounds_.lo[k] = std::min(root_bounds_.lo[k], lo[k]);
        root_bounds_.hi[k] = std::max(root_bounds_.hi[k], hi[k]);
      }
    }
  };
  end_boxes_.resize(wide_.size());
  // As refit_wide_only: children after their parent, so one backward sweep is bottom-up; a
  // bucket's lane from its triangles' corners, an inner lane the union of its wide node's lanes.
  for (std::size_t n = wide_.size(); n-- > 0;) {
    WideBvhNode<N>& w = wide_[n];
    WideEndBoxes& e = end_boxes_[n];
    for (std::size_t k = 0; k < 3; ++k) {
      for (std::size_t i = 0; i < 4; ++i) {
        e.lo0[k][i] = e.lo1[k][i] = kInf;
        e.hi0[k][i] = e.hi1[k][i] = -kInf;
      }
    }
    for (int lane = 0; lane < w.num_children; ++lane) {
      const auto i = static_cast<std::size_t>(lane);
      NodeEndBoxes lane_boxes;
      if (w.child[i] < 0) {
        const auto begin = static_cast<std::size_t>(~w.child[i]);
        slot_boxes(begin, begin + static_cast<std::size_t>(w.count[i]), lane_boxes);
      } else {
        const WideBvhNode<N>& cw = wide_[static_cast<std::size_t>(w.child[i])];
        const WideEndBoxes& ce = end_boxes_[static_cast<std::size_t>(w.child[i])];
        for (std::size_t k = 0; k < 3; ++k) {
          lane_boxes.lo0[k] = lane_boxes.lo1[k] = kInf;
          lane_boxes.hi0[k] = lane_boxes.hi1[k] = -kInf;
          for (int j = 0; j < cw.num_children; ++j) {
            const auto l = static_cast<std::size_t>(j);
            lane_boxes.lo0[k] = std::min(lane_boxes.lo0[k], ce.lo0[k][l]);
            lane_boxes.hi0[k] = std::max(lane_boxes.hi0[k], ce.hi0[k][l]);
            lane_boxes.lo1[k] = std::min(lane_boxes.lo1[k], ce.lo1[k][l]);
            lane_boxes.hi1[k] = std::max(lane_boxes.hi1[k], ce.hi1[k][l]);
          }
        }
      }
      for (std::size_t k = 0; k < 3; ++k) {
        e.lo0[k][i] = lane_boxes.lo0[k];
        e.hi0[k][i] = lane_boxes.hi0[k];
        e.lo1[k][i] = lane_boxes.lo1[k];
        e.hi1[k][i] = lane_boxes.hi1[k];
      }
      if constexpr (kSwept) {
        // refit()'s lane volume, the union of the lane's slots' (or its wide node's lanes').
        for (std::size_t k = 0; k < 3; ++k) {
          w.lo[k][i] = std::min(lane_boxes.lo0[k], lane_boxes.lo1[k]);
          w.hi[k][i] = std::max(lane_boxes.hi0[k], lane_boxes.hi1[k]);
        }
      }
    }
  }
  end_boxes_ready_ = true;
  if (with_slot_ends) slot_ends_ready_ = true;
}

template <int N>
void Bvh<N>::refit_slot_ends(
    const skinning::Triangles& triangles, std::span<const NodeEndBoxes> vertex_ends) {
  fill_slot_ends(CornerEndsSource{triangles, vertex_ends});
}

template <int N>
void Bvh<N>::refit_slot_ends(
    const skinning::Triangles& triangles,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  fill_slot_ends(PositionEndsSource{triangles, x_t0, x_t1, 0.0});
}

template <int N>
template <class Source>
void Bvh<N>::fill_slot_ends(const Source& source) {
  const std::size_t stride = slot_stride();
  // The padding slots are never read for a pair (their lanes are masked off): zeros.
  if (slot_ends_.size() != 12 * stride) slot_ends_.assign(12 * stride, 0.0f);
  float* const rows = slot_ends_.data();
  for (std::size_t s = 0; s < order_.size(); ++s) {
    if (s + kAheadRows < order_.size()) source.prefetch_row(order_[s + kAheadRows]);
    if (s + kAheadEnds < order_.size()) {
      source.prefetch(order_[s + kAheadEnds]);
    }
    write_slot_ends(rows, stride, s, source.triangle(order_[s]));
  }
  slot_ends_ready_ = true;
}

template class Bvh<3>;
template class Bvh<8>;

namespace detail {

void force_bvh_baseline_binning(bool baseline) {
  baseline_binning.store(baseline, std::memory_order_relaxed);
}

}  // namespace detail

}  // namespace skelcd::culling
