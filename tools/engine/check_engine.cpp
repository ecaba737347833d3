#include "tools/engine/check_engine.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>

#include "culling/hierarchy_cache.hpp"
#include "culling/method.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "tools/engine/scene.hpp"
#include "tools/io/file_hash.hpp"
#include "tools/io/log/log_writer.hpp"

namespace skelcd::tools {
namespace {

RunOptions run_options(const CheckRequest& r) {
  if (!(std::isfinite(r.fps) && r.fps >= 0)) {
    throw InvalidInput("rate " + std::to_string(r.fps) + ": expected a rate > 0 (samples/s)");
  }
  if (!(std::isfinite(r.min_separation) && r.min_separation >= 0)) {
    throw InvalidInput(
        "min_separation " + std::to_string(r.min_separation) + ": expected a finite distance >= 0");
  }
  const auto known = check_method_names();
  if (std::find(known.begin(), known.end(), r.method) == known.end()) {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InvalidInput("--method '" + r.method + "': unknown method (known: " + list + ")");
  }
  RunOptions o;
  o.clip = r.clip;
  o.fps = r.fps;
  o.frames = r.frames;
  o.method = r.method;
  o.accuracy = r.accuracy;
  o.query = r.query;
  o.min_separation = r.min_separation;
  o.threads = r.threads;
  o.incremental_dcd = r.incremental_dcd;
  o.reuse_static_intervals = r.reuse_static_intervals;
  o.rigid_rows = r.rigid_rows;
  o.elementary_tests_done = r.tests_done;
  return o;
}

}  // namespace

std::string file_name_part(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool keep =
        std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' || c == '.';
    out += keep ? c : '_';
  }
  while (!out.empty() && out.front() == '.') out.erase(out.begin());
  return out.empty() ? std::string("model") : out;
}

std::string batch_log_name(const std::string& model_arg, const std::string& clip) {
  std::string stem;
  if (skinning::is_generator_spec(model_arg)) {
    stem = model_arg;
  } else {
    auto path = std::filesystem::path(model_arg).lexically_normal();
    if (path.filename().empty()) path = path.parent_path();
    const bool glob = model_arg.find_first_of("*?[") != std::string::npos;
    stem = glob ? path.parent_path().filename().string() : path.stem().string();
  }
  std::string name = file_name_part(stem);
  if (!clip.empty()) {
    name += '-';  // (not "-" + …: GCC 12 warns -Wrestrict on that, wrongly)
    name += file_name_part(clip);
  }
  return name;
}

RunIdentity check_identity(
    const skinning::LoadedModel& model, const CheckRequest& request, const CheckOutcome& outcome) {
  return RunIdentity{
      .model = model.path.string(),
      .clip = outcome.clip,
      .fps = outcome.fps,
      .first_sample = outcome.plan.first_sample,
      .last_sample = outcome.plan.last_sample,
      .method = request.method,
      .accuracy = std::string(ccd::to_string(request.accuracy)),
      .query = std::string(to_string(request.query)),
      .log = request.log_path,
  };
}

RunLabels check_labels(
    const skinning::LoadedModel& model, const CheckRequest& request, const CheckOutcome& outcome) {
  return RunLabels{
      .baseline = outcome.baseline,
      .baseline_slack = request.baseline_slack,
      .allow = request.allow.rules,
      .allow_adjacent_bones = request.allow.adjacent_bones,
      .events = outcome.events,
      .events_recorded = true,
      .part_names = model.mesh->part_names,
  };
}

std::vector<std::string> check_method_names() { return scene_method_names(); }

