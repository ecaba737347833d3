#include "segmentation/segmentation.hpp"

#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include <tbb/parallel_for.h>

#include "segmentation/atomic_clusters.hpp"
#include "segmentation/face_graph.hpp"
#include "skinning/errors.hpp"

namespace skelcd::segmentation {

namespace {

// Per bone: the bones of its subtree (itself and its descendants), ascending.
std::vector<std::vector<std::int32_t>> subtrees(const std::vector<BoneSegment>& bones) {
  const auto nb = bones.size();
  std::vector<std::vector<std::int32_t>> out(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    // Walk up from k, adding k to every ancestor's subtree (bounded against cycles).
    std::size_t steps = 0;
    for (auto b = static_cast<std::int32_t>(k); b >= 0 && steps <= nb;
         b = bones[static_cast<std::size_t>(b)].parent, ++steps) {
      out[static_cast<std::size_t>(b)].push_back(static_cast<std::int32_t>(k));
    }
  }
  return out;
}

// Runs body(i) for i in [0, n), in parallel when allowed and there is enough work; each i writes
// only its own result, so the outcome does not depend on the schedule.
template <class Body>
void for_each_index(std::size_t n, std::size_t work, bool parallel, Body&& body) {
  if (parallel && work > 20000 && n > 1) {
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { body(i); });
  } else {
    for (std::size_t i = 0; i < n; ++i) body(i);
  }
}

}  // namespace

