// The HDF5 log: round trip of every field, partial logs, refusing to clobber, bad files reported by
// name, and the h5py example of docs/log-format.md run on a real log.

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "skinning/detail/import_guard.hpp"
#include "skinning/errors.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/file_hash.hpp"
#include "tools/io/log/detail/hdf5_schema.hpp"
#include "tools/io/log/detail/log_answer.hpp"
#include "tools/io/log/log_reader.hpp"
#include "tools/io/log/log_writer.hpp"

namespace {

using namespace skelcd::tools;
using skelcd::IoError;
using Kind = skelcd::culling::CcdContact::Kind;

/// Debian's interpreter, where python3-h5py is installed (a pyenv python on PATH may lack it).
constexpr const char* kPython = "/usr/bin/python3";

LogHeader sample_header() {
  LogHeader h;
  h.skelcd_version = "9.8.7";
  h.command_line = "skelcd check \"model with spaces.x\" --fps 30";
  h.input_path = "/tmp/model with spaces.x";
  h.input_hash = "fnv1a64:0123456789abcdef";
  h.clip = "Walk — ünïcödé";
  h.method = "bvh";
  h.accuracy = "conservative";
  h.query = "both";
  h.fps = 29.97;
  h.min_separation = 1.5e-4;
  h.gamma = 0.25;
  h.theta = 1.0471975511965976;
  h.seed = (std::int64_t{1} << 40) + 3;
  h.segmentation = "computed (rig weights)";
  h.start_time = "2026-01-31T12:34:56Z";
  h.first_sample = 3;
  h.last_sample = 5;
  h.planned_rows = 5;
  h.num_vertices = 1234;
  h.num_triangles = 2345;
  h.part_names = {"Body", "Hat", ""};
  h.baseline = "sample 12";
  h.baseline_slack = 3;
  h.allow = {"Body:Hat", "Händ:Händ"};
  h.allow_adjacent_bones = true;
  return h;
}

/// Events with every field distinct: a missing t_first_contact, no bones, a merge, a negative
/// peak_sample, names with spaces and accents.
std::vector<EventRecord> sample_events() {
  EventRecord a;
  a.id = 0;
  a.first_sample = 3;
  a.last_sample = 5;
  a.t_first = 0.1;
  a.t_last = 5 / 30.0;
  a.t_first_contact = 0.0875;
  a.parts = {0, 2};
  a.bones = {"mixamorig:LeftForeArm", "Spine 1", "Hüfte"};
  a.peak_pairs = 1500;
  a.peak_sample = 5;
  a.dcd_pairs = 1502;
  a.ccd_contacts = (std::int64_t{1} << 33) + 7;
  a.depth = 0.03125;
  a.merged_into = -1;
  EventRecord b;
  b.id = 1;
  b.first_sample = 3;
  b.last_sample = 4;
  b.t_first = 0.1;
  b.t_last = 4 / 30.0;
  b.parts = {1};
  b.peak_pairs = 0;
  b.peak_sample = -1;
  b.ccd_contacts = 2;
  b.merged_into = 0;
  EventRecord c;  // neither parts nor bones
  c.id = 2;
  c.first_sample = c.last_sample = 5;
  c.t_first = c.t_last = 5 / 30.0;
  c.t_first_contact = 0.0;
  return {a, b, c};
}

/// Report with every counter and time distinct so a swapped column shows.
FrameReport sample_report(int sample, QueryKind kind, int contacts, int pairs) {
  FrameReport r;
  r.row.sample = sample;
  r.row.kind = kind;
  r.row.t0 = sample / 30.0;
  r.row.t1 = kind == QueryKind::ccd ? (sample + 1) / 30.0 : r.row.t0;
  auto& c = r.row.counters;
  const std::int64_t base = 1000 * sample + (kind == QueryKind::ccd ? 500 : 0);
  c.atomic_clusters = base + 1;
  c.mega_clusters = base + 2;
  c.h_minus = base + 3;
  c.h_uncertain = base + 4;
  c.bv_tests = base + 5;
  c.candidate_pairs = base + 6;
  c.vf_tests = base + 7;
  c.ee_tests = base + 8;
  c.vf_contacts = base + 9;
  c.ee_contacts = base + 10;
  c.tt_tests = base + 11;
  c.dcd_pairs = (std::int64_t{1} << 40) + base;  // beyond 32 bits
  c.feature_bv_tests = base + 12;
  c.new_dcd_pairs = base + 13;
  c.new_ccd_contacts = base + 14;
  c.baseline_dcd_pairs = base + 15;
  c.baseline_ccd_contacts = base + 16;
  c.allowed_dcd_pairs = base + 17;
  c.allowed_ccd_contacts = base + 18;
  auto& t = r.row.times;
  t.skin_us = 0.5 + sample;
  t.refit_us = 1.25 + sample;
  t.classify_us = 2.125 + sample;
  t.merge_us = 3.0625 + sample;
  t.traverse_us = 4.03125 + sample;
  t.elementary_us = 5.015625 + sample;
  r.row.total_us = 100.5 + sample;
  for (int i = 0; i < contacts; ++i) {
    r.contacts.push_back(ContactRow{
        .frame = sample,
        .kind = i % 2 == 0 ? Kind::vf : Kind::ee,
        .a = FeatureId{i % 3, 10 * i, static_cast<std::int8_t>(i % 2 == 0 ? -1 : i % 3)},
        .b = FeatureId{(i + 1) % 3, 10 * i + 1, static_cast<std::int8_t>(i % 2 == 0 ? -1 : 2)},
        .toi_lower = 0.125 * i / (contacts + 1.0),
        .toi_upper = 0.125 * (i + 1) / (contacts + 1.0),
        .label = i % 4 - 2,  // allowed, baseline, event 0, event 1
    });
  }
  for (int i = 0; i < pairs; ++i) {
    r.dcd_pairs.push_back(DcdPairRow{
        .frame = sample,
        .a = FeatureId{0, 7 * i, -1},
        .b = FeatureId{2, 7 * i + 3, -1},
        .label = i % 5 - 2});
  }
  return r;
}

void expect_rows_equal(const FrameRow& a, const FrameRow& b) {
  EXPECT_EQ(a.sample, b.sample);
  EXPECT_EQ(a.t0, b.t0);
  EXPECT_EQ(a.t1, b.t1);
  EXPECT_EQ(a.kind, b.kind);
  const auto& x = a.counters;
  const auto& y = b.counters;
  EXPECT_EQ(x.atomic_clusters, y.atomic_clusters);
  EXPECT_EQ(x.mega_clusters, y.mega_clusters);
  EXPECT_EQ(x.h_minus, y.h_minus);
  EXPECT_EQ(x.h_uncertain, y.h_uncertain);
  EXPECT_EQ(x.bv_tests, y.bv_tests);
  EXPECT_EQ(x.candidate_pairs, y.candidate_pairs);
  EXPECT_EQ(x.vf_tests, y.vf_tests);
  EXPECT_EQ(x.ee_tests, y.ee_tests);
  EXPECT_EQ(x.vf_contacts, y.vf_contacts);
  EXPECT_EQ(x.ee_contacts, y.ee_contacts);
  EXPECT_EQ(x.tt_tests, y.tt_tests);
  EXPECT_EQ(x.dcd_pairs, y.dcd_pairs);
  EXPECT_EQ(x.feature_bv_tests, y.feature_bv_tests);
  EXPECT_EQ(x.new_dcd_pairs, y.new_dcd_pairs);
  EXPECT_EQ(x.new_ccd_contacts, y.new_ccd_contacts);
  EXPECT_EQ(x.baseline_dcd_pairs, y.baseline_dcd_pairs);
  EXPECT_EQ(x.baseline_ccd_contacts, y.baseline_ccd_contacts);
  EXPECT_EQ(x.allowed_dcd_pairs, y.allowed_dcd_pairs);
  EXPECT_EQ(x.allowed_ccd_contacts, y.allowed_ccd_contacts);
  EXPECT_EQ(a.times.skin_us, b.times.skin_us);
  EXPECT_EQ(a.times.refit_us, b.times.refit_us);
  EXPECT_EQ(a.times.classify_us, b.times.classify_us);
  EXPECT_EQ(a.times.merge_us, b.times.merge_us);
  EXPECT_EQ(a.times.traverse_us, b.times.traverse_us);
  EXPECT_EQ(a.times.elementary_us, b.times.elementary_us);
  EXPECT_EQ(a.total_us, b.total_us);
}

void expect_headers_equal(const LogHeader& a, const LogHeader& b) {
  EXPECT_EQ(a.format_version, b.format_version);
  EXPECT_EQ(a.skelcd_version, b.skelcd_version);
  EXPECT_EQ(a.command_line, b.command_line);
  EXPECT_EQ(a.input_path, b.input_path);
  EXPECT_EQ(a.input_hash, b.input_hash);
  EXPECT_EQ(a.clip, b.clip);
  EXPECT_EQ(a.method, b.method);
  EXPECT_EQ(a.accuracy, b.accuracy);
  EXPECT_EQ(a.query, b.query);
  EXPECT_EQ(a.fps, b.fps);
  EXPECT_EQ(a.min_separation, b.min_separation);
  EXPECT_EQ(a.gamma, b.gamma);
  EXPECT_EQ(a.theta, b.theta);
  EXPECT_EQ(a.start_time, b.start_time);
  EXPECT_EQ(a.first_sample, b.first_sample);
  EXPECT_EQ(a.last_sample, b.last_sample);
  EXPECT_EQ(a.planned_rows, b.planned_rows);
  EXPECT_EQ(a.num_vertices, b.num_vertices);
  EXPECT_EQ(a.num_triangles, b.num_triangles);
  EXPECT_EQ(a.part_names, b.part_names);
  EXPECT_EQ(a.baseline, b.baseline);
  EXPECT_EQ(a.baseline_slack, b.baseline_slack);
  EXPECT_EQ(a.allow, b.allow);
  EXPECT_EQ(a.allow_adjacent_bones, b.allow_adjacent_bones);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.segmentation, b.segmentation);
  EXPECT_EQ(a.routes, b.routes);
  EXPECT_EQ(a.checks, b.checks);
}

