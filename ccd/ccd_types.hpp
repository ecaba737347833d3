#pragma once
// Options, result and status shared by the vertex-face and edge-edge CCD queries.

#include <cstdint>

namespace skelcd::ccd {

struct CcdOptions {
  /// Distance (same unit as the coordinates) at which primitives count as touching; 0 means
  /// actual contact. The `exact` accuracy supports only 0.
  double min_separation = 0.0;
  /// Width below which the time-of-impact interval [toi_lower, toi_upper] is not narrowed further
  /// (a fraction of the interval, unitless).
  double toi_tolerance = 1e-6;
  /// Upper bound on subdivision steps of the conservative solver; when reached the answer is
  /// "hit" (the safe side) with the widest interval still open.
  std::int64_t max_iterations = 1'000'000;
};

enum class CcdStatus : std::uint8_t {
  separated,        ///< proven to stay apart over [0,1]
  contact,          ///< contact found (or not excluded within the error bound)
  iteration_limit,  ///< conservative solver stopped at max_iterations; reported as a hit
};

struct CcdResult {
  bool hit = false;
  /// Time-of-impact interval in [0,1] (fraction of the interval); toi_lower <= the true first
  /// contact time. Both 1 when hit == false.
  double toi_lower = 1.0;
  double toi_upper = 1.0;
  CcdStatus status = CcdStatus::separated;
};

}  // namespace skelcd::ccd
