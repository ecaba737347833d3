#include "segmentation/atomic_clusters.hpp"

#include <algorithm>
#include <cassert>
#include <numeric>

namespace skelcd::segmentation {

namespace {

constexpr std::int32_t kUnassigned = -1;

double affinity(const Eigen::MatrixXd& W, const skinning::Triangles& F, std::int32_t f,
                std::int32_t label) {
  return W(F(f, 0), label) + W(F(f, 1), label) + W(F(f, 2), label);
}

bool is_positive(const skinning::Positions& V, const skinning::Triangles& F,
                 std::span<const Observer> observers, std::int32_t f, std::int32_t label) {
  return orientation(observers[static_cast<std::size_t>(label)], V, F, f) ==
         Orientation::positive;
}

}  // namespace

std::vector<std::int32_t> largest_weight_bones(const Eigen::MatrixXd& W,
                                               const skinning::Triangles& F) {
  std::vector<std::int32_t> out(static_cast<std::size_t>(F.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::RowVectorXd s = W.row(F(f, 0)) + W.row(F(f, 1)) + W.row(F(f, 2));
    Eigen::Index best = 0;
    for (Eigen::Index b = 1; b < s.size(); ++b) {
      if (s[b] > s[best]) best = b;
    }
    out[static_cast<std::size_t>(f)] = static_cast<std::int32_t>(best);
  }
  return out;
}

RefinementStats refine_labels(const skinning::Positions& V, const skinning::Triangles& F,
                              const FaceGraph& graph, std::span<const Observer> observers,
                              const Eigen::MatrixXd& W, std::vector<std::int32_t>& labels) {
  const auto nf = static_cast<std::int32_t>(F.rows());
  assert(labels.size() == static_cast<std::size_t>(nf));
  RefinementStats stats;
  const std::vector<std::int32_t> first = labels;

  // 1. Remove the triangles that are not positively oriented to their own cluster's observer.
  for (std::int32_t f = 0; f < nf; ++f) {
    auto& l = labels[static_cast<std::size_t>(f)];
    if (!is_positive(V, F, observers, f, l)) {
      l = kUnassigned;
      ++stats.removed;
    }
  }
  stats.non_positive_before = stats.removed;

  // The unassigned triangles that touch an assigned one: the growth frontier.
  std::vector<std::int32_t> frontier;
  std::vector<char> in_frontier(static_cast<std::size_t>(nf), 0);
  const auto neighbours = [&](std::int32_t f) {
    return std::span<const std::int32_t>(
        graph.neighbours.data() + graph.offsets[static_cast<std::size_t>(f)],
        graph.neighbours.data() + graph.offsets[static_cast<std::size_t>(f) + 1]);
  };
  const auto push_unassigned_neighbours = [&](std::int32_t f, std::vector<std::int32_t>& out) {
    for (const auto g : neighbours(f)) {
      if (labels[static_cast<std::size_t>(g)] == kUnassigned && !in_frontier[static_cast<std::size_t>(g)]) {
        in_frontier[static_cast<std::size_t>(g)] = 1;
        out.push_back(g);
      }
    }
  };
  for (std::int32_t f = 0; f < nf; ++f) {
    if (labels[static_cast<std::size_t>(f)] != kUnassigned) continue;
    for (const auto g : neighbours(f)) {
      if (labels[static_cast<std::size_t>(g)] != kUnassigned) {
        in_frontier[static_cast<std::size_t>(f)] = 1;
        frontier.push_back(f);
        break;
      }
    }
  }

  // One synchronous round over the frontier: each triangle picks, among the labels of its
  // assigned neighbours (as at the start of the round) — only those it is positively oriented to
  // when `constrained` — the one of largest affinity. Returns the triangles that joined.
  std::vector<std::pair<std::int32_t, std::int32_t>> joins;
  const auto round = [&](bool constrained) {
    joins.clear();
    for (const auto f : frontier) {
      std::int32_t best = kUnassigned;
      double best_affinity = 0.0;
      for (const auto g : neighbours(f)) {
        const auto l = labels[static_cast<std::size_t>(g)];
        if (l == kUnassigned || l == best) continue;
        if (constrained && !is_positive(V, F, observers, f, l)) continue;
        const double a = affinity(W, F, f, l);
        if (best == kUnassigned || a > best_affinity || (a == best_affinity && l < best)) {
          best = l;
          best_affinity = a;
        }
      }
      if (best != kUnassigned) joins.emplace_back(f, best);
    }
    for (const auto& [f, l] : joins) labels[static_cast<std::size_t>(f)] = l;
    // New frontier: the old one minus the joined, plus unassigned neighbours of the joined.
    std::vector<std::int32_t> next;
    for (const auto f : frontier) {
      if (labels[static_cast<std::size_t>(f)] == kUnassigned) {
        next.push_back(f);
      } else {
        in_frontier[static_cast<std::size_t>(f)] = 0;
      }
    }
    for (const auto& [f, l] : joins) push_unassigned_neighbours(f, next);
    std::sort(next.begin(), next.end());
    frontier = std::move(next);
    return static_cast<std::int64_t>(joins.size());
  };

  // 2./3. Constrained growth to a fixed point, then one unconstrained ring, and again.
  for (;;) {
    for (std::int64_t n = round(true); n > 0; n = round(true)) stats.regrown_positive += n;
    if (frontier.empty()) break;
    stats.regrown_unconstrained += round(false);
  }

  // Components in which every triangle was removed: nothing can grow into them; restore.
  for (std::int32_t f = 0; f < nf; ++f) {
    auto& l = labels[static_cast<std::size_t>(f)];
    if (l == kUnassigned) {
      l = first[static_cast<std::size_t>(f)];
      ++stats.restored;
    }
  }

  for (std::int32_t f = 0; f < nf; ++f) {
    stats.non_positive_after +=
        !is_positive(V, F, observers, f, labels[static_cast<std::size_t>(f)]);
  }
  return stats;
}

ConnectedClusters split_connected(const FaceGraph& graph, std::span<const std::int32_t> labels) {
  const auto nf = static_cast<std::int32_t>(labels.size());
  ConnectedClusters out;
  out.triangle_cluster.assign(static_cast<std::size_t>(nf), -1);
  // Seeds in (label, triangle) order so that clusters are numbered by label first.
  std::vector<std::int32_t> order(static_cast<std::size_t>(nf));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return labels[static_cast<std::size_t>(a)] < labels[static_cast<std::size_t>(b)];
  });
  std::vector<std::int32_t> stack;
  for (const auto seed : order) {
    if (out.triangle_cluster[static_cast<std::size_t>(seed)] != -1) continue;
    const auto cluster = static_cast<std::int32_t>(out.cluster_label.size());
    const auto label = labels[static_cast<std::size_t>(seed)];
    out.cluster_label.push_back(label);
    out.triangle_cluster[static_cast<std::size_t>(seed)] = cluster;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const auto f = stack.back();
      stack.pop_back();
      for (auto k = graph.offsets[static_cast<std::size_t>(f)];
           k < graph.offsets[static_cast<std::size_t>(f) + 1]; ++k) {
        const auto g = graph.neighbours[static_cast<std::size_t>(k)];
        if (out.triangle_cluster[static_cast<std::size_t>(g)] == -1 &&
            labels[static_cast<std::size_t>(g)] == label) {
          out.triangle_cluster[static_cast<std::size_t>(g)] = cluster;
          stack.push_back(g);
        }
      }
    }
  }
  return out;
}

}  // namespace skelcd::segmentation
