#pragma once
// How `rvbc` and `dynamic` are reached through culling::make_method: an extension
// (culling/method_extension.hpp) that holds what they need beyond the mesh — the segmentation and
// the bone poses of the interval — put into MethodOptions::extension by whoever has them (the
// `check` command, tests, a routed method forwarding its options).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "clustering/bone_poses.hpp"
#include "clustering/radial_view_method.hpp"
#include "culling/method_extension.hpp"
#include "segmentation/segmentation.hpp"

namespace skelcd::clustering {

/// Parameters of the radial-view methods chosen on the command line (`--gamma`, `--seed`).
struct RadialViewParameters {
  double gamma = 0.05;
  std::uint64_t seed = 1;
};

class RadialViewExtension final : public culling::MethodExtension {
 public:
  /// @param segmentation of the mesh the methods will be built for.
  /// @param poses selected before each query by the driver (BonePoses::select_samples).
  /// @param num_bones bones of the rig.
  /// @throws InvalidInput when gamma is not finite and in [0, 1], or an argument is null.
  RadialViewExtension(
      std::shared_ptr<const segmentation::Segmentation> segmentation,
      std::shared_ptr<const BonePoses> poses,
      std::int32_t num_bones,
      const RadialViewParameters& parameters = {});

  /// For runs that ask for DCD only: `rvbc` and `dynamic` answer DCD with `bvh` (radial view
  /// culls intervals, not instants), so nothing of the radial view is built — no segmentation,
  /// no bone poses. The methods it makes refuse CCD queries.
  [[nodiscard]] static std::shared_ptr<const RadialViewExtension> dcd_only(
      const RadialViewParameters& parameters = {});

  /// {"rvbc", "dynamic"}.
  [[nodiscard]] std::vector<std::string> method_names() const override;

  /// `rvbc` (fixed atomic clusters) or `dynamic` (mega clusters); null for any other name. From a
  /// dcd_only() extension: a method of that name that answers DCD with `bvh` and throws
  /// InvalidInput on a CCD query.
  [[nodiscard]] std::unique_ptr<culling::CullingMethod> make_method(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const culling::MethodOptions& options) const override;

  [[nodiscard]] const RadialViewParameters& parameters() const { return parameters_; }

  /// True for an extension made by dcd_only().
  [[nodiscard]] bool is_dcd_only() const { return segmentation_ == nullptr; }

 private:
  explicit RadialViewExtension(const RadialViewParameters& parameters);

  std::shared_ptr<const segmentation::Segmentation> segmentation_;
  std::shared_ptr<const BonePoses> poses_;
  std::int32_t num_bones_;
  RadialViewParameters parameters_;
};

/// True for "rvbc" and "dynamic".
[[nodiscard]] bool is_radial_view_method(std::string_view name);

}  // namespace skelcd::clustering
