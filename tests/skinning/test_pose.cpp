// Pose evaluation: key interpolation, the hierarchy, bind/rest poses, and rig validation, on a
// hand-built two-bone rig whose answers are worked out in the comments.

#include "skinning/pose.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/lbs.hpp"
#include "tests/skinning/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

using std::numbers::pi;
using skelcd::test::expect_matrix_near;

Eigen::Quaterniond about_z(double angle) { return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())); }

TEST(Interpolate, LerpAtKeysMidpointsAndOutside) {
  const std::vector<double> times{1.0, 2.0, 4.0};
  const std::vector<Eigen::Vector3d> values{{0, 0, 0}, {2, 4, 6}, {2, 0, 6}};
  EXPECT_EQ(interpolate_vector(times, values, 1.0), values[0]);
  EXPECT_EQ(interpolate_vector(times, values, 2.0), values[1]);
  EXPECT_EQ(interpolate_vector(times, values, 4.0), values[2]);
  EXPECT_EQ(interpolate_vector(times, values, 1.5), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(interpolate_vector(times, values, 3.0), Eigen::Vector3d(2, 2, 6));
  EXPECT_EQ(interpolate_vector(times, values, 2.5), Eigen::Vector3d(2, 3, 6));
  // Clamped outside the keys.
  EXPECT_EQ(interpolate_vector(times, values, -10.0), values[0]);
  EXPECT_EQ(interpolate_vector(times, values, 99.0), values[2]);
  // One key: constant.
  EXPECT_EQ(interpolate_vector(std::vector<double>{0.5}, std::vector<Eigen::Vector3d>{{7, 8, 9}}, 3.0), Eigen::Vector3d(7, 8, 9));
}

TEST(Interpolate, SlerpMidpointIsHalfTheAngle) {
  const std::vector<double> times{0.0, 1.0};
  const std::vector<Eigen::Quaterniond> q{about_z(0), about_z(pi / 2)};
  const auto mid = interpolate_rotation(times, q, 0.5);
  EXPECT_NEAR(mid.angularDistance(about_z(pi / 4)), 0.0, 1e-15);
  const auto quarter = interpolate_rotation(times, q, 0.25);
  EXPECT_NEAR(quarter.angularDistance(about_z(pi / 8)), 0.0, 1e-15);
  EXPECT_NEAR(interpolate_rotation(times, q, -1.0).angularDistance(q[0]), 0.0, 0.0);
  EXPECT_NEAR(interpolate_rotation(times, q, 2.0).angularDistance(q[1]), 0.0, 0.0);
}

TEST(Interpolate, SlerpTakesTheShorterArc) {
  // The second key is written as -q (the same rotation, 170° about z): the midpoint is 85°,
  // not the long way round through -95°.
  const std::vector<double> times{0.0, 1.0};
  Eigen::Quaterniond far = about_z(170.0 * pi / 180.0);
  far.coeffs() = -far.coeffs();
  const std::vector<Eigen::Quaterniond> q{about_z(0), far};
  const auto mid = interpolate_rotation(times, q, 0.5);
  EXPECT_NEAR(mid.angularDistance(about_z(85.0 * pi / 180.0)), 0.0, 1e-14);
}

TEST(PoseEvaluator, NinetyDegreeJointRotationMovesVerticesToHandComputedPlaces) {
  const Rig rig = test::two_bone_rig();
  const PoseEvaluator evaluator(rig);
  const LinearBlendSkinning lbs(rig);
  Pose pose;
  Positions posed;
  evaluator.clip_pose(0, 1.0, pose);
  lbs.apply(pose, posed);
  // Bone 1 = T(1,0,0) · Rz(90°) · T(-1,0,0). Vertex 1 (2,0,0) → (1,0,0) → (0,1,0) → (1,1,0).
  // Vertex 2 (1.5,0.5,0): bone 0 keeps it; bone 1 takes it to (0.5,0.5,0); half of each is (1,0.5,0).
  Positions expected(4, 3);
  expected << 0, 0, 0,  //
      1, 1, 0,          //
      1, 0.5, 0,        //
      0.5, 0.5, 0;
  EXPECT_TRUE(expect_matrix_near(posed, expected, 1e-15));
  // Halfway (45°): vertex 1 at (1 + cos 45°, sin 45°, 0).
  evaluator.clip_pose(0, 0.5, pose);
  lbs.apply(pose, posed);
  const double h = std::sqrt(0.5);
  EXPECT_NEAR(posed(1, 0), 1 + h, 1e-15);
  EXPECT_NEAR(posed(1, 1), h, 1e-15);
  // The node globals: node 1 sits at (1,0,0) turned by 45°.
  EXPECT_TRUE(expect_matrix_near(pose.node_global[1].translation(), Eigen::Vector3d(1, 0, 0), 0.0));
  EXPECT_NEAR(Eigen::Quaterniond(pose.node_global[1].linear()).angularDistance(about_z(pi / 4)), 0.0, 1e-15);
}

TEST(PoseEvaluator, BindAndRestPosesReproduceTheRestPositions) {
  const Rig rig = test::two_bone_rig();
  const PoseEvaluator evaluator(rig);
  const LinearBlendSkinning lbs(rig);
  Pose pose;
  Positions posed;
  evaluator.bind_pose(pose);
  lbs.apply(pose, posed);
  EXPECT_TRUE(expect_matrix_near(posed, rig.mesh.rest_positions, 0.0));
  evaluator.rest_pose(pose);
  lbs.apply(pose, posed);
  EXPECT_TRUE(expect_matrix_near(posed, rig.mesh.rest_positions, 0.0));
  // Before the first key the clip holds its first value (identity: the rest pose).
  evaluator.clip_pose(0, -3.0, pose);
  lbs.apply(pose, posed);
  EXPECT_TRUE(expect_matrix_near(posed, rig.mesh.rest_positions, 0.0));
}

TEST(PoseEvaluator, NodesWithoutChannelsAndMissingTracksKeepTheirRestValues) {
  Rig rig = test::two_bone_rig();
  // The root now has a rest transform (a shift by (0, 0, 5) and a scale of 2) and a channel
  // that animates only its rotation: its translation and scale must stay.
  rig.skeleton.nodes[0].rest_local = Eigen::Translation3d(0, 0, 5) * Eigen::Scaling(2.0);
  rig.skeleton.bones[0].inverse_bind = rig.skeleton.nodes[0].rest_local.inverse();
  rig.skeleton.bones[1].inverse_bind = (rig.skeleton.nodes[0].rest_local * rig.skeleton.nodes[1].rest_local).inverse();
  Channel root;
  root.node = 0;
  root.rotation_times = {0.0};
  root.rotations = {about_z(pi)};
  rig.clips[0].channels.push_back(root);
  const PoseEvaluator evaluator(rig);
  Pose pose;
  evaluator.clip_pose(0, 0.0, pose);
  // Root global = T(0,0,5) · Rz(180°) · S(2).
  const Eigen::Affine3d expected = Eigen::Translation3d(0, 0, 5) * Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitZ()) * Eigen::Scaling(2.0);
  EXPECT_TRUE(expect_matrix_near(pose.node_global[0].matrix(), expected.matrix(), 1e-15));
  // Node 1 has a channel with a rotation key of 0 at t = 0: at rest relative to the root.
  EXPECT_TRUE(expect_matrix_near(pose.node_global[1].matrix(), (expected * Eigen::Translation3d(1, 0, 0)).matrix(), 1e-15));
}

