#include "clustering/cluster_set.hpp"

#include <algorithm>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::clustering {
namespace {

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

}  // namespace

ClusterSet::ClusterSet(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation& segmentation,
    std::int32_t num_bones,
    const culling::BvhOptions& bvh) {
  const auto num_faces = static_cast<std::int32_t>(topology.welded_triangles.rows());
  const auto num_clusters = static_cast<std::int32_t>(segmentation.clusters.size());
  const std::int32_t num_welded = topology.num_welded_vertices();

  // --- the segmentation must fit the mesh --------------------------------------------------------
  if (static_cast<std::int32_t>(segmentation.triangle_cluster.size()) != num_faces) {
    throw InvalidInput(
        "clustering: the segmentation has " + std::to_string(segmentation.triangle_cluster.size()) +
        " triangles, the mesh " + std::to_string(num_faces));
  }
  if (num_clusters == 0) throw InvalidInput("clustering: the segmentation has no clusters");
  for (std::int32_t f = 0; f < num_faces; ++f) {
    const std::int32_t c = segmentation.triangle_cluster[at(f)];
    if (c < 0 || c >= num_clusters) {
      throw InvalidInput(
          "clustering: triangle " + std::to_string(f) + " is in cluster " + std::to_string(c) +
          ", outside [0, " + std::to_string(num_clusters) + ")");
    }
  }
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    const std::int32_t b = segmentation.clusters[at(c)].bone;
    if (b < 0 || b >= num_bones) {
      throw InvalidInput(
          "clustering: cluster " + std::to_string(c) + " has bone " + std::to_string(b) +
          ", the rig has " + std::to_string(num_bones) + " bones");
    }
  }

  // --- atomic clusters: triangle lists (CSR), bones, observers -----------------------------------
  triangle_atomic_ = segmentation.triangle_cluster;
  atomic_offsets_.assign(at(num_clusters) + 1, 0);
  for (const std::int32_t c : triangle_atomic_) ++atomic_offsets_[at(c) + 1];
  for (std::size_t c = 0; c < at(num_clusters); ++c) atomic_offsets_[c + 1] += atomic_offsets_[c];
  atomic_triangles_.resize(at(num_faces));
  {
    std::vector<std::int32_t> fill(atomic_offsets_.begin(), atomic_offsets_.end() - 1);
    for (std::int32_t f = 0; f < num_faces; ++f) {
      atomic_triangles_[at(fill[at(triangle_atomic_[at(f)])]++)] = f;
    }
  }
  atomic_bone_.resize(at(num_clusters));
  atomic_observer_.resize(at(num_clusters));
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    atomic_bone_[at(c)] = segmentation.clusters[at(c)].bone;
    atomic_observer_[at(c)] = segmentation.clusters[at(c)].observer;
  }

  // --- the cluster graph: joints and per-cluster neighbour lists ---------------------------------
  joints_.reserve(segmentation.graph.size());
  for (std::size_t i = 0; i < segmentation.graph.size(); ++i) {
    const auto& g = segmentation.graph[i];
    if (g.a < 0 || g.b < 0 || g.a >= num_clusters || g.b >= num_clusters || g.a == g.b) {
      throw InvalidInput(
          "clustering: cluster graph entry " + std::to_string(i) + " joins clusters " +
          std::to_string(g.a) + " and " + std::to_string(g.b) + ", outside [0, " +
          std::to_string(num_clusters) + ") or equal");
    }
    ClusterJoint j;
    j.a = g.a;
    j.b = g.b;
    j.bone = (g.ancestor_bone >= 0 && g.ancestor_bone < num_bones) ? g.ancestor_bone
                                                                  : atomic_bone_[at(g.a)];
    j.rest = g.joint;
    joints_.push_back(j);
  }
  neighbour_offsets_.assign(at(num_clusters) + 1, 0);
  for (const auto& j : joints_) {
    ++neighbour_offsets_[at(j.a) + 1];
    ++neighbour_offsets_[at(j.b) + 1];
  }
  for (std::size_t c = 0; c < at(num_clusters); ++c) {
    neighbour_offsets_[c + 1] += neighbour_offsets_[c];
  }
  neighbours_.resize(at(neighbour_offsets_.back()));
  {
    std::vector<std::int32_t> fill(neighbour_offsets_.begin(), neighbour_offsets_.end() - 1);
    for (std::size_t e = 0; e < joints_.size(); ++e) {
      const auto& j = joints_[e];
      neighbours_[at(fill[at(j.a)]++)] = {j.b, static_cast<std::int32_t>(e)};
      neighbours_[at(fill[at(j.b)]++)] = {j.a, static_cast<std::int32_t>(e)};
    }
  }
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    auto begin = neighbours_.begin() + neighbour_offsets_[at(c)];
    auto end = neighbours_.begin() + neighbour_offsets_[at(c) + 1];
    std::sort(begin, end, [](const ClusterNeighbour& x, const ClusterNeighbour& y) {
      return x.cluster != y.cluster ? x.cluster < y.cluster : x.edge < y.edge;
    });
  }

  // --- components: which ones the radial-view argument applies to --------------------------------
  const auto num_components = static_cast<std::int32_t>(topology.components.size());
  triangle_component_ = topology.face_component;
  if (static_cast<std::int32_t>(triangle_component_.size()) != num_faces) {
    throw InvalidInput("clustering: the topology has no component for every triangle");
  }
  component_ok_.assign(at(num_components), 0);
  for (std::int32_t k = 0; k < num_components; ++k) {
    component_ok_[at(k)] = topology.components[at(k)].closed ? 1 : 0;
  }
  // Consistent orientation: the two faces of every interior edge run along it in opposite
  // directions (the crossings of a ray then alternate in sign, docs/radial-view.md).
  const auto num_edges = topology.num_edges();
  for (std::int32_t e = 0; e < num_edges; ++e) {
    const auto begin = topology.edge_face_offsets[at(e)];
    const auto end = topology.edge_face_offsets[at(e) + 1];
    if (end - begin != 2) continue;  // boundary / non-manifold: the component is not closed
    int direction_sum = 0;
    for (auto i = begin; i < end; ++i) {
      const std::int32_t f = topology.edge_faces[at(i)];
      for (int k = 0; k < 3; ++k) {
        if (topology.face_edges(f, k) == e) {
          direction_sum += topology.welded_triangles(f, k) == topology.edges(e, 0) ? 1 : -1;
          break;
        }
      }
    }
    if (direction_sum != 0) {
      component_ok_[at(triangle_component_[at(topology.edge_faces[at(begin)])])] = 0;
    }
  }
  // One part per component when part pairs are excluded: an excluded pair inside a component
  // hides contacts the argument relies on.
  if (!mesh.excluded_part_pairs.empty() && !mesh.face_part.empty()) {
    std::vector<std::int32_t> part(at(num_components), -1);
    for (std::int32_t f = 0; f < num_faces; ++f) {
      const std::int32_t k = triangle_component_[at(f)];
      if (part[at(k)] < 0) part[at(k)] = mesh.face_part[at(f)];
      if (part[at(k)] != mesh.face_part[at(f)]) component_ok_[at(k)] = 0;
    }
  }
  // Atomic clusters must not straddle components (mega clusters grow over shared edges, so they
  // then stay inside one component too).
  atomic_component_.assign(at(num_clusters), -1);
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    const auto tris = triangles(c);
    if (tris.empty()) continue;
    const std::int32_t k = triangle_component_[at(tris.front())];
    atomic_component_[at(c)] = k;
    for (const std::int32_t f : tris) {
      if (triangle_component_[at(f)] != k) {
        component_ok_[at(k)] = 0;
        component_ok_[at(triangle_component_[at(f)])] = 0;
      }
    }
  }

  // --- vertex components -------------------------------------------------------------------------
  vertex_component_.assign(at(num_welded), -1);
  for (std::int32_t f = 0; f < num_faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      vertex_component_[at(topology.welded_triangles(f, k))] = triangle_component_[at(f)];
    }
  }

  // --- hierarchies: one per atomic cluster over welded rest positions, one over the clusters -----
  skinning::Positions rest(num_welded, 3);
  for (std::int32_t w = 0; w < num_welded; ++w) {
    rest.row(w) = mesh.rest_positions.row(topology.representative_vertex[at(w)]);
  }
  // No binary node volumes (2·#F volumes less): everything walks the wide copy and tests the
  // triangles' own volumes after a lane's (radial_view_method.cpp); the root's exact volume is
  // kept (Bvh::root_bounds).
  culling::BvhOptions local_options = bvh;
  local_options.node_volumes = false;
  local_.reserve(at(num_clusters));
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    local_.emplace_back(topology.welded_triangles, rest, triangles(c), local_options);
  }
  // The global hierarchy reuses Bvh over "triangles" (c, c, c) whose one point is the cluster's
  // centroid: the median split then orders clusters by centroid, and its leaves are the clusters.
  skinning::Positions centroids = skinning::Positions::Zero(num_clusters, 3);
  skinning::Triangles items(num_clusters, 3);
  for (std::int32_t c = 0; c < num_clusters; ++c) {
    const auto tris = triangles(c);
    for (const std::int32_t f : tris) {
      for (int k = 0; k < 3; ++k) centroids.row(c) += rest.row(topology.welded_triangles(f, k));
    }
    if (!tris.empty()) centroids.row(c) /= 3.0 * static_cast<double>(tris.size());
    items.row(c).setConstant(c);
  }
  global_ = culling::AabbBvh(
      items, centroids, culling::BvhOptions{.leaf_size = 1, .split = culling::BvhSplit::median});
}

}  // namespace skelcd::clustering
