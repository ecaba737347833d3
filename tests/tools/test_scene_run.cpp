// Scene runs: zero work for stages left out (counters in the result and in the log), pair checks
// against brute force over all cross pairs, refusals before any work, the bundled scenes, the CLI.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "ccd/edge_edge.hpp"
#include "ccd/triangle_triangle.hpp"
#include "ccd/vertex_face.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/engine/scene_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {
namespace {

std::filesystem::path write_scene(
    const std::string& text, const std::string& dir_name = "scene_run") {
  const auto dir = test::temp_dir(dir_name);
  const auto path = dir / "scene.toml";
  std::ofstream(path) << text;
  return path;
}

const SceneCheckResult& check_named(const SceneRunResult& r, const std::string& name) {
  for (const auto& c : r.checks) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no check " + name);
}

TEST(SceneRun, DcdOnlyCheckDoesNoCcdOrClusteringWorkAndUncheckedObjectsAreNeverLoaded) {
  // hand: DCD only with bvh. dyn: CCD with dynamic — the counters that must stay 0 for `hand`
  // move here, so they do measure clustering when it runs. idle: checked by nothing.
  const auto path = write_scene(
      "[objects.hand]\nmodel = \"gen:hand?triangles=1000&frames=4\"\nchecks = [\"self-dcd\"]\n"
      "[objects.idle]\nmodel = \"gen:rope?triangles=48000&frames=60\"\n"
      "[objects.dyn]\nmodel = \"gen:hand?triangles=1000&frames=3\"\nchecks = [\"self-ccd\"]\n"
      "method = \"dynamic\"\n");
  const Scene scene = parse_scene(path);
  std::vector<std::string> loads;
  SceneRunOptions options;
  options.log = path.parent_path() / "log.h5";
  options.on_load = [&](std::string_view name) { loads.emplace_back(name); };
  bool planned = false;
  options.on_plan = [&](const ScenePlan& plan) {
    planned = true;
    EXPECT_FALSE(plan.objects[1].load);
    EXPECT_FALSE(
        plan.objects[0].swept_bounds || plan.objects[0].segmentation || plan.objects[0].cones);
    EXPECT_TRUE(plan.objects[2].segmentation && plan.objects[2].swept_bounds);
  };
  const auto result = run_scene(scene, options);
  EXPECT_TRUE(planned);
  EXPECT_EQ(loads, (std::vector<std::string>{"hand", "dyn"}));

  const auto& hand = check_named(result, "self hand");
  ASSERT_EQ(hand.rows.size(), 4u);
  std::int64_t tt_tests = 0;
  for (const auto& row : hand.rows) {
    EXPECT_EQ(row.kind, QueryKind::dcd);
    const auto& c = row.counters;
    EXPECT_EQ(c.vf_tests + c.ee_tests + c.vf_contacts + c.ee_contacts + c.feature_bv_tests, 0);
    EXPECT_EQ(c.atomic_clusters + c.mega_clusters + c.h_minus + c.h_uncertain, 0);
    EXPECT_EQ(row.times.classify_us, 0.0);
    EXPECT_EQ(row.times.merge_us, 0.0);
    tt_tests += c.tt_tests;
  }
  EXPECT_GT(tt_tests, 0);  // the DCD itself did run
  const auto& dyn = check_named(result, "self dyn");
  ASSERT_EQ(dyn.rows.size(), 2u);
  std::int64_t clusters = 0;
  for (const auto& row : dyn.rows) {
    EXPECT_EQ(row.kind, QueryKind::ccd);
    clusters += row.counters.atomic_clusters;
  }
  EXPECT_GT(clusters, 0);

  // The same from the log: rows of check 0 show zero CCD and clustering work.
  const auto log = read_log(options.log);
  ASSERT_EQ(log.frames.size(), 6u);
  ASSERT_EQ(log.frame_checks.size(), log.frames.size());
  ASSERT_EQ(log.header.checks.size(), 2u);
  EXPECT_EQ(log.header.checks[0].name, "self hand");
  EXPECT_EQ(log.header.checks[1].method, "dynamic");
  EXPECT_TRUE(log.header.complete);
  // Only posed objects have parts in the log: hand then dyn.
  EXPECT_EQ(log.header.part_names.front().rfind("hand/", 0), 0u);
  EXPECT_EQ(log.header.part_names.back().rfind("dyn/", 0), 0u);
  for (std::size_t i = 0; i < log.frames.size(); ++i) {
    const auto& row = log.frames[i];
    if (log.frame_checks[i] != 0) continue;
    EXPECT_EQ(row.kind, QueryKind::dcd);
    EXPECT_EQ(row.counters.vf_tests + row.counters.ee_tests + row.counters.atomic_clusters, 0);
    EXPECT_EQ(row.times.classify_us + row.times.merge_us, 0.0);
  }
}

TEST(SceneRun, DcdOnlyRadialViewObjectsAreNotSegmentedAndFindWhatBvhFinds) {
  // rvbc/dynamic/auto with self-dcd only: nothing of the radial view is planned or built (their
  // DCD is bvh's); the run still succeeds and every row equals the bvh object's.
  const std::string rig = test::asset("characters/CesiumMan.glb").string();
  std::string text = "frames = \"0:6\"\n";
  for (const char* method : {"bvh", "rvbc", "dynamic", "auto"}) {
    text += std::string("[objects.") + (method[0] == 'a' ? "auto_" : method) + "]\nmodel = \"" +
            rig + "\"\nchecks = [\"self-dcd\"]\nmethod = \"" + method + "\"\n";
  }
  const Scene scene = parse_scene(write_scene(text, "scene_dcd_rv"));
  SceneRunOptions options;
  bool planned = false;
  options.on_plan = [&](const ScenePlan& plan) {
    planned = true;
    for (const auto& o : plan.objects) {
      EXPECT_FALSE(o.segmentation || o.swept_bounds) << o.name;
    }
  };
  const auto result = run_scene(scene, options);
  EXPECT_TRUE(planned);
  ASSERT_EQ(result.checks.size(), 4u);
  const auto& bvh = result.checks[0];
  ASSERT_EQ(bvh.rows.size(), 7u);
  EXPECT_GT(bvh.dcd_pairs.size(), 0u);  // the walk interpenetrates: the comparison means something
  for (std::size_t k = 1; k < result.checks.size(); ++k) {
    const auto& c = result.checks[k];
    ASSERT_EQ(c.rows.size(), bvh.rows.size()) << c.name;
    EXPECT_EQ(c.dcd_pairs.size(), bvh.dcd_pairs.size()) << c.name;
    for (std::size_t i = 0; i < c.rows.size(); ++i) {
      EXPECT_EQ(c.rows[i].counters.dcd_pairs, bvh.rows[i].counters.dcd_pairs) << c.name;
      EXPECT_EQ(c.rows[i].counters.atomic_clusters + c.rows[i].counters.h_uncertain, 0) << c.name;
    }
  }
}

// --- pair checks against brute force -----------------------------------------------------------

Eigen::Vector3d row_of(const skinning::Positions& x, Eigen::Index i) {
  return x.row(i).transpose();
}

struct Posed {
  skinning::Mesh mesh;
  std::vector<skinning::Positions> samples;
};

/// An independent pose of a `gen:` object: load_model's motion, translated.
Posed pose_generated(const std::string& spec, const Eigen::Vector3d& offset) {
  const auto model = skinning::load_model(spec);
  const auto motion = model.motion();
  Posed p;
  p.mesh = motion->mesh();
  for (int i = 0; i < motion->num_samples(); ++i) {
    skinning::Positions x;
    motion->positions(i, x);
    for (Eigen::Index v = 0; v < x.rows(); ++v) x.row(v) += offset.transpose();
    p.samples.push_back(x);
  }
  return p;
}

using TrianglePairs = std::set<std::pair<std::int32_t, std::int32_t>>;

TrianglePairs brute_dcd(const Posed& a, const Posed& b, int sample) {
  TrianglePairs out;
  const auto& xa = a.samples[static_cast<std::size_t>(sample)];
  const auto& xb = b.samples[static_cast<std::size_t>(sample)];
  for (Eigen::Index i = 0; i < a.mesh.triangles.rows(); ++i) {
    for (Eigen::Index j = 0; j < b.mesh.triangles.rows(); ++j) {
      const auto ta = a.mesh.triangles.row(i);
      const auto tb = b.mesh.triangles.row(j);
      const ccd::TriangleTriangleQuery q{
          row_of(xa, ta[0]),
          row_of(xa, ta[1]),
          row_of(xa, ta[2]),
          row_of(xb, tb[0]),
          row_of(xb, tb[1]),
          row_of(xb, tb[2])};
      if (ccd::triangles_intersect(q))
        out.insert({static_cast<std::int32_t>(i), static_cast<std::int32_t>(j)});
    }
  }
  return out;
}

/// VF contacts (vertex part 0/1, vertex, face) over interval [i, i+1], both ways, exact.
using VertexFaces = std::set<std::tuple<int, std::int32_t, std::int32_t>>;

VertexFaces brute_vf(const Posed& a, const Posed& b, int i) {
  VertexFaces out;
  const auto one_way = [&](int side, const Posed& pv, const Posed& pf) {
    const auto& v0 = pv.samples[static_cast<std::size_t>(i)];
    const auto& v1 = pv.samples[static_cast<std::size_t>(i + 1)];
    const auto& f0 = pf.samples[static_cast<std::size_t>(i)];
    const auto& f1 = pf.samples[static_cast<std::size_t>(i + 1)];
    for (Eigen::Index v = 0; v < v0.rows(); ++v) {
      for (Eigen::Index f = 0; f < pf.mesh.triangles.rows(); ++f) {
        const auto t = pf.mesh.triangles.row(f);
        const ccd::VertexFaceQuery q{
            row_of(v0, v),
            row_of(f0, t[0]),
            row_of(f0, t[1]),
            row_of(f0, t[2]),
            row_of(v1, v),
            row_of(f1, t[0]),
            row_of(f1, t[1]),
            row_of(f1, t[2])};
        if (ccd::vertex_face_ccd(q, ccd::Accuracy::exact).hit) {
          out.insert({side, static_cast<std::int32_t>(v), static_cast<std::int32_t>(f)});
        }
      }
    }
  };
  one_way(0, a, b);
  one_way(1, b, a);
  return out;
}

std::int64_t brute_ee(const Posed& a, const Posed& b, int i) {
  const auto ta = skinning::build_topology(a.mesh);
  const auto tb = skinning::build_topology(b.mesh);
  std::int64_t hits = 0;
  const auto& a0 = a.samples[static_cast<std::size_t>(i)];
  const auto& a1 = a.samples[static_cast<std::size_t>(i + 1)];
  const auto& b0 = b.samples[static_cast<std::size_t>(i)];
  const auto& b1 = b.samples[static_cast<std::size_t>(i + 1)];
  const auto vertex = [](const skinning::Topology& t, std::int32_t w) {
    return static_cast<Eigen::Index>(t.representative_vertex[static_cast<std::size_t>(w)]);
  };
  for (Eigen::Index e = 0; e < ta.edges.rows(); ++e) {
    for (Eigen::Index g = 0; g < tb.edges.rows(); ++g) {
      const Eigen::Index p0 = vertex(ta, ta.edges(e, 0)), p1 = vertex(ta, ta.edges(e, 1));
      const Eigen::Index q0 = vertex(tb, tb.edges(g, 0)), q1 = vertex(tb, tb.edges(g, 1));
      const ccd::EdgeEdgeQuery q{
          row_of(a0, p0),
          row_of(a0, p1),
          row_of(b0, q0),
          row_of(b0, q1),
          row_of(a1, p0),
          row_of(a1, p1),
          row_of(b1, q0),
          row_of(b1, q1)};
      if (ccd::edge_edge_ccd(q, ccd::Accuracy::exact).hit) ++hits;
    }
  }
  return hits;
}

TEST(ScenePairs, GeneratedObjectsAgreeWithBruteForceOverAllCrossPairs) {
  // Two small cloths: B lies 2 cm above A's plane, shifted; A's right part folds up through B.
  // At sample 0 the sheets are parallel and apart, so no pair intersects (known answer).
  const std::string spec = "gen:cloth?triangles=100&frames=4";
  const Eigen::Vector3d offset(0.5, 0.3, 0.02);
  const auto path = write_scene(
      "accuracy = \"exact\"\n"
      "[objects.a]\nmodel = \"" +
      spec +
      "\"\n"
      "[objects.b]\nmodel = \"" +
      spec +
      "\"\noffset = [0.5, 0.3, 0.02]\n"
      "[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\", \"ccd\"]\n");
  const auto result = run_scene(parse_scene(path));
  ASSERT_EQ(result.checks.size(), 1u);
  const auto& pair = result.checks[0];
  ASSERT_EQ(pair.rows.size(), 7u);  // dcd 0, ccd 0, dcd 1, …, dcd 3
  const Posed a = pose_generated(spec, Eigen::Vector3d::Zero());
  const Posed b = pose_generated(spec, offset);

  std::int64_t total_dcd = 0, total_ccd = 0;
  for (int s = 0; s < 4; ++s) {
    TrianglePairs found;
    for (const auto& p : pair.dcd_pairs) {
      if (p.frame != s) continue;
      EXPECT_EQ(p.a.part, 0);  // a's part, then b's (log numbering: objects in order)
      EXPECT_EQ(p.b.part, 1);
      found.insert({p.a.index, p.b.index});
    }
    const auto expected = brute_dcd(a, b, s);
    EXPECT_EQ(found, expected) << "sample " << s;
    total_dcd += static_cast<std::int64_t>(expected.size());
    if (s == 0) {
      EXPECT_TRUE(expected.empty());
    }
  }
  for (int i = 0; i < 3; ++i) {
    VertexFaces vf;
    std::int64_t ee = 0;
    for (const auto& c : pair.contacts) {
      if (c.frame != i) continue;
      if (c.kind == culling::CcdContact::Kind::vf) {
        vf.insert({c.a.part, c.a.index, c.b.index});
        EXPECT_NE(c.a.part, c.b.part);
      } else {
        ++ee;
      }
    }
    const auto expected_vf = brute_vf(a, b, i);
    EXPECT_EQ(vf, expected_vf) << "interval " << i;
    EXPECT_EQ(ee, brute_ee(a, b, i)) << "interval " << i;
    total_ccd += static_cast<std::int64_t>(expected_vf.size()) + ee;
  }
  EXPECT_GT(total_dcd, 0);
  EXPECT_GT(total_ccd, 0);
  // Counters agree with the findings.
  std::int64_t counted = 0;
  for (const auto& row : pair.rows) counted += row.counters.dcd_pairs;
  EXPECT_EQ(counted, total_dcd);
}

TEST(ScenePairs, ObjectsFarApartHaveNoCandidatesAndCoincidentCopiesIntersectEverywhere) {
  const std::string spec = "gen:hand?triangles=1000&frames=3";
  const auto far = write_scene(
      "[objects.a]\nmodel = \"" + spec + "\"\n[objects.b]\nmodel = \"" + spec +
      "\"\noffset = [100, 0, 0]\n[[pairs]]\nobjects = [\"a\", \"b\"]\n"
      "checks = [\"dcd\", \"ccd\"]\n");
  const auto r_far = run_scene(parse_scene(far));
  for (const auto& row : r_far.checks[0].rows) {
    EXPECT_EQ(row.counters.candidate_pairs, 0);
    EXPECT_EQ(row.counters.dcd_pairs + row.counters.vf_contacts + row.counters.ee_contacts, 0);
    EXPECT_GT(row.counters.bv_tests, 0);  // the roots were compared
  }
  const std::string cloth = "gen:cloth?triangles=200&frames=2";
  const auto same = write_scene(
      "[objects.a]\nmodel = \"" + cloth + "\"\n[objects.b]\nmodel = \"" + cloth +
          "\"\n[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\"]\n",
      "scene_same");
  const auto r_same = run_scene(parse_scene(same));
  const auto triangles = skinning::load_model(cloth).mesh->num_triangles();
  for (const auto& row : r_same.checks[0].rows) {
    EXPECT_GE(row.counters.dcd_pairs, triangles);  // each triangle meets its own copy at least
  }
  std::set<std::pair<std::int32_t, std::int32_t>> diagonal;
  for (const auto& p : r_same.checks[0].dcd_pairs) {
    if (p.frame == 0 && p.a.index == p.b.index) diagonal.insert({p.a.index, p.b.index});
  }
  EXPECT_EQ(static_cast<std::int64_t>(diagonal.size()), triangles);
}

TEST(ScenePairs, PandaHandAgainstUpperArmEqualsTheRobotsOwnSelfCheckBetweenThoseLinks) {
  // A real asset, two independent paths: the pair check of two part selections (PairChecker)
  // and the whole robot's self check (bvh with SRDF exclusions) restricted to those links.
  SceneRunOptions options;
  const auto result = run_scene(parse_scene(test::asset("scenes/panda.toml")), options);
  const auto& self = check_named(result, "self panda");
  const auto& pair = check_named(result, "pair hand upper_arm");
  const auto& names = result.part_names;
  const auto link = [&](std::int32_t part) {
    const std::string& n = names[static_cast<std::size_t>(part)];
    return n.substr(n.find('/') + 1);
  };
  const std::set<std::string> hand{"panda_hand", "panda_leftfinger", "panda_rightfinger"};
  const std::set<std::string> arm{"panda_link1", "panda_link2"};
  using Key = std::tuple<std::int32_t, std::string, std::int32_t, std::string, std::int32_t>;
  std::set<Key> from_self, from_pair;
  for (const auto& p : self.dcd_pairs) {
    auto a = std::make_pair(link(p.a.part), p.a.index);
    auto b = std::make_pair(link(p.b.part), p.b.index);
    if (hand.count(b.first) != 0) std::swap(a, b);
    if (hand.count(a.first) != 0 && arm.count(b.first) != 0) {
      from_self.insert({p.frame, a.first, a.second, b.first, b.second});
    }
  }
  for (const auto& p : pair.dcd_pairs) {
    from_pair.insert({p.frame, link(p.a.part), p.a.index, link(p.b.part), p.b.index});
  }
  EXPECT_GT(from_pair.size(), 0u);
  EXPECT_EQ(from_pair, from_self);
  // Known answer of the trajectory (assets/SOURCES.md): samples 38–60 intersect.
  EXPECT_EQ(self.summary.frames_with_interpenetration, 23);
  for (const auto& p : pair.dcd_pairs) EXPECT_GE(p.frame, 38);
}

TEST(SceneRun, SelfChecksGiveTheSameRowsOnOneOrSeveralThreads) {
  const auto scene = parse_scene(test::asset("scenes/panda.toml"));
  SceneRunOptions serial;
  serial.threads = 1;
  SceneRunOptions parallel;
  parallel.threads = 2;
  const auto a = run_scene(scene, serial);
  const auto b = run_scene(scene, parallel);
  ASSERT_EQ(a.checks.size(), b.checks.size());
  for (std::size_t k = 0; k < a.checks.size(); ++k) {
    ASSERT_EQ(a.checks[k].rows.size(), b.checks[k].rows.size());
    for (std::size_t i = 0; i < a.checks[k].rows.size(); ++i) {
      const auto& x = a.checks[k].rows[i];
      const auto& y = b.checks[k].rows[i];
      EXPECT_EQ(std::tie(x.sample, x.kind, x.t0, x.t1), std::tie(y.sample, y.kind, y.t0, y.t1));
      EXPECT_EQ(x.counters.bv_tests, y.counters.bv_tests);
      EXPECT_EQ(x.counters.dcd_pairs, y.counters.dcd_pairs);
      EXPECT_EQ(
          x.counters.vf_contacts + x.counters.ee_contacts,
          y.counters.vf_contacts + y.counters.ee_contacts);
    }
    EXPECT_EQ(a.checks[k].contacts, b.checks[k].contacts);
    EXPECT_EQ(a.checks[k].dcd_pairs, b.checks[k].dcd_pairs);
  }
}

// --- refusals --------------------------------------------------------------------------------

TEST(SceneRun, PairsWithDifferentSamplesAreRefusedBeforeTheLogExists) {
  const auto path = write_scene(
      "[objects.a]\nmodel = \"gen:cloth?triangles=100&frames=5\"\n"
      "[objects.b]\nmodel = \"gen:cloth?triangles=100&frames=6\"\n"
      "[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\"]\n");
  SceneRunOptions options;
  options.log = path.parent_path() / "never.h5";
  EXPECT_THROW_MESSAGE(
      (void)run_scene(parse_scene(path), options),
      InvalidInput,
      path.string() + ":5: pair a × b: 'a' has 5 samples");
  EXPECT_FALSE(std::filesystem::exists(options.log));
  // Same count, different rate: the time bases differ.
  const auto rates = write_scene(
      "[objects.a]\nmodel = \"" + test::asset("characters/RiggedFigure.glb").string() +
          "\"\nrate = 8\n"
          "[objects.b]\nmodel = \"gen:cloth?triangles=100&frames=11\"\n"
          "[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\"]\n",
      "scene_rates");
  EXPECT_THROW_MESSAGE((void)run_scene(parse_scene(rates)), InvalidInput, ":6: pair a × b: ");
}

TEST(SceneRun, LoadFaultsNameTheObjectsLine) {
  const auto path = write_scene(
      "[objects.fig]\nmodel = \"" + test::asset("characters/RiggedFigure.glb").string() +
      "\"\nclip = \"no such clip\"\nchecks = [\"self-dcd\"]\n"
      "[objects.arm]\nmodel = \"gen:panda\"\nparts = [\"panda_link9\"]\nchecks = [\"self-dcd\"]\n");
  EXPECT_THROW_MESSAGE(
      (void)run_scene(parse_scene(path)), InvalidInput, path.string() + ":1: object 'fig': ");
  const auto parts = write_scene(
      "[objects.arm]\nmodel = \"gen:panda\"\nparts = [\"panda_link9\"]\nchecks = [\"self-dcd\"]\n",
      "scene_parts");
  EXPECT_THROW_MESSAGE(
      (void)run_scene(parse_scene(parts)),
      InvalidInput,
      parts.string() + ":3: object 'arm': unknown part 'panda_link9'");
}

TEST(SceneRun, ASheetNeedsASkeletonToHangFrom) {
  const auto path = write_scene(
      "[objects.frames]\nmodel = \"" + test::asset("cloth-funnel/frames").string() +
      "\"\n"
      "[objects.cape]\nsheet = { corner = [0,0,0], u = [1,0,0], v = [0,1,0] }\n"
      "attach_to = \"frames\"\nchecks = [\"self-ccd\"]\n");
  EXPECT_THROW_MESSAGE(
      (void)run_scene(parse_scene(path)),
      InvalidInput,
      path.string() + ":5: object 'cape': 'frames' has no skeleton");
}

// --- the bundled scenes ----------------------------------------------------------------------

TEST(BundledScenes, EachParsesPlansRunsAndLogsEveryPlannedRow) {
  for (const char* name : {"cape", "panda", "cloth_funnel"}) {
    SCOPED_TRACE(name);
    const auto scene = parse_scene(test::asset(std::string("scenes/") + name + ".toml"));
    SceneRunOptions options;
    options.log = test::temp_dir(std::string("bundled_") + name) / "log.h5";
    const auto result = run_scene(scene, options);
    ASSERT_EQ(result.checks.size(), result.plan.checks.size());
    std::int64_t rows = 0;
    for (std::size_t k = 0; k < result.checks.size(); ++k) {
      EXPECT_EQ(
          static_cast<std::int64_t>(result.checks[k].rows.size()), result.plan.checks[k].rows);
      rows += result.plan.checks[k].rows;
    }
    EXPECT_EQ(rows, result.plan.rows);
    const auto log = read_log(options.log);
    EXPECT_EQ(static_cast<std::int64_t>(log.frames.size()), result.plan.rows);
    EXPECT_EQ(log.frame_checks.size(), log.frames.size());
    EXPECT_EQ(log.header.checks.size(), result.plan.checks.size());
    EXPECT_TRUE(log.header.complete);
    if (std::string(name) == "cloth_funnel") {
      // The step's ground truth (assets/cloth-funnel/mma_bool): 27 VF and 107 EE contacts;
      // conservative tests never miss one, and here report no more.
      const auto& s = result.checks[0].summary;
      EXPECT_EQ(s.ccd_vf, 27);
      EXPECT_EQ(s.ccd_ee, 107);
      EXPECT_FALSE(result.plan.objects[0].segmentation);
      EXPECT_TRUE(result.plan.objects[0].cones);
    }
    if (std::string(name) == "cape") {
      // The body is closed throughout: auto sends it whole to bvh, without a segmentation.
      EXPECT_TRUE(result.plan.objects[0].facts.auto_whole_to_bvh);
      EXPECT_FALSE(result.plan.objects[0].segmentation);
      EXPECT_FALSE(result.plan.objects[0].cones);
      EXPECT_TRUE(result.plan.objects[1].cones);  // the open cape
      EXPECT_FALSE(result.plan.objects[1].segmentation);
    }
  }
}

// --- the command line ------------------------------------------------------------------------

TEST(SceneCli, CheckPrintsThePlanThenTheSummaryAndWritesTheLog) {
  const auto log = test::temp_dir("scene_cli") / "panda.h5";
  const auto r =
      test::run_skelcd({"check", test::asset("scenes/panda.toml").string(), "-o", log.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto plan_at = r.out.find("plan      ");
  const auto result_at = r.out.find("result    self panda");
  ASSERT_NE(plan_at, std::string::npos) << r.out;
  ASSERT_NE(result_at, std::string::npos) << r.out;
  EXPECT_LT(plan_at, result_at);
  EXPECT_NE(r.out.find("skips swept bounds: no CCD check names it"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("result    pair hand upper_arm"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(log));
  // inspect reads the scene log, and a plain check's log still has no checks.
  const auto inspect = test::run_skelcd({"inspect", log.string()});
  EXPECT_EQ(inspect.exit_code, 0) << inspect.err;
  const auto plain = log.parent_path() / "plain.h5";
  ASSERT_EQ(
      test::run_skelcd({"check", "gen:hand?triangles=1000&frames=3", "-o", plain.string()})
          .exit_code,
      0);
  const auto data = read_log(plain);
  EXPECT_TRUE(data.header.checks.empty());
  EXPECT_TRUE(data.frame_checks.empty());
  EXPECT_EQ(data.frames.size(), 5u);

  const auto json = test::run_skelcd(
      {"check",
       test::asset("scenes/cloth_funnel.toml").string(),
       "-o",
       (log.parent_path() / "cf.h5").string(),
       "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["plan"]["objects"][0]["stages"]["segmentation"], false);
  EXPECT_EQ(j["checks"][0]["ccd_vf"], 27);
  EXPECT_EQ(j["checks"][0]["ccd_ee"], 107);

  // --frames overrides the scene's range for every check.
  const auto part = test::run_skelcd(
      {"check", test::asset("scenes/panda.toml").string(), "--frames", "40:43", "--json"});
  ASSERT_EQ(part.exit_code, 0) << part.err;
  const auto k = nlohmann::json::parse(part.out);
  EXPECT_EQ(k["plan"]["checks"][0]["rows"], 4 + 3);
  EXPECT_EQ(k["plan"]["checks"][1]["rows"], 4);
  EXPECT_EQ(k["checks"][1]["frames_with_interpenetration"], 4);  // samples 40–43 all intersect
  EXPECT_TRUE(k["log"].is_null());
}

TEST(SceneCli, ABadSceneIsOneLineExitOneAndNothingWritten) {
  const auto dir = test::temp_dir("scene_cli_bad");
  const auto scene = dir / "bad.toml";
  std::ofstream(scene)
      << "[objects.a]\nmodel = \"gen:rope?triangles=1000\"\nchecks = [\"self-dcd\"]\n"
         "[[pairs]]\nobjects = [\"a\", \"ghost\"]\nchecks = [\"dcd\"]\n";
  const auto log = dir / "out.h5";
  const auto r = test::run_skelcd({"check", scene.string(), "-o", log.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(scene.string() + ":5: pair 1: unknown object 'ghost'"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_FALSE(std::filesystem::exists(log));
}

}  // namespace
}  // namespace skelcd::tools

namespace skelcd::tools {
namespace {

// Scenes label their self checks against each object's baseline and allowances (docs/events.md):
// a baseline at a sample where the limbs touch leaves nothing new there; allowing every part with
// itself leaves nothing new at all; the log holds every check's events with ids and parts as in
// the log, and a bad baseline or allow entry is refused with its line.
TEST(SceneEvents, ObjectsAreLabelledAgainstTheirBaselineAndAllowances) {
  const std::string octopus = "gen:octopus?triangles=2000&frames=30";
  const auto path = write_scene(
      "baseline = \"sample:0\"\nframes = \"17:29\"\n"
      "[objects.free]\nmodel = \"" +
          octopus +
          "\"\nchecks = [\"self-dcd\"]\n"
          "[objects.touching]\nmodel = \"" +
          octopus +
          "\"\nchecks = [\"self-dcd\"]\n"
          "baseline = \"sample:29\"\n"
          "[objects.allowed]\nmodel = \"" +
          octopus +
          "\"\nchecks = [\"self-dcd\"]\n"
          "allow = [\"octopus:octopus\"]\n",
      "scene_events");
  const Scene scene = parse_scene(path);
  EXPECT_EQ(scene.objects[1].baseline.kind, BaselineSpec::Kind::sample);
  EXPECT_EQ(scene.objects[0].baseline.sample, 0);
  SceneRunOptions options;
  options.log = path.parent_path() / "log.h5";
  const auto result = run_scene(scene, options);
  const auto& free = check_named(result, "self free");
  const auto& touching = check_named(result, "self touching");
  const auto& allowed = check_named(result, "self allowed");
  ASSERT_FALSE(free.events.empty());
  EXPECT_GT(free.summary.new_dcd_pairs, 0);
  EXPECT_EQ(free.summary.new_dcd_pairs, free.summary.dcd_pairs);
  // The last sample is the touching object's baseline: nothing new there.
  EXPECT_EQ(touching.rows.back().counters.new_dcd_pairs, 0);
  EXPECT_EQ(
      touching.rows.back().counters.baseline_dcd_pairs, touching.rows.back().counters.dcd_pairs);
  EXPECT_GT(touching.rows.back().counters.dcd_pairs, 0);
  EXPECT_EQ(allowed.summary.new_dcd_pairs, 0);
  EXPECT_EQ(allowed.summary.allowed_dcd_pairs, free.summary.dcd_pairs);
  EXPECT_TRUE(allowed.events.empty());

  const auto log = read_log(options.log);
  ASSERT_TRUE(log.events_recorded);
  ASSERT_EQ(log.events.size(), free.events.size() + touching.events.size());
  for (std::size_t i = 0; i < log.events.size(); ++i) {
    EXPECT_EQ(log.events[i].id, static_cast<std::int32_t>(i));
  }
  // The touching object's events come after the free one's, with its parts.
  const auto touching_part = static_cast<std::int32_t>(
      std::find(log.header.part_names.begin(), log.header.part_names.end(), "touching/octopus") -
      log.header.part_names.begin());
  for (std::size_t i = free.events.size(); i < log.events.size(); ++i) {
    EXPECT_EQ(log.events[i].parts, (std::vector<std::int32_t>{touching_part}));
  }
  std::set<std::int32_t> labels;
  for (const auto& p : log.dcd_pairs) labels.insert(p.label);
  EXPECT_TRUE(labels.contains(kLabelAllowed));
  EXPECT_TRUE(labels.contains(kLabelBaseline));
  EXPECT_TRUE(labels.contains(0));

  EXPECT_THROW_MESSAGE(
      (void)parse_scene(write_scene(
          "[objects.a]\nmodel = \"" + octopus +
              "\"\nchecks = [\"self-dcd\"]\nbaseline = \"sample:x\"\n",
          "scene_events_bad")),
      InvalidInput,
      "scene.toml:4:");
  EXPECT_THROW_MESSAGE(
      (void)parse_scene(write_scene(
          "[objects.a]\nmodel = \"" + octopus +
              "\"\nchecks = [\"self-dcd\"]\nallow = [\"octopus\"]\n",
          "scene_events_bad2")),
      InvalidInput,
      "scene.toml:4:");
  // A name that is neither a part nor a bone is refused before any work, naming the object.
  const auto unknown = write_scene(
      "[objects.a]\nmodel = \"" + octopus +
          "\"\nchecks = [\"self-dcd\"]\nallow = [\"octopus:fin\"]\n",
      "scene_events_bad3");
  EXPECT_THROW_MESSAGE((void)run_scene(parse_scene(unknown)), InvalidInput, "'fin'");
}

}  // namespace
}  // namespace skelcd::tools