std::vector<FrameReport> sample_reports() {
  return {sample_report(3, QueryKind::dcd, 0, 2), sample_report(3, QueryKind::ccd, 5, 0),
          sample_report(4, QueryKind::dcd, 0, 0), sample_report(4, QueryKind::ccd, 3000, 0),
          sample_report(5, QueryKind::dcd, 0, 1500)};
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Log, RoundTripsEveryField) {
  const auto path = skelcd::test::temp_dir("log-roundtrip") / "run.h5";
  const auto header = sample_header();
  const auto reports = sample_reports();
  {
    LogWriter writer(path, header);
    for (const auto& r : reports) writer.append(r);
    EXPECT_EQ(writer.rows_written(), 5);
    writer.write_events(sample_events());
    writer.finish();
  }
  const auto data = read_log(path);
  expect_headers_equal(data.header, header);
  EXPECT_TRUE(data.header.complete);
  EXPECT_TRUE(data.verified);
  EXPECT_TRUE(data.damage.empty());
  EXPECT_TRUE(data.events_recorded);
  EXPECT_EQ(data.events, sample_events());

  std::vector<ContactRow> contacts;
  std::vector<DcdPairRow> pairs;
  ASSERT_EQ(data.frames.size(), reports.size());
  for (std::size_t i = 0; i < reports.size(); ++i) {
    SCOPED_TRACE(i);
    expect_rows_equal(data.frames[i], reports[i].row);
    contacts.insert(contacts.end(), reports[i].contacts.begin(), reports[i].contacts.end());
    pairs.insert(pairs.end(), reports[i].dcd_pairs.begin(), reports[i].dcd_pairs.end());
  }
  EXPECT_EQ(data.contacts, contacts);
  EXPECT_EQ(data.dcd_pairs, pairs);
  // 3000 contacts in one append: 168 KB of rows, converted through the writer's 64 KiB buffers in
  // strips (log_writer.cpp, kConversionBufferBytes).
  EXPECT_EQ(data.contacts.size(), 3005u);
  EXPECT_EQ(data.dcd_pairs.size(), 1502u);

  const auto summary_only = read_log(path, ReadLogOptions{.findings = false});
  EXPECT_EQ(summary_only.frames.size(), 5u);
  EXPECT_TRUE(summary_only.contacts.empty());
  EXPECT_EQ(summary_only.events, sample_events());  // events are read either way
}

