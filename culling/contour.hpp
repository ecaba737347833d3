#pragma once
// Contours of hierarchy nodes and the contour test of the cone culling methods (paper 000 §5.1,
// §5.2.2; Volino & Thalmann's contour test; ICCD's continuous contour test).
//
// The contour of a node is the boundary of the surface its triangles form: the mesh's own
// boundary edges inside the node and the "internal boundary" edges the hierarchy's splits create
// (an edge whose other triangle lies outside the node). It is found once, from the topology, for
// every node that has grandchildren, oriented as the node's triangles traverse it, ordered along
// its loop and cut into chains: maximal runs of consecutive edges whose triangles lie in the same
// sub-surface (grandchild, or a child that is a leaf) — the four boundary-edge subsets of §5.2.2.
//
// The contour is split into loops: at a pinch vertex (two or more fans of the node's triangles
// meeting at one vertex) each fan's incoming edge is paired with its own outgoing edge, and a loop
// that still visits a vertex twice is cut there, so every loop is a simple cycle of vertices. The
// cone tests are proven for such contours (docs/dual-cone.md, "Why the tests are sufficient"); a
// node whose triangles do not form one (non-manifold, inconsistently oriented, ...) gets a status
// saying why and is never culled.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/feature_topology.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// What the topology says about a node's contour (decided once, in preprocessing).
enum class ContourStatus : std::uint8_t {
  loops,                     ///< one or more closed loops: the contour tests apply
  not_tested,                ///< a leaf, or both children are leaves: standard tests only
  no_contour,                ///< closed surface: its normals never lie in a half-space
  degenerate_triangle,       ///< a triangle with a repeated vertex
  non_manifold,              ///< an edge with three or more triangles of the node
  inconsistent_orientation,  ///< an edge traversed twice in the same direction by the node
  unpaired_fan,              ///< a contour vertex whose triangle fans could not be paired
  too_many_loops,            ///< more loops than the nesting test examines (kMaxContourLoops)
};
inline constexpr int kNumContourStatuses = 8;
/// Most loops a node's contour may have for the nesting test (each loop's winding is evaluated
/// at one vertex of every other loop).
inline constexpr int kMaxContourLoops = 16;

[[nodiscard]] const char* to_string(ContourStatus status);

/// A directed contour edge: from → to as the node's triangle traverses it (welded ids).
struct ContourEdge {
  std::int32_t from = -1;
  std::int32_t to = -1;
  std::int8_t part = -1;  ///< which sub-surface of the node holds its triangle (0..3)
};

/// A fan of the node's triangles around a pinch vertex (a vertex where the contour passes more
/// than once): its incoming and outgoing contour edges (indices into NodeContours::edges(node)).
/// Seen along V the fan covers the wedge swept counter-clockwise from the out-edge to the in-edge.
struct ContourFan {
  std::int32_t vertex = -1;
  std::int32_t in_edge = -1;
  std::int32_t out_edge = -1;
};

/// The sub-surfaces of `node` for the enhanced dual-cone conditions: the children of each child,
/// or the child itself when it is a leaf. Returns how many (0 for a leaf, 2..4 otherwise).
int sub_surfaces(const AabbBvh& bvh, std::int32_t node, std::array<std::int32_t, 4>& out);

/// Whether NodeContours gives `node` a contour of its own (any status but not_tested): an internal
/// node with at least one internal child. Known from the hierarchy alone, before the contours.
[[nodiscard]] bool contour_tested(const AabbBvh& bvh, std::int32_t node);

/// The contours of every node of one hierarchy, built once per mesh.
class NodeContours {
 public:
  NodeContours() = default;
  /// @param bvh the hierarchy (node ids and triangle ranges are used).
  /// @param topology the welded triangles and edges the hierarchy was built over.
  NodeContours(const AabbBvh& bvh, const FeatureTopology& topology);

  [[nodiscard]] ContourStatus status(std::int32_t node) const {
    return status_[static_cast<std::size_t>(node)];
  }
  /// The contour of a `loops` node (empty otherwise), loop after loop; each loop visits every
  /// vertex once and is rotated so that it starts a chain.
  /// @param out receives the edges (cleared first; allocation-free once its capacity suffices).
  /// @note Stored as each edge's start vertex and sub-surface only (an edge ends where the next
  /// edge of its loop starts): expanded here, once per contour test (bounded memory).
  void edges(std::int32_t node, std::vector<ContourEdge>& out) const;
  /// The same, in a new vector.
  [[nodiscard]] std::vector<ContourEdge> edges(std::int32_t node) const;
  /// Offsets into edges(node) where each loop starts, followed by edges(node).size().
  [[nodiscard]] std::span<const std::int32_t> loop_starts(std::int32_t node) const;
  /// Offsets into edges(node) where each chain starts, followed by edges(node).size(). A chain
  /// is a maximal run of one loop's edges in one sub-surface; a loop lying in a single
  /// sub-surface is cut into one-edge chains (a closed chain is never monotone).
  [[nodiscard]] std::span<const std::int32_t> chain_starts(std::int32_t node) const;
  /// Per loop, a vertex on no other loop (-1 when there is none): where the other loops'
  /// winding numbers are evaluated.
  [[nodiscard]] std::span<const std::int32_t> loop_probe(std::int32_t node) const;
  /// The fans at the node's pinch vertices, grouped by vertex.
  [[nodiscard]] std::span<const ContourFan> fans(std::int32_t node) const;
  /// How many nodes have each status (indexed by ContourStatus).
  [[nodiscard]] const std::array<std::int64_t, kNumContourStatuses>& status_counts() const {
    return status_counts_;
  }
  /// Total contour edges stored (all nodes).
  [[nodiscard]] std::int64_t total_edges() const { return static_cast<std::int64_t>(from_.size()); }

