#include "segmentation/cluster_graph.hpp"

#include <algorithm>
#include <map>
#include <utility>

namespace skelcd::segmentation {

namespace {

// Bone j and its ancestors, j first. Guards against a cycle by the bone count.
std::vector<std::int32_t> ancestors(const std::vector<BoneSegment>& bones, std::int32_t j) {
  std::vector<std::int32_t> out;
  for (std::int32_t b = j; b >= 0 && out.size() <= bones.size();
       b = bones[static_cast<std::size_t>(b)].parent) {
    out.push_back(b);
  }
  return out;
}

}  // namespace

BoneJoint bone_joint(const std::vector<BoneSegment>& bones, std::int32_t j, std::int32_t k) {
  BoneJoint out;
  if (j == k) {
    out.ancestor_bone = j;
    out.joint = bones[static_cast<std::size_t>(j)].midpoint();
    return out;
  }
  const auto path_j = ancestors(bones, j);
  const auto path_k = ancestors(bones, k);
  // Nearest common ancestor: the first bone on j's path that is also on k's.
  std::size_t ij = 0;
  std::size_t ik = 0;
  bool found = false;
  for (ij = 0; ij < path_j.size() && !found; ++ij) {
    for (ik = 0; ik < path_k.size(); ++ik) {
      if (path_j[ij] == path_k[ik]) {
        found = true;
        break;
      }
    }
    if (found) break;
  }
  const auto head = [&](std::int32_t b) { return bones[static_cast<std::size_t>(b)].head; };
  if (!found) {
    out.joint = 0.5 * (head(path_j.back()) + head(path_k.back()));
    return out;
  }
  out.ancestor_bone = path_j[ij];
  // The bones leaving the ancestor towards j and towards k (index − 1 on each path).
  if (ij == 0) {
    out.joint = head(path_k[ik - 1]);
  } else if (ik == 0) {
    out.joint = head(path_j[ij - 1]);
  } else {
    out.joint = 0.5 * (head(path_j[ij - 1]) + head(path_k[ik - 1]));
  }
  return out;
}

std::vector<ClusterAdjacency> cluster_graph(const FaceGraph& graph,
                                            std::span<const std::int32_t> triangle_cluster,
                                            std::span<const std::int32_t> cluster_bone,
                                            const std::vector<BoneSegment>& bones) {
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> shared;
  std::vector<std::int32_t> on_edge;
  for (std::int32_t e = 0; e < graph.num_edges(); ++e) {
    on_edge.clear();
    for (auto k = graph.edge_offsets[static_cast<std::size_t>(e)];
         k < graph.edge_offsets[static_cast<std::size_t>(e) + 1]; ++k) {
      on_edge.push_back(
          triangle_cluster[static_cast<std::size_t>(graph.edge_faces[static_cast<std::size_t>(k)])]);
    }
    std::sort(on_edge.begin(), on_edge.end());
    on_edge.erase(std::unique(on_edge.begin(), on_edge.end()), on_edge.end());
    for (std::size_t x = 0; x < on_edge.size(); ++x) {
      for (std::size_t y = x + 1; y < on_edge.size(); ++y) ++shared[{on_edge[x], on_edge[y]}];
    }
  }
  std::vector<ClusterAdjacency> out;
  out.reserve(shared.size());
  for (const auto& [key, count] : shared) {
    ClusterAdjacency adj;
    adj.a = key.first;
    adj.b = key.second;
    adj.shared_edges = count;
    const auto joint = bone_joint(bones, cluster_bone[static_cast<std::size_t>(key.first)],
                                  cluster_bone[static_cast<std::size_t>(key.second)]);
    adj.ancestor_bone = joint.ancestor_bone;
    adj.joint = joint.joint;
    out.push_back(adj);
  }
  return out;
}

}  // namespace skelcd::segmentation
