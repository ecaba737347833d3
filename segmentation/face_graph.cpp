#include "segmentation/face_graph.hpp"

#include <algorithm>
#include <array>

namespace skelcd::segmentation {

namespace {

/// g.offsets and g.neighbours from g's edge lists (nf faces).
void add_face_neighbours(FaceGraph& g, std::size_t nf) {
  // Face → faces: every pair of faces on an edge, counted, placed, then sorted and deduplicated
  // per face (lists are short: three neighbours on a manifold mesh).
  std::vector<std::int32_t> degree(nf + 1, 0);
  const auto for_each_pair = [&](auto&& visit) {
    for (std::size_t e = 0; e + 1 < g.edge_offsets.size(); ++e) {
      const auto begin = static_cast<std::size_t>(g.edge_offsets[e]);
      const auto end = static_cast<std::size_t>(g.edge_offsets[e + 1]);
      for (auto x = begin; x < end; ++x) {
        for (auto y = begin; y < end; ++y) {
          if (x != y) visit(g.edge_faces[x], g.edge_faces[y]);
        }
      }
    }
  };
  for_each_pair([&](std::int32_t a, std::int32_t) { ++degree[static_cast<std::size_t>(a) + 1]; });
  for (std::size_t f = 0; f < nf; ++f) degree[f + 1] += degree[f];
  std::vector<std::int32_t> raw(static_cast<std::size_t>(degree[nf]));
  std::vector<std::int32_t> fill(degree.begin(), degree.end() - 1);
  for_each_pair([&](std::int32_t a, std::int32_t b) {
    raw[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
  });
  g.offsets.assign(nf + 1, 0);
  g.neighbours.reserve(raw.size());
  for (std::size_t f = 0; f < nf; ++f) {
    const auto begin = raw.begin() + degree[f];
    const auto end = raw.begin() + degree[f + 1];
    std::sort(begin, end);
    for (auto it = begin; it != end; ++it) {
      if (it == begin || *it != *(it - 1)) g.neighbours.push_back(*it);
    }
    g.offsets[f + 1] = static_cast<std::int32_t>(g.neighbours.size());
  }
}

}  // namespace

FaceGraph face_graph(const skinning::Triangles& F) {
  // (a, b, face) for every side with a < b, sorted: runs of equal (a, b) are the edges.
  std::vector<std::array<std::int32_t, 3>> sides;
  sides.reserve(static_cast<std::size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto a = F(f, k), b = F(f, (k + 1) % 3);
      if (a == b) continue;
      sides.push_back({std::min(a, b), std::max(a, b), static_cast<std::int32_t>(f)});
    }
  }
  std::sort(sides.begin(), sides.end());

  FaceGraph g;
  g.edge_offsets.push_back(0);
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j][0] == sides[i][0] && sides[j][1] == sides[i][1]) ++j;
    for (std::size_t k = i; k < j; ++k) {
      // A triangle listing the same edge twice (a folded, degenerate one) counts once.
      if (k > i && sides[k][2] == sides[k - 1][2]) continue;
      g.edge_faces.push_back(sides[k][2]);
    }
    g.edge_offsets.push_back(static_cast<std::int32_t>(g.edge_faces.size()));
    i = j;
  }
  add_face_neighbours(g, static_cast<std::size_t>(F.rows()));
  return g;
}

FaceGraph face_graph(const skinning::Topology& topology) {
  FaceGraph g;
  g.edge_offsets = topology.edge_face_offsets;
  g.edge_faces = topology.edge_faces;
  if (g.edge_offsets.empty()) g.edge_offsets.push_back(0);
  add_face_neighbours(g, static_cast<std::size_t>(topology.welded_triangles.rows()));
  return g;
}

}  // namespace skelcd::segmentation
