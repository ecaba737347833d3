// skelcd ccd-queries as a user meets it: the file format (decimals, exact p/q, comments, expected
// results), stdin, results file, JSON summary, one-line errors naming the line, and the
// cloth-funnel ground truth run through the real binary.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ccd/vertex_face.hpp"
#include "tests/ccd/cloth_funnel.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/ccd_query_file.hpp"

namespace {

using skelcd::test::run_skelcd;

// Vertex falling through the unit triangle at t = 1/2 (hit), and beside it (miss).
constexpr const char* kHit =
    "vf 0.25 0.25 1  0 0 0  1 0 0  0 1 0  0.25 0.25 -1  0 0 0  1 0 0  0 1 0";
constexpr const char* kMiss =
    "vf 2 2 1  0 0 0  1 0 0  0 1 0  2 2 -1  0 0 0  1 0 0  0 1 0";
// Edge a sweeping down through edge b (hit at t = 1/2), written with rationals.
constexpr const char* kEdgeHit =
    "ee 0/1 -1/1 1/2 0 1 1/2 -1/2 0 0 1/2 0 0   0 -1 -1/2 0 1 -1/2 -1/2 0 0 1/2 0 0";

std::string write_file(const std::string& name, const std::string& text) {
  const auto dir = skelcd::test::temp_dir("ccd-queries");
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(CcdQueriesFile, ParsesNumbersExactlyAndToTheNearestDouble) {
  double v = 0;
  double rounding = -1;
  mpq_class q;
  std::string fault;
  using skelcd::tools::parse_ccd_number;
  ASSERT_TRUE(parse_ccd_number("0.1", v, &q, rounding, fault));
  EXPECT_EQ(v, 0.1);
  EXPECT_EQ(q, mpq_class(1, 10));
  EXPECT_GT(rounding, 0.0);
  EXPECT_GE(mpq_class(rounding), abs(mpq_class(v) - q));  // the bound holds
  ASSERT_TRUE(parse_ccd_number("-2.5e-3", v, &q, rounding, fault));
  EXPECT_EQ(v, -0.0025);
  EXPECT_EQ(q, mpq_class(-1, 400));
  ASSERT_TRUE(parse_ccd_number("+7/3", v, &q, rounding, fault));
  EXPECT_EQ(v, 7.0 / 3.0);
  EXPECT_EQ(q, mpq_class(7, 3));
  EXPECT_GE(mpq_class(rounding), abs(mpq_class(v) - q));
  // Numbers that are doubles have no rounding.
  for (const char* exact : {"0.5", "-0.375", "1e3", "12.5e-1", "3589935/67108864", "-12695021/2147483648", "0", "7"}) {
    ASSERT_TRUE(parse_ccd_number(exact, v, &q, rounding, fault)) << exact;
    EXPECT_EQ(rounding, 0.0) << exact;
    EXPECT_EQ(mpq_class(v), q) << exact;
  }
  // A big rational, rounded to nearest: (2^60 + 1) / 2^60 is 1 + 2^-60, nearest double 1.
  ASSERT_TRUE(parse_ccd_number("1152921504606846977/1152921504606846976", v, &q, rounding, fault));
  EXPECT_EQ(v, 1.0);
  EXPECT_GT(q, 1);
  EXPECT_GE(mpq_class(rounding), abs(mpq_class(v) - q));
  for (const char* bad : {"", "1/0", "abc", "1e", "--1", "1.2.3", "0x10", "inf", "nan", "1e400", "1/-2", "3/"}) {
    EXPECT_FALSE(parse_ccd_number(bad, v, &q, rounding, fault)) << bad;
    EXPECT_FALSE(fault.empty()) << bad;
  }
}

TEST(CcdQueries, CountsHitsAndFalseResults) {
  std::ostringstream text;
  text << "# a comment line\n\n"
       << kHit << " 1\n"
       << kMiss << " 1   # expected wrongly: a false negative for every accuracy\n"
       << kEdgeHit << " 0\n"  // expected wrongly: a false positive
       << kMiss << "\n";      // no expected result
  const auto path = write_file("counts.txt", text.str());
  for (const char* accuracy : {"exact", "conservative", "fast"}) {
    const auto r = run_skelcd({"ccd-queries", path, "--accuracy", accuracy, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["accuracy"], accuracy);
    EXPECT_EQ(j["queries"], 4);
    EXPECT_EQ(j["vertex_face"], 3);
    EXPECT_EQ(j["edge_edge"], 1);
    EXPECT_EQ(j["hits"], 2);
    EXPECT_EQ(j["with_expected"], 3);
    EXPECT_EQ(j["false_negatives"], 1);
    EXPECT_EQ(j["false_positives"], 1);
    EXPECT_GE(j["ns_per_query"].get<double>(), 0.0);
  }
}

TEST(CcdQueries, ReadsStandardInputAndWritesResults) {
  const auto dir = skelcd::test::temp_dir("ccd-queries-results");
  const auto out = (dir / "results.txt").string();
  const auto r = run_skelcd({"ccd-queries", "-", "-o", out}, std::string(kHit) + "\n" + kMiss + "\n");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 queries"), std::string::npos) << r.out;
  std::ifstream in(out);
  std::string header, line1, line2;
  std::getline(in, header);
  std::getline(in, line1);
  std::getline(in, line2);
  EXPECT_EQ(header.rfind("#", 0), 0u);
  std::istringstream l1(line1);
  int hit = -1;
  double lo = -1, hi = -1;
  l1 >> hit >> lo >> hi;
  EXPECT_EQ(hit, 1);
  EXPECT_LE(lo, 0.5);
  EXPECT_GE(hi, 0.5 - 1e-6);
  EXPECT_EQ(line2.substr(0, 2), "0 ");
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

TEST(CcdQueries, ExactReadsDecimalsAsWritten) {
  // The edge from (0.1, -1) to (0.5, 1) crosses y = 0 at exactly x = 3/10, where the vertex falls
  // through: a contact in the decimals as written. In doubles, 0.3 lies ~3e-18 outside that edge.
  const std::string q = "vf 0.3 0 1  0.1 -1 0  0.5 1 0  2 0 0  0.3 0 -1  0.1 -1 0  0.5 1 0  2 0 0 1\n";
  const auto r = run_skelcd({"ccd-queries", "-", "--accuracy", "exact", "--json"}, q);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["hits"], 1);
  // The same query on its doubles, through the library: no contact.
  using V = Eigen::Vector3d;
  const skelcd::ccd::VertexFaceQuery d{V(0.3, 0, 1), V(0.1, -1, 0), V(0.5, 1, 0), V(2, 0, 0),
                                       V(0.3, 0, -1), V(0.1, -1, 0), V(0.5, 1, 0), V(2, 0, 0)};
  EXPECT_FALSE(skelcd::ccd::vertex_face_ccd(d, skelcd::ccd::Accuracy::exact).hit);
}

TEST(CcdQueries, ConservativeCoversTheRoundingOfTheInput) {
  // As written, the vertex falls through the point (3000000.3, 0) of the edge from
  // (3000000.1, -1) to (3000000.5, 1): a contact. Rounded to doubles (ulp 2^-31 near 3e6) the vertex
  // passes 2.3e-10 outside that edge — a miss the doubles alone prove. Conservative must still
  // answer "hit" for the numbers as written: it widens the query by their rounding.
  const std::string q =
      "vf 3000000.3 0 1  3000000.1 -1 0  3000000.5 1 0  3000002 0 0  "
      "3000000.3 0 -1  3000000.1 -1 0  3000000.5 1 0  3000002 0 0  1\n";
  for (const char* accuracy : {"exact", "conservative"}) {
    const auto r = run_skelcd({"ccd-queries", "-", "--accuracy", accuracy, "--json"}, q);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["false_negatives"], 0) << accuracy;
  }
  using V = Eigen::Vector3d;
  const skelcd::ccd::VertexFaceQuery d{V(3000000.3, 0, 1), V(3000000.1, -1, 0), V(3000000.5, 1, 0), V(3000002, 0, 0),
                                       V(3000000.3, 0, -1), V(3000000.1, -1, 0), V(3000000.5, 1, 0), V(3000002, 0, 0)};
  EXPECT_FALSE(skelcd::ccd::vertex_face_ccd(d, skelcd::ccd::Accuracy::exact).hit);
  EXPECT_FALSE(skelcd::ccd::vertex_face_ccd(d, skelcd::ccd::Accuracy::conservative).hit)
      << "the doubles alone are a provable miss: without the widening this would be a false negative";
}

TEST(CcdQueries, MalformedLinesAreOneLineErrorsNamingTheLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"xx 0 0 0", ":3: expected 'vf' or 'ee'"},
      {"vf 1 2 3", ":3: expected 24 coordinates"},
      {std::string(kHit) + " 2", ":3: expected result must be 0 or 1"},
      {"vf 0.25 0.25 1 0 0 0 1 0 0 0 1 0 0.25 0.25 -1 0 0 0 1 0 0 0 1 zero",
       ":3: coordinate 24 'zero'"},
      {"ee 1/0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0",
       ":3: coordinate 1 '1/0': zero denominator"},
      // Nonzero but below the smallest subnormal, as a decimal and as a big rational.
      {"ee 1e-400 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0",
       ":3: coordinate 1 '1e-400': beyond the range of a double"},
      {"ee 1/1" + std::string(400, '0') + " 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0",
       ":3: coordinate 1 '1/100"},  // the quote is cut at 40 characters
      {"ee 1/1" + std::string(400, '0') + " 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0",
       "beyond the range of a double (nonzero, below the smallest subnormal)"},
  };
  for (const auto& [bad_line, message] : cases) {
    const auto path = write_file("bad.txt", std::string("# header\n") + kHit + "\n" + bad_line + "\n" + kMiss + "\n");
    const auto r = run_skelcd({"ccd-queries", path, "-o", path + ".out"});
    EXPECT_EQ(r.exit_code, 1) << bad_line;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("bad.txt"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(path + ".out")) << "nothing half-written";
  }
  const auto missing = run_skelcd({"ccd-queries", "/no/such/file.txt"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("/no/such/file.txt"), std::string::npos);
  const auto accuracy = run_skelcd({"ccd-queries", "-", "--accuracy", "precise"}, kHit);
  EXPECT_NE(accuracy.exit_code, 0);
}

TEST(CcdQueries, ClothFunnelGroundTruth) {
  auto queries = skelcd::ccd::test::load_cloth_funnel("vf");
  const auto ee = skelcd::ccd::test::load_cloth_funnel("ee");
  queries.insert(queries.end(), ee.begin(), ee.end());
  const auto path = write_file("cloth-funnel.txt", skelcd::ccd::test::to_query_file(queries));
  for (const char* accuracy : {"exact", "conservative"}) {
    const auto r = run_skelcd({"ccd-queries", path, "--accuracy", accuracy, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["queries"], 355);
    EXPECT_EQ(j["with_expected"], 355);
    EXPECT_EQ(j["expected_hits"], 134);
    EXPECT_EQ(j["false_negatives"], 0) << accuracy;
    if (std::string(accuracy) == "exact") {
      EXPECT_EQ(j["false_positives"], 0);
      EXPECT_EQ(j["hits"], 134);
    }
  }
}

}  // namespace
