#pragma once
// A rig, its clip, its segmentation and the methods to compare (`brute`, `bvh`, `rvbc`,
// `dynamic`), run interval by interval the way the runner does, with the bone poses selected
// before every query. Shared by the tests and the benchmark of clustering/.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "clustering/bone_poses.hpp"
#include "clustering/radial_view_method.hpp"
#include "clustering/radial_view_methods.hpp"
#include "culling/method.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"

namespace skelcd::test {

/// A loaded rig with its motion, welded topology and segmentation.
struct RadialViewScene {
  std::shared_ptr<const skinning::Rig> rig;
  std::unique_ptr<skinning::RigMotion> motion;
  skinning::Topology topology;
  std::shared_ptr<const segmentation::Segmentation> segmentation;
  std::shared_ptr<clustering::BonePoses> poses;

  /// @param clip index into rig->clips (−1: bind pose); @param weights rig (fast) or heat.
  RadialViewScene(
      std::shared_ptr<const skinning::Rig> rig_in,
      std::int32_t clip = 0,
      segmentation::WeightSource weights = segmentation::WeightSource::rig,
      double rate_hz = 0.0)
      : rig(std::move(rig_in)) {
    motion = std::make_unique<skinning::RigMotion>(
        rig, skinning::RigMotionOptions{.clip = clip, .rate_hz = rate_hz});
    topology = skinning::build_topology(rig->mesh);
    segmentation::SegmentationOptions options;
    options.weights = weights;
    segmentation = std::make_shared<const segmentation::Segmentation>(
        segmentation::segment(*rig, options));
    poses = std::make_shared<clustering::BonePoses>(clustering::pose_at_sample(*motion));
  }

  [[nodiscard]] culling::MethodOptions options(
      const culling::MethodParameters& parameters = {}, culling::MethodOptions base = {}) const {
    base.segmentation = segmentation;
    base.num_bones = rig->skeleton.num_bones();
    base.parameters = parameters;
    return base;
  }

  /// `rvbc`/`dynamic` pose their observers with the bone poses this fixture selects before each
  /// query; every other method comes from the registry.
  [[nodiscard]] std::unique_ptr<culling::CullingMethod> method(
      const std::string& name,
      const culling::MethodParameters& parameters = {},
      culling::MethodOptions base = {}) const {
    if (clustering::is_radial_view_method(name)) {
      return clustering::make_radial_view_method(
          name, rig->mesh, topology, options(parameters, base), poses);
    }
    return culling::make_method(name, rig->mesh, topology, options(parameters, base));
  }

  /// Welded positions of sample i.
  void welded(std::int32_t i, skinning::Positions& out) const {
    skinning::Positions posed;
    motion->positions(i, posed);
    skinning::gather_welded(topology, posed, out);
  }
};

/// A contact without its time of impact (what the methods must agree on).
struct ContactKey {
  std::int32_t interval;
  culling::CcdContact::Kind kind;
  std::int32_t a;
  std::int32_t b;
  friend auto operator<=>(const ContactKey&, const ContactKey&) = default;
};

struct ClipRun {
  std::vector<ContactKey> contacts;
  std::vector<culling::FrameResult> frames;  ///< one per interval
  std::vector<double> ccd_ms;                ///< wall time of each detect_ccd call
  /// Radial-view methods only: their stats per interval.
  std::vector<clustering::RadialViewStats> stats;
};

/// DCD queries made by run_clip besides the CCD ones (not recorded).
enum class DcdQueries : std::uint8_t {
  none,   ///< CCD only (`check --query ccd`)
  first,  ///< a DCD at the first sample, then CCD only
  every,  ///< a DCD at every interval's start sample (`check --query both`)
};

/// The bone transforms an interval carries: the fixture's BonePoses (the bones the observers
/// ride), or the motion's own (Motion::bone_transforms: the bones, then any part attachments —
/// what the runner gives every interval, and what rigid rows are certified from).
enum class Transforms : std::uint8_t { poses, motion };

/// `method`'s CCD of the interval from x0 (sample i) to x1 (sample i + 1), the bone poses of the
/// two samples selected first, into `out`.
inline void interval_ccd(
    RadialViewScene& scene,
    culling::CullingMethod& method,
    std::int32_t i,
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    culling::FrameResult& out,
    Transforms transforms = Transforms::poses) {
  scene.poses->select_samples(i, i + 1);
  const bool own = transforms == Transforms::motion;
  std::vector<skinning::BoneTransform> b0, b1;
  if (own) {
    scene.motion->bone_transforms(i, b0);
    scene.motion->bone_transforms(i + 1, b1);
  }
  method.detect_ccd(
      culling::Interval{
          .x_t0 = x0,
          .x_t1 = x1,
          .bones_t0 = own ? std::span<const skinning::BoneTransform>(b0) : scene.poses->t0(),
          .bones_t1 = own ? std::span<const skinning::BoneTransform>(b1) : scene.poses->t1(),
          .sample_t0 = i,
          .sample_t1 = i + 1},
      out);
}

/// Runs `method` over intervals [first, last) of the scene's motion.
inline ClipRun run_clip(
    RadialViewScene& scene,
    culling::CullingMethod& method,
    std::int32_t first,
    std::int32_t last,
    DcdQueries dcd = DcdQueries::none,
    Transforms transforms = Transforms::poses) {
  ClipRun run;
  skinning::Positions x0, x1;
  scene.welded(first, x1);
  for (std::int32_t i = first; i < last; ++i) {
    std::swap(x0, x1);
    scene.welded(i + 1, x1);
    culling::FrameResult out;
    if (dcd == DcdQueries::every || (dcd == DcdQueries::first && i == first)) {
      scene.poses->select_samples(i, i);
      method.detect_dcd(x0, out);
      out.clear();
    }
    const auto start = std::chrono::steady_clock::now();
    interval_ccd(scene, method, i, x0, x1, out, transforms);
    run.ccd_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    for (const auto& c : out.contacts) run.contacts.push_back({i, c.kind, c.a, c.b});
    if (const auto* rv = dynamic_cast<const clustering::RadialViewMethod*>(&method)) {
      run.stats.push_back(rv->last_stats());
    }
    run.frames.push_back(std::move(out));
  }
  std::sort(run.contacts.begin(), run.contacts.end());
  return run;
}

}  // namespace skelcd::test
