#pragma once
// A bounding volume hierarchy over triangles, built once top-down and refit bottom-up every
// interval. Flat layout: nodes in depth-first order, a node's left child right after it, its
// triangles one contiguous range of triangle_order().

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "culling/dop.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// How Bvh splits a range of triangles in two (at the build positions).
enum class BvhSplit {
  /// The surface-area heuristic, binned (docs/culling.md "The hierarchy"): the split that
  /// minimises area(left) · #left + area(right) · #right over 16 slabs per axis. The median split
  /// below is taken instead where the centroids fall into one slab on every axis, below depth 48
  /// (which bounds the depth on any input) and inside a bucket. Fewer overlapping siblings on real
  /// meshes, at a few times the median build's cost, paid once per hierarchy.
  surface_area,
  /// At the median by count along the longest axis of the centroids: balanced, depth
  /// ⌈log₂(#F / leaf_size)⌉. The cone methods' hierarchy (paper 000's figures were taken on it).
  median,
};

struct BvhOptions {
  /// Most triangles in a leaf (>= 1). Larger leaves: fewer nodes to refit and visit, more
  /// triangle-box tests inside leaf pairs (bench/culling measures the trade).
  int leaf_size = 1;
  /// Keep the binary nodes' double volumes (Bvh::node_bounds), which the cone methods, the masked
  /// traversals and radial view read. Without them (the `bvh`, `kdop` and `auto` traversals read
  /// only the wide copy and the triangles' volumes) refit fills the wide nodes straight from the
  /// triangles' volumes, with the same bits, and the tree holds 2·#F·sizeof(Dop<N>) bytes less.
  bool node_volumes = true;
  /// With node_volumes: keep them as floats rounded outwards (Bvh::float_node_bounds, half the
  /// bytes) instead of doubles. A traversal on them is conservative (volumes that overlap in
  /// double overlap in float) and tests its triangle pairs with the triangles' exact volumes: the
  /// cone methods, whose binary tree is their traversal's.
  bool float_node_volumes = false;
  BvhSplit split = BvhSplit::surface_area;

  /// Every member equal: the same tree from the same triangles and positions (HierarchyCache).
  friend bool operator==(const BvhOptions&, const BvhOptions&) = default;
};

/// A node volume as floats rounded outwards (BvhOptions::float_node_volumes).
template <int N>
struct FloatDop {
  std::array<float, static_cast<std::size_t>(N)> lo;
  std::array<float, static_cast<std::size_t>(N)> hi;
  /// True when the closed volumes share a point on every axis (touching counts).
  [[nodiscard]] bool overlaps(const FloatDop& other) const {
    bool ok = true;
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      ok = ok & (lo[k] <= other.hi[k]) & (other.lo[k] <= hi[k]);
    }
    return ok;
  }
};

struct BvhNode {
  std::int32_t begin = 0;  ///< first slot of the node's triangles in Bvh::triangle_order()
  std::int32_t end = 0;    ///< one past the last slot
  std::int32_t right = 0;  ///< index of the right child; 0 for a leaf (the left child is index + 1)
  [[nodiscard]] bool is_leaf() const { return right == 0; }
  [[nodiscard]] std::int32_t size() const { return end - begin; }
};

/// Most triangles in a bucket of the traversals' wide tree (Bvh::wide_nodes) with leaves of
/// `leaf_size`: a subtree of at most this many triangles is one bucket, whose triangles are tested
/// against another bucket's all at once; so a traversal step may emit up to its square in pairs.
[[nodiscard]] constexpr int bucket_size(int leaf_size) { return leaf_size > 4 ? leaf_size : 4; }

/// A node of the traversals' copy of the hierarchy (Bvh::wide_nodes): up to four children, each a
/// binary node of the tree, with their volumes as floats rounded outwards (float_below /
/// float_above), axis by axis four children side by side (SoA), so that one volume is tested
/// against all four children at once. Half the bytes of double volumes; the float test is
/// conservative (two volumes that overlap in double overlap in float), and the traversals test
/// triangle pairs again with the exact double volumes.
template <int N>
struct alignas(16) WideBvhNode {
  static constexpr int kWidth = 4;
  /// lo[k][i], hi[k][i]: child i's interval on axis k; unused lanes are empty (+inf, −inf).
  static constexpr auto kAxes = static_cast<std::size_t>(N);
  static constexpr auto kLanes = static_cast<std::size_t>(kWidth);
  float lo[kAxes][kLanes];
  float hi[kAxes][kLanes];
  /// child[i] >= 0: the wide node holding child i's children; child[i] < 0: child i is a bucket
  /// (a subtree of at most bucket_size(leaf_size) triangles) holding the triangles
  /// triangle_order()[~child[i] .. ~child[i] + count[i]).
  std::int32_t child[kLanes];
  std::int32_t count[kLanes];  ///< triangles under child i (0 for an unused lane)
  std::int32_t node[kLanes];   ///< child i's index in nodes() (refit reads its volume)
  std::int32_t num_children;   ///< lanes in use, 1..4 (lanes 0 .. num_children − 1)
};

