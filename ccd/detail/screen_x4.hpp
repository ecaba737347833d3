#pragma once
// The screens of ccd/coplanarity_screen.hpp compiled for the baseline instruction set alone: what
// vertex_face_screen_x4 and edge_edge_screen_x4 run on a CPU without AVX2 (declared for the tests,
// which hold both builds to the kernels' scalar screen on any machine); and one lane of the
// screens as the kernels' own screen, for the stages after it.

#include <cstddef>

#include "ccd/coplanarity_screen.hpp"
#include "ccd/detail/trilinear_cubic.hpp"

namespace skelcd::ccd::detail {

/// Lane `lane` of `screens` as trilinear_screen's result: its coefficients and magnitude (what the
/// stages after the screen read; its error bound is not kept).
[[nodiscard]] inline TrilinearScreen lane_screen(const CoplanarityScreens& screens, int lane) {
  const auto k = static_cast<std::size_t>(lane);
  TrilinearScreen screen;
  screen.coefficients = screens.coefficients[k];
  screen.magnitude = screens.magnitude[k];
  return screen;
}

[[nodiscard]] CoplanarityScreens vertex_face_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

[[nodiscard]] CoplanarityScreens point_faces_screen_x4_baseline(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1);
[[nodiscard]] CoplanarityScreens edge_edge_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

}  // namespace skelcd::ccd::detail
