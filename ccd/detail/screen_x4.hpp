#pragma once
// The screens of ccd/coplanarity_screen.hpp compiled for the baseline instruction set alone: what
// vertex_face_screen_x4 and edge_edge_screen_x4 run on a CPU without AVX2. Declared for the tests,
// which hold both builds to the kernels' scalar screen on any machine.

#include "ccd/coplanarity_screen.hpp"

namespace skelcd::ccd::detail {

[[nodiscard]] CoplanarityScreens vertex_face_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

[[nodiscard]] CoplanarityScreens edge_edge_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

}  // namespace skelcd::ccd::detail
