#include "tools/segmentation_colors.hpp"

#include <cmath>
#include <string>

#include "skinning/errors.hpp"
#include "tools/segmentation_file.hpp"

namespace skelcd::tools {
namespace {

// HSV (s = 0.65, v = 0.95) → RGB for hue h in [0, 1).
std::array<float, 4> hue_color(double h) {
  const double s = 0.65;
  const double v = 0.95;
  const double sector = h * 6.0;
  const int i = static_cast<int>(std::floor(sector)) % 6;
  const double f = sector - std::floor(sector);
  const double p = v * (1 - s);
  const double q = v * (1 - s * f);
  const double u = v * (1 - s * (1 - f));
  double r = v, g = u, b = p;
  switch (i) {
    case 0: r = v; g = u; b = p; break;
    case 1: r = q; g = v; b = p; break;
    case 2: r = p; g = v; b = u; break;
    case 3: r = p; g = q; b = v; break;
    case 4: r = u; g = p; b = v; break;
    default: r = v; g = p; b = q; break;
  }
  return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b), 1.0f};
}

}  // namespace

std::vector<std::array<float, 4>> segmentation_face_colors(
    const std::filesystem::path& path,
    const skinning::Mesh& mesh) {
  const SegmentationFile file = read_segmentation(path);
  const auto& cluster_of = file.segmentation.triangle_cluster;
  if (static_cast<std::int64_t>(cluster_of.size()) != mesh.num_triangles()) {
    throw InvalidInput(path.string() + ": segmentation has " + std::to_string(cluster_of.size()) +
                       " triangles, the model has " + std::to_string(mesh.num_triangles()));
  }
  constexpr double kGoldenRatioConjugate = 0.6180339887498949;
  std::vector<std::array<float, 4>> colors(cluster_of.size());
  for (std::size_t f = 0; f < cluster_of.size(); ++f) {
    const double h = std::fmod(static_cast<double>(cluster_of[f]) * kGoldenRatioConjugate, 1.0);
    colors[f] = hue_color(h);
  }
  return colors;
}

}  // namespace skelcd::tools
