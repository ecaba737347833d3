#pragma once
// Per-vertex bounding volumes for one interval (CCD, swept) or one instant (DCD, static): what
// every refit starts from. Edge and triangle volumes are unions of these (FeatureBounds), so a
// triangle's volume contains its features' volumes bit for bit — the property the feature
// de-duplication relies on (docs/culling.md).

#include <vector>

#include "culling/dop.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// Swept volumes: out[w] contains the segment from x_t0.row(w) to x_t1.row(w) (exactly, on every
/// axis), grown by `half_width` per Dop::inflate.
/// @param x_t0,x_t1 #W × 3 positions at the interval's ends.
/// @param half_width half the contact distance (min_separation / 2), >= 0.
/// @param out resized to #W (allocates only when it grows).
template <int N>
void swept_vertex_bounds(
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<Dop<N>>& out);

/// Static volumes: out[w] contains the point x.row(w).
/// @param x #W × 3 positions.  @param out resized to #W.
template <int N>
void static_vertex_bounds(const skinning::Positions& x, std::vector<Dop<N>>& out);

}  // namespace skelcd::culling
