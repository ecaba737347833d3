#pragma once
// Motion: positions of a mesh at samples i = 0 … N-1 — the one interface every later stage reads
// positions through, whatever moves the mesh (a skinned clip, a robot trajectory, a frame sequence).

#include <memory>
#include <string>

#include "skinning/mesh.hpp"

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
};

}  // namespace skelcd::skinning
