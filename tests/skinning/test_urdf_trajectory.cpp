// Joint trajectories: CSV parsing and its errors, and the clip they become — evaluated here by
// hand (keys composed down the link tree, slerp/lerp between keys) against forward kinematics.

#include "skinning/urdf_trajectory.hpp"

#include <cmath>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/urdf.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

namespace fs = std::filesystem;
using test::expect_matrix_near;

constexpr double kPi = std::numbers::pi;

const Robot& panda() {
  static const Robot robot =
      load_urdf(test::asset("robots/example-robot-data/robots/panda_description/urdf/panda.urdf"));
  return robot;
}

// Value of a keyed track at t, written independently of skinning/pose.cpp: clamp outside the
// keys, lerp or slerp (Eigen's, shorter arc) between the two keys around t.
template <typename T, typename Mix>
T sample_track(const std::vector<double>& times, const std::vector<T>& values, double t, Mix mix) {
  if (t <= times.front()) return values.front();
  if (t >= times.back()) return values.back();
  std::size_t k = 1;
  while (times[k] < t) ++k;
  const double u = (t - times[k - 1]) / (times[k] - times[k - 1]);
  return mix(values[k - 1], values[k], u);
}

// Global link transforms of `clip` at time t: nodes with a channel take its value, the others
// their rest_local; composed from the root down.
std::vector<Eigen::Affine3d> clip_globals(const Robot& robot, const Clip& clip, double t) {
  const Skeleton& s = robot.rig.skeleton;
  std::vector<Eigen::Affine3d> local(s.nodes.size());
  for (std::size_t i = 0; i < s.nodes.size(); ++i) local[i] = s.nodes[i].rest_local;
  for (const Channel& c : clip.channels) {
    const Eigen::Vector3d p = sample_track(c.translation_times, c.translations, t,
                                           [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double u) { return Eigen::Vector3d((1 - u) * a + u * b); });
    const Eigen::Quaterniond q = sample_track(c.rotation_times, c.rotations, t,
                                              [](const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double u) { return a.slerp(u, b); });
    EXPECT_TRUE(c.scales.empty());
    local[static_cast<std::size_t>(c.node)] = Eigen::Translation3d(p) * q;
  }
  std::vector<Eigen::Affine3d> global(s.nodes.size());
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    global[i] = s.nodes[i].parent < 0 ? local[i] : global[static_cast<std::size_t>(s.nodes[i].parent)] * local[i];
  }
  return global;
}

std::vector<double> q_named(const Robot& robot, const std::vector<std::pair<std::string, double>>& values) {
  std::vector<double> q(robot.joints.size(), 0.0);
  for (const auto& [name, v] : values) q[static_cast<std::size_t>(robot.find_joint(name))] = v;
  return q;
}

void expect_same_poses(const std::vector<Eigen::Affine3d>& a, const std::vector<Eigen::Affine3d>& b, double tol) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(expect_matrix_near(a[i].matrix(), b[i].matrix(), tol)) << "link " << i;
}

TEST(UrdfTrajectory, ParsesAndBecomesAClipMatchingForwardKinematics) {
  const Robot& robot = panda();
  const std::string csv =
      "# a comment\n"
      "time, panda_joint2 ,panda_joint4,panda_finger_joint1\n"
      "1.0,0,-0.1,0\n"
      "\n"
      "1.5,0.5,-1.2,0.02\r\n"
      "2.0,-0.25,-2.5,0.04\n";
  const JointTrajectory t = parse_joint_trajectory(csv, "mem.csv", robot);
  ASSERT_EQ(t.num_rows(), 3);
  ASSERT_EQ(t.joints.size(), 3U);
  EXPECT_EQ(t.joints[0], robot.find_joint("panda_joint2"));
  EXPECT_EQ(t.times, (std::vector<double>{1.0, 1.5, 2.0}));
  EXPECT_EQ(t.positions(1, 1), -1.2);

  const Clip clip = trajectory_clip(robot, t, "reach");
  EXPECT_EQ(clip.name, "reach");
  EXPECT_DOUBLE_EQ(clip.duration_s, 1.0);  // times start at the first row
  EXPECT_EQ(clip.key_times, (std::vector<double>{0.0, 0.5, 1.0}));
  EXPECT_DOUBLE_EQ(clip.keys_per_s(), 2.0);
  // joint2, joint4, both fingers (finger 2 mimics finger 1).
  EXPECT_EQ(clip.channels.size(), 4U);

  // At the keys: exactly the robot's forward kinematics at each row (unlisted joints at 0).
  const std::vector<std::vector<std::pair<std::string, double>>> rows = {
      {{"panda_joint4", -0.1}},
      {{"panda_joint2", 0.5}, {"panda_joint4", -1.2}, {"panda_finger_joint1", 0.02}},
      {{"panda_joint2", -0.25}, {"panda_joint4", -2.5}, {"panda_finger_joint1", 0.04}}};
  for (std::size_t r = 0; r < rows.size(); ++r) {
    expect_same_poses(clip_globals(robot, clip, 0.5 * static_cast<double>(r)),
                      forward_kinematics(robot, q_named(robot, rows[r])), 1e-14);
  }
  // Between keys: slerp about a fixed axis is the linearly interpolated angle.
  for (const double u : {0.1, 0.37, 0.5, 0.93}) {
    const double j2 = 0.5 + u * (-0.25 - 0.5);
    const double j4 = -1.2 + u * (-2.5 + 1.2);
    const double f = 0.02 + u * 0.02;
    expect_same_poses(clip_globals(robot, clip, 0.5 + 0.5 * u),
                      forward_kinematics(robot, q_named(robot, {{"panda_joint2", j2}, {"panda_joint4", j4}, {"panda_finger_joint1", f}})),
                      1e-12);
  }
  // Row positions for forward kinematics resolve the mimic finger.
  const std::vector<double> q = trajectory_row_positions(robot, t, 2);
  EXPECT_EQ(q[static_cast<std::size_t>(robot.find_joint("panda_finger_joint2"))], 0.04);
}

