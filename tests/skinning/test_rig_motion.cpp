// RigMotion: sample counts and times, default rates, names, and positions at samples.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "skinning/errors.hpp"
#include "skinning/rig_motion.hpp"
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
  // Durations read in float32: 3.4166667 s (Fox's Survey) at 24 Hz is 82.000002 intervals.
  EXPECT_EQ(sample_count(static_cast<double>(3.41666667f), 24.0), 83);
  EXPECT_EQ(sample_count(static_cast<double>(3.8666667f), 30.0), 117);
  EXPECT_EQ(sample_count(1.0 + 2e-6, 30.0), 32);  // a real extra 2 µs is still an interval
}

TEST(RigMotion, DefaultRateIsTheFrameRateAndTimesEndAtTheDuration) {
  auto rig = test::two_bone_rig();
  rig.clips[0].duration_s = 1.0;
  rig.clips[0].channels[0].rotation_times = {0.0, 0.5, 1.0};
  rig.clips[0].channels[0].rotations.assign(3, Eigen::Quaterniond::Identity());
  rig.clips[0].key_times = {0.0, 0.5, 1.0};  // 2 keys/s: not what is sampled
  rig.clips[0].frame_rate_hz = 4.0;
  rig.clips[0].frame_rate_source = FrameRateSource::file;
  const RigMotion motion(std::make_shared<const Rig>(rig), RigMotionOptions{.clip = 0});
  EXPECT_DOUBLE_EQ(motion.rate_hz(), 4.0);
  EXPECT_EQ(motion.num_samples(), 5);
  EXPECT_DOUBLE_EQ(motion.sample_time(0), 0.0);
  EXPECT_DOUBLE_EQ(motion.sample_time(4), 1.0);
  EXPECT_EQ(motion.name(), "bend");
}

TEST(RigMotion, KeysDoNotSetTheRateOfAClipWithoutFrameRate) {
  // Near-duplicate key pairs (t and t + 5e-8 s, as some FBX exports have) made the key rate twice
  // the frame rate; sparse keys made it tiny. Without a frame rate the clip is sampled at 30 Hz.
  for (const std::vector<double>& keys :
       {std::vector<double>{0.0, 5e-8, 0.5, 0.5 + 5e-8, 1.0}, std::vector<double>{0.0, 1.0}}) {
    auto rig = test::two_bone_rig();
    rig.clips[0].duration_s = 1.0;
    rig.clips[0].channels[0].rotation_times = keys;
    rig.clips[0].channels[0].rotations.assign(keys.size(), Eigen::Quaterniond::Identity());
    rig.clips[0].key_times = keys;
    ASSERT_GT(rig.clips[0].keys_per_s(), 0.0);
    const RigMotion motion(std::make_shared<const Rig>(rig), RigMotionOptions{.clip = 0});
    EXPECT_EQ(motion.rate_hz(), kDefaultSampleRateHz);
    EXPECT_EQ(motion.num_samples(), 31);
  }
}

TEST(KeyGridFrameRate, EvenlySpacedKeysAtAStandardRateGiveThatRate) {
  std::vector<double> at24;
  for (int k = 1; k <= 48; ++k)
    at24.push_back(static_cast<double>(static_cast<float>(k / 24.0)));  // float times, as glTF
  EXPECT_EQ(key_grid_frame_rate(at24), 24.0);
  std::vector<double> ntsc;
  for (int k = 0; k < 100; ++k) ntsc.push_back(k * 1001.0 / 30000.0);
  EXPECT_DOUBLE_EQ(key_grid_frame_rate(ntsc), 30000.0 / 1001.0);
  EXPECT_EQ(key_grid_frame_rate({0.0, 1.0 / 30, 2.0 / 30}), 30.0);
}

TEST(KeyGridFrameRate, OtherKeysGiveNone) {
  EXPECT_EQ(key_grid_frame_rate({}), 0.0);
  EXPECT_EQ(key_grid_frame_rate({0.0, 1.0 / 24}), 0.0);            // two keys: no evidence
  EXPECT_EQ(key_grid_frame_rate({0.0, 0.5, 1.0, 1.5, 2.0}), 0.0);  // 2 Hz: keys, not frames
  EXPECT_EQ(key_grid_frame_rate({0.0, 1.0 / 24, 3.0 / 24, 4.0 / 24}), 0.0);  // a hole in the grid
  std::vector<double> pairs;  // frames at 30 Hz, each key doubled 5e-8 s later
  for (int k = 0; k < 30; ++k) {
    pairs.push_back(k / 30.0);
    pairs.push_back(k / 30.0 + 5e-8);
  }
  EXPECT_EQ(key_grid_frame_rate(pairs), 0.0);
  std::vector<double> odd;  // evenly spaced at 27 Hz: not a standard frame rate
  for (int k = 0; k < 27; ++k) odd.push_back(k / 27.0);
  EXPECT_EQ(key_grid_frame_rate(odd), 0.0);
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
