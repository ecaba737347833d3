#pragma once
// The welded features of one mesh as the culling stages use them, built once per mesh: triangles
// and edges in welded ids, the representative-triangle ownership of every vertex and edge (Curtis,
// Tamstorf & Manocha 2008: each feature is assigned to exactly one incident triangle, so a feature
// pair is produced by exactly one triangle pair), and the part exclusions of
// Mesh::excluded_part_pairs.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ccd/triangle_triangle.hpp"
#include "culling/vertex_fans.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

class FeatureTopology {
 public:
  FeatureTopology() = default;

  /// @param mesh the parts of its triangles (face_part; empty = one part) and the excluded pairs.
  /// @param topology welded_triangles (#F × 3), edges (#E × 2), face_edges (#F × 3) and
  ///        representative_vertex (#W) are used.
  /// @throws InvalidInput naming "culling" and the offending index when the two disagree: sizes,
  ///         ids out of range, a face_edges entry that is not the side it claims (-1 is accepted
  ///         for a collapsed side only), a part id of an excluded pair outside [0, num_parts),
  ///         or an owner_order that is not a permutation of the triangles.
  /// @param owner_order the order in which the triangles take the vertices and edges no earlier
  ///        triangle took (a permutation of 0 … #F−1); empty: triangle order. Any order gives each
  ///        feature exactly one owner; a method may choose one that gathers features it treats
  ///        alike into few triangles (clustering::RadialViewMethod: the cluster rims).
  FeatureTopology(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      std::span<const std::int32_t> owner_order = {});

  /// True when this was built from these very objects in triangle order (no owner_order): what a
  /// method may take instead of building its own (MethodOptions::features). A mesh of other parts
  /// or exclusions can have the same triangles, so the counts do not say it. The mesh by address;
  /// the topology by the address of its welded-triangle array, which a move of the Topology keeps
  /// and a copy does not (so that a caller may build this, then move the topology into its owner),
  /// and by its own address when that array is empty.
  [[nodiscard]] bool built_from(
      const skinning::Mesh& mesh, const skinning::Topology& topology) const {
    return triangle_order_ && describes(mesh, topology);
  }
  /// True when this was built from these very objects, in any owner order: what a user that
  /// reads no ownership may take (the DCD, culling::DcdUpdater).
  [[nodiscard]] bool describes(
      const skinning::Mesh& mesh, const skinning::Topology& topology) const {
    return mesh_ == &mesh && topology_ == identity(topology);
  }

  [[nodiscard]] std::int32_t num_vertices() const { return num_vertices_; }
  [[nodiscard]] std::int32_t num_triangles() const {
    return static_cast<std::int32_t>(triangles_.size());
  }
  [[nodiscard]] std::int32_t num_edges() const { return static_cast<std::int32_t>(edges_.size()); }

