// skelcd check MODEL — the main job: self-collision over a clip, sample by sample (DCD) and
// interval by interval (CCD); prints a summary and writes the HDF5 log row by row (docs/check.md).

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "culling/routed_method.hpp"
#include "skelcd_version.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tools/cli_util.hpp"
#include "tools/commands.hpp"
#include "tools/file_hash.hpp"
#include "tools/radial_view_setup.hpp"
#include "tools/log/log_writer.hpp"
#include "tools/run_summary.hpp"
#include "tools/runner.hpp"

namespace skelcd::tools {
namespace {

struct CheckArguments {
  std::string model;
  std::string clip;
  double fps = 0;
  std::string frames;
  std::string method = "bvh";
  std::string accuracy = "conservative";
  std::string query = "both";
  double min_separation = 0;
  std::string output;
  bool json = false;
  RadialViewArguments radial_view;
};

/// The process's own command line (from /proc), arguments quoted when they need it.
std::string command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string line;
  std::size_t start = 0;
  while (start < raw.size()) {
    auto end = raw.find('\0', start);
    if (end == std::string::npos) end = raw.size();
    std::string arg = raw.substr(start, end - start);
    if (start == 0) arg = std::filesystem::path(arg).filename().string();
    const bool quote = arg.empty() || arg.find_first_of(" \t\"'\\$") != std::string::npos;
    if (!line.empty()) line += ' ';
    if (quote) {
      line += '\'';
      for (const char c : arg) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
      line += '\'';
    } else {
      line += arg;
    }
    start = end + 1;
  }
  return line;
}

/// Samples per second of the motion: the rig's own rate, else estimated from sample times.
double motion_rate(const skinning::Motion& motion, double requested) {
  if (const auto* rig = dynamic_cast<const skinning::RigMotion*>(&motion)) return rig->rate_hz();
  if (requested > 0) return requested;
  const int n = motion.num_samples();
  if (n < 2) return 0;
  const double span = motion.sample_time(n - 1) - motion.sample_time(0);
  return span > 0 ? (n - 1) / span : 0;
}

RunOptions to_run_options(const CheckArguments& a) {
  RunOptions o;
  o.clip = a.clip;
  if (!(std::isfinite(a.fps) && a.fps >= 0)) {
    throw InvalidInput("--fps " + std::to_string(a.fps) + ": expected a rate > 0 (samples/s)");
  }
  o.fps = a.fps;
  if (!a.frames.empty()) o.frames = parse_frame_range(a.frames);
  o.method = a.method;
  const auto accuracy = ccd::parse_accuracy(a.accuracy);
  if (!accuracy) {
    throw InvalidInput("--accuracy '" + a.accuracy + "': expected exact, conservative or fast");
  }
  o.accuracy = *accuracy;
  const auto query = parse_query_set(a.query);
  if (!query) throw InvalidInput("--query '" + a.query + "': expected ccd, dcd or both");
  o.query = *query;
  if (!(std::isfinite(a.min_separation) && a.min_separation >= 0)) {
    throw InvalidInput("--min-separation: expected a distance >= 0");
  }
  o.min_separation = a.min_separation;
  return o;
}

std::string describe(const FrameRow& row) {
  std::ostringstream s;
  char time[32];
  if (row.kind == QueryKind::dcd) {
    std::snprintf(time, sizeof time, "%.3f", row.t0);
    s << "sample " << row.sample << " (t = " << time << " s): " << row.counters.dcd_pairs
      << " intersecting triangle pairs";
  } else {
    std::snprintf(time, sizeof time, "%.3f", row.t0);
    s << "interval " << row.sample << "-" << row.sample + 1 << " (t = " << time
      << " s): " << row.counters.vf_contacts << " VF + " << row.counters.ee_contacts
      << " EE contacts";
  }
  return s.str();
}

void print_text_summary(const skinning::LoadedModel& model, const skinning::Motion& motion,
                        const RunOptions& options, const RunPlan& plan, double fps,
                        const RunSummary& s, const std::string& log_path) {
  const auto& mesh = motion.mesh();
  char line[256];
  std::cout << "model     " << model.path.string() << " (" << mesh.num_parts() << " parts, "
            << mesh.num_vertices() << " vertices, " << mesh.num_triangles() << " triangles)\n";
  std::snprintf(line, sizeof line, "%.6g", fps);
  std::cout << "clip      " << motion.name() << ": samples " << plan.first_sample << ".."
            << plan.last_sample << " at " << line << " Hz\n";
  std::cout << "method    " << options.method << ", accuracy " << ccd::to_string(options.accuracy)
            << ", query " << to_string(options.query) << "\n";
  std::cout << "frames    " << s.samples << " samples, " << s.intervals << " intervals\n";
  if (options.query != QuerySet::ccd) {
    std::cout << "DCD       " << s.frames_with_interpenetration << " of " << s.samples
              << " samples interpenetrate; " << s.dcd_pairs << " intersecting triangle pairs\n";
  }
  if (options.query != QuerySet::dcd) {
    std::cout << "CCD       " << s.intervals_with_contacts << " of " << s.intervals
              << " intervals have contacts; " << s.ccd_vf << " VF + " << s.ccd_ee
              << " EE contacts\n";
  }
  if (!s.worst.empty()) {
    std::cout << "worst\n";
    for (const auto& row : s.worst) std::cout << "  " << describe(row) << '\n';
  }
  std::snprintf(line, sizeof line,
                "time      %.3f ms per %s (skin %.3f, refit %.3f, classify %.3f, merge %.3f, "
                "traverse %.3f, elementary %.3f, other %.3f)\n",
                s.ms_per_interval, s.intervals > 0 ? "interval" : "sample", s.skin_ms, s.refit_ms,
                s.classify_ms, s.merge_ms, s.traverse_ms, s.elementary_ms, s.other_ms);
  std::cout << line;
  if (!log_path.empty()) std::cout << "log       " << log_path << '\n';
}

nlohmann::json json_summary(const skinning::LoadedModel& model, const skinning::Motion& motion,
                            const RunOptions& options, const RunPlan& plan, double fps,
                            const RunSummary& s, const std::string& log_path) {
  auto worst = nlohmann::json::array();
  for (const auto& row : s.worst) {
    worst.push_back({{"sample", row.sample},
                     {"kind", std::string(to_string(row.kind))},
                     {"t0", row.t0},
                     {"t1", row.t1},
                     {"dcd_pairs", row.counters.dcd_pairs},
                     {"vf_contacts", row.counters.vf_contacts},
                     {"ee_contacts", row.counters.ee_contacts}});
  }
  return nlohmann::json{
      {"model", model.path.string()},
      {"clip", motion.name()},
      {"fps", fps},
      {"first_sample", plan.first_sample},
      {"last_sample", plan.last_sample},
      {"method", options.method},
      {"accuracy", std::string(ccd::to_string(options.accuracy))},
      {"query", std::string(to_string(options.query))},
      {"frames", s.samples},
      {"intervals", s.intervals},
      {"dcd_pairs", s.dcd_pairs},
      {"ccd_vf", s.ccd_vf},
      {"ccd_ee", s.ccd_ee},
      {"frames_with_contacts", s.frames_with_contacts},
      {"frames_with_interpenetration", s.frames_with_interpenetration},
      {"intervals_with_contacts", s.intervals_with_contacts},
      {"max_candidate_pairs", s.max_candidate_pairs},
      {"bv_tests", s.bv_tests},
      {"candidate_pairs", s.candidate_pairs},
      {"ms_per_interval", s.ms_per_interval},
      {"total_ms", s.total_ms},
      {"stages_ms", stages_json(s)},
      {"worst", worst},
      {"log", log_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(log_path)},
  };
}

/// Under `auto`, where each connected component went (the plan make_method("auto") follows, with
/// the same options), for the log's /routes; empty for any other method.
std::vector<LogRoute> log_routes(const skinning::Topology& topology, const RunOptions& options) {
  std::vector<LogRoute> routes;
  if (options.method != "auto") return routes;
  const culling::MethodOptions method_options{.accuracy = options.accuracy,
                                              .min_separation = options.min_separation,
                                              .extension = options.method_extension};
  for (const auto& r : culling::route_components(topology, method_options)) {
    routes.push_back(LogRoute{.component = r.component, .part = r.part, .closed = r.closed,
                              .triangles = r.num_triangles, .method = r.method});
  }
  return routes;
}

void run_check(const CheckArguments& args) {
  // Everything that can be refused is checked before the log is created: options, the model,
  // the clip, the frame range and the method.
  RunOptions options = to_run_options(args);
  const std::filesystem::path model_path(args.model);
  const auto kind = skinning::classify_model_path(model_path);
  if (kind != skinning::ModelKind::frame_sequence) require_exists(model_path);
  const auto model = skinning::load_model(model_path);
  const auto motion = model.motion(skinning::MotionRequest{.clip = args.clip, .rate_hz = args.fps});
  const auto radial_view = setup_radial_view(args.radial_view, model, *motion, options);
  ClipRunner runner(*motion, options);
  const RunPlan& plan = runner.plan();
  const double fps = motion_rate(*motion, args.fps);

  std::unique_ptr<LogWriter> writer;
  if (!args.output.empty()) {
    LogHeader header;
    header.skelcd_version = kVersion;
    header.command_line = command_line();
    header.input_path = args.model;
    header.input_hash =
        std::filesystem::is_regular_file(model_path) ? file_content_hash(model_path) : "";
    header.clip = motion->name();
    header.method = std::string(runner.method_name());
    header.accuracy = std::string(ccd::to_string(options.accuracy));
    header.query = std::string(to_string(options.query));
    header.fps = fps;
    header.min_separation = options.min_separation;
    header.gamma = radial_view.gamma;
    header.start_time = iso8601_utc_now();
    header.first_sample = plan.first_sample;
    header.last_sample = plan.last_sample;
    header.planned_rows = plan.rows;
    header.num_vertices = motion->mesh().num_vertices();
    header.num_triangles = motion->mesh().num_triangles();
    header.part_names = motion->mesh().part_names;
    header.routes = log_routes(runner.topology(), options);
    writer = std::make_unique<LogWriter>(args.output, header);
  }

  std::vector<FrameRow> rows;
  rows.reserve(static_cast<std::size_t>(plan.rows));
  Progress progress("check " + motion->name(), plan.rows);
  runner.run([&](const FrameReport& report) {
    if (writer) writer->append(report);
    rows.push_back(report.row);
    progress.update(static_cast<std::int64_t>(rows.size()));
  });
  progress.finish();
  if (writer) writer->finish();

  const auto summary = summarize(rows);
  if (args.json) {
    print_json(json_summary(model, *motion, options, plan, fps, summary, args.output));
  } else {
    print_text_summary(model, *motion, options, plan, fps, summary, args.output);
  }
}

}  // namespace

