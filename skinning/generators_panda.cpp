// The Panda reach and free trajectories, and the `panda` generator (the bundled robot on the reach
// trajectory).

#include "skinning/generators_panda.hpp"

#include <cstdlib>
#include <numbers>

#include "skinning/errors.hpp"
#include "skinning/generators_common.hpp"

namespace skelcd::skinning {

namespace fs = std::filesystem;

fs::path panda_description_dir() {
  const char* env = std::getenv("SKELCD_ASSETS");
  const fs::path assets = env != nullptr && *env != '\0' ? fs::path(env) : fs::path(__FILE__).parent_path().parent_path() / "assets";
  const fs::path dir = assets / "robots" / "example-robot-data" / "robots" / "panda_description";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw IoError(dir.string() + ": the bundled Panda is missing (set SKELCD_ASSETS to the repository's assets/ folder)");
  }
  return dir;
}

Robot load_bundled_panda() {
  const fs::path dir = panda_description_dir();
  UrdfOptions options;
  options.srdf = dir / "srdf" / "panda.srdf";
  return load_urdf(dir / "urdf" / "panda.resolved.urdf", options);
}

namespace {

constexpr double kPi = std::numbers::pi;

// Arm joints 1–7 and finger joint 1. The ready pose is the SRDF's "default" group state.
constexpr std::array<double, 8> kReady = {0.0, -kPi / 4, 0.0, -3 * kPi / 4, 0.0, kPi / 2, kPi / 4, 0.04};
// Shoulder back, elbow folded to near its limit, wrist tucked: the open fingers, then the hand,
// press into links 1 and 2.
constexpr std::array<double, 8> kReachEnd = {0.0, -1.7, 0.0, -3.0, 0.0, 0.5, kPi / 4, 0.04};
// Far from the ready pose on every joint, and collision-free all the way.
constexpr std::array<double, 8> kFreeEnd = {2.0, 0.3, -0.8, -1.2, 1.5, 2.5, -1.0, 0.01};

}  // namespace

JointTrajectory panda_trajectory(const Robot& panda, int rows, bool reach) {
  static const char* const kNames[8] = {"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                        "panda_joint5", "panda_joint6", "panda_joint7", "panda_finger_joint1"};
  JointTrajectory t;
  t.source = reach ? "panda_reach" : "panda_free";
  for (const char* name : kNames) {
    const std::int32_t j = panda.find_joint(name);
    if (j < 0) throw InvalidInput(panda.urdf_file.string() + ": no joint '" + name + "' (not the Panda?)");
    t.joints.push_back(j);
  }
  const auto& end = reach ? kReachEnd : kFreeEnd;
  t.positions.resize(rows, 8);
  for (int i = 0; i < rows; ++i) {
    const double tau = static_cast<double>(i) / (rows - 1);
    const double s = tau * tau * (3 - 2 * tau);
    t.times.push_back(i / kGeneratorFrameRateHz);
    for (Eigen::Index c = 0; c < 8; ++c) {
      const auto k = static_cast<std::size_t>(c);
      t.positions(i, c) = kReady[k] + s * (end[k] - kReady[k]);
    }
  }
  return t;
}

// Found by bisection on tau with the exact triangle test of the tests (first contact, left finger
// against link 1, between tau = 0.625726955208 and 0.625726955209), and checked at 401 evenly
// spaced tau: free below, hand or fingers against links 1-2 above.
PandaReachWindow panda_reach_window() { return {0.6257, 0.6258}; }

namespace generators {

GeneratedRig generate_panda(int frames, bool reach) {
  Robot panda = load_bundled_panda();
  const JointTrajectory t = panda_trajectory(panda, frames, reach);
  GeneratedRig g;
  panda.rig.clips.push_back(trajectory_clip(panda, t, reach ? "reach" : "free"));
  g.rig = std::move(panda.rig);
  if (!reach) {
    g.answer.rule = "collision-free at every sample (checked exactly at 61 rows)";
    g.answer.margin.assign(static_cast<std::size_t>(frames), -1.0);
    decide(g.answer, 0.0);
    return g;
  }
  const PandaReachWindow w = panda_reach_window();
  g.answer.rule = "trajectory parameter tau = i / (frames - 1): free for tau < " + std::to_string(w.free_below) +
                  ", hand or fingers intersecting links 1-2 for tau > " + std::to_string(w.intersecting_above);
  for (int i = 0; i < frames; ++i) {
    const double tau = static_cast<double>(i) / (frames - 1);
    // Margin in units of tau: negative below the free bound, positive above the intersecting one.
    g.answer.margin.push_back(tau < w.free_below ? tau - w.free_below
                              : tau > w.intersecting_above ? tau - w.intersecting_above
                                                           : 0.0);
  }
  decide(g.answer, 0.0);
  return g;
}

}  // namespace generators
}  // namespace skelcd::skinning
