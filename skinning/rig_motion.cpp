#include "skinning/rig_motion.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::skinning {
namespace {

// A product duration × rate this close (relative) to an integer is that many intervals: durations
// read in float32 (glTF seconds, Collada and FBX ticks) are off by up to 6e-8 relative, so 24 Hz
// times a 3.4166667 s clip is 82.000002, 82 intervals, not 83 with a last one of 1e-7 s.
constexpr double kWholeIntervalTolerance = 1e-6;

const Rig& checked(const std::shared_ptr<const Rig>& rig) {
  if (!rig) throw InvalidInput("RigMotion: no rig");
  return *rig;
}

}  // namespace

int sample_count(double duration_s, double rate_hz) {
  assert(duration_s >= 0 && rate_hz > 0);
  const double intervals = duration_s * rate_hz;
  const double nearest = std::round(intervals);
  const double whole =
      std::abs(intervals - nearest) <= kWholeIntervalTolerance * std::max(1.0, nearest) ? nearest : std::ceil(intervals);
  if (whole >= static_cast<double>(std::numeric_limits<int>::max() - 1)) {
    throw InvalidInput("sample_count: " + std::to_string(duration_s) + " s at " + std::to_string(rate_hz) +
                       " Hz is too many samples");
  }
  return static_cast<int>(whole) + 1;
}

RigMotion::RigMotion(std::shared_ptr<const Rig> rig, const RigMotionOptions& options)
    : rig_(std::move(rig)), evaluator_(checked(rig_)), skinning_(*rig_), clip_(options.clip) {
  if (clip_ < -1 || clip_ >= static_cast<std::int32_t>(rig_->clips.size())) {
    throw InvalidInput(rig_->source + ": clip " + std::to_string(clip_) + " out of range (the file has " +
                       std::to_string(rig_->clips.size()) + " clips)");
  }
  if (!std::isfinite(options.rate_hz) || options.rate_hz < 0) {
    throw InvalidInput(rig_->source + ": sample rate " + std::to_string(options.rate_hz) + " Hz is not positive");
  }
  if (clip_ >= 0) {
    const auto& c = rig_->clips[static_cast<std::size_t>(clip_)];
    duration_s_ = c.duration_s;
    rate_hz_ = options.rate_hz > 0 ? options.rate_hz : c.sample_rate_hz();
    num_samples_ = sample_count(duration_s_, rate_hz_);
  } else {
    rate_hz_ = options.rate_hz > 0 ? options.rate_hz : kDefaultSampleRateHz;
    num_samples_ = 1;
  }
}

double RigMotion::sample_time(int i) const {
  assert(i >= 0 && i < num_samples_);
  if (i == num_samples_ - 1) return duration_s_;  // the last sample is the clip's end
  return std::min(static_cast<double>(i) / rate_hz_, duration_s_);
}

std::string RigMotion::name() const {
  return clip_ >= 0 ? rig_->clips[static_cast<std::size_t>(clip_)].name : std::string("bind pose");
}

void RigMotion::positions(int i, Positions& out) const {
  assert(i >= 0 && i < num_samples_);
  positions_at_time(sample_time(i), out);
}

void RigMotion::positions_of(int i, std::span<const std::int32_t> vertices, Positions& out) const {
  assert(i >= 0 && i < num_samples_);
  skinning_.apply_rows(pose_at(sample_time(i)), vertices, out);
}

std::int32_t RigMotion::num_bones() const { return rig_->skeleton.num_bones(); }

void RigMotion::bone_transforms(int i, std::vector<BoneTransform>& out) const {
  assert(i >= 0 && i < num_samples_);
  const Pose& pose = pose_at(sample_time(i));
  out.assign(pose.transforms.begin(), pose.transforms.end());
}

void RigMotion::positions_at_time(double time_s, Positions& out) const {
  skinning_.apply(pose_at(time_s), out);
}

const Pose& RigMotion::pose_at(double time_s) const {
  // One pose buffer per thread, grown to the largest skeleton seen and then reused.
  thread_local Pose pose;
  if (clip_ >= 0) {
    evaluator_.clip_pose(clip_, time_s, pose);
  } else {
    evaluator_.bind_pose(pose);
  }
  return pose;
}

}  // namespace skelcd::skinning
