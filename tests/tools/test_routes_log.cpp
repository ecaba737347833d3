// check --method auto records in the log where each connected component went (/routes): closed
// components to the closed method, open ones to the cone method, as the mesh's own edges say.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "clustering/ghost_caps.hpp"
#include "culling/routed_method.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {
namespace {

using skelcd::test::run_skelcd;

// Closed, counted from the welded triangles alone: every undirected edge of the component has
// exactly two incident triangles of the whole mesh.
bool closed_by_edges(const skinning::Triangles& F, const std::vector<std::int32_t>& faces) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> all;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto a = F(f, k);
      const auto b = F(f, (k + 1) % 3);
      ++all[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (const auto f : faces) {
    for (int k = 0; k < 3; ++k) {
      const auto a = F(f, k);
      const auto b = F(f, (k + 1) % 3);
      if (all[{std::min(a, b), std::max(a, b)}] != 2) return false;
    }
  }
  return true;
}

/// What check_routes saw of one model's /routes.
struct RoutesSeen {
  std::int32_t too_small = 0;          ///< open parts with small holes but too few triangles to cap
  std::set<bool> kinds;                ///< closed and/or open components
  std::set<std::string> open_methods;  ///< the methods of the open components
  bool whole = false;  ///< every component closed, under 256 triangles, or with small holes only
  std::string segmentation;  ///< the summary's `segmentation`: where it came from, or why none
};

/// Runs `check --method auto` on a rig's clip and checks its /routes against the mesh's own edges:
/// a mesh whose every component is closed, under RoutingOptions::min_open_triangles, or open only
/// at holes the radial-view method caps goes whole to `bvh` (RoutingOptions::all_closed_method);
/// otherwise closed components go to the radial-view method, and so do open ones with small holes
/// only, and open ones too small for a group of their own, the rest to the open method.
RoutesSeen check_routes(const std::filesystem::path& model, const std::string& name) {
  RoutesSeen seen;
  const auto log = skelcd::test::temp_dir("routes-log-" + name) / "auto.h5";
  const auto r = run_skelcd(
      {"check",
       model.string(),
       "--method",
       "auto",
       "--frames",
       "0:1",
       "--json",
       "-o",
       log.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return seen;
  seen.segmentation = nlohmann::json::parse(r.out).at("segmentation").get<std::string>();

  const auto loaded = skinning::load_model(model);
  const auto topology = skinning::build_topology(*loaded.mesh);
  const auto header = read_log(log).header;
  EXPECT_EQ(header.routes.size(), topology.components.size());
  if (header.routes.size() != topology.components.size()) return seen;
  // Open components whose every hole is a small loop (at most 64 edges; a loop that passes a
  // vertex twice would be split) in a component without non-manifold edges, with at least
  // kMinTrianglesPerGhost triangles per loop edge, are capped by the radial-view method and go
  // with the closed ones; the others go to the open method.
  std::vector<std::uint8_t> small_holes(topology.components.size(), 1);
  std::vector<std::size_t> loop_edges(topology.components.size(), 0);
  for (const auto& loop : topology.boundary_loops) {
    const std::set<std::int32_t> distinct(loop.begin(), loop.end());
    const bool small = loop.size() <= 64 && distinct.size() == loop.size();
    for (std::size_t c = 0; c < topology.components.size(); ++c) {
      for (const std::int32_t f : topology.components[c].faces) {
        const auto row = topology.welded_triangles.row(f);
        if (distinct.count(row(0)) + distinct.count(row(1)) + distinct.count(row(2)) > 0) {
          if (!small) small_holes[c] = 0;
          loop_edges[c] += loop.size();
          break;
        }
      }
    }
  }
  for (std::size_t c = 0; c < topology.components.size(); ++c) {
    const auto per_edge = static_cast<std::size_t>(clustering::kMinTrianglesPerGhost);
    if (small_holes[c] != 0 && topology.components[c].faces.size() < per_edge * loop_edges[c]) {
      small_holes[c] = 0;
      ++seen.too_small;
    }
  }
  for (const std::int32_t e : topology.non_manifold_edges) {
    const auto f = topology.edge_faces[static_cast<std::size_t>(
        topology.edge_face_offsets[static_cast<std::size_t>(e)])];
    small_holes[static_cast<std::size_t>(topology.face_component[static_cast<std::size_t>(f)])] = 0;
  }
  seen.whole = true;
  for (std::size_t c = 0; c < topology.components.size(); ++c) {
    const auto& component = topology.components[c];
    seen.whole = seen.whole && (closed_by_edges(topology.welded_triangles, component.faces) ||
                                component.faces.size() < 256 ||  // min_open_triangles
                                small_holes[c] != 0);
  }
  std::int64_t triangles = 0;
  for (std::size_t i = 0; i < header.routes.size(); ++i) {
    const auto& route = header.routes[i];
    const auto& component = topology.components[i];
    EXPECT_EQ(route.component, static_cast<std::int32_t>(i));
    EXPECT_EQ(route.triangles, static_cast<std::int32_t>(component.faces.size()));
    EXPECT_EQ(route.part, loaded.mesh->face_part[static_cast<std::size_t>(component.faces.front())]);
    const bool closed = closed_by_edges(topology.welded_triangles, component.faces);
    EXPECT_EQ(route.closed, closed) << "component " << i;
    const bool small = component.faces.size() < 256;  // RoutingOptions::min_open_triangles
    const std::string want = seen.whole                               ? "bvh"
                             : closed || small_holes[i] != 0 || small ? "dynamic"
                                                                      : "enhanced-dual-cone";
    EXPECT_EQ(route.method, want) << "component " << i;
    if (!closed) seen.open_methods.insert(route.method);
    triangles += route.triangles;
    seen.kinds.insert(closed);
  }
  EXPECT_EQ(triangles, loaded.mesh->num_triangles());
  // What the set-up and a scene's plan decide from the topology alone (culling::auto_groups) is
  // what the routes show: a segmentation only for a closed group that is not the whole mesh's bvh.
  const culling::AutoGroups groups = culling::auto_groups(topology, /*rig=*/true);
  EXPECT_EQ(groups.whole, seen.whole);
  std::int32_t open_group = 0;
  for (const auto& route : header.routes) open_group += route.method == "enhanced-dual-cone";
  EXPECT_EQ(groups.open_components, open_group);
  EXPECT_EQ(groups.closed_components, static_cast<std::int32_t>(header.routes.size()) - open_group);
  const bool segmented = seen.segmentation.rfind("computed", 0) == 0;
  EXPECT_EQ(segmented, !seen.whole && groups.closed_components > 0) << seen.segmentation;
  return seen;
}

TEST(RoutesLog, AutoWritesWhereEachComponentWent) {
  // RobotExpressive: closed parts and open ones, every open one under 256 triangles — the whole
  // mesh to `bvh`.
  const RoutesSeen robot =
      check_routes(skelcd::test::asset("characters/RobotExpressive.glb"), "robot");
  EXPECT_TRUE(robot.whole);
  EXPECT_GT(robot.too_small, 0);  // small parts whose caps would cost more than they save
  EXPECT_EQ(robot.kinds.size(), 2u) << "the robot has both open and closed components";
  EXPECT_EQ(robot.open_methods, (std::set<std::string>{"bvh"}));
  // BCN_Epileptic: open parts only, some of 256 triangles or more, each with small holes only
  // (the radial-view method would cap them) or under 256 triangles — the whole mesh to `bvh` too.
  const RoutesSeen bcn = check_routes(skelcd::test::assimp_model("X/BCN_Epileptic.X"), "bcn");
  EXPECT_TRUE(bcn.whole);
  EXPECT_EQ(bcn.kinds, (std::set<bool>{false}));
  EXPECT_EQ(bcn.open_methods, (std::set<std::string>{"bvh"}));
}

TEST(RoutesLog, AGarmentOnItsOwnSkeletonGoesToConesUnsegmented) {
  // gen:cloth: one open sheet of 256 triangles or more on hinge bones, its boundary no hole to
  // cap — `auto` sends it whole to the cones, so no segmentation is made for a closed group that
  // would be empty, and the answer is bvh's.
  const std::string model = "gen:cloth?triangles=1200&frames=12";
  const RoutesSeen cloth = check_routes(model, "cloth");
  EXPECT_FALSE(cloth.whole);
  EXPECT_EQ(cloth.kinds, (std::set<bool>{false}));
  EXPECT_EQ(cloth.open_methods, (std::set<std::string>{"enhanced-dual-cone"}));
  EXPECT_EQ(cloth.segmentation.rfind("none (auto: every part open", 0), 0u) << cloth.segmentation;
  // A segmentation file given anyway is not read, and the user is told why.
  const auto dir = skelcd::test::temp_dir("routes-cloth");
  const auto unused = dir / "unused.h5";
  const auto note = run_skelcd(
      {"check", model, "--method", "auto", "--frames", "0:1", "--segmentation", unused.string()});
  EXPECT_EQ(note.exit_code, 0) << note.err;
  EXPECT_NE(
      note.err.find("is not used: auto sends every part of this mesh to cones"), std::string::npos)
      << note.err;
  std::vector<nlohmann::json> runs;
  for (const char* method : {"auto", "bvh"}) {
    const auto r = run_skelcd({"check", model, "--method", method, "--baseline", "none", "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    runs.push_back(nlohmann::json::parse(r.out));
  }
  EXPECT_GT(runs[1]["new_ccd_contacts"].get<std::int64_t>(), 0);
  for (const char* key : {"ccd_vf", "ccd_ee", "dcd_pairs"}) {
    EXPECT_EQ(runs[0][key], runs[1][key]) << key;
  }
}

TEST(RoutesLog, AutoWithEveryComponentInOneGroupIsThatGroupsMethod) {
  // Testwuson (54 parts, 53 of them small and open) and RobotExpressive: every component is closed
  // or under 256 triangles; BCN_Epileptic: every component under 256 triangles or open only at
  // holes the radial-view method would cap. So `auto` hands the whole mesh to `bvh`
  // (RoutingOptions::all_closed_method) — with `--no-rigid-rows` the same candidate pairs, tests
  // and findings at every frame (no group split, no traversal of its own); by default that `bvh`
  // also skips the CCD pairs skinning moves by one matrix (docs/culling.md "Rigid rows"): the same
  // findings and DCD rows, fewer candidate pairs.
  for (const auto& model :
       {skelcd::test::assimp_model("X/Testwuson.X"),
        skelcd::test::asset("characters/RobotExpressive.glb"),
        skelcd::test::assimp_model("X/BCN_Epileptic.X")}) {
    SCOPED_TRACE(model.string());
    const auto dir = skelcd::test::temp_dir("routes-one-group");
    std::vector<LogData> logs;
    for (const std::string run : {"auto-no-rows", "bvh", "auto"}) {
      const auto log = dir / (run + ".h5");
      std::vector<std::string> args{
          "check",
          model.string(),
          "--method",
          run == "bvh" ? "bvh" : "auto",
          "--frames",
          "0:5",
          "-o",
          log.string()};
      if (run == "auto-no-rows") args.push_back("--no-rigid-rows");
      const auto r = run_skelcd(args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      logs.push_back(read_log(log));
    }
    for (const std::size_t k : {std::size_t{0}, std::size_t{2}}) {
      ASSERT_FALSE(logs[k].header.routes.empty());
      for (const auto& route : logs[k].header.routes) EXPECT_EQ(route.method, "bvh");
      ASSERT_EQ(logs[k].frames.size(), logs[1].frames.size());
      EXPECT_EQ(logs[k].contacts.size(), logs[1].contacts.size());
      EXPECT_EQ(logs[k].dcd_pairs.size(), logs[1].dcd_pairs.size());
    }
    std::int64_t candidates = 0;
    std::int64_t with_rows = 0;
    for (std::size_t i = 0; i < logs[0].frames.size(); ++i) {
      const auto& a = logs[0].frames[i];
      const auto& b = logs[1].frames[i];
      const auto& c = logs[2].frames[i];
      EXPECT_EQ(a.counters.candidate_pairs, b.counters.candidate_pairs) << "row " << i;
      EXPECT_EQ(a.counters.vf_tests, b.counters.vf_tests) << "row " << i;
      EXPECT_EQ(a.counters.ee_tests, b.counters.ee_tests) << "row " << i;
      EXPECT_EQ(a.counters.tt_tests, b.counters.tt_tests) << "row " << i;
      EXPECT_EQ(c.counters.vf_contacts, b.counters.vf_contacts) << "row " << i;
      EXPECT_EQ(c.counters.ee_contacts, b.counters.ee_contacts) << "row " << i;
      EXPECT_EQ(c.counters.dcd_pairs, b.counters.dcd_pairs) << "row " << i;
      EXPECT_LE(c.counters.candidate_pairs, b.counters.candidate_pairs) << "row " << i;
      candidates += a.counters.candidate_pairs;
      with_rows += c.counters.candidate_pairs;
    }
    EXPECT_GT(candidates, 0);
    EXPECT_LT(with_rows, candidates);
  }
}

TEST(RoutesLog, AutoFindsWhatBvhFindsOnACharacterWithOpenParts) {
  const auto model = skelcd::test::asset("characters/RobotExpressive.glb");
  const auto dir = skelcd::test::temp_dir("routes-agree");
  std::vector<LogData> logs;
  for (const char* method : {"auto", "bvh"}) {
    const auto log = dir / (std::string(method) + ".h5");
    const auto r = run_skelcd({"check", model.string(), "--method", method, "--frames", "0:6", "-o", log.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    logs.push_back(read_log(log));
  }
  const auto key = [](const LogData& log) {
    std::set<std::tuple<std::int32_t, int, std::int32_t, std::int32_t, std::int32_t, std::int32_t>> s;
    for (const auto& c : log.contacts) {
      s.insert({c.frame, static_cast<int>(c.kind), c.a.part * 8 + c.a.side, c.a.index, c.b.part * 8 + c.b.side, c.b.index});
    }
    for (const auto& p : log.dcd_pairs) s.insert({p.frame, -1, p.a.part, p.a.index, p.b.part, p.b.index});
    return s;
  };
  EXPECT_EQ(key(logs[0]), key(logs[1]));
  EXPECT_EQ(logs[0].frames.size(), logs[1].frames.size());
}

TEST(RoutesLog, SceneLogsHoldTheRoutesOfEveryAutoObject) {
  // Two objects checked with auto and one with bvh: the scene log holds the routes of the auto
  // objects, each row's part naming its object, and they are the routes a plain check writes.
  const auto bot = skelcd::test::asset("characters/RobotExpressive.glb").string();
  const auto dir = skelcd::test::temp_dir("routes-scene");
  const auto scene = dir / "scene.toml";
  std::ofstream(scene) << "frames = \"0:1\"\n"
                       << "[objects.bot]\nmodel = \"" << bot
                       << "\"\nchecks = [\"self-dcd\", \"self-ccd\"]\nmethod = \"auto\"\n"
                       << "[objects.sheet]\nmodel = \"gen:cloth?triangles=400&frames=4\"\n"
                       << "checks = [\"self-ccd\"]\nmethod = \"auto\"\n"
                       << "[objects.rope]\nmodel = \"gen:rope?triangles=200&frames=4\"\n"
                       << "checks = [\"self-dcd\"]\n";
  const auto log = dir / "scene.h5";
  const auto r = run_skelcd({"check", scene.string(), "-o", log.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto header = read_log(log).header;

  const auto single = dir / "bot.h5";
  ASSERT_EQ(
      run_skelcd({"check", bot, "--method", "auto", "--frames", "0:1", "-o", single.string()})
          .exit_code,
      0);
  const auto bot_routes = read_log(single).header.routes;
  ASSERT_FALSE(bot_routes.empty());

  std::vector<LogRoute> scene_bot, scene_sheet;
  for (const auto& route : header.routes) {
    ASSERT_GE(route.part, 0);
    ASSERT_LT(static_cast<std::size_t>(route.part), header.part_names.size());
    const std::string& part = header.part_names[static_cast<std::size_t>(route.part)];
    if (part.rfind("bot/", 0) == 0) {
      scene_bot.push_back(route);
    } else {
      EXPECT_EQ(part.rfind("sheet/", 0), 0u) << part << ": only auto objects have routes";
      scene_sheet.push_back(route);
    }
  }
  ASSERT_EQ(scene_bot.size(), bot_routes.size());
  for (std::size_t i = 0; i < bot_routes.size(); ++i) {
    EXPECT_EQ(scene_bot[i].component, bot_routes[i].component);
    EXPECT_EQ(scene_bot[i].method, bot_routes[i].method) << i;
    EXPECT_EQ(scene_bot[i].triangles, bot_routes[i].triangles);
    EXPECT_EQ(
        header.part_names[static_cast<std::size_t>(scene_bot[i].part)],
        "bot/" + read_log(single).header.part_names[static_cast<std::size_t>(bot_routes[i].part)]);
  }
  ASSERT_EQ(scene_sheet.size(), 1u);  // the cloth is one open sheet
  EXPECT_FALSE(scene_sheet[0].closed);
  EXPECT_EQ(scene_sheet[0].method, "enhanced-dual-cone");
}

TEST(RoutesLog, OtherMethodsWriteNoRoutes) {
  const auto log = skelcd::test::temp_dir("routes-none") / "bvh.h5";
  const auto r = run_skelcd({"check", skelcd::test::asset("characters/RobotExpressive.glb").string(),
                             "--method", "bvh", "--frames", "0:1", "-o", log.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(read_log(log).header.routes.empty());
}

}  // namespace
}  // namespace skelcd::tools