/// The lanes of one wide node as boxes at the two ends of an interval (Bvh::refit_end_boxes): the
/// box of the lane's triangles' corners at t = 0 (lo0, hi0) and at t = 1 (lo1, hi1), grown by a
/// half width, as floats rounded outwards, axis by axis four lanes side by side like
/// WideBvhNode's (unused lanes empty). A traversal tests whether two lanes' boxes lie apart on an
/// axis at both ends (end_boxes_meet, culling/traversal.hpp; docs/culling.md "Relative boxes at
/// the nodes").
struct alignas(16) WideEndBoxes {
  float lo0[3][4];
  float hi0[3][4];
  float lo1[3][4];
  float hi1[3][4];
};

/// One vertex's (or a set of them: a lane's, while Bvh::refit_end_boxes gathers it) boxes at the
/// two ends of an interval, as floats rounded outwards: lo0[k], hi0[k] at t = 0 and lo1[k], hi1[k]
/// at t = 1 on axis k < 3; the fourth slot of each is 0.
struct alignas(16) NodeEndBoxes {
  float lo0[4];
  float hi0[4];
  float lo1[4];
  float hi1[4];
};

/// Every vertex's end boxes over x_t0 → x_t1 (#W × 3 each): its position at t = 0 and at t = 1
/// grown by half_width, rounded outwards to floats, into `out` (resized to #W), for
/// Bvh::refit_end_boxes. Computed once per interval for all the trees over one mesh.
void vertex_end_boxes(
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<NodeEndBoxes>& out);

/// Hierarchy of Dop<N> volumes (Dop<3>: AABB, Dop<8>: 16-DOP) over a set of triangles.
template <int N>
class Bvh {
 public:
  using Volume = Dop<N>;

  Bvh() = default;

  /// Builds over every triangle: each range split in two (BvhOptions::split), recursively, until
  /// it holds at most leaf_size triangles.
  /// @param triangles #F × 3 vertex ids into positions.
  /// @param positions #W × 3 positions the split is computed from (rest pose, usually).
  /// @throws InvalidInput when leaf_size < 1 or a vertex id is out of range (naming the triangle).
  Bvh(const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const BvhOptions& options = {});

  /// Builds over the triangles listed in `subset` (ids into `triangles`; a cluster, a part).
  /// @throws InvalidInput as above, or for a subset id out of range.
  Bvh(const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      std::span<const std::int32_t> subset,
      const BvhOptions& options = {});

  /// Bottom-up refit: a leaf's volume is the union of its triangles' volumes, a parent's the
  /// union of its children's. Unions are exact (min/max), so every node contains its triangles'
  /// volumes exactly as given; the wide nodes' float volumes contain them too (rounded
  /// outwards). Allocation-free. Without node volumes (BvhOptions::node_volumes) only the wide
  /// nodes are filled: a bucket's lanes from its triangles, an inner lane as the union of its wide
  /// node's lanes — float_below / float_above are monotone, so that is the rounding of the exact
  /// union, bit for bit.
  /// @param triangle_bounds indexed by triangle id (#F of the `triangles` built from).
  void refit(std::span<const Volume> triangle_bounds);
  /// refit() of the wide nodes and the slot volumes only — the bits refit() gives them — for a
  /// caller that reads nothing else until the next refit(): the binary node volumes, when kept,
  /// stay those of the last refit() (`auto`'s DCD on a cone group's tree, which traverses the wide
  /// copy). Allocation-free.
  void refit_wide(std::span<const Volume> triangle_bounds) {
    end_boxes_ready_ = false;
    slot_ends_ready_ = false;
    slot_whole_ = false;
    refit_wide_only(triangle_bounds);
  }