  /// Welded corners of triangle f.
  [[nodiscard]] const std::array<std::int32_t, 3>& triangle(std::int32_t f) const {
    return triangles_[static_cast<std::size_t>(f)];
  }
  /// Welded endpoints of edge e (smaller first).
  [[nodiscard]] const std::array<std::int32_t, 2>& edge(std::int32_t e) const {
    return edges_[static_cast<std::size_t>(e)];
  }
  /// Edge id of side k (corner k → corner (k+1) % 3) of triangle f; -1 for a collapsed side
  /// (both corners the same welded vertex), which is no edge.
  [[nodiscard]] std::int32_t face_edge(std::int32_t f, int k) const {
    return face_edges_[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
  }
  /// #F × 3 welded triangles (a copy of the Topology's), for the bounds and the BVH build.
  [[nodiscard]] const skinning::Triangles& welded_triangles() const { return welded_triangles_; }

  /// Ownership bits of triangle f: bit k (k < 3) — f owns the vertex at corner k; bit 3 + k — f
  /// owns the edge of side k.
  [[nodiscard]] std::uint8_t owned(std::int32_t f) const {
    return owned_[static_cast<std::size_t>(f)];
  }
  /// What the CCD feature stage reads of one triangle, in one cache line: its corners, the
  /// vertices and edges it owns in corner / side order (the set bits of owned(f), collapsed sides
  /// never among them) and where they are among the corners, so that the stage reads each
  /// corner's position once and compares vertex ids once per triangle pair.
  struct alignas(64) OwnedFeatures {
    std::array<std::int32_t, 3> corners;
    std::array<std::int32_t, 3> vertices;  ///< the first num_vertices are owned
    std::array<std::int32_t, 3> edges;     ///< the first num_edges are owned
    /// corners[vertex_slots[k]] is vertices[k].
    std::array<std::uint8_t, 3> vertex_slots;
    /// corners[edge_slots[i][0]] and corners[edge_slots[i][1]] are edge(edges[i])[0] and [1].
    std::array<std::array<std::uint8_t, 2>, 3> edge_slots;
    std::uint8_t num_vertices;
    std::uint8_t num_edges;
  };
  [[nodiscard]] const OwnedFeatures& owned_features(std::int32_t f) const {
    return owned_features_[static_cast<std::size_t>(f)];
  }
  /// The triangle owning vertex v (its first incident triangle in the owner order), or -1 when v
  /// is on no triangle.
  [[nodiscard]] std::int32_t vertex_owner(std::int32_t v) const {
    return vertex_owner_[static_cast<std::size_t>(v)];
  }
  /// The triangle owning edge e (its first incident triangle in the owner order).
  [[nodiscard]] std::int32_t edge_owner(std::int32_t e) const {
    return edge_owner_[static_cast<std::size_t>(e)];
  }

  /// True when the mesh excludes any part pair (else every *_excluded below is false).
  [[nodiscard]] bool has_exclusions() const { return has_exclusions_; }
  /// DCD: triangles a and b lie in an excluded part pair.
  [[nodiscard]] bool triangles_excluded(std::int32_t a, std::int32_t b) const {
    return has_exclusions_ && part_pair_excluded(face_part(a), face_part(b));
  }
  /// CCD: every (triangle at v, face f) part pair is excluded. A feature belongs to the parts of
  /// all its incident triangles; a feature pair is skipped only when no triangle pair holding it
  /// may be checked.
  [[nodiscard]] bool vertex_face_excluded(std::int32_t v, std::int32_t f) const {
    return has_exclusions_ && all_excluded(vertex_parts(v), face_part(f));
  }
  /// CCD: every (triangle at edge a, triangle at edge b) part pair is excluded.
  [[nodiscard]] bool edges_excluded(std::int32_t a, std::int32_t b) const {
    return has_exclusions_ && all_excluded(edge_parts(a), edge_parts(b));
  }
  /// True when every feature pair triangles a and b can produce (their owned features) is
  /// excluded: both own only features of their own part, and that part pair is excluded.
  [[nodiscard]] bool owned_pairs_excluded(std::int32_t a, std::int32_t b) const {
    return has_exclusions_ && pure_[static_cast<std::size_t>(a)] &&
           pure_[static_cast<std::size_t>(b)] && part_pair_excluded(face_part(a), face_part(b));
  }

  /// Which corners triangle a shares with triangle b: result[i] = j when corner i of a is corner
  /// j of b (the first such j), -1 otherwise. `count` receives the number of distinct shared
  /// welded vertices.
  [[nodiscard]] ccd::SharedCorners shared_corners(std::int32_t a, std::int32_t b, int& count) const;

  /// The vertex fans (culling/vertex_fans.hpp), for the DCD tests of pairs sharing a corner.
  [[nodiscard]] const VertexFans& fans() const { return fans_; }

  [[nodiscard]] std::int32_t face_part(std::int32_t f) const {
    return face_part_.empty() ? 0 : face_part_[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] bool part_pair_excluded(std::int32_t p, std::int32_t q) const {
    return excluded_[static_cast<std::size_t>(p) * num_parts_ + static_cast<std::size_t>(q)] != 0;
  }

 private:
  [[nodiscard]] std::span<const std::int32_t> vertex_parts(std::int32_t v) const;
  [[nodiscard]] std::span<const std::int32_t> edge_parts(std::int32_t e) const;
  [[nodiscard]] bool all_excluded(std::span<const std::int32_t> parts, std::int32_t q) const;
  [[nodiscard]] bool all_excluded(
      std::span<const std::int32_t> parts_a, std::span<const std::int32_t> parts_b) const;

  /// What built_from compares a topology by (never read through).
  [[nodiscard]] static const void* identity(const skinning::Topology& topology) {
    const void* triangles = topology.welded_triangles.data();
    return triangles != nullptr ? triangles : static_cast<const void*>(&topology);
  }

  // Provenance, for built_from: the mesh given to the constructor and identity(topology).
  const skinning::Mesh* mesh_ = nullptr;
  const void* topology_ = nullptr;
  bool triangle_order_ = true;
  skinning::Triangles welded_triangles_;
  std::int32_t num_vertices_ = 0;
  std::vector<std::array<std::int32_t, 3>> triangles_;
  std::vector<std::array<std::int32_t, 2>> edges_;
  std::vector<std::array<std::int32_t, 3>> face_edges_;
  std::vector<std::uint8_t> owned_;
  std::vector<OwnedFeatures> owned_features_;
  std::vector<std::int32_t> vertex_owner_;
  std::vector<std::int32_t> edge_owner_;

  // Parts: per face; per vertex and per edge the sorted distinct parts of the incident triangles
  // (CSR); pure_[f] when all features f owns lie in f's part only; the #P × #P exclusion table.
  std::vector<std::int32_t> face_part_;
  std::vector<std::int32_t> vertex_part_offsets_, vertex_part_ids_;
  std::vector<std::int32_t> edge_part_offsets_, edge_part_ids_;
  std::vector<std::uint8_t> pure_;
  std::size_t num_parts_ = 1;
  std::vector<std::uint8_t> excluded_ = std::vector<std::uint8_t>(1, 0);
  bool has_exclusions_ = false;
  VertexFans fans_;
};

/// Which owner orders a FeatureTopology's user accepts: `triangle` (a method: what it tests
/// follows the ownership) or `any` (a user that reads no ownership: the DCD).
enum class OwnerOrder { triangle, any };

/// `offered` when it was built from these very objects (built_from; with OwnerOrder::any,
/// describes), else a new FeatureTopology(mesh, topology): how a method or a DCD updater takes
/// the one its caller shares (MethodOptions::features) without ever taking one of another mesh.
[[nodiscard]] std::shared_ptr<const FeatureTopology> shared_or_built(
    std::shared_ptr<const FeatureTopology> offered,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    OwnerOrder accepted = OwnerOrder::triangle);

}  // namespace skelcd::culling
