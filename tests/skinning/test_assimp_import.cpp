// Importing real models: counts against what `assimp info` reports for the same files, the bind
// pose reproduced by skinning, weights normalised, unit scale, rigid parts, a hand-computed pose
// of glTF2/simple_skin, and the bad-input corpus (each an error naming the file, never a crash).
//
// Reference numbers were read off `assimp info FILE` (default post-processing) and
// `assimp info FILE -r` (raw) from assimp-utils 5.2.5:
//   file                              Faces (triangulated)  Bones(-r)  Animations  Vertices(-r)
//   X/BCN_Epileptic.X                 5126                  54         1           15378
//   X/Testwuson.X                     3732                  37         3           11196
//   X/anim_test.x                     840                   4          1           2520
//   FBX/animation_with_skeleton.fbx   2112                  14         1           4224
//   glTF2/simple_skin/simple_skin.gltf 8                    2          1           10
//   characters/CesiumMan.glb          4672                  19         1           3273
//   characters/Fox.glb                576                   24         3           1728
//   characters/RiggedFigure.glb       256                   19         1           370
//   characters/RobotExpressive.glb    3237 (-r)             172 = 4 skinned meshes × 43 joints  14  7214
// `assimp info` counts bones per mesh; a Rig counts distinct bones, which is the same number
// for every file here except RobotExpressive, whose four skinned meshes share one 43-joint
// skeleton (two skins of the same 43 joints in the glTF).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "skinning/assimp_import.hpp"
#include "skinning/errors.hpp"
#include "skinning/lbs.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;

struct Expected {
  std::string file;  // under the assimp models folder, or "assets/…" for our own
  std::int64_t triangles;
  std::int32_t bones;
  std::size_t clips;
  std::int64_t raw_vertices;  // with join_identical_vertices = false
};

std::filesystem::path resolve(const std::string& file) {
  return file.rfind("assets/", 0) == 0 ? asset(file.substr(7)) : assimp_model(file);
}

class RealModel : public ::testing::TestWithParam<Expected> {};

TEST_P(RealModel, CountsAgreeWithAssimpInfo) {
  const auto& e = GetParam();
  const auto imported = import_rig(resolve(e.file));
  const Rig& rig = imported.rig;
  EXPECT_EQ(rig.mesh.num_triangles(), e.triangles);
  EXPECT_EQ(rig.skeleton.num_bones(), e.bones);
  EXPECT_EQ(rig.clips.size(), e.clips);
  const auto raw = import_rig(resolve(e.file), ImportOptions{.join_identical_vertices = false});
  EXPECT_EQ(raw.rig.mesh.num_vertices(), e.raw_vertices);
  EXPECT_EQ(raw.rig.mesh.num_triangles(), e.triangles);
}

TEST_P(RealModel, BindPoseReproducesTheBindPositions) {
  const auto& e = GetParam();
  const auto rig = std::make_shared<const Rig>(import_rig(resolve(e.file)).rig);
  const RigMotion bind(rig);  // no clip: the bind pose
  Positions posed;
  bind.positions(0, posed);
  const double scale = rig->mesh.rest_positions.cwiseAbs().maxCoeff();
  const double error = (posed - rig->mesh.rest_positions).cwiseAbs().maxCoeff() / scale;
  EXPECT_LE(error, 1e-12) << e.file;
}