  [[nodiscard]] std::span<const BvhNode> nodes() const { return nodes_; }
  /// The binary nodes' volumes; empty when built without them (BvhOptions::node_volumes) or
  /// with float ones (BvhOptions::float_node_volumes).
  [[nodiscard]] std::span<const Volume> node_bounds() const { return node_bounds_; }
  /// The binary nodes' volumes as floats rounded outwards, each containing its node's exact
  /// volume; empty unless built with BvhOptions::float_node_volumes.
  [[nodiscard]] std::span<const FloatDop<N>> float_node_bounds() const {
    return float_node_bounds_;
  }
  /// The root's exact volume: the union of the triangles' volumes of the last refit() (empty for
  /// an empty tree). refit_wide() leaves it as it was on a tree with double node volumes.
  [[nodiscard]] const Volume& root_bounds() const {
    return float_node_volumes_ || node_bounds_.empty() ? root_bounds_ : node_bounds_[0];
  }
  /// Triangle ids in leaf order; node n holds triangle_order()[n.begin .. n.end).
  [[nodiscard]] std::span<const std::int32_t> triangle_order() const { return order_; }
  [[nodiscard]] bool empty() const { return nodes_.empty(); }
  /// Longest root-to-leaf path in edges (0 for a single leaf).
  [[nodiscard]] int depth() const { return depth_; }
  [[nodiscard]] int leaf_size() const { return leaf_size_; }

