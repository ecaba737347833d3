// load_model()'s robot branch: a URDF, its SRDF and joint trajectory as one LoadedModel.

#include <string>
#include <utility>
#include <vector>

#include "skinning/load.hpp"
#include "skinning/urdf.hpp"
#include "skinning/urdf_trajectory.hpp"

namespace skelcd::skinning {

LoadedModel load_urdf_model(const std::filesystem::path& urdf_file, const LoadOptions& options) {
  UrdfOptions urdf_options;
  urdf_options.package_path = options.package_path;
  urdf_options.srdf = options.srdf;
  Robot robot = load_urdf(urdf_file, urdf_options);

  std::vector<std::string> problems;
  std::string without_geometry;
  for (const RobotLink& link : robot.links) {
    if (link.part < 0) without_geometry += (without_geometry.empty() ? "" : ", ") + link.name;
  }
  if (!without_geometry.empty()) {
    problems.push_back("links without collision or visual geometry (not checked): " + without_geometry);
  }
  if (options.trajectory.empty()) {
    problems.push_back("no joint trajectory given: the robot stays in its rest pose (every joint at 0)");
  } else {
    const JointTrajectory trajectory = read_joint_trajectory(options.trajectory, robot);
    Clip clip = trajectory_clip(robot, trajectory, options.trajectory.stem().string());
    if (clip.key_times.size() != trajectory.times.size()) {
      problems.push_back("trajectory " + options.trajectory.string() + ": " +
                         std::to_string(clip.key_times.size() - trajectory.times.size()) +
                         " keys added where a revolute joint turns more than pi/2 between rows");
    }
    robot.rig.clips.push_back(std::move(clip));
    robot.rig.source = urdf_file.string() + " + " + options.trajectory.string();
  }
  LoadedModel model = model_from_rig(std::move(robot.rig), ModelKind::robot, std::move(problems));
  model.path = urdf_file;
  return model;
}

}  // namespace skelcd::skinning
