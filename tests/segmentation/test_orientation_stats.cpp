// Orientation counts against observers that move with their bones: the rest pose reproduces the
// segmentation's own counts, a translated rig keeps every class, and a half turn in one interval
// (the mesh collapses onto the axis half way) leaves no triangle provably positive.

#include <memory>
#include <numbers>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "segmentation/orientation_stats.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tests/segmentation/mini_rigs.hpp"

namespace {

using namespace skelcd::segmentation;
using skelcd::skinning::Rig;

// A two-key clip on the root node: translation and rotation (about z) from the rest values at
// t = 0 to the given ones at t = 1 s.
Rig with_root_clip(Rig rig, const Eigen::Vector3d& translation, double angle) {
  skelcd::skinning::Clip clip;
  clip.name = "move";
  clip.duration_s = 1.0;
  skelcd::skinning::Channel channel;
  channel.node = 0;
  channel.translation_times = {0.0, 1.0};
  channel.translations = {Eigen::Vector3d::Zero(), translation};
  channel.rotation_times = {0.0, 1.0};
  channel.rotations = {Eigen::Quaterniond::Identity(),
                       Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()))};
  clip.channels.push_back(channel);
  clip.key_times = {0.0, 1.0};
  rig.clips.push_back(clip);
  return rig;
}

TEST(OrientationStats, RestPoseCountsMatchTheSegmentation) {
  const Rig rig = skelcd::test::bent_capsule_chain(4, 120.0, true, 0.15);
  const auto seg = segment(rig);
  const auto topo = skelcd::skinning::build_topology(rig.mesh);
  skelcd::skinning::Positions welded;
  skelcd::skinning::gather_welded(topo, rig.mesh.rest_positions, welded);
  std::vector<skelcd::skinning::BoneTransform> identity(
      4, skelcd::skinning::BoneTransform::Identity());
  const auto counts = count_orientations(seg, welded, topo.welded_triangles, identity);
  EXPECT_EQ(counts.h_minus, seg.stats.h_minus);
  EXPECT_EQ(counts.h_uncertain, seg.stats.h_uncertain);
  EXPECT_EQ(counts.h_plus + counts.h_minus + counts.h_uncertain, rig.mesh.num_triangles());
  EXPECT_GT(counts.h_plus, 0);
}

TEST(OrientationStats, ATranslatedRigKeepsEveryTrianglePositive) {
  // A straight chain (no non-positive triangle at rest) sliding along y: vertices and observers
  // move together, each f(t) is constant, and the conservative classifier proves it positive.
  const auto rig = std::make_shared<const Rig>(
      with_root_clip(skelcd::test::capsule_chain(3), Eigen::Vector3d(0, 2, 0), 0.0));
  const auto seg = segment(*rig);
  ASSERT_EQ(seg.stats.h_minus + seg.stats.h_uncertain, 0);
  skelcd::skinning::RigMotion motion(rig, {.clip = 0, .rate_hz = 4.0});
  const auto stats = clip_orientation_stats(seg, motion);
  EXPECT_EQ(stats.intervals, motion.num_samples() - 1);
  EXPECT_GT(stats.intervals, 0);
  EXPECT_EQ(stats.mean_h_minus, 0.0);
  EXPECT_EQ(stats.mean_h_uncertain, 0.0);
  EXPECT_EQ(stats.clip, "move");
}

TEST(OrientationStats, AHalfTurnInOneIntervalLeavesNothingProvablyPositive) {
  // Vertices move linearly from p to the half-turned p: half way every x and y is 0, the mesh
  // lies on the z axis, every normal vanishes, so no f(t) > 0 on all of [0, 1].
  const auto rig = std::make_shared<const Rig>(
      with_root_clip(skelcd::test::capsule_chain(2), Eigen::Vector3d::Zero(), std::numbers::pi));
  const auto seg = segment(*rig);
  skelcd::skinning::RigMotion motion(rig, {.clip = 0, .rate_hz = 1.0});
  ASSERT_EQ(motion.num_samples(), 2);
  const auto stats = clip_orientation_stats(seg, motion);
  ASSERT_EQ(stats.intervals, 1);
  EXPECT_EQ(stats.mean_h_minus + stats.mean_h_uncertain,
            static_cast<double>(rig->mesh.num_triangles()));
}

TEST(OrientationStats, ASegmentationOfAnotherMeshIsRefused) {
  const auto rig = std::make_shared<const Rig>(
      with_root_clip(skelcd::test::capsule_chain(2), Eigen::Vector3d::Zero(), 0.5));
  const auto other = segment(skelcd::test::capsule_chain(3));
  skelcd::skinning::RigMotion motion(rig, {.clip = 0, .rate_hz = 2.0});
  EXPECT_THROW(std::ignore = clip_orientation_stats(other, motion), skelcd::InvalidInput);
}

}  // namespace