TEST_P(RealModel, WeightsAreNormalisedAndBonesWellFormed) {
  const auto& e = GetParam();
  const Rig rig = import_rig(resolve(e.file)).rig;
  ASSERT_EQ(rig.weights.rows(), rig.mesh.num_vertices());
  ASSERT_EQ(rig.weights.cols(), rig.skeleton.num_bones());
  for (Eigen::Index v = 0; v < rig.weights.rows(); ++v) {
    double sum = 0;
    for (SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
      EXPECT_GT(it.value(), 0.0);
      sum += it.value();
    }
    if (rig.weights.row(v).nonZeros() > 0) {
      EXPECT_NEAR(sum, 1.0, 1e-14) << e.file << " vertex " << v;
    }
  }
  // Bones sorted parents first, each parent bone's node an ancestor of its own.
  const auto& nodes = rig.skeleton.nodes;
  for (std::int32_t b = 0; b < rig.skeleton.num_bones(); ++b) {
    const auto& bone = rig.skeleton.bones[std::size_t(b)];
    EXPECT_LT(bone.parent, b);
    if (bone.parent >= 0) {
      bool ancestor = false;
      for (auto n = nodes[std::size_t(bone.node)].parent; n >= 0; n = nodes[std::size_t(n)].parent) {
        ancestor |= n == rig.skeleton.bones[std::size_t(bone.parent)].node;
      }
      EXPECT_TRUE(ancestor) << e.file << " bone " << bone.name;
    }
    EXPECT_GT((bone.rest_tail - bone.rest_head).norm(), 0.0) << e.file << " bone " << bone.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    AssimpTestModelsAndBundledCharacters,
    RealModel,
    ::testing::Values(
        Expected{"X/BCN_Epileptic.X", 5126, 54, 1, 15378},
        Expected{"X/Testwuson.X", 3732, 37, 3, 11196},
        Expected{"X/anim_test.x", 840, 4, 1, 2520},
        Expected{"FBX/animation_with_skeleton.fbx", 2112, 14, 1, 4224},
        Expected{"glTF2/simple_skin/simple_skin.gltf", 8, 2, 1, 10},
        Expected{"assets/characters/CesiumMan.glb", 4672, 19, 1, 3273},
        Expected{"assets/characters/Fox.glb", 576, 24, 3, 1728},
        Expected{"assets/characters/RiggedFigure.glb", 256, 19, 1, 370},
        Expected{"assets/characters/RobotExpressive.glb", 3237, 43, 14, 7214}),
    [](const auto& param_info) {
      std::string name = std::filesystem::path(param_info.param.file).stem().string();
      for (auto& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

// The import joins identical vertices with assimp's step and moves the bones' weights itself
// (linear; assimp 5.2.4's step is quadratic in a bone's weights). What it gives must be what
// assimp's own step gives, bit for bit — the vertices, the triangles, the weights after
// normalising (a weight moved twice onto one joined vertex would double that bone's share), the
// problems — or the same refusal, on every rigged real model at hand: the Debian models with
// bones and the bundled characters, up to the 28k-triangle CesiumMan copy.
TEST(AssimpImport, JoiningMovesTheWeightsAsAssimpDoes) {
  const std::vector<std::string> files = {
      "X/BCN_Epileptic.X",
      "X/Testwuson.X",
      "X/anim_test.x",
      "X/test_cube_text.x",
      "FBX/animation_with_skeleton.fbx",
      "FBX/huesitos.fbx",
      "SMD/WusonSMD.smd",
      "MD5/SimpleCube.md5mesh",
      "Collada/box_nested_animation.dae",
      "glTF2/simple_skin/simple_skin.gltf",
      "assets/characters/CesiumMan.glb",
      "assets/characters/CesiumMan-dense.glb",
      "assets/characters/Fox.glb",
      "assets/characters/RiggedFigure.glb",
      "assets/characters/RobotExpressive.glb",
      "assets/characters/stormtrooper/stormtrooper.dae",
      "assets/characters/ninja/ninja.mesh",
  };
  std::int64_t compared = 0;
  for (const std::string& file : files) {
    const auto import = [&](bool assimp_moves_weights) -> std::pair<ImportedRig, std::string> {
      try {
        return {
            import_rig(resolve(file), ImportOptions{.assimp_moves_weights = assimp_moves_weights}),
            ""};
      } catch (const std::exception& e) {
        return {ImportedRig{}, e.what()};
      }
    };
    const auto [ours, our_error] = import(false);
    const auto [assimps, assimp_error] = import(true);
    EXPECT_EQ(our_error, assimp_error) << file;
    if (!our_error.empty() || !assimp_error.empty()) continue;
    const Mesh& a = ours.rig.mesh;
    const Mesh& b = assimps.rig.mesh;
    ASSERT_EQ(a.num_vertices(), b.num_vertices()) << file;
    ASSERT_EQ(a.num_triangles(), b.num_triangles()) << file;
    EXPECT_TRUE((a.rest_positions.array() == b.rest_positions.array()).all()) << file;
    EXPECT_TRUE((a.triangles.array() == b.triangles.array()).all()) << file;
    EXPECT_EQ(ours.rig.weights.nonZeros(), assimps.rig.weights.nonZeros()) << file;
    EXPECT_TRUE(ours.rig.weights.isApprox(assimps.rig.weights, 0.0)) << file;
    EXPECT_EQ(ours.problems, assimps.problems) << file;
    compared += ours.rig.weights.nonZeros() > 0;
  }
  EXPECT_GE(compared, 12);  // most of them import, with weights
}

TEST(AssimpImport, BcnEpilepticPartsClipAndRestPose) {
  const auto imported = import_rig(assimp_model("X/BCN_Epileptic.X"));
  const Rig& rig = imported.rig;
  // assimp info: meshes Torso 1966, Head 2036, Legs 1124 faces.
  ASSERT_EQ(rig.mesh.part_names, (std::vector<std::string>{"Torso", "Head", "Legs"}));
  std::vector<int> per_part(3, 0);
  for (auto p : rig.mesh.face_part) ++per_part[std::size_t(p)];
  EXPECT_EQ(per_part, (std::vector<int>{1966, 2036, 1124}));
  ASSERT_EQ(rig.clips.size(), 1u);
  EXPECT_EQ(rig.clips[0].name, "Epileptisch");
  EXPECT_DOUBLE_EQ(rig.clips[0].duration_s, 15840.0 / 4800.0);  // ticks / ticks per second
  // The file stores its hierarchy in the bind pose: the node rest pose skins to the bind
  // positions up to the file's single precision.
  const PoseEvaluator evaluator(rig);
  const LinearBlendSkinning lbs(rig);
  Pose pose;
  Positions posed;
  evaluator.rest_pose(pose);
  lbs.apply(pose, posed);
  EXPECT_LT((posed - rig.mesh.rest_positions).rowwise().norm().maxCoeff(), 1e-5);
  EXPECT_LT(imported.rest_pose_deviation, 1e-5);
}

TEST(AssimpImport, ClipsOfTestwusonAndFox) {
  const Rig wuson = import_rig(assimp_model("X/Testwuson.X")).rig;
  ASSERT_EQ(wuson.clips.size(), 3u);
  EXPECT_EQ(wuson.clips[0].name, "Wuson_Run");
  EXPECT_EQ(wuson.clips[1].name, "Wuson_Walk");
  EXPECT_EQ(wuson.clips[2].name, "Wuson_Bind");
  EXPECT_DOUBLE_EQ(wuson.clips[1].duration_s, 17280.0 / 4800.0);
  EXPECT_EQ(wuson.clips[2].duration_s, 0.0);
  const Rig fox = import_rig(asset("characters/Fox.glb")).rig;
  ASSERT_EQ(fox.clips.size(), 3u);
  EXPECT_EQ(fox.clips[0].name, "Survey");
  EXPECT_EQ(fox.clips[1].name, "Walk");
  EXPECT_EQ(fox.clips[2].name, "Run");
  // glTF key times are in seconds; the Walk clip has 18 keys 1/24 s apart.
  EXPECT_NEAR(fox.clips[1].keys_per_s(), 24.0, 1e-4);
  EXPECT_EQ(fox.clips[1].key_times.size(), 18u);
}

// A check poses its welded vertices alone (tools/engine/runner.cpp, pose_sample): on the real
// characters, RigMotion::positions_of gives each representative vertex's row of the whole pose bit
// for bit, as the default Motion::positions_of (pose all, copy the rows) does, at the clip's first,
// middle and last samples; and it poses fewer vertices than the whole pose on at least one of them.
TEST(AssimpImport, PosingTheWeldedVerticesAloneGivesTheirRowsOfTheWholePose) {
  std::int64_t fewer = 0;
  for (const std::string file :
       {"assets/characters/CesiumMan-dense.glb",
        "assets/characters/Fox.glb",
        "assets/characters/stormtrooper/stormtrooper.dae",
        "X/BCN_Epileptic.X"}) {
    const auto rig = std::make_shared<const Rig>(import_rig(resolve(file)).rig);
    ASSERT_FALSE(rig->clips.empty()) << file;
    const RigMotion motion(rig, RigMotionOptions{.clip = 0});
    const Topology topology = build_topology(rig->mesh);
    const std::vector<std::int32_t>& rows = topology.representative_vertex;
    if (static_cast<Eigen::Index>(rows.size()) < rig->mesh.num_vertices()) ++fewer;
    Positions all;
    Positions some;
    Positions copied;
    for (const int i : {0, motion.num_samples() / 2, motion.num_samples() - 1}) {
      motion.positions(i, all);
      motion.positions_of(i, rows, some);
      motion.Motion::positions_of(i, rows, copied);
      ASSERT_EQ(some.rows(), static_cast<Eigen::Index>(rows.size())) << file;
      ASSERT_EQ(copied.rows(), some.rows()) << file;
      Eigen::Index differ = 0;
      for (std::size_t k = 0; k < rows.size(); ++k) {
        const auto r = static_cast<Eigen::Index>(k);
        if (some.row(r) != all.row(rows[k]) || copied.row(r) != some.row(r)) ++differ;
      }
      EXPECT_EQ(differ, 0) << file << " sample " << i;
    }
  }
  EXPECT_GE(fewer, 1);
}

TEST(AssimpImport, SimpleSkinPoseMatchesAHandComputation) {
  // glTF2/simple_skin: 10 vertices (x ∈ {0, 1}, y ∈ {0, 0.5, …, 2}), joints node 1 at (0,1,0)
  // and its child node 2; both inverse bind matrices translate by (-0.5, -1, 0). Node 2 rotates
  // about z; at t = 1 s its key is (0, 0, 0.707, 0.707): 90°.
  const auto rig = std::make_shared<const Rig>(import_rig(assimp_model("glTF2/simple_skin/simple_skin.gltf")).rig);
  ASSERT_EQ(rig->mesh.num_vertices(), 10);
  const RigMotion motion(rig, RigMotionOptions{.clip = 0});
  Positions posed;
  // Vertex (1, 2, 0) hangs on node 2 alone: T(0,1,0)·Rz(90°)·T(-0.5,-1,0)·(1,2,0) = (-1, 1.5, 0).
  // Vertex (0, 1, 0) is half node 1: T(0,1,0)·T(-0.5,-1,0)·(0,1,0) = (-0.5, 1, 0), half node 2:
  // T(0,1,0)·Rz(90°)·(-0.5, 0, 0) = (0, 0.5, 0); blended (-0.25, 0.75, 0).
  motion.positions_at_time(1.0, posed);
  const auto find = [&](double x, double y) {
    for (Eigen::Index v = 0; v < 10; ++v) {
      if (rig->mesh.rest_positions(v, 0) == x && rig->mesh.rest_positions(v, 1) == y) return v;
    }
    return Eigen::Index(-1);
  };
  const auto top = find(1, 2);
  const auto middle = find(0, 1);
  ASSERT_GE(top, 0);
  ASSERT_GE(middle, 0);
  // Tolerance: the file's quaternion (0.70710677 in float) is 90° to ~1e-7.
  EXPECT_TRUE(skelcd::test::expect_matrix_near(posed.row(top), Eigen::RowVector3d(-1, 1.5, 0), 1e-6));
  EXPECT_TRUE(skelcd::test::expect_matrix_near(posed.row(middle), Eigen::RowVector3d(-0.25, 0.75, 0), 1e-6));
  // Halfway between the keys at 0 s (identity) and 0.5 s (q1 = (0, 0, 0.383, 0.924) as stored):
  // slerp gives a rotation by φ = atan2(0.383, 0.924) (half of q1's angle 2φ).
  motion.positions_at_time(0.25, posed);
  const double phi = std::atan2(static_cast<double>(0.383f), static_cast<double>(0.924f));
  const Eigen::Vector2d local(0.5, 1.0);  // (1,2,0) after T(-0.5,-1,0)
  const Eigen::RowVector3d expected(std::cos(phi) * local.x() - std::sin(phi) * local.y(),
                                    1.0 + std::sin(phi) * local.x() + std::cos(phi) * local.y(), 0.0);
  EXPECT_TRUE(skelcd::test::expect_matrix_near(posed.row(top), expected, 1e-6));
}

TEST(AssimpImport, FbxUnitScaleIsApplied) {
  // huesitos.fbx declares UnitScaleFactor 1 (centimetres). `assimp info` reports its bounding
  // box in file units: (-105.841469 0.349106 -528.864929) to (429.930786 544.186401 -207.329895).
  const auto imported = import_rig(assimp_model("FBX/huesitos.fbx"));
  EXPECT_DOUBLE_EQ(imported.unit_scale, 0.01);
  const auto& p = imported.rig.mesh.rest_positions;
  const Eigen::RowVector3d lo = p.colwise().minCoeff();
  const Eigen::RowVector3d hi = p.colwise().maxCoeff();
  EXPECT_TRUE(skelcd::test::expect_matrix_near(lo, Eigen::RowVector3d(-1.05841469, 0.00349106, -5.28864929), 1e-6));
  EXPECT_TRUE(skelcd::test::expect_matrix_near(hi, Eigen::RowVector3d(4.29930786, 5.44186401, -2.07329895), 1e-6));
  const auto unscaled = import_rig(assimp_model("FBX/huesitos.fbx"), ImportOptions{.convert_to_metres = false});
  EXPECT_EQ(unscaled.unit_scale, 1.0);
  EXPECT_TRUE(skelcd::test::expect_matrix_near(unscaled.rig.mesh.rest_positions, p * 100.0, 1e-9));
}

TEST(AssimpImport, GltfMeshNodeTransformsPlaceTheMesh) {
  // `assimp info` bounding boxes (node transforms applied): Fox (-12.592718 -0.121745
  // -88.095001) to (12.592718 78.907188 66.624863).
  const auto& p = import_rig(asset("characters/Fox.glb")).rig.mesh.rest_positions;
  EXPECT_TRUE(skelcd::test::expect_matrix_near(p.colwise().minCoeff(), Eigen::RowVector3d(-12.592718, -0.121745, -88.095001), 1e-5));
  EXPECT_TRUE(skelcd::test::expect_matrix_near(p.colwise().maxCoeff(), Eigen::RowVector3d(12.592718, 78.907188, 66.624863), 1e-5));
}

TEST(AssimpImport, UnskinnedPartsFollowTheirNodesRigidly) {
  // RobotExpressive: 15 of its 19 meshes have no skin and hang from nodes of the skeleton.
  const auto imported = import_rig(asset("characters/RobotExpressive.glb"));
  const auto rig = std::make_shared<const Rig>(imported.rig);
  ASSERT_EQ(rig->part_attachments.size(), std::size_t(rig->mesh.num_parts()));
  const auto head = std::find(rig->mesh.part_names.begin(), rig->mesh.part_names.end(), "Head-1") - rig->mesh.part_names.begin();
  ASSERT_LT(head, rig->mesh.num_parts());
  const RigMotion dance(rig, RigMotionOptions{.clip = rig->find_clip("Dance")});
  Positions posed;
  dance.positions(dance.num_samples() / 3, posed);
  // The head moved, and every distance between two of its vertices is unchanged.
  std::vector<Eigen::Index> vertices;
  for (Eigen::Index v = 0; v < rig->mesh.num_vertices(); ++v) {
    if (rig->mesh.vertex_part[std::size_t(v)] == head) vertices.push_back(v);
  }
  ASSERT_GT(vertices.size(), 10u);
  double moved = 0, worst = 0;
  for (std::size_t i = 0; i < vertices.size(); i += 7) {
    moved = std::max(moved, (posed.row(vertices[i]) - rig->mesh.rest_positions.row(vertices[i])).norm());
    for (std::size_t j = i + 1; j < vertices.size(); j += 13) {
      const double rest = (rig->mesh.rest_positions.row(vertices[i]) - rig->mesh.rest_positions.row(vertices[j])).norm();
      const double now = (posed.row(vertices[i]) - posed.row(vertices[j])).norm();
      worst = std::max(worst, std::abs(now - rest));
    }
  }
  EXPECT_GT(moved, 1e-3);
  EXPECT_LT(worst, 1e-5);  // single-precision keys: rotations are unit to ~1e-7
  // The three degenerate triangles assimp's FindDegenerates turns into lines are ours to report.
  const auto topo = build_topology(rig->mesh);
  EXPECT_EQ(topo.degenerate_triangles.size(), 3u);
}

TEST(AssimpImport, AMissingBoneNodeStaysInItsBindPose) {
  // anim_test.x binds 'joint3' and 'joint4', which no frame of the file defines.
  const auto imported = import_rig(assimp_model("X/anim_test.x"));
  int reported = 0;
  for (const auto& p : imported.problems) reported += p.find("names no node") != std::string::npos;
  EXPECT_EQ(reported, 2);
  const auto rig = std::make_shared<const Rig>(imported.rig);
  const PoseEvaluator evaluator(*rig);
  Pose pose;
  evaluator.clip_pose(0, 0.5, pose);
  for (std::int32_t b = 0; b < rig->skeleton.num_bones(); ++b) {
    const auto& name = rig->skeleton.bones[std::size_t(b)].name;
    if (name == "joint3" || name == "joint4") {
      EXPECT_TRUE(skelcd::test::expect_matrix_near(pose.transforms[std::size_t(b)], BoneTransform::Identity(), 1e-12)) << name;
    }
  }
}

TEST(AssimpImport, WeldingRemovesTheUvSeamsOfARealModel) {
  // CesiumMan is closed, but its file splits vertices along UV seams: without welding, the
  // seams are boundaries.
  const auto mesh = import_rig(asset("characters/CesiumMan.glb")).rig.mesh;
  const auto welded = build_topology(mesh);
  EXPECT_TRUE(welded.boundary_edges.empty());
  ASSERT_EQ(welded.components.size(), 1u);
  EXPECT_TRUE(welded.components[0].closed);
  const auto raw = build_topology(mesh, WeldOptions{.weld = false});
  EXPECT_GT(raw.boundary_edges.size(), 100u);
  EXPECT_LT(welded.num_welded_vertices(), raw.num_welded_vertices());
}

TEST(AssimpImport, PointsAndLinesAreDroppedAndReported) {
  const auto dir = skelcd::test::temp_dir("import_lines");
  const auto file = dir / "quad_and_line.obj";
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 2 2\nf 1 2 3 4\nl 4 5\n";
  const auto imported = import_rig(file);
  EXPECT_EQ(imported.rig.mesh.num_triangles(), 2);
  bool reported = false;
  for (const auto& p : imported.problems) reported |= p.find("1 lines") != std::string::npos;
  EXPECT_TRUE(reported);
}

// --- bad input: each an exception of our types naming the file; none crashes -----------------

template <typename Error>
void expect_error(const std::filesystem::path& file, const std::string& fault) {
  try {
    (void)import_rig(file);
    ADD_FAILURE() << "no error for " << file;
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find(fault), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
  }
}

TEST(AssimpImportBadInput, GltfIndexOutOfRange) {
  // assimp drops the face with a warning; dropping data is an error for us.
  expect_error<InvalidInput>(assimp_model("glTF2/IndexOutOfRange/IndexOutOfRange.gltf"), "out-of-range");
  expect_error<IoError>(assimp_model("glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf"), "no faces");
}

TEST(AssimpImportBadInput, GltfBoxWithInfinites) {
  expect_error<InvalidInput>(assimp_model("glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"), "non-finite");
}

TEST(AssimpImportBadInput, GltfRecursiveNodes) {
  expect_error<IoError>(assimp_model("glTF2/RecursiveNodes/RecursiveNodes.gltf"), "recursive");
}

TEST(AssimpImportBadInput, GltfMissingBin) {
  expect_error<IoError>(assimp_model("glTF2/MissingBin/BoxTextured.gltf"), "BoxTextured0.bin");
}

TEST(AssimpImportBadInput, GltfSceneWrongType) {
  expect_error<IoError>(assimp_model("glTF2/SchemaFailures/sceneWrongType.gltf"), "scene");
}

TEST(AssimpImportBadInput, MissingEmptyAndDirectory) {
  const auto dir = skelcd::test::temp_dir("import_bad");
  expect_error<IoError>(dir / "nothing_here.glb", "no such file");
  const auto empty = dir / "empty.obj";
  std::ofstream{empty};
  expect_error<IoError>(empty, "empty file");
  expect_error<IoError>(dir, "is a directory");
  const auto garbage = dir / "garbage.glb";
  std::ofstream(garbage) << "this is not a model";
  expect_error<IoError>(garbage, garbage.string());
}

TEST(AssimpImportBadInput, NanCoordinatesInAnObj) {
  const auto dir = skelcd::test::temp_dir("import_nan");
  const auto file = dir / "nan.obj";
  std::ofstream(file) << "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n";
  expect_error<InvalidInput>(file, "vertex 1 has a non-finite coordinate");
}

}  // namespace
}  // namespace skelcd::skinning