CheckOutcome check_model(
    const skinning::LoadedModel& model, const CheckRequest& request, const RowCallback& on_row) {
  const auto start = std::chrono::steady_clock::now();
  const auto ms_since = [](std::chrono::steady_clock::time_point from) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - from)
        .count();
  };
  RunOptions options = run_options(request);
  const auto motion =
      model.motion(skinning::MotionRequest{.clip = request.clip, .rate_hz = request.fps});
  CheckOutcome outcome;
  // The baseline and the allowances, refused (a bad sample, a log of another model, an unknown
  // part) before the log is created. The baseline's DCD builds its own `bvh`. A serial run frees
  // it before the runner builds its method — all but its tree, which the runner's method takes
  // over when it has one of the same key: the two would otherwise be the run's peak memory
  // together (docs/benchmarks.md "Real assets"). A parallel run computes it on a thread of its
  // own while this one sets up the radial view and the runner builds the workers' methods: the
  // stretch before the workers start is serial, and it caps the speed-up (docs/check.md,
  // "Threads").
  const bool parallel = options.threads != 1;
  // Welded once, for the segmentation, the baseline and the runner: one object that all three
  // read (a parallel run's baseline thread reads it while the runner is built on it).
  auto phase = std::chrono::steady_clock::now();
  const auto topology =
      std::make_shared<const skinning::Topology>(skinning::build_topology(motion->mesh()));
  outcome.setup.topology = ms_since(phase);
  BaselineFindings baseline;
  // The mesh's FeatureTopology, built once for the baseline's `bvh` and the runner's methods.
  std::shared_ptr<const culling::FeatureTopology> features;
  // A parallel run's baseline `bvh` and its workers' methods build the same hierarchy: once,
  // by whichever asks first; the others copy it (culling::HierarchyCache). The runner closes it.
  std::shared_ptr<culling::HierarchyCache> hierarchies;
  // A parallel run's baseline thread builds the FeatureTopology first, for its `bvh` (when it has
  // a DCD), and hands it over here at once: the runner waits for it rather than build a second
  // one beside it (both at half speed on two cores: 31 ms each on CesiumMan-dense, 15 alone).
  std::promise<std::shared_ptr<const culling::FeatureTopology>> handed_over;
  std::future<std::shared_ptr<const culling::FeatureTopology>> baseline_features;
  std::future<void> baseline_task;  // after what it reads: waited for before they go
  if (parallel) {
    hierarchies = std::make_shared<culling::HierarchyCache>();
    baseline_features = handed_over.get_future();
    baseline_task = std::async(
        std::launch::async,
        [&baseline, &handed_over, &request, &motion, topology, &outcome, &ms_since, hierarchies] {
          const auto began = std::chrono::steady_clock::now();
          std::shared_ptr<const culling::FeatureTopology> built;
          // Only a baseline with a DCD of its own builds one (not `none`, nor a log's findings).
          const auto kind = request.baseline.kind;
          if (kind == BaselineSpec::Kind::rest || kind == BaselineSpec::Kind::sample) {
            try {
              built = std::make_shared<const culling::FeatureTopology>(motion->mesh(), *topology);
            } catch (...) {
              // The runner builds its own; this failure is the one reported.
              handed_over.set_value(nullptr);
              throw;
            }
          }
          handed_over.set_value(built);
          baseline = baseline_findings(request.baseline, *motion, *topology, built, hierarchies);
          outcome.setup.baseline = ms_since(began);
        });
  }
  phase = std::chrono::steady_clock::now();
  outcome.radial_view =
      setup_radial_view(request.radial_view, model, *motion, options, topology.get());
  outcome.setup.segmentation = ms_since(phase);
  // A parallel run with a DCD baseline: its `bvh` asks for the whole mesh's tree once the baseline
  // thread has built the feature topology, and the workers' `bvh` (alone or under `auto`) ask for
  // the same. This thread, which would otherwise wait for the feature topology (no segmentation
  // to do: `bvh`, `kdop`, `auto` on a closed mesh), builds the tree meanwhile; after a
  // segmentation the baseline thread has asked for it already, and this returns at once
  // (docs/check.md "Threads").
  if (parallel && (request.baseline.kind == BaselineSpec::Kind::rest ||
                   request.baseline.kind == BaselineSpec::Kind::sample)) {
    culling::prebuild_bvh_hierarchy(*hierarchies, motion->mesh(), *topology, culling::BvhOptions{});
  }
  if (!parallel) {
    // Counted with the weld (`topology`): it is built whatever the baseline, also with `none`.
    phase = std::chrono::steady_clock::now();
    features = std::make_shared<const culling::FeatureTopology>(motion->mesh(), *topology);
    outcome.setup.topology += ms_since(phase);
    // The baseline's `bvh` tree, kept for the runner's method (`bvh`, `dynamic`'s DCD tree: the
    // same key) once the `bvh` is freed: lent, not copied, so that the two never hold it twice,
    // and not built again (culling::HierarchyCache::Sharing::hand_over). The runner closes it.
    if (request.baseline.kind == BaselineSpec::Kind::rest ||
        request.baseline.kind == BaselineSpec::Kind::sample) {
      hierarchies =
          std::make_shared<culling::HierarchyCache>(culling::HierarchyCache::Sharing::hand_over);
    }
    phase = std::chrono::steady_clock::now();
    baseline = baseline_findings(request.baseline, *motion, *topology, features, hierarchies);
    outcome.setup.baseline = ms_since(phase);
  }
  phase = std::chrono::steady_clock::now();
  if (baseline_features.valid()) features = baseline_features.get();
  // A parallel run's baseline done already (the segmentation took longer): its refusal now, as
  // in a serial run.
  if (baseline_task.valid() &&
      baseline_task.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    baseline_task.get();
  }
  ClipRunner runner = [&] {
    try {
      return ClipRunner(
          *motion, options, topology, {}, std::move(features), std::move(hierarchies));
    } catch (...) {
      if (baseline_task.valid()) baseline_task.get();  // its refusal first, as in a serial run
      throw;
    }
  }();
  outcome.setup.methods = ms_since(phase);
  outcome.plan = runner.plan();
  outcome.clip = motion->name();
  outcome.fps = motion->rate_hz();
  outcome.method = std::string(runner.method_name());

  const skinning::Mesh& mesh = motion->mesh();
  const auto positions_at = [&motion](std::int32_t sample, skinning::Positions& out) {
    motion->positions(sample, out);
  };
  outcome.baseline = describe(request.baseline);
  const skinning::Rig* rig = model.rig && model.rig->mesh.num_vertices() == mesh.num_vertices()
                                 ? model.rig.get()
                                 : nullptr;

  // Labelling the rows and logging them need the baseline's findings: the tracker, and the log,
  // which is created only once they are known (a refused baseline leaves no file behind). A serial
  // run has them already, and so has a parallel run whose baseline is done by now. Otherwise the
  // workers start on the blocks without them: the rows do not depend on the baseline, only their
  // labels do, so the thread that reports the first row waits for the baseline's thread there,
  // while the other workers go on checking blocks (before, every worker waited, and one core sat
  // idle until the baseline was done: docs/check.md, "Threads"). The order of refusals is a
  // serial run's: the baseline's, then the tracker's (an unknown part in the allowances), then
  // the log's.
  std::optional<EventTracker> tracker;
  std::unique_ptr<LogWriter> writer;
  const auto start_reporting = [&] {
    if (tracker) return;
    if (baseline_task.valid()) baseline_task.get();
    outcome.baseline_pairs = static_cast<std::int64_t>(baseline.pairs.size());
    tracker.emplace(
        mesh,
        runner.topology(),
        rig,
        baseline,
        request.allow,
        request.baseline_slack,
        positions_at,
        options.query == QuerySet::ccd ? EventTracker::DcdRows::none
                                       : EventTracker::DcdRows::expected);
    if (request.log_path.empty()) return;
    const std::string input = request.input_path.empty() ? model.path.string() : request.input_path;
    LogHeader header = log_header_base({
        .input_path = input,
        .input_hash = model_identity(input),
        .command_line = request.command_line,
        .first_sample = outcome.plan.first_sample,
        .last_sample = outcome.plan.last_sample,
        .planned_rows = outcome.plan.rows,
        .num_vertices = mesh.num_vertices(),
        .num_triangles = mesh.num_triangles(),
        .part_names = mesh.part_names,
    });
    header.clip = outcome.clip;
    header.method = outcome.method;
    header.accuracy = std::string(ccd::to_string(options.accuracy));
    header.query = std::string(to_string(options.query));
    header.fps = outcome.fps;
    header.min_separation = options.min_separation;
    header.gamma = outcome.radial_view.gamma;
    header.seed = outcome.radial_view.seed;
    header.segmentation = outcome.radial_view.segmentation_source;
    header.routes = runner.routes();
    header.baseline = outcome.baseline;
    header.baseline_slack = request.baseline_slack;
    header.allow = request.allow.rules;
    header.allow_adjacent_bones = request.allow.adjacent_bones;
    writer = std::make_unique<LogWriter>(request.log_path, header);
  };
  if (!baseline_task.valid() ||
      baseline_task.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    start_reporting();
  }

  outcome.rows.reserve(static_cast<std::size_t>(outcome.plan.rows));
  // A parallel run's baseline may still be running: its time overlaps the first blocks'.
  outcome.setup.total = ms_since(start);
  if (request.on_plan) request.on_plan(outcome.plan);
  const auto emit = [&](const std::vector<FrameReport>& ready) {
    for (const auto& report : ready) {
      if (writer) writer->append(report);
      outcome.rows.push_back(report.row);
      if (on_row) on_row(report);
    }
  };
  try {
    runner.run([&](FrameReport& report) {
      start_reporting();
      // The tracker takes the row whole, not a copy: a copy of the cloth-ball step's contacts
      // first-touched 6.4 MB more at every interval, at the moment the run's memory peaked. The
      // largest vectors of the rows it gives back, once written, return to the runner, which
      // refills them for its next row instead of allocating (runner.hpp, FrameCallback): a CCD
      // row's contacts, also when a DCD row came out after it.
      std::vector<FrameReport> ready = tracker->push(std::move(report));
      emit(ready);
      for (auto& done : ready) {
        if (done.contacts.capacity() > report.contacts.capacity()) {
          report.contacts = std::move(done.contacts);
        }
        if (done.dcd_pairs.capacity() > report.dcd_pairs.capacity()) {
          report.dcd_pairs = std::move(done.dcd_pairs);
        }
      }
    });
  } catch (...) {
    // A block's failure before the first row was reported: the baseline's refusal comes first, as
    // in a serial run (its thread is waited for either way: it reads this function's locals).
    if (baseline_task.valid()) baseline_task.get();
    throw;
  }
  start_reporting();  // a clip without rows
  emit(tracker->flush());
  outcome.events = tracker->events();
  if (writer) {
    writer->write_events(outcome.events);
    writer->finish();
  }
  outcome.summary = summarize(outcome.rows);
  return outcome;
}

}  // namespace skelcd::tools
