// The per-interval runner: rows in order for each --query, positions handed to the method,
// findings converted from welded ids to the file's own numbering, non-finite samples refused.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tools/engine/runner.hpp"

namespace {

using namespace skelcd;
using namespace skelcd::tools;
using skinning::Positions;

/// Two parts: part 0 "tri" is one triangle (file vertices 0..2); part 1 "quad" is a unit square
/// made of two triangles with its own 6 vertices (3..8), the diagonal's ends duplicated as a seam
/// that welding merges: file vertices 6 and 7 repeat 4 and 5... see below.
skinning::Mesh two_part_mesh() {
  skinning::Mesh m;
  m.rest_positions.resize(9, 3);
  m.rest_positions << 0, 0, 1,   // 0 part 0 index 0
      1, 0, 1,                  // 1 part 0 index 1
      0, 1, 1,                  // 2 part 0 index 2
      0, 0, 0,                  // 3 part 1 index 0
      1, 0, 0,                  // 4 part 1 index 1
      1, 1, 0,                  // 5 part 1 index 2
      1, 1, 0,                  // 6 part 1 index 3 (= 5)
      0, 1, 0,                  // 7 part 1 index 4
      0, 0, 0;                  // 8 part 1 index 5 (= 3)
  m.triangles.resize(3, 3);
  m.triangles << 0, 1, 2, 3, 4, 5, 6, 7, 8;
  m.face_part = {0, 1, 1};
  m.face_index_in_part = {0, 0, 1};
  m.vertex_part = {0, 0, 0, 1, 1, 1, 1, 1, 1};
  m.vertex_index_in_part = {0, 1, 2, 0, 1, 2, 3, 4, 5};
  m.part_names = {"tri", "quad"};
  return m;
}

/// Sample i: every vertex translated by (0, 0, -0.5 i); optionally one NaN at a chosen sample.
class ShiftMotion : public skinning::Motion {
 public:
  ShiftMotion(skinning::Mesh mesh, int samples) : mesh_(std::move(mesh)), samples_(samples) {}
  const skinning::Mesh& mesh() const override { return mesh_; }
  int num_samples() const override { return samples_; }
  double sample_time(int i) const override { return 0.25 * i; }
  std::string name() const override { return "shift-clip"; }
  void positions(int i, Positions& out) const override {
    out = mesh_.rest_positions;
    out.col(2).array() -= 0.5 * i;
    if (i == nan_sample) out(4, 1) = std::numeric_limits<double>::quiet_NaN();
  }
  int nan_sample = -1;

 private:
  skinning::Mesh mesh_;
  int samples_;
};

/// ShiftMotion's samples held in memory, lent through held_positions() as a frame sequence's.
class HeldShiftMotion : public skinning::Motion {
 public:
  HeldShiftMotion(skinning::Mesh mesh, int samples) : mesh_(std::move(mesh)) {
    for (int i = 0; i < samples; ++i) {
      frames_.push_back(mesh_.rest_positions);
      frames_.back().col(2).array() -= 0.5 * i;
    }
  }
  const skinning::Mesh& mesh() const override { return mesh_; }
  int num_samples() const override { return static_cast<int>(frames_.size()); }
  double sample_time(int i) const override { return 0.25 * i; }
  std::string name() const override { return "held-clip"; }
  void positions(int i, Positions& out) const override { out = *held_positions(i); }
  const Positions* held_positions(int i) const override {
    return &frames_[static_cast<std::size_t>(i)];
  }

