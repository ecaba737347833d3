#include "culling/feature_topology.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace {

std::string at(const char* what, std::int64_t index) {
  return std::string("culling::FeatureTopology: ") + what + " " + std::to_string(index);
}

/// CSR of the sorted distinct values per key from (key, value) pairs.
void build_csr(
    std::vector<std::pair<std::int32_t, std::int32_t>>& pairs,
    std::size_t num_keys,
    std::vector<std::int32_t>& offsets,
    std::vector<std::int32_t>& values) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  offsets.assign(num_keys + 1, 0);
  values.clear();
  values.reserve(pairs.size());
  for (const auto& [key, value] : pairs) {
    ++offsets[static_cast<std::size_t>(key) + 1];
    values.push_back(value);
  }
  for (std::size_t k = 0; k < num_keys; ++k) offsets[k + 1] += offsets[k];
}

}  // namespace

FeatureTopology::FeatureTopology(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    std::span<const std::int32_t> owner_order)
    : mesh_(&mesh),
      topology_(identity(topology)),
      triangle_order_(owner_order.empty()),
      welded_triangles_(topology.welded_triangles),
      num_vertices_(topology.num_welded_vertices()) {
  const auto num_faces = static_cast<std::size_t>(topology.welded_triangles.rows());
  const auto num_edges = static_cast<std::size_t>(topology.edges.rows());
  const auto num_vertices = static_cast<std::size_t>(num_vertices_);

  // Sizes and ranges: the mesh and its topology must describe the same triangles.
  if (num_faces != static_cast<std::size_t>(mesh.triangles.rows())) {
    throw InvalidInput(
        "culling::FeatureTopology: topology has " + std::to_string(num_faces) +
        " welded triangles, the mesh " + std::to_string(mesh.triangles.rows()));
  }
  if (static_cast<std::size_t>(topology.face_edges.rows()) != num_faces) {
    throw InvalidInput(
        "culling::FeatureTopology: face_edges has " + std::to_string(topology.face_edges.rows()) +
        " rows, expected " + std::to_string(num_faces));
  }
  if (!mesh.face_part.empty() && mesh.face_part.size() != num_faces) {
    throw InvalidInput(
        "culling::FeatureTopology: mesh.face_part has " + std::to_string(mesh.face_part.size()) +
        " entries, expected " + std::to_string(num_faces));
  }
  num_parts_ = std::max<std::size_t>(1, static_cast<std::size_t>(mesh.num_parts()));
  triangles_.resize(num_faces);
  face_edges_.resize(num_faces);
  edges_.resize(num_edges);
  for (std::size_t e = 0; e < num_edges; ++e) {
    const auto r = static_cast<Eigen::Index>(e);
    for (Eigen::Index k = 0; k < 2; ++k) {
      const std::int32_t v = topology.edges(r, k);
      if (v < 0 || static_cast<std::size_t>(v) >= num_vertices) throw InvalidInput(at("edge", r));
    }
    edges_[e] = {topology.edges(r, 0), topology.edges(r, 1)};
  }
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto r = static_cast<Eigen::Index>(f);
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t v = topology.welded_triangles(r, k);
      if (v < 0 || static_cast<std::size_t>(v) >= num_vertices) {
        throw InvalidInput(at("welded triangle", r) + " has vertex id out of range");
      }
      triangles_[f][static_cast<std::size_t>(k)] = v;
    }
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t e = topology.face_edges(r, k);
      // Side k joins corner k and corner (k+1) % 3; a collapsed side (both corners the same
      // welded vertex) is no edge and has id -1.
      const std::int32_t u = triangles_[f][static_cast<std::size_t>(k)];
      const std::int32_t w = triangles_[f][static_cast<std::size_t>((k + 1) % 3)];
      if (e == -1 && u == w) {
        face_edges_[f][static_cast<std::size_t>(k)] = -1;
        continue;
      }
      if (e < 0 || static_cast<std::size_t>(e) >= num_edges) {
        throw InvalidInput(at("face_edges of triangle", r) + " has edge id out of range");
      }
      const auto& ed = edges_[static_cast<std::size_t>(e)];
      if (!((ed[0] == u && ed[1] == w) || (ed[0] == w && ed[1] == u))) {
        throw InvalidInput(
            at("face_edges of triangle", r) + " side " + std::to_string(k) + " is edge " +
            std::to_string(e) + ", which does not join that side's corners");
      }
      face_edges_[f][static_cast<std::size_t>(k)] = e;
    }
    if (!mesh.face_part.empty()) {
      const std::int32_t p = mesh.face_part[f];
      if (p < 0 || static_cast<std::size_t>(p) >= num_parts_) {
        throw InvalidInput(at("triangle", r) + " has part " + std::to_string(p) + " out of range");
      }
    }
  }
  face_part_ = mesh.face_part;

  // Representative triangles: every vertex and edge goes to its first incident triangle (in the
  // owner order, else triangle order), and to one corner / side of it (a degenerate triangle may
  // list a vertex twice).
  if (!owner_order.empty()) {
    std::vector<std::uint8_t> seen(num_faces, 0);
    bool permutation = owner_order.size() == num_faces;
    for (std::size_t i = 0; permutation && i < owner_order.size(); ++i) {
      const std::int32_t f = owner_order[i];
      permutation = f >= 0 && static_cast<std::size_t>(f) < num_faces &&
                    seen[static_cast<std::size_t>(f)] == 0;
      if (permutation) seen[static_cast<std::size_t>(f)] = 1;
    }
    if (!permutation) {
      throw InvalidInput(
          "culling: the owner order (" + std::to_string(owner_order.size()) +
          " entries) is not a permutation of the " + std::to_string(num_faces) + " triangles");
    }
  }
  owned_.assign(num_faces, 0);
  vertex_owner_.assign(num_vertices, -1);
  edge_owner_.assign(num_edges, -1);
  for (std::size_t i = 0; i < num_faces; ++i) {
    const auto f = owner_order.empty() ? i : static_cast<std::size_t>(owner_order[i]);
    for (std::size_t k = 0; k < 3; ++k) {
      auto& vo = vertex_owner_[static_cast<std::size_t>(triangles_[f][k])];
      if (vo < 0) {
        vo = static_cast<std::int32_t>(f);
        owned_[f] = static_cast<std::uint8_t>(owned_[f] | (1u << k));
      }
      if (face_edges_[f][k] < 0) continue;  // a collapsed side
      auto& eo = edge_owner_[static_cast<std::size_t>(face_edges_[f][k])];
      if (eo < 0) {
        eo = static_cast<std::int32_t>(f);
        owned_[f] = static_cast<std::uint8_t>(owned_[f] | (1u << (3 + k)));
      }
    }
  }
  owned_features_.resize(num_faces);
  for (std::size_t f = 0; f < num_faces; ++f) {
    OwnedFeatures& o = owned_features_[f];
    o = {};
    o.corners = triangles_[f];
    for (std::size_t k = 0; k < 3; ++k) {
      if (owned_[f] & (1u << k)) {
        o.vertex_slots[o.num_vertices] = static_cast<std::uint8_t>(k);
        o.vertices[o.num_vertices++] = triangles_[f][k];
      }
      if (owned_[f] & (1u << (3 + k))) {
        // Side k joins corners k and k + 1, in the edge's order.
        const std::int32_t e = face_edges_[f][k];
        const auto next = static_cast<std::uint8_t>((k + 1) % 3);
        const bool same_way = edges_[static_cast<std::size_t>(e)][0] == triangles_[f][k];
        o.edge_slots[o.num_edges] = {
            same_way ? static_cast<std::uint8_t>(k) : next,
            same_way ? next : static_cast<std::uint8_t>(k)};
        o.edges[o.num_edges++] = e;
      }
    }
  }
  for (std::size_t e = 0; e < num_edges; ++e) {
    if (edge_owner_[e] < 0) {
      throw InvalidInput(at("edge", static_cast<std::int64_t>(e)) + " is a side of no triangle");
    }
  }

  // Part exclusions: the table, then each feature's parts (those of its incident triangles).
  excluded_.assign(num_parts_ * num_parts_, 0);
  for (std::size_t i = 0; i < mesh.excluded_part_pairs.size(); ++i) {
    const auto [p, q] = mesh.excluded_part_pairs[i];
    if (p < 0 || q < 0 || static_cast<std::size_t>(p) >= num_parts_ ||
        static_cast<std::size_t>(q) >= num_parts_) {
      throw InvalidInput(
          at("excluded_part_pairs entry", static_cast<std::int64_t>(i)) +
          " names a part outside [0, " + std::to_string(num_parts_) + ")");
    }
    excluded_[static_cast<std::size_t>(p) * num_parts_ + static_cast<std::size_t>(q)] = 1;
    excluded_[static_cast<std::size_t>(q) * num_parts_ + static_cast<std::size_t>(p)] = 1;
    has_exclusions_ = true;
  }
  pure_.assign(num_faces, 1);
  if (has_exclusions_) {
    std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
    pairs.reserve(3 * num_faces);
    for (std::size_t f = 0; f < num_faces; ++f) {
      for (std::size_t k = 0; k < 3; ++k) {
        pairs.emplace_back(triangles_[f][k], face_part(static_cast<std::int32_t>(f)));
      }
    }
    build_csr(pairs, num_vertices, vertex_part_offsets_, vertex_part_ids_);
    pairs.clear();
    for (std::size_t f = 0; f < num_faces; ++f) {
      for (std::size_t k = 0; k < 3; ++k) {
        if (face_edges_[f][k] < 0) continue;
        pairs.emplace_back(face_edges_[f][k], face_part(static_cast<std::int32_t>(f)));
      }
    }
    build_csr(pairs, num_edges, edge_part_offsets_, edge_part_ids_);
    for (std::size_t f = 0; f < num_faces; ++f) {
      const std::int32_t p = face_part(static_cast<std::int32_t>(f));
      const auto only_p = [p](std::span<const std::int32_t> parts) {
        return parts.size() == 1 && parts[0] == p;
      };
      for (std::size_t k = 0; k < 3; ++k) {
        if ((owned_[f] & (1u << k)) && !only_p(vertex_parts(triangles_[f][k]))) pure_[f] = 0;
        if ((owned_[f] & (1u << (3 + k))) && !only_p(edge_parts(face_edges_[f][k]))) pure_[f] = 0;
      }
    }
  }
  fans_ = VertexFans(triangles_, num_vertices_);
}

