// skelcd check --method rvbc|dynamic as a user runs it: the same contacts as bvh, the Table 3
// columns in the log (clusters, |H⁻|, |Hᵘ|, RV-update times), γ in the header, a segmentation
// from `skelcd preprocess` reused, and bad input refused in one line.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tuple>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace {

using namespace skelcd::tools;
using skelcd::test::run_skelcd;

const std::string kCesium = skelcd::test::asset("characters/CesiumMan.glb").string();
const std::string kFox = skelcd::test::asset("characters/Fox.glb").string();

using Key = std::tuple<int, int, int, int, int, int, int, int>;
std::vector<Key> contact_keys(const LogData& log) {
  std::vector<Key> keys;
  for (const auto& c : log.contacts) {
    keys.emplace_back(c.frame, static_cast<int>(c.kind), c.a.part, c.a.index, c.a.side, c.b.part,
                      c.b.index, c.b.side);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

TEST(RadialViewCheck, SameContactsAsBvhAndTable3Columns) {
  const auto dir = skelcd::test::temp_dir("rv-check");
  std::vector<LogData> logs;
  for (const char* method : {"bvh", "rvbc", "dynamic"}) {
    const auto log = (dir / (std::string(method) + ".h5")).string();
    const auto r = run_skelcd({"check", kCesium, "--frames", "0:6", "--query", "ccd", "--method",
                               method, "--json", "-o", log});
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["method"], method);
    logs.push_back(read_log(log));
  }
  ASSERT_FALSE(logs[0].contacts.empty());
  EXPECT_EQ(contact_keys(logs[1]), contact_keys(logs[0]));
  EXPECT_EQ(contact_keys(logs[2]), contact_keys(logs[0]));
  // The Table 3 columns: clusters per interval, classification and merge times.
  const auto& dynamic = logs[2];
  EXPECT_EQ(dynamic.header.method, "dynamic");
  ASSERT_TRUE(dynamic.header.gamma.has_value());
  EXPECT_DOUBLE_EQ(*dynamic.header.gamma, 0.05);
  EXPECT_FALSE(logs[1].header.gamma.has_value());  // rvbc does not merge
  ASSERT_TRUE(dynamic.header.seed.has_value());
  EXPECT_EQ(*dynamic.header.seed, 1);
  EXPECT_FALSE(logs[1].header.seed.has_value());
  EXPECT_EQ(dynamic.header.segmentation, "computed (rig weights)");
  EXPECT_TRUE(logs[0].header.segmentation.empty());  // bvh: no radial view
  ASSERT_EQ(dynamic.frames.size(), 6u);
  for (const auto& row : dynamic.frames) {
    EXPECT_GT(row.counters.atomic_clusters, 0);
    EXPECT_GT(row.counters.mega_clusters, 0);
    EXPECT_LE(row.counters.mega_clusters, row.counters.atomic_clusters);
    EXPECT_GT(row.times.classify_us, 0.0);
    EXPECT_GT(row.counters.h_minus + row.counters.h_uncertain, 0);
  }
  for (const auto& row : logs[1].frames) {
    EXPECT_EQ(row.counters.mega_clusters, row.counters.atomic_clusters);
  }
  for (const auto& row : logs[0].frames) EXPECT_EQ(row.counters.atomic_clusters, 0);
}

TEST(RadialViewCheck, ReusesAPreprocessedSegmentation) {
  const auto dir = skelcd::test::temp_dir("rv-seg");
  const auto seg = (dir / "cesium.seg.h5").string();
  const auto pre = run_skelcd({"preprocess", kCesium, "--weights", "rig", "-o", seg});
  ASSERT_EQ(pre.exit_code, 0) << pre.err;
  const auto with_file = run_skelcd({"check", kCesium, "--frames", "2:4", "--query", "ccd",
                                     "--method", "dynamic", "--segmentation", seg, "--json"});
  const auto computed = run_skelcd(
      {"check", kCesium, "--frames", "2:4", "--query", "ccd", "--method", "dynamic", "--json"});
  ASSERT_EQ(with_file.exit_code, 0) << with_file.err;
  ASSERT_EQ(computed.exit_code, 0) << computed.err;
  const auto a = nlohmann::json::parse(with_file.out);
  const auto b = nlohmann::json::parse(computed.out);
  EXPECT_EQ(a["ccd_vf"], b["ccd_vf"]);
  EXPECT_EQ(a["ccd_ee"], b["ccd_ee"]);
  // The summary says which segmentation ran: the file, or the one computed from the rig.
  EXPECT_EQ(a["segmentation"], seg);
  EXPECT_EQ(b["segmentation"], "computed (rig weights)");
  // A segmentation of another model is not used: the model is segmented anew, with a note
  // naming the file, and the contacts are those of the computed segmentation.
  const auto fox_seg = (dir / "fox.seg.h5").string();
  ASSERT_EQ(run_skelcd({"preprocess", kFox, "--weights", "rig", "-o", fox_seg}).exit_code, 0);
  const auto wrong = run_skelcd({"check", kCesium, "--frames", "2:4", "--query", "ccd", "--method",
                                 "dynamic", "--segmentation", fox_seg, "--json"});
  ASSERT_EQ(wrong.exit_code, 0) << wrong.err;
  EXPECT_NE(wrong.err.find("fox.seg.h5"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("segmenting it anew"), std::string::npos) << wrong.err;
  const auto c = nlohmann::json::parse(wrong.out);
  EXPECT_EQ(c["segmentation"], "computed (rig weights)");
  EXPECT_EQ(c["ccd_vf"], b["ccd_vf"]);
  EXPECT_EQ(c["ccd_ee"], b["ccd_ee"]);
  // A file that is no segmentation at all is refused.
  const auto not_seg = (dir / "not-a-seg.h5").string();
  std::ofstream(not_seg) << "not hdf5";
  const auto bad = run_skelcd({"check", kCesium, "--frames", "0:1", "--method", "rvbc",
                               "--segmentation", not_seg});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("not-a-seg.h5"), std::string::npos) << bad.err;
}

TEST(RadialViewCheck, AutoTakesRadialViewOnADenseRigClosedThroughout) {
  // `auto` sends a mesh closed throughout to `bvh` only under 20,000 triangles
  // (culling::RoutingOptions::all_closed_below_triangles): CesiumMan (4,672) goes to `bvh`,
  // CesiumMan-dense (28,032) to `dynamic` on the rig's own weights — its log's Table 3 columns
  // and routes say so — and finds `bvh`'s contacts and DCD pairs.
  const auto dir = skelcd::test::temp_dir("rv-auto-dense");
  const std::string dense = skelcd::test::asset("characters/CesiumMan-dense.glb").string();
  std::vector<LogData> logs;
  std::vector<nlohmann::json> summaries;
  for (const char* method : {"bvh", "auto"}) {
    const auto log = (dir / (std::string(method) + ".h5")).string();
    const auto r =
        run_skelcd({"check", dense, "--frames", "0:4", "--method", method, "--json", "-o", log});
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    summaries.push_back(nlohmann::json::parse(r.out));
    logs.push_back(read_log(log));
  }
  EXPECT_EQ(summaries[1]["method"], "auto");
  EXPECT_EQ(summaries[1]["segmentation"], "computed (rig weights)");
  ASSERT_FALSE(logs[0].contacts.empty());
  EXPECT_EQ(contact_keys(logs[1]), contact_keys(logs[0]));
  EXPECT_GT(summaries[0]["dcd_pairs"].get<std::int64_t>(), 0);
  EXPECT_EQ(summaries[1]["dcd_pairs"], summaries[0]["dcd_pairs"]);
  EXPECT_EQ(summaries[1]["ccd_vf"], summaries[0]["ccd_vf"]);
  EXPECT_EQ(summaries[1]["ccd_ee"], summaries[0]["ccd_ee"]);
  bool culled = false;
  for (const auto& row : logs[1].frames) culled = culled || row.counters.mega_clusters > 0;
  EXPECT_TRUE(culled) << "no CCD row of auto's ran radial view";
  const auto small = run_skelcd({"check", kCesium, "--frames", "0:2", "--json"});
  ASSERT_EQ(small.exit_code, 0) << small.err;
  EXPECT_EQ(
      nlohmann::json::parse(small.out)["segmentation"],
      "none (auto: every part closed, small or capped, under 20000 triangles, the whole mesh to "
      "bvh)");
}

TEST(RadialViewCheck, DcdOnlyBuildsNoSegmentationAndFindsBvhsPairs) {
  // Radial view culls intervals; at an instant rvbc/dynamic answer with bvh. So --query dcd must
  // not segment: a --segmentation file is not even read (this one is no HDF5 file at all).
  const auto dir = skelcd::test::temp_dir("rv-dcd");
  const auto not_seg = (dir / "not-a-seg.h5").string();
  std::ofstream(not_seg) << "not hdf5";
  const auto bvh = run_skelcd(
      {"check", kCesium, "--frames", "0:8", "--query", "dcd", "--method", "bvh", "--json"});
  ASSERT_EQ(bvh.exit_code, 0) << bvh.err;
  const auto bvh_pairs = nlohmann::json::parse(bvh.out)["dcd_pairs"];
  ASSERT_GT(bvh_pairs.get<std::int64_t>(), 0);  // CesiumMan's walk does interpenetrate
  for (const char* method : {"rvbc", "dynamic", "auto"}) {
    const auto log = (dir / (std::string(method) + ".h5")).string();
    const auto r = run_skelcd(
        {"check",
         kCesium,
         "--frames",
         "0:8",
         "--query",
         "dcd",
         "--method",
         method,
         "--segmentation",
         not_seg,
         "--json",
         "-o",
         log});
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    EXPECT_NE(r.err.find("is not used: --query dcd needs no segmentation"), std::string::npos)
        << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["method"], method);
    EXPECT_EQ(j["dcd_pairs"], bvh_pairs) << method;
    EXPECT_EQ(j["segmentation"], "none (DCD only: no radial-view stage runs)") << method;
    const auto data = read_log(log);
    ASSERT_EQ(data.frames.size(), 9u);
    for (const auto& row : data.frames) {
      EXPECT_EQ(row.counters.atomic_clusters + row.counters.mega_clusters, 0) << method;
      EXPECT_EQ(row.times.classify_us + row.times.merge_us, 0.0) << method;
    }
  }
}

TEST(RadialViewCheck, BadInputIsRefusedInOneLine) {
  const auto dir = skelcd::test::temp_dir("rv-bad");
  const auto log = (dir / "out.h5");
  const auto gamma = run_skelcd({"check", kCesium, "--frames", "0:1", "--method", "dynamic",
                                 "--gamma", "2", "-o", log.string()});
  EXPECT_EQ(gamma.exit_code, 1);
  EXPECT_NE(gamma.err.find("--gamma"), std::string::npos) << gamma.err;
  EXPECT_EQ(std::count(gamma.err.begin(), gamma.err.end(), '\n'), 1);
  EXPECT_FALSE(std::filesystem::exists(log));
  // A frame sequence has no bones to move the observers.
  const auto frames = run_skelcd({"check", skelcd::test::asset("cloth-funnel/frames").string(),
                                  "--frames", "0:1", "--method", "dynamic"});
  EXPECT_EQ(frames.exit_code, 1);
  EXPECT_NE(frames.err.find("rigged model"), std::string::npos) << frames.err;
  const auto missing = run_skelcd({"check", kCesium, "--method", "rvbc", "--segmentation",
                                   (dir / "none.h5").string()});
  EXPECT_EQ(missing.exit_code, 1);
}

}  // namespace
