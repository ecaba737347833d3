#pragma once
// `rvbc` and `dynamic` as registered methods (culling/method_registry.hpp): they need the mesh's
// segmentation (MethodOptions::segmentation) and the bone transforms of every interval (carried
// by culling::Interval), and carry from one query to the next which components were free of
// self-intersection. `dynamic` is `auto`'s choice for closed components when both are there.
// Registered from radial_view_methods.cpp at start-up; nothing outside this module names them.

#include <memory>
#include <string_view>

#include "clustering/bone_poses.hpp"
#include "culling/method.hpp"

namespace skelcd::clustering {

/// True for "rvbc" and "dynamic".
[[nodiscard]] bool is_radial_view_method(std::string_view name);

/// Builds `rvbc` or `dynamic` (what the registry's factory does). With options.segmentation: the
/// full method, posing its observers with each interval's bone transforms — or, for a driver that
/// selects them itself before each query (tests, benchmarks), with `poses`. Without a segmentation
/// (a run that asks for DCD only): a method that answers DCD as `bvh` does and refuses CCD.
/// @throws InvalidInput for another name, γ outside [0, 1], options make_method refuses, or a
///   segmentation that does not fit the mesh.
[[nodiscard]] std::unique_ptr<culling::CullingMethod> make_radial_view_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const culling::MethodOptions& options,
    std::shared_ptr<const BonePoses> poses = nullptr);

}  // namespace skelcd::clustering