TEST(Log, ARowOfManyFindingsIsAppendedInBlocksAndVerifiedWhole) {
  // 20,000 contacts and 9,000 pairs in one row: appended 8,192 at a time (log_writer.cpp,
  // kRowsPerAppend), the row's checksums continued over its blocks.
  const auto path = skelcd::test::temp_dir("log-blocks") / "run.h5";
  const std::vector<FrameReport> reports{
      sample_report(7, QueryKind::ccd, 20000, 0),
      sample_report(8, QueryKind::dcd, 0, 9000),
      sample_report(8, QueryKind::ccd, 3, 0)};
  {
    LogWriter writer(path, sample_header());
    for (const auto& r : reports) writer.append(r);
    writer.finish();
  }
  const auto data = read_log(path);
  EXPECT_TRUE(data.verified);
  EXPECT_TRUE(data.damage.empty());
  ASSERT_EQ(data.frames.size(), 3u);
  std::vector<ContactRow> contacts = reports[0].contacts;
  contacts.insert(contacts.end(), reports[2].contacts.begin(), reports[2].contacts.end());
  EXPECT_EQ(data.contacts, contacts);
  EXPECT_EQ(data.dcd_pairs, reports[1].dcd_pairs);
  for (std::size_t i = 0; i < reports.size(); ++i)
    expect_rows_equal(data.frames[i], reports[i].row);
}

TEST(Log, EventsAreWrittenOnceBeforeFinishAndAbsentEventsAreNotNoEvents) {
  const auto dir = skelcd::test::temp_dir("log-events");
  {
    LogWriter writer(dir / "none.h5", sample_header());
    writer.append(sample_report(3, QueryKind::dcd, 0, 1));
    writer.write_events({});
    EXPECT_THROW_MESSAGE(writer.write_events({}), IoError, "events already written");
    writer.finish();
    EXPECT_THROW_MESSAGE(writer.write_events({}), IoError, "log already finished");
  }
  const auto none = read_log(dir / "none.h5");
  EXPECT_TRUE(none.events_recorded);  // a run with no events
  EXPECT_TRUE(none.events.empty());
  EXPECT_TRUE(none.verified);
  {
    LogWriter writer(dir / "cut.h5", sample_header());
    writer.append(sample_report(3, QueryKind::dcd, 0, 1));
  }  // cut short: no events written
  const auto cut = read_log(dir / "cut.h5");
  EXPECT_FALSE(cut.events_recorded);
  EXPECT_EQ(cut.header.baseline, "sample 12");  // labelled, but the events never came
  EXPECT_EQ(cut.dcd_pairs.at(0).label, -2);
}

TEST(Log, ALogWithoutBaselineWritesNoEventAttributes) {
  const auto path = skelcd::test::temp_dir("log-no-baseline") / "run.h5";
  auto header = sample_header();
  header.baseline.clear();
  {
    LogWriter writer(path, header);
    writer.finish();
  }
  const std::string script =
      "import h5py, sys\n"
      "with h5py.File('" +
      path.string() +
      "', 'r') as f:\n"
      "    names = ('baseline', 'baseline_slack', 'allow', 'allow_adjacent_bones')\n"
      "    sys.exit(3 if any(n in f.attrs for n in names) else 0)\n";
  const auto py = path.parent_path() / "attrs.py";
  write_text(py, script);
  EXPECT_EQ(std::system((std::string(kPython) + " " + py.string()).c_str()), 0);
  const auto data = read_log(path);
  EXPECT_TRUE(data.header.baseline.empty());
  EXPECT_TRUE(data.header.allow.empty());
  EXPECT_FALSE(data.header.allow_adjacent_bones);
}

/// tests/tools/data/log_before_events.hdf5: written by the log writer of commit 139b64c (format 1,
/// before labels and events, with /checksums) for the seam mesh of test_highlight.cpp: rows dcd 3
/// (one pair), ccd 3 (a VF and an EE contact), dcd 4.
std::filesystem::path log_before_events() {
  return std::filesystem::path(SKELCD_SOURCE_DIR) / "tests/tools/data/log_before_events.hdf5";
}

