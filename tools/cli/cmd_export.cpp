// skelcd export MODEL [--clip NAME] [--frame K | --time S] [--rate HZ] -o OUT.{obj,ply,glb}:
// the mesh posed at one sample (or time) of a clip, written through assimp's exporter.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/model_options.hpp"
#include "tools/io/export_mesh.hpp"
#include "tools/report/highlight.hpp"
#include "tools/report/segmentation_colors.hpp"

namespace skelcd::tools {
namespace {

struct ExportArgs {
  std::string model;
  std::string clip;
  std::optional<int> frame;
  std::optional<double> time;
  double rate = 0.0;
  std::string output;
  std::string format;
  std::string highlight;
  std::string segmentation;
  skinning::LoadOptions load;
};

void run_export(const ExportArgs& args) {
  // The files' order (a frame sequence is otherwise held in a spatial one): the written mesh
  // numbers its vertices and triangles as the input does.
  skinning::LoadOptions load = args.load;
  load.mesh_order = skinning::MeshOrder::file;
  const auto model = skinning::load_model(args.model, load);
  const auto motion = model.motion({args.clip, args.rate});
  const auto fail = [&](const std::string& fault) {
    throw InvalidInput(args.model + ": " + fault);
  };

  // The pose: a sample index, or a time (any time for a rig; a sample's time otherwise).
  skinning::Positions positions;
  std::string where;
  if (args.time) {
    const double t = *args.time;
    const double end = motion->sample_time(motion->num_samples() - 1);
    if (!std::isfinite(t) || t < 0 || t > end) {
      fail(
          "time " + std::to_string(t) + " s is outside '" + motion->name() + "' [0, " +
          std::to_string(end) + "] s");
    }
    if (!motion->positions_at(t, positions, kSampleTimeTolerance)) {
      fail(
          "time " + std::to_string(t) + " s is not a sample time of '" + motion->name() +
          "'; use --frame");
    }
    where = "t = " + std::to_string(t) + " s";
  } else {
    const int k = args.frame.value_or(0);
    if (k < 0 || k >= motion->num_samples()) {
      fail(
          "frame " + std::to_string(k) + " out of range: '" + motion->name() + "' has " +
          std::to_string(motion->num_samples()) + " samples (0 to " +
          std::to_string(motion->num_samples() - 1) + ")");
    }
    motion->positions(k, positions);
    where =
        "frame " + std::to_string(k) + " (t = " + std::to_string(motion->sample_time(k)) + " s)";
  }

  ExportOptions options;
  if (!args.format.empty()) {
    options.format = parse_mesh_format(args.format);
    if (!options.format)
      throw InvalidInput("--format " + args.format + ": expected obj, ply or glb");
  }
  // --highlight LOG.h5 (colliding triangles of this frame) or --segmentation SEG.h5 (one colour
  // per atomic cluster) fill options.face_colors, one RGBA per triangle.
  std::string marked;
  if (!args.segmentation.empty()) {
    auto colors = segmentation_colors(args.segmentation, motion->mesh());
    options.face_colors = std::move(colors.face_colors);
    marked = "; " + std::to_string(colors.non_positive.size()) +
             " triangles not positively oriented to their cluster's observer in the rest pose "
             "drawn dark";
  }
  if (!args.highlight.empty()) {
    const auto frame = args.frame.value_or(0);
    auto highlight = highlight_frame(
        args.highlight, motion->mesh(), frame, motion->sample_time(frame), motion->name());
    options.face_colors = std::move(highlight.face_colors);
    marked = "; " + legend(highlight);
  }
  const auto result = export_mesh(motion->mesh(), positions, args.output, options);
  // Standard output may be carrying the mesh: the summary goes to stderr then.
  auto& report = is_stdout(args.output) ? std::cerr : std::cout;
  report << "wrote " << (is_stdout(args.output) ? std::string("standard output") : args.output)
         << ": " << result.triangles << " triangles, " << result.vertices << " vertices, '"
         << motion->name() << "' at " << where << marked << "\n";
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  auto* cmd =
      app.add_subcommand("export", "the posed mesh at a frame, for a viewer (OBJ, PLY or glb)");
  cmd->add_option("model", args->model, "model file, URDF, or frames (folder or glob)")->required();
  cmd->add_option(
      "--clip", args->clip, "clip to pose (default: the first; the bind pose when there is none)");
  auto* frame = cmd->add_option("--frame", args->frame, "sample index K at --rate (default 0)");
  auto* time = cmd->add_option("--time", args->time, "time in seconds from the start of the clip");
  frame->excludes(time);
  time->excludes(frame);
  add_rate_option(*cmd, "--rate,--fps", args->rate, kClipRateHelp);
  cmd->add_option(
         "-o,--output",
         args->output,
         "OUT.obj, OUT.ply or OUT.glb; '-' or /dev/stdout for standard output")
      ->required();
  cmd->add_option(
      "--format",
      args->format,
      "obj, ply or glb (default: from OUT's extension; obj on standard output)");
  cmd->add_option(
         "--highlight",
         args->highlight,
         "colour the triangles the log LOG.h5 found colliding at --frame: a colour per collision "
         "event, slate for the baseline's findings, khaki for allowed ones")
      ->excludes(time);
  cmd->add_option(
         "--segmentation",
         args->segmentation,
         "colour each atomic cluster of the segmentation SEG.h5 (from skelcd preprocess); "
         "triangles not positively oriented to their observer in the rest pose are drawn dark")
      ->excludes("--highlight");
  add_model_options(*cmd, args->load);
  cmd->callback([args] { run_export(*args); });
}

}  // namespace skelcd::tools