void add_check_command(CLI::App& app) {
  auto args = std::make_shared<CheckArguments>();
  auto* cmd = app.add_subcommand(
      "check", "Self-collision over a clip: DCD at every sample, CCD over every interval");
  cmd->add_option("model", args->model, "model file (glTF, FBX, Collada, .X, …), URDF or frames")
      ->required();
  cmd->add_option("--clip", args->clip, "clip to check (default: the first)");
  cmd->add_option("--fps", args->fps, "samples per second (default: the clip's key rate, else 30)");
  cmd->add_option("--frames", args->frames, "samples A:B to check, both included (A:, :B, A)");
  cmd->add_option("--method", args->method, "culling method: brute, bvh, kdop, …")
      ->capture_default_str();
  cmd->add_option("--accuracy", args->accuracy, "elementary tests: exact, conservative, fast")
      ->capture_default_str();
  cmd->add_option("--query", args->query, "ccd, dcd or both")->capture_default_str();
  cmd->add_option("--min-separation", args->min_separation,
                  "contact distance in model units (0: touching counts)");
  cmd->add_option("-o,--output", args->output, "write the HDF5 log here (LOG.h5)");
  cmd->add_flag("--json", args->json, "print the summary as one JSON object");
  add_radial_view_options(*cmd, args->radial_view);
  cmd->callback([args] { run_check(*args); });
}

}  // namespace skelcd::tools
