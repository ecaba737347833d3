// skelcd preprocess MODEL — the offline half of the radial-view method (paper 002, §4): bone
// weights, atomic clusters and their observers; prints paper Table 1 style statistics and saves
// the segmentation to HDF5 (docs/segmentation.md).

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "segmentation/orientation_stats.hpp"
#include "segmentation/segmentation.hpp"
#include "skelcd_version.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "tools/cli/cli_util.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/model_options.hpp"
#include "tools/io/segmentation_file.hpp"

namespace skelcd::tools {
namespace {

namespace seg = skelcd::segmentation;

struct PreprocessArguments {
  std::string model;
  std::string weights = "heat";
  std::string distance = "exact";
  double theta = 10.0;
  std::string clip;
  double fps = 0.0;
  int grid = seg::HeatWeightsOptions{}.grid_resolution;
  bool no_refine = false;
  std::string output;
  bool json = false;
  skinning::LoadOptions load;
};

seg::SegmentationOptions to_options(const PreprocessArguments& a) {
  seg::SegmentationOptions o;
  if (a.weights == "heat") {
    o.weights = seg::WeightSource::heat;
  } else if (a.weights == "rig") {
    o.weights = seg::WeightSource::rig;
  } else {
    throw InvalidInput("--weights '" + a.weights + "': expected heat or rig");
  }
  if (a.distance == "exact") {
    o.heat.distance = seg::DistanceMode::exact;
  } else if (a.distance == "coarse") {
    o.heat.distance = seg::DistanceMode::coarse;
  } else {
    throw InvalidInput("--distance '" + a.distance + "': expected exact or coarse");
  }
  if (!(std::isfinite(a.theta) && a.theta >= 0.0 && a.theta <= 90.0)) {
    throw InvalidInput("--theta " + std::to_string(a.theta) + ": expected degrees in [0, 90]");
  }
  o.theta_deg = a.theta;
  if (a.grid < 1 || a.grid > 1024) {
    throw InvalidInput("--grid " + std::to_string(a.grid) + ": expected 1 … 1024 cells");
  }
  o.heat.grid_resolution = a.grid;
  o.refine = !a.no_refine;
  return o;
}

std::string bone_list(const skinning::Rig& rig, const std::vector<std::int32_t>& bones) {
  std::string out;
  for (const auto b : bones) {
    if (!out.empty()) out += ", ";
    out += rig.skeleton.bones[static_cast<std::size_t>(b)].name;
  }
  return out;
}

void print_text(
    const PreprocessArguments& args,
    const skinning::Rig& rig,
    const seg::Segmentation& s,
    const std::optional<seg::ClipOrientationStats>& clip) {
  const auto& st = s.stats;
  char line[512];
  std::snprintf(
      line,
      sizeof line,
      "model          %s: %lld triangles, %lld vertices (%lld welded), %d bones\n",
      args.model.c_str(),
      static_cast<long long>(st.triangles),
      static_cast<long long>(st.vertices),
      static_cast<long long>(st.welded_vertices),
      st.bones);
  std::cout << line;
  if (s.options.weights == seg::WeightSource::heat) {
    std::snprintf(
        line,
        sizeof line,
        "weights        heat diffusion, %s distance: %.3f s (distance %.3f, factorise "
        "%.3f, solve %.3f); %lld vertices saw no bone, %lld negative weights clamped\n",
        args.distance.c_str(),
        st.weights_s,
        st.heat.distance_s,
        st.heat.factorize_s,
        st.heat.solve_s,
        static_cast<long long>(st.heat.fallback_vertices),
        static_cast<long long>(st.heat.clamped_weights));
  } else {
    std::snprintf(
        line,
        sizeof line,
        "weights        the rig's own: %.3f s; %lld vertices without a weight\n",
        st.weights_s,
        static_cast<long long>(st.unweighted_vertices));
  }
  std::cout << line;
  std::snprintf(
      line,
      sizeof line,
      "decomposition  %.1f ms: %d atomic clusters (%d extra pieces of split bones), %d "
      "point and %d line observers (theta %g deg)\n",
      st.decomposition_ms,
      st.atomic_clusters,
      st.split_clusters,
      st.point_observers,
      st.line_observers,
      s.options.theta_deg);
  std::cout << line;
  if (!st.bones_without_cluster.empty()) {
    std::cout << "               " << st.bones_without_cluster.size()
              << " bones own no cluster: " << bone_list(rig, st.bones_without_cluster) << '\n';
  }
  if (s.options.refine) {
    std::snprintf(
        line,
        sizeof line,
        "refinement     non-positive triangles %lld -> %lld (%lld removed, %lld regrown "
        "positive, %lld regrown unconstrained)\n",
        static_cast<long long>(st.refinement.non_positive_before),
        static_cast<long long>(st.refinement.non_positive_after),
        static_cast<long long>(st.refinement.removed),
        static_cast<long long>(st.refinement.regrown_positive),
        static_cast<long long>(st.refinement.regrown_unconstrained));
    std::cout << line;
  }
  std::snprintf(
      line,
      sizeof line,
      "rest pose      |H-| %lld  |Hu| %lld\n",
      static_cast<long long>(st.h_minus),
      static_cast<long long>(st.h_uncertain));
  std::cout << line;
  if (clip) {
    std::snprintf(
        line,
        sizeof line,
        "clip           %s: |H-| %.1f  |Hu| %.1f averaged over %d intervals (max %lld, "
        "%lld)\n",
        clip->clip.c_str(),
        clip->mean_h_minus,
        clip->mean_h_uncertain,
        clip->intervals,
        static_cast<long long>(clip->max_h_minus),
        static_cast<long long>(clip->max_h_uncertain));
    std::cout << line;
  }
  if (!args.output.empty()) std::cout << "saved          " << args.output << '\n';
}

nlohmann::json to_json(
    const PreprocessArguments& args,
    const skinning::Rig& rig,
    const seg::Segmentation& s,
    const std::optional<seg::ClipOrientationStats>& clip) {
  const auto& st = s.stats;
  auto empty = nlohmann::json::array();
  for (const auto b : st.bones_without_cluster) {
    empty.push_back(rig.skeleton.bones[static_cast<std::size_t>(b)].name);
  }
  nlohmann::json j{
      {"model", args.model},
      {"triangles", st.triangles},
      {"vertices", st.vertices},
      {"welded_vertices", st.welded_vertices},
      {"bones", st.bones},
      {"weights", args.weights},
      {"distance", args.distance},
      {"theta_deg", s.options.theta_deg},
      {"refine", s.options.refine},
      {"atomic_clusters", st.atomic_clusters},
      {"split_clusters", st.split_clusters},
      {"bones_without_cluster", empty},
      {"point_observers", st.point_observers},
      {"line_observers", st.line_observers},
      {"h_minus", st.h_minus},
      {"h_uncertain", st.h_uncertain},
      {"refinement",
       {{"non_positive_before", st.refinement.non_positive_before},
        {"non_positive_after", st.refinement.non_positive_after},
        {"removed", st.refinement.removed},
        {"regrown_positive", st.refinement.regrown_positive},
        {"regrown_unconstrained", st.refinement.regrown_unconstrained},
        {"restored", st.refinement.restored}}},
      {"weights_s", st.weights_s},
      {"decomposition_ms", st.decomposition_ms},
      {"heat",
       {{"fallback_vertices", st.heat.fallback_vertices},
        {"isolated_vertices", st.heat.isolated_vertices},
        {"degenerate_triangles", st.heat.degenerate_triangles},
        {"clamped_weights", st.heat.clamped_weights},
        {"distance_s", st.heat.distance_s},
        {"factorize_s", st.heat.factorize_s},
        {"solve_s", st.heat.solve_s}}},
      {"unweighted_vertices", st.unweighted_vertices},
      {"output", args.output.empty() ? nlohmann::json(nullptr) : nlohmann::json(args.output)},
  };
  if (clip) {
    j["clip"] = {
        {"name", clip->clip},
        {"intervals", clip->intervals},
        {"mean_h_minus", clip->mean_h_minus},
        {"mean_h_uncertain", clip->mean_h_uncertain},
        {"max_h_minus", clip->max_h_minus},
        {"max_h_uncertain", clip->max_h_uncertain},
        {"seconds", clip->seconds}};
  } else {
    j["clip"] = nullptr;
  }
  return j;
}

void run_preprocess(const PreprocessArguments& args) {
  // Everything that can be refused is checked before anything is computed or written.
  const auto options = to_options(args);
  const std::filesystem::path model_path(args.model);
  if (!skinning::is_generator_spec(args.model)) require_exists(model_path);
  const auto model = skinning::load_model(model_path, args.load);
  if (!model.rig) {
    throw InvalidInput(
        args.model +
        ": preprocess needs a rigged model (a mesh with a skeleton); "
        "this is a " +
        skinning::to_string(model.kind));
  }
  const skinning::Rig& rig = *model.rig;
  std::unique_ptr<skinning::Motion> motion;
  if (!args.clip.empty()) {
    motion = model.motion(skinning::MotionRequest{.clip = args.clip, .rate_hz = args.fps});
  }
  const auto input_hash = model_identity(args.model);

  const auto s = seg::segment(rig, options);
  std::optional<seg::ClipOrientationStats> clip;
  if (motion) {
    try {
      clip = seg::clip_orientation_stats(s, *motion);
    } catch (const InvalidInput& e) {
      throw InvalidInput(args.model + ": --clip: " + e.what());
    }
  }

  if (!args.output.empty()) {
    SegmentationRecord record;
    record.skelcd_version = kVersion;
    record.input_path = args.model;
    record.input_hash = input_hash;
    record.bones = seg::bone_segments(rig.skeleton);
    for (const auto& b : rig.skeleton.bones) record.bone_names.push_back(b.name);
    record.clip = clip;
    write_segmentation(args.output, s, record);
  }
  if (args.json) {
    print_json(to_json(args, rig, s, clip));
  } else {
    print_text(args, rig, s, clip);
  }
}

}  // namespace

void add_preprocess_command(CLI::App& app) {
  auto args = std::make_shared<PreprocessArguments>();
  auto* cmd = app.add_subcommand(
      "preprocess",
      "Segmentation: bone weights, atomic clusters and observers; Table 1 statistics; saved to "
      "HDF5");
  cmd->add_option(
         "model",
         args->model,
         "rigged model file (glTF, FBX, Collada, .X, …) or generator spec (gen:rope?…)")
      ->required();
  cmd->add_option("--weights", args->weights, "heat (bone heat diffusion) or rig (the file's own)")
      ->capture_default_str();
  cmd->add_option(
         "--distance",
         args->distance,
         "heat visibility: exact (ray casts) or coarse (smoothed mesh, voxel field)")
      ->capture_default_str();
  cmd->add_option("--theta", args->theta, "observer test rotation, degrees")->capture_default_str();
  cmd->add_option("--clip", args->clip, "also average |H-| and |Hu| over this clip's intervals");
  add_rate_option(
      *cmd, "--fps", args->fps, "samples per second for --clip (default: its frame rate, else 30)");
  cmd->add_option("--grid", args->grid, "coarse distance: voxels along the longest side")
      ->capture_default_str();
  cmd->add_flag("--no-refine", args->no_refine, "skip the cluster refinement (RVBC's plain split)");
  cmd->add_option("-o,--output", args->output, "write the segmentation here (SEG.h5)");
  cmd->add_flag("--json", args->json, "print the statistics as one JSON object");
  add_model_options(*cmd, args->load);
  cmd->callback([args] { run_preprocess(*args); });
}

}  // namespace skelcd::tools
