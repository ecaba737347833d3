#include "segmentation/face_graph.hpp"

#include <algorithm>
#include <array>

namespace skelcd::segmentation {

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
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j][0] == sides[i][0] && sides[j][1] == sides[i][1]) ++j;
    for (std::size_t k = i; k < j; ++k) {
      // A triangle listing the same edge twice (a folded, degenerate one) counts once.
      if (k > i && sides[k][2] == sides[k - 1][2]) continue;
      g.edge_faces.push_back(sides[k][2]);
      for (std::size_t l = i; l < k; ++l) {
        if (sides[l][2] == sides[k][2]) continue;
        pairs.emplace_back(sides[k][2], sides[l][2]);
        pairs.emplace_back(sides[l][2], sides[k][2]);
      }
    }
    g.edge_offsets.push_back(static_cast<std::int32_t>(g.edge_faces.size()));
    i = j;
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  g.offsets.assign(static_cast<std::size_t>(F.rows()) + 1, 0);
  for (const auto& p : pairs) ++g.offsets[static_cast<std::size_t>(p.first) + 1];
  for (std::size_t f = 0; f < static_cast<std::size_t>(F.rows()); ++f) {
    g.offsets[f + 1] += g.offsets[f];
  }
  g.neighbours.reserve(pairs.size());
  for (const auto& p : pairs) g.neighbours.push_back(p.second);
  return g;
}

}  // namespace skelcd::segmentation
