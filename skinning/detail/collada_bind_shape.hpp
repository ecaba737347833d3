#pragma once
// Internal to skinning/: the Collada <bind_shape_matrix> of each skin, which Debian's assimp 5.2
// reads but never applies (its skinned vertices stay in the geometry's own frame).

#include <Eigen/Geometry>
#include <filesystem>
#include <map>
#include <string>

namespace skelcd::skinning::detail {

/// For a Collada file: the bind shape matrix of every <controller><skin source="#GEOMETRY">,
/// keyed by the geometry's id and, when it has one, its name (assimp names meshes by one of the
/// two). Empty for any other file, or when the file has no skin with a non-identity matrix.
/// The matrix maps the geometry's vertices into the space the skin's inverse bind matrices
/// expect (COLLADA 1.4.1, skin/bind_shape_matrix: "provides extra information about the position
/// and orientation of the base mesh before binding").
/// @throws InvalidInput naming the file and controller for a matrix that is not 16 finite numbers.
[[nodiscard]] std::map<std::string, Eigen::Affine3d> collada_bind_shape_matrices(
    const std::filesystem::path& file);

}  // namespace skelcd::skinning::detail
