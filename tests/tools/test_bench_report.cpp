// The accuracy-versus-time report (tools/report/bench_report.hpp): set comparison on hand-made
// keys, the reference choice, and whole reports on a generated rope with a known answer and on a
// real character — the reference row is clean, exact and conservative hierarchies miss nothing, a
// method that drops known contacts is charged exactly what it dropped, and `fast`'s misses are
// recounted independently.

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <set>
#include <sstream>

#include "culling/method.hpp"
#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tools/report/bench_report.hpp"

namespace {

using namespace skelcd;
using namespace skelcd::tools;

constexpr const char* kRope = "gen:rope?triangles=1000&frames=60";  // free 0–44, intersecting 45–59

FindingKey key(std::int32_t sample, std::int32_t query, std::int32_t a, std::int32_t b) {
  return FindingKey{sample, query, 0, 0, a, -1, 0, b, -1};
}

TEST(BenchReport, CompareFindingsCountsBothSetDifferences) {
  // reference {1, 2, 3, 5}, run {2, 3, 4, 6, 7}: FN {1, 5}, FP {4, 6, 7}.
  std::vector<FindingKey> reference{
      key(0, 0, 0, 1), key(0, 0, 0, 2), key(0, 1, 0, 3), key(2, 0, 4, 5)};
  std::vector<FindingKey> run{
      key(0, 0, 0, 2), key(0, 1, 0, 3), key(1, 0, 0, 4), key(3, 0, 0, 6), key(3, 1, 0, 7)};
  std::sort(reference.begin(), reference.end());
  std::sort(run.begin(), run.end());
  const auto d = compare_findings(reference, run);
  EXPECT_EQ(d.false_negatives, 2);
  EXPECT_EQ(d.false_positives, 3);
  EXPECT_EQ(compare_findings(reference, reference).false_negatives, 0);
  EXPECT_EQ(compare_findings(reference, {}).false_negatives, 4);
  EXPECT_EQ(compare_findings({}, run).false_positives, 5);
  // The same pair at another sample, or as a CCD contact instead of a DCD pair, is another finding.
  const std::vector<FindingKey> one{key(0, 0, 0, 1)};
  const std::vector<FindingKey> other_sample{key(1, 0, 0, 1)};
  const std::vector<FindingKey> other_query{key(0, 1, 0, 1)};
  EXPECT_EQ(compare_findings(one, other_sample).false_negatives, 1);
  EXPECT_EQ(compare_findings(one, other_query).false_positives, 1);
}

TEST(BenchReport, ReferenceIsBruteOnlyWithinTheBudget) {
  EXPECT_DOUBLE_EQ(brute_cost(1000, 21), 21e6);
  EXPECT_EQ(pick_reference(ReferenceChoice::automatic, 1000, 21, 21e6).method, "brute");
  EXPECT_EQ(pick_reference(ReferenceChoice::automatic, 1000, 22, 21e6).method, "bvh");
  EXPECT_EQ(pick_reference(ReferenceChoice::brute, 100000, 1000, 1).method, "brute");
  EXPECT_EQ(pick_reference(ReferenceChoice::bvh, 10, 1, 1e9).method, "bvh");
  EXPECT_EQ(parse_reference_choice("auto"), ReferenceChoice::automatic);
  EXPECT_FALSE(parse_reference_choice("exact").has_value());
}

TEST(BenchReport, UnknownMethodsAreRefusedBeforeAnyWork) {
  const std::vector<std::string> bad{"bvh", "octree"};
  EXPECT_THROW_MESSAGE(validate_methods(bad, true), InvalidInput, "'octree'");
  const std::vector<std::string> rv{"dynamic"};
  EXPECT_THROW_MESSAGE(validate_methods(rv, false), InvalidInput, "rigged");
  EXPECT_NO_THROW(validate_methods(rv, true));
}

/// The rows of `report` by (method, accuracy).
const BenchRow& row_of(const BenchReport& report, const std::string& method, ccd::Accuracy a) {
  const auto it = std::find_if(report.rows.begin(), report.rows.end(), [&](const BenchRow& r) {
    return r.method == method && r.accuracy == a;
  });
  if (it == report.rows.end()) throw std::runtime_error("no row " + method);
  return *it;
}

/// Samples 44–47 of the rope: DCD answers known from the generator (free up to 44, intersecting
/// from 45), and CCD contacts where the end comes down onto the start.
BenchOptions rope_options() {
  BenchOptions o;
  o.run.frames = FrameRange{44, 47};
  o.methods = {"brute", "bvh", "kdop"};
  o.accuracies = {ccd::Accuracy::exact, ccd::Accuracy::conservative};
  return o;
}

TEST(BenchReport, RopeReferenceAgreesWithTheKnownAnswerAndHierarchiesMissNothing) {
  const auto model = skinning::load_model(kRope);
  const auto motion = model.motion();
  const auto generated = skinning::generate(skinning::parse_generator_spec(kRope));
  const auto report = run_bench(*motion, rope_options());

  EXPECT_EQ(report.reference.method, "brute");  // 1k triangles × 7 rows fits the budget
  EXPECT_EQ(report.plan.first_sample, 44);
  EXPECT_EQ(report.plan.last_sample, 47);
  EXPECT_EQ(report.plan.intervals, 3);
  ASSERT_EQ(report.rows.size(), 6u);
  const auto& reference = row_of(report, "brute", ccd::Accuracy::exact);
  EXPECT_TRUE(reference.reference);
  EXPECT_EQ(reference.false_negatives, 0);
  EXPECT_EQ(reference.false_positives, 0);
  EXPECT_EQ(reference.contacts, report.reference_contacts);
  // The reference's DCD samples: pairs exactly at the generator's intersecting samples 45–47.
  const std::int64_t intersecting = 47 - generated.answer.first_intersecting_frame + 1;
  ASSERT_EQ(generated.answer.first_intersecting_frame, 45);
  EXPECT_GE(reference.summary.dcd_pairs, intersecting);  // at least one pair per such sample
  EXPECT_EQ(reference.summary.frames_with_interpenetration, intersecting);
  EXPECT_GT(reference.summary.ccd_vf + reference.summary.ccd_ee, 0);

  for (const auto& r : report.rows) {
    SCOPED_TRACE(r.method + "/" + std::string(ccd::to_string(r.accuracy)));
    EXPECT_EQ(r.false_negatives, 0);
    if (r.accuracy == ccd::Accuracy::exact) {
      EXPECT_EQ(r.false_positives, 0);
    }
    // Contacts = reference − FN + FP.
    EXPECT_EQ(r.contacts, report.reference_contacts - r.false_negatives + r.false_positives);
    EXPECT_GT(r.summary.ms_per_interval, 0.0);
    EXPECT_GT(r.elementary_tests, 0);
  }
  // The hierarchies test fewer bounding volumes than brute force.
  EXPECT_LT(
      row_of(report, "bvh", ccd::Accuracy::exact).summary.bv_tests, reference.summary.bv_tests);
}

/// A method that loses the first finding of every query that has one: the DCD pair at a sample,
/// else the first CCD contact of an interval; counts what it dropped.
class DroppingMethod final : public culling::CullingMethod {
 public:
  DroppingMethod(
      std::unique_ptr<culling::CullingMethod> inner, std::shared_ptr<std::int64_t> dropped)
      : inner_(std::move(inner)), dropped_(std::move(dropped)) {}
  std::string_view name() const override { return "dropping-bvh"; }
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    const skinning::Positions& x = at.x;
    inner_->detect_dcd(x, out);
    if (!out.dcd_pairs.empty()) {
      out.dcd_pairs.erase(out.dcd_pairs.begin());
      ++*dropped_;
    }
  }
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    inner_->detect_ccd(x_t0, x_t1, out);
    if (!out.contacts.empty()) {
      out.contacts.erase(out.contacts.begin());
      ++*dropped_;
    }
  }

 private:
  std::unique_ptr<culling::CullingMethod> inner_;
  std::shared_ptr<std::int64_t> dropped_;
};