 private:
  skinning::Mesh mesh_;
  std::vector<Positions> frames_;
};

/// A method that records what it was given and reports fixed findings in welded numbering.
struct Recorded {
  std::vector<Positions> dcd_inputs;
  std::vector<std::pair<Positions, Positions>> ccd_inputs;
  std::vector<std::pair<const double*, const double*>> ccd_addresses;  // where they were read
};

class FakeMethod : public culling::CullingMethod {
 public:
  FakeMethod(Recorded& record, std::vector<culling::CcdContact> contacts,
             std::vector<culling::TrianglePair> pairs)
      : record_(record), contacts_(std::move(contacts)), pairs_(std::move(pairs)) {}
  std::string_view name() const override { return "fake"; }
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    const skinning::Positions& x = at.x;
    record_.dcd_inputs.push_back(x);
    out.dcd_pairs = pairs_;
    out.counters.tt_tests = 7;
    out.counters.dcd_pairs = 999;  // wrong on purpose: the runner counts the findings itself
    out.times.traverse_us = 1.5;
  }
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    record_.ccd_inputs.emplace_back(x_t0, x_t1);
    record_.ccd_addresses.emplace_back(x_t0.data(), x_t1.data());
    out.contacts = contacts_;
    out.counters.vf_tests = 11;
    out.times.elementary_us = 2.5;
  }

 private:
  Recorded& record_;
  std::vector<culling::CcdContact> contacts_;
  std::vector<culling::TrianglePair> pairs_;
};

std::int32_t edge_between(const skinning::Topology& t, std::int32_t file_a, std::int32_t file_b) {
  auto a = t.welded_of_vertex[static_cast<std::size_t>(file_a)];
  auto b = t.welded_of_vertex[static_cast<std::size_t>(file_b)];
  if (a > b) std::swap(a, b);
  for (std::int32_t e = 0; e < t.num_edges(); ++e) {
    if (t.edges(e, 0) == a && t.edges(e, 1) == b) return e;
  }
  ADD_FAILURE() << "no edge " << file_a << "-" << file_b;
  return -1;
}

struct RunOutput {
  std::vector<FrameReport> reports;
  Recorded record;
  RunPlan plan;
};

/// What a callback does with each row: by default, copies it into `out.reports`.
using TakeRow = std::function<void(FrameReport&, RunOutput&)>;

RunOutput run(
    QuerySet query,
    FrameRange frames,
    int samples = 4,
    int nan_sample = -1,
    const TakeRow& take = {}) {
  ShiftMotion motion(two_part_mesh(), samples);
  motion.nan_sample = nan_sample;
  RunOutput out;
  RunOptions options;
  options.query = query;
  options.frames = frames;
  ClipRunner runner(motion, options,
                    [&](const skinning::Mesh&, const skinning::Topology& t,
                        const culling::MethodOptions&) {
                      // VF: the quad's seam vertex (file 6 welds onto 5) against the triangle;
                      // EE: the tri's edge 1-2 against the quad's diagonal 3-5.
                      std::vector<culling::CcdContact> contacts{
                          {culling::CcdContact::Kind::vf, t.welded_of_vertex[6], 0, 0.25, 0.375},
                          {culling::CcdContact::Kind::ee, edge_between(t, 1, 2),
                           edge_between(t, 3, 5), 0.5, 0.625}};
                      std::vector<culling::TrianglePair> pairs{{0, 2}};
                      return std::make_unique<FakeMethod>(out.record, contacts, pairs);
                    });
  out.plan = runner.plan();
  try {
    runner.run([&](FrameReport& r) {
      if (take) {
        take(r, out);
      } else {
        out.reports.push_back(r);
      }
    });
  } catch (...) {
    if (nan_sample < 0) throw;
  }
  return out;
}

TEST(FrameRange, ParsesTheFourForms) {
  auto r = parse_frame_range("3:7");
  EXPECT_EQ(r.first, 3);
  EXPECT_EQ(r.last, 7);
  r = parse_frame_range("5:");
  EXPECT_EQ(r.first, 5);
  EXPECT_FALSE(r.last.has_value());
  r = parse_frame_range(":2");
  EXPECT_EQ(r.first, 0);
  EXPECT_EQ(r.last, 2);
  r = parse_frame_range("4");
  EXPECT_EQ(r.first, 4);
  EXPECT_EQ(r.last, 4);
  for (const char* bad : {"", "a:b", "-1:3", "3:1", "1:2:3", "1.5:3", " 1:2"}) {
    EXPECT_THROW_MESSAGE((void)parse_frame_range(bad), InvalidInput, "--frames");
  }
}

