#include "tools/report/segmentation_colors.hpp"

#include <cmath>
#include <string>

#include "segmentation/observer.hpp"
#include "skinning/errors.hpp"
#include "tools/io/segmentation_file.hpp"

namespace skelcd::tools {
namespace {

// HSV (s = 0.65, value v) → RGB for hue h in [0, 1).
std::array<float, 4> hue_color(double h, double v) {
  const double s = 0.65;
  const double sector = h * 6.0;
  const int i = static_cast<int>(std::floor(sector)) % 6;
  const double f = sector - std::floor(sector);
  const double p = v * (1 - s);
  const double q = v * (1 - s * f);
  const double u = v * (1 - s * (1 - f));
  double r = v, g = u, b = p;
  switch (i) {
    case 0:
      r = v;
      g = u;
      b = p;
      break;
    case 1:
      r = q;
      g = v;
      b = p;
      break;
    case 2:
      r = p;
      g = v;
      b = u;
      break;
    case 3:
      r = p;
      g = q;
      b = v;
      break;
    case 4:
      r = u;
      g = p;
      b = v;
      break;
    default:
      r = v;
      g = p;
      b = q;
      break;
  }
  return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b), 1.0f};
}

}  // namespace

SegmentationColors segmentation_colors(
    const std::filesystem::path& path, const skinning::Mesh& mesh) {
  const SegmentationFile file = read_segmentation(path);
  const auto& cluster_of = file.segmentation.triangle_cluster;
  if (static_cast<std::int64_t>(cluster_of.size()) != mesh.num_triangles()) {
    throw InvalidInput(
        path.string() + ": segmentation has " + std::to_string(cluster_of.size()) +
        " triangles, the model has " + std::to_string(mesh.num_triangles()));
  }
  const auto num_clusters = file.segmentation.clusters.size();
  constexpr double kGoldenRatioConjugate = 0.6180339887498949;
  SegmentationColors out;
  out.face_colors.resize(cluster_of.size());
  for (std::size_t f = 0; f < cluster_of.size(); ++f) {
    const auto c = cluster_of[f];
    if (c < 0 || static_cast<std::size_t>(c) >= num_clusters) {
      throw InvalidInput(
          path.string() + ": triangle " + std::to_string(f) + " names cluster " +
          std::to_string(c) + " of " + std::to_string(num_clusters));
    }
    // Welding merges only equal positions, so the file's rest positions and triangles are the
    // welded geometry the segmentation classified.
    const auto& observer = file.segmentation.clusters[static_cast<std::size_t>(c)].observer;
    const bool positive =
        segmentation::orientation(
            observer, mesh.rest_positions, mesh.triangles, static_cast<Eigen::Index>(f)) ==
        segmentation::Orientation::positive;
    if (!positive) out.non_positive.push_back(static_cast<std::int32_t>(f));
    const double h = std::fmod(static_cast<double>(c) * kGoldenRatioConjugate, 1.0);
    out.face_colors[f] = hue_color(h, positive ? kPositiveValue : kNonPositiveValue);
  }
  return out;
}

std::vector<std::array<float, 4>> segmentation_face_colors(
    const std::filesystem::path& path, const skinning::Mesh& mesh) {
  return segmentation_colors(path, mesh).face_colors;
}

}  // namespace skelcd::tools
