#pragma once
// Internal to skinning/: what Debian's assimp 5.2 reads from a Collada file but does not hand
// over — the <bind_shape_matrix> of each skin, which it reads but never applies (its skinned
// vertices stay in the geometry's own frame), and the frame rate 3ds Max exporters write in an
// <extra>, which it ignores.

#include <Eigen/Geometry>
#include <filesystem>
#include <map>
#include <string>

namespace skelcd::skinning::detail {

struct ColladaExtras {
  /// The bind shape matrix of every <controller><skin source="#GEOMETRY">, keyed by the
  /// geometry's id and, when it has one, its name (assimp names meshes by one of the two); only
  /// non-identity matrices. The matrix maps the geometry's vertices into the space the skin's
  /// inverse bind matrices expect (COLLADA 1.4.1, skin/bind_shape_matrix: "provides extra
  /// information about the position and orientation of the base mesh before binding").
  std::map<std::string, Eigen::Affine3d> bind_shapes;
  /// Frames per second from <visual_scene><extra><technique profile="MAX3D"><frame_rate> (3ds
  /// Max's exporters: ColladaMax, OpenCOLLADA, Autodesk Collada) of the scene <scene> instances,
  /// else of the first visual scene that has one; 0 when there is none. COLLADA itself has no
  /// frame rate (its times are seconds).
  double frame_rate_hz = 0.0;
  /// The <frame_rate> as written when it is not a positive finite number (frame_rate_hz is then
  /// 0); empty otherwise (and for an empty <frame_rate/>).
  std::string bad_frame_rate;
};

/// The extras of a Collada file (`.dae`); empty for any other file, or a file pugixml cannot
/// parse (assimp then says what is wrong with it).
/// @throws InvalidInput naming the file and controller for a bind shape matrix that is not 16
///   finite numbers.
[[nodiscard]] ColladaExtras read_collada_extras(const std::filesystem::path& file);

}  // namespace skelcd::skinning::detail
