// skelcd bench MODEL — the accuracy-versus-time report: every culling method × elementary-test
// accuracy over the same samples and intervals, each compared with a reference run (docs/bench.md).

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/model_options.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/scene.hpp"
#include "tools/engine/scene_runner.hpp"
#include "tools/report/bench_report.hpp"

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
      throw InvalidInput(
          "--accuracies: unknown accuracy '" + name + "' (known: exact, conservative, fast)");
    }
    o.accuracies.push_back(*accuracy);
  }
  if (!(std::isfinite(a.radial_view.gamma) && a.radial_view.gamma >= 0.0 &&
        a.radial_view.gamma <= 1.0)) {
    throw InvalidInput(
        "--gamma " + std::to_string(a.radial_view.gamma) + ": expected a value in [0, 1]");
  }
  o.run.clip = a.clip;
  o.run.fps = a.fps;
  if (!a.frames.empty()) o.run.frames = parse_frame_range(a.frames);
  const auto query = parse_query_set(a.query);
  if (!query) throw InvalidInput("--query '" + a.query + "': expected ccd, dcd or both");
  o.run.query = *query;
  // Every method and accuracy pays a full DCD at every sample: `check` updates it from the CCD
  // contacts except with `fast`, which would make the accuracies' times incomparable.
  o.run.incremental_dcd = false;
  // And every interval is queried: a held pose would cost the methods that carry no state
  // nothing, the others their full time.
  o.run.reuse_static_intervals = false;
  const auto reference = parse_reference_choice(a.reference);
  if (!reference) {
    throw InvalidInput("--reference '" + a.reference + "': expected auto, brute or bvh");
  }
  o.reference = *reference;
  return o;
}

/// One model to benchmark: the MODEL argument, or one self-checked object of a scene.
struct BenchTarget {
  std::string object;  ///< scene object name; empty for a MODEL argument
  std::string model;   ///< as load_model takes it
  skinning::LoadOptions load;
  std::string clip;
  double fps = 0;
  QuerySet query = QuerySet::both;
  FrameRange frames;
  /// A scene object that only the scene runner can build (a sheet, a part selection, an offset):
  /// loaded already; `model`, `load`, `clip` and `fps` are then only labels.
  std::optional<LoadedSceneObject> loaded;
};

/// Loads `target` and runs the report on it (the radial-view methods only on a rig's clip).
BenchReport bench_target(
    const BenchTarget& target, BenchOptions options, const BenchArguments& args) {
  std::optional<skinning::LoadedModel> own_model;
  std::unique_ptr<skinning::Motion> own_motion;
  if (!target.loaded) {
    const std::filesystem::path model_path(target.model);
    if (!skinning::is_generator_spec(target.model) &&
        skinning::classify_model_path(model_path) != skinning::ModelKind::frame_sequence) {
      require_exists(model_path);
    }
    own_model = skinning::load_model(model_path, target.load);
    own_motion =
        own_model->motion(skinning::MotionRequest{.clip = target.clip, .rate_hz = target.fps});
  }
  const skinning::LoadedModel& model = target.loaded ? *target.loaded->model : *own_model;
  const skinning::Motion& motion = target.loaded ? *target.loaded->motion : *own_motion;
  options.run.clip = target.clip;
  options.run.fps = target.fps;
  options.run.query = target.query;
  options.run.frames = target.frames;

  // rvbc and dynamic need a rig's clip: they are in the default list only then, and refused by
  // name otherwise. Their segmentation is made once, at the first radial-view run, and shared.
  options.radial_view =
      model.rig != nullptr && model.kind == skinning::ModelKind::rig && motion.num_bones() > 0;
  validate_methods(options.methods, options.radial_view);
  struct RadialViewCache {
    bool ready = false;
    RunOptions options;
    /// Whether `auto` was asked yet, and why it makes no segmentation (empty: it makes one, the
    /// one `rvbc` and `dynamic` share), as `check` says it.
    bool auto_asked = false;
    std::string auto_without;
  };
  auto cache = std::make_shared<RadialViewCache>();
  options.prepare = [cache, &args, &model, &motion, radial_view = options.radial_view](
                        RunOptions& run) {
    // Methods that need a segmentation, and `auto` (closed components to `dynamic`) on a rig's
    // clip, as `check` does.
    const culling::MethodInfo* info = culling::find_method(run.method);
    const bool is_auto = run.method == "auto";
    const bool uses_radial_view =
        (info != nullptr && info->needs.segmentation) || (is_auto && radial_view);
    if (!uses_radial_view) return;
    if (is_auto && !cache->auto_asked && run.query != QuerySet::dcd) {
      // `auto` segments only for a closed group it sends to `dynamic`: not for a mesh it sends
      // whole to `bvh`, nor for a garment whose every part goes to the cones (decided on the
      // mesh's topology, as `check` decides it).
      if (auto without = auto_without_segmentation(skinning::build_topology(motion.mesh()))) {
        cache->auto_without = std::move(without->source);
      }
      cache->auto_asked = true;
    }
    if (is_auto && !cache->auto_without.empty()) {
      run.method_parameters =
          culling::MethodParameters{.gamma = args.radial_view.gamma, .seed = args.radial_view.seed};
      return;
    }
    if (!cache->ready) {
      cache->options = run;
      cache->options.method = "dynamic";
      (void)setup_radial_view(args.radial_view, model, motion, cache->options);
      cache->ready = true;
    }
    run.segmentation = cache->options.segmentation;
    run.method_parameters = cache->options.method_parameters;
  };
  options.progress = true;
  BenchReport report = run_bench(motion, options);
  if (!cache->auto_without.empty()) {
    report.notes.push_back("auto: segmentation " + cache->auto_without);
  }
  return report;
}

