#pragma once
// The cotangent Laplacian of a triangle mesh (welded vertices), with lumped vertex areas, built to
// survive real assets: degenerate triangles, several components, non-manifold edges, unreferenced
// vertices.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "skinning/mesh.hpp"

namespace skelcd::segmentation {

/// The cotangent stiffness matrix L and the lumped mass M of a mesh; the area-normalised
/// Laplacian is Δ = M⁻¹ L.
struct CotangentLaplacian {
  /// #W × #W symmetric: L(i, j) = (cot α_ij + cot β_ij) / 2 summed over the triangles sharing
  /// edge ij (a non-manifold edge sums all of them), L(i, i) = −Σ_j L(i, j). Rows sum to 0 and
  /// −L is positive semi-definite (it is the Dirichlet energy of piecewise-linear functions).
  Eigen::SparseMatrix<double> stiffness;
  /// #W lumped (barycentric) area of each vertex: one third of the area of every non-degenerate
  /// triangle around it; 0 for a vertex that no non-degenerate triangle uses.
  Eigen::VectorXd mass;
  /// Triangles left out because they have (numerically) no area or a repeated vertex, ascending.
  std::vector<std::int32_t> degenerate_triangles;

  /// Δ = M⁻¹ L, #W × #W; a row whose vertex has zero mass is all zero. Rows sum to 0.
  [[nodiscard]] Eigen::SparseMatrix<double> area_normalised() const;
};

/// Builds the cotangent Laplacian of the mesh (V, F).
/// @param V #W × 3 vertex positions (welded: a seam must not split the mesh).
/// @param F #F × 3 vertex indices into V.
/// @note A triangle is degenerate when twice its area is below 16 ε times its longest squared edge
///   (ε = 2⁻⁵³), i.e. within the rounding error of the cross product that measures it: its
///   cotangents would be rounding noise. It contributes neither stiffness nor area.
/// @throws InvalidInput when an index in F is outside [0, #W) or a coordinate is not finite.
[[nodiscard]] CotangentLaplacian cotangent_laplacian(
    const skinning::Positions& V,
    const skinning::Triangles& F);

}  // namespace skelcd::segmentation
