// skelcd check MODEL… — the main job: self-collision over a clip, sample by sample (DCD) and
// interval by interval (CCD); prints a summary and writes the HDF5 log row by row (docs/check.md).
// Several models (or a quoted glob, or --all-clips) make a batch: one log per clip in a folder,
// broken inputs reported at the end.

#include <fnmatch.h>
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "culling/routed_method.hpp"
#include "skelcd_version.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/model_options.hpp"
#include "tools/cli/scene_check.hpp"
#include "tools/engine/check_engine.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/engine/runner.hpp"
#include "tools/engine/scene.hpp"
#include "tools/engine/scene_runner.hpp"
#include "tools/io/file_hash.hpp"
#include "tools/io/log/log_writer.hpp"
#include "tools/report/summary_json.hpp"

namespace skelcd::tools {
namespace {

struct CheckArguments {
  std::vector<std::string> models;
  std::string clip;
  double fps = 0;
  std::string frames;
  std::string method = "auto";  // docs/benchmarks.md, "auto against bvh: the default method"
  std::string accuracy = "conservative";
  std::string query = "both";
  double min_separation = 0;
  std::string output;
  std::string output_dir;
  bool all_clips = false;
  bool json = false;
  std::int32_t threads = 0;
  bool full_dcd = false;
  bool no_reuse = false;
  bool no_rigid_rows = false;
  std::string baseline = "rest";
  std::int32_t baseline_slack = kDefaultBaselineSlack;
  Allowances allow;
  RadialViewArguments radial_view;
  skinning::LoadOptions load;
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

RunOptions to_run_options(const CheckArguments& a) {
  RunOptions o;
  o.clip = a.clip;
  o.fps = a.fps;
  if (!a.frames.empty()) o.frames = parse_frame_range(a.frames);
  o.method = a.method;
  // Every method the check knows, radial view's included, whether or not this run would build them.
  if (const auto known = scene_method_names();
      std::find(known.begin(), known.end(), a.method) == known.end()) {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InvalidInput("--method '" + a.method + "': unknown method (known: " + list + ")");
  }
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
  if (a.threads < 0) {
    throw InvalidInput(
        "--threads " + std::to_string(a.threads) + ": expected a worker count >= 1 (0: all cores)");
  }
  o.threads = a.threads;
  o.incremental_dcd = !a.full_dcd;
  o.reuse_static_intervals = !a.no_reuse;
  o.rigid_rows = !a.no_rigid_rows;
  return o;
}

std::string describe(const FrameRow& row) {
  std::ostringstream s;
  char time[32];
  std::snprintf(time, sizeof time, "%.3f", row.t0);
  if (row.kind == QueryKind::dcd) {
    s << "sample " << row.sample << " (t = " << time << " s): " << new_dcd_pairs(row)
      << " new intersecting triangle pairs";
    if (new_dcd_pairs(row) != row.counters.dcd_pairs) s << " of " << row.counters.dcd_pairs;
  } else {
    s << "interval " << row.sample << "-" << row.sample + 1 << " (t = " << time
      << " s): " << new_ccd_contacts(row) << " new contacts";
    s << " of " << row.counters.vf_contacts << " VF + " << row.counters.ee_contacts << " EE";
  }
  return s.str();
}

/// "a, b, c +2": as many names as fit in `width` characters, then how many more.
std::string name_list(const std::vector<std::string>& names, std::size_t width) {
  std::string text;
  std::size_t shown = 0;
  for (; shown < names.size(); ++shown) {
    const std::string more = " +" + std::to_string(names.size() - shown - 1);
    const std::size_t extra =
        (shown > 0 ? 2 : 0) + names[shown].size() + (shown + 1 < names.size() ? more.size() : 0);
    if (shown > 0 && text.size() + extra > width) break;
    if (shown > 0) text += ", ";
    text += names[shown];
  }
  if (shown < names.size()) text += " +" + std::to_string(names.size() - shown);
  return text.empty() ? std::string("-") : text;
}

std::vector<std::string> part_list(const skinning::Mesh& mesh, const EventRecord& e) {
  std::vector<std::string> parts;
  for (const auto p : e.parts) parts.push_back(mesh.part_names[static_cast<std::size_t>(p)]);
  return parts;
}

/// Most events the text summary lists; the log and --json have every one.
constexpr std::size_t kEventsShown = 20;

/// The events table, then the baseline's and the allowed counts: what the clip causes first.
/// With more than kEventsShown events, the largest (peak pairs, then contacts) are listed.
void print_events(
    std::ostream& out,
    const skinning::Mesh& mesh,
    const CheckOutcome& o,
    const RunOptions& options) {
  const auto& s = o.summary;
  char line[512];
  auto roots = root_events(o.events);
  out << "events    " << roots.size() << " new collision event" << (roots.size() == 1 ? "" : "s")
      << " against the baseline (" << o.baseline << "): " << s.new_dcd_pairs << " new DCD pairs, "
      << s.new_ccd_contacts << " new CCD contacts\n";
  const std::size_t total = roots.size();
  if (roots.size() > kEventsShown) {
    std::stable_sort(roots.begin(), roots.end(), [](const EventRecord* a, const EventRecord* b) {
      return std::tie(a->peak_pairs, a->ccd_contacts) > std::tie(b->peak_pairs, b->ccd_contacts);
    });
    roots.resize(kEventsShown);
    std::sort(roots.begin(), roots.end(), [](const EventRecord* a, const EventRecord* b) {
      return a->id < b->id;
    });
  }
  if (!roots.empty()) {
    std::snprintf(
        line,
        sizeof line,
        "  %4s  %-9s  %-13s  %-8s  %-34s  %-20s  %5s  %8s\n",
        "#",
        "samples",
        "time (s)",
        "contact",
        "bones",
        "parts",
        "peak",
        "depth");
    out << line;
  }
  for (const auto* e : roots) {
    const std::string samples =
        std::to_string(e->first_sample) + "-" + std::to_string(e->last_sample);
    char times[64];
    std::snprintf(times, sizeof times, "%.3f-%.3f", e->t_first, e->t_last);
    char contact[32] = "-";
    if (e->t_first_contact) std::snprintf(contact, sizeof contact, "%.4f", *e->t_first_contact);
    std::snprintf(
        line,
        sizeof line,
        "  %4d  %-9s  %-13s  %-8s  %-34s  %-20s  %5lld  %8.3g\n",
        e->id,
        samples.c_str(),
        times,
        contact,
        name_list(e->bones, 34).c_str(),
        name_list(part_list(mesh, *e), 20).c_str(),
        static_cast<long long>(e->peak_pairs),
        e->depth);
    out << line;
  }
  if (total > roots.size()) {
    out << "  … " << total - roots.size()
        << " smaller events not listed (--json and the log have all: skelcd inspect LOG)\n";
  }
  out << "baseline  " << o.baseline << ": " << s.baseline_dcd_pairs << " DCD pairs";
  if (options.query != QuerySet::dcd) out << ", " << s.baseline_ccd_contacts << " CCD contacts";
  out << " the rig already had (" << o.baseline_pairs << " pairs at the baseline)\n";
  out << "allowed   " << s.allowed_dcd_pairs << " DCD pairs";
  if (options.query != QuerySet::dcd) out << ", " << s.allowed_ccd_contacts << " CCD contacts";
  out << '\n';
}

void print_text_summary(
    std::ostream& out,
    const skinning::LoadedModel& model,
    const skinning::Motion& motion,
    const RunOptions& options,
    const RunPlan& plan,
    double fps,
    const RunSummary& s,
    const std::string& log_path) {
  const auto& mesh = motion.mesh();
  char line[256];
  out << "model     " << model.path.string() << " (" << mesh.num_parts() << " parts, "
      << mesh.num_vertices() << " vertices, " << mesh.num_triangles() << " triangles)\n";
  std::snprintf(line, sizeof line, "%.6g", fps);
  out << "clip      " << motion.name() << ": samples " << plan.first_sample << ".."
      << plan.last_sample << " at " << line << " Hz\n";
  out << "method    " << options.method << ", accuracy " << ccd::to_string(options.accuracy)
      << ", query " << to_string(options.query) << "\n";
  out << "frames    " << s.samples << " samples, " << s.intervals << " intervals\n";
  if (options.query != QuerySet::ccd) {
    out << "DCD       " << s.frames_with_interpenetration << " of " << s.samples
        << " samples have new intersections; " << s.dcd_pairs
        << " intersecting triangle pairs in all\n";
  }
  if (options.query != QuerySet::dcd) {
    out << "CCD       " << s.intervals_with_contacts << " of " << s.intervals
        << " intervals have new contacts; " << s.ccd_vf << " VF + " << s.ccd_ee
        << " EE contacts in all\n";
  }
  if (!s.worst.empty()) {
    out << "worst\n";
    for (const auto& row : s.worst) out << "  " << describe(row) << '\n';
  }
  std::snprintf(
      line,
      sizeof line,
      "time      %.3f ms per %s (skin %.3f, refit %.3f, classify %.3f, merge %.3f, "
      "traverse %.3f, elementary %.3f, other %.3f)\n",
      s.ms_per_interval,
      s.intervals > 0 ? "interval" : "sample",
      s.skin_ms,
      s.refit_ms,
      s.classify_ms,
      s.merge_ms,
      s.traverse_ms,
      s.elementary_ms,
      s.other_ms);
  out << line;
  if (!log_path.empty()) out << "log       " << log_path << '\n';
}

/// Under `auto`, where each connected component went (the plan make_method("auto") follows, with
/// the same options), for the log's /routes; empty for any other method.
/// A model argument that names no file: a generator spec (`gen:rope`) or a frame sequence (a
/// folder or a glob of frames).
bool names_a_file(const std::string& model_arg) {
  if (skinning::is_generator_spec(model_arg)) return false;
  return skinning::classify_model_path(model_arg) != skinning::ModelKind::frame_sequence;
}

/// commands.hpp, on_check_model_loaded.
std::function<void(std::int64_t)>& model_loaded_hook() {
  static std::function<void(std::int64_t)> hook;
  return hook;
}

/// malloc's thresholds for a check (run_check_command), set again after the executable's hook,
/// which may move them.
void set_check_malloc_thresholds();

/// The executable's hook (model_loaded_hook) told a check's mesh size, and malloc's thresholds
/// for the check set again after it (the hook may move them).
void tell_model_loaded(std::int64_t triangles) {
  if (const auto& hook = model_loaded_hook()) {
    hook(triangles);
    set_check_malloc_thresholds();
  }
}

skinning::LoadedModel load_checked_model(const CheckArguments& args, const std::string& model_arg) {
  if (names_a_file(model_arg)) require_exists(model_arg);
  // A parallel check starts its thread pool while the import's child reads the file: this
  // process only waits then, and the pool's start (2-3 ms) would otherwise stand between the
  // set-up and the first block (docs/check.md "Threads").
  skinning::LoadOptions load = args.load;
  if (args.threads != 1) {
    load.import.while_importing = [threads = args.threads] { warm_up_workers(threads); };
  }
  auto model = skinning::load_model(model_arg, load);
  tell_model_loaded(model.mesh->num_triangles());
  return model;
}

/// One clip checked: the summary as text and as JSON.
struct CheckedClip {
  std::string text;
  nlohmann::json json;
};

/// Checks one clip of a loaded model, writing the log at `log_path` (none when empty).
/// Everything that can be refused is checked before the log is created: the clip, the frame
/// range and the method.
CheckedClip check_clip(
    const CheckArguments& args,
    RunOptions options,
    const std::string& model_arg,
    const skinning::LoadedModel& model,
    const std::string& clip,
    const std::string& log_path) {
  CheckRequest request{
      .clip = clip,
      .fps = args.fps,
      .frames = options.frames,
      .method = options.method,
      .accuracy = options.accuracy,
      .query = options.query,
      .min_separation = options.min_separation,
      .threads = options.threads,
      .incremental_dcd = options.incremental_dcd,
      .reuse_static_intervals = options.reuse_static_intervals,
      .rigid_rows = options.rigid_rows,
      .radial_view = args.radial_view,
      .baseline = parse_baseline(args.baseline),
      .baseline_slack = args.baseline_slack,
      .allow = args.allow,
      .log_path = log_path,
      .input_path = model_arg,
      .command_line = command_line(),
      .tests_done = nullptr,
      .on_plan = {},
  };
  std::atomic<std::int64_t> tests_done{0};  // shown by the progress line inside long queries
  request.tests_done = &tests_done;
  // The progress line starts once the check is planned; a check refused before shows none (a
  // parallel run's baseline refused later erases it, as any failure does, before the message).
  std::unique_ptr<Progress> progress;
  std::int64_t rows = 0;
  request.on_plan = [&](const RunPlan& plan) {
    progress = std::make_unique<Progress>(
        "check " + (clip.empty() ? model.path.filename().string() : clip), plan.rows, &tests_done);
  };
  const auto outcome =
      check_model(model, request, [&](const FrameReport&) { progress->update(++rows); });
  progress.reset();
  const auto motion = model.motion(skinning::MotionRequest{.clip = clip, .rate_hz = args.fps});
  options.clip = clip;
  CheckedClip checked;
  std::ostringstream text;
  print_events(text, motion->mesh(), outcome, options);
  print_text_summary(
      text, model, *motion, options, outcome.plan, outcome.fps, outcome.summary, log_path);
  {
    const SetupTimes& t = outcome.setup;
    char line[200];
    std::snprintf(
        line,
        sizeof line,
        "set-up    %.1f ms before the first row (topology %.1f, segmentation %.1f, baseline "
        "%.1f, methods %.1f)\n",
        t.total,
        t.topology,
        t.segmentation,
        t.baseline,
        t.methods);
    text << line;
  }
  if (!outcome.radial_view.segmentation_source.empty()) {
    text << "segmentation: " << outcome.radial_view.segmentation_source << "\n";
  }
  checked.text = text.str();
  checked.json = summary_json(
      check_identity(model, request, outcome),
      outcome.summary,
      check_labels(model, request, outcome));
  if (!outcome.radial_view.segmentation_source.empty()) {
    checked.json["segmentation"] = outcome.radial_view.segmentation_source;
  }
  checked.json["setup_ms"] = setup_json(outcome.setup);
  return checked;
}

void run_check(const CheckArguments& args) {
  // Everything that can be refused is checked before the log is created: options, the model,
  // the clip, the frame range and the method.
  const RunOptions options = to_run_options(args);
  const std::string& model_arg = args.models.front();
  const auto model = load_checked_model(args, model_arg);
  const auto checked = check_clip(args, options, model_arg, model, args.clip, args.output);
  if (args.json) {
    print_json(checked.json);
  } else {
    std::cout << checked.text;
  }
}

// --- batch mode ---------------------------------------------------------------------------------

bool has_glob(const std::string& arg) {
  return !skinning::is_generator_spec(arg) && arg.find_first_of("*?[") != std::string::npos;
}

bool is_frame_file(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return ext == ".obj" || ext == ".ply";
}

/// The files and folders a glob's last component matches in its folder, sorted; empty when the
/// folder part has glob characters or cannot be listed.
std::vector<std::string> glob_matches(const std::string& pattern) {
  std::vector<std::string> matches;
  const std::filesystem::path path(pattern);
  const auto dir = path.parent_path();
  const std::string name = path.filename().string();
  if (name.empty() || dir.string().find_first_of("*?[") != std::string::npos) return matches;
  std::error_code ec;
  const std::filesystem::path listed = dir.empty() ? std::filesystem::path(".") : dir;
  for (const auto& entry : std::filesystem::directory_iterator(listed, ec)) {
    const std::string file = entry.path().filename().string();
    if (fnmatch(name.c_str(), file.c_str(), FNM_PERIOD) != 0) continue;
    matches.push_back((dir / file).string());
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

/// The model arguments with quoted globs expanded (`'dir/*.glb'`): a glob that matches only OBJ/PLY
/// frames (or nothing) stays one argument, a frame sequence, as with a single model.
std::vector<std::string> expand_models(const std::vector<std::string>& args, bool& expanded) {
  std::vector<std::string> models;
  expanded = false;
  for (const auto& arg : args) {
    if (!has_glob(arg)) {
      models.push_back(arg);
      continue;
    }
    const auto matches = glob_matches(arg);
    const bool frames = std::all_of(matches.begin(), matches.end(), [](const std::string& m) {
      return std::filesystem::is_regular_file(m) && is_frame_file(m);
    });
    if (frames) {
      models.push_back(arg);
    } else {
      models.insert(models.end(), matches.begin(), matches.end());
      expanded = true;
    }
  }
  return models;
}

struct Failure {
  std::string model;
  std::string clip;
  std::string error;
};

/// "MODEL (clip C): fault". Errors mostly start with the model's name already ("MODEL: fault");
/// it is not repeated then.
std::string describe(const Failure& f) {
  const std::string where = f.model + (f.clip.empty() ? "" : " (clip " + f.clip + ")");
  if (f.error.rfind(f.model + ":", 0) != 0) return where + ": " + f.error;
  return where + f.error.substr(f.model.size());
}

void run_batch(const CheckArguments& args, const std::vector<std::string>& models) {
  const RunOptions options = to_run_options(args);
  if (args.all_clips && !args.clip.empty()) {
    throw InvalidInput("--all-clips and --clip " + args.clip + ": give one of them");
  }
  if (!args.output.empty() && !args.output_dir.empty() && args.output != args.output_dir) {
    throw InvalidInput(
        "-o " + args.output + " and --output-dir " + args.output_dir +
        ": in batch mode both name the folder for the logs; give one");
  }
  const std::filesystem::path dir = args.output_dir.empty() ? args.output : args.output_dir;
  if (!dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
      throw IoError(
          dir.string() + ": cannot create the log folder" +
          (ec ? ": " + ec.message() : std::string()));
    }
  }

  std::vector<CheckedClip> runs;
  std::vector<Failure> failures;
  std::set<std::string> names;
  std::size_t checks = 0;
  for (const auto& model_arg : models) {
    std::optional<skinning::LoadedModel> model;
    try {
      model.emplace(load_checked_model(args, model_arg));
    } catch (const std::exception& e) {
      ++checks;
      failures.push_back(Failure{model_arg, args.clip, e.what()});
      continue;
    }
    std::vector<std::string> clips{args.clip};
    if (args.all_clips && !model->clips.empty()) {
      clips.clear();
      for (const auto& c : model->clips) clips.push_back(c.name);
    }
    for (const auto& clip : clips) {
      ++checks;
      // The log's name: the clip asked for, else the model's first clip.
      const std::string clip_name =
          !clip.empty() ? clip : (model->clips.empty() ? std::string() : model->clips.front().name);
      std::string log_path;
      if (!dir.empty()) {
        const std::string base = batch_log_name(model_arg, clip_name);
        std::string name = base;
        for (int k = 2; names.count(name) != 0; ++k) name = base + "-" + std::to_string(k);
        names.insert(name);
        log_path = (dir / (name + ".h5")).string();
      }
      try {
        runs.push_back(check_clip(args, options, model_arg, *model, clip, log_path));
        if (!args.json) std::cout << runs.back().text << '\n' << std::flush;
      } catch (const std::exception& e) {
        failures.push_back(Failure{model_arg, clip_name, e.what()});
      }
    }
  }

  if (args.json) {
    auto done = nlohmann::json::array();
    for (const auto& r : runs) done.push_back(r.json);
    auto failed = nlohmann::json::array();
    for (const auto& f : failures) {
      failed.push_back({{"model", f.model}, {"clip", f.clip}, {"error", f.error}});
    }
    print_json({{"runs", done}, {"failures", failed}});
  } else {
    std::cout << "batch     " << checks << " checks of " << models.size()
              << " models: " << runs.size() << " done, " << failures.size() << " failed\n";
    for (const auto& f : failures) std::cout << "FAILED    " << describe(f) << '\n';
  }
  if (!failures.empty()) {
    throw InvalidInput(
        std::to_string(failures.size()) + " of " + std::to_string(checks) +
        " checks failed, first " + describe(failures.front()));
  }
}

void set_check_malloc_thresholds() {
  // Blocks of 128 KiB or more get their own mapping, returned to the system when freed. glibc
  // raises this threshold by itself to the largest block freed so far, after which big buffers
  // that a check frees (the baseline DCD's hierarchy, a query's scratch) stay resident in the heap
  // and count in the peak RSS with the next ones: on cloth-funnel's CCD check, 1-2 MiB of its
  // ~17 MiB above the floor (docs/benchmarks.md, "Fixed costs"). Only here: `inspect` reads logs
  // under libhdf5's own allocation pattern (tests/tools/test_log.cpp, the fuzzed logs). Set again
  // once the executable has put a large mesh's heap top on huge pages (tools/cli/main.cpp,
  // heap_on_huge_pages, which leaves this threshold to be set here).
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  // When glibc trims the heap's free top it keeps this much mapped (default 128 KiB): a check
  // frees and allocates its per-phase and per-query buffers over and over, and each page given
  // back is a page fault the next time, which this project's VMs make dear. 4 MiB took a third of
  // the page faults off CesiumMan-dense's check (`dynamic`, one thread: 17.5k -> 11.9k, 0.79 ->
  // 0.70 s) with the same peak RSS on one thread; 16 MiB gave the worker threads' heaps 8 MiB
  // more on two (docs/benchmarks.md, "The heap's top kept"). The import's child inherits it: an
  // import that needs all but the last 4 MiB of its limit may be refused (the limit is 64 MiB at
  // least on the command line). With the heap's top on huge pages it is not trimmed below 60 MiB
  // free, and the pad matters only below the mesh size for them, with SKELCD_LARGE_PAGES=0, or
  // outside the executable.
  mallopt(M_TOP_PAD, 4 << 20);
}

void run_check_command(const CheckArguments& args) {
  set_check_malloc_thresholds();
  if (args.models.size() == 1 && is_scene_path(args.models.front())) {  // a scene (docs/scenes.md)
    run_scene_check(
        args.models.front(),
        SceneCheckArguments{
            .output = args.output,
            .frames = args.frames,
            .threads = args.threads,
            .json = args.json,
            .on_loaded = tell_model_loaded});
    return;
  }
  bool expanded = false;
  const auto models = expand_models(args.models, expanded);
  const bool batch = models.size() != 1 || expanded || args.all_clips || !args.output_dir.empty();
  if (batch) {
    run_batch(args, models);
  } else {
    run_check(args);
  }
}

}  // namespace

void on_check_model_loaded(std::function<void(std::int64_t)> hook) {
  model_loaded_hook() = std::move(hook);
}

void add_check_command(CLI::App& app) {
  auto args = std::make_shared<CheckArguments>();
  auto* cmd = app.add_subcommand(
      "check", "Self-collision over a clip: DCD at every sample, CCD over every interval");
  cmd->add_option(
         "model",
         args->models,
         "model file(s) (glTF, FBX, Collada, .X, …), URDF, frames or gen:NAME; several, "
         "or a quoted glob ('dir/*.glb'), make a batch")
      ->required();
  cmd->add_option("--clip", args->clip, "clip to check (default: the first)");
  add_rate_option(*cmd, "--fps", args->fps, kClipRateHelp);
  cmd->add_option("--frames", args->frames, "samples A:B to check, both included (A:, :B, A)");
  cmd->add_option("--method", args->method, method_option_help("culling method, one of:"))
      ->capture_default_str();
  cmd->add_option(
         "--accuracy",
         args->accuracy,
         "elementary tests: conservative (never misses), fast (no guarantee), or exact (GMP "
         "rationals, the judge: 10-30x the time of conservative per test; a 92k-triangle cloth "
         "step takes minutes)")
      ->capture_default_str();
  cmd->add_option("--query", args->query, "ccd, dcd or both")->capture_default_str();
  cmd->add_option(
      "--min-separation",
      args->min_separation,
      "contact distance in model units (0: touching counts)");
  cmd->add_option(
      "-o,--output",
      args->output,
      "write the HDF5 log here (LOG.h5); in a batch: the folder for the logs");
  cmd->add_option(
      "--output-dir",
      args->output_dir,
      "batch: write one log per clip into this folder (MODEL-CLIP.h5)");
  cmd->add_flag("--all-clips", args->all_clips, "check every clip of each model (a batch)");
  cmd->add_option(
      "--threads",
      args->threads,
      "worker threads (default 0: all cores; 1: serial); results do not depend on it");
  cmd->add_flag(
      "--full-dcd",
      args->full_dcd,
      "test every candidate pair at every sample; by default, with --query both, the DCD at a "
      "sample updates the previous one from the interval's CCD contacts (the same pairs, "
      "docs/culling.md \"Incremental DCD\")");
  cmd->add_flag(
      "--no-reuse",
      args->no_reuse,
      "query every CCD interval; by default an interval that holds the pose of the last held one "
      "(the same positions at both ends) gets that one's row without a query, where the method "
      "keeps no state between queries or only what follows from the pose (docs/check.md "
      "\"Static intervals\")");
  cmd->add_flag(
      "--no-rigid-rows",
      args->no_rigid_rows,
      "kdop, rvbc, dynamic and auto: test the pairs that skinning moves by one matrix too; by "
      "default their CCD skips them where the interval certifies their row (the same contacts, "
      "docs/culling.md \"Rigid rows\")");
  cmd->add_flag("--json", args->json, "print the summary as one JSON object");
  cmd->add_option(
         "--baseline",
         args->baseline,
         "what the rig already had, never reported as new (docs/events.md): rest (its "
         "rest pose), sample:K, none, or LOG.h5 (every finding of a log of this model)")
      ->capture_default_str();
  cmd->add_option(
         "--baseline-slack",
         args->baseline_slack,
         "rings of triangles a baseline intersection may slide by and stay the rig's")
      ->capture_default_str();
  cmd->add_option(
      "--allow",
      args->allow.rules,
      "PART_A:PART_B: parts or bones allowed to touch; their findings are counted "
      "apart (repeatable)");
  cmd->add_flag(
      "--allow-adjacent-bones",
      args->allow.adjacent_bones,
      "allow findings between triangles driven by the same bone or a bone and its parent");
  add_radial_view_options(*cmd, args->radial_view);
  add_model_options(*cmd, args->load);
  add_mesh_order_option(*cmd, args->load);
  cmd->callback([args] { run_check_command(*args); });
}

}  // namespace skelcd::tools