  /// The same tree collapsed into nodes of up to four children for the traversals
  /// (culling/traversal.hpp): wide_nodes()[0] is a virtual root whose one child is nodes()[0];
  /// every other wide node is an inner node of the binary tree with more than
  /// bucket_size(leaf_size()) triangles and holds the up to four descendants found by replacing,
  /// while fewer than four, the child with the most triangles among those with more than
  /// bucket_size by its two children. Children of at most bucket_size triangles are buckets.
  /// Empty when the tree is.
  [[nodiscard]] std::span<const WideBvhNode<N>> wide_nodes() const { return wide_; }
  /// Axes of the triangles' float volumes by slot: the three coordinate axes (all of an AABB's;
  /// the first three of a 16-DOP's — a test on fewer axes only prunes less, and 24 bytes a
  /// triangle instead of 64 keep `kdop` within its memory budget).
  static constexpr int kSlotAxes = N < 3 ? N : 3;
  /// The triangles' own volumes on the first kSlotAxes axes, as floats rounded outwards (as the
  /// wide nodes'), by slot of triangle_order(), axis by axis: slot_lo(k)[s], slot_hi(k)[s] for
  /// k < kSlotAxes and s in [0, #triangles + 3), the last three slots empty (+inf, −inf) so that
  /// any four consecutive slots of the tree can be read at once. The traversals test a triangle
  /// against four of a bucket with them (a float test that only prunes). Refit writes them.
  /// Slots of one axis of slot_lo / slot_hi: #triangles + 3. Per-slot arrays of the traversals'
  /// callers (ClassMasks::slots) are as long, for the same four-at-a-time reads.
  [[nodiscard]] std::size_t slot_stride() const { return order_.size() + kSlotPadding; }
  [[nodiscard]] const float* slot_lo(int k) const {
    return slot_bounds_.data() + static_cast<std::size_t>(k) * slot_stride();
  }
  [[nodiscard]] const float* slot_hi(int k) const {
    return slot_bounds_.data() + static_cast<std::size_t>(kSlotAxes + k) * slot_stride();
  }
  /// Fills end_boxes() for an interval from its vertices' end boxes (vertex_end_boxes, indexed by
  /// the vertex ids of `triangles`, the triangles the tree was built from). Valid until the next
  /// refit() (which drops them), so that a traversal never reads boxes of another interval.
  /// Allocates once (#wide nodes × 192 bytes). Every traversal walks the wide nodes (the masked
  /// ones too), so the binary nodes get none. With `with_slot_ends`, also what refit_slot_ends
  /// fills, bit for bit, from one gather of each triangle's corners for both.
  void refit_end_boxes(
      const skinning::Triangles& triangles,
      std::span<const NodeEndBoxes> vertex_ends,
      bool with_slot_ends = false);
  /// The same boxes, bit for bit, from the corners' positions at the two ends grown by
  /// half_width (what vertex_end_boxes reads), bounded per triangle before the rounding: for one
  /// tree over a mesh, without #W vertex boxes held (64 bytes a vertex; bounded memory).
  void refit_end_boxes(
      const skinning::Triangles& triangles,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      double half_width,
      bool with_slot_ends);
  /// refit() over the interval's swept AABBs and refit_end_boxes() on the positions without a
  /// width (with the slots' rows when `with_slot_ends`), in one pass over the corners, for a tree
  /// without binary node volumes (BvhOptions::node_volumes false; `dynamic`'s local trees with
  /// node end boxes). A swept AABB from the corners is the union of its two end boxes, and the
  /// rounding outwards is monotone, so the slots' and the wide nodes' float volumes are each the
  /// union of the two rounded end boxes, bit for bit what refit() gives them from
  /// FeatureBounds::swept_triangles' volumes; the root's double volume is the corners' extremes,
  /// the same values (a zero's sign aside, which no comparison sees). The triangles' volumes are
  /// not read: refit()'s scattered reads of them by triangle id and their rounding are saved.
  /// @throws std::logic_error when the tree was built with node_volumes true (left unchanged).
  void refit_swept_and_ends(
      const skinning::Triangles& triangles,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      bool with_slot_ends) requires(N == 3);
  /// refit() over the interval's swept volumes, each computed from its triangle's corners at the
  /// two ends (bit for bit FeatureBounds::swept_triangles' volume) and rounded into its slot
  /// without being stored, for a tree without binary node volumes: the slots' and the wide nodes'
  /// float volumes and root_bounds() are refit()'s over those volumes, bit for bit. The slots'
  /// volumes are then whole (slot_volumes_whole): on every axis, the diagonal ones in
  /// slot_diagonal_lo / slot_diagonal_hi, so that a traversal tests a triangle pair on the floats
  /// alone (rounded outwards: they only prune less than the exact volumes, within a float's step)
  /// and reads no volume by triangle id (docs/culling.md, "Whole slot volumes"). 128 bytes a
  /// triangle of double volumes are not held; 8 · (N − 3) bytes a slot of diagonals are, from the
  /// first call on. Valid until the next refit() or refit_wide().
  /// @throws std::logic_error when the tree was built with node_volumes true (left unchanged).
  void refit_swept(
      const skinning::Triangles& triangles,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1);
  /// Whether the slots' float volumes hold the triangles' whole volumes (every axis) of the last
  /// refit: true after refit_swept, false after refit() and refit_wide().
  [[nodiscard]] bool slot_volumes_whole() const { return slot_whole_; }
  /// Axes of a slot volume past the first kSlotAxes: N − kSlotAxes (none for an AABB).
  static constexpr int kSlotDiagonals = N - kSlotAxes;
  /// The slots' float volumes on axis kSlotAxes + k, k < kSlotDiagonals, by slot as slot_lo /
  /// slot_hi (the padding slots empty); null unless slot_volumes_whole().
  [[nodiscard]] const float* slot_diagonal_lo(int k) const {
    return slot_whole_ && kSlotDiagonals > 0
               ? slot_diagonals_.data() + static_cast<std::size_t>(k) * slot_stride()
               : nullptr;
  }
  [[nodiscard]] const float* slot_diagonal_hi(int k) const {
    return slot_whole_ && kSlotDiagonals > 0
               ? slot_diagonals_.data() +
                     static_cast<std::size_t>(kSlotDiagonals + k) * slot_stride()
               : nullptr;
  }
  /// The triangles' own end boxes by slot, from their corners' (vertex_end_boxes): 12 rows of
  /// slot_stride() floats — lo at t = 0 on x, y, z, then hi at t = 0, lo at t = 1, hi at t = 1 —
  /// so that the traversals drop a triangle pair whose boxes lie apart on an axis at both ends
  /// before it is emitted, four slots at a time (docs/culling.md, "Apart at both ends in the
  /// leaves"). Valid until the next refit(), as end_boxes(). Allocates once (#triangles × 48
  /// bytes).
  void refit_slot_ends(
      const skinning::Triangles& triangles, std::span<const NodeEndBoxes> vertex_ends);
  /// The same rows, bit for bit, from the corners' positions (no width), as refit_end_boxes'
  /// overload on positions.
  void refit_slot_ends(
      const skinning::Triangles& triangles,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1);
  /// Row r of the slot end boxes (refit_slot_ends), or null unless it ran after the last refit().
  [[nodiscard]] const float* slot_ends(int r) const {
    return slot_ends_ready_ ? slot_ends_.data() + static_cast<std::size_t>(r) * slot_stride()
                            : nullptr;
  }
  /// The wide nodes' end boxes (WideEndBoxes), by wide node; empty unless refit_end_boxes ran
  /// after the last refit().
  [[nodiscard]] std::span<const WideEndBoxes> end_boxes() const {
    return end_boxes_ready_ ? std::span<const WideEndBoxes>(end_boxes_)
                            : std::span<const WideEndBoxes>();
  }
  /// Wide nodes on the longest path from the virtual root to a leaf, the virtual root included
  /// (1 when the tree is one leaf; 0 when empty).
  [[nodiscard]] int wide_depth() const { return wide_depth_; }