TEST(Runner, BothQueriesInterleaveRowsInTimeOrder) {
  const auto out = run(QuerySet::both, FrameRange{});
  EXPECT_EQ(out.plan.samples, 4);
  EXPECT_EQ(out.plan.intervals, 3);
  ASSERT_EQ(out.plan.rows, 7);
  ASSERT_EQ(out.reports.size(), 7u);
  const std::vector<std::pair<QueryKind, int>> expected{
      {QueryKind::dcd, 0}, {QueryKind::ccd, 0}, {QueryKind::dcd, 1}, {QueryKind::ccd, 1},
      {QueryKind::dcd, 2}, {QueryKind::ccd, 2}, {QueryKind::dcd, 3}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const auto& row = out.reports[i].row;
    EXPECT_EQ(row.kind, expected[i].first) << i;
    EXPECT_EQ(row.sample, expected[i].second) << i;
    EXPECT_EQ(row.t0, 0.25 * row.sample);
    EXPECT_EQ(row.t1, row.kind == QueryKind::ccd ? 0.25 * (row.sample + 1) : row.t0);
    EXPECT_GE(row.times.skin_us, 0.0);
    EXPECT_GE(row.total_us, row.times.skin_us);
  }
  // Each of the 4 samples is posed once; the skinning time of sample i+1 is charged to the CCD row.
  EXPECT_EQ(out.record.dcd_inputs.size(), 4u);
  EXPECT_EQ(out.record.ccd_inputs.size(), 3u);
}

TEST(Runner, ARowIsTheCallbacksToTakeAndVectorsHandedBackAreClearedAndRefilled) {
  const auto copied = run(QuerySet::both, FrameRange{});
  // Each row moved out whole, and in its place vectors with room for 64 findings handed back,
  // each holding a finding of no row (what a caller's emptied buffers may still hold).
  std::vector<const ContactRow*> contacts_back;
  std::vector<const DcdPairRow*> pairs_back;
  std::size_t rows_in_handed_back = 0;
  const auto taken = run(QuerySet::both, FrameRange{}, 4, -1, [&](FrameReport& r, RunOutput& out) {
    if (!contacts_back.empty()) {
      rows_in_handed_back +=
          r.contacts.data() == contacts_back.back() && r.dcd_pairs.data() == pairs_back.back();
    }
    out.reports.push_back(std::move(r));
    std::vector<ContactRow> contacts(64);
    contacts.resize(1);
    contacts.front().frame = -7;
    std::vector<DcdPairRow> pairs(64);
    pairs.resize(1);
    pairs.front().frame = -7;
    contacts_back.push_back(contacts.data());
    pairs_back.push_back(pairs.data());
    r.contacts = std::move(contacts);
    r.dcd_pairs = std::move(pairs);
  });
  ASSERT_EQ(taken.reports.size(), 7u);
  ASSERT_EQ(copied.reports.size(), 7u);
  // Every row after the first came in the vectors handed back after the one before it.
  EXPECT_EQ(rows_in_handed_back, 6u);
  std::size_t findings = 0;
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(taken.reports[i].row.kind, copied.reports[i].row.kind) << i;
    EXPECT_EQ(taken.reports[i].row.sample, copied.reports[i].row.sample) << i;
    EXPECT_EQ(
        taken.reports[i].row.counters.vf_contacts, copied.reports[i].row.counters.vf_contacts);
    EXPECT_EQ(taken.reports[i].contacts, copied.reports[i].contacts) << i;
    EXPECT_EQ(taken.reports[i].dcd_pairs, copied.reports[i].dcd_pairs) << i;
    findings += copied.reports[i].contacts.size() + copied.reports[i].dcd_pairs.size();
  }
  EXPECT_EQ(findings, 4u * 1 + 3u * 2);  // a DCD pair per sample, two contacts per interval
}

