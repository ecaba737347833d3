#include "tools/check_engine.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>

#include "skelcd_version.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "tools/file_hash.hpp"
#include "tools/log/log_writer.hpp"
#include "tools/scene.hpp"

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

std::vector<std::string> check_method_names() { return scene_method_names(); }

CheckOutcome check_model(
    const skinning::LoadedModel& model, const CheckRequest& request, const FrameCallback& on_row) {
  RunOptions options = run_options(request);
  const auto motion =
      model.motion(skinning::MotionRequest{.clip = request.clip, .rate_hz = request.fps});
  CheckOutcome outcome;
  outcome.radial_view = setup_radial_view(request.radial_view, model, *motion, options);
  ClipRunner runner(*motion, options);
  outcome.plan = runner.plan();
  outcome.clip = motion->name();
  outcome.fps = motion->rate_hz();
  outcome.method = std::string(runner.method_name());

  std::unique_ptr<LogWriter> writer;
  if (!request.log_path.empty()) {
    const std::string input = request.input_path.empty() ? model.path.string() : request.input_path;
    LogHeader header;
    header.skelcd_version = kVersion;
    header.command_line = request.command_line;
    header.input_path = input;
    header.input_hash = model_identity(input);
    header.clip = outcome.clip;
    header.method = outcome.method;
    header.accuracy = std::string(ccd::to_string(options.accuracy));
    header.query = std::string(to_string(options.query));
    header.fps = outcome.fps;
    header.min_separation = options.min_separation;
    header.gamma = outcome.radial_view.gamma;
    header.seed = outcome.radial_view.seed;
    header.segmentation = outcome.radial_view.segmentation_source;
    header.start_time = iso8601_utc_now();
    header.first_sample = outcome.plan.first_sample;
    header.last_sample = outcome.plan.last_sample;
    header.planned_rows = outcome.plan.rows;
    header.num_vertices = motion->mesh().num_vertices();
    header.num_triangles = motion->mesh().num_triangles();
    header.part_names = motion->mesh().part_names;
    header.routes = runner.routes();
    writer = std::make_unique<LogWriter>(request.log_path, header);
  }

  outcome.rows.reserve(static_cast<std::size_t>(outcome.plan.rows));
  if (request.on_plan) request.on_plan(outcome.plan);
  runner.run([&](const FrameReport& report) {
    if (writer) writer->append(report);
    outcome.rows.push_back(report.row);
    if (on_row) on_row(report);
  });
  if (writer) writer->finish();
  outcome.summary = summarize(outcome.rows);
  return outcome;
}

}  // namespace skelcd::tools
