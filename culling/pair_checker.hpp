#pragma once
// Inter-object collision: two meshes (a character and its garment, two links of a robot) checked
// against each other, never against themselves. Each side keeps its own welded topology and AABB
// hierarchy, built once at rest and refit per instant (DCD) or interval (CCD); the two hierarchies
// are traversed against each other (culling::pair_traverse) and the overlapping triangle pairs go
// through the same feature de-duplication and elementary tests as the self-collision methods, with
// the same counters (docs/scenes.md, "Pair checks").

#include <cstdint>
#include <vector>

#include "ccd/accuracy.hpp"
#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "culling/traversal.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

struct PairOptions {
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  /// Contact distance (coordinate units, shared by both objects); 0 = touching counts.
  double min_separation = 0.0;
  BvhOptions bvh{};
  /// The elementary tests to call; null members mean the ccd/ kernels.
  ElementaryTests elementary{};
};

/// A CCD contact between the two objects, in each object's welded numbering.
/// VF: `a` is a welded vertex and `b` a triangle — the vertex of object A against a triangle of
/// object B, or (vertex_of_b) the vertex of B against a triangle of A. EE: `a` is an edge of A,
/// `b` an edge of B (Topology::edges rows).
struct PairContact {
  CcdContact::Kind kind = CcdContact::Kind::vf;
  bool vertex_of_b = false;
  std::int32_t a = -1;
  std::int32_t b = -1;
  double toi_lower = 1.0;
  double toi_upper = 1.0;
  /// Canonical order: (kind, vertex_of_b, a, b).
  [[nodiscard]] bool before(const PairContact& other) const {
    if (kind != other.kind) return kind < other.kind;
    if (vertex_of_b != other.vertex_of_b) return !vertex_of_b;
    if (a != other.a) return a < other.a;
    return b < other.b;
  }
  friend bool operator==(const PairContact&, const PairContact&) = default;
};

/// What one pair query produces. dcd_pairs: `a` a triangle of A, `b` a triangle of B, sorted.
struct PairFrameResult {
  Counters counters;
  StageTimes times;
  std::vector<PairContact> contacts;    ///< sorted canonically
  std::vector<TrianglePair> dcd_pairs;  ///< sorted by (a, b)
  void clear() {
    counters = {};
    times = {};
    contacts.clear();
    dcd_pairs.clear();
  }
};

/// Checks object A against object B. Every cross pair is considered: the objects share no
/// vertex, so no pair is skipped for adjacency and no part exclusion applies between them.
/// Guarantee (tests/culling/test_pair_checker.cpp against all cross pairs): DCD reports exactly
/// the intersecting (triangle of A, triangle of B) pairs; CCD reports each VF pair (vertex of A,
/// face of B), (vertex of B, face of A) and EE pair (edge of A, edge of B) the elementary test
/// reports, each tested once.
class PairChecker {
 public:
  /// @param mesh_a,topology_a object A (its welded topology, built by build_topology).
  /// @param mesh_b,topology_b object B.
  /// @throws InvalidInput as FeatureTopology, for a negative or non-finite min_separation, or
  ///   min_separation > 0 with the `exact` accuracy.
  PairChecker(
      const skinning::Mesh& mesh_a,
      const skinning::Topology& topology_a,
      const skinning::Mesh& mesh_b,
      const skinning::Topology& topology_b,
      const PairOptions& options = {});

  /// Intersecting cross triangle pairs at one instant.
  /// @param x_a #W_a × 3 welded positions of A, x_b #W_b × 3 of B (finite).
  /// @param out cleared by the caller.
  /// @throws InvalidInput when a row count is wrong.
  void detect_dcd(
      const skinning::Positions& x_a, const skinning::Positions& x_b, PairFrameResult& out);

  /// Cross VF / EE contacts over the interval, both objects moving linearly.
  /// @param x_a_t0,x_a_t1 #W_a × 3; x_b_t0,x_b_t1 #W_b × 3.
  void detect_ccd(
      const skinning::Positions& x_a_t0,
      const skinning::Positions& x_a_t1,
      const skinning::Positions& x_b_t0,
      const skinning::Positions& x_b_t1,
      PairFrameResult& out);

  [[nodiscard]] const FeatureTopology& topology_a() const { return topology_a_; }
  [[nodiscard]] const FeatureTopology& topology_b() const { return topology_b_; }

 private:
  void check_rows(const skinning::Positions& x, std::int32_t rows, const char* what) const;

  PairOptions options_;
  ElementaryTests tests_;
  ccd::CcdOptions ccd_options_;
  FeatureTopology topology_a_;
  FeatureTopology topology_b_;
  AabbBvh bvh_a_;
  AabbBvh bvh_b_;
  FeatureBounds<3> bounds_a_;
  FeatureBounds<3> bounds_b_;
  TraversalScratch scratch_;
  std::vector<TrianglePair> pairs_;
  struct VertexFace {
    bool vertex_of_b;
    std::int32_t vertex;
    std::int32_t face;
  };
  std::vector<VertexFace> vf_;
  std::vector<EdgeEdgePair> ee_;  // a: edge of A, b: edge of B
};

}  // namespace skelcd::culling