TEST(Runner, QuerySubsetsAndFrameRanges) {
  auto out = run(QuerySet::dcd, parse_frame_range("1:3"));
  EXPECT_EQ(out.plan.rows, 3);
  ASSERT_EQ(out.reports.size(), 3u);
  EXPECT_EQ(out.reports.front().row.sample, 1);
  EXPECT_TRUE(out.record.ccd_inputs.empty());

  out = run(QuerySet::ccd, parse_frame_range("1:3"));
  EXPECT_EQ(out.plan.rows, 2);
  ASSERT_EQ(out.reports.size(), 2u);
  EXPECT_EQ(out.reports[0].row.kind, QueryKind::ccd);
  EXPECT_EQ(out.reports[0].row.sample, 1);
  EXPECT_EQ(out.reports[1].row.sample, 2);
  EXPECT_TRUE(out.record.dcd_inputs.empty());

  out = run(QuerySet::both, parse_frame_range("2"));
  EXPECT_EQ(out.plan.rows, 1);
  EXPECT_EQ(out.plan.intervals, 0);

  EXPECT_THROW_MESSAGE(run(QuerySet::ccd, parse_frame_range("2")), InvalidInput, "two samples");
  EXPECT_THROW_MESSAGE(run(QuerySet::both, parse_frame_range("2:4")), InvalidInput,
                       "outside the 4 samples");
}

TEST(Runner, MethodSeesWeldedPositionsOfConsecutiveSamples) {
  const auto out = run(QuerySet::ccd, FrameRange{});
  ShiftMotion motion(two_part_mesh(), 4);
  const auto topology = skinning::build_topology(motion.mesh());
  ASSERT_EQ(topology.num_welded_vertices(), 7);  // 9 file vertices, two seam duplicates
  ASSERT_EQ(out.record.ccd_inputs.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    Positions x0, x1;
    motion.positions(i, x0);
    motion.positions(i + 1, x1);
    const auto& [w0, w1] = out.record.ccd_inputs[static_cast<std::size_t>(i)];
    ASSERT_EQ(w0.rows(), 7);
    for (int w = 0; w < 7; ++w) {
      const auto v = topology.representative_vertex[static_cast<std::size_t>(w)];
      EXPECT_EQ(w0.row(w), x0.row(v)) << "sample " << i << " welded " << w;
      EXPECT_EQ(w1.row(w), x1.row(v)) << "sample " << i + 1 << " welded " << w;
    }
  }
}

// A held frame is handed to the method where the motion holds it when welding leaves every
// vertex as it is, and welded into the worker's own buffer when it merges some; the positions
// the method sees are the welded ones either way.
TEST(Runner, HeldFramesAreLentWhereWeldingIsTheIdentity) {
  skinning::Mesh seamless = two_part_mesh();  // the quad on 4 vertices: nothing to weld
  seamless.rest_positions.conservativeResize(7, 3);
  seamless.rest_positions.row(6) << 0, 1, 0;
  seamless.triangles << 0, 1, 2, 3, 4, 5, 3, 5, 6;
  seamless.vertex_part.resize(7);
  seamless.vertex_index_in_part.resize(7);
  for (const bool welds : {false, true}) {
    const HeldShiftMotion motion(welds ? two_part_mesh() : seamless, 3);
    const auto topology = skinning::build_topology(motion.mesh());
    ASSERT_EQ(topology.num_welded_vertices() < motion.mesh().num_vertices(), welds);
    Recorded record;
    RunOptions options;
    options.query = QuerySet::ccd;
    ClipRunner runner(
        motion,
        options,
        [&](const skinning::Mesh&, const skinning::Topology&, const culling::MethodOptions&) {
          return std::make_unique<FakeMethod>(
              record, std::vector<culling::CcdContact>{}, std::vector<culling::TrianglePair>{});
        });
    runner.run([](const FrameReport&) {});
    ASSERT_EQ(record.ccd_inputs.size(), 2U);
    for (std::size_t i = 0; i < 2; ++i) {
      const auto k = static_cast<int>(i);
      const auto& [a0, a1] = record.ccd_addresses[i];
      EXPECT_EQ(a0 == motion.held_positions(k)->data(), !welds) << "interval " << i;
      EXPECT_EQ(a1 == motion.held_positions(k + 1)->data(), !welds) << "interval " << i;
      const auto& [w0, w1] = record.ccd_inputs[i];
      ASSERT_EQ(w0.rows(), topology.num_welded_vertices());
      for (Eigen::Index w = 0; w < w0.rows(); ++w) {
        const auto v = topology.representative_vertex[static_cast<std::size_t>(w)];
        EXPECT_EQ(w0.row(w), motion.held_positions(k)->row(v)) << i << " welded " << w;
        EXPECT_EQ(w1.row(w), motion.held_positions(k + 1)->row(v)) << i << " welded " << w;
      }
    }
  }
}

