// skelcd inspect as a user runs it: several logs with known contents plus files that are not
// readable logs (truncated, foreign HDF5, plain text), sorting, CSV/JSON, the per-frame table,
// plots, and the collision events of labelled logs next to logs written before events.

#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_writer.hpp"

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

/// What makes a log labelled (docs/events.md): its header and its events. No baseline: a log as
/// written before events.
struct EventSpec {
  std::string baseline{};
  std::vector<EventRecord> events{};
  bool write_events = true;  ///< false: a run cut short before its events
};

/// Writes a log whose rows have the given findings (with matching /contacts and /dcd_pairs rows).
/// Labelled (events.baseline set): every DCD row's first pair is new (event 0), the second in the
/// baseline and the rest allowed; every contact is in the baseline.
void write_log(
    const std::filesystem::path& path,
    const std::string& method,
    const std::vector<RowSpec>& rows,
    bool finish = true,
    const EventSpec& events = {}) {
  LogHeader h;
  h.skelcd_version = "test";
  h.input_path = "/models/" + method + "-model.x";
  h.clip = "clip-" + method;
  h.method = method;
  h.accuracy = "conservative";
  h.query = "both";
  h.fps = 30;
  h.planned_rows = static_cast<std::int64_t>(rows.size()) + (finish ? 0 : 3);
  h.part_names = {"body", "cape"};
  h.baseline = events.baseline;
  if (!h.baseline.empty()) {
    h.baseline_slack = 2;
    h.allow = {"body:cape"};
    h.allow_adjacent_bones = true;
  }
  const bool labelled = !h.baseline.empty();
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
      const std::int32_t label = !labelled ? kLabelNone
                                 : i == 0  ? 0
                                 : i == 1  ? kLabelBaseline
                                           : kLabelAllowed;
      r.dcd_pairs.push_back({spec.sample, {0, i, -1}, {0, 100 + i, -1}, label});
      auto& c = r.row.counters;
      (label == 0                ? c.new_dcd_pairs
       : label == kLabelBaseline ? c.baseline_dcd_pairs
                                 : c.allowed_dcd_pairs) += labelled;
    }
    for (int i = 0; i < spec.vf + spec.ee; ++i) {
      const auto kind = i < spec.vf ? skelcd::culling::CcdContact::Kind::vf
                                    : skelcd::culling::CcdContact::Kind::ee;
      r.contacts.push_back(
          {spec.sample,
           kind,
           {0, i, -1},
           {0, 50 + i, -1},
           0.5,
           0.5,
           labelled ? kLabelBaseline : kLabelNone});
      r.row.counters.baseline_ccd_contacts += labelled;
    }
    writer.append(r);
  }
  if (labelled && events.write_events) writer.write_events(events.events);
  if (finish) writer.finish();
}

EventRecord event(
    std::int32_t id,
    std::int32_t first,
    std::int32_t last,
    std::vector<std::string> bones,
    std::vector<std::int32_t> parts,
    double depth) {
  EventRecord e;
  e.id = id;
  e.first_sample = first;
  e.last_sample = last;
  e.t_first = first / 30.0;
  e.t_last = last / 30.0;
  e.bones = std::move(bones);
  e.parts = std::move(parts);
  e.peak_pairs = 1;
  e.peak_sample = first;
  e.dcd_pairs = last - first + 1;
  e.depth = depth;
  return e;
}

