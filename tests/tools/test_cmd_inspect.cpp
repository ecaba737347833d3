// skelcd inspect as a user runs it: several logs with known contents plus files that are not
// readable logs (truncated, foreign HDF5, plain text), sorting, CSV/JSON, the per-frame table, plots.

#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/log/log_writer.hpp"

namespace {

using namespace skelcd::tools;
using skelcd::test::run_skelcd;

struct RowSpec {
  QueryKind kind;
  int sample;
  int dcd_pairs = 0;
  int vf = 0;
  int ee = 0;
  int candidates = 0;
  double total_us = 1000;
};

/// Writes a log whose rows have the given findings (with matching /contacts and /dcd_pairs rows).
void write_log(const std::filesystem::path& path, const std::string& method,
               const std::vector<RowSpec>& rows, bool finish = true) {
  LogHeader h;
  h.skelcd_version = "test";
  h.input_path = "/models/" + method + "-model.x";
  h.clip = "clip-" + method;
  h.method = method;
  h.accuracy = "conservative";
  h.query = "both";
  h.fps = 30;
  h.planned_rows = static_cast<std::int64_t>(rows.size()) + (finish ? 0 : 3);
  h.part_names = {"body"};
  LogWriter writer(path, h);
  for (const auto& spec : rows) {
    FrameReport r;
    r.row.kind = spec.kind;
    r.row.sample = spec.sample;
    r.row.t0 = spec.sample / 30.0;
    r.row.t1 = spec.kind == QueryKind::ccd ? (spec.sample + 1) / 30.0 : r.row.t0;
    r.row.counters.dcd_pairs = spec.dcd_pairs;
    r.row.counters.vf_contacts = spec.vf;
    r.row.counters.ee_contacts = spec.ee;
    r.row.counters.candidate_pairs = spec.candidates;
    r.row.total_us = spec.total_us;
    for (int i = 0; i < spec.dcd_pairs; ++i) {
      r.dcd_pairs.push_back({spec.sample, {0, i, -1}, {0, 100 + i, -1}});
    }
    for (int i = 0; i < spec.vf + spec.ee; ++i) {
      const auto kind = i < spec.vf ? skelcd::culling::CcdContact::Kind::vf
                                    : skelcd::culling::CcdContact::Kind::ee;
      r.contacts.push_back({spec.sample, kind, {0, i, -1}, {0, 50 + i, -1}, 0.5, 0.5});
    }
    writer.append(r);
  }
  if (finish) writer.finish();
}

/// Three logs: bvh (findings in frames 0 and 2), kdop (none), brute (slow, one CCD contact).
std::filesystem::path make_logs(const std::string& name) {
  const auto dir = skelcd::test::temp_dir(name);
  write_log(dir / "bvh.h5", "bvh",
            {{QueryKind::dcd, 0, 2, 0, 0, 10},
             {QueryKind::ccd, 0, 0, 1, 2, 40},
             {QueryKind::dcd, 1, 0, 0, 0, 12},
             {QueryKind::ccd, 1, 0, 0, 0, 30},
             {QueryKind::dcd, 2, 1, 0, 0, 11}});
  write_log(dir / "kdop.h5", "kdop",
            {{QueryKind::dcd, 0, 0, 0, 0, 5, 500},
             {QueryKind::ccd, 0, 0, 0, 0, 7, 500},
             {QueryKind::dcd, 1, 0, 0, 0, 6, 500}});
  write_log(dir / "brute.h5", "brute",
            {{QueryKind::ccd, 4, 0, 1, 0, 900, 9000}, {QueryKind::ccd, 5, 0, 0, 0, 800, 9000}});
  return dir;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::size_t count_lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST(CmdInspect, SummarisesGoodLogsAndSkipsBadOnesByName) {
  const auto dir = make_logs("inspect-mixed");
  // A truncated log, a foreign HDF5 file and a text file.
  const std::string bytes = read_text(dir / "bvh.h5");
  write_text(dir / "truncated.h5", bytes.substr(0, bytes.size() / 2));
  write_text(dir / "notes.h5", "not hdf5 at all\n");
  write_text(dir / "make.py", "import h5py\nwith h5py.File('" + (dir / "foreign.h5").string() +
                                  "', 'w') as f:\n    f['frames'] = [1, 2, 3]\n");
  ASSERT_EQ(std::system(("/usr/bin/python3 " + (dir / "make.py").string()).c_str()), 0);

  const auto r = run_skelcd({"inspect", (dir / "bvh.h5").string(), (dir / "truncated.h5").string(),
                             (dir / "kdop.h5").string(), (dir / "foreign.h5").string(),
                             (dir / "notes.h5").string(), (dir / "brute.h5").string(), "--json"});
  // The good logs are summarised, each bad one named, and the exit status says some were bad.
  EXPECT_EQ(r.exit_code, 1) << r.err;
  for (const char* bad : {"truncated.h5", "foreign.h5", "notes.h5"}) {
    EXPECT_NE(r.err.find(std::string(bad) + ": "), std::string::npos) << r.err;
  }
  EXPECT_NE(r.err.find("3 of 6 files skipped"), std::string::npos) << r.err;
  EXPECT_EQ(count_lines(r.err), 4u) << r.err;
  const auto out = nlohmann::json::parse(r.out);
  ASSERT_EQ(out.size(), 3u);
  const auto& bvh = out[0];
  EXPECT_EQ(bvh["method"], "bvh");
  EXPECT_EQ(bvh["model"], "bvh-model.x");
  EXPECT_EQ(bvh["clip"], "clip-bvh");
  EXPECT_EQ(bvh["frames"], 3);
  EXPECT_EQ(bvh["intervals"], 2);
  EXPECT_EQ(bvh["frames_with_contacts"], 2);  // sample 0 (DCD and CCD) and sample 2
  EXPECT_EQ(bvh["dcd_pairs"], 3);
  EXPECT_EQ(bvh["ccd_contacts"], 3);
  EXPECT_EQ(bvh["contacts"], 6);
  EXPECT_EQ(bvh["max_candidate_pairs"], 40);
  EXPECT_DOUBLE_EQ(bvh["ms_per_interval"].get<double>(), 2.5);  // 5 rows × 1 ms / 2 intervals
  EXPECT_EQ(bvh["complete"], "yes");
  EXPECT_EQ(out[1]["method"], "kdop");
  EXPECT_EQ(out[1]["contacts"], 0);
  EXPECT_DOUBLE_EQ(out[1]["ms_per_interval"].get<double>(), 1.5);
  EXPECT_EQ(out[2]["method"], "brute");
  EXPECT_EQ(out[2]["frames"], 3);  // CCD only: 2 intervals span 3 samples
  EXPECT_EQ(out[2]["ccd_contacts"], 1);
  EXPECT_DOUBLE_EQ(out[2]["ms_per_interval"].get<double>(), 9.0);
}

TEST(CmdInspect, TableSortsByAnyColumn) {
  const auto dir = make_logs("inspect-sort");
  const std::vector<std::string> logs{(dir / "bvh.h5").string(), (dir / "kdop.h5").string(),
                                      (dir / "brute.h5").string()};
  auto args = std::vector<std::string>{"inspect"};
  args.insert(args.end(), logs.begin(), logs.end());
  auto sorted = args;
  sorted.insert(sorted.end(), {"--sort", "ms_per_interval", "--desc"});
  const auto r = run_skelcd(sorted);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(count_lines(r.out), 4u) << r.out;  // header + 3 logs
  const auto brute = r.out.find("brute.h5");
  const auto bvh = r.out.find("bvh.h5");
  const auto kdop = r.out.find("kdop.h5");
  EXPECT_LT(brute, bvh);
  EXPECT_LT(bvh, kdop);
  EXPECT_EQ(r.out.rfind("log", 0), 0u);  // header first

  auto by_method = args;
  by_method.insert(by_method.end(), {"--sort", "method", "--json"});
  const auto j = nlohmann::json::parse(run_skelcd(by_method).out);
  EXPECT_EQ(j[0]["method"], "brute");
  EXPECT_EQ(j[1]["method"], "bvh");
  EXPECT_EQ(j[2]["method"], "kdop");

  auto unknown = args;
  unknown.insert(unknown.end(), {"--sort", "nonsense"});
  const auto bad = run_skelcd(unknown);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(count_lines(bad.err), 1u) << bad.err;
  EXPECT_NE(bad.err.find("nonsense"), std::string::npos);
}

TEST(CmdInspect, CsvHasAHeaderAndOneLinePerLog) {
  const auto dir = make_logs("inspect-csv");
  const auto r = run_skelcd({"inspect", (dir / "bvh.h5").string(), (dir / "kdop.h5").string(),
                             "--csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string header, first, second, extra;
  std::getline(lines, header);
  std::getline(lines, first);
  std::getline(lines, second);
  EXPECT_FALSE(std::getline(lines, extra));
  EXPECT_EQ(header.rfind("log,model,clip,method,", 0), 0u) << header;
  EXPECT_NE(first.find(",bvh,conservative,both,3,2,2,3,3,6,40,2.5,yes"), std::string::npos) << first;
  EXPECT_NE(second.find(",kdop,"), std::string::npos);
}

TEST(CmdInspect, FramesTableOfOneLog) {
  const auto dir = make_logs("inspect-frames");
  const auto r = run_skelcd({"inspect", (dir / "bvh.h5").string(), "--frames", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["rows"].size(), 5u);
  EXPECT_EQ(j["rows"][1]["kind"], "ccd");
  EXPECT_EQ(j["rows"][1]["vf_contacts"], 1);
  EXPECT_EQ(j["rows"][1]["ee_contacts"], 2);
  EXPECT_EQ(j["rows"][4]["dcd_pairs"], 1);

  const auto two = run_skelcd({"inspect", (dir / "bvh.h5").string(), (dir / "kdop.h5").string(),
                               "--frames"});
  EXPECT_EQ(two.exit_code, 1);
  EXPECT_NE(two.err.find("exactly one log"), std::string::npos) << two.err;
}

TEST(CmdInspect, PartialLogIsShownAsIncomplete) {
  const auto dir = skelcd::test::temp_dir("inspect-partial");
  write_log(dir / "cut.h5", "bvh", {{QueryKind::dcd, 0, 1}, {QueryKind::ccd, 0}}, /*finish=*/false);
  const auto r = run_skelcd({"inspect", (dir / "cut.h5").string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j[0]["complete"], "no (2/5 rows)");
  EXPECT_EQ(j[0]["dcd_pairs"], 1);
}

TEST(CmdInspect, WritesOnePngPerLog) {
  const auto dir = make_logs("inspect-plot");
  const auto plots = dir / "plots";
  const auto r = run_skelcd({"inspect", (dir / "bvh.h5").string(), (dir / "kdop.h5").string(),
                             (dir / "brute.h5").string(), "--plot", plots.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"bvh.png", "kdop.png", "brute.png"}) {
    const std::string png = read_text(plots / name);
    ASSERT_GT(png.size(), 10000u) << name;
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << name;
    // IHDR: width and height, big-endian, at bytes 16..23: 1000 × 900 (three 300 px panels).
    const auto be32 = [&](std::size_t at) {
      return (static_cast<unsigned>(static_cast<unsigned char>(png[at])) << 24) |
             (static_cast<unsigned>(static_cast<unsigned char>(png[at + 1])) << 16) |
             (static_cast<unsigned>(static_cast<unsigned char>(png[at + 2])) << 8) |
             static_cast<unsigned>(static_cast<unsigned char>(png[at + 3]));
    };
    EXPECT_EQ(be32(16), 1000u) << name;
    EXPECT_EQ(be32(20), 900u) << name;
    EXPECT_NE(r.out.find((plots / name).string()), std::string::npos) << r.out;
  }
}

TEST(CmdInspect, FailsOnlyWhenNoFileIsReadable) {
  const auto dir = skelcd::test::temp_dir("inspect-none");
  write_text(dir / "a.h5", "junk");
  const auto r = run_skelcd({"inspect", (dir / "a.h5").string(), (dir / "missing.h5").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a.h5: not an HDF5 file"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing.h5: no such file"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("none of the 2 files"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
}

}  // namespace
