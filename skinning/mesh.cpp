#include "skinning/mesh.hpp"

#include <cmath>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::skinning {

void validate_mesh(const Mesh& mesh, const std::string& source) {
  const auto nv = mesh.num_vertices();
  const auto nf = mesh.num_triangles();
  for (Eigen::Index v = 0; v < nv; ++v) {
    if (!mesh.rest_positions.row(v).allFinite()) {
      throw InvalidInput(source + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto i = mesh.triangles(f, k);
      if (i < 0 || i >= nv) {
        throw InvalidInput(source + ": triangle " + std::to_string(f) + " has vertex index " +
                           std::to_string(i) + " out of range [0, " + std::to_string(nv) + ")");
      }
    }
  }
  const auto check_size = [&](std::size_t size, std::int64_t expected, const char* what) {
    if (static_cast<std::int64_t>(size) != expected) {
      throw InvalidInput(source + ": " + what + " has " + std::to_string(size) + " entries, expected " +
                         std::to_string(expected));
    }
  };
  check_size(mesh.face_part.size(), nf, "face_part");
  check_size(mesh.face_index_in_part.size(), nf, "face_index_in_part");
  check_size(mesh.vertex_part.size(), nv, "vertex_part");
  check_size(mesh.vertex_index_in_part.size(), nv, "vertex_index_in_part");
  for (std::size_t f = 0; f < mesh.face_part.size(); ++f) {
    if (mesh.face_part[f] < 0 || mesh.face_part[f] >= mesh.num_parts()) {
      throw InvalidInput(source + ": triangle " + std::to_string(f) + " has part " +
                         std::to_string(mesh.face_part[f]) + " out of range");
    }
  }
}

}  // namespace skelcd::skinning
