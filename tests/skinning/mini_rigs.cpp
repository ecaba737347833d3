#include "tests/skinning/mini_rigs.hpp"

#include <numbers>

#include "tests/skinning/mini_meshes.hpp"

namespace skelcd::skinning::test {

Rig two_bone_rig() {
  Rig rig;
  rig.source = "two_bone_rig";
  rig.mesh = make_mesh({{0, 0, 0}, {2, 0, 0}, {1.5, 0.5, 0}, {0.5, 0.5, 0}}, {{0, 1, 2}, {0, 2, 3}}, "strip");
  SkeletonNode root;
  root.name = "root";
  SkeletonNode elbow;
  elbow.name = "elbow";
  elbow.parent = 0;
  elbow.rest_local = Eigen::Translation3d(1, 0, 0);
  rig.skeleton.nodes = {root, elbow};
  Bone b0;
  b0.name = "upper";
  b0.node = 0;
  b0.rest_head = {0, 0, 0};
  b0.rest_tail = {1, 0, 0};
  Bone b1;
  b1.name = "lower";
  b1.node = 1;
  b1.parent = 0;
  b1.inverse_bind = Eigen::Translation3d(-1, 0, 0);
  b1.rest_head = {1, 0, 0};
  b1.rest_tail = {2, 0, 0};
  rig.skeleton.bones = {b0, b1};
  rig.weights.resize(4, 2);
  std::vector<Eigen::Triplet<double>> w{{0, 0, 1.0}, {1, 1, 1.0}, {2, 0, 0.5}, {2, 1, 0.5}, {3, 0, 1.0}};
  rig.weights.setFromTriplets(w.begin(), w.end());
  rig.weights.makeCompressed();
  Clip clip;
  clip.name = "bend";
  clip.duration_s = 1.0;
  Channel ch;
  ch.node = 1;
  ch.rotation_times = {0.0, 1.0};
  ch.rotations = {Eigen::Quaterniond::Identity(),
                  Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()))};
  clip.channels = {ch};
  clip.key_times = {0.0, 1.0};
  rig.clips = {clip};
  return rig;
}

}  // namespace skelcd::skinning::test
