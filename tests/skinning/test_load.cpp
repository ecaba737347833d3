// load_model: what a MODEL argument names, and the motions a loaded rig makes.

#include "skinning/load.hpp"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/rig_motion.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

TEST(ClassifyModelPath, FilesFoldersGlobsAndRobots) {
  const auto dir = skelcd::test::temp_dir("classify");
  const auto bracketed = dir / "walk[2].obj";
  std::ofstream(bracketed) << "v 0 0 0\n";
  EXPECT_EQ(classify_model_path(bracketed), ModelKind::rig);  // exists: a file, not a glob
  EXPECT_EQ(classify_model_path(dir), ModelKind::frame_sequence);
  EXPECT_EQ(classify_model_path(dir / "frame_*.ply"), ModelKind::frame_sequence);
  EXPECT_EQ(classify_model_path(dir / "robot.URDF"), ModelKind::robot);
  EXPECT_EQ(classify_model_path(dir / "missing.glb"), ModelKind::rig);
}

TEST(LoadModel, RigMotionsByClipName) {
  const auto model = load_model(skelcd::test::asset("characters/Fox.glb"));
  EXPECT_EQ(model.kind, ModelKind::rig);
  ASSERT_TRUE(model.rig);
  EXPECT_EQ(model.mesh.get(), &model.rig->mesh);
  ASSERT_EQ(model.clips.size(), 3u);
  EXPECT_EQ(model.clips[1].name, "Walk");
  const auto first = model.motion();
  EXPECT_EQ(first->name(), "Survey");
  const auto walk = model.motion({"Walk", 0.0});
  EXPECT_EQ(walk->name(), "Walk");
  EXPECT_NEAR(walk->sample_time(walk->num_samples() - 1), model.clips[1].duration_s, 1e-12);
  const auto slow = model.motion({"Walk", 10.0});
  EXPECT_EQ(slow->num_samples(), sample_count(model.clips[1].duration_s, 10.0));
  EXPECT_THROW_MESSAGE((void)model.motion({"Dance", 0.0}), InvalidInput, "no clip named 'Dance' (clips: 'Survey' 'Walk' 'Run')");
}

TEST(LoadModel, AModelWithoutClipsMovesToItsBindPose) {
  const auto dir = skelcd::test::temp_dir("load_static");
  const auto file = dir / "tri.obj";
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const auto model = load_model(file);
  EXPECT_TRUE(model.clips.empty());
  const auto motion = model.motion();
  EXPECT_EQ(motion->num_samples(), 1);
  Positions p;
  motion->positions(0, p);
  EXPECT_TRUE(skelcd::test::expect_matrix_near(p, model.mesh->rest_positions, 0.0));
}

TEST(LoadModel, RobotOptionsOnAModelFileAreRefused) {
  LoadOptions options;
  options.trajectory = "walk.csv";
  EXPECT_THROW_MESSAGE((void)load_model(skelcd::test::asset("characters/Fox.glb"), options), InvalidInput,
                       "applies to URDF robots only");
}

}  // namespace
}  // namespace skelcd::skinning