/// The query a scene object's self checks ask for.
QuerySet self_query(const SceneObject& object) {
  if (object.self_dcd && object.self_ccd) return QuerySet::both;
  return object.self_dcd ? QuerySet::dcd : QuerySet::ccd;
}

/// `OUT.png` for one target; `OUT_<object>.png` for each of several.
std::filesystem::path per_object_path(
    const std::string& path, const std::string& object, std::size_t targets) {
  std::filesystem::path p(path);
  if (targets <= 1) return p;
  return p.parent_path() / (p.stem().string() + "_" + object + p.extension().string());
}

void run_bench_command(const BenchArguments& args, bool query_given) {
  const BenchOptions options = to_bench_options(args);

  // What to run: the MODEL, or every self-checked object of a scene (a sheet, a part selection or
  // an offset object as the scene runner builds it). Pair checks are not benchmarked: they are
  // listed as skipped.
  std::vector<BenchTarget> targets;
  std::vector<std::string> skipped;
  const bool scene_mode = is_scene_path(args.model);
  if (scene_mode) {
    const Scene scene = parse_scene(args.model);
    for (const auto& pair : scene.pairs) {
      skipped.push_back("pair " + pair.a + " " + pair.b + " (pair checks are not benchmarked)");
    }
    for (const auto& object : scene.objects) {
      if (!object.has_self_check()) continue;
      BenchTarget t;
      t.object = object.name;
      if (object.sheet || !object.parts.empty() || !object.offset.isZero()) {
        t.loaded = load_scene_object(scene, object.name);
      }
      t.model = object.sheet ? "sheet on " + object.attach_to : object.model;
      t.load = object.load;
      t.clip = object.clip;
      t.fps = object.rate_hz;
      t.query = query_given ? options.run.query : self_query(object);
      t.frames = !args.frames.empty() ? options.run.frames : scene.frames.value_or(FrameRange{});
      targets.push_back(std::move(t));
    }
    if (targets.empty()) {
      throw InvalidInput(args.model + ": no object has a self check (bench runs self checks)");
    }
  } else {
    targets.push_back(BenchTarget{
        .object = "",
        .model = args.model,
        .load = args.load,
        .clip = args.clip,
        .fps = args.fps,
        .query = options.run.query,
        .frames = options.run.frames,
        .loaded = std::nullopt});
  }

  // Outputs are claimed before any work (an unwritable path is refused now) and appear whole at
  // the end or not at all.
  std::optional<PendingOutput> csv;
  std::vector<std::unique_ptr<PendingOutput>> plots;
  if (!args.csv.empty()) csv.emplace(args.csv);
  if (!args.plot.empty()) {
    for (const auto& t : targets) {
      plots.push_back(
          std::make_unique<PendingOutput>(per_object_path(args.plot, t.object, targets.size())));
    }
  }

  std::vector<BenchReport> reports;
  for (const auto& t : targets) reports.push_back(bench_target(t, options, args));

  if (csv) {
    std::string text;
    for (std::size_t i = 0; i < reports.size(); ++i) {
      std::string part = bench_csv(reports[i]);
      if (scene_mode) {
        // A trailing `object` column names the scene object of each row.
        std::string tagged;
        std::size_t start = 0;
        bool header = true;
        while (start < part.size()) {
          const auto end = part.find('\n', start);
          tagged += part.substr(start, end - start) +
                    (header ? std::string(",object") : "," + targets[i].object) + "\n";
          header = false;
          start = end + 1;
        }
        part = std::move(tagged);
        if (i > 0) part = part.substr(part.find('\n') + 1);  // one header
      }
      text += part;
    }
    csv->write(text);
  }
  for (std::size_t i = 0; i < plots.size(); ++i) {
    const auto& r = reports[i];
    const std::string name =
        scene_mode ? targets[i].object : std::filesystem::path(args.model).filename().string();
    write_bench_plot(
        plots[i]->temporary(),
        r,
        name + " — " + r.motion + ", " + std::to_string(r.triangles) + " triangles, " +
            std::to_string(r.plan.intervals) + " intervals");
  }
  if (csv) csv->commit();
  for (auto& p : plots) p->commit();

  if (args.json) {
    nlohmann::json j;
    if (scene_mode) {
      j["scene"] = args.model;
      j["objects"] = nlohmann::json::array();
      for (std::size_t i = 0; i < reports.size(); ++i) {
        auto o = bench_json(reports[i]);
        o["object"] = targets[i].object;
        o["model"] = targets[i].model;
        j["objects"].push_back(std::move(o));
      }
      j["skipped"] = skipped;
    } else {
      j = bench_json(reports.front());
      j["model"] = args.model;
    }
    if (csv) j["csv"] = args.csv;
    if (!plots.empty()) {
      auto paths = nlohmann::json::array();
      for (const auto& p : plots) paths.push_back(p->path().string());
      j["plot"] = scene_mode ? paths : paths.front();
    }
    print_json(j);
    return;
  }
  for (std::size_t i = 0; i < reports.size(); ++i) {
    if (i > 0) std::cout << '\n';
    if (scene_mode) std::cout << "object    " << targets[i].object << '\n';
    std::cout << "model     " << targets[i].model << "\n";
    print_bench_table(std::cout, reports[i]);
  }
  for (const auto& name : skipped)
    std::cout << "skipped   " << name << " (not supported by bench)\n";
  if (csv) std::cout << "csv       " << args.csv << "\n";
  for (const auto& p : plots) std::cout << "plot      " << p->path().string() << "\n";
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  auto* cmd = app.add_subcommand(
      "bench", "Accuracy versus time: every method × accuracy compared with an exact reference");
  cmd->add_option(
         "model",
         args->model,
         "model file, URDF, frames folder/glob, gen: spec, or SCENE.toml (its "
         "self-checked objects)")
      ->required();
  cmd->add_option(
         "--methods",
         args->methods,
         method_option_help(
             "methods to run, comma-separated (default: all; brute only when it fits):"))
      ->delimiter(',');
  cmd->add_option(
         "--accuracies",
         args->accuracies,
         "accuracies, comma-separated (default: exact,conservative,fast)")
      ->delimiter(',');
  cmd->add_option("--clip", args->clip, "clip to run (default: the first)");
  add_rate_option(*cmd, "--fps", args->fps, kClipRateHelp);
  cmd->add_option("--frames", args->frames, "samples A:B, both included (A:, :B, A)");
  cmd->add_option("--query", args->query, "ccd, dcd or both")->capture_default_str();
  cmd->add_option(
         "--reference",
         args->reference,
         "auto (brute + exact when it fits, else bvh + exact), brute or bvh")
      ->capture_default_str();
  cmd->add_option("--csv", args->csv, "write the rows as CSV here");
  cmd->add_option("--plot", args->plot, "write the time-vs-missed-collisions PNG here");
  cmd->add_flag("--json", args->json, "print the report as one JSON object");
  add_radial_view_options(*cmd, args->radial_view);
  add_model_options(*cmd, args->load);
  add_mesh_order_option(*cmd, args->load);
  auto* query = cmd->get_option("--query");
  cmd->callback([args, query] { run_bench_command(*args, query->count() > 0); });
}

}  // namespace skelcd::tools
