#pragma once
// The bone transforms at the two ends of the interval being checked: what moves the observers
// (they ride their bones, paper 002 §3.2). A CullingMethod sees only vertex positions, so whoever
// drives the method (the runner) selects the samples here before each query; the radial-view
// methods read the transforms from it.

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "skinning/pose.hpp"
#include "skinning/rig_motion.hpp"

namespace skelcd::clustering {

/// Writes the bone transforms (Pose::transforms: #B bones first) of sample `sample` into `out`.
using PoseAtSample =
    std::function<void(std::int32_t sample, std::vector<skinning::BoneTransform>& out)>;

/// The PoseAtSample of a rig motion: the clip's pose at the sample's time (the bind pose when the
/// motion has no clip). `motion` must outlive the returned function.
[[nodiscard]] PoseAtSample pose_at_sample(const skinning::RigMotion& motion);

class BonePoses {
 public:
  /// Transforms only through set().
  BonePoses() = default;
  /// Transforms through select_samples(), evaluated by `source`.
  explicit BonePoses(PoseAtSample source);

  /// Makes the interval [s0, s1] current (s0 == s1 for an instant). Re-uses the last evaluated
  /// sample when an interval starts where the previous one ended.
  /// @throws InvalidInput when there is no source.
  void select_samples(std::int32_t s0, std::int32_t s1);

  /// Makes the given transforms current (tests, drivers without a rig motion).
  void set(
      std::span<const skinning::BoneTransform> t0,
      std::span<const skinning::BoneTransform> t1);

  /// True once set() or select_samples() has been called.
  [[nodiscard]] bool ready() const { return ready_; }
  [[nodiscard]] std::span<const skinning::BoneTransform> t0() const { return t0_; }
  [[nodiscard]] std::span<const skinning::BoneTransform> t1() const { return t1_; }
  /// Samples of the current interval (−1 after set()).
  [[nodiscard]] std::int32_t sample_t0() const { return sample_t0_; }
  [[nodiscard]] std::int32_t sample_t1() const { return sample_t1_; }

 private:
  PoseAtSample source_;
  std::vector<skinning::BoneTransform> t0_, t1_;
  std::int32_t sample_t0_ = -1;
  std::int32_t sample_t1_ = -1;
  bool ready_ = false;
};

}  // namespace skelcd::clustering
