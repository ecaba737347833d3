#include "skinning/rig.hpp"

#include <cmath>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::skinning {
namespace {

// Weight rows and quaternions are normalised at import in double precision; what is left is
// rounding of a few operations, far below this. A row that misses it by more was not normalised.
constexpr double kNormalisedTolerance = 1e-9;

bool finite_transform(const Eigen::Affine3d& t) { return t.matrix().allFinite(); }

std::string where(const Rig& rig) { return rig.source.empty() ? std::string("rig") : rig.source; }

void check_keys(
    const Rig& rig,
    const Clip& clip,
    const std::vector<double>& times,
    std::size_t values,
    const char* what,
    std::int32_t node) {
  const auto fail = [&](const std::string& fault) {
    throw InvalidInput(where(rig) + ": clip '" + clip.name + "', node '" +
                       rig.skeleton.nodes[static_cast<std::size_t>(node)].name + "', " + what + " " +
                       fault);
  };
  if (times.size() != values) fail("has " + std::to_string(times.size()) + " times for " + std::to_string(values) + " values");
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (!std::isfinite(times[k])) fail("key " + std::to_string(k) + " has a non-finite time");
    if (k > 0 && !(times[k] > times[k - 1])) fail("key " + std::to_string(k) + " is not after key " + std::to_string(k - 1));
  }
}

// Frame rates of film, video and game animation (FBX SDK time modes, 12 and 15 fps), in Hz.
constexpr double kStandardFrameRates[] = {
    12.0,
    15.0,
    24000.0 / 1001.0,
    24.0,
    25.0,
    30000.0 / 1001.0,
    30.0,
    48.0,
    50.0,
    60000.0 / 1001.0,
    60.0,
    72.0,
    96.0,
    100.0,
    120000.0 / 1001.0,
    120.0};
// Every gap within this of the mean gap (relative): float32 key times (glTF) near t = 100 s are
// 8e-6 s apart, 1e-3 of a 1/120 s gap; a near-duplicate key or a missing frame is off by 50 % or
// more.
constexpr double kGridGapTolerance = 1e-2;
// The mean gap's rate within this of a standard rate (relative): 23.976 and 24 differ by 1e-3; the
// mean over the whole span is exact to float32 rounding of its two ends.
constexpr double kGridRateTolerance = 2e-4;

}  // namespace

const char* to_string(FrameRateSource source) {
  switch (source) {
    case FrameRateSource::none:
      return "default";
    case FrameRateSource::file:
      return "file";
    case FrameRateSource::key_grid:
      return "key_grid";
    case FrameRateSource::trajectory_rows:
      return "trajectory_rows";
    case FrameRateSource::frame_sequence:
      return "frame_sequence";
    case FrameRateSource::generator:
      return "generator";
  }
  return "?";
}

const char* describe(FrameRateSource source) {
  switch (source) {
    case FrameRateSource::none:
      return "default: no frame rate in the file";
    case FrameRateSource::file:
      return "the file's frame rate";
    case FrameRateSource::key_grid:
      return "evenly spaced keys at a standard frame rate";
    case FrameRateSource::trajectory_rows:
      return "the trajectory's rows per second";
    case FrameRateSource::frame_sequence:
      return "one sample per frame";
    case FrameRateSource::generator:
      return "the generator's frames";
  }
  return "?";
}

double key_grid_frame_rate(const std::vector<double>& key_times) {
  const std::size_t n = key_times.size();
  if (n < 3) return 0.0;
  const double span = key_times.back() - key_times.front();
  if (!(span > 0) || !std::isfinite(span)) return 0.0;
  const double gap = span / static_cast<double>(n - 1);
  for (std::size_t k = 1; k < n; ++k) {
    if (!(std::abs(key_times[k] - key_times[k - 1] - gap) <= kGridGapTolerance * gap)) return 0.0;
  }
  const double rate = 1.0 / gap;
  for (const double standard : kStandardFrameRates) {
    if (std::abs(rate - standard) <= kGridRateTolerance * standard) return standard;
  }
  return 0.0;
}