 private:
  void build(const skinning::Triangles& triangles, const skinning::Positions& positions);
  /// The bounding box of a range's centroids (build_range's split axis and bins).
  struct CentroidBox {
    Eigen::Vector3d lo;
    Eigen::Vector3d hi;
  };
  /// Builds the subtree of items [begin, end); `known`, when given, is the box of their
  /// centroids (the split that made the range has it), else it is computed here.
  std::int32_t build_range(
      std::int32_t begin, std::int32_t end, int depth, const CentroidBox* known = nullptr);
  void build_wide();
  int wide_lanes(std::int32_t node, std::array<std::int32_t, WideBvhNode<N>::kWidth>& lanes) const;
  std::size_t count_wide(std::int32_t node) const;
  std::int32_t build_wide_node(std::int32_t node, int depth);
  void refit_wide_only(std::span<const Volume> triangle_bounds);
  /// refit_wide_only over a source of the slots' volumes: `source.prefetch(s)` asks for slot
  /// s's, `source.volume(s)` gives it. kWhole also writes the slots' diagonal axes.
  template <bool kWhole, class Source>
  void refit_wide_from(const Source& source);
  void refit_float_nodes(std::span<const Volume> triangle_bounds);
  /// refit_end_boxes and refit_slot_ends over a source of triangles' end boxes (bvh.cpp).
  /// With kSwept, also refit()'s slot and wide-node volumes and root_bounds() from the end boxes
  /// (refit_swept_and_ends).
  template <bool kSwept = false, class Source>
  void fill_end_boxes(const Source& source, bool with_slot_ends);
  template <class Source>
  void fill_slot_ends(const Source& source);
  using FloatBounds = std::array<float, static_cast<std::size_t>(N)>;
  /// The volume t of the triangle in slot s rounded outwards into (lo, hi), its slot volume
  /// (slot_lo / slot_hi) written.
  void round_slot(std::size_t s, const Volume& t, FloatBounds& lo, FloatBounds& hi);

  std::vector<BvhNode> nodes_;
  std::vector<Volume> node_bounds_;
  std::vector<FloatDop<N>> float_node_bounds_;
  Volume root_bounds_ = Volume::empty();  // root_bounds() without double node volumes
  std::vector<std::int32_t> order_;
  std::vector<WideBvhNode<N>> wide_;
  std::vector<WideEndBoxes> end_boxes_;
  bool end_boxes_ready_ = false;
  std::vector<float> slot_ends_;  // 12 rows of slot_stride(): refit_slot_ends
  bool slot_ends_ready_ = false;
  static constexpr std::size_t kSlotPadding = 3;
  std::vector<float> slot_bounds_;     // 2·kSlotAxes rows of slot_stride(): lo by axis, then hi
  std::vector<float> slot_diagonals_;  // 2·kSlotDiagonals rows, as slot_bounds_: refit_swept
  bool slot_whole_ = false;
  struct Item {
    Eigen::Vector3d centroid;  // three times the centroid (the split only compares them)
    Eigen::Vector3d lo;        // the triangle's box at the build positions
    Eigen::Vector3d hi;
    std::int32_t id;
  };
  /// The surface-area split of [begin, end) (docs/culling.md "The hierarchy"), or −1 when the
  /// centroids fall in one bin on every axis; partitions items_ when it finds one, and then
  /// gives each side's centroid box in `sides` (left, right), met on the way.
  std::int32_t sah_split(
      std::int32_t begin,
      std::int32_t end,
      const Eigen::Vector3d& lo,
      const Eigen::Vector3d& hi,
      std::array<CentroidBox, 2>& sides);
  std::vector<Item> items_;  // build-time only, by slot; freed after the build
  std::vector<Item> spill_;  // build-time only: the smaller side of a split while partitioning
  int depth_ = 0;
  int wide_depth_ = 0;
  int leaf_size_ = 1;
  bool node_volumes_ = true;
  bool float_node_volumes_ = false;
  BvhSplit split_ = BvhSplit::surface_area;
};

using AabbBvh = Bvh<3>;
using KdopBvh = Bvh<8>;

namespace detail {
/// For the tests: with `baseline` true the surface-area build bins its items with its SSE2 loop
/// even where the CPU has AVX (the same trees either way), until asked again.
void force_bvh_baseline_binning(bool baseline);
}  // namespace detail

}  // namespace skelcd::culling
