// skelcd preprocess as a user meets it: Table 1 statistics (text and JSON), the saved HDF5 file
// (h5dump opens it; read back equal to what was computed; its input hash checked), clip averages,
// and bad input refused with one line and nothing written.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/segmentation_file.hpp"

namespace {

using skelcd::test::run_skelcd;
namespace fs = std::filesystem;

const fs::path kBcn = skelcd::test::assimp_model("X/BCN_Epileptic.X");

fs::path character(const std::string& name) { return skelcd::test::asset("characters/" + name); }

// Runs a shell command, returns its exit status and standard output.
std::pair<int, std::string> shell(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::string out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = fread(buffer, 1, sizeof buffer, pipe.get())) > 0) out.append(buffer, n);
  const int status = pclose(pipe.release());
  return {WEXITSTATUS(status), out};
}

TEST(CmdPreprocess, JsonReportsTable1Statistics) {
  const auto r = run_skelcd({"preprocess", kBcn.string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"atomic_clusters", "h_minus", "h_uncertain", "weights_s",
                          "decomposition_ms", "triangles", "vertices"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["triangles"].get<int>(), 5126);
  EXPECT_EQ(j["bones"].get<int>(), 54);
  EXPECT_GT(j["atomic_clusters"].get<int>(), 0);
  EXPECT_GE(j["h_minus"].get<int>(), 0);
  EXPECT_GT(j["weights_s"].get<double>(), 0.0);
  EXPECT_GT(j["decomposition_ms"].get<double>(), 0.0);
  EXPECT_TRUE(j["clip"].is_null());
  // Refinement never makes it worse.
  EXPECT_LE(j["refinement"]["non_positive_after"].get<int>(),
            j["refinement"]["non_positive_before"].get<int>());
}

TEST(CmdPreprocess, SavedFileOpensInH5dumpAndReadsBackAsComputed) {
  const auto dir = skelcd::test::temp_dir("cmd_preprocess_saved");
  const auto out = dir / "seg.h5";
  const auto r = run_skelcd({"preprocess", kBcn.string(), "--weights", "rig", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("atomic clusters"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("|H-|"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(out));

  // h5dump, knowing nothing of skelcd, reads the header and the tables.
  const auto [status, dump] = shell("h5dump -H '" + out.string() + "' 2>&1");
  EXPECT_EQ(status, 0) << dump;
  for (const char* name : {"triangle_cluster", "observer_kind", "format", "input_hash", "joint"}) {
    EXPECT_NE(dump.find(name), std::string::npos) << name;
  }

  // Equal to the segmentation computed here with the same options (the computation is
  // deterministic), and the input hash ties it to the model.
  const auto file = skelcd::tools::read_segmentation(out, kBcn.string());
  const auto model = skelcd::skinning::load_model(kBcn);
  skelcd::segmentation::SegmentationOptions options;
  options.weights = skelcd::segmentation::WeightSource::rig;
  const auto expected = skelcd::segmentation::segment(*model.rig, options);
  EXPECT_EQ(file.segmentation.triangle_cluster, expected.triangle_cluster);
  ASSERT_EQ(file.segmentation.clusters.size(), expected.clusters.size());
  for (std::size_t c = 0; c < expected.clusters.size(); ++c) {
    EXPECT_EQ(file.segmentation.clusters[c].bone, expected.clusters[c].bone);
    EXPECT_EQ(file.segmentation.clusters[c].observer.kind, expected.clusters[c].observer.kind);
    EXPECT_EQ(file.segmentation.clusters[c].triangles, expected.clusters[c].triangles);
    EXPECT_EQ(file.segmentation.clusters[c].observer.segment.head,
              expected.clusters[c].observer.segment.head);
  }
  ASSERT_EQ(file.segmentation.graph.size(), expected.graph.size());
  for (std::size_t e = 0; e < expected.graph.size(); ++e) {
    EXPECT_EQ(file.segmentation.graph[e].a, expected.graph[e].a);
    EXPECT_EQ(file.segmentation.graph[e].b, expected.graph[e].b);
    EXPECT_EQ(file.segmentation.graph[e].shared_edges, expected.graph[e].shared_edges);
    EXPECT_EQ(file.segmentation.graph[e].joint, expected.graph[e].joint);
  }
  EXPECT_EQ(file.segmentation.stats.h_minus, expected.stats.h_minus);
  EXPECT_EQ(file.segmentation.options.weights, skelcd::segmentation::WeightSource::rig);
  EXPECT_EQ(file.record.bone_names.size(), 54u);
  EXPECT_TRUE(skelcd::tools::segmentation_matches(out, kBcn.string()));

  // A different model: the hash check refuses it, and matches() says no.
  const auto fox = character("Fox.glb");
  EXPECT_FALSE(skelcd::tools::segmentation_matches(out, fox.string()));
  EXPECT_THROW_MESSAGE(std::ignore = skelcd::tools::read_segmentation(out, fox.string()),
                       skelcd::InvalidInput, "different file");
}

TEST(CmdPreprocess, DocumentedH5pyExampleReadsASegmentation) {
  // The python block of docs/segmentation.md, run as it stands on a file written here, with
  // Debian's interpreter (where python3-h5py is installed).
  const auto dir = skelcd::test::temp_dir("cmd_preprocess_h5py");
  const auto out = dir / "seg.h5";
  ASSERT_EQ(run_skelcd({"preprocess", character("Fox.glb").string(), "-o", out.string()}).exit_code, 0);
  std::ifstream doc(fs::path(SKELCD_SOURCE_DIR) / "docs/segmentation.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  const auto begin = text.find("```python\n");
  ASSERT_NE(begin, std::string::npos) << "docs/segmentation.md has no python example";
  const auto end = text.find("```", begin + 10);
  const auto script = dir / "example.py";
  { std::ofstream(script) << text.substr(begin + 10, end - begin - 10); }
  const auto [status, output] =
      shell("/usr/bin/python3 '" + script.string() + "' '" + out.string() + "' 2>&1");
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("clusters"), std::string::npos) << output;
  EXPECT_NE(output.find("h_minus:"), std::string::npos) << output;
}

TEST(CmdPreprocess, GeneratedRigsAreIdentifiedByTheirSpec) {
  const auto dir = skelcd::test::temp_dir("cmd_preprocess_gen");
  const auto out = dir / "octopus.h5";
  const std::string spec = "gen:octopus?triangles=4000";
  const auto r = run_skelcd({"preprocess", spec, "-o", out.string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto file = skelcd::tools::read_segmentation(out, spec);
  EXPECT_EQ(file.record.input_hash.rfind("gen:octopus?", 0), 0u) << file.record.input_hash;
  EXPECT_TRUE(skelcd::tools::segmentation_matches(out, spec));
  EXPECT_FALSE(skelcd::tools::segmentation_matches(out, "gen:octopus?triangles=5000"));
  EXPECT_FALSE(skelcd::tools::segmentation_matches(out, kBcn.string()));
}

TEST(CmdPreprocess, ClipAveragesAndCoarseDistance) {
  const auto model = skelcd::skinning::load_model(character("CesiumMan.glb"));
  ASSERT_FALSE(model.clips.empty());
  const auto r2 = run_skelcd({"preprocess", character("CesiumMan.glb").string(), "--distance",
                              "coarse", "--clip", model.clips[0].name, "--json"});
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  const auto j = nlohmann::json::parse(r2.out);
  ASSERT_TRUE(j["clip"].is_object());
  EXPECT_GT(j["clip"]["intervals"].get<int>(), 0);
  EXPECT_GE(j["clip"]["mean_h_minus"].get<double>(), 0.0);
  EXPECT_EQ(j["distance"], "coarse");
}

TEST(CmdPreprocess, RobotsTakeTheirTrajectoryAndSrdf) {
  // The robot options reach preprocess: the Panda moved by its bundled reach trajectory (61 rows,
  // so 60 intervals), with the rig's own (rigid, one link each) weights.
  const auto urdf =
      skelcd::test::asset("robots/example-robot-data/robots/panda_description/urdf/panda.urdf");
  const auto trajectory = skelcd::test::asset("trajectories/panda_reach.csv");
  const auto r = run_skelcd({"preprocess", urdf.string(), "--trajectory", trajectory.string(),
                             "--weights", "rig", "--clip", "panda_reach", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["bones"].get<int>(), 11);
  ASSERT_TRUE(j["clip"].is_object());
  EXPECT_EQ(j["clip"]["intervals"].get<int>(), 60);
  EXPECT_TRUE(j["bones_without_cluster"].empty());
  // Without --trajectory there is no such clip; a missing trajectory file is named.
  const auto no_clip = run_skelcd({"preprocess", urdf.string(), "--clip", "panda_reach"});
  EXPECT_NE(no_clip.exit_code, 0);
  EXPECT_NE(no_clip.err.find("panda_reach"), std::string::npos) << no_clip.err;
  const auto missing = run_skelcd({"preprocess", urdf.string(), "--trajectory", "no-such.csv"});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("no-such.csv"), std::string::npos) << missing.err;
}

TEST(CmdPreprocess, BadInputIsOneLineAndWritesNothing) {
  const auto dir = skelcd::test::temp_dir("cmd_preprocess_bad");
  const auto out = dir / "seg.h5";
  const auto expect_refused = [&](const std::vector<std::string>& args, const std::string& part) {
    const auto r = run_skelcd(args);
    EXPECT_NE(r.exit_code, 0) << r.out;
    EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out));
  };
  expect_refused({"preprocess", (dir / "missing.glb").string(), "-o", out.string()}, "missing.glb");
  expect_refused({"preprocess", kBcn.string(), "--weights", "magic", "-o", out.string()}, "--weights");
  expect_refused({"preprocess", kBcn.string(), "--distance", "far", "-o", out.string()}, "--distance");
  expect_refused({"preprocess", kBcn.string(), "--theta", "400", "-o", out.string()}, "--theta");
  expect_refused({"preprocess", kBcn.string(), "--clip", "no-such-clip", "-o", out.string()},
                 "no-such-clip");
  // A mesh without a skeleton.
  expect_refused({"preprocess", skelcd::test::assimp_model("OBJ/box.obj").string(), "-o", out.string()},
                 "box.obj");
  // An existing file that is not a segmentation is never overwritten.
  const auto precious = dir / "notes.h5";
  { std::ofstream(precious) << "not hdf5\n"; }
  const auto r = run_skelcd({"preprocess", kBcn.string(), "-o", precious.string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("refusing"), std::string::npos) << r.err;
  std::ifstream in(precious);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "not hdf5\n");
  // Reading something that is not a segmentation.
  EXPECT_THROW_MESSAGE(std::ignore = skelcd::tools::read_segmentation(precious), skelcd::IoError,
                       "not an HDF5 file");
  EXPECT_THROW_MESSAGE(std::ignore = skelcd::tools::read_segmentation(dir / "none.h5"),
                       skelcd::IoError, "no such file");
}

}  // namespace
