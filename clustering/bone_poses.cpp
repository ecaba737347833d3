#include "clustering/bone_poses.hpp"

#include <utility>

#include "skinning/errors.hpp"

namespace skelcd::clustering {

PoseAtSample pose_at_sample(const skinning::RigMotion& motion) {
  return [&motion, pose = skinning::Pose{}](
             std::int32_t sample, std::vector<skinning::BoneTransform>& out) mutable {
    if (motion.clip() >= 0) {
      motion.evaluator().clip_pose(motion.clip(), motion.sample_time(sample), pose);
    } else {
      motion.evaluator().bind_pose(pose);
    }
    out.assign(pose.transforms.begin(), pose.transforms.end());
  };
}

BonePoses::BonePoses(PoseAtSample source) : source_(std::move(source)) {}

void BonePoses::select_samples(std::int32_t s0, std::int32_t s1) {
  if (!source_) {
    throw InvalidInput("clustering::BonePoses::select_samples: no pose source (use set())");
  }
  if (ready_ && s0 == sample_t0_ && s1 == sample_t1_) return;
  // The common case: this interval starts where the previous one ended.
  if (ready_ && s0 == sample_t1_) {
    std::swap(t0_, t1_);
  } else if (!(ready_ && s0 == sample_t0_)) {
    source_(s0, t0_);
  }
  if (s1 == s0) {
    t1_ = t0_;
  } else {
    source_(s1, t1_);
  }
  sample_t0_ = s0;
  sample_t1_ = s1;
  ready_ = true;
}

void BonePoses::set(
    std::span<const skinning::BoneTransform> t0,
    std::span<const skinning::BoneTransform> t1) {
  t0_.assign(t0.begin(), t0.end());
  t1_.assign(t1.begin(), t1.end());
  sample_t0_ = -1;
  sample_t1_ = -1;
  ready_ = true;
}

}  // namespace skelcd::clustering