TEST(Runner, FindingsAreReportedInTheFilesNumbering) {
  const auto out = run(QuerySet::both, parse_frame_range("0:1"));
  ASSERT_EQ(out.reports.size(), 3u);
  const auto& dcd = out.reports[0];
  ASSERT_EQ(dcd.dcd_pairs.size(), 1u);
  EXPECT_EQ(dcd.dcd_pairs[0].frame, 0);
  EXPECT_EQ(dcd.dcd_pairs[0].a, (FeatureId{0, 0, -1}));  // triangle 0 = part 0 triangle 0
  EXPECT_EQ(dcd.dcd_pairs[0].b, (FeatureId{1, 1, -1}));  // triangle 2 = part 1 triangle 1
  EXPECT_EQ(dcd.row.counters.dcd_pairs, 1);  // counted from the findings, not the method's 999
  EXPECT_EQ(dcd.row.counters.tt_tests, 7);
  EXPECT_EQ(dcd.row.times.traverse_us, 1.5);
  EXPECT_TRUE(dcd.contacts.empty());

  const auto& ccd = out.reports[1];
  ASSERT_EQ(ccd.contacts.size(), 2u);
  const auto& vf = ccd.contacts[0];
  EXPECT_EQ(vf.frame, 0);
  EXPECT_EQ(vf.kind, culling::CcdContact::Kind::vf);
  // File vertex 6 sits on file vertex 5 (part 1, index 2), the first in file order: that one names it.
  EXPECT_EQ(vf.a, (FeatureId{1, 2, -1}));
  EXPECT_EQ(vf.b, (FeatureId{0, 0, -1}));
  EXPECT_EQ(vf.toi_lower, 0.25);
  EXPECT_EQ(vf.toi_upper, 0.375);
  const auto& ee = ccd.contacts[1];
  EXPECT_EQ(ee.kind, culling::CcdContact::Kind::ee);
  // Edge 1-2 belongs to triangle (0, 1, 2) only: its side 1 (corner 1 → corner 2).
  EXPECT_EQ(ee.a, (FeatureId{0, 0, 1}));
  // The diagonal 3-5 is shared by both quad triangles; whichever names it, its side must run
  // between the welded ends of the diagonal.
  const auto mesh = two_part_mesh();
  const auto topology = skinning::build_topology(mesh);
  ASSERT_EQ(ee.b.part, 1);
  ASSERT_GE(ee.b.side, 0);
  const std::int32_t f = ee.b.index == 0 ? 1 : 2;
  const auto corner = [&](int k) {
    return topology.welded_of_vertex[static_cast<std::size_t>(mesh.triangles(f, k % 3))];
  };
  std::array<std::int32_t, 2> ends{corner(ee.b.side), corner(ee.b.side + 1)};
  std::sort(ends.begin(), ends.end());
  std::array<std::int32_t, 2> diagonal{topology.welded_of_vertex[3], topology.welded_of_vertex[5]};
  std::sort(diagonal.begin(), diagonal.end());
  EXPECT_EQ(ends, diagonal);
  EXPECT_EQ(ccd.row.counters.vf_contacts, 1);
  EXPECT_EQ(ccd.row.counters.ee_contacts, 1);
  EXPECT_EQ(ccd.row.counters.vf_tests, 11);
  EXPECT_EQ(ccd.row.times.elementary_us, 2.5);
  EXPECT_TRUE(ccd.dcd_pairs.empty());
}

