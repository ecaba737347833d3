#pragma once
// The culling method interface (a run-time choice, DESIGN.md "Methods"): a method is built once for
// a mesh's topology and then answers, per instant (DCD) or per interval (CCD), which primitive pairs
// collide — through the shared elementary tests of ccd/ at the requested accuracy.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

struct MethodOptions {
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  /// Contact distance (coordinate units); 0 = touching counts.
  double min_separation = 0.0;
};

class CullingMethod {
 public:
  virtual ~CullingMethod() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;

  /// Intersecting non-adjacent triangle pairs at one instant.
  /// @param x #W × 3 welded positions.
  /// @param out cleared by the caller; filled with dcd_pairs, counters and times.
  virtual void detect_dcd(const skinning::Positions& x, FrameResult& out) = 0;

  /// VF and EE contacts over the interval with linear motion from x_t0 to x_t1.
  /// @param x_t0,x_t1 #W × 3 welded positions at the interval's ends.
  virtual void detect_ccd(
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      FrameResult& out) = 0;
};

/// Names of the methods available now, in the order `bench` lists them.
[[nodiscard]] std::vector<std::string> method_names();

/// Builds method `name` for `mesh` / `topology` (which must outlive it).
/// @throws InvalidInput for an unknown name (the message lists the known ones).
[[nodiscard]] std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

}  // namespace skelcd::culling
