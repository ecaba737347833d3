#pragma once
// Small meshes with known topology, built in code for the skinning tests.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::skinning::test {

/// A mesh of one part from positions and triangles.
[[nodiscard]] Mesh make_mesh(
    const std::vector<Eigen::Vector3d>& positions,
    const std::vector<std::array<std::int32_t, 3>>& triangles,
    const std::string& name = "part");

/// Appends `b` to `a` as a new part (vertices not shared).
void append_part(Mesh& a, const Mesh& b);

/// Unit cube [0,1]^3 with 8 shared vertices and 12 outward triangles.
[[nodiscard]] Mesh shared_cube();
/// The same cube with 4 vertices per face (24 vertices): every edge is a seam.
[[nodiscard]] Mesh seamed_cube();
/// An n × m grid of quads (2 triangles each) in the z = 0 plane, (n+1)(m+1) vertices.
[[nodiscard]] Mesh sheet(int n, int m);

}  // namespace skelcd::skinning::test
