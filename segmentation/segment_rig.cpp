// segment(rig): weld the rig's mesh, get its weights (heat or the file's), segment the welded mesh.
// (Separate from segmentation.cpp so the core links without the importer side of skinning/.)

#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>

#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {

namespace {

// The rig's own weights on the welded vertices: the mean of the rows of the file vertices that
// weld together (seams normally carry equal weights). A welded vertex without any weight — a
// vertex the file attaches to no bone — takes its nearest bone, and is counted.
Eigen::MatrixXd welded_rig_weights(const skinning::Rig& rig, const skinning::Topology& topology,
                                   const skinning::Positions& welded,
                                   const std::vector<BoneSegment>& bones,
                                   std::int64_t& unweighted) {
  const auto nw = topology.num_welded_vertices();
  const auto nb = static_cast<Eigen::Index>(bones.size());
  if (rig.weights.rows() != rig.mesh.num_vertices() || rig.weights.cols() != nb) {
    throw InvalidInput(rig.source + ": the rig's weights are " + std::to_string(rig.weights.rows()) +
                       " x " + std::to_string(rig.weights.cols()) + ", expected " +
                       std::to_string(rig.mesh.num_vertices()) + " x " + std::to_string(nb) +
                       " (use heat weights for a mesh without skin weights)");
  }
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(nw, nb);
  for (Eigen::Index v = 0; v < rig.weights.outerSize(); ++v) {
    const auto w = topology.welded_of_vertex[static_cast<std::size_t>(v)];
    for (skinning::SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
      W(w, it.col()) += it.value();
    }
  }
  unweighted = 0;
  for (Eigen::Index w = 0; w < nw; ++w) {
    const double sum = W.row(w).sum();
    if (sum > 0.0) {
      W.row(w) /= sum;
      continue;
    }
    ++unweighted;
    const Eigen::Vector3d x = welded.row(w).transpose();
    Eigen::Index best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (Eigen::Index b = 0; b < nb; ++b) {
      const double d = (bones[static_cast<std::size_t>(b)].closest_point(x) - x).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = b;
      }
    }
    W(w, best) = 1.0;
  }
  return W;
}

/// The refusals that come before the mesh is welded.
void require_segmentable(const skinning::Rig& rig) {
  if (rig.skeleton.bones.empty()) {
    throw InvalidInput(rig.source + ": cannot segment: the skeleton has no bones");
  }
  if (rig.mesh.num_triangles() == 0) {
    throw InvalidInput(rig.source + ": cannot segment: the mesh has no triangles");
  }
}

}  // namespace

Segmentation segment(const skinning::Rig& rig, const SegmentationOptions& options) {
  require_segmentable(rig);
  return segment(rig, options, skinning::build_topology(rig.mesh));
}

Segmentation segment(
    const skinning::Rig& rig,
    const SegmentationOptions& options,
    const skinning::Topology& topology) {
  require_segmentable(rig);
  if (topology.welded_of_vertex.size() != static_cast<std::size_t>(rig.mesh.num_vertices()) ||
      topology.welded_triangles.rows() != rig.mesh.num_triangles()) {
    throw std::invalid_argument("segment: the topology is not the rig mesh's");
  }
  skinning::Positions welded;
  skinning::gather_welded(topology, rig.mesh.rest_positions, welded);
  const auto bones = bone_segments(rig.skeleton);

  const auto start = std::chrono::steady_clock::now();
  Eigen::MatrixXd W;
  HeatWeightsStats heat_stats;
  std::int64_t unweighted = 0;
  try {
    if (options.weights == WeightSource::heat) {
      HeatWeightsSolver solver(welded, topology.welded_triangles, bones, options.heat);
      auto heat = solver.solve_all();
      W = std::move(heat.weights);
      heat_stats = heat.stats;
    } else {
      W = welded_rig_weights(rig, topology, welded, bones, unweighted);
    }
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    if (what.rfind(rig.source, 0) == 0) throw;
    throw InvalidInput(rig.source + ": " + what);
  }
  const double weights_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  Segmentation out;
  try {
    out = segment_mesh(welded, topology.welded_triangles, bones, W, options, &topology);
  } catch (const InvalidInput& e) {
    throw InvalidInput(rig.source + ": " + e.what());
  }
  out.stats.vertices = rig.mesh.num_vertices();
  out.stats.heat = heat_stats;
  out.stats.weights_s = weights_s;
  out.stats.unweighted_vertices = unweighted;
  return out;
}

}  // namespace skelcd::segmentation
