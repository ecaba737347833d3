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
  /// Conservative only: the solver reports a contact once it has proven that the primitives come
  /// within min_separation + relative_distance_tolerance * extent (+ the rounding bound), where
  /// extent is the largest coordinate difference between the query's points at t = 0 or t = 1.
  /// Unitless. Smaller values give fewer false positives on near misses and cost more boxes.
  double relative_distance_tolerance = 1e-10;
  /// Conservative only: after the coplanarity stage, reject queries whose relative boxes are apart
  /// (the points minus their mean motion; docs/ccd.md, "Relative boxes"). It only removes queries
  /// that never come within min_separation — never a contact — and pays where features move
  /// together and lie close to coplanar (cloth layers). Off by default, so that the kernel alone
  /// answers as it always has; the culling methods turn it on.
  bool relative_boxes = false;
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

/// How many queries each stage of the pipeline saw and removed (DESIGN.md: every method reports
/// what it culled and what it tested). Filled by the overloads of vertex_face_ccd / edge_edge_ccd
/// that take a CcdStats; the filter counters move only for the conservative accuracy.
struct CcdStats {
  std::int64_t queries = 0;               ///< queries answered
  std::int64_t aabb_rejected = 0;         ///< removed by the swept-AABB filter
  std::int64_t coplanarity_rejected = 0;  ///< removed by the deforming non-penetration filter
  std::int64_t relative_rejected =
      0;  ///< removed by the relative boxes (CcdOptions::relative_boxes)
  std::int64_t algebraic_rejected = 0;    ///< proven separated by the algebraic filter
  std::int64_t algebraic_hits = 0;        ///< proven in contact by the algebraic filter
  std::int64_t solver_runs = 0;           ///< queries the filters left to the inclusion solver
  std::int64_t solver_rejected = 0;       ///< of those, proven separated by the solver
  std::int64_t solver_boxes = 0;          ///< (t, u, v) boxes the solver examined (its work)
  std::int64_t iteration_limit = 0;       ///< solver runs stopped by max_iterations (reported hit)
  std::int64_t hits = 0;                  ///< queries answered hit == true

  CcdStats& operator+=(const CcdStats& other) {
    queries += other.queries;
    aabb_rejected += other.aabb_rejected;
    coplanarity_rejected += other.coplanarity_rejected;
    relative_rejected += other.relative_rejected;
    algebraic_rejected += other.algebraic_rejected;
    algebraic_hits += other.algebraic_hits;
    solver_runs += other.solver_runs;
    solver_rejected += other.solver_rejected;
    solver_boxes += other.solver_boxes;
    iteration_limit += other.iteration_limit;
    hits += other.hits;
    return *this;
  }
};

}  // namespace skelcd::ccd