TEST(UrdfTrajectory, LargeStepsAreSplitSoSlerpStaysExact) {
  const fs::path dir = test::temp_dir("trajectory_split");
  {
    std::ofstream out(dir / "spin.urdf");
    out << R"(<robot name="spin"><link name="a"/><link name="b"><collision><geometry><box size="1 0.1 0.1"/></geometry></collision></link>
    <joint name="j" type="continuous"><parent link="a"/><child link="b"/><origin rpy="0.3 0 0" xyz="0 0 1"/><axis xyz="0 0 1"/></joint></robot>)";
  }
  const Robot robot = load_urdf(dir / "spin.urdf");
  // 0 -> 3.5 rad in one row (3 sub-steps of 7/6 rad <= pi/2... ceil(3.5 / (pi/2)) = 3), then back by 0.2.
  const JointTrajectory t = parse_joint_trajectory("time,j\n0,0\n1,3.5\n2,3.3\n", "spin.csv", robot);
  const Clip clip = trajectory_clip(robot, t, "spin");
  ASSERT_EQ(clip.channels.size(), 1U);
  EXPECT_EQ(clip.channels[0].rotation_times.size(), 5U);
  ASSERT_EQ(clip.key_times.size(), 5U);
  EXPECT_NEAR(clip.key_times[1], 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(clip.key_times[2], 2.0 / 3.0, 1e-15);
  // The extra keys raise the key rate, not the frame rate: the rows (3 over 2 s) are the frames.
  EXPECT_DOUBLE_EQ(clip.keys_per_s(), 2.0);
  EXPECT_DOUBLE_EQ(
      clip.frame_rate_hz,
      static_cast<double>(t.num_rows() - 1) / (t.times.back() - t.times.front()));
  EXPECT_EQ(clip.frame_rate_source, FrameRateSource::trajectory_rows);
  for (const double time : {0.1, 0.5, 0.9, 1.0, 1.4, 2.0}) {
    const double angle = time <= 1.0 ? 3.5 * time : 3.5 - 0.2 * (time - 1.0);
    expect_same_poses(clip_globals(robot, clip, time), forward_kinematics(robot, std::vector<double>{angle}), 1e-12);
  }
}

TEST(UrdfTrajectory, WriteThenReadIsExact) {
  const Robot& robot = panda();
  JointTrajectory t;
  t.joints = {robot.find_joint("panda_joint1"), robot.find_joint("panda_joint7")};
  t.times = {0.0, 1.0 / 30.0, 2.0 / 30.0};
  t.positions.resize(3, 2);
  t.positions << 0.1, -0.3, 1.0 / 3.0, std::nextafter(0.5, 1.0), -2.8973, 2.8973;
  const fs::path file = test::temp_dir("trajectory_write") / "t.csv";
  write_joint_trajectory(file, robot, t);
  const JointTrajectory back = read_joint_trajectory(file, robot);
  EXPECT_EQ(back.joints, t.joints);
  EXPECT_EQ(back.times, t.times);
  EXPECT_EQ(back.positions, t.positions);
}

