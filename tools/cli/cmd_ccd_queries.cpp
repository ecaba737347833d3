// skelcd ccd-queries FILE [--accuracy A] [-o RESULTS] [--json]: elementary CCD on a file of queries
// (format: docs/ccd-queries.md), with false negatives / positives against the expected results the
// file gives, and the time per query.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "ccd/accuracy.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/vertex_face.hpp"
#include "skinning/errors.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/io/ccd_query_file.hpp"

namespace skelcd::tools {
namespace {

struct CcdQueriesArgs {
  std::string input;
  std::string accuracy = "conservative";
  std::string output;
  bool json = false;
};

Eigen::Vector3d point(const CcdQueryRecord& r, int i) {
  const auto k = static_cast<std::size_t>(3 * i);
  return {r.coordinates[k], r.coordinates[k + 1], r.coordinates[k + 2]};
}

ccd::RationalPoint rational_point(const CcdQueryRecord& r, int i) {
  const auto k = static_cast<std::size_t>(3 * i);
  return {r.exact[k], r.exact[k + 1], r.exact[k + 2]};
}

ccd::CcdResult run_one(const CcdQueryRecord& r, ccd::Accuracy accuracy, ccd::CcdStats& stats) {
  if (accuracy == ccd::Accuracy::exact) {
    // The exact values as written (0.1 is 1/10), not their doubles.
    ccd::CcdResult result;
    if (r.vertex_face) {
      const ccd::RationalVertexFaceQuery q{
          rational_point(r, 0),
          rational_point(r, 1),
          rational_point(r, 2),
          rational_point(r, 3),
          rational_point(r, 4),
          rational_point(r, 5),
          rational_point(r, 6),
          rational_point(r, 7)};
      result = ccd::vertex_face_ccd_exact(q);
    } else {
      const ccd::RationalEdgeEdgeQuery q{
          rational_point(r, 0),
          rational_point(r, 1),
          rational_point(r, 2),
          rational_point(r, 3),
          rational_point(r, 4),
          rational_point(r, 5),
          rational_point(r, 6),
          rational_point(r, 7)};
      result = ccd::edge_edge_ccd_exact(q);
    }
    ++stats.queries;
    if (result.hit) ++stats.hits;
    return result;
  }
  // The doubles nearest to the written numbers. For `conservative`, a query whose numbers are not
  // all exactly doubles is widened by its rounding: every coordinate moved by at most `rounding`,
  // so every point of both primitives by at most sqrt(3) rounding at every time, and a contact of
  // the written query is within 2 sqrt(3) rounding <= 4 rounding in the doubles
  // (docs/ccd-queries.md).
  ccd::CcdOptions options;
  if (accuracy == ccd::Accuracy::conservative) options.min_separation = 4 * r.rounding;
  if (r.vertex_face) {
    const ccd::VertexFaceQuery q{
        point(r, 0),
        point(r, 1),
        point(r, 2),
        point(r, 3),
        point(r, 4),
        point(r, 5),
        point(r, 6),
        point(r, 7)};
    return ccd::vertex_face_ccd(q, accuracy, options, stats);
  }
  const ccd::EdgeEdgeQuery q{
      point(r, 0),
      point(r, 1),
      point(r, 2),
      point(r, 3),
      point(r, 4),
      point(r, 5),
      point(r, 6),
      point(r, 7)};
  return ccd::edge_edge_ccd(q, accuracy, options, stats);
}

// Writes the results next to `path` first and renames, so a failure leaves no half-written file.
void write_results(
    const std::string& path, const std::vector<ccd::CcdResult>& results, ccd::Accuracy accuracy) {
  const std::filesystem::path target(path);
  const std::filesystem::path temp = target.string() + ".partial";
  {
    std::FILE* f = std::fopen(temp.c_str(), "w");
    if (f == nullptr) throw IoError(path + ": cannot write results");
    std::fprintf(
        f,
        "# skelcd ccd-queries, accuracy %s: hit toi_lower toi_upper (one line per query)\n",
        std::string(ccd::to_string(accuracy)).c_str());
    for (const auto& r : results)
      std::fprintf(f, "%d %.17g %.17g\n", r.hit ? 1 : 0, r.toi_lower, r.toi_upper);
    const bool ok = std::ferror(f) == 0;
    if (std::fclose(f) != 0 || !ok) {
      std::filesystem::remove(temp);
      throw IoError(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    std::filesystem::remove(temp);
    throw IoError(path + ": cannot write results (" + ec.message() + ")");
  }
}

void run_ccd_queries(const CcdQueriesArgs& args) {
  const auto accuracy = ccd::parse_accuracy(args.accuracy);
  if (!accuracy) {
    throw InvalidInput(
        "--accuracy: expected exact, conservative or fast, got '" + args.accuracy + "'");
  }
  const auto records = read_ccd_queries(args.input, *accuracy == ccd::Accuracy::exact);

  std::vector<ccd::CcdResult> results(records.size());
  ccd::CcdStats stats;
  Progress progress("ccd-queries", static_cast<std::int64_t>(records.size()));
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < records.size(); ++i) {
    results[i] = run_one(records[i], *accuracy, stats);
    if ((i & 1023) == 0) progress.update(static_cast<std::int64_t>(i));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.finish();

  std::int64_t vf = 0, with_expected = 0, expected_hits = 0, false_negatives = 0,
               false_positives = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (records[i].vertex_face) ++vf;
    if (!records[i].expected) continue;
    ++with_expected;
    if (*records[i].expected) ++expected_hits;
    if (*records[i].expected && !results[i].hit) ++false_negatives;
    if (!*records[i].expected && results[i].hit) ++false_positives;
  }
  if (!args.output.empty()) write_results(args.output, results, *accuracy);

  const auto n = static_cast<std::int64_t>(records.size());
  const double ns_per_query = n > 0 ? seconds * 1e9 / static_cast<double>(n) : 0.0;
  if (args.json) {
    nlohmann::json j = {
        {"input", args.input},
        {"accuracy", std::string(ccd::to_string(*accuracy))},
        {"queries", n},
        {"vertex_face", vf},
        {"edge_edge", n - vf},
        {"hits", stats.hits},
        {"with_expected", with_expected},
        {"expected_hits", expected_hits},
        {"false_negatives", false_negatives},
        {"false_positives", false_positives},
        {"ns_per_query", ns_per_query},
        {"seconds", seconds},
    };
    if (*accuracy == ccd::Accuracy::conservative) {
      j["stages"] = {
          {"aabb_rejected", stats.aabb_rejected},
          {"coplanarity_rejected", stats.coplanarity_rejected},
          {"algebraic_rejected", stats.algebraic_rejected},
          {"algebraic_hits", stats.algebraic_hits},
          {"solver_runs", stats.solver_runs},
          {"solver_rejected", stats.solver_rejected},
          {"solver_boxes", stats.solver_boxes},
          {"iteration_limit", stats.iteration_limit}};
    }
    print_json(j);
    return;
  }
  std::cout << n << " queries (" << vf << " vertex-face, " << n - vf << " edge-edge), accuracy "
            << ccd::to_string(*accuracy) << ": " << stats.hits << " hits, " << ns_per_query
            << " ns/query\n";
  if (with_expected > 0) {
    std::cout << with_expected << " with expected results (" << expected_hits
              << " hits): " << false_negatives << " false negatives, " << false_positives
              << " false positives\n";
  }
}

}  // namespace

void add_ccd_queries_command(CLI::App& app) {
  auto args = std::make_shared<CcdQueriesArgs>();
  auto* cmd = app.add_subcommand(
      "ccd-queries", "elementary CCD on a file of queries (format in docs/ccd-queries.md)");
  cmd->add_option("file", args->input, "query file, or - for standard input")->required();
  cmd->add_option("--accuracy", args->accuracy, "exact | conservative | fast")
      ->default_val("conservative")
      ->check(CLI::IsMember({"exact", "conservative", "fast"}));
  cmd->add_option("-o,--output", args->output, "write one line per query: hit toi_lower toi_upper");
  cmd->add_flag("--json", args->json, "print one JSON object instead of the summary");
  cmd->callback([args] { run_ccd_queries(*args); });
}

}  // namespace skelcd::tools
