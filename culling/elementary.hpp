#pragma once
// The elementary stage every method ends with: the VF / EE CCD tests of a set of feature pairs
// and the triangle-triangle DCD tests of a set of triangle pairs, through the ccd/ kernels (or
// substitutes: tests inject reference or counting implementations).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "ccd/accuracy.hpp"
#include "ccd/ccd_types.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/triangle_triangle.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/candidates.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// Below this many queries of one kind in one call the elementary tests stay on the calling thread
/// (splitting costs more than it saves).
inline constexpr std::size_t kParallelElementaryThreshold = 512;

/// Queries whose outcomes one call holds at once: a call over more tests them a window at a time,
/// so the scratch each calling thread keeps between calls stays this size (24 bytes a query)
/// whatever the largest call of the run.
inline constexpr std::size_t kElementaryOutcomeWindow = 8192;

/// The three elementary tests a method calls. A null member means "the ccd/ kernel".
struct ElementaryTests {
  using VertexFaceFn =
      ccd::CcdResult (*)(const ccd::VertexFaceQuery&, ccd::Accuracy, const ccd::CcdOptions&);
  using EdgeEdgeFn =
      ccd::CcdResult (*)(const ccd::EdgeEdgeQuery&, ccd::Accuracy, const ccd::CcdOptions&);
  using TrianglesFn = bool (*)(const ccd::TriangleTriangleQuery&, const ccd::SharedCorners&);
  VertexFaceFn vertex_face = nullptr;
  EdgeEdgeFn edge_edge = nullptr;
  TrianglesFn triangles = nullptr;
  /// Threads one call may split its queries over (oneTBB, inside the caller's task arena): 1 keeps
  /// every test on the calling thread. The results do not depend on it: each query's outcome has
  /// its own slot, gathered in candidate order and sorted as in a serial run.
  std::int32_t threads = 1;
  /// When set, the number of queries tested so far is added here as they finish (a block at a
  /// time), so that a caller can show progress inside one long query; read it, never reset it
  /// while tests run.
  std::atomic<std::int64_t>* tests_done = nullptr;
};

/// The CCD query of vertex `v` (positions xv_t0 → xv_t1) against triangle `f` (positions
/// xf_t0 → xf_t1). Within one object pass the same positions twice; across two objects (pair
/// checks) each side its own.
[[nodiscard]] ccd::VertexFaceQuery vertex_face_query(
    const skinning::Positions& xv_t0,
    const skinning::Positions& xv_t1,
    std::int32_t v,
    const skinning::Positions& xf_t0,
    const skinning::Positions& xf_t1,
    const std::array<std::int32_t, 3>& f);

/// The CCD query of edge `ea` (positions xa_t0 → xa_t1) against edge `eb` (xb_t0 → xb_t1).
[[nodiscard]] ccd::EdgeEdgeQuery edge_edge_query(
    const skinning::Positions& xa_t0,
    const skinning::Positions& xa_t1,
    const std::array<std::int32_t, 2>& ea,
    const skinning::Positions& xb_t0,
    const skinning::Positions& xb_t1,
    const std::array<std::int32_t, 2>& eb);

/// `tests` with every null member replaced by the ccd/ kernel (ccd::vertex_face_ccd,
/// ccd::edge_edge_ccd, ccd::triangles_intersect).
[[nodiscard]] ElementaryTests with_ccd_defaults(ElementaryTests tests);

/// The order run_ccd_tests leaves the contacts it appends in: canonical (kind, a, b), or as
/// tested (the VF candidates' order, then the EE candidates') for a caller that sorts what several
/// calls appended once, at the end (PairBlocks: one sort instead of one per call and another over
/// them all).
enum class ContactOrder : std::uint8_t { sorted, as_tested };

/// Runs the VF and EE tests of `candidates` over the interval x_t0 → x_t1 and appends the hits to
/// out.contacts, then sorts the appended contacts canonically (kind, a, b) unless told otherwise.
/// Counts vf_tests, ee_tests, vf_contacts, ee_contacts. With tests.threads > 1 and at least
/// kParallelElementaryThreshold queries of a kind, those queries are split over threads; the
/// output is the same.
/// @param x_t0,x_t1 #W × 3 welded positions.  @pre `tests` has no null member.
void run_ccd_tests(
    const FeatureTopology& topology,
    const FeatureCandidates& candidates,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const ElementaryTests& tests,
    ccd::Accuracy accuracy,
    const ccd::CcdOptions& options,
    FrameResult& out,
    ContactOrder order = ContactOrder::sorted);

/// Runs the exact triangle-triangle test of each pair (with the corners the two share as mesh
/// vertices) and appends the intersecting ones to out.dcd_pairs, sorted (a, b). Counts tt_tests
/// and dcd_pairs. Split over tests.threads as run_ccd_tests.
/// @param pairs a < b.  @param x #W × 3 welded positions.  @pre `tests` has no null member.
void run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    FrameResult& out);

/// Whether a CCD query may settle triangle pairs by vertex fans certified over its interval
/// (VertexFans::certified_over): the mesh has fans, `options` asks for contact itself
/// (min_separation 0: a contact is then a common point of two triangles), and `tests` are the
/// product's kernels (a substituted test sees every pair).
[[nodiscard]] bool ccd_uses_fans(
    const FeatureTopology& topology, const ElementaryTests& tests, const ccd::CcdOptions& options);

/// The certified vertex fans at instant x (culling/vertex_fans.hpp), one flag per welded vertex,
/// for run_dcd_tests calls on blocks of one instant's pairs; empty when `tests` is not the exact
/// triangle test (fans stand for that test only). Valid until the calling thread's next call.
[[nodiscard]] std::span<const std::uint8_t> certify_dcd_fans(
    const FeatureTopology& topology, const skinning::Positions& x, const ElementaryTests& tests);

/// run_dcd_tests with the fans of certify_dcd_fans(topology, x, tests) (empty: no fans).
void run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::span<const std::uint8_t> certified_fans,
    FrameResult& out);

/// The plane of every triangle at instant x (ccd::triangle_plane of its corners in topology order)
/// into `planes`, for filter_and_run_dcd_tests calls on blocks of that instant's pairs: each
/// triangle's plane once instead of once per tested pair. Empties `planes` when `tests` is not
/// the exact triangle test (the planes stand for its own computation).
/// @param planes resized to #triangles (its capacity is kept across instants).
void dcd_planes(
    const FeatureTopology& topology,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::vector<ccd::TrianglePlane>& planes);

/// Outcomes the calling thread's scratch has room for (kept between calls, reused by the next):
/// at most kElementaryOutcomeWindow.
[[nodiscard]] std::size_t elementary_outcome_capacity();

/// dcd_filter_triangle_pairs (candidates.hpp) and run_dcd_tests in one pass: pairs that are
/// part-excluded or duplicate faces are dropped, the others counted in candidate_pairs and tested,
/// with each pair's shared corners looked up once (the traversing methods' blocks). The
/// intersecting pairs are appended in the order of `pairs`, not sorted: PairBlocks::finish sorts a
/// query's pairs once, after its last block.
/// @param planes dcd_planes at x, or empty (the test computes each pair's planes).
void filter_and_run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::span<const std::uint8_t> certified_fans,
    std::span<const ccd::TrianglePlane> planes,
    FrameResult& out);

}  // namespace skelcd::culling
