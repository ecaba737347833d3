// A method added by its own file only: this file registers `test-wrapped-bvh` (a `bvh` under
// another name that `auto` may choose for closed parts of a rig's clip) and nothing else in the
// project names it. It must then appear in `check --help`, in `bench`'s default table, in the
// methods a scene accepts, among `auto`'s choices, and run through `check` like any method.
// Its own test executable (tools/CMakeLists.txt), so the registration reaches no other test.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <string>

#include "culling/method_registry.hpp"
#include "culling/routed_method.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tools/cli/commands.hpp"
#include "tools/engine/check_engine.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/scene.hpp"
#include "tools/report/bench_report.hpp"

namespace skelcd {
namespace {

class WrappedBvh final : public culling::CullingMethod {
 public:
  explicit WrappedBvh(std::unique_ptr<culling::CullingMethod> bvh) : bvh_(std::move(bvh)) {}
  [[nodiscard]] std::string_view name() const override { return "test-wrapped-bvh"; }

 protected:
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    bvh_->detect_dcd(at, out);
  }
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    ++intervals_with_bones;
    if (interval.bones_t0.empty() || interval.bones_t1.empty()) ++intervals_without_bones;
    bvh_->detect_ccd(interval, out);
  }

 public:
  static inline int intervals_with_bones = 0;
  static inline int intervals_without_bones = 0;

 private:
  std::unique_ptr<culling::CullingMethod> bvh_;
};

[[maybe_unused]] const bool registered = culling::register_method(
    {.name = "test-wrapped-bvh",
     .description = "a bvh registered by tests/tools/test_method_registry.cpp",
     .needs = {.bone_poses = true},
     // Above `dynamic` (10): on a rig's clip `auto` sends closed parts here.
     .route = culling::RouteKind::closed,
     .route_priority = 20,
     .order = 90,
     .make = [](const skinning::Mesh& mesh,
                const skinning::Topology& topology,
                const culling::MethodOptions& options) {
       return std::make_unique<WrappedBvh>(culling::make_method("bvh", mesh, topology, options));
     }});

constexpr const char* kName = "test-wrapped-bvh";

TEST(MethodRegistry, AMethodOfItsOwnFileAppearsInHelp) {
  CLI::App app{"skelcd", "skelcd"};
  tools::add_check_command(app);
  tools::add_bench_command(app);
  EXPECT_NE(
      app.get_subcommand("check")->help().find(std::string(kName) + ": a bvh registered by"),
      std::string::npos);
  EXPECT_NE(app.get_subcommand("bench")->help().find(kName), std::string::npos);
}

TEST(MethodRegistry, AMethodOfItsOwnFileIsAcceptedByScenesAndChecks) {
  const auto names = tools::scene_method_names();
  EXPECT_NE(std::find(names.begin(), names.end(), kName), names.end());
  const auto scene = tools::parse_scene_text(
      "[objects.man]\nmodel = \"../characters/CesiumMan.glb\"\nchecks = [\"self-ccd\"]\nmethod = "
      "\"test-wrapped-bvh\"\n",
      test::asset("scenes/registry.toml"));
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].method, kName);

  // Through the check engine: bvh's findings, and every interval carried the bones it needs.
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  tools::CheckRequest request;
  request.frames = tools::FrameRange{0, 4};
  request.method = kName;
  const int before = WrappedBvh::intervals_with_bones;
  const auto wrapped = tools::check_model(model, request);
  EXPECT_EQ(wrapped.method, kName);
  EXPECT_EQ(WrappedBvh::intervals_with_bones - before, 4);
  EXPECT_EQ(WrappedBvh::intervals_without_bones, 0);
  request.method = "bvh";
  const auto bvh = tools::check_model(model, request);
  ASSERT_EQ(wrapped.rows.size(), bvh.rows.size());
  for (std::size_t i = 0; i < bvh.rows.size(); ++i) {
    EXPECT_EQ(wrapped.rows[i].counters.dcd_pairs, bvh.rows[i].counters.dcd_pairs) << i;
    EXPECT_EQ(wrapped.rows[i].counters.vf_contacts, bvh.rows[i].counters.vf_contacts) << i;
    EXPECT_EQ(wrapped.rows[i].counters.ee_contacts, bvh.rows[i].counters.ee_contacts) << i;
  }
}

TEST(MethodRegistry, AMethodOfItsOwnFileIsAmongAutosChoicesAndInBench) {
  // `auto` on a rig's clip: closed parts to the highest-priority closed-part method whose needs
  // are met — this one (bones only), even without a segmentation.
  culling::MethodOptions with_bones;
  with_bones.num_bones = 19;
  EXPECT_EQ(culling::auto_group_methods(with_bones).back(), kName);
  EXPECT_EQ(culling::auto_group_methods({}).back(), "bvh");
  // CesiumMan is closed throughout: `auto` hands it whole to `bvh`
  // (culling::RoutingOptions::all_closed_method), and this method is not built for it
  // (tests/culling/test_routing.cpp routes a mesh with open parts to a registered one).
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  tools::CheckRequest request;
  request.frames = tools::FrameRange{0, 2};
  request.method = "auto";
  request.log_path = (test::temp_dir("registry-auto") / "auto.h5").string();
  const int before = WrappedBvh::intervals_with_bones;
  const auto outcome = tools::check_model(model, request);
  EXPECT_EQ(outcome.method, "auto");
  EXPECT_EQ(WrappedBvh::intervals_with_bones, before);
  EXPECT_GT(outcome.rows.size(), 0u);

  // bench's default table on a rig's clip has a row for it.
  tools::BenchOptions options;
  options.run.frames = tools::FrameRange{0, 2};
  options.run.query = tools::QuerySet::ccd;
  options.accuracies = {ccd::Accuracy::conservative};
  options.radial_view = true;
  const auto motion = model.motion();
  // As `skelcd bench` does: the methods that need a segmentation get one.
  options.prepare = [&](tools::RunOptions& run) {
    (void)tools::setup_radial_view({}, model, *motion, run);
  };
  const auto report = tools::run_bench(*motion, options);
  const bool listed =
      std::any_of(report.rows.begin(), report.rows.end(), [](const tools::BenchRow& r) {
        return r.method == kName;
      });
  EXPECT_TRUE(listed);
}

}  // namespace
}  // namespace skelcd
