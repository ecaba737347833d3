#include "tools/engine/radial_view_setup.hpp"

#include <tbb/global_control.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "culling/method_registry.hpp"
#include "culling/routed_method.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "tools/engine/runner.hpp"
#include "tools/io/segmentation_file.hpp"

namespace skelcd::tools {

std::string auto_whole_mesh_size() {
  return "under " + std::to_string(culling::RoutingOptions{}.all_closed_below_triangles) +
         " triangles";
}

std::string auto_open_size() {
  return std::to_string(culling::RoutingOptions{}.min_open_triangles) + " triangles";
}

std::optional<AutoWithoutSegmentation> auto_without_segmentation(
    const skinning::Topology& topology) {
  const culling::AutoGroups groups = culling::auto_groups(topology, /*rig=*/true);
  if (groups.whole) {
    const std::string size = auto_whole_mesh_size();
    return AutoWithoutSegmentation{
        .source =
            "none (auto: every part closed, small or capped, " + size + ", the whole mesh to bvh)",
        .why = "auto sends a mesh " + size + " whose every part is closed, small or capped to bvh"};
  }
  if (groups.closed_components == 0) {
    const std::string size = auto_open_size();
    return AutoWithoutSegmentation{
        .source = "none (auto: every part open, " + size + " or more and not capped, all to cones)",
        .why = "auto sends every part of this mesh to cones (each is open, has " + size +
               " or more and no hole dynamic caps)"};
  }
  return std::nullopt;
}

RadialViewSetup setup_radial_view(
    const RadialViewArguments& args,
    const skinning::LoadedModel& model,
    const skinning::Motion& motion,
    RunOptions& options,
    const skinning::Topology* topology) {
  RadialViewSetup setup;
  const std::string method = options.method;
  // Which methods of this run need a segmentation: the method itself, or `auto`'s choices once a
  // segmentation is there (it routes closed parts to `dynamic` only then).
  const culling::MethodInfo* info = culling::find_method(method);
  const bool needs = info != nullptr && info->needs.segmentation;
  if (method == "auto") {
    // `auto` sends closed components to a method that needs a segmentation only when the model is
    // a rig whose motion carries its bones; otherwise they go to the `bvh` fallback.
    if (!model.rig || motion.num_bones() == 0) return setup;
  } else if (!needs) {
    return setup;
  }
  if (!(std::isfinite(args.gamma) && args.gamma >= 0.0 && args.gamma <= 1.0)) {
    throw InvalidInput("--gamma " + std::to_string(args.gamma) + ": expected a value in [0, 1]");
  }
  options.method_parameters = culling::MethodParameters{.gamma = args.gamma, .seed = args.seed};
  const bool uses_parameters = method == "dynamic" || method == "auto";
  // DCD only: rvbc/dynamic answer each instant with `bvh` (radial view culls intervals), so no
  // segmentation is read or computed (DESIGN.md, "compute only what is asked"); `auto` sends its
  // closed parts to its `bvh` fallback, which is the same answer.
  if (options.query == QuerySet::dcd) {
    setup.segmentation_source = "none (DCD only: no radial-view stage runs)";
    if (!args.segmentation.empty()) {
      std::cerr << "skelcd: note: " << args.segmentation
                << " is not used: --query dcd needs no segmentation\n";
    }
    if (method == "dynamic") {
      setup.gamma = args.gamma;
      setup.seed = static_cast<std::int64_t>(args.seed);
    }
    return setup;
  }
  // Nor when every part is closed, small (under 256 triangles: auto_open_size()) or open only at
  // holes the radial view would cap, in a mesh under 20,000 triangles: `auto` then sends the whole
  // mesh to `bvh` (culling::RoutingOptions::all_closed_method, all_closed_below_triangles). Nor
  // when `auto` sends nothing to `dynamic`: every part open, of 256 triangles or more and not
  // capped (a garment on its own skeleton goes whole to the cones).
  if (method == "auto" && topology != nullptr) {
    if (auto skipped = auto_without_segmentation(*topology)) {
      setup.segmentation_source = std::move(skipped->source);
      if (!args.segmentation.empty()) {
        std::cerr << "skelcd: note: " << args.segmentation << " is not used: " << skipped->why
                  << "\n";
      }
      return setup;
    }
  }
  if (!model.rig) {
    throw InvalidInput(
        "--method " + method + " needs a rigged model (bones move the observers): " +
        model.path.string() + " has no skeleton");
  }
  if (motion.num_bones() == 0) {
    throw InvalidInput("--method " + method + ": " + motion.name() + " is not a rig's clip");
  }

  // The segmentation: the preprocess file when given and made from this very model, else
  // computed now with the rig's own weights (fast; `preprocess` offers heat weights).
  std::shared_ptr<const segmentation::Segmentation> seg;
  // A readable segmentation of another model (or of an older version of this file) is not used:
  // the model is segmented anew, and the user is told why. A missing or damaged file is an error.
  bool reuse = !args.segmentation.empty();
  if (reuse && std::filesystem::exists(args.segmentation) &&
      !segmentation_matches(args.segmentation, model.path.string())) {
    (void)read_segmentation(
        args.segmentation);  // throws naming the file when it is no segmentation
    std::cerr << "skelcd: note: " << args.segmentation << " was made from another model than "
              << model.path.string() << " (input hash differs); segmenting it anew\n";
    reuse = false;
  }
  if (reuse) {
    auto file = read_segmentation(args.segmentation, model.path);
    seg = std::make_shared<const segmentation::Segmentation>(std::move(file.segmentation));
    setup.segmentation_source = args.segmentation;
  } else {
    segmentation::SegmentationOptions o;
    o.weights = model.rig->weights.nonZeros() > 0 ? segmentation::WeightSource::rig
                                                  : segmentation::WeightSource::heat;
    // The caller's weld of the mesh when it is the rig's own (a rig's clip moves rig.mesh).
    const bool rig_mesh = topology != nullptr && &motion.mesh() == &model.rig->mesh;
    // On the threads the run asked for: segment_mesh splits its bones and clusters (from 20,000
    // triangles), and heat weights their solves, over oneTBB's threads, which would otherwise
    // take every core, `--threads 1` too (a second core for 8 of CesiumMan-dense's 44 ms;
    // docs/check.md "Threads"): on the calling thread alone when the run is serial, on at most
    // the run's threads otherwise.
    const auto threads = static_cast<std::size_t>(resolve_threads(options.threads));
    o.parallel = threads > 1;
    o.heat.parallel = threads > 1;
    const tbb::global_control threads_asked(tbb::global_control::max_allowed_parallelism, threads);
    seg = std::make_shared<const segmentation::Segmentation>(
        rig_mesh ? segmentation::segment(*model.rig, o, *topology)
                 : segmentation::segment(*model.rig, o));
    setup.segmentation_source = o.weights == segmentation::WeightSource::rig
                                    ? "computed (rig weights)"
                                    : "computed (heat weights)";
  }
  setup.atomic_clusters = static_cast<std::int32_t>(seg->clusters.size());
  // The bones' transforms travel with every query (the runner asks the motion for them).
  options.segmentation = std::move(seg);
  if (uses_parameters) {
    setup.gamma = args.gamma;
    setup.seed = static_cast<std::int64_t>(args.seed);
  }
  return setup;
}

}  // namespace skelcd::tools