TEST(Runner, NonFiniteSampleIsRefusedByNameAfterEarlierRowsWereReported) {
  ShiftMotion motion(two_part_mesh(), 4);
  motion.nan_sample = 2;
  Recorded record;
  ClipRunner runner(motion, RunOptions{},
                    [&](const skinning::Mesh&, const skinning::Topology&,
                        const culling::MethodOptions&) {
                      return std::make_unique<FakeMethod>(
                          record, std::vector<culling::CcdContact>{},
                          std::vector<culling::TrianglePair>{});
                    });
  std::vector<FrameReport> reports;
  EXPECT_THROW_MESSAGE(runner.run([&](const FrameReport& r) { reports.push_back(r); }),
                       InvalidInput, "shift-clip: sample 2 (t = 0.5");
  EXPECT_EQ(reports.size(), 3u);  // dcd 0, ccd 0, dcd 1
}

TEST(Runner, UnknownMethodIsRefusedBeforeAnyWork) {
  ShiftMotion motion(two_part_mesh(), 2);
  RunOptions options;
  options.method = "no-such-method";
  EXPECT_THROW_MESSAGE(ClipRunner(motion, options), InvalidInput, "no-such-method");
}

/// Part 0: a large triangle in z = 0. Part 1: a small triangle that passes down through it
/// (samples 0 → 1) and then tilts until it pierces it (sample 2). Worked out by hand:
/// interval 0-1: each of the small triangle's 3 vertices crosses the large face at t = 1/2 inside
/// it (3 VF), no edge comes near another (0 EE); interval 1-2: vertices 1 and 2 cross at t = 1/2
/// at (1.75, 1) and (1.5, 2) (2 VF), vertex 0 stays at z = -1; DCD: only sample 2 intersects.
class CrossingMotion : public skinning::Motion {
 public:
  CrossingMotion() {
    mesh_.rest_positions.resize(6, 3);
    mesh_.rest_positions << 0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 1, 1, 2, 1, 1, 1, 2, 1;
    mesh_.triangles.resize(2, 3);
    mesh_.triangles << 0, 1, 2, 3, 4, 5;
    mesh_.face_part = {0, 1};
    mesh_.face_index_in_part = {0, 0};
    mesh_.vertex_part = {0, 0, 0, 1, 1, 1};
    mesh_.vertex_index_in_part = {0, 1, 2, 0, 1, 2};
    mesh_.part_names = {"floor", "blade"};
  }
  const skinning::Mesh& mesh() const override { return mesh_; }
  int num_samples() const override { return 3; }
  double sample_time(int i) const override { return i / 24.0; }
  std::string name() const override { return "crossing"; }
  void positions(int i, Positions& out) const override {
    out = mesh_.rest_positions;
    if (i == 1) out.block(3, 2, 3, 1).setConstant(-1);
    if (i == 2) out.bottomRows(3) << 1, 1, -1, 1.5, 1, 1, 2, 2, 1;
  }

 private:
  skinning::Mesh mesh_;
};

