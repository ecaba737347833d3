// segment(rig): weld the rig's mesh, get its weights (heat or the file's), segment the welded mesh.
// (Separate from segmentation.cpp so the core links without the importer side of skinning/.)

#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

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
  // Summed and normalized a welded vertex (a row) at a time in a row-major buffer: a row's
  // weights are adjacent there, where a column-major matrix spreads them over nb pages. The
  // matrix is then written whole, before anything reads it. (Built as MatrixXd::Zero and summed
  // in place, the compiler turned the zeroing into calloc, whose fresh pages the first `+=` read
  // before writing them: each read-then-written page took a copy-on-write fault that interrupts
  // every core the process runs on, 277 pages on BCN_Epileptic, a third of the segmentation's
  // time while a parallel check computes its baseline on the other core.)
  const auto cols = static_cast<std::size_t>(nb);
  std::vector<double> rows(static_cast<std::size_t>(nw) * cols, 0.0);
  const auto row = [&](Eigen::Index w) { return rows.data() + static_cast<std::size_t>(w) * cols; };
  for (Eigen::Index v = 0; v < rig.weights.outerSize(); ++v) {
    double* const r = row(topology.welded_of_vertex[static_cast<std::size_t>(v)]);
    for (skinning::SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
      r[static_cast<std::size_t>(it.col())] += it.value();
    }
  }
  unweighted = 0;
  for (Eigen::Index w = 0; w < nw; ++w) {
    double* const r = row(w);
    double sum = 0.0;
    for (std::size_t b = 0; b < cols; ++b) sum += r[b];
    if (sum > 0.0) {
      for (std::size_t b = 0; b < cols; ++b) r[b] /= sum;
      continue;
    }
    ++unweighted;
    const Eigen::Vector3d x = welded.row(w).transpose();
    std::size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < cols; ++b) {
      const double d = (bones[b].closest_point(x) - x).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = b;
      }
    }
    r[best] = 1.0;
  }
  Eigen::MatrixXd W(nw, nb);
  W = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      rows.data(), nw, nb);
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