TEST(PoseEvaluator, PartAttachmentsMoveUnweightedVerticesRigidly) {
  Rig rig = test::two_bone_rig();
  // Vertex 3 loses its weight; its part hangs from node 1 (rest global T(1,0,0)).
  rig.weights.coeffRef(3, 0) = 0.0;
  rig.weights.prune(0.0);
  rig.part_attachments = {{1, Eigen::Affine3d(Eigen::Translation3d(-1, 0, 0))}};
  const PoseEvaluator evaluator(rig);
  const LinearBlendSkinning lbs(rig);
  Pose pose;
  Positions posed;
  evaluator.clip_pose(0, 1.0, pose);
  lbs.apply(pose, posed);
  // (0.5,0.5,0) → node space (-0.5,0.5,0) → Rz(90°) (-0.5,-0.5,0) → +(1,0,0) = (0.5,-0.5,0).
  EXPECT_TRUE(expect_matrix_near(posed.row(3), Eigen::RowVector3d(0.5, -0.5, 0), 1e-15));
  evaluator.bind_pose(pose);
  lbs.apply(pose, posed);
  EXPECT_TRUE(expect_matrix_near(posed, rig.mesh.rest_positions, 1e-15));
}

TEST(ValidateRig, RefusesBrokenRigsNamingTheFault) {
  {
    Rig rig = test::two_bone_rig();
    rig.skeleton.nodes[0].parent = 1;  // a cycle: 0 → 1 → 0
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "node 0 ('root') has parent 1");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.weights.coeffRef(2, 1) = 0.7;  // row sums to 1.2
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "weights of vertex 2 sum to");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.clips[0].channels[0].node = 7;
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "node 7 out of range");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.clips[0].channels[0].rotation_times = {1.0, 0.0};
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "key 1 is not after key 0");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.skeleton.bones[1].inverse_bind(0, 3) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "bone 1 ('lower')");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.clips[0].channels[0].rotations[1].coeffs() *= 2.0;
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "not a unit quaternion");
  }
  {
    Rig rig = test::two_bone_rig();
    rig.weights.resize(4, 3);
    EXPECT_THROW_MESSAGE(validate_rig(rig), InvalidInput, "weights are 4 x 3, expected 4 x 2");
  }
  EXPECT_NO_THROW(validate_rig(test::two_bone_rig()));
}

}  // namespace
}  // namespace skelcd::skinning