TEST(Runner, AutoTakesRigidRowsOnlyForAClosedGroup) {
  // Rigid rows go to the methods that take them; under `auto` those are its closed group's. A
  // garment on its own skeleton (gen:cloth: one open sheet, its boundary no hole to cap) goes
  // whole to the cones, which take none: no rows are built. RobotExpressive, closed parts hanging
  // rigidly from nodes, goes whole to `bvh` with them.
  const auto rows_of = [](const std::string& model, const std::string& method, bool asked) {
    const auto loaded = skinning::load_model(model);
    const auto motion = loaded.motion({});
    RunOptions options;
    options.method = method;
    options.rigid_rows = asked;
    options.frames = FrameRange{0, 2};
    return ClipRunner(*motion, options).has_rigid_rows();
  };
  const std::string cloth = "gen:cloth?triangles=1200&frames=6";
  const std::string robot = test::asset("characters/RobotExpressive.glb").string();
  EXPECT_FALSE(rows_of(cloth, "auto", true));
  EXPECT_TRUE(rows_of(cloth, "kdop", true));  // the sheet has rows, and kdop takes them
  EXPECT_TRUE(rows_of(robot, "auto", true));
  EXPECT_FALSE(rows_of(robot, "auto", false));  // --no-rigid-rows
}

TEST(Runner, RealMethodsFindTheHandCountedContactsInFileNumbering) {
  const CrossingMotion motion;
  for (const char* method : {"brute", "bvh", "kdop"}) {
    for (const auto accuracy : {ccd::Accuracy::conservative, ccd::Accuracy::exact}) {
      SCOPED_TRACE(std::string(method) + " " + std::string(ccd::to_string(accuracy)));
      RunOptions options;
      options.method = method;
      options.accuracy = accuracy;
      ClipRunner runner(motion, options);
      std::vector<FrameReport> reports;
      runner.run([&](const FrameReport& r) { reports.push_back(r); });
      ASSERT_EQ(reports.size(), 5u);  // dcd 0, ccd 0, dcd 1, ccd 1, dcd 2

      EXPECT_TRUE(reports[0].dcd_pairs.empty());
      EXPECT_TRUE(reports[2].dcd_pairs.empty());
      ASSERT_EQ(reports[4].dcd_pairs.size(), 1u);
      EXPECT_EQ(reports[4].dcd_pairs[0].a, (FeatureId{0, 0, -1}));
      EXPECT_EQ(reports[4].dcd_pairs[0].b, (FeatureId{1, 0, -1}));
      EXPECT_EQ(reports[4].row.counters.dcd_pairs, 1);

      const auto vertices_hitting_the_floor = [](const FrameReport& r) {
        std::vector<std::int32_t> v;
        for (const auto& c : r.contacts) {
          EXPECT_EQ(c.kind, culling::CcdContact::Kind::vf);
          EXPECT_EQ(c.a.part, 1);
          EXPECT_EQ(c.b, (FeatureId{0, 0, -1}));
          EXPECT_LE(c.toi_lower, 0.5);
          EXPECT_GE(c.toi_upper, 0.5);
          v.push_back(c.a.index);
        }
        std::sort(v.begin(), v.end());
        return v;
      };
      EXPECT_EQ(vertices_hitting_the_floor(reports[1]), (std::vector<std::int32_t>{0, 1, 2}));
      EXPECT_EQ(vertices_hitting_the_floor(reports[3]), (std::vector<std::int32_t>{1, 2}));
      EXPECT_EQ(reports[1].row.counters.vf_contacts, 3);
      EXPECT_EQ(reports[1].row.counters.ee_contacts, 0);
      EXPECT_EQ(reports[3].row.counters.vf_contacts, 2);
      EXPECT_EQ(reports[3].row.t1, 2 / 24.0);
    }
  }
}

/// The two-part mesh lowered by 0.5 per step; sample i takes step kHoldSteps[i]: a pose held
/// over samples 0-2, a move, then another pose held over samples 4-6.
class HoldMotion : public skinning::Motion {
 public:
  static constexpr int kHoldSteps[] = {0, 0, 0, 1, 2, 2, 2};
  HoldMotion() : mesh_(two_part_mesh()) {}
  const skinning::Mesh& mesh() const override { return mesh_; }
  int num_samples() const override { return 7; }
  double sample_time(int i) const override { return 0.25 * i; }
  std::string name() const override { return "hold-clip"; }
  void positions(int i, Positions& out) const override {
    out = mesh_.rest_positions;
    out.col(2).array() -= 0.5 * kHoldSteps[i];
  }

