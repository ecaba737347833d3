#pragma once
// Motion: positions of a mesh at samples i = 0 … N-1 — the one interface every later stage reads
// positions through, whatever moves the mesh (a skinned clip, a robot trajectory, a frame sequence).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"

namespace skelcd::skinning {

class Motion {
 public:
  virtual ~Motion() = default;

  /// The mesh being moved; positions(i) has one row per mesh().rest_positions row.
  [[nodiscard]] virtual const Mesh& mesh() const = 0;
  /// Number of samples N (>= 1); the check runs N-1 intervals [i, i+1].
  [[nodiscard]] virtual int num_samples() const = 0;
  /// Time of sample i in seconds from the start of the clip.
  [[nodiscard]] virtual double sample_time(int i) const = 0;
  /// Human-readable name of what moves the mesh (clip name, trajectory file, sequence folder).
  [[nodiscard]] virtual std::string name() const = 0;
  /// Writes the #V × 3 positions at sample i into `out` (resized if needed).
  /// @pre 0 <= i < num_samples()
  virtual void positions(int i, Positions& out) const = 0;
  /// The positions at sample i of `vertices` only: row k of `out` is vertex vertices[k]'s row of
  /// positions(i), bit for bit (a check's welded positions: Topology::representative_vertex).
  /// The default poses every vertex into a per-thread buffer and copies the rows; a motion that can
  /// pose some vertices alone (a skinned rig) poses only those.
  /// @pre 0 <= i < num_samples(); every entry of `vertices` is in [0, mesh().num_vertices()).
  virtual void positions_of(int i, std::span<const std::int32_t> vertices, Positions& out) const {
    thread_local Positions all;
    positions(i, all);
    out.resize(static_cast<Eigen::Index>(vertices.size()), 3);
    for (std::size_t k = 0; k < vertices.size(); ++k) {
      out.row(static_cast<Eigen::Index>(k)) = all.row(vertices[k]);
    }
  }
  /// Sample i's positions where the motion holds them in memory as they are (a frame sequence
  /// whose frames it keeps), else nullptr: then a caller reads them there instead of copying them
  /// through positions(). Valid while the motion lives.
  /// @pre 0 <= i < num_samples()
  [[nodiscard]] virtual const Positions* held_positions(int i) const {
    (void)i;
    return nullptr;
  }

  /// Positions at time t (seconds). A motion defined between its samples (a rig's clip)
  /// evaluates it there (clamped to the clip); the others answer at a sample time only, within
  /// tolerance_s × max(1, t). Returns false, `out` untouched, when t is not such a time.
  [[nodiscard]] virtual bool positions_at(double t, Positions& out, double tolerance_s) const {
    for (int i = 0; i < num_samples(); ++i) {
      if (std::abs(sample_time(i) - t) <= tolerance_s * std::max(1.0, t)) {
        positions(i, out);
        return true;
      }
    }
    return false;
  }

  /// Samples per second. The default estimates it from the sample times ((N-1) / span; 0 for a
  /// single sample); motions that know their rate say it.
  [[nodiscard]] virtual double rate_hz() const {
    const int n = num_samples();
    if (n < 2) return 0.0;
    const double span = sample_time(n - 1) - sample_time(0);
    return span > 0 ? (n - 1) / span : 0.0;
  }

  /// Number of bones whose transforms move the mesh (0: no skeleton, e.g. a frame sequence).
  [[nodiscard]] virtual std::int32_t num_bones() const { return 0; }

  /// Writes the skinning transforms at sample i into `out` (Pose::transforms: the num_bones()
  /// bones first, posed global · inverse bind in object space, then any part attachments); empty
  /// when there is no skeleton.
  /// Thread-safe like positions().
  /// @pre 0 <= i < num_samples()
  virtual void bone_transforms(int i, std::vector<BoneTransform>& out) const {
    (void)i;
    out.clear();
  }
  /// The weights by which positions(i) is exactly linear_blend_skinning(mesh().rest_positions,
  /// weights, bone_transforms(i)) at every sample (#V × the transforms' count), else nullptr (a
  /// frame sequence; a motion that moves its vertices otherwise). Valid while the motion lives.
  [[nodiscard]] virtual const SkinWeights* skin_weights() const { return nullptr; }
};

}  // namespace skelcd::skinning
