// URDF robots: structure counts, forward kinematics against transforms computed by hand from the
// Panda URDF's joint origins and axes, mesh path resolution, excluded pairs, and bad input.

#include "skinning/urdf.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/urdf_srdf.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

namespace fs = std::filesystem;
using test::asset;
using test::expect_matrix_near;

constexpr double kPi = std::numbers::pi;
const double kC = std::sqrt(0.5);  // cos(pi/4) = sin(pi/4)

fs::path panda_dir() { return asset("robots/example-robot-data/robots/panda_description"); }
fs::path panda_urdf() { return panda_dir() / "urdf/panda.urdf"; }
fs::path panda_resolved() { return panda_dir() / "urdf/panda.resolved.urdf"; }
fs::path panda_srdf() { return panda_dir() / "srdf/panda.srdf"; }
fs::path ur5_dir() { return asset("robots/example-robot-data/robots/ur_description"); }

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

const Robot& panda() {
  static const Robot robot = load_urdf(panda_urdf());
  return robot;
}

/// Joint positions by name (everything else 0).
std::vector<double> positions(const Robot& robot, const std::vector<std::pair<std::string, double>>& q) {
  std::vector<double> out(robot.joints.size(), 0.0);
  for (const auto& [name, value] : q) {
    const std::int32_t j = robot.find_joint(name);
    EXPECT_GE(j, 0) << name;
    out[static_cast<std::size_t>(j)] = value;
  }
  return out;
}

Eigen::Matrix4d pose(const Eigen::Matrix3d& r, const Eigen::Vector3d& p) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r;
  m.topRightCorner<3, 1>() = p;
  return m;
}

Eigen::Matrix3d rows(std::initializer_list<double> v) {
  Eigen::Matrix3d m;
  auto it = v.begin();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = *it++;
  }
  return m;
}

TEST(Urdf, PandaCounts) {
  const Robot& robot = panda();
  EXPECT_EQ(robot.name, "panda");
  EXPECT_EQ(robot.num_links(), 13);
  EXPECT_EQ(robot.num_movable_joints(), 9);
  EXPECT_EQ(robot.links[0].name, "panda_link0");  // the root comes first
  // Geometry: link0..link7 and the hand have STL collision meshes, each finger four boxes;
  // link8 and hand_tcp have none.
  EXPECT_EQ(robot.rig.mesh.num_parts(), 11);
  EXPECT_EQ(robot.rig.skeleton.num_bones(), 11);
  EXPECT_EQ(robot.rig.skeleton.nodes.size(), 13U);
  const std::int32_t finger = robot.find_link("panda_leftfinger");
  const std::int32_t part = robot.links[static_cast<std::size_t>(finger)].part;
  EXPECT_EQ(std::count(robot.rig.mesh.face_part.begin(), robot.rig.mesh.face_part.end(), part), 4 * 12);
  EXPECT_EQ(robot.links[static_cast<std::size_t>(robot.find_link("panda_link8"))].part, -1);
  // Mimic: finger 2 follows finger 1.
  const RobotJoint& f2 = robot.joints[static_cast<std::size_t>(robot.find_joint("panda_finger_joint2"))];
  EXPECT_EQ(f2.mimic_joint, robot.find_joint("panda_finger_joint1"));
  EXPECT_EQ(f2.type, JointType::kPrismatic);
  const RobotJoint& j4 = robot.joints[static_cast<std::size_t>(robot.find_joint("panda_joint4"))];
  EXPECT_TRUE(j4.has_limits);
  EXPECT_DOUBLE_EQ(j4.lower, -3.0718);
  EXPECT_DOUBLE_EQ(j4.upper, -0.0698);
}

TEST(Urdf, Ur5Counts) {
  const Robot robot = load_urdf(ur5_dir() / "urdf/ur5_robot.urdf");
  EXPECT_EQ(robot.num_movable_joints(), 6);
  // world, base_link, base, shoulder, upper_arm, forearm, wrist_1..3, ee_link, tool0.
  EXPECT_EQ(robot.num_links(), 11);
  EXPECT_EQ(robot.links[0].name, "world");
  EXPECT_EQ(robot.rig.mesh.num_parts(), 8);  // 7 STL links and ee_link's box
}

