// The binding of ElementaryTests to the ccd/ kernels, alone in its file: tests that inject their
// own elementary tests do not need it.
#include "culling/elementary.hpp"

namespace skelcd::culling {

ElementaryTests with_ccd_defaults(ElementaryTests tests) {
  if (tests.vertex_face == nullptr) tests.vertex_face = &ccd::vertex_face_ccd;
  if (tests.edge_edge == nullptr) tests.edge_edge = &ccd::edge_edge_ccd;
  if (tests.triangles == nullptr) tests.triangles = &ccd::triangles_intersect;
  return tests;
}

}  // namespace skelcd::culling