Segmentation segment_mesh(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    const std::vector<BoneSegment>& bones,
    const Eigen::MatrixXd& W,
    const SegmentationOptions& options,
    const skinning::Topology* topology) {
  if (bones.empty()) throw InvalidInput("segment_mesh: the skeleton has no bones");
  if (F.rows() == 0) throw InvalidInput("segment_mesh: the mesh has no triangles");
  if (W.rows() != V.rows() || W.cols() != static_cast<Eigen::Index>(bones.size())) {
    throw InvalidInput("segment_mesh: weights are " + std::to_string(W.rows()) + " x " +
                       std::to_string(W.cols()) + ", expected " + std::to_string(V.rows()) +
                       " x " + std::to_string(bones.size()));
  }
  if (!(options.theta_deg >= 0.0 && options.theta_deg <= 90.0)) {
    throw InvalidInput("segment_mesh: theta must be in [0, 90] degrees, got " +
                       std::to_string(options.theta_deg));
  }
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const auto p = bones[b].parent;
    if (p < -1 || p >= static_cast<std::int32_t>(bones.size()) || p == static_cast<std::int32_t>(b)) {
      throw InvalidInput("segment_mesh: bone " + std::to_string(b) + " has parent " +
                         std::to_string(p) + " out of range");
    }
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      if (F(f, c) < 0 || F(f, c) >= V.rows()) {
        throw InvalidInput("segment_mesh: triangle " + std::to_string(f) + " has vertex index " +
                           std::to_string(F(f, c)) + " out of range");
      }
    }
  }

  const auto start = std::chrono::steady_clock::now();
  const double theta = options.theta_deg * std::numbers::pi / 180.0;
  const auto nb = static_cast<std::int32_t>(bones.size());
  Segmentation out;
  out.options = options;
  auto& stats = out.stats;
  stats.triangles = F.rows();
  stats.welded_vertices = V.rows();
  stats.vertices = V.rows();
  stats.bones = nb;

  const auto graph = topology != nullptr && &topology->welded_triangles == &F
                         ? face_graph(*topology)
                         : face_graph(F);
  const auto subtree = subtrees(bones);

  // 1. Each triangle to the bone of its largest summed weight (§4.1).
  std::vector<std::int32_t> labels = largest_weight_bones(W, F);

  // 2. Observers of those per-bone clusters (§4.2), then refinement against them (§4.1). Each
  // triangle's positive counts under its bone's test poses are kept: step 4 observes most
  // triangles from the same bone again (refinement moves few), and the counts do not depend on
  // the cluster (positive_counts).
  std::vector<PositiveCounts> counts(static_cast<std::size_t>(F.rows()));
  std::vector<std::int32_t> counted_bone(static_cast<std::size_t>(F.rows()), -1);
  if (options.refine) {
    std::vector<std::vector<std::int32_t>> per_bone(static_cast<std::size_t>(nb));
    for (std::int32_t f = 0; f < F.rows(); ++f) {
      per_bone[static_cast<std::size_t>(labels[static_cast<std::size_t>(f)])].push_back(f);
    }
    std::vector<Observer> observers(static_cast<std::size_t>(nb));
    for_each_index(
        observers.size(), static_cast<std::size_t>(F.rows()), options.parallel, [&](std::size_t b) {
          const auto& tris = per_bone[b];
          observers[b].segment = bones[b];
          if (tris.empty()) return;
          // The bones' clusters are disjoint: each writes its own triangles' counts.
          std::vector<PositiveCounts> mine(tris.size());
          positive_counts(V, F, tris, bones[b], W, subtree[b], theta, mine);
          std::int64_t point = 0;
          std::int64_t line = 0;
          for (std::size_t i = 0; i < tris.size(); ++i) {
            const auto f = static_cast<std::size_t>(tris[i]);
            counts[f] = mine[i];
            counted_bone[f] = static_cast<std::int32_t>(b);
            point += mine[i].point;
            line += mine[i].line;
          }
          observers[b].kind = observer_choice(point, line).kind;
        });
    stats.refinement = refine_labels(V, F, graph, observers, W, labels);
  }

  // 3. Edge-connected pieces become the atomic clusters.
  const auto split = split_connected(graph, labels);
  out.triangle_cluster = split.triangle_cluster;
  out.clusters.resize(split.cluster_label.size());
  for (std::size_t c = 0; c < split.cluster_label.size(); ++c) {
    out.clusters[c].bone = split.cluster_label[c];
  }
  for (std::int32_t f = 0; f < F.rows(); ++f) {
    out.clusters[static_cast<std::size_t>(out.triangle_cluster[static_cast<std::size_t>(f)])]
        .triangles.push_back(f);
  }

  // 4. The final observer of each atomic cluster, and the rest-pose orientation counts.
  for_each_index(
      out.clusters.size(),
      static_cast<std::size_t>(F.rows()),
      options.parallel,
      [&](std::size_t c) {
        auto& cluster = out.clusters[c];
        const auto b = static_cast<std::size_t>(cluster.bone);
        // Counts from step 2 where the triangle was observed from this bone; the others now (the
        // clusters are disjoint: each fills its own triangles).
        std::vector<std::int32_t> missing;
        for (const auto f : cluster.triangles) {
          if (counted_bone[static_cast<std::size_t>(f)] != cluster.bone) missing.push_back(f);
        }
        if (!missing.empty()) {
          std::vector<PositiveCounts> fresh(missing.size());
          positive_counts(V, F, missing, bones[b], W, subtree[b], theta, fresh);
          for (std::size_t i = 0; i < missing.size(); ++i) {
            counts[static_cast<std::size_t>(missing[i])] = fresh[i];
          }
        }
        std::int64_t point = 0;
        std::int64_t line = 0;
        for (const auto f : cluster.triangles) {
          point += counts[static_cast<std::size_t>(f)].point;
          line += counts[static_cast<std::size_t>(f)].line;
        }
        const auto choice = observer_choice(point, line);
        cluster.observer = Observer{choice.kind, bones[b]};
        cluster.mean_positive_point = choice.mean_positive_point;
        cluster.mean_positive_line = choice.mean_positive_line;
      });
  std::vector<char> bone_used(static_cast<std::size_t>(nb), 0);
  for (auto& cluster : out.clusters) {
    bone_used[static_cast<std::size_t>(cluster.bone)] = 1;
    (cluster.observer.kind == ObserverKind::point ? stats.point_observers : stats.line_observers)++;
    for (const auto f : cluster.triangles) {
      const auto o = orientation(cluster.observer, V, F, f);
      stats.h_minus += o == Orientation::negative;
      stats.h_uncertain += o == Orientation::uncertain;
    }
  }
  stats.atomic_clusters = static_cast<std::int32_t>(out.clusters.size());
  std::int32_t bones_with_cluster = 0;
  for (std::int32_t b = 0; b < nb; ++b) {
    if (bone_used[static_cast<std::size_t>(b)]) {
      ++bones_with_cluster;
    } else {
      stats.bones_without_cluster.push_back(b);
    }
  }
  stats.split_clusters = stats.atomic_clusters - bones_with_cluster;

  // 5. The cluster graph.
  std::vector<std::int32_t> cluster_bone;
  for (const auto& c : out.clusters) cluster_bone.push_back(c.bone);
  out.graph = cluster_graph(graph, out.triangle_cluster, cluster_bone, bones);

  stats.decomposition_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace skelcd::segmentation
