#pragma once
// Hand-built rigs whose poses can be worked out on paper.

#include "skinning/rig.hpp"

namespace skelcd::skinning::test {

/// Two bones in a chain along x: bone 0 at the origin (node 0, root), bone 1 at (1, 0, 0)
/// (node 1, child of node 0). Vertices:
///   0 (0, 0, 0)      weight 1 on bone 0
///   1 (2, 0, 0)      weight 1 on bone 1
///   2 (1.5, 0.5, 0)  weights 0.5 / 0.5
///   3 (0.5, 0.5, 0)  weight 1 on bone 0
/// Triangles (0 1 2) and (0 2 3). One clip "bend", 1 s: node 1 rotates about +z from 0° (t = 0)
/// to 90° (t = 1); keys at 0 and 1 s.
[[nodiscard]] Rig two_bone_rig();

}  // namespace skelcd::skinning::test
