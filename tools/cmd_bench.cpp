// skelcd bench MODEL — the accuracy-versus-time report: every culling method × elementary-test
// accuracy over the same samples and intervals, each compared with a reference run (docs/bench.md).

#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "clustering/radial_view_extension.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tools/bench_report.hpp"
#include "tools/cli_util.hpp"
#include "tools/commands.hpp"
#include "tools/model_options.hpp"
#include "tools/radial_view_setup.hpp"

namespace skelcd::tools {
namespace {

struct BenchArguments {
  std::string model;
  std::vector<std::string> methods;
  std::vector<std::string> accuracies;
  std::string clip;
  double fps = 0;
  std::string frames;
  std::string query = "both";
  std::string reference = "auto";
  std::string csv;
  std::string plot;
  bool json = false;
  RadialViewArguments radial_view;
  skinning::LoadOptions load;  ///< robots: --trajectory, --srdf, --package-path
};

/// Everything that can be refused without reading the model: lists, query, frames, reference.
BenchOptions to_bench_options(const BenchArguments& a) {
  BenchOptions o;
  // Unknown names are refused now; whether rvbc/dynamic fit the model is checked once it is read.
  validate_methods(a.methods, /*radial_view=*/true);
  o.methods = a.methods;
  for (const auto& name : a.accuracies) {
    const auto accuracy = ccd::parse_accuracy(name);
    if (!accuracy) {
      throw InvalidInput("--accuracies: unknown accuracy '" + name +
                         "' (known: exact, conservative, fast)");
    }
    o.accuracies.push_back(*accuracy);
  }
  if (!(std::isfinite(a.radial_view.gamma) && a.radial_view.gamma >= 0.0 &&
        a.radial_view.gamma <= 1.0)) {
    throw InvalidInput("--gamma " + std::to_string(a.radial_view.gamma) +
                       ": expected a value in [0, 1]");
  }
  if (!(std::isfinite(a.fps) && a.fps >= 0)) {
    throw InvalidInput("--fps " + std::to_string(a.fps) + ": expected a rate > 0 (samples/s)");
  }
  o.run.clip = a.clip;
  o.run.fps = a.fps;
  if (!a.frames.empty()) o.run.frames = parse_frame_range(a.frames);
  const auto query = parse_query_set(a.query);
  if (!query) throw InvalidInput("--query '" + a.query + "': expected ccd, dcd or both");
  o.run.query = *query;
  const auto reference = parse_reference_choice(a.reference);
  if (!reference) {
    throw InvalidInput("--reference '" + a.reference + "': expected auto, brute or bvh");
  }
  o.reference = *reference;
  return o;
}

void run_bench_command(const BenchArguments& args) {
  BenchOptions options = to_bench_options(args);

  // Outputs are claimed before any work (an unwritable path is refused now) and appear whole at
  // the end or not at all.
  std::optional<PendingOutput> csv;
  std::optional<PendingOutput> plot;
  if (!args.csv.empty()) csv.emplace(args.csv);
  if (!args.plot.empty()) plot.emplace(args.plot);

  const std::filesystem::path model_path(args.model);
  if (!skinning::is_generator_spec(args.model) &&
      skinning::classify_model_path(model_path) != skinning::ModelKind::frame_sequence) {
    require_exists(model_path);
  }
  const auto model = skinning::load_model(model_path, args.load);
  const auto motion = model.motion(skinning::MotionRequest{.clip = args.clip, .rate_hz = args.fps});

  // rvbc and dynamic need a rig's clip: they are in the default list only then, and refused by
  // name otherwise. Their segmentation is made once, at the first radial-view run, and shared.
  options.radial_view = model.rig != nullptr && model.kind == skinning::ModelKind::rig &&
                        dynamic_cast<const skinning::RigMotion*>(motion.get()) != nullptr;
  validate_methods(options.methods, options.radial_view);
  struct RadialViewCache {
    bool ready = false;
    RunOptions options;
  };
  auto cache = std::make_shared<RadialViewCache>();
  options.prepare = [cache, &args, &model, &motion, radial_view = options.radial_view](
                        RunOptions& run) {
    // `auto` sends closed components to `dynamic` on a rig's clip, as `check` does.
    const bool uses_radial_view = clustering::is_radial_view_method(run.method) ||
                                  (run.method == "auto" && radial_view);
    if (!uses_radial_view) return;
    if (!cache->ready) {
      cache->options = run;
      cache->options.method = "dynamic";
      (void)setup_radial_view(args.radial_view, model, *motion, cache->options);
      cache->ready = true;
    }
    run.method_extension = cache->options.method_extension;
    run.before_query = cache->options.before_query;
  };
  options.progress = true;

  const auto report = run_bench(*motion, options);

  if (csv) {
    csv->write(bench_csv(report));
    csv->commit();
  }
  if (plot) {
    write_bench_plot(plot->temporary(), report,
                     model_path.filename().string() + " — " + report.motion + ", " +
                         std::to_string(report.triangles) + " triangles, " +
                         std::to_string(report.plan.intervals) + " intervals");
    plot->commit();
  }
  if (args.json) {
    auto j = bench_json(report);
    j["model"] = args.model;
    if (csv) j["csv"] = args.csv;
    if (plot) j["plot"] = args.plot;
    print_json(j);
  } else {
    std::cout << "model     " << args.model << "\n";
    print_bench_table(std::cout, report);
    if (csv) std::cout << "csv       " << args.csv << "\n";
    if (plot) std::cout << "plot      " << args.plot << "\n";
  }
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  auto* cmd = app.add_subcommand(
      "bench", "Accuracy versus time: every method × accuracy compared with an exact reference");
  cmd->add_option("model", args->model, "model file, URDF, frames folder/glob, or gen: spec")
      ->required();
  cmd->add_option("--methods", args->methods,
                  "methods to run, comma-separated (default: all; brute only when it fits)")
      ->delimiter(',');
  cmd->add_option("--accuracies", args->accuracies,
                  "accuracies, comma-separated (default: exact,conservative,fast)")
      ->delimiter(',');
  cmd->add_option("--clip", args->clip, "clip to run (default: the first)");
  cmd->add_option("--fps", args->fps, "samples per second (default: the clip's key rate, else 30)");
  cmd->add_option("--frames", args->frames, "samples A:B, both included (A:, :B, A)");
  cmd->add_option("--query", args->query, "ccd, dcd or both")->capture_default_str();
  cmd->add_option("--reference", args->reference,
                  "auto (brute + exact when it fits, else bvh + exact), brute or bvh")
      ->capture_default_str();
  cmd->add_option("--csv", args->csv, "write the rows as CSV here");
  cmd->add_option("--plot", args->plot, "write the time-vs-missed-collisions PNG here");
  cmd->add_flag("--json", args->json, "print the report as one JSON object");
  add_radial_view_options(*cmd, args->radial_view);
  add_model_options(*cmd, args->load);
  cmd->callback([args] { run_bench_command(*args); });
}

}  // namespace skelcd::tools