/// A labelled log of two events: 0 (samples 0–2, five bones, body and cape) and 1 (sample 2,
/// first contact during the interval before it, merged into 0).
void write_labelled_log(const std::filesystem::path& path, const std::string& method) {
  auto e1 = event(1, 2, 2, {"LeftHand"}, {1}, 0.5);
  e1.t_first_contact = 1.5 / 30.0;
  e1.merged_into = 0;
  write_log(
      path,
      method,
      {{QueryKind::dcd, 0, 3, 0, 0, 10},
       {QueryKind::ccd, 0, 0, 1, 0, 40},
       {QueryKind::dcd, 1, 1, 0, 0, 12},
       {QueryKind::ccd, 1, 0, 0, 0, 30},
       {QueryKind::dcd, 2, 1, 0, 0, 11}},
      true,
      {.baseline = "rest pose",
       .events = {
           event(0, 0, 2, {"Hips", "Spine", "LeftArm", "RightArm", "Head"}, {0, 1}, 0.0123), e1}});
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
  // The events section (none of these logs has event data), a blank line, then the table.
  const auto blank = r.out.find("\n\n");
  ASSERT_NE(blank, std::string::npos) << r.out;
  const std::string events = r.out.substr(0, blank + 1);
  const std::string summary = r.out.substr(blank + 2);
  EXPECT_EQ(events.rfind("events: 0 in 3 logs\n", 0), 0u) << events;
  EXPECT_NE(events.find("kdop.h5: no event data (log written before events)"), std::string::npos);
  ASSERT_EQ(count_lines(summary), 4u) << summary;  // header + 3 logs
  const auto brute = summary.find("brute.h5");
  const auto bvh = summary.find("bvh.h5");
  const auto kdop = summary.find("kdop.h5");
  EXPECT_LT(brute, bvh);
  EXPECT_LT(bvh, kdop);
  EXPECT_EQ(summary.rfind("log", 0), 0u);  // header first

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

TEST(CmdInspect, TheEventsOfOneLogComeFirstWithItsBaselineAndAllowances) {
  const auto dir = skelcd::test::temp_dir("inspect-events-one");
  write_labelled_log(dir / "walk.h5", "bvh");
  const auto r = run_skelcd({"inspect", (dir / "walk.h5").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::vector<std::string> line;
  for (std::string l; std::getline(lines, l);) line.push_back(l);
  ASSERT_GE(line.size(), 9u) << r.out;
  // Counted as check counts them: event 1 ran into event 0.
  EXPECT_EQ(line[0], "events: 1 (+1 merged into an older one)");
  EXPECT_EQ(line[1].rfind("event  samples  time_s", 0), 0u) << line[1];
  EXPECT_NE(line[1].find("bones"), std::string::npos);
  // Event 0: samples 0–2, the first three bones and how many more, both parts.
  EXPECT_NE(line[2].find("0–2"), std::string::npos) << line[2];
  EXPECT_NE(line[2].find("0.000–0.067"), std::string::npos) << line[2];
  EXPECT_NE(line[2].find("Hips, Spine, LeftArm +2"), std::string::npos) << line[2];
  EXPECT_NE(line[2].find("body, cape"), std::string::npos) << line[2];
  EXPECT_NE(line[2].find("0.0123"), std::string::npos) << line[2];
  // Event 1: one sample, its first contact, merged into 0.
  EXPECT_NE(line[3].find("0.067–0.067 (contact 0.050)"), std::string::npos) << line[3];
  EXPECT_NE(line[3].find("LeftHand"), std::string::npos) << line[3];
  EXPECT_EQ(line[3].back(), '0') << line[3];
  // Rows 0, 1, 2 have 3 + 1 + 1 DCD pairs: 3 new, 1 baseline, 1 allowed; the contact is baseline.
  EXPECT_EQ(line[4], "baseline: 1 DCD pairs, 1 CCD contacts (rest pose, slack 2)");
  EXPECT_EQ(line[5], "allowed: 1 DCD pairs, 0 CCD contacts (body:cape, adjacent bones)");
  EXPECT_EQ(line[6], "");
  EXPECT_EQ(line[7].rfind("log ", 0), 0u);  // then the summary, as before
  EXPECT_NE(
      line[7].find("events  new_findings  baseline_findings  allowed_findings  baseline"),
      std::string::npos)
      << line[7];

  const auto j =
      nlohmann::json::parse(run_skelcd({"inspect", (dir / "walk.h5").string(), "--json"}).out);
  EXPECT_EQ(j[0]["events"], 1);
  EXPECT_EQ(j[0]["new_findings"], 3);
  EXPECT_EQ(j[0]["baseline_findings"], 2);
  EXPECT_EQ(j[0]["allowed_findings"], 1);
  EXPECT_EQ(j[0]["baseline"], "rest pose");
}

TEST(CmdInspect, ALogWrittenBeforeEventsSaysSo) {
  const auto old =
      (std::filesystem::path(SKELCD_SOURCE_DIR) / "tests/tools/data/log_before_events.hdf5")
          .string();
  const auto r = run_skelcd({"inspect", old});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("events: no event data (log written before events)\n\nlog ", 0), 0u)
      << r.out;
  EXPECT_EQ(r.out.find("baseline:"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(run_skelcd({"inspect", old, "--json"}).out);
  EXPECT_TRUE(j[0]["events"].is_null());
  EXPECT_TRUE(j[0]["new_findings"].is_null());
  EXPECT_EQ(j[0]["dcd_pairs"], 1);
  EXPECT_EQ(j[0]["complete"], "yes");
  const auto events = run_skelcd({"inspect", old, "--events", "--json"});
  ASSERT_EQ(events.exit_code, 0) << events.err;
  EXPECT_TRUE(nlohmann::json::parse(events.out).empty());
  EXPECT_EQ(events.err, old + ": no event data (log written before events)\n");
  // Its frames table has the columns added since, at 0.
  const auto frames = nlohmann::json::parse(run_skelcd({"inspect", old, "--frames", "--json"}).out);
  EXPECT_EQ(frames["rows"][0]["dcd_pairs"], 1);
  EXPECT_EQ(frames["rows"][0]["new_dcd_pairs"], 0);
}

TEST(CmdInspect, OneRowPerEventOfEveryLogInCsvAndJson) {
  const auto dir = skelcd::test::temp_dir("inspect-events-many");
  write_labelled_log(dir / "a.h5", "bvh");
  write_labelled_log(dir / "b.h5", "kdop");
  write_log(dir / "none.h5", "brute", {{QueryKind::dcd, 0, 0}}, true, {.baseline = "sample 0"});
  write_log(
      dir / "cut.h5",
      "brute",
      {{QueryKind::dcd, 0, 2}},
      false,
      {.baseline = "rest pose", .write_events = false});
  write_log(dir / "old.h5", "brute", {{QueryKind::dcd, 0, 1}});
  std::vector<std::string> args{"inspect"};
  for (const char* name : {"a.h5", "none.h5", "b.h5", "cut.h5", "old.h5"}) {
    args.push_back((dir / name).string());
  }
  auto json_args = args;
  json_args.insert(json_args.end(), {"--events", "--json", "--sort", "depth", "--desc"});
  const auto r = run_skelcd(json_args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.size(), 4u);                             // two events in each of a.h5 and b.h5
  EXPECT_DOUBLE_EQ(j[0]["depth"].get<double>(), 0.5);  // sorted by depth, deepest first
  EXPECT_EQ(j[0]["event"], 1);
  EXPECT_EQ(j[0]["clip"], "clip-bvh");
  EXPECT_EQ(j[0]["log"], (dir / "a.h5").string());
  EXPECT_EQ(j[0]["merged_into"], 0);
  EXPECT_DOUBLE_EQ(j[0]["t_first_contact"].get<double>(), 0.05);
  EXPECT_EQ(j[1]["clip"], "clip-kdop");
  const auto& e0 = j[2];
  EXPECT_EQ(e0["event"], 0);
  EXPECT_EQ(e0["bones"], (nlohmann::json{"Hips", "Spine", "LeftArm", "RightArm", "Head"}));
  EXPECT_EQ(e0["parts"], (nlohmann::json{"body", "cape"}));
  EXPECT_TRUE(e0["t_first_contact"].is_null());
  EXPECT_TRUE(e0["merged_into"].is_null());
  EXPECT_EQ(e0["first_sample"], 0);
  EXPECT_EQ(e0["last_sample"], 2);
  // Logs with nothing to list are named on stderr, each with its reason; a run without events
  // is not among them.
  EXPECT_NE(r.err.find("cut.h5: no event data (the run did not finish)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("old.h5: no event data (log written before events)"), std::string::npos);
  EXPECT_EQ(r.err.find("none.h5"), std::string::npos) << r.err;

  auto csv_args = args;
  csv_args.insert(csv_args.end(), {"--events", "--csv"});
  const auto csv = run_skelcd(csv_args);
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  std::istringstream lines(csv.out);
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  EXPECT_EQ(
      header,
      "log,clip,event,first_sample,last_sample,t_first,t_last,t_first_contact,bones,parts,"
      "peak_pairs,peak_sample,dcd_pairs,ccd_contacts,depth,merged_into");
  EXPECT_NE(first.find(",clip-bvh,0,0,2,0.0,"), std::string::npos) << first;
  EXPECT_NE(first.find(",Hips; Spine; LeftArm; RightArm; Head,body; cape,"), std::string::npos)
      << first;
  EXPECT_EQ(count_lines(csv.out), 5u);

  // The text: every log's events, then the logs without any, then the summary.
  const auto text = run_skelcd(args);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(text.out.rfind("events: 4 in 5 logs\nlog ", 0), 0u) << text.out;
  EXPECT_NE(text.out.find("none.h5: no events\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("cut.h5: no event data (the run did not finish)\n"), std::string::npos);
  const auto summary = nlohmann::json::parse(
      run_skelcd({"inspect", (dir / "none.h5").string(), (dir / "cut.h5").string(), "--json"}).out);
  EXPECT_EQ(summary[0]["events"], 0);
  EXPECT_TRUE(summary[1]["events"].is_null());  // unknown, not 0
  EXPECT_EQ(summary[1]["new_findings"], 1);
}

TEST(CmdInspect, PlotsTheEventsOfEveryLogOnATimeline) {
  const auto dir = skelcd::test::temp_dir("inspect-events-plot");
  write_labelled_log(dir / "a.h5", "bvh");
  write_log(dir / "old.h5", "brute", {{QueryKind::dcd, 0, 1}});
  const auto plots = dir / "plots";
  const auto r = run_skelcd(
      {"inspect",
       (dir / "a.h5").string(),
       (dir / "old.h5").string(),
       "--plot",
       plots.string(),
       "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j[0]["events_plot"], (plots / "events.png").string());
  EXPECT_EQ(j[1]["plot"], (plots / "old.png").string());
  const auto size = [](const std::filesystem::path& png) {
    const std::string bytes = read_text(png);
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << png;
    const auto be32 = [&](std::size_t at) {
      unsigned v = 0;
      for (std::size_t k = 0; k < 4; ++k)
        v = (v << 8) | static_cast<unsigned char>(bytes.at(at + k));
      return v;
    };
    return std::pair{be32(16), be32(20)};
  };
  // The labelled log's page has a fourth panel, its events; the old log's has the three.
  EXPECT_EQ(size(plots / "a.png"), (std::pair{1000u, 1200u}));
  EXPECT_EQ(size(plots / "old.png"), (std::pair{1000u, 900u}));
  // The timeline: one lane per log, at least 300 px.
  EXPECT_EQ(size(plots / "events.png"), (std::pair{1000u, 300u}));
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
