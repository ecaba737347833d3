// The rig-level entry point of the heat weights: weld, solve, map back to file vertices.
// (Separate from heat_weights.cpp so the solver links without the importer side of skinning/.)

#include <string>

#include "segmentation/heat_weights.hpp"
#include "skinning/errors.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {

HeatWeights heat_weights(const skinning::Rig& rig, const HeatWeightsOptions& options) {
  const auto& mesh = rig.mesh;
  if (rig.skeleton.bones.empty()) {
    throw InvalidInput(rig.source + ": heat weights need bones, and the skeleton has none");
  }
  if (mesh.num_triangles() == 0) {
    throw InvalidInput(rig.source + ": heat weights need triangles, and the mesh has none");
  }
  const auto topology = skinning::build_topology(mesh);
  skinning::Positions welded;
  skinning::gather_welded(topology, mesh.rest_positions, welded);
  HeatWeights out;
  try {
    HeatWeightsSolver solver(welded, topology.welded_triangles, bone_segments(rig.skeleton),
                             options);
    out = solver.solve_all();
  } catch (const InvalidInput& e) {
    throw InvalidInput(rig.source + ": " + e.what());
  }
  Eigen::MatrixXd per_vertex(mesh.num_vertices(), out.weights.cols());
  for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
    per_vertex.row(v) = out.weights.row(topology.welded_of_vertex[static_cast<std::size_t>(v)]);
  }
  out.weights = std::move(per_vertex);
  out.stats.vertices = mesh.num_vertices();
  return out;
}

}  // namespace skelcd::segmentation
