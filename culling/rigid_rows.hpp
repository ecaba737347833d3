#pragma once
// Triangles that linear blend skinning moves by one matrix (docs/culling.md, "Rigid rows"). Two
// triangles whose six corners have the same weight row get the same blended matrix M_s at every
// sample, so over an interval their corners move by one affine map of their rest positions,
// A(t) = (1 − t) M_s + t M_s+1, up to the rounding of the two posed ends. Where A(t)'s linear
// part is nonsingular an affine map keeps incidence: such a pair touches during the interval only
// if it touches at rest. A method that takes rigid rows skips, in its traversal, every pair of two
// triangles of one certified row, and tests instead the few pairs of the row that lie within the
// rest tolerance at rest (rest_pairs): its contacts are those of the same method without them.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

struct RigidRows {
  /// #F (welded triangles, Topology order): the weight row of all three corners, or -1 when the
  /// corners' rows differ, the triangle repeats a welded vertex, or no other triangle has its row.
  std::vector<std::int32_t> triangle_row;
  /// Triangles with a row (triangle_row ≥ 0).
  std::int64_t triangles_in_rows = 0;
  /// Each row's influences as linear blend skinning blends them: (transform index, weight), in
  /// the weights' stored order; every row has two triangles or more.
  std::vector<std::vector<std::pair<std::int32_t, double>>> rows;
  /// Pairs (a < b) of triangles of one row with a vertex-face or edge-edge pair that shares no
  /// vertex and lies within rest_tolerance at rest (conservatively: the CCD kernel's conservative
  /// test of the held rest pose with that contact distance, asked about every feature pair that
  /// neither its boxes nor a separating direction show to lie more than that apart), except
  /// pairs of excluded parts (Mesh::excluded_part_pairs), which are never tested. Tested whenever
  /// their row is skipped.
  std::vector<TrianglePair> rest_pairs;
  /// Rest distance below which a row's pairs are kept in rest_pairs: 1e-6 of rest_extent.
  double rest_tolerance = 0.0;
  /// The largest rest coordinate (absolute) of a welded vertex, at least 1e-300.
  double rest_extent = 0.0;
  /// Transforms a sample carries (Motion::bone_transforms: bones, then part attachments).
  std::int32_t num_transforms = 0;

  [[nodiscard]] std::int32_t num_rows() const { return static_cast<std::int32_t>(rows.size()); }
};

/// The rigid rows of `mesh` moved by `weights` (#V × num_transforms, the weights
/// skinning::linear_blend_skinning applies to mesh.rest_positions), welded by `topology`: a welded
/// vertex moves as its representative file vertex. When fewer than `min_share` of the triangles
/// would have a row, none is kept (no rest pair is sought): too few pairs to pay for the rows'
/// certificates and the walk's checks.
/// @throws InvalidInput naming "culling::rigid_rows" when the sizes disagree or a weight or rest
///         coordinate is not finite.
[[nodiscard]] RigidRows build_rigid_rows(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const skinning::SkinWeights& weights,
    std::int32_t num_transforms,
    double min_share = 0.0);

/// Certifies each row for the interval between two samples with transforms `t0` and `t1`
/// (Motion::bone_transforms; a row is certified when every corner pair of its triangles that
/// lies more than rest_tolerance apart at rest stays more than `min_separation` apart over the
/// whole interval, posed rounding included): certified[r] = 1 or 0. All 0 when the transforms are
/// missing or do not cover the rows.
/// The bound: with L_s the linear part of row r's blended matrix at sample s, B = L_0⁻¹ L_1 and
/// β = ‖B − I‖₂ < 0.9, σ_min((1 − t) L_0 + t L_1) ≥ (1 − β) / ‖L_0⁻¹‖_F for t in [0, 1]; each
/// posed corner lies within E of its exact image (E from the blend's size, the rest extent and
/// the unit roundoff); certified when min_separation + 2E < that bound × rest_tolerance.
void certify_rigid_rows(
    const RigidRows& rows,
    std::span<const skinning::BoneTransform> t0,
    std::span<const skinning::BoneTransform> t1,
    double min_separation,
    std::vector<std::uint8_t>& certified);

}  // namespace skelcd::culling
