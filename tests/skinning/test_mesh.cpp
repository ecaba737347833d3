#include "skinning/mesh.hpp"

#include <limits>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

Mesh one_triangle() {
  Mesh m;
  m.rest_positions.resize(3, 3);
  m.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.triangles.resize(1, 3);
  m.triangles << 0, 1, 2;
  m.face_part = {0};
  m.face_index_in_part = {0};
  m.vertex_part = {0, 0, 0};
  m.vertex_index_in_part = {0, 1, 2};
  m.part_names = {"tri"};
  return m;
}

TEST(ValidateMesh, AcceptsAWellFormedMesh) { EXPECT_NO_THROW(validate_mesh(one_triangle(), "t")); }

TEST(ValidateMesh, RefusesNaNNamingTheVertex) {
  auto m = one_triangle();
  m.rest_positions(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW_MESSAGE(validate_mesh(m, "file.obj"), InvalidInput, "file.obj: vertex 1");
}

TEST(ValidateMesh, RefusesIndexOutOfRange) {
  auto m = one_triangle();
  m.triangles(0, 2) = 3;
  EXPECT_THROW_MESSAGE(validate_mesh(m, "file.obj"), InvalidInput, "out of range");
}

}  // namespace
}  // namespace skelcd::skinning