TEST(UrdfTrajectory, BadInputNamesFileAndLine) {
  const Robot& robot = panda();
  const auto parse = [&](const std::string& text) { return parse_joint_trajectory(text, "bad.csv", robot); };
  EXPECT_THROW_MESSAGE((void)parse("t,panda_joint1\n0,0\n"), InvalidInput, "bad.csv:1: header must start with 'time'");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1,elbow\n0,0,0\n"), InvalidInput, "bad.csv:1: unknown joint 'elbow'");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint8\n0,0\n"), InvalidInput, "bad.csv:1: joint 'panda_joint8' is fixed");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_finger_joint2\n0,0\n"), InvalidInput, "bad.csv:1: joint 'panda_finger_joint2' mimics joint 'panda_finger_joint1'");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1,panda_joint1\n0,0,0\n"), InvalidInput, "appears twice");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,0\n1,0.1\n0.5,0.2\n"), InvalidInput, "bad.csv:4: time 0.5 is not after");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,0\n0,0.1\n"), InvalidInput, "bad.csv:3: time 0 is not after");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,abc\n"), InvalidInput, "bad.csv:2: cell 2 ('abc') is not a finite number");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,0.1x\n"), InvalidInput, "bad.csv:2: cell 2 ('0.1x')");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,nan\n"), InvalidInput, "bad.csv:2: cell 2 ('nan') is not a finite number");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,\n"), InvalidInput, "bad.csv:2: cell 2 ('')");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0,0\n1,0,0\n"), InvalidInput, "bad.csv:3: row has 3 cells, the header has 2");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n0\n"), InvalidInput, "bad.csv:2: row has 1 cells");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint4\n0,0.5\n"), InvalidInput, "bad.csv:2: joint 'panda_joint4' position 0.5 is outside its limits");
  EXPECT_THROW_MESSAGE((void)parse("time,panda_joint1\n"), InvalidInput, "bad.csv: no data rows");
  EXPECT_THROW_MESSAGE((void)parse("# only a comment\n"), InvalidInput, "bad.csv: no header line");
  // Limits can be left unchecked.
  TrajectoryOptions options;
  options.check_limits = false;
  EXPECT_EQ(parse_joint_trajectory("time,panda_joint4\n0,0.5\n", "ok.csv", robot, options).positions(0, 0), 0.5);
  EXPECT_THROW_MESSAGE((void)read_joint_trajectory("/nonexistent/t.csv", robot), IoError, "/nonexistent/t.csv: cannot open");
}

// load_model on a URDF with a trajectory: the Motion (RigMotion over the trajectory clip, one-hot
// skinning) puts every link's rest vertices where forward kinematics of that row puts them.
TEST(UrdfTrajectory, LoadModelMotionFollowsForwardKinematics) {
  const Robot& robot = panda();
  const fs::path dir = test::temp_dir("trajectory_load_model");
  write_joint_trajectory(dir / "wave.csv", robot, [&] {
    JointTrajectory t;
    t.joints = {robot.find_joint("panda_joint1"), robot.find_joint("panda_joint2"),
                robot.find_joint("panda_joint6"), robot.find_joint("panda_finger_joint1")};
    t.times = {0.0, 0.1, 0.2, 0.3};
    t.positions.resize(4, 4);
    t.positions << 0, 0, 0, 0, 0.4, -0.3, 1.0, 0.01, 0.8, -0.6, 2.0, 0.02, 1.2, -0.9, 3.0, 0.04;
    return t;
  }());
  LoadOptions options;
  options.trajectory = dir / "wave.csv";
  options.srdf = test::asset("robots/example-robot-data/robots/panda_description/srdf/panda.srdf");
  const LoadedModel model = load_model(test::asset("robots/example-robot-data/robots/panda_description/urdf/panda.urdf"), options);
  EXPECT_EQ(model.kind, ModelKind::robot);
  ASSERT_EQ(model.clips.size(), 1U);
  EXPECT_EQ(model.clips[0].name, "wave");
  EXPECT_NEAR(model.clips[0].duration_s, 0.3, 1e-15);
  EXPECT_NEAR(model.clips[0].keys_per_s, 10.0, 1e-9);
  EXPECT_NEAR(model.clips[0].rate_hz, 10.0, 1e-9);  // 4 rows over 0.3 s
  EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::trajectory_rows);
  EXPECT_EQ(model.mesh->excluded_part_pairs.size(), 46U);
  ASSERT_FALSE(model.problems.empty());
  EXPECT_NE(model.problems[0].find("panda_link8, panda_hand_tcp"), std::string::npos);
  const auto motion = model.motion({});
  ASSERT_EQ(motion->num_samples(), 4);
  const JointTrajectory t = read_joint_trajectory(dir / "wave.csv", robot);
  const auto rest = forward_kinematics(robot, std::vector<double>(robot.joints.size(), 0.0));
  Positions p;
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(motion->sample_time(i), 0.1 * i, 1e-12);
    motion->positions(i, p);
    const auto world = forward_kinematics(robot, trajectory_row_positions(robot, t, i));
    const Mesh& mesh = robot.rig.mesh;
    ASSERT_EQ(p.rows(), mesh.num_vertices());
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      const std::int32_t part = mesh.vertex_part[static_cast<std::size_t>(v)];
      const std::int32_t link = robot.find_link(mesh.part_names[static_cast<std::size_t>(part)]);
      const Eigen::Vector3d local = rest[static_cast<std::size_t>(link)].inverse() * mesh.rest_positions.row(v).transpose();
      const Eigen::Vector3d expected = world[static_cast<std::size_t>(link)] * local;
      ASSERT_TRUE(expect_matrix_near(p.row(v).transpose(), expected, 1e-12)) << "sample " << i << " vertex " << v;
    }
  }
  LoadOptions missing;
  missing.trajectory = dir / "absent.csv";
  EXPECT_THROW_MESSAGE((void)load_model(test::asset("robots/example-robot-data/robots/panda_description/urdf/panda.urdf"), missing),
                       IoError, "absent.csv: cannot open");
}

}  // namespace
}  // namespace skelcd::skinning