void validate_rig(const Rig& rig) {
  const auto src = where(rig);
  validate_mesh(rig.mesh, src);
  const auto& nodes = rig.skeleton.nodes;
  const auto nn = static_cast<std::int32_t>(nodes.size());

  // Hierarchy: parents precede children, so it is a forest (no cycle can be written this way).
  for (std::int32_t i = 0; i < nn; ++i) {
    const auto& node = nodes[static_cast<std::size_t>(i)];
    if (node.parent < -1 || node.parent >= i) {
      throw InvalidInput(src + ": node " + std::to_string(i) + " ('" + node.name + "') has parent " +
                         std::to_string(node.parent) + ", which does not precede it (cycle or bad index)");
    }
    if (!finite_transform(node.rest_local)) {
      throw InvalidInput(src + ": node " + std::to_string(i) + " ('" + node.name + "') has a non-finite transform");
    }
  }
  if (!finite_transform(rig.skeleton.root_transform)) throw InvalidInput(src + ": root transform is not finite");

  const auto nb = rig.skeleton.num_bones();
  for (std::int32_t b = 0; b < nb; ++b) {
    const auto& bone = rig.skeleton.bones[static_cast<std::size_t>(b)];
    const auto name = "bone " + std::to_string(b) + " ('" + bone.name + "')";
    if (bone.node < 0 || bone.node >= nn) throw InvalidInput(src + ": " + name + " has node " + std::to_string(bone.node) + " out of range");
    if (bone.parent < -1 || bone.parent >= nb || bone.parent == b) {
      throw InvalidInput(src + ": " + name + " has parent bone " + std::to_string(bone.parent) + " out of range");
    }
    if (!finite_transform(bone.inverse_bind) || !bone.rest_head.allFinite() || !bone.rest_tail.allFinite()) {
      throw InvalidInput(src + ": " + name + " has a non-finite inverse bind matrix or rest segment");
    }
  }

  // Weights: #V × #B, non-negative, finite, rows summing to 1 or empty.
  const auto& w = rig.weights;
  if (w.rows() != rig.mesh.num_vertices() || w.cols() != nb) {
    throw InvalidInput(src + ": weights are " + std::to_string(w.rows()) + " x " + std::to_string(w.cols()) +
                       ", expected " + std::to_string(rig.mesh.num_vertices()) + " x " + std::to_string(nb));
  }
  for (Eigen::Index v = 0; v < w.outerSize(); ++v) {
    double sum = 0;
    bool any = false;
    for (SkinWeights::InnerIterator it(w, v); it; ++it) {
      if (!std::isfinite(it.value()) || it.value() < 0) {
        throw InvalidInput(src + ": vertex " + std::to_string(v) + " has weight " + std::to_string(it.value()) +
                           " for bone " + std::to_string(it.col()));
      }
      sum += it.value();
      any = true;
    }
    if (any && std::abs(sum - 1.0) > kNormalisedTolerance) {
      throw InvalidInput(src + ": weights of vertex " + std::to_string(v) + " sum to " + std::to_string(sum) + ", not 1");
    }
  }

  if (!rig.part_attachments.empty()) {
    if (static_cast<std::int32_t>(rig.part_attachments.size()) != rig.mesh.num_parts()) {
      throw InvalidInput(src + ": " + std::to_string(rig.part_attachments.size()) + " part attachments for " +
                         std::to_string(rig.mesh.num_parts()) + " parts");
    }
    for (std::size_t p = 0; p < rig.part_attachments.size(); ++p) {
      const auto& a = rig.part_attachments[p];
      if (a.node < -1 || a.node >= nn || !finite_transform(a.inverse_bind)) {
        throw InvalidInput(src + ": part " + std::to_string(p) + " is attached to node " + std::to_string(a.node) +
                           " (out of range or non-finite transform)");
      }
    }
  }

  for (const auto& clip : rig.clips) {
    if (!(clip.duration_s >= 0) || !std::isfinite(clip.duration_s)) {
      throw InvalidInput(src + ": clip '" + clip.name + "' has duration " + std::to_string(clip.duration_s));
    }
    if (!(clip.frame_rate_hz >= 0) || !std::isfinite(clip.frame_rate_hz)) {
      throw InvalidInput(
          src + ": clip '" + clip.name + "' has frame rate " + std::to_string(clip.frame_rate_hz));
    }
    for (const auto& ch : clip.channels) {
      if (ch.node < 0 || ch.node >= nn) {
        throw InvalidInput(src + ": clip '" + clip.name + "' has a channel for node " + std::to_string(ch.node) + " out of range");
      }
      check_keys(rig, clip, ch.translation_times, ch.translations.size(), "translation", ch.node);
      check_keys(rig, clip, ch.rotation_times, ch.rotations.size(), "rotation", ch.node);
      check_keys(rig, clip, ch.scale_times, ch.scales.size(), "scale", ch.node);
      const auto node_name = nodes[static_cast<std::size_t>(ch.node)].name;
      for (const auto& t : ch.translations) {
        if (!t.allFinite()) throw InvalidInput(src + ": clip '" + clip.name + "', node '" + node_name + "' has a non-finite translation key");
      }
      for (const auto& s : ch.scales) {
        if (!s.allFinite()) throw InvalidInput(src + ": clip '" + clip.name + "', node '" + node_name + "' has a non-finite scale key");
      }
      for (const auto& q : ch.rotations) {
        if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > kNormalisedTolerance) {
          throw InvalidInput(src + ": clip '" + clip.name + "', node '" + node_name + "' has a rotation key that is not a unit quaternion");
        }
      }
    }
  }
}

}  // namespace skelcd::skinning
