// Scene files: parsing and validation (one line naming the file and the line of the fault) and
// the plan (which stages run for which object).
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "skinning/errors.hpp"
#include "tests/support/test_support.hpp"
#include "tools/engine/scene.hpp"
#include "tools/engine/scene_plan.hpp"
#include "tools/report/scene_plan_report.hpp"

namespace skelcd::tools {
namespace {

/// Writes `text` as a scene file in a fresh temporary folder.
std::filesystem::path scene_in_assets(const std::string& text, const std::string& name = "t.toml") {
  const auto dir = test::temp_dir("scene");
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

/// The message of the InvalidInput that parsing `text` throws ("" if none).
std::string parse_error(const std::string& text) {
  const auto path = scene_in_assets(text);
  try {
    (void)parse_scene(path);
  } catch (const InvalidInput& e) {
    const std::string m = e.what();
    // Every scene error names the file and a line: "PATH:LINE: …", and is one line.
    EXPECT_EQ(m.rfind(path.string() + ":", 0), 0u) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m.substr(path.string().size() + 1);
  }
  return "";
}

const std::string kRig = test::asset("characters/RiggedFigure.glb").string();

TEST(SceneParse, ReadsObjectsChecksPairsAndOverrides) {
  const auto path = scene_in_assets(
      "output = \"out/log.h5\"\n"
      "frames = \"2:5\"\n"
      "accuracy = \"exact\"\n"
      "[objects.fig]\n"
      "model = \"" +
      kRig +
      "\"\n"
      "rate = 20\n"
      "checks = [\"self-dcd\", \"self-ccd\"]\n"
      "method = \"kdop\"\n"
      "[objects.rope]\n"
      "model = \"gen:rope?triangles=1000&frames=8\"\n"
      "offset = [1, 2, 3]\n"
      "accuracy = \"fast\"\n"
      "[objects.idle]\n"
      "model = \"gen:hand?triangles=1000\"\n"
      "[[pairs]]\n"
      "objects = [\"fig\", \"rope\"]\n"
      "checks = [\"ccd\"]\n");
  const Scene s = parse_scene(path);
  ASSERT_EQ(s.objects.size(), 3u);
  EXPECT_EQ(s.objects[0].name, "fig");  // file order, not TOML's sorted keys
  EXPECT_EQ(s.objects[1].name, "rope");
  EXPECT_EQ(s.objects[2].name, "idle");
  EXPECT_EQ(s.objects[0].line, 4);
  EXPECT_TRUE(s.objects[0].self_dcd && s.objects[0].self_ccd);
  EXPECT_EQ(s.objects[0].method, "kdop");
  EXPECT_EQ(s.objects[0].accuracy, ccd::Accuracy::exact);  // the scene's
  EXPECT_EQ(s.objects[0].rate_hz, 20);
  EXPECT_EQ(s.objects[1].method, "bvh");
  EXPECT_EQ(s.objects[1].accuracy, ccd::Accuracy::fast);
  EXPECT_EQ(s.objects[1].model, "gen:rope?triangles=1000&frames=8");
  EXPECT_EQ(s.objects[1].offset, Eigen::Vector3d(1, 2, 3));
  ASSERT_EQ(s.pairs.size(), 1u);
  EXPECT_TRUE(s.pairs[0].ccd);
  EXPECT_FALSE(s.pairs[0].dcd);
  EXPECT_EQ(s.pairs[0].line, 15);
  EXPECT_EQ(s.output, path.parent_path() / "out/log.h5");
  ASSERT_TRUE(s.frames.has_value());
  EXPECT_EQ(s.frames->first, 2);
  EXPECT_TRUE(s.is_checked("fig"));
  EXPECT_TRUE(s.is_checked("rope"));
  EXPECT_FALSE(s.is_checked("idle"));
}

TEST(SceneParse, RefusesEachFaultWithTheLineOfIt) {
  const std::string head = "[objects.a]\nmodel = \"" + kRig + "\"\n";
  // Missing file (line 2).
  EXPECT_EQ(parse_error("[objects.a]\nmodel = \"nowhere/missing.glb\"\n").substr(0, 2), "2:");
  EXPECT_NE(
      parse_error("[objects.a]\nmodel = \"nowhere/missing.glb\"\n")
          .find("missing.glb: no such file"),
      std::string::npos);
  // Unknown key (line 3), check (3), method (3), accuracy (3).
  EXPECT_EQ(parse_error(head + "clp = \"walk\"\n").substr(0, 24), "3: object 'a': unknown k");
  EXPECT_NE(
      parse_error(head + "checks = [\"self-dcd\", \"selfccd\"]\n")
          .find("3: object 'a': unknown check 'selfccd'"),
      std::string::npos);
  EXPECT_NE(
      parse_error(head + "method = \"octree\"\n").find("3: object 'a': unknown method 'octree'"),
      std::string::npos);
  EXPECT_NE(
      parse_error(head + "accuracy = \"sloppy\"\n")
          .find("3: object 'a': unknown accuracy 'sloppy'"),
      std::string::npos);
  // A pair naming an unknown object (line 4: the objects line).
  EXPECT_NE(
      parse_error(head + "[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\"]\n")
          .find("4: pair 1: unknown object 'b' (objects: a)"),
      std::string::npos);
  // Unknown pair check, a pair of one object with itself.
  EXPECT_NE(
      parse_error(head + "[[pairs]]\nobjects = [\"a\", \"a\"]\nchecks = [\"dcd\"]\n")
          .find("4: pair 1: 'a' against itself"),
      std::string::npos);
  EXPECT_NE(
      parse_error(
          head + "[objects.b]\nmodel = \"gen:rope\"\n[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = "
                 "[\"tcd\"]\n")
          .find("7: pair 1: unknown pair check 'tcd'"),
      std::string::npos);
  // Unknown top-level key, TOML syntax error, bad frames, bad generator spec, URDF keys on a rig.
  EXPECT_NE(
      parse_error("outptu = \"x.h5\"\n" + head).find("1: unknown key 'outptu'"), std::string::npos);
  EXPECT_EQ(parse_error(head + "checks = [\"self-dcd\"\n").substr(0, 2), "3:");
  EXPECT_NE(parse_error("frames = \"5:2\"\n" + head).find("1: "), std::string::npos);
  EXPECT_NE(
      parse_error("[objects.a]\nmodel = \"gen:nosuch\"\n").find("2: object 'a': "),
      std::string::npos);
  EXPECT_NE(
      parse_error(head + "trajectory = \"x.csv\"\n")
          .find("3: object 'a': 'trajectory' is only for a URDF"),
      std::string::npos);
  // A sheet needs attach_to naming a model object; a scene needs objects.
  EXPECT_NE(
      parse_error("[objects.s]\nsheet = { corner = [0,0,0], u = [1,0,0], v = [0,1,0] }\n")
          .find("object 's': a 'sheet' needs 'attach_to'"),
      std::string::npos);
  EXPECT_NE(
      parse_error(
          head + "[objects.s]\nsheet = { corner = [0,0,0], u = [1,0,0], v = [0,1,0] }\nattach_to = "
                 "\"zz\"\n")
          .find("5: object 's': 'attach_to' names unknown object 'zz'"),
      std::string::npos);
  EXPECT_NE(parse_error("method = \"bvh\"\n").find("no [objects.NAME] table"), std::string::npos);
  EXPECT_NE(
      parse_error(head + "method = \"dynamic\"\noffset = [1,0,0]\n")
          .find("3: object 'a': method 'dynamic' needs"),
      std::string::npos);
}

TEST(SceneParse, MissingSceneFileIsRefused) {
  EXPECT_THROW_MESSAGE(
      (void)parse_scene("/nonexistent/scene.toml"),
      InvalidInput,
      "/nonexistent/scene.toml: no such scene file");
}

TEST(SceneParse, RelativePathsResolveAgainstTheSceneFile) {
  // The bundled scenes name ../characters/… and ../robots/… relative to assets/scenes/.
  const Scene s = parse_scene(test::asset("scenes/panda.toml"));
  ASSERT_GE(s.objects.size(), 1u);
  EXPECT_TRUE(std::filesystem::exists(s.objects[0].model));
  EXPECT_TRUE(std::filesystem::exists(s.objects[0].load.trajectory));
  // `output` too: relative to the scene's folder.
  const auto path =
      scene_in_assets("output = \"../logs/x.h5\"\n[objects.a]\nmodel = \"gen:rope\"\n");
  EXPECT_EQ(parse_scene(path).output, (path.parent_path() / "../logs/x.h5").lexically_normal());
}

ObjectFacts facts(std::int32_t samples, std::int32_t open, std::int32_t closed, bool rig) {
  ObjectFacts f;
  f.samples = samples;
  f.open_components = open;
  f.closed_components = closed;
  f.auto_open_group = open;  // every open part large and uncapped
  f.auto_closed_group = closed;
  f.rig_motion = rig;
  return f;
}

TEST(ScenePlan, BuildsOnlyWhatTheChecksNeed) {
  const auto path = scene_in_assets(
      "[objects.dcd_only]\nmodel = \"gen:rope\"\nchecks = [\"self-dcd\"]\n"
      "[objects.ccd_auto]\nmodel = \"gen:cloth\"\nchecks = [\"self-ccd\"]\nmethod = \"auto\"\n"
      "[objects.closed_auto]\nmodel = \"gen:hand\"\nchecks = [\"self-ccd\"]\nmethod = \"auto\"\n"
      "[objects.dyn]\nmodel = \"gen:octopus\"\nchecks = [\"self-dcd\"]\nmethod = \"dynamic\"\n"
      "[objects.idle]\nmodel = \"gen:pipe\"\n"
      "[objects.paired]\nmodel = \"gen:rope\"\n"
      "[[pairs]]\nobjects = [\"paired\", \"dcd_only\"]\nchecks = [\"dcd\"]\n");
  const Scene s = parse_scene(path);
  const auto plan = plan_scene(
      s,
      {facts(10, 0, 1, true),
       facts(10, 1, 0, true),
       facts(10, 0, 1, true),
       facts(10, 0, 1, true),
       ObjectFacts{},
       facts(10, 0, 1, true)},
      std::nullopt);
  const auto& o = plan.objects;
  // DCD only: no swept bounds, no cones, no segmentation.
  EXPECT_TRUE(o[0].load && o[0].skin && o[0].bvh);
  EXPECT_FALSE(o[0].swept_bounds || o[0].cones || o[0].segmentation);
  // auto on an open part: cones, no segmentation; on a closed rig: segmentation, no cones.
  EXPECT_TRUE(o[1].cones && o[1].swept_bounds);
  EXPECT_FALSE(o[1].segmentation);
  EXPECT_TRUE(o[2].segmentation);
  EXPECT_FALSE(o[2].cones);
  // dynamic with self-dcd only: its DCD is bvh's, so nothing of the radial view is built.
  EXPECT_FALSE(o[3].segmentation);
  EXPECT_FALSE(o[3].swept_bounds);
  EXPECT_NE(
      std::find_if(
          o[3].skipped.begin(),
          o[3].skipped.end(),
          [](const std::string& why) { return why.rfind("segmentation: DCD only", 0) == 0; }),
      o[3].skipped.end());
  // Unchecked: not even loaded.
  EXPECT_FALSE(o[4].load || o[4].skin || o[4].topology || o[4].bvh);
  // Only in a DCD pair: posed, hierarchy, no swept bounds.
  EXPECT_TRUE(o[5].skin && o[5].bvh && o[5].checked);
  EXPECT_FALSE(o[5].swept_bounds || o[5].cones || o[5].segmentation);
  // Checks: four self checks in object order, then the pair; rows per query.
  ASSERT_EQ(plan.checks.size(), 5u);
  EXPECT_EQ(plan.checks[0].rows, 10);  // DCD: a row per sample
  EXPECT_EQ(plan.checks[1].rows, 9);   // CCD: a row per interval
  EXPECT_EQ(plan.checks[4].kind, CheckKind::pair);
  EXPECT_EQ(plan.checks[4].name(plan.objects), "pair paired dcd_only");
  EXPECT_EQ(plan.rows, 10 + 9 + 9 + 10 + 10);
  // auto on a closed part that no skeleton moves: no segmentation, and the plan says why.
  const auto no_rig = plan_scene(
      s,
      {facts(10, 0, 1, true),
       facts(10, 1, 0, true),
       facts(10, 0, 1, false),
       facts(10, 0, 1, true),
       ObjectFacts{},
       facts(10, 0, 1, true)},
      std::nullopt);
  EXPECT_FALSE(no_rig.objects[2].segmentation);
  const auto json = plan_json(no_rig);
  EXPECT_EQ(json["objects"][4]["stages"]["load"], false);
  EXPECT_EQ(json["objects"][0]["stages"]["swept_bounds"], false);
}

TEST(ScenePlan, AutoRunsConesAndSegmentsOnlyForTheGroupsItFills) {
  // What `auto` makes of an object (culling::auto_groups) decides its cones and its segmentation,
  // not whether it has open or closed parts at all.
  const auto path = scene_in_assets(
      "[objects.a]\nmodel = \"gen:rope\"\nchecks = [\"self-ccd\"]\nmethod = \"auto\"\n");
  const Scene s = parse_scene(path);
  const auto plan_of = [&](const ObjectFacts& f) {
    return plan_scene(s, {f}, std::nullopt).objects[0];
  };
  const auto skipped = [](const ObjectPlan& o, const std::string& start) {
    return std::any_of(o.skipped.begin(), o.skipped.end(), [&](const std::string& why) {
      return why.rfind(start, 0) == 0;
    });
  };
  // Open and closed components, and what auto's groups get of them.
  const auto groups =
      [](std::int32_t open, std::int32_t closed, std::int32_t to_cones, bool whole) {
        ObjectFacts f = facts(10, open, closed, true);
        f.auto_open_group = to_cones;
        f.auto_closed_group = open + closed - to_cones;
        f.auto_whole_to_bvh = whole;
        return f;
      };
  // A large rig whose open parts are all small or capped: they go with the closed parts to
  // dynamic; no cones, a segmentation.
  const ObjectPlan a = plan_of(groups(2, 1, 0, false));
  EXPECT_FALSE(a.cones);
  EXPECT_TRUE(a.segmentation);
  EXPECT_TRUE(skipped(a, "cones: every open part under 256 triangles or capped"));
  // Open parts only, one of them capped: a closed group after all, so a segmentation.
  const ObjectPlan b = plan_of(groups(2, 0, 1, false));
  EXPECT_TRUE(b.cones);
  EXPECT_TRUE(b.segmentation);
  // A garment on its own skeleton, every part large and open: cones, no segmentation.
  const ObjectPlan c = plan_of(groups(1, 0, 1, false));
  EXPECT_TRUE(c.cones);
  EXPECT_FALSE(c.segmentation);
  EXPECT_TRUE(skipped(c, "segmentation: no closed part, and no open one under 256 triangles"));
  // The whole mesh to bvh: neither.
  const ObjectPlan d = plan_of(groups(2, 1, 0, true));
  EXPECT_FALSE(d.cones || d.segmentation);
  EXPECT_TRUE(skipped(d, "cones: every part closed, small or capped and under 20000 triangles"));
}

TEST(ScenePlan, ATargetOnlyCarryingASheetIsLoadedButNeverPosed) {
  const auto path = scene_in_assets(
      "[objects.body]\nmodel = \"" + kRig +
      "\"\n"
      "[objects.cape]\nsheet = { corner = [0,0,0], u = [1,0,0], v = [0,1,0] }\nattach_to = "
      "\"body\"\n"
      "checks = [\"self-ccd\"]\n");
  const Scene s = parse_scene(path);
  EXPECT_EQ(objects_to_load(s), (std::vector<bool>{true, true}));
  const auto plan = plan_scene(s, {facts(10, 0, 1, true), facts(10, 1, 0, true)}, std::nullopt);
  EXPECT_TRUE(plan.objects[0].load);
  EXPECT_FALSE(plan.objects[0].skin || plan.objects[0].topology || plan.objects[0].bvh);
  ASSERT_EQ(plan.objects[0].skipped.size(), 1u);
  EXPECT_NE(plan.objects[0].skipped[0].find("no check names it"), std::string::npos);
  ASSERT_EQ(plan.checks.size(), 1u);
  EXPECT_EQ(plan.checks[0].name(plan.objects), "self cape");
}

TEST(ScenePlan, RefusesFramesOutsideAnObjectsSamples) {
  const auto path = scene_in_assets(
      "frames = \"3:12\"\n[objects.a]\nmodel = \"gen:rope\"\nchecks = [\"self-dcd\"]\n");
  const Scene s = parse_scene(path);
  EXPECT_THROW_MESSAGE(
      (void)plan_scene(s, {facts(10, 0, 1, true)}, s.frames),
      InvalidInput,
      path.string() + ":1: object 'a': frames 3:12 do not fit its 10 samples (0:9)");
}

}  // namespace
}  // namespace skelcd::tools
