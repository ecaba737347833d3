// RigMotion: sample counts and times, default rates, names, and positions at samples.

#include "skinning/rig_motion.hpp"

#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "tests/skinning/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

TEST(SampleCount, CoversTheClipWithBothEnds) {
  EXPECT_EQ(sample_count(0.0, 30.0), 1);
  EXPECT_EQ(sample_count(1.0, 30.0), 31);
  EXPECT_EQ(sample_count(3.3, 30.0), 100);    // 3.3 × 30 = 98.99999999999999 in doubles
  EXPECT_EQ(sample_count(2.0, 24.0), 49);
  EXPECT_EQ(sample_count(1.0, 2.5), 4);       // 0, 0.4, 0.8, then 1.0 (a shorter last interval)
  EXPECT_EQ(sample_count(0.7083333333333334, 24.0), 18);
}

TEST(RigMotion, DefaultRateIsTheKeyRateAndTimesEndAtTheDuration) {
  auto rig = test::two_bone_rig();
  rig.clips[0].duration_s = 1.0;
  rig.clips[0].channels[0].rotation_times = {0.0, 0.25, 0.5, 0.75, 1.0};
  rig.clips[0].channels[0].rotations.assign(5, Eigen::Quaterniond::Identity());
  rig.clips[0].key_times = {0.0, 0.25, 0.5, 0.75, 1.0};
  const RigMotion motion(std::make_shared<const Rig>(rig), RigMotionOptions{.clip = 0});
  EXPECT_DOUBLE_EQ(motion.rate_hz(), 4.0);
  EXPECT_EQ(motion.num_samples(), 5);
  EXPECT_DOUBLE_EQ(motion.sample_time(0), 0.0);
  EXPECT_DOUBLE_EQ(motion.sample_time(4), 1.0);
  EXPECT_EQ(motion.name(), "bend");
}

TEST(RigMotion, RateFallsBackToThirtyHertzAndCanBeChosen) {
  auto rig = test::two_bone_rig();
  rig.clips[0].channels[0].rotation_times = {0.0};
  rig.clips[0].channels[0].rotations = {Eigen::Quaterniond::Identity()};
  rig.clips[0].key_times = {0.0};  // one key: no key rate
  const auto shared = std::make_shared<const Rig>(rig);
  const RigMotion fallback(shared, RigMotionOptions{.clip = 0});
  EXPECT_EQ(fallback.rate_hz(), kDefaultSampleRateHz);
  EXPECT_EQ(fallback.num_samples(), 31);
  const RigMotion chosen(shared, RigMotionOptions{.clip = 0, .rate_hz = 2.5});
  EXPECT_EQ(chosen.num_samples(), 4);
  EXPECT_DOUBLE_EQ(chosen.sample_time(1), 0.4);
  EXPECT_DOUBLE_EQ(chosen.sample_time(3), 1.0);
}

TEST(RigMotion, BindPoseMotionHasOneSampleAtRest) {
  const auto rig = std::make_shared<const Rig>(test::two_bone_rig());
  const RigMotion motion(rig);
  EXPECT_EQ(motion.num_samples(), 1);
  EXPECT_EQ(motion.name(), "bind pose");
  Positions out;
  motion.positions(0, out);
  EXPECT_TRUE(skelcd::test::expect_matrix_near(out, rig->mesh.rest_positions, 1e-15));
}

TEST(RigMotion, PositionsAtSamplesFollowTheClip) {
  const auto rig = std::make_shared<const Rig>(test::two_bone_rig());
  const RigMotion motion(rig, RigMotionOptions{.clip = 0, .rate_hz = 2});
  ASSERT_EQ(motion.num_samples(), 3);
  Positions out;
  motion.positions(2, out);  // t = 1: 90°, vertex 1 at (1, 1, 0) (see PoseEvaluator tests)
  EXPECT_TRUE(skelcd::test::expect_matrix_near(out.row(1), Eigen::RowVector3d(1, 1, 0), 1e-15));
  EXPECT_EQ(&motion.mesh(), &rig->mesh);
}

TEST(RigMotion, RefusesBadClipAndRate) {
  const auto rig = std::make_shared<const Rig>(test::two_bone_rig());
  EXPECT_THROW_MESSAGE(RigMotion(rig, RigMotionOptions{.clip = 3}), InvalidInput, "clip 3 out of range");
  EXPECT_THROW_MESSAGE(RigMotion(rig, RigMotionOptions{.clip = 0, .rate_hz = -1}), InvalidInput, "not positive");
  EXPECT_THROW_MESSAGE(RigMotion(rig, RigMotionOptions{.clip = 0, .rate_hz = std::nan("")}), InvalidInput, "not positive");
}

}  // namespace
}  // namespace skelcd::skinning