 private:
  std::vector<ContourStatus> status_;
  // Compressed rows: per node its record among the `loops` nodes (-1 for any other), per record r
  // (node order) and one past the last, where its rows begin in the arrays below; loop_starts_
  // has #loops + 1 entries per record, so record r's begin at loop_begin_[r] + r. 32-bit offsets,
  // and no row for the nodes without a contour test (most of them: leaves and their parents).
  std::vector<std::int32_t> record_;
  std::vector<std::int32_t> edge_begin_;
  std::vector<std::int32_t> loop_begin_;
  std::vector<std::int32_t> chain_begin_;
  std::vector<std::int32_t> fan_begin_;
  std::vector<std::int32_t>
      from_;  // per contour edge: where it starts (it ends at the next's start)
  std::vector<std::int8_t> part_;          // per contour edge: the sub-surface holding its triangle
  std::vector<std::int32_t> loop_starts_;  // per record: #loops + 1 entries
  std::vector<std::int32_t> loop_probe_;   // per record: #loops entries
  std::vector<std::int32_t> chain_starts_;
  std::vector<ContourFan> fans_;
  std::array<std::int64_t, kNumContourStatuses> status_counts_{};
};

/// Which edge pairs the contour test examines.
enum class ContourMode : std::uint8_t {
  /// Enhanced dual-cone (§5.1 conditions 2 and 3): each chain must be strictly monotone in the
  /// projection (its binormal cone in the projection plane has half-angle < π/2), which makes it
  /// simple by itself; only edges of different chains are tested against each other.
  chains,
  /// Normal cone test (Volino–Thalmann / ICCD): every pair of edges of the loop.
  every_edge,
};

/// What the contour test did, for the stats of a method.
struct ContourTestCounters {
  std::int64_t chain_tests = 0;      ///< dual-cone (monotone chain) tests of condition 2
  std::int64_t chain_cuts = 0;       ///< chains that failed it and were cut into monotone runs
  std::int64_t projected_edges = 0;  ///< contour edges projected
  std::int64_t edge_box_tests = 0;   ///< 2D box tests of projected edge pairs
  std::int64_t edge_pair_tests = 0;  ///< exact/conservative projected segment tests
  std::int64_t pinch_tests = 0;      ///< fan pairs compared at pinch vertices
  std::int64_t nesting_tests = 0;    ///< winding numbers of a loop around another's vertex
};

/// The outcome of one contour test: which condition failed first (for the ten-result record of
/// Algorithm 3), with the sub-surfaces involved.
struct ContourVerdict {
  bool simple = false;
  /// Chains mode: bit p set when a chain of sub-surface p failed the dual-cone test (its BNC in
  /// the projection plane spans π or more) and was cut into monotone runs. Not a failure by
  /// itself: the runs are then tested against each other by condition 3.
  std::uint8_t cut_parts = 0;
  bool failed_pinch = false;    ///< fans at a pinch vertex may overlap in projection
  bool failed_nesting = false;  ///< loops may nest so that two sheets cover one point
  std::int8_t part_a = -1;      ///< sub-surface of the failing chain / first failing edge
  std::int8_t part_b = -1;      ///< sub-surface of the second failing edge (condition 3)
};

/// Evaluates the contour test of a node in the projection along a given direction V, at an
/// instant or over an interval with linear motion. Holds scratch buffers: reuse one per thread.
class ContourTester {
 public:
  /// DCD: proves that the projection along v of the node's contour at positions x is a set of
  /// simple closed polygons, meeting only at pinch vertices without crossing there, whose winding
  /// numbers add up to at most 1 everywhere (`simple == true`); anything not proven is reported as
  /// not simple.
  /// @pre nodes.status(node) == loops; v non-zero.
  [[nodiscard]] ContourVerdict test(
      const NodeContours& nodes,
      std::int32_t node,
      const Eigen::Vector3d& v,
      const skinning::Positions& x,
      ContourMode mode,
      ContourTestCounters& counters);

  /// CCD: proves the same for every t in [0,1] while every vertex moves linearly from x_t0 to
  /// x_t1 (the continuous contour test).
  [[nodiscard]] ContourVerdict test(
      const NodeContours& nodes,
      std::int32_t node,
      const Eigen::Vector3d& v,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      ContourMode mode,
      ContourTestCounters& counters);

 private:
  template <bool kContinuous>
  ContourVerdict run(
      const NodeContours& nodes,
      std::int32_t node,
      const Eigen::Vector3d& v,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      ContourMode mode,
      ContourTestCounters& counters);

  struct Box2 {
    double lo1, hi1, lo2, hi2;
  };
  std::vector<ContourEdge> edges_;  // the node's contour, expanded (NodeContours::edges)
  std::vector<Box2> boxes_;
  std::vector<std::int32_t> chain_of_;
  std::vector<std::pair<double, std::int32_t>> sorted_;
};

}  // namespace skelcd::culling