std::span<const std::int32_t> FeatureTopology::vertex_parts(std::int32_t v) const {
  const auto b = static_cast<std::size_t>(vertex_part_offsets_[static_cast<std::size_t>(v)]);
  const auto e = static_cast<std::size_t>(vertex_part_offsets_[static_cast<std::size_t>(v) + 1]);
  return std::span<const std::int32_t>(vertex_part_ids_).subspan(b, e - b);
}

std::span<const std::int32_t> FeatureTopology::edge_parts(std::int32_t e) const {
  const auto b = static_cast<std::size_t>(edge_part_offsets_[static_cast<std::size_t>(e)]);
  const auto n = static_cast<std::size_t>(edge_part_offsets_[static_cast<std::size_t>(e) + 1]);
  return std::span<const std::int32_t>(edge_part_ids_).subspan(b, n - b);
}

bool FeatureTopology::all_excluded(std::span<const std::int32_t> parts, std::int32_t q) const {
  for (const std::int32_t p : parts) {
    if (!part_pair_excluded(p, q)) return false;
  }
  return true;
}

bool FeatureTopology::all_excluded(
    std::span<const std::int32_t> parts_a, std::span<const std::int32_t> parts_b) const {
  for (const std::int32_t p : parts_a) {
    for (const std::int32_t q : parts_b) {
      if (!part_pair_excluded(p, q)) return false;
    }
  }
  return true;
}

ccd::SharedCorners FeatureTopology::shared_corners(
    std::int32_t a, std::int32_t b, int& count) const {
  const auto& ta = triangle(a);
  const auto& tb = triangle(b);
  ccd::SharedCorners shared = ccd::kNoSharedCorners;
  count = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) {
      if (ta[i] == tb[j]) {
        shared[i] = static_cast<std::int8_t>(j);
        break;
      }
    }
    // Count distinct welded vertices (a degenerate triangle may repeat one).
    if (shared[i] >= 0 && (i == 0 || ta[i] != ta[0]) && (i < 2 || ta[2] != ta[1])) ++count;
  }
  return shared;
}

std::shared_ptr<const FeatureTopology> shared_or_built(
    std::shared_ptr<const FeatureTopology> offered,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    OwnerOrder accepted) {
  if (offered != nullptr && (accepted == OwnerOrder::any ? offered->describes(mesh, topology)
                                                         : offered->built_from(mesh, topology))) {
    return offered;
  }
  return std::make_shared<const FeatureTopology>(mesh, topology);
}

}  // namespace skelcd::culling
