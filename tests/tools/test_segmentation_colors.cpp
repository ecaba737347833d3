// export --segmentation: one colour per atomic cluster of a file written by `skelcd preprocess`.

#include "tools/segmentation_colors.hpp"

#include <array>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/segmentation_file.hpp"

namespace skelcd::tools {
namespace {

using skelcd::test::run_skelcd;

TEST(SegmentationColors, OneColourPerClusterOnARealCharacter) {
  const auto dir = skelcd::test::temp_dir("segmentation_colors_real");
  const auto model = skelcd::test::asset("characters/RiggedFigure.glb");
  const auto seg = dir / "seg.h5";
  const auto r = run_skelcd({"preprocess", model.string(), "-o", seg.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const auto loaded = skinning::load_model(model);
  const auto colors = segmentation_face_colors(seg, *loaded.mesh);
  const auto file = read_segmentation(seg);
  ASSERT_EQ(colors.size(), file.segmentation.triangle_cluster.size());

  // Same cluster ⇒ same colour, and as many distinct colours as clusters used.
  std::map<std::int32_t, std::array<float, 4>> color_of_cluster;
  std::set<std::array<float, 4>> distinct;
  for (std::size_t f = 0; f < colors.size(); ++f) {
    const auto c = file.segmentation.triangle_cluster[f];
    const auto [it, inserted] = color_of_cluster.emplace(c, colors[f]);
    if (!inserted) {
      EXPECT_EQ(it->second, colors[f]) << "triangle " << f;
    }
    distinct.insert(colors[f]);
  }
  EXPECT_GT(color_of_cluster.size(), 1u);
  EXPECT_EQ(distinct.size(), color_of_cluster.size());

  const auto out = dir / "clusters.ply";
  const auto e = run_skelcd({"export", model.string(), "--segmentation", seg.string(), "-o", out.string()});
  EXPECT_EQ(e.exit_code, 0) << e.err;
  EXPECT_TRUE(std::filesystem::exists(out));
}

TEST(SegmentationColors, AnotherModelsSegmentationIsRefused) {
  const auto dir = skelcd::test::temp_dir("segmentation_colors_mismatch");
  const auto seg = dir / "seg.h5";
  ASSERT_EQ(run_skelcd({"preprocess", skelcd::test::asset("characters/RiggedFigure.glb").string(),
                        "-o", seg.string()}).exit_code, 0);
  const auto fox = skelcd::test::asset("characters/Fox.glb");
  const auto loaded = skinning::load_model(fox);
  EXPECT_THROW_MESSAGE((void)segmentation_face_colors(seg, *loaded.mesh), InvalidInput, "segmentation has");

  const auto out = dir / "fox.ply";
  const auto e = run_skelcd({"export", fox.string(), "--segmentation", seg.string(), "-o", out.string()});
  EXPECT_NE(e.exit_code, 0);
  EXPECT_NE(e.err.find("seg.h5"), std::string::npos) << e.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace skelcd::tools