TEST(Log, ALogWrittenBeforeEventsReadsUnlabelledAndVerified) {
  const auto data = read_log(log_before_events());
  EXPECT_EQ(data.header.format_version, 1);
  EXPECT_TRUE(data.header.complete);
  // Its checksums cover the columns it has: still verified with the columns added since.
  EXPECT_TRUE(data.verified);
  EXPECT_TRUE(data.damage.empty());
  EXPECT_TRUE(data.header.baseline.empty());
  EXPECT_FALSE(data.events_recorded);
  EXPECT_TRUE(data.events.empty());
  ASSERT_EQ(data.frames.size(), 3u);
  EXPECT_EQ(data.frames[0].counters.dcd_pairs, 1);
  EXPECT_EQ(data.frames[0].counters.tt_tests, 3);
  EXPECT_EQ(data.frames[1].counters.ee_contacts, 1);
  for (const auto& f : data.frames) {  // counters the log has no column for read 0
    EXPECT_EQ(f.counters.new_dcd_pairs, 0);
    EXPECT_EQ(f.counters.baseline_ccd_contacts, 0);
    EXPECT_EQ(f.counters.allowed_dcd_pairs, 0);
  }
  ASSERT_EQ(data.dcd_pairs.size(), 1u);
  EXPECT_EQ(data.dcd_pairs[0], (DcdPairRow{3, {0, 0, -1}, {1, 1, -1}, kLabelNone}));
  ASSERT_EQ(data.contacts.size(), 2u);
  EXPECT_EQ(data.contacts[1].toi_upper, 0.75);
  EXPECT_EQ(data.contacts[0].label, kLabelNone);
  EXPECT_EQ(data.contacts[1].label, kLabelNone);
}

TEST(Log, ANewerFormatIsRefusedByItsVersion) {
  // What a version-1 reader does with the logs this build writes (it could not checksum them).
  const auto path = skelcd::test::temp_dir("log-version") / "run.h5";
  auto header = sample_header();
  header.format_version = kLogFormatVersion + 1;
  {
    LogWriter writer(path, header);
    writer.finish();
  }
  EXPECT_THROW_MESSAGE((void)read_log(path), IoError, "is not supported (this build reads 1..");
}

TEST(Log, DamagedEventsAreDroppedAndNamed) {
  const auto dir = skelcd::test::temp_dir("log-events-damage");
  const auto path = dir / "run.h5";
  {
    LogWriter writer(path, sample_header());
    for (const auto& r : sample_reports()) writer.append(r);
    writer.write_events(sample_events());
    writer.finish();
  }
  // One bone renamed behind the writer's back: the events fail their checksum.
  const std::string script =
      "import h5py, numpy\n"
      "with h5py.File('" +
      path.string() +
      "', 'r+') as f:\n"
      "    d = f['event_bones']; row = d[1]; row['bone'] = 'Spine 2'; d[1] = row\n";
  write_text(dir / "edit.py", script);
  ASSERT_EQ(std::system((std::string(kPython) + " " + (dir / "edit.py").string()).c_str()), 0);
  const auto data = read_log(path);
  EXPECT_FALSE(data.verified);
  ASSERT_EQ(data.damage.size(), 1u);
  EXPECT_EQ(
      data.damage[0],
      "/events (with /event_parts and /event_bones) is damaged (it fails its checksum)");
  EXPECT_FALSE(data.events_recorded);
  EXPECT_TRUE(data.events.empty());
  EXPECT_EQ(data.frames.size(), 5u);  // the rows before the events are whole
  EXPECT_EQ(data.dcd_pairs.size(), 1502u);
}

TEST(Log, OptionalParametersStayAbsent) {
  const auto path = skelcd::test::temp_dir("log-optional") / "run.h5";
  auto header = sample_header();
  header.gamma.reset();
  header.theta.reset();
  header.seed.reset();
  header.part_names.clear();
  {
    LogWriter writer(path, header);
    writer.finish();
  }
  const auto data = read_log(path);
  EXPECT_FALSE(data.header.gamma.has_value());
  EXPECT_FALSE(data.header.theta.has_value());
  EXPECT_FALSE(data.header.seed.has_value());
  EXPECT_TRUE(data.header.part_names.empty());
  EXPECT_TRUE(data.frames.empty());
  EXPECT_TRUE(data.header.complete);
}

TEST(Log, UnfinishedLogIsReadableAndMarkedIncomplete) {
  const auto path = skelcd::test::temp_dir("log-unfinished") / "run.h5";
  {
    LogWriter writer(path, sample_header());
    writer.append(sample_report(3, QueryKind::dcd, 0, 4));
    writer.append(sample_report(3, QueryKind::ccd, 7, 0));
  }  // destroyed without finish(), as a run cut short by an error
  const auto data = read_log(path);
  EXPECT_FALSE(data.header.complete);
  EXPECT_EQ(data.frames.size(), 2u);
  EXPECT_EQ(data.contacts.size(), 7u);
  EXPECT_EQ(data.dcd_pairs.size(), 4u);
}

