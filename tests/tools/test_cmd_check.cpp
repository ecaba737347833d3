// skelcd check as a user runs it on a real character: JSON summary consistent with the log it
// writes, bvh against the brute-force reference, bad inputs refused in one line with no log
// left behind, and a run killed with SIGKILL half-way leaving a log that our reader, h5dump and
// skelcd inspect all read.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <tuple>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace {

using namespace skelcd::tools;
using skelcd::test::run_skelcd;

const std::string kModel =
    skelcd::test::assimp_model("X/BCN_Epileptic.X").string();  // 5126 triangles, 100 samples

std::size_t count_lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

/// Sorted contact and pair keys of a log, to compare two logs' findings as sets.
using ContactKey = std::tuple<int, int, int, int, int, int, int, int>;
std::vector<ContactKey> contact_keys(const LogData& log) {
  std::vector<ContactKey> keys;
  for (const auto& c : log.contacts) {
    keys.emplace_back(c.frame, static_cast<int>(c.kind), c.a.part, c.a.index, c.a.side, c.b.part,
                      c.b.index, c.b.side);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}
std::vector<std::tuple<int, int, int, int, int>> pair_keys(const LogData& log) {
  std::vector<std::tuple<int, int, int, int, int>> keys;
  for (const auto& p : log.dcd_pairs) {
    keys.emplace_back(p.frame, p.a.part, p.a.index, p.b.part, p.b.index);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

// setup_ms: the phases before the first row, each measured on its own. A serial check runs them
// one after the other, so they fit in the total; a parallel one computes the baseline beside the
// others (only the rest must fit).
TEST(CmdCheck, SetupTimesFitInTheTimeBeforeTheFirstRow) {
  for (const char* threads : {"1", "2"}) {
    const auto r = run_skelcd(
        {"check",
         kModel,
         "--method",
         "dynamic",
         "--frames",
         "0:2",
         "--threads",
         threads,
         "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_TRUE(j.contains("setup_ms")) << r.out;
    const auto& s = j["setup_ms"];
    double parts = 0;
    for (const char* phase : {"topology", "segmentation", "baseline", "methods"}) {
      ASSERT_TRUE(s.contains(phase)) << phase;
      EXPECT_GT(s[phase].get<double>(), 0.0) << phase << " (" << threads << " threads)";
      if (std::string(threads) == "1" || std::string(phase) != "baseline") {
        parts += s[phase].get<double>();
      }
    }
    EXPECT_LE(parts, s["total"].get<double>()) << threads << " threads: " << s.dump();
  }
  const auto text = run_skelcd({"check", kModel, "--method", "bvh", "--frames", "0:1"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("\nset-up    "), std::string::npos) << text.out;
}

TEST(CmdCheck, JsonSummaryMatchesTheLogItWrote) {
  const auto dir = skelcd::test::temp_dir("check-json");
  const auto log_path = (dir / "bcn.h5").string();
  const auto r = run_skelcd({"check", kModel, "--frames", "10:13", "--json", "-o", log_path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"frames", "intervals", "method", "accuracy", "dcd_pairs", "ccd_vf",
                          "ccd_ee", "frames_with_contacts", "ms_per_interval", "stages_ms"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["frames"], 4);
  EXPECT_EQ(j["intervals"], 3);
  EXPECT_EQ(j["method"], "auto");  // the default (docs/benchmarks.md)
  EXPECT_EQ(j["accuracy"], "conservative");
  EXPECT_EQ(j["log"], log_path);
  EXPECT_GT(j["ms_per_interval"].get<double>(), 0.0);
  for (const char* stage : {"skin", "refit", "traverse", "elementary"}) {
    EXPECT_TRUE(j["stages_ms"].contains(stage)) << stage;
  }

  const auto log = read_log(log_path);
  EXPECT_TRUE(log.header.complete);
  EXPECT_EQ(log.header.method, "auto");
  EXPECT_EQ(log.header.input_path, kModel);
  EXPECT_EQ(log.header.input_hash.rfind("fnv1a64:", 0), 0u);
  EXPECT_EQ(log.header.first_sample, 10);
  EXPECT_EQ(log.header.last_sample, 13);
  EXPECT_EQ(log.header.num_triangles, 5126);
  EXPECT_NE(log.header.command_line.find("--frames 10:13"), std::string::npos)
      << log.header.command_line;
  ASSERT_EQ(log.frames.size(), 7u);
  std::int64_t dcd = 0, vf = 0, ee = 0;
  for (const auto& row : log.frames) {
    EXPECT_GE(row.sample, 10);
    EXPECT_LE(row.sample, 13);
    dcd += row.counters.dcd_pairs;
    vf += row.counters.vf_contacts;
    ee += row.counters.ee_contacts;
  }
  EXPECT_EQ(j["dcd_pairs"], dcd);
  EXPECT_EQ(j["ccd_vf"], vf);
  EXPECT_EQ(j["ccd_ee"], ee);
  EXPECT_EQ(static_cast<std::int64_t>(log.dcd_pairs.size()), dcd);
  EXPECT_EQ(static_cast<std::int64_t>(log.contacts.size()), vf + ee);
  // Every feature id is in the file's numbering: a valid part, a non-negative index.
  for (const auto& c : log.contacts) {
    EXPECT_GE(c.a.part, 0);
    EXPECT_LT(c.a.part, static_cast<int>(log.header.part_names.size()));
    EXPECT_GE(c.b.index, 0);
    EXPECT_LE(c.toi_lower, c.toi_upper);
  }

  // Text summary of the same run names the log.
  const auto text = run_skelcd({"check", kModel, "--frames", "10:11", "-o", log_path});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("log       " + log_path), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("ms per interval"), std::string::npos) << text.out;
}

// `--no-reuse` reaches the runner: on a clip that holds one pose (Debian's unnamed_bones.mdl) the
// default hands most CCD rows on without a query (no stage time in the log), `--no-reuse` queries
// every one, and the two logs hold the same counters and contacts row by row.
TEST(CmdCheck, NoReuseQueriesEveryIntervalOfAHeldPoseAndFindsTheSame) {
  const auto dir = skelcd::test::temp_dir("check-no-reuse");
  const std::string model = skelcd::test::assimp_model("MDL/MDL (HL1)/unnamed_bones.mdl").string();
  std::vector<LogData> logs;
  for (const bool no_reuse : {false, true}) {
    const auto log_path = (dir / (no_reuse ? "each.h5" : "held.h5")).string();
    std::vector<std::string> args{
        "check", model, "--frames", "0:8", "--query", "ccd", "--method", "bvh", "-o", log_path};
    if (no_reuse) args.emplace_back("--no-reuse");
    const auto r = run_skelcd(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    logs.push_back(read_log(log_path));
  }
  ASSERT_EQ(logs[0].frames.size(), 8u);
  ASSERT_EQ(logs[1].frames.size(), 8u);
  int handed_on = 0;
  for (std::size_t i = 0; i < 8; ++i) {
    const auto& held = logs[0].frames[i];
    const auto& each = logs[1].frames[i];
    EXPECT_EQ(held.counters.bv_tests, each.counters.bv_tests) << i;
    EXPECT_EQ(held.counters.candidate_pairs, each.counters.candidate_pairs) << i;
    EXPECT_EQ(held.counters.ee_tests, each.counters.ee_tests) << i;
    EXPECT_EQ(held.counters.vf_contacts + held.counters.ee_contacts, 1852) << i;
    EXPECT_EQ(held.counters.ee_contacts, each.counters.ee_contacts) << i;
    EXPECT_GT(each.times.elementary_us, 0.0) << i;
    handed_on += held.times.elementary_us == 0.0 ? 1 : 0;
  }
  EXPECT_GE(handed_on, 4);
  EXPECT_EQ(logs[0].contacts, logs[1].contacts);
  EXPECT_NE(logs[1].header.command_line.find("--no-reuse"), std::string::npos);
}

// The runner gives `dynamic` the rigid rows (docs/radial-view.md "Rigid rows") unless
// `--no-rigid-rows`: on RobotExpressive, whose parts hang rigidly from nodes, the same contacts and
// DCD pairs row by row (the logs' rows whole), fewer candidate pairs over the clip's start.
TEST(CmdCheck, DynamicTakesTheRigidRowsAndFindsTheSame) {
  const auto dir = skelcd::test::temp_dir("check-dynamic-rows");
  const std::string model = skelcd::test::asset("characters/RobotExpressive.glb").string();
  std::vector<LogData> logs;
  for (const bool rows : {false, true}) {
    const auto log_path = (dir / (rows ? "rows.h5" : "none.h5")).string();
    std::vector<std::string> args{
        "check", model, "--frames", "20:30", "--method", "dynamic", "-o", log_path};
    if (!rows) args.emplace_back("--no-rigid-rows");
    const auto r = run_skelcd(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    logs.push_back(read_log(log_path));
  }
  ASSERT_EQ(logs[0].frames.size(), logs[1].frames.size());
  ASSERT_FALSE(logs[0].contacts.empty());
  EXPECT_EQ(logs[0].contacts, logs[1].contacts);
  EXPECT_EQ(logs[0].dcd_pairs, logs[1].dcd_pairs);
  std::int64_t without = 0;
  std::int64_t with = 0;
  for (std::size_t i = 0; i < logs[0].frames.size(); ++i) {
    EXPECT_LE(
        logs[1].frames[i].counters.candidate_pairs, logs[0].frames[i].counters.candidate_pairs)
        << i;
    without += logs[0].frames[i].counters.candidate_pairs;
    with += logs[1].frames[i].counters.candidate_pairs;
  }
  EXPECT_LT(with, without);
}

// A frame sequence is checked in a spatial order unless `--mesh-order file` asks for the files':
// the cloth-funnel step gives the same findings either way, every feature named by its index in
// the files (an EE pair or a DCD pair may list its two features the other way round).
TEST(CmdCheck, TheMeshOrderChangesNoFindingNorItsName) {
  const auto dir = skelcd::test::temp_dir("check-mesh-order");
  const std::string funnel = skelcd::test::asset("cloth-funnel/frames").string();
  std::vector<LogData> logs;
  std::vector<nlohmann::json> summaries;
  for (const char* order : {"spatial", "file"}) {
    const auto log_path = (dir / (std::string(order) + ".h5")).string();
    const auto r = run_skelcd(
        {"check",
         funnel,
         "--method",
         "kdop",
         "--mesh-order",
         order,
         "--threads",
         "1",
         "--json",
         "-o",
         log_path});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    summaries.push_back(nlohmann::json::parse(r.out));
    logs.push_back(read_log(log_path));
  }
  const auto unordered = [](const LogData& log) {
    std::vector<ContactKey> keys;
    for (auto c : log.contacts) {
      if (c.kind == skelcd::culling::CcdContact::Kind::ee &&
          std::tie(c.b.part, c.b.index, c.b.side) < std::tie(c.a.part, c.a.index, c.a.side)) {
        std::swap(c.a, c.b);
      }
      keys.emplace_back(
          c.frame,
          static_cast<int>(c.kind),
          c.a.part,
          c.a.index,
          c.a.side,
          c.b.part,
          c.b.index,
          c.b.side);
    }
    std::sort(keys.begin(), keys.end());
    return keys;
  };
  const auto pairs = [](const LogData& log) {
    std::vector<std::tuple<int, int, int, int, int>> keys;
    for (const auto& p : log.dcd_pairs) {
      const auto a = std::pair{p.a.part, p.a.index};
      const auto b = std::pair{p.b.part, p.b.index};
      const auto [lo, hi] = std::minmax(a, b);
      keys.emplace_back(p.frame, lo.first, lo.second, hi.first, hi.second);
    }
    std::sort(keys.begin(), keys.end());
    return keys;
  };
  EXPECT_GT(logs[0].contacts.size(), 0u);
  EXPECT_EQ(unordered(logs[0]), unordered(logs[1]));
  EXPECT_EQ(pairs(logs[0]), pairs(logs[1]));
  for (const char* key : {"dcd_pairs", "ccd_vf", "ccd_ee", "new_ccd_contacts", "new_dcd_pairs"}) {
    EXPECT_EQ(summaries[0][key], summaries[1][key]) << key;
  }
  const auto refused = run_skelcd({"check", funnel, "--mesh-order", "morton"});
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("--mesh-order"), std::string::npos) << refused.err;
}

TEST(CmdCheck, BvhAndBruteFindTheSameContactsOnARealCharacter) {
  // The full clip comparison is scripts/check_methods_agree.sh; one interval here keeps ctest fast.
  const auto dir = skelcd::test::temp_dir("check-agree");
  const auto bvh = run_skelcd({"check", kModel, "--frames", "40:41", "--method", "bvh", "--json",
                               "-o", (dir / "bvh.h5").string()});
  const auto brute = run_skelcd({"check", kModel, "--frames", "40:41", "--method", "brute",
                                 "--json", "-o", (dir / "brute.h5").string()});
  ASSERT_EQ(bvh.exit_code, 0) << bvh.err;
  ASSERT_EQ(brute.exit_code, 0) << brute.err;
  const auto a = nlohmann::json::parse(bvh.out);
  const auto b = nlohmann::json::parse(brute.out);
  EXPECT_EQ(a["dcd_pairs"], b["dcd_pairs"]);
  EXPECT_EQ(a["ccd_vf"], b["ccd_vf"]);
  EXPECT_EQ(a["ccd_ee"], b["ccd_ee"]);
  const auto la = read_log(dir / "bvh.h5");
  const auto lb = read_log(dir / "brute.h5");
  EXPECT_EQ(contact_keys(la), contact_keys(lb));
  EXPECT_EQ(pair_keys(la), pair_keys(lb));
  EXPECT_EQ(lb.header.method, "brute");
}

TEST(CmdCheck, BadInputsFailWithOneLineAndLeaveNoLog) {
  const auto dir = skelcd::test::temp_dir("check-bad");
  const auto log = (dir / "out.h5").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"check", (dir / "missing.x").string(), "-o", log}, "missing.x: no such file"},
      {{"check", kModel, "--frames", "5:2", "-o", log}, "--frames"},
      {{"check", kModel, "--frames", "x", "-o", log}, "--frames"},
      {{"check", kModel, "--frames", "0:100", "-o", log}, "outside the 100 samples"},
      {{"check", kModel, "--method", "no-such-method", "-o", log}, "no-such-method"},
      {{"check", kModel, "--accuracy", "sloppy", "-o", log}, "--accuracy"},
      {{"check", kModel, "--query", "all", "-o", log}, "--query"},
      {{"check", kModel, "--fps", "-3", "-o", log}, "--fps"},
      {{"check", kModel, "--clip", "NoSuchClip", "-o", log}, "NoSuchClip"},
      // The baseline and the allowances (docs/events.md) are refused before the log too.
      {{"check", kModel, "--baseline", "sample:100", "-o", log}, "--baseline sample:100"},
      {{"check", kModel, "--baseline", "bogus", "-o", log}, "--baseline 'bogus'"},
      {{"check", kModel, "--baseline", (dir / "none.h5").string(), "-o", log},
       "none.h5: no such file (the --baseline log)"},
      {{"check", kModel, "--baseline-slack", "-1", "-o", log}, "--baseline-slack"},
      {{"check", kModel, "--allow", "a-b", "-o", log}, "--allow 'a-b'"},
      {{"check", kModel, "--allow", "fin:fin", "-o", log}, "'fin' names neither a part nor a bone"},
      // On two threads the baseline runs beside the first blocks, and the log waits for it.
      {{"check", kModel, "--threads", "2", "--baseline", "sample:100", "-o", log},
       "--baseline sample:100"},
      {{"check", kModel, "--threads", "2", "--allow", "fin:fin", "-o", log},
       "'fin' names neither a part nor a bone"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = run_skelcd(args);
    EXPECT_EQ(r.exit_code, 1) << message;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_FALSE(std::filesystem::exists(log)) << message;
  }
}

TEST(CmdCheck, RefusesToOverwriteAFileThatIsNotALog) {
  const auto dir = skelcd::test::temp_dir("check-clobber");
  const auto precious = dir / "thesis.h5";
  std::ofstream(precious) << "chapter one\n";
  const auto r = run_skelcd({"check", kModel, "--frames", "0:1", "-o", precious.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("refusing to overwrite"), std::string::npos) << r.err;
  std::ifstream in(precious);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "chapter one");
}

TEST(CmdCheck, KilledRunLeavesALogWithEveryCompletedFrame) {
  const auto dir = skelcd::test::temp_dir("check-kill");
  const auto log_path = dir / "killed.h5";
  // 300 samples per second: ~1000 samples, far more than we let it do.
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen((dir / "stderr.txt").c_str(), "w", stderr);
    // One thread: rows reach the log one by one (with several, a block of up to 64 samples at a
    // time, which a Debug + ASan build may not finish within the wait below).
    ::execl(SKELCD_EXE, SKELCD_EXE, "check", kModel.c_str(), "--fps", "300", "--threads", "1",
            "-o", log_path.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Poll the log until a few rows are on disk, then kill. The run is stopped (SIGSTOP) while the
  // log is read: the writer flushes twice per row, every few ms, and a read racing it fails
  // (the writer takes no file lock); polling a running writer saw no rows before the end of the
  // whole run in about half the runs on a loaded 2-core machine. Stopped mid-flush, the read
  // fails and the run goes on to the next poll; the kill comes while it is stopped, at a state
  // the read saw whole.
  std::size_t seen = 0;
  int status = 0;
  bool ended = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (seen < 5 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_EQ(::kill(pid, SIGSTOP), 0);
    ASSERT_EQ(::waitpid(pid, &status, WUNTRACED), pid);
    if (!WIFSTOPPED(status)) {
      ended = true;
      break;
    }
    try {
      seen = read_log(log_path, ReadLogOptions{.findings = false}).frames.size();
    } catch (const std::exception&) {
      // not created yet, or stopped mid-write: poll again
    }
    if (seen < 5) {
      ASSERT_EQ(::kill(pid, SIGCONT), 0);
    }
  }
  ASSERT_FALSE(ended) << "the run ended before it was killed";
  ASSERT_EQ(::kill(pid, SIGKILL), 0);  // stopped or not, it dies
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";
  ASSERT_GE(seen, 5u) << "no rows appeared within 60 s";

  // Our reader: every row written before the kill, the run marked incomplete, findings consistent.
  const auto log = read_log(log_path);
  EXPECT_FALSE(log.header.complete);
  EXPECT_GE(log.frames.size(), seen);
  EXPECT_LT(static_cast<std::int64_t>(log.frames.size()), log.header.planned_rows);
  std::int64_t contacts = 0, pairs = 0;
  for (std::size_t i = 0; i < log.frames.size(); ++i) {
    const auto& row = log.frames[i];
    // Rows in order: dcd 0, ccd 0, dcd 1, ccd 1, …
    EXPECT_EQ(row.sample, static_cast<int>(i / 2)) << i;
    EXPECT_EQ(row.kind, i % 2 == 0 ? QueryKind::dcd : QueryKind::ccd) << i;
    contacts += row.counters.vf_contacts + row.counters.ee_contacts;
    pairs += row.counters.dcd_pairs;
  }
  // Findings are written before their row: at least those of the completed rows are there, and
  // any extra ones belong to the row being computed when the kill came.
  const int last_sample = log.frames.back().sample;
  std::int64_t kept_contacts = 0, kept_pairs = 0;
  for (const auto& c : log.contacts) kept_contacts += c.frame <= last_sample ? 1 : 0;
  for (const auto& p : log.dcd_pairs) kept_pairs += p.frame <= last_sample ? 1 : 0;
  EXPECT_GE(kept_contacts, contacts);
  EXPECT_GE(kept_pairs, pairs);

  // h5dump reads it without our code.
  const std::string dump = "h5dump -H " + log_path.string() + " > " + (dir / "dump.txt").string();
  EXPECT_EQ(std::system(dump.c_str()), 0);
  std::ifstream in(dir / "dump.txt");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("DATASET \"frames\""), std::string::npos);
  const std::string data = "h5dump -d /frames " + log_path.string() + " > /dev/null";
  EXPECT_EQ(std::system(data.c_str()), 0);

  // skelcd inspect lists it as incomplete.
  const auto r = run_skelcd({"inspect", log_path.string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j[0]["complete"].get<std::string>().rfind("no (", 0), 0u) << j.dump();
}

TEST(CmdCheck, GeneratedFrameSequenceHasTheHandCountedContacts) {
  // A large triangle in z = 0 and a small one that passes down through it (frames 0 → 1), then
  // tilts until it pierces it (frame 2). By hand: interval 0-1, the small triangle's 3 vertices
  // cross the large face at t = 1/2 (3 VF); interval 1-2, vertices 1 and 2 cross it (2 VF);
  // no edge comes near another (0 EE); only frame 2 intersects (1 DCD pair).
  const auto dir = skelcd::test::temp_dir("check-generated");
  const auto frames = dir / "frames";
  std::filesystem::create_directories(frames);
  const std::array<std::string, 3> small{"1 1 1\nv 2 1 1\nv 1 2 1", "1 1 -1\nv 2 1 -1\nv 1 2 -1",
                                         "1 1 -1\nv 1.5 1 1\nv 2 2 1"};
  for (int i = 0; i < 3; ++i) {
    std::ofstream(frames / ("frame" + std::to_string(i) + ".obj"))
        << "v 0 0 0\nv 4 0 0\nv 0 4 0\nv " << small[static_cast<std::size_t>(i)]
        << "\nf 1 2 3\nf 4 5 6\n";
  }
  for (const char* method : {"bvh", "brute", "kdop"}) {
    SCOPED_TRACE(method);
    const auto log_path = dir / (std::string(method) + ".h5");
    const auto r = run_skelcd({"check", frames.string(), "--method", method, "--json", "-o",
                               log_path.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["frames"], 3);
    EXPECT_EQ(j["intervals"], 2);
    EXPECT_EQ(j["dcd_pairs"], 1);
    EXPECT_EQ(j["ccd_vf"], 5);
    EXPECT_EQ(j["ccd_ee"], 0);
    EXPECT_EQ(j["frames_with_contacts"], 3);
    EXPECT_EQ(j["frames_with_interpenetration"], 1);

    const auto log = read_log(log_path);
    ASSERT_EQ(log.dcd_pairs.size(), 1u);
    EXPECT_EQ(log.dcd_pairs[0].frame, 2);
    EXPECT_EQ(log.dcd_pairs[0].a, (FeatureId{0, 0, -1}));
    EXPECT_EQ(log.dcd_pairs[0].b, (FeatureId{0, 1, -1}));
    std::vector<std::pair<int, int>> hits;  // (frame, vertex of the small triangle)
    for (const auto& c : log.contacts) {
      EXPECT_EQ(c.kind, skelcd::culling::CcdContact::Kind::vf);
      EXPECT_EQ(c.b, (FeatureId{0, 0, -1}));
      EXPECT_LE(c.toi_lower, 0.5);
      EXPECT_GE(c.toi_upper, 0.5);
      hits.emplace_back(c.frame, c.a.index);
    }
    std::sort(hits.begin(), hits.end());
    EXPECT_EQ(hits, (std::vector<std::pair<int, int>>{{0, 3}, {0, 4}, {0, 5}, {1, 4}, {1, 5}}));
  }
  // The logs identify the sequence by its frames' content: the same for the three runs, and
  // another hash once one frame changes.
  const auto hash = read_log(dir / "bvh.h5").header.input_hash;
  EXPECT_EQ(hash.rfind("fnv1a64:", 0), 0u) << hash;
  EXPECT_EQ(read_log(dir / "brute.h5").header.input_hash, hash);
  std::ofstream(frames / "frame1.obj", std::ios::app) << "# edited\n";
  const auto edited = dir / "edited.h5";
  ASSERT_EQ(run_skelcd({"check", frames.string(), "-o", edited.string()}).exit_code, 0);
  const auto edited_hash = read_log(edited).header.input_hash;
  EXPECT_EQ(edited_hash.rfind("fnv1a64:", 0), 0u) << edited_hash;
  EXPECT_NE(edited_hash, hash);
}

// --- batch mode, robots, generator specs, threads -------------------------------------------------

std::vector<std::string> h5_files(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".h5") names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(CmdCheck, BatchWritesOneLogPerClipAndReportsBrokenInputsAtTheEnd) {
  const auto dir = skelcd::test::temp_dir("check-batch");
  const auto models = dir / "models";
  std::filesystem::create_directories(models);
  std::filesystem::copy_file(kModel, models / "a.X");
  std::filesystem::copy_file(kModel, models / "b.X");
  std::ofstream(models / "broken.X") << "xof 0303txt 0032\nFrame {{ this is not an X file\n";
  const std::string glob = (models / "*.X").string();
  const std::string rope = "gen:rope?triangles=200&frames=3";
  const std::string missing = (dir / "missing.glb").string();

  const auto out = dir / "logs";
  const auto r = run_skelcd({"check", glob, rope, missing, "--frames", "0:2", "-o", out.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("2 of 5 checks failed"), std::string::npos) << r.err;
  // The summary names each failure in one line, after the runs that worked.
  EXPECT_NE(r.out.find("batch     5 checks of 5 models: 3 done, 2 failed"), std::string::npos)
      << r.out;
  for (const auto& bad : {(models / "broken.X").string(), missing}) {
    const auto at = r.out.find("FAILED    " + bad);
    ASSERT_NE(at, std::string::npos) << bad << "\n" << r.out;
    EXPECT_NE(r.out.find('\n', at), std::string::npos);
  }
  EXPECT_NE(r.out.find(missing + ": no such file"), std::string::npos) << r.out;

  // One complete log per clip that ran, named after the model and clip; none for the failures.
  const auto names = h5_files(out);
  ASSERT_EQ(names.size(), 3u) << r.out;
  EXPECT_EQ(names[0].rfind("a-", 0), 0u) << names[0];
  EXPECT_EQ(names[1].rfind("b-", 0), 0u) << names[1];
  EXPECT_EQ(names[2].rfind("gen_rope_triangles_200_frames_3", 0), 0u) << names[2];
  const std::vector<std::string> inputs{(models / "a.X").string(), (models / "b.X").string(), rope};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto log = read_log(out / names[i]);
    EXPECT_TRUE(log.header.complete) << names[i];
    EXPECT_EQ(log.header.input_path, inputs[i]);
    EXPECT_EQ(log.frames.size(), 3u + 2u) << names[i];
  }
  // The two copies of the same character found the same things.
  EXPECT_EQ(contact_keys(read_log(out / names[0])), contact_keys(read_log(out / names[1])));

  // --json: the summaries and the failures, still a failing exit.
  const auto j_run = run_skelcd({"check", glob, missing, "--frames", "0:1", "--query", "dcd",
                                 "--json", "--output-dir", (dir / "json").string()});
  EXPECT_EQ(j_run.exit_code, 1);
  const auto j = nlohmann::json::parse(j_run.out);
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["model"], (models / "a.X").string());
  EXPECT_EQ(j["runs"][1]["frames"], 2);
  ASSERT_EQ(j["failures"].size(), 2u);
  EXPECT_EQ(j["failures"][0]["model"], (models / "broken.X").string());
  EXPECT_EQ(j["failures"][1]["model"], missing);
  EXPECT_NE(j["failures"][1]["error"].get<std::string>().find("no such file"), std::string::npos);
  EXPECT_EQ(h5_files(dir / "json").size(), 2u);
}

TEST(CmdCheck, BatchOfGoodInputsSucceedsAndAllClipsChecksEachClip) {
  const auto dir = skelcd::test::temp_dir("check-all-clips");
  const auto model = skelcd::test::asset("characters/RobotExpressive.glb").string();
  const auto info = nlohmann::json::parse(run_skelcd({"info", model, "--json"}).out);
  const auto clips = info["clips"].size();
  ASSERT_GT(clips, 3u);
  const auto r = run_skelcd({"check", model, "--all-clips", "--frames", "0:1", "--query", "dcd",
                             "--method", "bvh", "--json", "-o", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["runs"].size(), clips);
  EXPECT_TRUE(j["failures"].empty());
  EXPECT_EQ(h5_files(dir).size(), clips);
  for (std::size_t i = 0; i < clips; ++i) {
    EXPECT_EQ(j["runs"][i]["clip"], info["clips"][i]["name"]);
    const auto name = "RobotExpressive-" + info["clips"][i]["name"].get<std::string>() + ".h5";
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  }
  // --all-clips with --clip is a contradiction, refused before any work.
  const auto both = run_skelcd({"check", model, "--all-clips", "--clip", "Dance"});
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.err.find("--all-clips"), std::string::npos);
}

TEST(CmdCheck, BareGeneratorSpecsRobotOptionsAndThreads) {
  // gen:panda without a '?' is a model, not a missing file.
  const auto panda_log = skelcd::test::temp_dir("check-gen") / "panda.h5";
  const auto panda = run_skelcd(
      {"check",
       "gen:panda",
       "--frames",
       "0:3",
       "--query",
       "dcd",
       "--json",
       "-o",
       panda_log.string()});
  ASSERT_EQ(panda.exit_code, 0) << panda.err;
  EXPECT_EQ(nlohmann::json::parse(panda.out)["frames"], 4);
  // A generated rig is identified by its canonical spec (generators are deterministic).
  EXPECT_EQ(read_log(panda_log).header.input_hash.rfind("gen:panda?", 0), 0u)
      << read_log(panda_log).header.input_hash;

  // The URDF with its trajectory and SRDF, as `info` takes them.
  const auto root = skelcd::test::asset("robots/example-robot-data/robots/panda_description");
  const auto urdf = (root / "urdf/panda.urdf").string();
  const auto srdf = (root / "srdf/panda.srdf").string();
  const auto csv = skelcd::test::asset("trajectories/panda_reach.csv").string();
  const auto robot = run_skelcd({"check", urdf, "--trajectory", csv, "--srdf", srdf, "--frames",
                                 "0:4", "--json", "--threads", "2"});
  ASSERT_EQ(robot.exit_code, 0) << robot.err;
  const auto j = nlohmann::json::parse(robot.out);
  EXPECT_EQ(j["frames"], 5);
  EXPECT_EQ(j["intervals"], 4);
  const auto no_trajectory = run_skelcd({"check", urdf, "--trajectory",
                                         (root / "missing.csv").string()});
  EXPECT_EQ(no_trajectory.exit_code, 1);
  EXPECT_NE(no_trajectory.err.find("missing.csv"), std::string::npos) << no_trajectory.err;

  const auto bad = run_skelcd({"check", kModel, "--threads", "-2"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(count_lines(bad.err), 1u);
  EXPECT_NE(bad.err.find("--threads -2"), std::string::npos) << bad.err;
}

}  // namespace
