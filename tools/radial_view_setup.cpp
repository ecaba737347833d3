#include "tools/radial_view_setup.hpp"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "clustering/bone_poses.hpp"
#include "clustering/radial_view_extension.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/rig_motion.hpp"
#include "tools/segmentation_file.hpp"

namespace skelcd::tools {

RadialViewSetup setup_radial_view(
    const RadialViewArguments& args,
    const skinning::LoadedModel& model,
    const skinning::Motion& motion,
    RunOptions& options) {
  RadialViewSetup setup;
  const std::string method = options.method;
  if (method == "auto") {
    // `auto` sends closed components to `dynamic` when the model is a rig played by its clip
    // (bones move the observers); otherwise they go to the `bvh` fallback.
    if (!model.rig || dynamic_cast<const skinning::RigMotion*>(&motion) == nullptr) return setup;
  } else if (!clustering::is_radial_view_method(method)) {
    return setup;
  }
  if (!(std::isfinite(args.gamma) && args.gamma >= 0.0 && args.gamma <= 1.0)) {
    throw InvalidInput("--gamma " + std::to_string(args.gamma) + ": expected a value in [0, 1]");
  }
  const clustering::RadialViewParameters parameters{.gamma = args.gamma, .seed = args.seed};
  // DCD only: rvbc/dynamic answer each instant with `bvh` (radial view culls intervals), so no
  // segmentation is read or computed (DESIGN.md, "compute only what is asked"); `auto` sends its
  // closed parts to its `bvh` fallback, which is the same answer.
  if (options.query == QuerySet::dcd) {
    setup.segmentation_source = "none (DCD only: no radial-view stage runs)";
    if (!args.segmentation.empty()) {
      std::cerr << "skelcd: note: " << args.segmentation
                << " is not used: --query dcd needs no segmentation\n";
    }
    if (method != "auto")
      options.method_extension = clustering::RadialViewExtension::dcd_only(parameters);
    if (method == "dynamic") {
      setup.gamma = args.gamma;
      setup.seed = static_cast<std::int64_t>(args.seed);
    }
    return setup;
  }
  if (!model.rig) {
    throw InvalidInput(
        "--method " + method + " needs a rigged model (bones move the observers): " +
        model.path.string() + " has no skeleton");
  }
  const auto* rig_motion = dynamic_cast<const skinning::RigMotion*>(&motion);
  if (rig_motion == nullptr) {
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
    (void)read_segmentation(args.segmentation);  // throws naming the file when it is no segmentation
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
    seg = std::make_shared<const segmentation::Segmentation>(segmentation::segment(*model.rig, o));
    setup.segmentation_source = o.weights == segmentation::WeightSource::rig
                                    ? "computed (rig weights)"
                                    : "computed (heat weights)";
  }
  setup.atomic_clusters = static_cast<std::int32_t>(seg->clusters.size());

  // Bone poses: the runner tells which samples each query spans.
  auto poses = std::make_shared<clustering::BonePoses>(clustering::pose_at_sample(*rig_motion));
  options.method_extension = std::make_shared<clustering::RadialViewExtension>(
      seg, poses, model.rig->skeleton.num_bones(), parameters);
  options.before_query = [poses](std::int32_t s0, std::int32_t s1) {
    poses->select_samples(s0, s1);
  };
  // A parallel run (RunOptions::threads) gives every extra worker its own bone poses.
  options.make_worker_hooks = [seg,
                               rig_motion,
                               num_bones = model.rig->skeleton.num_bones(),
                               parameters] {
    auto own = std::make_shared<clustering::BonePoses>(clustering::pose_at_sample(*rig_motion));
    return WorkerHooks{
        .method_extension =
            std::make_shared<clustering::RadialViewExtension>(seg, own, num_bones, parameters),
        .before_query = [own](std::int32_t s0, std::int32_t s1) { own->select_samples(s0, s1); }};
  };
  if (method == "dynamic" || method == "auto") {
    setup.gamma = args.gamma;
    setup.seed = static_cast<std::int64_t>(args.seed);
  }
  return setup;
}

}  // namespace skelcd::tools