TEST(Log, RowsCountedButNeverWrittenAreDropped) {
  // A kill inside a flush can leave a table's extent ahead of its data: those rows read as the
  // fill value (first field -1). Made here with h5py, which grows the tables without writing.
  const auto dir = skelcd::test::temp_dir("log-unwritten");
  const auto path = dir / "run.h5";
  {
    LogWriter writer(path, sample_header());
    writer.append(sample_report(3, QueryKind::dcd, 0, 4));
    writer.append(sample_report(3, QueryKind::ccd, 7, 0));
  }
  const std::string script =
      "import h5py, sys\n"
      "with h5py.File('" + path.string() + "', 'r+') as f:\n"
      "    for name, more in (('frames', 3), ('contacts', 5), ('dcd_pairs', 2)):\n"
      "        d = f[name]; d.resize((d.shape[0] + more,))\n"
      "    first = {'frames': 'sample', 'contacts': 'frame', 'dcd_pairs': 'frame'}\n"
      "    ok = all((f[n][-1][k] == -1) and (f[n][0][k] == 3) for n, k in first.items())\n"
      "sys.exit(0 if ok else 3)\n";
  write_text(dir / "grow.py", script);
  ASSERT_EQ(std::system((std::string(kPython) + " " + (dir / "grow.py").string()).c_str()), 0);
  const auto data = read_log(path);
  EXPECT_FALSE(data.header.complete);
  ASSERT_EQ(data.frames.size(), 2u);
  EXPECT_EQ(data.frames[1].sample, 3);
  EXPECT_EQ(data.contacts.size(), 7u);
  EXPECT_EQ(data.dcd_pairs.size(), 4u);
}

TEST(Log, RefusesToOverwriteAFileThatIsNotALog) {
  const auto dir = skelcd::test::temp_dir("log-clobber");
  const auto text = dir / "notes.txt";
  write_text(text, "precious notes\n");
  EXPECT_THROW_MESSAGE(LogWriter(text, sample_header()), IoError, "refusing to overwrite");
  EXPECT_EQ(read_text(text), "precious notes\n");
  EXPECT_FALSE(is_skelcd_log(text));

  // A log and an empty file may be replaced.
  const auto log = dir / "old.h5";
  {
    LogWriter writer(log, sample_header());
    writer.append(sample_report(3, QueryKind::dcd, 0, 1));
    writer.finish();
  }
  EXPECT_TRUE(is_skelcd_log(log));
  {
    LogWriter writer(log, sample_header());
    writer.finish();
  }
  EXPECT_TRUE(read_log(log).frames.empty());
  const auto empty = dir / "empty.h5";
  write_text(empty, "");
  {
    LogWriter writer(empty, sample_header());
    writer.finish();
  }
  EXPECT_TRUE(is_skelcd_log(empty));
}

TEST(Log, ReaderNamesMissingAndNonHdf5Files) {
  const auto dir = skelcd::test::temp_dir("log-bad");
  EXPECT_THROW_MESSAGE((void)read_log(dir / "absent.h5"), IoError, "absent.h5: no such file");
  write_text(dir / "text.h5", "this is not HDF5\n");
  EXPECT_THROW_MESSAGE((void)read_log(dir / "text.h5"), IoError, "text.h5: not an HDF5 file");
}

TEST(Log, ReaderReportsTruncatedAndDamagedLogsByName) {
  const auto dir = skelcd::test::temp_dir("log-corrupt");
  const auto good = dir / "good.h5";
  {
    LogWriter writer(good, sample_header());
    for (const auto& r : sample_reports()) writer.append(r);
    writer.finish();
  }
  const std::string bytes = read_text(good);
  ASSERT_GT(bytes.size(), 4096u);
  // Cut in half: the superblock is intact, the tables' chunks are not.
  write_text(dir / "half.h5", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW_MESSAGE((void)read_log(dir / "half.h5"), IoError, "half.h5");
  // Overwrite everything after the superblock with garbage.
  std::string garbage = bytes;
  for (std::size_t i = 800; i < garbage.size(); ++i) garbage[i] = static_cast<char>((i * 131) & 0xff);
  write_text(dir / "garbage.h5", garbage);
  EXPECT_THROW_MESSAGE((void)read_log(dir / "garbage.h5"), IoError, "garbage.h5");
}

// File address of chunk `index` of dataset `name` (where its rows are on disk).
haddr_t chunk_address(const std::filesystem::path& path, const char* name, hsize_t index) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t dataset = H5Dopen2(file, name, H5P_DEFAULT);
  const hid_t space = H5Dget_space(dataset);
  hsize_t offset = 0;
  unsigned filter_mask = 0;
  haddr_t address = HADDR_UNDEF;
  hsize_t size = 0;
  EXPECT_GE(H5Dget_chunk_info(dataset, space, index, &offset, &filter_mask, &address, &size), 0);
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
  return address;
}