 private:
  skinning::Mesh mesh_;
};

/// A method without state whose answer depends on the query's positions only: a VF contact of
/// the quad's seam vertex against the triangle at a time taken from the depth at t0, counters
/// from the depths at both ends. Counts the CCD queries it was asked.
class PoseMethod : public culling::CullingMethod {
 public:
  explicit PoseMethod(int& ccd_queries) : ccd_queries_(ccd_queries) {}
  std::string_view name() const override { return "pose"; }
  void dcd(const culling::Instant&, culling::FrameResult&) override {}
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    ++ccd_queries_;
    const double z0 = interval.x_t0(0, 2);
    const double z1 = interval.x_t1(0, 2);
    out.contacts = {{culling::CcdContact::Kind::vf, 4, 0, -z0 / 8, -z0 / 8 + 0.125}};
    out.counters.vf_tests = std::llround(-1000 * z0) + 7;
    out.counters.ee_tests = std::llround(-1000 * z1) + 3;
    out.times.elementary_us = 2.5;
  }

 private:
  int& ccd_queries_;
};

// A held pose asks its question once: of the intervals 0-1, 1-2 (the pose of samples 0-2) and
// 4-5, 5-6 (that of 4-6) only the first of each reaches a method declared stateless, and every
// row — its counters and contacts — is the one querying each interval gives. Rows handed on have
// no stage times. A factory not declared stateless, or reuse turned off, queries every interval.
TEST(Runner, AHeldPoseIsQueriedOnceAndItsRowsStayTheSame) {
  const HoldMotion motion;
  const auto run = [&](bool reuse, bool stateless, int& queries) {
    RunOptions options;
    options.query = QuerySet::ccd;
    options.reuse_static_intervals = reuse;
    options.factory_methods_stateless = stateless;
    ClipRunner runner(
        motion,
        options,
        [&](const skinning::Mesh&, const skinning::Topology&, const culling::MethodOptions&) {
          return std::make_unique<PoseMethod>(queries);
        });
    std::vector<FrameReport> reports;
    runner.run([&](const FrameReport& r) { reports.push_back(r); });
    return reports;
  };
  int queried_each = 0;
  const std::vector<FrameReport> each = run(false, true, queried_each);
  EXPECT_EQ(queried_each, 6);
  int queried_stateful = 0;
  (void)run(true, false, queried_stateful);
  EXPECT_EQ(queried_stateful, 6);
  int queried_held = 0;
  const std::vector<FrameReport> held = run(true, true, queried_held);
  EXPECT_EQ(queried_held, 4);  // intervals 0, 2, 3, 4
  ASSERT_EQ(held.size(), 6u);
  ASSERT_EQ(each.size(), 6u);
  for (std::size_t i = 0; i < held.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(held[i].row.sample, static_cast<std::int32_t>(i));
    EXPECT_EQ(held[i].row.counters.vf_tests, each[i].row.counters.vf_tests);
    EXPECT_EQ(held[i].row.counters.ee_tests, each[i].row.counters.ee_tests);
    EXPECT_EQ(held[i].row.counters.vf_contacts, 1);
    EXPECT_EQ(held[i].contacts, each[i].contacts);
    const bool handed_on = i == 1 || i == 5;
    EXPECT_EQ(held[i].row.times.elementary_us, handed_on ? 0.0 : 2.5);
  }
  // The rows differ between the two held poses: what is handed on is the pose's own answer.
  EXPECT_NE(held[1].row.counters.vf_tests, held[5].row.counters.vf_tests);
  EXPECT_NE(held[1].contacts, held[5].contacts);
}

}  // namespace