TEST(BenchReport, DroppedContactsAreCountedExactlyAsFalseNegatives) {
  const auto model = skinning::load_model(kRope);
  const auto motion = model.motion();
  auto dropped = std::make_shared<std::int64_t>(0);
  BenchOptions o = rope_options();
  o.methods = {"bvh"};
  o.accuracies = {ccd::Accuracy::exact, ccd::Accuracy::conservative};
  o.factory = [dropped](const std::string& method, ccd::Accuracy accuracy) -> MethodFactory {
    if (method != "bvh" || accuracy != ccd::Accuracy::conservative) return {};
    return [dropped](
               const skinning::Mesh& mesh,
               const skinning::Topology& topology,
               const culling::MethodOptions& options) {
      return std::make_unique<DroppingMethod>(
          culling::make_method("bvh", mesh, topology, options), dropped);
    };
  };
  const auto report = run_bench(*motion, o);
  EXPECT_EQ(report.reference.method, "brute");
  // 3 intersecting samples lose a pair each, and every interval with contacts loses one.
  EXPECT_GE(*dropped, 3);
  const auto& weakened = row_of(report, "bvh", ccd::Accuracy::conservative);
  EXPECT_EQ(weakened.false_negatives, *dropped);
  const auto& intact = row_of(report, "bvh", ccd::Accuracy::exact);
  EXPECT_EQ(intact.false_negatives, 0);
  EXPECT_EQ(intact.false_positives, 0);
  // The weakened run's other findings are the conservative bvh's: it adds no false positive that
  // the unweakened conservative run would not (those are only possible conservative extras).
  EXPECT_EQ(weakened.contacts + *dropped - weakened.false_positives, report.reference_contacts);
}

/// Findings of one plain ClipRunner run as an ordered set of tuples — a second, independent way to
/// build the sets the report compares.
std::set<std::vector<std::int32_t>> run_findings(const skinning::Motion& motion, RunOptions o) {
  std::set<std::vector<std::int32_t>> out;
  ClipRunner runner(motion, o);
  runner.run([&](const FrameReport& r) {
    for (const auto& p : r.dcd_pairs) {
      out.insert({p.frame, 0, p.a.part, p.a.index, p.b.part, p.b.index});
    }
    for (const auto& c : r.contacts) {
      out.insert(
          {c.frame,
           1 + static_cast<std::int32_t>(c.kind),
           c.a.part,
           c.a.index,
           c.a.side,
           c.b.part,
           c.b.index,
           c.b.side});
    }
  });
  return out;
}