TEST(Log, GarbageInsideATableIsFoundByItsChecksumAndTheRowsBeforeItStayReadable) {
  const auto dir = skelcd::test::temp_dir("log-checksum");
  const auto path = dir / "run.h5";
  // 40 frames of 100 DCD pairs each: /dcd_pairs fills four chunks of 1024 rows.
  std::vector<FrameReport> reports;
  for (int k = 0; k < 40; ++k) reports.push_back(sample_report(k, QueryKind::dcd, 0, 100));
  {
    LogWriter writer(path, sample_header());
    for (const auto& r : reports) writer.append(r);
    writer.finish();
  }
  const auto clean = read_log(path);
  EXPECT_TRUE(clean.verified);
  EXPECT_TRUE(clean.damage.empty());
  ASSERT_EQ(clean.dcd_pairs.size(), 4000u);

  // 4 KB of garbage over the start of the third chunk (rows 2048 on, frames 20 on).
  const auto address = chunk_address(path, "dcd_pairs", 2);
  ASSERT_NE(address, HADDR_UNDEF);
  std::string bytes = read_text(path);
  ASSERT_LT(address + 4096, bytes.size());
  for (std::size_t i = 0; i < 4096; ++i)
    bytes[address + i] = static_cast<char>((i * 131 + 7) & 0xff);
  write_text(path, bytes);

  const auto damaged = read_log(path);
  EXPECT_FALSE(damaged.verified);
  ASSERT_FALSE(damaged.damage.empty());
  // The frame whose pairs start at row 2000 spans the damage: its block, rows 2000 to 2099, fails.
  EXPECT_EQ(
      damaged.damage.front(),
      "/dcd_pairs rows 2000 to 2099 are damaged (they fail their checksum)");
  // Everything written before it reads back exactly.
  ASSERT_EQ(damaged.frames.size(), 20u);
  ASSERT_EQ(damaged.dcd_pairs.size(), 2000u);
  for (std::size_t i = 0; i < damaged.dcd_pairs.size(); ++i) {
    EXPECT_EQ(damaged.dcd_pairs[i].frame, clean.dcd_pairs[i].frame);
    EXPECT_EQ(damaged.dcd_pairs[i].a.index, clean.dcd_pairs[i].a.index);
    EXPECT_EQ(damaged.dcd_pairs[i].b.index, clean.dcd_pairs[i].b.index);
  }
  for (std::size_t i = 0; i < damaged.frames.size(); ++i)
    expect_rows_equal(damaged.frames[i], clean.frames[i]);
  // Summaries that do not ask for the findings still verify them.
  const auto summary = read_log(path, ReadLogOptions{.findings = false});
  EXPECT_EQ(summary.frames.size(), 20u);
  EXPECT_FALSE(summary.damage.empty());
  // inspect summarises the rows before the damage, names it, and exits 1.
  const auto r = skelcd::test::run_skelcd({"inspect", path.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(
      r.err.find(path.string() + ": /dcd_pairs rows 2000 to 2099 are damaged"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("damaged (20/"), std::string::npos) << r.out;
}

TEST(Log, ADamagedExtentIsRefusedNotAllocated) {
  // Found by fuzz_log_reader: /parts claiming 2^53 rows in a 26 KB file (a std::bad_alloc before).
  const auto file = std::filesystem::path(skelcd::test::asset("..")) /
                    "fuzz/crashes/ours/read_parts_huge_extent.hdf5";
  EXPECT_THROW_MESSAGE(
      (void)read_log(file), IoError, "/parts claims 14636698788954113 rows, more than the file's");
}

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kUnderAddressSanitizer = true;
#else
constexpr bool kUnderAddressSanitizer = false;
#endif

TEST(Log, LogsOnWhichHdf5ItselfCrashesAreOneLineEach) {
  // Found by fuzz_log_reader: libhdf5 1.10.8 overflows its heap, or asks for terabytes, on these.
  // Logs are read in a child process that sends the log back, so each is a line naming the file,
  // never a crash; this process never opens them with libhdf5 (until 2026-11-27 it read them again
  // after the child, and under ASan the read after free below once crashed that second read).
  const auto dir = std::filesystem::path(skelcd::test::asset("..")) / "fuzz/crashes/hdf5";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    const auto file = entry.path().string();
    bool refused = false;
    try {
      (void)read_log(file);
    } catch (const IoError& e) {
      refused = true;
      EXPECT_EQ(std::string(e.what()).rfind(file + ": ", 0), 0u) << e.what();
    }
    if (kUnderAddressSanitizer &&
        entry.path().filename().string().find("use_after_free") != std::string::npos) {
      // Under ASan freed memory usually sits in its quarantine untouched, so libhdf5's read after
      // free (in uninstrumented code) often reads intact data and the log is whole; sometimes
      // ASan's allocator sees it and the reader child dies. Either way no crash reaches the user:
      // a quiet read, or the one line.
      const auto r = skelcd::test::run_skelcd({"inspect", file});
      if (r.exit_code == 0) {
        EXPECT_EQ(r.err, "") << file;
      } else {
        EXPECT_EQ(r.exit_code, 1) << file << ": " << r.err;
        EXPECT_EQ(r.err.rfind("skelcd: " + file + ": ", 0), 0u) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      }
      continue;
    }
    EXPECT_TRUE(refused) << file;
    const auto r = skelcd::test::run_skelcd({"inspect", file});
    EXPECT_EQ(r.exit_code, 1) << file << ": " << r.err;
    EXPECT_EQ(r.err.rfind("skelcd: " + file + ": ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_GE(files, 6);
}

TEST(Log, ReaderRejectsForeignHdf5ByName) {
  const auto dir = skelcd::test::temp_dir("log-foreign");
  const auto foreign = dir / "foreign.h5";
  const std::string script = "import h5py, numpy\n"
                             "with h5py.File('" + foreign.string() + "', 'w') as f:\n"
                             "    f['frames'] = numpy.arange(10)\n"
                             "    f.attrs['format'] = 'something-else'\n";
  write_text(dir / "make.py", script);
  ASSERT_EQ(std::system((std::string(kPython) + " " + (dir / "make.py").string()).c_str()), 0);
  EXPECT_THROW_MESSAGE((void)read_log(foreign), IoError, "foreign.h5: not a skelcd log");
  EXPECT_FALSE(is_skelcd_log(foreign));
}

TEST(Log, DocumentedH5pyExampleReadsALog) {
  // The python block of docs/log-format.md, run as it is on a log written here.
  const std::string doc = read_text(std::filesystem::path(SKELCD_SOURCE_DIR) / "docs/log-format.md");
  const auto begin = doc.find("```python\n");
  ASSERT_NE(begin, std::string::npos) << "docs/log-format.md has no python example";
  const auto code_begin = begin + 10;
  const auto end = doc.find("```", code_begin);
  ASSERT_NE(end, std::string::npos);
  const std::string code = doc.substr(code_begin, end - code_begin);
  EXPECT_LE(std::count(code.begin(), code.end(), '\n'), 6) << "the example should stay short";

  const auto dir = skelcd::test::temp_dir("log-h5py");
  {
    LogWriter writer(dir / "run.h5", sample_header());
    for (const auto& r : sample_reports()) writer.append(r);
    writer.finish();
  }
  write_text(dir / "example.py", code);
  const std::string command = "cd " + dir.string() + " && " + kPython + " example.py run.h5 > out.txt 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(dir / "out.txt");
  const std::string out = read_text(dir / "out.txt");
  // The example prints the method, the row count and the first contact's frame and kind.
  EXPECT_NE(out.find("bvh"), std::string::npos) << out;
  EXPECT_NE(out.find("5 rows"), std::string::npos) << out;
  EXPECT_NE(out.find("3005 contacts"), std::string::npos) << out;
}

TEST(FileHash, MatchesPublishedFnv1aVectors) {
  const auto hash = [](std::string_view s) {
    return fnv1a64(std::span<const unsigned char>(
                       reinterpret_cast<const unsigned char*>(s.data()), s.size()),
                   kFnv1a64Offset);
  };
  EXPECT_EQ(hash(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(hash("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(hash("foobar"), 0x85944171f73967e8ULL);
  const auto dir = skelcd::test::temp_dir("file-hash");
  write_text(dir / "foobar.txt", "foobar");
  EXPECT_EQ(file_content_hash(dir / "foobar.txt"), "fnv1a64:85944171f73967e8");
  EXPECT_THROW_MESSAGE((void)file_content_hash(dir / "none"), IoError, "none");
}

/// A scene log's header (sample_header with routes and two checks): every table and every
/// header dataset the writer can make.
LogHeader scene_header() {
  LogHeader h = sample_header();
  h.routes = {
      LogRoute{.component = 0, .part = 0, .closed = true, .triangles = 10, .method = "bvh"},
      LogRoute{.component = 1, .part = 1, .closed = false, .triangles = 4, .method = "kdop"}};
  h.checks = {
      LogCheck{"self body", "body", "", "ccd", "bvh", "conservative"},
      LogCheck{"pair body hat", "body", "hat", "both", "kdop", "exact"}};
  return h;
}

/// Every field of two reads of one log.
void expect_logs_equal(const LogData& a, const LogData& b) {
  expect_headers_equal(a.header, b.header);
  EXPECT_EQ(a.header.complete, b.header.complete);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    SCOPED_TRACE(i);
    expect_rows_equal(a.frames[i], b.frames[i]);
  }
  EXPECT_EQ(a.contacts, b.contacts);
  EXPECT_EQ(a.dcd_pairs, b.dcd_pairs);
  EXPECT_EQ(a.frame_checks, b.frame_checks);
  EXPECT_EQ(a.events, b.events);
  EXPECT_EQ(a.events_recorded, b.events_recorded);
  EXPECT_EQ(a.verified, b.verified);
  EXPECT_EQ(a.damage, b.damage);
}

TEST(Log, TheChildsReadComesBackWholeAndTheParentNeverReadsTheFile) {
  // read_log reads in a child process, which sends the log back (log_answer.cpp): every field of
  // a scene log with routes, checks, events and findings, a log cut short, and a damaged one must
  // come back as the same read in this process gives them.
  const auto dir = skelcd::test::temp_dir("log-answer");
  const auto whole = dir / "scene.h5";
  {
    LogWriter writer(whole, scene_header());
    std::int32_t check = 0;
    for (const auto& r : sample_reports()) writer.append(r, check++ % 2);
    writer.write_events(sample_events());
    writer.finish();
  }
  const auto cut = dir / "cut.h5";
  {
    LogWriter writer(cut, sample_header());
    for (const auto& r : sample_reports()) writer.append(r);
  }  // destroyed without finish(), as a run cut short by an error
  const auto damaged = dir / "damaged.h5";
  {
    LogWriter writer(damaged, sample_header());
    for (int k = 0; k < 40; ++k) writer.append(sample_report(k, QueryKind::dcd, 0, 100));
    writer.finish();
  }
  const auto address = chunk_address(damaged, "dcd_pairs", 2);
  ASSERT_NE(address, HADDR_UNDEF);
  std::string bytes = read_text(damaged);
  for (std::size_t i = 0; i < 4096; ++i) bytes[address + i] = static_cast<char>(i * 37);
  write_text(damaged, bytes);

  for (const auto& path : {whole, cut, damaged}) {
    SCOPED_TRACE(path.string());
    for (const bool findings : {true, false}) {
      const auto isolated = read_log(path, ReadLogOptions{.findings = findings});
      const auto here = read_log(path, ReadLogOptions{.findings = findings, .isolate = false});
      expect_logs_equal(isolated, here);
    }
  }
  const auto scene = read_log(whole);
  EXPECT_EQ(scene.header.routes, scene_header().routes);
  EXPECT_EQ(scene.header.checks, scene_header().checks);
  EXPECT_EQ(scene.frame_checks, (std::vector<std::int32_t>{0, 1, 0, 1, 0}));
  EXPECT_EQ(scene.events, sample_events());
  EXPECT_FALSE(read_log(cut).header.complete);
  EXPECT_FALSE(read_log(damaged).damage.empty());
}

TEST(Log, ADamagedAnswerFromTheReadersChildIsOneLine) {
  // The bytes a child sends, cut short or announcing more than they hold, are refused by name
  // before anything is allocated for them.
  const auto path = skelcd::test::temp_dir("log-answer-damaged") / "run.h5";
  {
    LogWriter writer(path, scene_header());
    for (const auto& r : sample_reports()) writer.append(r, 0);
    writer.write_events(sample_events());
    writer.finish();
  }
  const auto log = read_log(path, ReadLogOptions{.isolate = false});
  std::string sent;
  skelcd::tools::detail::write_log_answer(log, [&](const void* data, std::size_t size) {
    sent.append(static_cast<const char*>(data), size);
  });
  const auto answer = [](std::string bytes) {
    skelcd::skinning::detail::ChildAnswer a;
    a.append(std::vector<char>(bytes.begin(), bytes.end()));
    return a;
  };
  {
    auto whole = answer(sent);
    expect_logs_equal(skelcd::tools::detail::read_log_answer(whole, "run.h5"), log);
  }
  const std::string prefix = "run.h5: the log reader's answer from its child process is damaged (";
  for (const std::size_t keep :
       {std::size_t{0}, std::size_t{7}, sent.size() / 2, sent.size() - 1}) {
    SCOPED_TRACE(keep);
    auto cut = answer(sent.substr(0, keep));
    EXPECT_THROW_MESSAGE(
        (void)skelcd::tools::detail::read_log_answer(cut, "run.h5"), IoError, prefix);
  }
  auto longer = answer(sent + "x");
  EXPECT_THROW_MESSAGE(
      (void)skelcd::tools::detail::read_log_answer(longer, "run.h5"),
      IoError,
      prefix + "1 bytes after the log)");
  // The part-name count (after the magic, the version and the header's leading fields) set to
  // 2^60: refused by the bytes that follow, not allocated.
  std::string huge = sent;
  const std::string first_part = log.header.part_names.front();
  const auto at = huge.find(first_part) - 2 * sizeof(std::uint64_t);
  const std::uint64_t count = std::uint64_t{1} << 60;
  std::memcpy(huge.data() + at, &count, sizeof count);
  auto announced = answer(huge);
  EXPECT_THROW_MESSAGE(
      (void)skelcd::tools::detail::read_log_answer(announced, "run.h5"),
      IoError,
      prefix + "1152921504606846976 part names announced");
}

TEST(Log, EachTableCachesOneOfItsChunksNotHdf5sMegabyte) {
  // HDF5's default chunk cache is 1 MiB per open dataset, kept until the file closes; the writer
  // only ever writes a table's last chunk, so each table caches exactly one chunk (the cache must
  // be at least a chunk, or HDF5 reads the chunk back for every partial write).
  const auto path = skelcd::test::temp_dir("log-chunk-cache") / "run.h5";
  LogWriter writer(path, scene_header());
  for (const auto& report : sample_reports()) writer.append(report, 1);
  const auto count = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_DATASET);
  ASSERT_GT(count, 0);
  std::vector<hid_t> ids(static_cast<std::size_t>(count));
  ASSERT_EQ(H5Fget_obj_ids(H5F_OBJ_ALL, H5F_OBJ_DATASET, ids.size(), ids.data()), count);
  std::vector<std::string> tables;
  for (const hid_t id : ids) {
    std::string name(256, '\0');
    name.resize(static_cast<std::size_t>(H5Iget_name(id, name.data(), name.size())));
    const hid_t create = H5Dget_create_plist(id);
    const hid_t access = H5Dget_access_plist(id);
    const hid_t type = H5Dget_type(id);
    hsize_t chunk_rows = 0;
    std::size_t slots = 0, bytes = 0;
    double w0 = 0;
    ASSERT_EQ(H5Pget_chunk(create, 1, &chunk_rows), 1) << name << " is chunked";
    ASSERT_GE(H5Pget_chunk_cache(access, &slots, &bytes, &w0), 0) << name;
    EXPECT_EQ(bytes, chunk_rows * H5Tget_size(type)) << name;
    EXPECT_LT(bytes, std::size_t{1} << 20) << name;
    EXPECT_LT(slots, 521u) << name << ": fewer slots than HDF5's default";
    H5Tclose(type);
    H5Pclose(access);
    H5Pclose(create);
    tables.push_back(name);
  }
  std::sort(tables.begin(), tables.end());
  EXPECT_EQ(
      tables,
      (std::vector<std::string>{
          "/checksums", "/contacts", "/dcd_pairs", "/frame_check", "/frames"}));
  writer.finish();
  EXPECT_EQ(read_log(path).frames.size(), sample_reports().size());
}

TEST(Log, ContactRecordsHaveTheSizesBenchRealCounts) {
  // scripts/bench_real.py (CONTACT_RECORD_BYTES) counts n × (32 + 56) bytes of a peak as the
  // findings of an interval with n contacts (the contacts, sorted in place, and the report's rows,
  // which the event tracker labels in place), and the log writer's rows (56 each, at most 8,192
  // at a time) inside its measured share: keep them in step.
  EXPECT_EQ(sizeof(skelcd::culling::CcdContact), 32u);
  EXPECT_EQ(sizeof(ContactRow), 56u);
  EXPECT_EQ(sizeof(skelcd::tools::detail::ContactDisk), 56u);
}

}  // namespace