// Transforms below are derived by hand from the URDF (see the comments), not printed by the code.
TEST(Urdf, PandaForwardKinematicsAtZero) {
  const Robot& robot = panda();
  const auto world = forward_kinematics(robot, positions(robot, {{"panda_finger_joint1", 0.04}}));
  const auto at = [&](const char* link) { return world[static_cast<std::size_t>(robot.find_link(link))].matrix(); };
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d rx90 = rows({1, 0, 0, 0, 0, -1, 0, 1, 0});
  const Eigen::Matrix3d rxm90 = rows({1, 0, 0, 0, 0, 1, 0, -1, 0});
  const Eigen::Matrix3d rx180 = rows({1, 0, 0, 0, -1, 0, 0, 0, -1});
  // link1: translate z 0.333.
  EXPECT_TRUE(expect_matrix_near(at("panda_link1"), pose(I, {0, 0, 0.333}), 1e-12));
  // link2: rpy(-pi/2) at the same point.
  EXPECT_TRUE(expect_matrix_near(at("panda_link2"), pose(rxm90, {0, 0, 0.333}), 1e-12));
  // link3: (0,-0.316,0) in link2's frame is +0.316 z; the two x rotations cancel.
  EXPECT_TRUE(expect_matrix_near(at("panda_link3"), pose(I, {0, 0, 0.649}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link4"), pose(rx90, {0.0825, 0, 0.649}), 1e-12));
  // link5: (-0.0825, 0.384, 0) under Rx(90) is (-0.0825, 0, 0.384).
  EXPECT_TRUE(expect_matrix_near(at("panda_link5"), pose(I, {0, 0, 1.033}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link6"), pose(rx90, {0, 0, 1.033}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link7"), pose(rx180, {0.088, 0, 1.033}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link8"), pose(rx180, {0.088, 0, 0.926}), 1e-12));
  // hand: Rx(180) Rz(-45).
  const Eigen::Matrix3d hand = rows({kC, kC, 0, kC, -kC, 0, 0, 0, -1});
  EXPECT_TRUE(expect_matrix_near(at("panda_hand"), pose(hand, {0.088, 0, 0.926}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_hand_tcp"), pose(hand, {0.088, 0, 0.8226}), 1e-12));
  // Fingers: hand frame (0, +-0.04, 0.0584).
  EXPECT_TRUE(expect_matrix_near(at("panda_leftfinger"), pose(hand, {0.088 + 0.04 * kC, -0.04 * kC, 0.8676}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_rightfinger"), pose(hand, {0.088 - 0.04 * kC, 0.04 * kC, 0.8676}), 1e-12));
}

TEST(Urdf, PandaForwardKinematicsBentConfiguration) {
  const Robot& robot = panda();
  const auto world = forward_kinematics(
      robot, positions(robot, {{"panda_joint1", kPi / 2},
                               {"panda_joint4", -kPi / 2},
                               {"panda_joint6", kPi / 2},
                               {"panda_joint7", kPi / 4},
                               {"panda_finger_joint1", 0.02}}));
  const auto at = [&](const char* link) { return world[static_cast<std::size_t>(robot.find_link(link))].matrix(); };
  // By hand, R_i = R_{i-1} · R_origin_i · Rz(q_i), p_i = p_{i-1} + R_{i-1} · xyz_i.
  EXPECT_TRUE(expect_matrix_near(at("panda_link1"), pose(rows({0, -1, 0, 1, 0, 0, 0, 0, 1}), {0, 0, 0.333}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link2"), pose(rows({0, 0, -1, 1, 0, 0, 0, -1, 0}), {0, 0, 0.333}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link3"), pose(rows({0, -1, 0, 1, 0, 0, 0, 0, 1}), {0, 0, 0.649}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link4"), pose(rows({0, 0, 1, 0, 1, 0, -1, 0, 0}), {0, 0.0825, 0.649}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link5"), pose(rows({0, -1, 0, 0, 0, 1, -1, 0, 0}), {0, 0.4665, 0.7315}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link6"), pose(rows({0, 0, 1, 1, 0, 0, 0, 1, 0}), {0, 0.4665, 0.7315}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_link7"), pose(rows({kC, kC, 0, kC, -kC, 0, 0, 0, -1}), {0, 0.5545, 0.7315}), 1e-12));
  const Eigen::Matrix3d hand = rows({0, 1, 0, 1, 0, 0, 0, 0, -1});
  EXPECT_TRUE(expect_matrix_near(at("panda_hand"), pose(hand, {0, 0.5545, 0.6245}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_hand_tcp"), pose(hand, {0, 0.5545, 0.5211}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_leftfinger"), pose(hand, {0.02, 0.5545, 0.5661}), 1e-12));
  EXPECT_TRUE(expect_matrix_near(at("panda_rightfinger"), pose(hand, {-0.02, 0.5545, 0.5661}), 1e-12));
}

// Reads the vertices of a binary STL (80-byte header, uint32 count, 50 bytes per triangle: normal,
// three corners as float32, uint16 attribute), three per triangle in file order.
std::vector<Eigen::Vector3d> read_binary_stl(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);
  EXPECT_EQ(bytes.size(), 84 + 50 * static_cast<std::size_t>(count));
  std::vector<Eigen::Vector3d> vertices;
  for (std::size_t t = 0; t < count; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      float xyz[3];
      std::memcpy(xyz, bytes.data() + 84 + 50 * t + 12 + 12 * k, 12);
      vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
  }
  return vertices;
}

// The rest mesh of a link is its STL, read here directly, placed at the link's rest transform;
// weights are one-hot on the link's bone.
TEST(Urdf, PandaRestMeshAndRigidWeights) {
  const Robot& robot = panda();
  const Mesh& mesh = robot.rig.mesh;
  const std::int32_t link = robot.find_link("panda_link3");
  const std::int32_t part = robot.links[static_cast<std::size_t>(link)].part;
  const std::vector<Eigen::Vector3d> stl = read_binary_stl(panda_dir() / "meshes/collision/link3.stl");
  ASSERT_FALSE(stl.empty());
  std::size_t checked = 0;
  for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.vertex_part[static_cast<std::size_t>(v)] != part) continue;
    const Eigen::Vector3d& p = stl[static_cast<std::size_t>(mesh.vertex_index_in_part[static_cast<std::size_t>(v)])];
    // link3 at rest: identity rotation, translation (0, 0, 0.649) — computed by hand above.
    const Eigen::RowVector3d expected(p.x(), p.y(), p.z() + 0.649);
    EXPECT_TRUE(expect_matrix_near(mesh.rest_positions.row(v), expected, 1e-12)) << v;
    ++checked;
  }
  EXPECT_EQ(checked, stl.size());
  const SkinWeights& w = robot.rig.weights;
  ASSERT_EQ(w.rows(), mesh.num_vertices());
  ASSERT_EQ(w.cols(), robot.rig.skeleton.num_bones());
  for (Eigen::Index v = 0; v < w.rows(); ++v) {
    ASSERT_EQ(w.row(v).nonZeros(), 1);
    const std::int32_t p = mesh.vertex_part[static_cast<std::size_t>(v)];
    for (SkinWeights::InnerIterator it(w, v); it; ++it) {
      EXPECT_EQ(it.value(), 1.0);
      EXPECT_EQ(robot.rig.skeleton.bones[static_cast<std::size_t>(it.col())].name, mesh.part_names[static_cast<std::size_t>(p)]);
    }
  }
  // Skeleton node rest_local = joint origin; bone inverse bind = inverse rest transform.
  const auto rest = forward_kinematics(robot, std::vector<double>(robot.joints.size(), 0.0));
  for (const Bone& b : robot.rig.skeleton.bones) {
    EXPECT_TRUE(expect_matrix_near((rest[static_cast<std::size_t>(b.node)] * b.inverse_bind).matrix(),
                                   Eigen::Matrix4d::Identity(), 1e-12)) << b.name;
  }
}

TEST(Urdf, PackageAndRelativePathsResolveToTheSameMeshes) {
  const Robot& a = panda();
  const Robot b = load_urdf(panda_resolved());
  ASSERT_EQ(a.rig.mesh.num_vertices(), b.rig.mesh.num_vertices());
  EXPECT_TRUE(expect_matrix_near(a.rig.mesh.rest_positions, b.rig.mesh.rest_positions, 0.0));
  EXPECT_EQ(a.rig.mesh.triangles, b.rig.mesh.triangles);
  EXPECT_EQ(a.rig.mesh.part_names, b.rig.mesh.part_names);

  // A copy of the URDF outside the package tree needs --package-path.
  const fs::path dir = test::temp_dir("urdf_package_path");
  fs::copy_file(panda_urdf(), dir / "panda.urdf");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "panda.urdf"), IoError, "package://example-robot-data/robots/panda_description/meshes/collision/link0.stl");
  UrdfOptions options;
  options.package_path = {asset("robots")};
  const Robot c = load_urdf(dir / "panda.urdf", options);
  EXPECT_TRUE(expect_matrix_near(a.rig.mesh.rest_positions, c.rig.mesh.rest_positions, 0.0));
}

TEST(Urdf, ExcludedPairs) {
  const Robot& robot = panda();
  const Mesh& mesh = robot.rig.mesh;
  const auto part = [&](const char* link) { return robot.links[static_cast<std::size_t>(robot.find_link(link))].part; };
  const auto excluded = [&](const char* a, const char* b) {
    const std::int32_t pa = std::min(part(a), part(b));
    const std::int32_t pb = std::max(part(a), part(b));
    return std::find(mesh.excluded_part_pairs.begin(), mesh.excluded_part_pairs.end(), std::pair{pa, pb}) !=
           mesh.excluded_part_pairs.end();
  };
  for (std::int32_t p = 0; p < mesh.num_parts(); ++p) {
    EXPECT_NE(std::find(mesh.excluded_part_pairs.begin(), mesh.excluded_part_pairs.end(), std::pair{p, p}),
              mesh.excluded_part_pairs.end());
  }
  EXPECT_TRUE(excluded("panda_link0", "panda_link1"));
  EXPECT_TRUE(excluded("panda_link6", "panda_link7"));
  EXPECT_TRUE(excluded("panda_link7", "panda_hand"));  // through link8, which has no geometry
  EXPECT_TRUE(excluded("panda_hand", "panda_leftfinger"));
  EXPECT_FALSE(excluded("panda_link0", "panda_link2"));  // not adjacent; the SRDF disables it
  EXPECT_FALSE(excluded("panda_hand", "panda_link1"));
  EXPECT_FALSE(excluded("panda_leftfinger", "panda_rightfinger"));
  // 11 self pairs + 10 parent-child pairs (link0-1 ... link6-7, link7-hand, hand-fingers).
  EXPECT_EQ(mesh.excluded_part_pairs.size(), 11U + 10U);

  UrdfOptions options;
  options.srdf = panda_srdf();
  const Robot with_srdf = load_urdf(panda_urdf(), options);
  const auto& pairs = with_srdf.rig.mesh.excluded_part_pairs;
  const auto has = [&](const char* a, const char* b) {
    const std::int32_t pa = std::min(part(a), part(b));
    const std::int32_t pb = std::max(part(a), part(b));
    return std::find(pairs.begin(), pairs.end(), std::pair{pa, pb}) != pairs.end();
  };
  EXPECT_TRUE(has("panda_link0", "panda_link2"));
  EXPECT_TRUE(has("panda_leftfinger", "panda_rightfinger"));
  EXPECT_FALSE(has("panda_hand", "panda_link1"));  // the SRDF leaves hand vs links 0-2 checked
  EXPECT_FALSE(has("panda_hand", "panda_link0"));
  // The SRDF has 35 pairs, 10 of them parent-child already (link0-1 … link6-7, hand-link7,
  // hand-fingers); none names link8 or hand_tcp.
  EXPECT_EQ(read_srdf_disabled_collisions(panda_srdf()).size(), 35U);
  EXPECT_EQ(pairs.size(), 11U + 10U + 35U - 10U);
}

TEST(Urdf, PrimitiveTessellation) {
  const fs::path dir = test::temp_dir("urdf_primitives");
  write_file(dir / "prims.urdf", R"(<robot name="prims">
  <link name="base"><collision><geometry><box size="1 2 3"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 1"/><geometry><cylinder radius="0.5" length="2"/></geometry></collision>
    <visual><geometry><sphere radius="9"/></geometry></visual></link>
  <link name="ball"><visual><geometry><sphere radius="0.25"/></geometry></visual></link>
  <joint name="j" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 2"/></joint>
  <joint name="k" type="prismatic"><parent link="arm"/><child link="ball"/><origin xyz="0 0 3"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>)");
  UrdfOptions options;
  options.round_segments = 16;
  options.sphere_rings = 8;
  const Robot robot = load_urdf(dir / "prims.urdf", options);
  const Mesh& mesh = robot.rig.mesh;
  ASSERT_EQ(mesh.num_parts(), 3);
  const auto faces = [&](std::int32_t p) { return std::count(mesh.face_part.begin(), mesh.face_part.end(), p); };
  EXPECT_EQ(faces(0), 12);
  EXPECT_EQ(faces(1), 4 * 16);          // collision cylinder; the visual sphere is ignored
  EXPECT_EQ(faces(2), 2 * 16 * (8 - 1));  // visual geometry when there is no collision geometry
  EXPECT_EQ(mesh.num_vertices(), 8 + (2 * 16 + 2) + (2 + 16 * 7));
  // Every vertex lies on its primitive: box corners at (+-0.5, +-1, +-1.5); cylinder radius 0.5,
  // z in [0, 2]; sphere radius 0.25 around (0, 0, 3).
  for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.rest_positions.row(v).transpose();
    switch (mesh.vertex_part[static_cast<std::size_t>(v)]) {
      case 0: EXPECT_TRUE(expect_matrix_near(p.cwiseAbs(), Eigen::Vector3d(0.5, 1.0, 1.5), 0.0)); break;
      case 1:
        EXPECT_TRUE(std::abs(p.head<2>().norm() - 0.5) < 1e-15 || p.head<2>().norm() == 0.0);
        EXPECT_TRUE(p.z() == 0.0 || p.z() == 2.0);
        break;
      default: EXPECT_NEAR((p - Eigen::Vector3d(0, 0, 3)).norm(), 0.25, 1e-15);
    }
  }
  // Closed and outward: the signed volume of each part is positive (box 6, cylinder < pi/2).
  std::vector<double> volume(3, 0.0);
  for (Eigen::Index f = 0; f < mesh.num_triangles(); ++f) {
    const Eigen::Vector3d a = mesh.rest_positions.row(mesh.triangles(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.rest_positions.row(mesh.triangles(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.rest_positions.row(mesh.triangles(f, 2)).transpose();
    volume[static_cast<std::size_t>(mesh.face_part[static_cast<std::size_t>(f)])] += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(volume[0], 6.0, 1e-12);
  EXPECT_GT(volume[1], 0.9 * kPi / 2);
  EXPECT_LT(volume[1], kPi / 2);
  EXPECT_GT(volume[2], 0.0);
  // The axis is normalised; continuous has no limits; prismatic moves along x.
  const RobotJoint& j = robot.joints[static_cast<std::size_t>(robot.find_joint("j"))];
  EXPECT_EQ(j.axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_FALSE(j.has_limits);
  std::vector<double> q(robot.joints.size(), 0.0);
  q[static_cast<std::size_t>(robot.find_joint("j"))] = kPi / 2;
  q[static_cast<std::size_t>(robot.find_joint("k"))] = 0.5;
  const auto world = forward_kinematics(robot, q);
  // ball: Rz(90) then (0,0,3) then +0.5 along the arm's x, which is world y.
  EXPECT_TRUE(expect_matrix_near(world[static_cast<std::size_t>(robot.find_link("ball"))].translation(),
                                 Eigen::Vector3d(0, 0.5, 3), 1e-15));
}

TEST(Urdf, BadInput) {
  const fs::path dir = test::temp_dir("urdf_bad");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "none.urdf"), IoError, "none.urdf");

  write_file(dir / "missing_mesh.urdf", R"(<robot name="r">
  <link name="a"><collision><geometry><mesh filename="meshes/nothere.stl"/></geometry></collision></link></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "missing_mesh.urdf"), IoError, "missing_mesh.urdf: link 'a': mesh file 'meshes/nothere.stl' not found");

  write_file(dir / "cycle.urdf", R"(<robot name="r"><link name="root"/><link name="a"/><link name="b"/>
  <joint name="j0" type="fixed"><parent link="root"/><child link="a"/></joint>
  <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "cycle.urdf"), InvalidInput, "cycle.urdf: link 'a' has two parents (joints 'j0' and 'j2')");

  write_file(dir / "ring.urdf", R"(<robot name="r"><link name="root"/><link name="a"/><link name="b"/>
  <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "ring.urdf"), InvalidInput, "ring.urdf: joint cycle through links");

  write_file(dir / "unknown.urdf", R"(<robot name="r"><link name="a"/>
  <joint name="j" type="fixed"><parent link="a"/><child link="zz"/></joint></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "unknown.urdf"), InvalidInput, "unknown.urdf: joint 'j' names unknown child link 'zz'");

  write_file(dir / "bad.urdf", R"(<robot name="r"><link name="a">)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "bad.urdf"), IoError, "bad.urdf: not well-formed XML");

  write_file(dir / "floating.urdf", R"(<robot name="r"><link name="a"/><link name="b"/>
  <joint name="f" type="floating"><parent link="a"/><child link="b"/></joint></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "floating.urdf"), InvalidInput, "floating.urdf: joint 'f' has an unsupported type");

  write_file(dir / "zero_axis.urdf", R"(<robot name="r"><link name="a"/><link name="b"/>
  <joint name="z" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "zero_axis.urdf"), InvalidInput, "zero_axis.urdf: joint 'z' has a zero");

  // A mesh with a NaN coordinate (ASCII OBJ) is refused naming the URDF, link and mesh.
  write_file(dir / "nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
  write_file(dir / "nan.urdf", R"(<robot name="r">
  <link name="a"><collision><geometry><mesh filename="nan.obj"/></geometry></collision></link></robot>)");
  EXPECT_THROW_MESSAGE((void)load_urdf(dir / "nan.urdf"), InvalidInput, "nan.urdf: link 'a': mesh");

  // An SRDF naming a link the robot does not have.
  write_file(dir / "wrong.srdf", R"(<robot name="panda"><disable_collisions link1="panda_link0" link2="nope"/></robot>)");
  UrdfOptions options;
  options.srdf = dir / "wrong.srdf";
  EXPECT_THROW_MESSAGE((void)load_urdf(panda_urdf(), options), InvalidInput, "wrong.srdf: <disable_collisions> names link 'nope'");
  write_file(dir / "broken.srdf", R"(<robot name="panda"><disable_collisions link1="a")");
  options.srdf = dir / "broken.srdf";
  EXPECT_THROW_MESSAGE((void)load_urdf(panda_urdf(), options), IoError, "broken.srdf: not well-formed XML");
}

// Found by fuzz/fuzz_srdf (docs/fuzzing.md): with an <?xml?> declaration TinyXML reads UTF-8 and
// steps over the 2 bytes a lead byte 0xdb announces even when the text ends after it, reading past
// the buffer. Cut short by the end, or by a NUL (past which it used to read on and accept the
// unterminated attribute as link2 "b\xdb"), the SRDF is refused.
TEST(Urdf, SrdfWithATruncatedUtf8SequenceIsRefused) {
  const std::string head =
      R"(<?xml version="1.0"?><robot name="r"><disable_collisions link1="a" link2="b)";
  EXPECT_THROW_MESSAGE(
      (void)parse_srdf_disabled_collisions(head + "\xdb", "cut.srdf"),
      IoError,
      "cut.srdf: not well-formed XML");
  EXPECT_THROW_MESSAGE(
      (void)parse_srdf_disabled_collisions(
          head + "\xdb" + std::string(1, '\0') + "c\"/></robot>", "nul.srdf"),
      IoError,
      "nul.srdf: not well-formed XML: a NUL byte at offset 76");
  // UTF-8 that is whole still reads as before.
  const auto pairs = parse_srdf_disabled_collisions(head + "\xc3\xa9\"/></robot>", "ok.srdf");
  ASSERT_EQ(pairs.size(), 1U);
  EXPECT_EQ(pairs[0].link2, "b\xc3\xa9");
}

TEST(Urdf, MeshScaleAndMultipleElements) {
  const fs::path dir = test::temp_dir("urdf_scale");
  write_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write_file(dir / "scaled.urdf", R"(<robot name="r"><link name="a">
  <collision><origin xyz="0 0 1"/><geometry><mesh filename="tri.obj" scale="2 3 4"/></geometry></collision>
  <collision><geometry><mesh filename="file://)" + (dir / "tri.obj").string() + R"("/></geometry></collision>
  </link></robot>)");
  const Robot robot = load_urdf(dir / "scaled.urdf");
  const Mesh& mesh = robot.rig.mesh;
  ASSERT_EQ(mesh.num_vertices(), 6);
  ASSERT_EQ(mesh.num_triangles(), 2);
  EXPECT_EQ(mesh.num_parts(), 1);
  Positions expected(6, 3);
  expected << 0, 0, 1, 2, 0, 1, 0, 3, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0;
  EXPECT_TRUE(expect_matrix_near(mesh.rest_positions, expected, 0.0));
  EXPECT_EQ(mesh.vertex_index_in_part, (std::vector<std::int32_t>{0, 1, 2, 3, 4, 5}));
}

}  // namespace
}  // namespace skelcd::skinning
