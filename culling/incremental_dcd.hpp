#pragma once
// Incremental DCD (docs/culling.md "Incremental DCD"): when a check runs both queries, the
// intersecting triangle pairs at sample k+1 follow from those at sample k and the CCD contacts of
// the interval k → k+1. A pair can change status over the interval only at a time when a vertex of
// one triangle (not a corner of the other) touches the other triangle, or an edge of one touches an
// edge of the other that shares no vertex with it — exactly the contacts a CCD that never misses
// reports. So only the triangle pairs holding a reported contact's features are tested again; every
// other pair keeps its status.
//
// Sound only with contacts from a CCD that never misses (accuracy exact or conservative, the
// ccd/ kernels) over the same mesh, parts and exclusions; the full DCD stays the reference
// (tests/culling/test_incremental_dcd.cpp compares them sample by sample).

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "culling/elementary.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

class DcdUpdater {
 public:
  /// Builds the incidences (vertex → triangles, edge → triangles) and the DCD rules of `mesh`
  /// (excluded parts, duplicate faces) for its welded `topology`.
  /// @param features the mesh's FeatureTopology when the caller has one built from these very
  ///        objects, in any owner order (FeatureTopology::describes: the updater reads no
  ///        ownership; the runner's, shared by its methods, or `dynamic`'s own): used, not built
  ///        again. Null or built from other objects: one is built here.
  /// @throws InvalidInput as FeatureTopology's constructor.
  DcdUpdater(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      std::shared_ptr<const FeatureTopology> features = {});

  /// The triangle pairs (a < b, sorted, each once) that hold the features of some contact in
  /// `contacts` and that the DCD checks (not part-excluded, not a duplicate face): a VF contact
  /// (v, f) gives every triangle at v with f, an EE contact (e, g) every triangle at e with every
  /// triangle at g.
  void affected_pairs(std::span<const CcdContact> contacts, std::vector<TrianglePair>& out) const;

  /// The intersecting pairs at positions `x` (the end of an interval) from `previous`, the
  /// intersecting pairs at the interval's start (sorted), and `contacts`, the CCD contacts of the
  /// interval: `previous` without the affected pairs, plus the affected pairs that intersect at x.
  /// Appends to out.dcd_pairs (sorted) and counts the tests in out.counters (candidate_pairs: the
  /// affected pairs; tt_tests: the ones tested) and out.times.elementary_us.
  /// @param tests the elementary tests (null members: the ccd/ kernels).
  void update(
      std::span<const TrianglePair> previous,
      std::span<const CcdContact> contacts,
      const skinning::Positions& x,
      const ElementaryTests& tests,
      FrameResult& out);

  [[nodiscard]] const FeatureTopology& features() const { return features_; }
  /// The triangles at welded vertex v, each once, ascending.
  [[nodiscard]] std::span<const std::int32_t> vertex_triangles(std::int32_t v) const {
    return csr_row(vertex_face_offsets_, vertex_faces_, v);
  }
  /// The triangles at edge e, in Topology::edge_faces' order.
  [[nodiscard]] std::span<const std::int32_t> edge_triangles(std::int32_t e) const {
    return csr_row(edge_face_offsets_, edge_faces_, e);
  }
  /// The FeatureTopology it uses (built here or lent), for a method to share.
  [[nodiscard]] const std::shared_ptr<const FeatureTopology>& shared_features() const {
    return shared_;
  }

 private:
  static std::span<const std::int32_t> csr_row(
      const std::vector<std::int32_t>& offsets,
      const std::vector<std::int32_t>& items,
      std::int32_t i) {
    const auto begin = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i)]);
    const auto end = static_cast<std::size_t>(offsets[static_cast<std::size_t>(i) + 1]);
    return std::span(items).subspan(begin, end - begin);
  }

  std::shared_ptr<const FeatureTopology> shared_;
  const FeatureTopology& features_;                // *shared_
  std::vector<std::int32_t> vertex_face_offsets_;  // CSR welded vertex → triangles
  std::vector<std::int32_t> vertex_faces_;
  std::vector<std::int32_t> edge_face_offsets_;  // CSR edge → triangles (Topology's)
  std::vector<std::int32_t> edge_faces_;
  std::vector<TrianglePair> affected_;  // scratch of update
  FrameResult tested_;                  // scratch of update
};

}  // namespace skelcd::culling
