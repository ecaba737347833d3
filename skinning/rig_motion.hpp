#pragma once
// RigMotion: a rig's clip sampled at a fixed rate, skinned — the Motion of rigged characters.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "skinning/lbs.hpp"
#include "skinning/motion.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"

namespace skelcd::skinning {

struct RigMotionOptions {
  /// Index into Rig::clips, or -1 for the bind pose alone (one sample at t = 0).
  std::int32_t clip = -1;
  /// Samples per second; 0 picks the clip's frame rate (Clip::sample_rate_hz: the frame rate
  /// when known, else kDefaultSampleRateHz), and kDefaultSampleRateHz for the bind pose.
  double rate_hz = 0.0;
};

/// Number of samples covering [0, duration_s] at `rate_hz`, both ends included: the intervals
/// are 1/rate long except possibly the last, which ends exactly at duration_s. A product
/// duration × rate within relative 1e-6 of an integer counts as that integer (key times and
/// durations come from files in float32 or as ticks / ticks-per-second: a float32 duration is
/// off by up to 6e-8 relative, which must not add a last interval of a fraction of a microsecond).
/// @pre duration_s >= 0, rate_hz > 0
[[nodiscard]] int sample_count(double duration_s, double rate_hz);

class RigMotion final : public Motion {
 public:
  /// @throws InvalidInput when the rig is invalid, the clip index is out of range, or the rate
  /// is not positive and finite (0 means "default").
  explicit RigMotion(std::shared_ptr<const Rig> rig, const RigMotionOptions& options = {});

  [[nodiscard]] const Mesh& mesh() const override { return rig_->mesh; }
  [[nodiscard]] int num_samples() const override { return num_samples_; }
  /// i / rate; the last sample at the clip's duration exactly.
  [[nodiscard]] double sample_time(int i) const override;
  /// The clip's name, or "bind pose".
  [[nodiscard]] std::string name() const override;
  /// Skinned positions at sample i. Thread-safe: pose scratch is per thread and reused, so
  /// repeated calls allocate nothing once `out` has its size.
  void positions(int i, Positions& out) const override;

  /// Skinned positions of `vertices` only at sample i (LinearBlendSkinning::apply_rows).
  void positions_of(int i, std::span<const std::int32_t> vertices, Positions& out) const override;
  /// Skinned positions at any time in seconds (clamped to the clip's keys).
  void positions_at_time(double time_s, Positions& out) const;
  /// Any time: positions_at_time (the tolerance is not needed).
  [[nodiscard]] bool positions_at(double t, Positions& out, double /*tolerance_s*/) const override {
    positions_at_time(t, out);
    return true;
  }

  [[nodiscard]] const Rig& rig() const { return *rig_; }
  [[nodiscard]] std::int32_t clip() const { return clip_; }
  [[nodiscard]] double rate_hz() const override { return rate_hz_; }
  /// The rig's bones.
  [[nodiscard]] std::int32_t num_bones() const override;
  /// The pose's transforms at sample i: #B bones, then one per part attachment (Pose::transforms).
  void bone_transforms(int i, std::vector<BoneTransform>& out) const override;
  /// The skinning's weights (LinearBlendSkinning::weights): positions(i) blends them exactly.
  [[nodiscard]] const SkinWeights* skin_weights() const override { return &skinning_.weights(); }
  [[nodiscard]] double duration_s() const { return duration_s_; }
  [[nodiscard]] const PoseEvaluator& evaluator() const { return evaluator_; }
  [[nodiscard]] const LinearBlendSkinning& skinning() const { return skinning_; }

 private:
  /// The clip's pose at `time_s` (the bind pose without a clip), in this thread's buffer: valid
  /// until this thread's next call.
  [[nodiscard]] const Pose& pose_at(double time_s) const;

  std::shared_ptr<const Rig> rig_;
  PoseEvaluator evaluator_;
  LinearBlendSkinning skinning_;
  std::int32_t clip_ = -1;
  double rate_hz_ = kDefaultSampleRateHz;
  double duration_s_ = 0.0;
  int num_samples_ = 1;
};

}  // namespace skelcd::skinning
