// export --segmentation: one colour per atomic cluster of a file written by `skelcd preprocess`.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/segmentation_file.hpp"
#include "tools/report/segmentation_colors.hpp"

namespace skelcd::tools {
namespace {

using skelcd::test::run_skelcd;

// RiggedFigure has no non-positive triangle in its rest pose; BCN_Epileptic has a few hundred.
class SegmentationColorsReal : public ::testing::TestWithParam<const char*> {};

INSTANTIATE_TEST_SUITE_P(Characters, SegmentationColorsReal,
                         ::testing::Values("RiggedFigure", "BCN_Epileptic"));

TEST_P(SegmentationColorsReal, OneColourPerClusterAndNonPositiveTrianglesDark) {
  const std::string name = GetParam();
  const auto dir = skelcd::test::temp_dir("segmentation_colors_real");
  const auto model = name == "BCN_Epileptic" ? skelcd::test::assimp_model("X/BCN_Epileptic.X")
                                             : skelcd::test::asset("characters/RiggedFigure.glb");
  const auto seg = dir / "seg.h5";
  const auto r = run_skelcd({"preprocess", model.string(), "-o", seg.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const auto loaded = skinning::load_model(model);
  const auto colors = segmentation_face_colors(seg, *loaded.mesh);
  const auto file = read_segmentation(seg);
  ASSERT_EQ(colors.size(), file.segmentation.triangle_cluster.size());

  // Same cluster and same orientation ⇒ same colour; as many distinct colours as (cluster,
  // orientation) classes used.
  const auto marked = segmentation_colors(seg, *loaded.mesh);
  ASSERT_EQ(marked.face_colors, colors);
  std::set<std::int32_t> non_positive(marked.non_positive.begin(), marked.non_positive.end());
  std::map<std::pair<std::int32_t, bool>, std::array<float, 4>> color_of_class;
  std::set<std::array<float, 4>> distinct;
  std::set<std::int32_t> clusters;
  for (std::size_t f = 0; f < colors.size(); ++f) {
    const auto c = file.segmentation.triangle_cluster[f];
    clusters.insert(c);
    const bool dark = non_positive.count(static_cast<std::int32_t>(f)) > 0;
    const auto [it, inserted] = color_of_class.emplace(std::make_pair(c, dark), colors[f]);
    if (!inserted) {
      EXPECT_EQ(it->second, colors[f]) << "triangle " << f;
    }
    distinct.insert(colors[f]);
  }
  EXPECT_GT(clusters.size(), 1u);
  EXPECT_EQ(distinct.size(), color_of_class.size());

  // The marked triangles are the rest-pose |H⁻| + |Hᵘ| that preprocess counted.
  EXPECT_EQ(static_cast<std::int64_t>(marked.non_positive.size()),
            file.segmentation.stats.h_minus + file.segmentation.stats.h_uncertain);
  // Independently, in plain doubles: where the triple product is far from zero, its sign says
  // whether the triangle is marked; the dark shade is darker than the bright one.
  const auto& mesh = *loaded.mesh;
  std::int64_t decided = 0;
  for (Eigen::Index f = 0; f < mesh.num_triangles(); ++f) {
    const auto& observer =
        file.segmentation.clusters[static_cast<std::size_t>(file.segmentation.triangle_cluster[static_cast<std::size_t>(f)])]
            .observer;
    const Eigen::Vector3d a = mesh.rest_positions.row(mesh.triangles(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.rest_positions.row(mesh.triangles(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.rest_positions.row(mesh.triangles(f, 2)).transpose();
    const Eigen::Vector3d q = observer.viewing_position(a);
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double det = (a - q).dot(n);
    if (std::abs(det) <= 1e-9 * (a - q).norm() * n.norm()) continue;
    ++decided;
    const bool dark = non_positive.count(static_cast<std::int32_t>(f)) > 0;
    EXPECT_EQ(dark, det < 0) << "triangle " << f << " det " << det;
    const auto& col = colors[static_cast<std::size_t>(f)];
    const float value = std::max({col[0], col[1], col[2]});
    EXPECT_NEAR(value, dark ? kNonPositiveValue : kPositiveValue, 1e-6) << "triangle " << f;
  }
  EXPECT_GT(decided, mesh.num_triangles() * 9 / 10);
  if (name == "BCN_Epileptic") {
    EXPECT_GT(marked.non_positive.size(), 100u) << "BCN_Epileptic's rest pose has H⁻ triangles";
  }

  const auto out = dir / "clusters.ply";
  const auto e = run_skelcd({"export", model.string(), "--segmentation", seg.string(), "-o", out.string()});
  EXPECT_EQ(e.exit_code, 0) << e.err;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_NE(e.out.find(std::to_string(marked.non_positive.size()) + " triangles not positively oriented"),
            std::string::npos)
      << e.out;
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