TEST(BenchReport, FastMissesAreThoseAnIndependentComparisonFinds) {
  const auto model = skinning::load_model(kRope);
  const auto motion = model.motion();
  BenchOptions o = rope_options();
  o.run.frames = FrameRange{50, 53};  // deep in the loop, where plain doubles lose contacts
  o.methods = {"bvh"};
  o.accuracies = {ccd::Accuracy::fast};
  o.reference = ReferenceChoice::brute;
  const auto report = run_bench(*motion, o);
  ASSERT_EQ(report.rows.size(), 1u);

  RunOptions r = o.run;
  r.method = "brute";
  r.accuracy = ccd::Accuracy::exact;
  const auto reference = run_findings(*motion, r);
  r.method = "bvh";
  r.accuracy = ccd::Accuracy::fast;
  const auto fast = run_findings(*motion, r);
  std::int64_t missed = 0;
  for (const auto& f : reference) missed += fast.count(f) == 0 ? 1 : 0;
  std::int64_t extra = 0;
  for (const auto& f : fast) extra += reference.count(f) == 0 ? 1 : 0;
  EXPECT_EQ(report.reference_contacts, static_cast<std::int64_t>(reference.size()));
  EXPECT_GT(missed, 0);  // fast does miss here: the comparison has something to count
  EXPECT_EQ(report.rows[0].false_negatives, missed);
  EXPECT_EQ(report.rows[0].false_positives, extra);
}

TEST(BenchReport, RealCharacterExactAndConservativeHierarchiesMissNothing) {
  // CesiumMan: 4,672 triangles; samples 0–2 (3 DCD samples, 2 intervals).
  const auto model = skinning::load_model(skelcd::test::asset("characters/CesiumMan.glb"));
  const auto motion = model.motion();
  BenchOptions o;
  o.run.frames = FrameRange{0, 2};
  o.methods = {"brute", "bvh", "kdop"};
  o.accuracies = {ccd::Accuracy::exact, ccd::Accuracy::conservative};
  const auto report = run_bench(*motion, o);
  EXPECT_EQ(report.reference.method, "brute");
  ASSERT_EQ(report.rows.size(), 6u);
  EXPECT_TRUE(report.rows[0].reference);
  EXPECT_GT(report.reference_contacts, 0);
  for (const auto& r : report.rows) {
    SCOPED_TRACE(r.method + "/" + std::string(ccd::to_string(r.accuracy)));
    EXPECT_EQ(r.false_negatives, 0);
    if (r.accuracy == ccd::Accuracy::exact) {
      EXPECT_EQ(r.false_positives, 0);
    }
  }

  // The table names every row and marks the reference.
  std::ostringstream table;
  print_bench_table(table, report);
  EXPECT_NE(table.str().find("* brute"), std::string::npos) << table.str();
  EXPECT_NE(table.str().find("kdop"), std::string::npos);
  // CSV: header + one line per row.
  const auto csv = bench_csv(report);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 7);
  EXPECT_EQ(bench_json(report)["rows"].size(), 6u);
}

TEST(BenchReport, BruteLeftOutOfTheDefaultListWhenOverBudget) {
  const auto model = skinning::load_model(kRope);
  const auto motion = model.motion();
  BenchOptions o;
  o.run.frames = FrameRange{44, 45};
  o.run.query = QuerySet::dcd;
  o.accuracies = {ccd::Accuracy::conservative};
  o.brute_budget = 1;  // nothing fits: bvh is the reference, brute is not run
  const auto report = run_bench(*motion, o);
  EXPECT_EQ(report.reference.method, "bvh");
  ASSERT_EQ(report.notes.size(), 1u);
  for (const auto& r : report.rows) EXPECT_NE(r.method, "brute");
  // Every registered method but brute, and but those that need a rig's bones (not this motion's).
  std::size_t expected = 0;
  for (const auto& m : culling::method_names()) {
    if (m != "brute" && !culling::method_needs(m).bone_poses) ++expected;
  }
  EXPECT_EQ(report.rows.size(), expected);
}

TEST(BenchReport, PendingOutputAppearsWholeOrNotAtAll) {
  const auto dir = skelcd::test::temp_dir("bench-pending");
  const auto path = dir / "out.csv";
  {
    PendingOutput out(path);
    out.write("a,b\n");
    EXPECT_FALSE(std::filesystem::exists(path));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));  // dropped uncommitted: nothing left
  {
    PendingOutput out(path);
    out.write("a,b\n1,2\n");
    out.commit();
  }
  EXPECT_EQ(std::filesystem::file_size(path), 8u);
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_THROW(PendingOutput{dir / "missing" / "out.csv"}, IoError);
  EXPECT_THROW(PendingOutput{dir}, IoError);  // a directory
}

}  // namespace
